"""Strides at any speed: sections of ``scripts/bench_gait.py``'s report.

* **Speeds**: the simulated foot (:func:`pipeline.simulate.foot_walk.foot_walk`) walking at 0.6,
  1.0, 1.4, 1.8 and 2.2 m/s (:meth:`~pipeline.simulate.foot_walk.Pace.at`: from 1.8 m/s its foot
  never rests by the fixed thresholds, as real fast walks') and running at 3 m/s, three seeds, at
  100 and 200 Hz: strides found, contact, stride time and length errors.
* **A walk after shuffling**: S02 with 10 s of shuffling in place before it (each foot lifting
  its heel and setting it down, its larger turn backwards, about its own sagittal axis): the
  same strides, none invented, none flipped.
* **qmt's run**: the qmt full-body recording (a walk that turns into a run; no truth): strides per
  foot against the thighs' rhythm.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pipeline.analysis.foot_trajectory import foot_trajectory
from pipeline.analysis.gait_events import gait_events
from pipeline.analysis.strides import foot_strides
from pipeline.io.recording import Recording
from pipeline.process.gait import gait_of
from pipeline.rotations import exp3
from pipeline.simulate.foot_walk import Pace, foot_walk

__all__ = ["SPEEDS", "qmt_run", "shuffling", "speeds"]

SPEEDS = (0.6, 1.0, 1.4, 1.8, 2.2)
#: The issue's targets: contacts and stride time (ms), stride length (%).
TARGETS = (20.0, 20.0, 3.0)


def _stillest(w, rate: float) -> float:
    """The largest, over the stances, of the stance's stillest 50 ms (its angular speed's moving
    maximum at its smallest), rad/s."""
    n = max(1, int(0.05 * rate))
    speed = np.linalg.norm(w.gyr, axis=1)
    moving = np.lib.stride_tricks.sliding_window_view(np.pad(speed, (0, n - 1), "edge"), n)
    top = moving.max(axis=1)
    return max(float(top[int(a * rate):int(b * rate)].min()) for a, b in zip(w.ic[:-1], w.fc,
                                                                             strict=False))


def _one(pace: Pace, rate: float, seed: int):
    """``(found, swings, ic_ms, time_ms, length_pct, stillest)`` of one simulated walk."""
    w = foot_walk(strides=10, pace=pace, rate_hz=rate, seed=seed, turns_deg=(0, 0, 90))
    ev = gait_events(w.gyr, w.acc, rate)
    path = ev.trajectory or foot_trajectory(w.gyr, w.acc, rate, ev.rests)
    strides = foot_strides("right", w.time, ev, path)
    ic = np.array([t - w.ic[np.argmin(np.abs(w.ic - t))] for t in ev.ic / rate])
    times = np.array([s.stride_time_s for s in strides]) - pace.stride_time_s
    lengths = np.array([s.stride_length_m for s in strides]) / pace.length_m - 1
    return (len(strides), len(w.ic) - 2, 1000 * np.abs(ic).max(), 1000 * np.abs(times).max(),
            100 * np.abs(lengths).max(), _stillest(w, rate))


def speeds(seeds=(0, 1, 2)) -> list[str]:
    lines = ["", "## Strides at any speed (the simulated foot, 10 strides, a 90 deg turn; "
             "three seeds)", "",
             "| pace | rate (Hz) | strides found / walked | IC error (ms, largest) | stride "
             "time error (ms) | stride length error (%) | stillest 50 ms in stance (rad/s) |",
             "|---|---|---|---|---|---|---|"]
    worst = np.zeros(3)
    missed = 0
    paces = [(f"walk {v:g} m/s", Pace.at(v)) for v in SPEEDS] + [("run 3 m/s", Pace.running())]
    for label, pace in paces:
        for rate in (100.0, 200.0):
            rows = np.array([_one(pace, rate, seed) for seed in seeds])
            found, walked = int(rows[:, 0].sum()), int(rows[:, 1].sum())
            missed += walked - found
            worst = np.maximum(worst, rows[:, 2:5].max(axis=0))
            lines.append(f"| {label} | {rate:.0f} | {found} / {walked} | "
                         f"{rows[:, 2].max():.1f} | {rows[:, 3].max():.1f} | "
                         f"{rows[:, 4].max():.2f} | {rows[:, 5].max():.2f} |")
    ok = missed == 0 and np.all(worst <= TARGETS)
    lines += ["", f"Targets (every stride found; contacts and stride time within "
              f"{TARGETS[0]:g} ms, length within {TARGETS[2]:g} %): "
              + ("met" if ok else "**not met**") + f" (missed {missed}; largest errors "
              f"{worst[0]:.1f} ms, {worst[1]:.1f} ms, {worst[2]:.2f} %)."]
    return lines


def _shuffled(rec: Recording, seconds: float = 10.0) -> Recording:
    """``rec`` with ``seconds`` of shuffling in place before it (module docstring): each foot
    sensor turns about its own sagittal axis by +3, -8, +5 deg once a second, the shank, thigh and
    pelvis sensors stand as at the recording's first sample."""
    rate = rec.rate_hz
    n = int(round(seconds * rate))
    t = np.arange(n) / rate
    phase = t % 1.0
    angle = np.radians(np.interp(phase, [0, 0.1, 0.3, 0.6, 1.0], [0, 3, -5, 0, 0]))
    rate_w = np.gradient(angle) * rate
    sensors = {}
    for name, s in rec.sensors.items():
        if name.startswith("calcn"):
            axis = gait_events(s.gyr, s.acc, rate).axis
            R = exp3(np.outer(-angle, axis))
            gyr, acc = np.outer(rate_w, axis), np.einsum("nij,j->ni", R, s.acc[0])
        else:
            gyr, acc = np.zeros((n, 3)), np.tile(s.acc[0], (n, 1))
        noise = np.random.default_rng(len(sensors)).normal(0, [0.005] * 3 + [0.03] * 3, (n, 6))
        sensors[name] = s.replace(gyr=np.vstack([gyr + noise[:, :3], s.gyr]),
                                  acc=np.vstack([acc + noise[:, 3:], s.acc]),
                                  quat=None, mag=None)
    time = np.concatenate([t, rec.time + seconds])
    return Recording(time, rate, sensors, source=rec.source)


