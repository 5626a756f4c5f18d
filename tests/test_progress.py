"""pipeline.progress: a line on a terminal's stderr once a step has taken a while, and nothing
anywhere else."""

import io

from pipeline import progress


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_a_terminal_sees_the_step_after_the_delay_and_the_line_cleared(monkeypatch):
    err = _Terminal()
    monkeypatch.setattr("sys.stderr", err)
    monkeypatch.setattr(progress, "DELAY_S", 0.0)
    with progress.shown("pipeline ik"):
        progress.step("inverse kinematics")
    text = err.getvalue()
    assert "pipeline ik: inverse kinematics (0 s)" in text and text.endswith("\r\033[K")


def test_nothing_before_the_delay_off_a_terminal_or_without_a_line(monkeypatch):
    err, log = _Terminal(), io.StringIO()
    monkeypatch.setattr("sys.stderr", err)
    with progress.shown("pipeline ik"):  # within the delay: short runs stay silent
        progress.step("calibration pose")
    progress.step("no line open")
    monkeypatch.setattr(progress, "DELAY_S", 0.0)
    monkeypatch.setattr("sys.stderr", log)
    with progress.shown("pipeline simulate"):  # a log file, not a terminal
        progress.step("the legs' joints")
    assert err.getvalue() == "" and log.getvalue() == ""
