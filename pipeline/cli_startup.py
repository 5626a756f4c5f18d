"""What the ``pipeline`` program does before it parses its arguments: one BLAS thread per
process, and for ``pipeline ik`` the recording's writer forked first (:func:`recording_writer`).
"""

from __future__ import annotations

import sys

__all__ = ["BLAS_THREADS", "recording_writer", "single_threaded_blas"]


#: BLAS thread pools the program sizes to one thread unless the user set them.
BLAS_THREADS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def single_threaded_blas() -> None:
    """One BLAS thread per process, unless the environment says otherwise: the commands' arrays
    are small (3 x 3 rotations, joint-sized normal matrices, stacks of them), where BLAS threads
    gain nothing, and the program runs a second process (the recording's writer, Dask workers)
    on the other cores: two processes' spinning BLAS pools on two cores slowed each ~2x here.
    Before NumPy is imported (its pool is sized then)."""
    import os

    for var in BLAS_THREADS:
        os.environ.setdefault(var, "1")


def recording_writer(argv: list[str] | None):
    """``pipeline ik`` run as the program, its recording wanted: the recording's writer forked
    first, before the parser and the heavy imports, so that it imports NumPy, pyarrow, rerun's
    native writer and matplotlib (the report's figures) on the second core meanwhile
    (:mod:`pipeline.viz.background`; ``run_ik`` hands it the job or closes it)."""
    words = sys.argv[1:] if argv is None else []
    if words[:1] != ["ik"] or any(w in ("-h", "--help") for w in words) or (
            "--no-rerun" in words and "--no-report" in words):
        return None
    from pipeline.viz.background import BackgroundRecording

    report = "--no-report" not in words
    return BackgroundRecording.start(warm=_warm_outputs if report else _warm_recording)


def _warm_recording() -> None:
    from pipeline.viz.scene import warm_recording  # no Pinocchio: the child only logs

    warm_recording()


def _warm_outputs() -> None:
    from pipeline.report.plots import warm_plots

    _warm_recording()
    warm_plots()