def shuffling(rec: Recording | None) -> list[str]:
    lines = ["", "## A walk after 10 s of shuffling in place (S02, each foot lifting and setting "
             "its heel once a second before the walk)", ""]
    if rec is None:
        return lines + ["S02 not found: skipped."]
    before = gait_of(rec, [])
    after = gait_of(_shuffled(rec), [])
    for side in ("right", "left"):
        a = [s.start_s for s in before.strides if s.side == side]
        b = [s.start_s - 10.0 for s in after.strides if s.side == side]
        same = sum(any(abs(x - y) < 0.011 for y in b) for x in a)
        lines.append(f"- {side}: {len(a)} strides as recorded, {len(b)} after the shuffling: "
                     f"{same} the same (within 10 ms), {len(b) - same} invented.")
    return lines


def qmt_run(data: Path) -> list[str]:
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    from _helpers import qmt_recording

    from pipeline.calibration.flexion_axis import flexion_axis, stride_frequency

    lines = ["", "## qmt's walk and run (no truth): strides against the thighs' rhythm", ""]
    rec = qmt_recording(data)
    if rec is None:
        return lines + ["qmt not found: skipped."]
    gait = gait_of(rec, [])
    for side, thigh in (("right", "femur_r_imu"), ("left", "femur_l_imu")):
        strides = [s for s in gait.strides if s.side == side]
        s = rec.sensors[thigh]
        span = (strides[0].start_s, strides[-1].end_s) if strides else (0.0, 0.0)
        rows = (rec.time >= span[0]) & (rec.time <= span[1])
        up = s.acc / np.linalg.norm(s.acc, axis=1, keepdims=True)
        axis = flexion_axis(s.gyr[rows], up[rows], rec.rate_hz).axis
        f = stride_frequency(s.gyr[rows] @ axis, rec.rate_hz)
        covered = sum(x.stride_time_s for x in strides)
        lines.append(f"- {side}: {len(strides)} strides over {covered:.1f} s of "
                     f"{span[1] - span[0]:.1f} s walked or run ({span[0]:.1f}-{span[1]:.1f} s); "
                     f"median stride {np.median([x.stride_time_s for x in strides]):.2f} s, the "
                     f"thigh's rhythm {1 / f:.2f} s: {(span[1] - span[0]) * f:.0f} strides "
                     "expected if it never paused.")
    return lines
