"""Live capture's latency, and live against offline (``pipeline live``, issue 42).

    python scripts/bench_live.py [--data ../shared/data] [--hours 1] [--out results/bench_live.txt]

S02 (7 Xsens MTw, 100 Hz) replayed as fast as it is processed through the live path
(:mod:`pipeline.live.capture`: the streams aligned, orientations, the calibration on the capture
so far, each frame's IK warm-started, its angles): each frame's processing time from its block's
arrival to its angles (a calibration made in line not counted: live it runs beside the frames),
p50 and p99, on the vendor's orientations and on the raw signals through VQF (9-D where the
magnetometer is trusted, and without magnetometers) and through the PI filter, at 100 Hz and
at 200 Hz (S02 resampled); the highest rate that p99 sustains. Live against offline: each live
angle against ``pipeline ik``'s on the same capture, RMS from the final calibration on. Then a
long replay (``--hours``, S02's walk repeated) at full speed: the process's memory and the
frames' latency over its first and last 10 minutes. One run on one core of this machine: ratios
and percentiles, not absolute promises.
"""

from __future__ import annotations

import argparse
import resource
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_gait import S02_MAP  # noqa: E402

from pipeline.io.formats import read_recording  # noqa: E402
from pipeline.io.recording import Recording  # noqa: E402
from pipeline.live.capture import LiveCapture  # noqa: E402
from pipeline.live.sources import ReplaySource  # noqa: E402
from pipeline.model.measures import Measures  # noqa: E402
from pipeline.process import process_recording  # noqa: E402
from pipeline.process.options import IKOptions  # noqa: E402

SUBJECT = Measures("m", 1.72)
#: Target (issue 42): p99 per frame at 100 Hz with 7 sensors.
TARGET_MS = 5.0


def paths(rec: Recording) -> dict[str, tuple[Recording, IKOptions]]:
    """Input path -> (recording, options): the vendor's orientations, VQF 9-D, VQF without the
    magnetometers, the PI filter (6-D)."""
    raw = rec.with_sensors({n: s.replace(quat=None) for n, s in rec.sensors.items()})
    six = rec.with_sensors({n: s.replace(quat=None, mag=None) for n, s in rec.sensors.items()})
    return {"vendor": (rec, IKOptions(sensor_to_model=(-np.pi / 2, 0.0, 0.0))),
            "VQF 9-D": (raw, IKOptions(filter="vqf")),
            "VQF 6-D": (six, IKOptions(filter="vqf")),
            "PI 6-D": (six, IKOptions(filter="pi"))}


def capture(rec: Recording, opts: IKOptions, watch=None):
    source = ReplaySource(rec, np.inf)
    source.header = dict(rec.header)
    if watch is not None:
        source = watch(source)
    return LiveCapture(source, SUBJECT, opts, in_line=True, say=lambda s: None).run()


def against_offline(result, opts: IKOptions) -> dict[str, float]:
    """RMS (deg) of each live angle against the offline pipeline's, from the final calibration."""
    offline = process_recording(result.recording, SUBJECT, opts)
    at = next((c.from_s for c in result.calibrations if c.final), None)
    if at is None:
        return {}
    k = int(np.searchsorted(result.recording.time, at))
    out = {}
    for name, y in offline.joint_angles.items():
        if name in result.angles:
            out[name] = _rms_deg(result.angles[name][k:], y[k:])
    return out


def _rms_deg(a: np.ndarray, b: np.ndarray) -> float:
    d = np.angle(np.exp(1j * (a - b)))
    return float(np.degrees(np.sqrt(np.nanmean(d**2))))


def offline_hindsight(result, opts: IKOptions, window_s: float = 2.0) -> dict[str, float]:
    """RMS (deg) of each offline angle, run on the capture up to the final calibration, against
    the offline angle run on the whole capture, over the last ``window_s`` before it: how much
    the offline pipeline itself changes with the rest of the recording, which a live capture
    cannot have seen."""
    at = next((c.at_s for c in result.calibrations if c.final), None)
    if at is None:
        return {}
    rec = result.recording
    n = int(np.searchsorted(rec.time, at)) + 1
    part = process_recording(rec.cropped(0, n), SUBJECT, opts)
    whole = process_recording(rec, SUBJECT, opts)
    w = slice(max(0, n - 1 - int(window_s * rec.rate_hz)), n - 1)
    return {k: _rms_deg(part.joint_angles[k][w], y[w]) for k, y in whole.joint_angles.items()
            if k in part.joint_angles}


def resampled(rec: Recording, factor: int) -> Recording:
    """``rec`` at ``factor`` times its rate (linear; quaternions normalised linear)."""
    t = np.arange((rec.n_samples - 1) * factor + 1) / (rec.rate_hz * factor)
    sensors = {}
    for n, s in rec.sensors.items():
        parts = {}
        for k in ("quat", "gyr", "acc", "mag"):
            v = getattr(s, k)
            if v is not None:
                w = np.stack([np.interp(t, rec.time, v[:, j]) for j in range(v.shape[1])], 1)
                parts[k] = w / np.linalg.norm(w, axis=1, keepdims=True) if k == "quat" else w
        sensors[n] = s.replace(**parts)
    return Recording(t, rec.rate_hz * factor, sensors, dict(rec.header))


def repeated(rec: Recording, seconds: float) -> Recording:
    """``rec`` played again and again for ``seconds`` (its time running on)."""
    k = int(np.ceil(seconds / (rec.n_samples / rec.rate_hz)))
    n = rec.n_samples * k
    t = np.arange(n) / rec.rate_hz
    sensors = {name: s.replace(**{g: np.tile(getattr(s, g), (k, 1)) for g in
                                  ("quat", "gyr", "acc", "mag") if getattr(s, g) is not None})
               for name, s in rec.sensors.items()}
    return Recording(t, rec.rate_hz, sensors, dict(rec.header))


def rss_mb() -> float:
    """The process's resident memory now (MB, /proc)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return float("nan")


class _Watched:
    """A source that notes the process's memory at given times of the replay."""

    def __init__(self, source, marks_s) -> None:
        self.source, self.marks, self.seen = source, list(marks_s), {}
        self.names, self.rate_hz, self.header = source.names, source.rate_hz, source.header

    def read(self):
        chunks = self.source.read()
        if chunks:
            t = chunks[0].time[-1]
            while self.marks and t >= self.marks[0]:
                self.seen[self.marks.pop(0)] = rss_mb()
        return chunks

    def close(self) -> None:
        self.source.close()


def _ms(x: np.ndarray) -> tuple[float, float]:
    return tuple(float(v) for v in 1e3 * np.percentile(x, [50, 99]))


def latency_section(rec: Recording) -> tuple[list[str], float]:
    lines = ["## Latency per frame and live against offline (S02, 7 sensors)", "",
             "| input | rate (Hz) | p50 (ms) | p99 (ms) | highest rate p99 sustains (Hz) | "
             "final calibration at (s) | live vs offline: sagittal, worst (deg RMS) | median | "
             "worst angle | offline on the capture up to the final calibration vs on the whole,"
             " its last 2 s: that angle, the worst |", "|---|---|---|---|---|---|---|---|---|---|"]
    p99_100 = float("nan")
    for factor in (1, 2):
        r = rec if factor == 1 else resampled(rec, factor)
        for label, (x, opts) in paths(r).items():
            result = capture(x, opts)
            p50, p99 = _ms(result.frame_s)
            if factor == 1 and label == "vendor":
                p99_100 = p99
            rms = against_offline(result, opts) if factor == 1 else {}
            final = next((c.at_s for c in result.calibrations if c.final), float("nan"))
            sag = max((v for k, v in rms.items() if "flexion" in k), default=float("nan"))
            worst = max(rms, key=rms.get) if rms else "-"
            hind = offline_hindsight(result, opts) if rms else {}
            most = max(hind, key=hind.get) if hind else "-"
            lines.append(f"| {label} | {r.rate_hz:.0f} | {p50:.2f} | {p99:.2f} | "
                         f"{1e3 / p99:.0f} | {final:.1f} | "
                         + (f"{sag:.2f} | {np.median(list(rms.values())):.2f} | {worst} "
                            f"{rms[worst]:.2f} | {hind.get(worst, float('nan')):.2f}, {most} "
                            f"{hind[most]:.2f} |" if rms else "- | - | - | - |"))
    return lines, p99_100


def long_section(rec: Recording, hours: float) -> list[str]:
    seconds = hours * 3600.0
    long = repeated(rec, seconds)
    marks = [600.0, seconds - 1.0]
    watched = {}

    def watch(source):
        watched["w"] = _Watched(source, marks)
        return watched["w"]

    opts = paths(long)["vendor"][1]
    result = capture(long, opts, watch)
    seen = watched["w"].seen
    n10 = int(600 * long.rate_hz)
    first, last = _ms(result.frame_s[:n10]), _ms(result.frame_s[-n10:])
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    return ["## A long capture (S02's walk repeated, vendor orientations, as fast as processed)",
            "", f"{hours:g} h replayed ({long.n_samples} frames): memory {seen.get(600.0, 0):.0f} "
            f"MB after 10 minutes, {seen.get(seconds - 1.0, 0):.0f} MB at the end (peak "
            f"{peak:.0f} MB, the replayed recording itself included); latency p50/p99 "
            f"{first[0]:.2f}/{first[1]:.2f} ms over the first 10 minutes, {last[0]:.2f}/"
            f"{last[1]:.2f} ms over the last.", ""]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", type=Path, default=Path("../shared/data"))
    ap.add_argument("--hours", type=float, default=1.0)
    ap.add_argument("--out", type=Path, default=Path("results/bench_live.txt"))
    args = ap.parse_args()
    rec = read_recording(args.data / "gaittoolbox_s02" / "imu", S02_MAP)
    lines, p99 = latency_section(rec)
    head = ["# Live capture (scripts/bench_live.py)", "",
            f"p99 per frame (100 Hz, 7 sensors): {p99:.2f} ms (target {TARGET_MS:g}; vendor "
            "orientations; the other inputs below)", ""]
    text = "\n".join(head + lines + [""] + long_section(rec, args.hours)) + "\n"
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text)
    print(text)


if __name__ == "__main__":
    main()
