"""Benchmark the joint-constraint calibration solvers (Hu et al. 2021) on simulated knee trials.

Trials (15 s, 100 Hz, gyro noise 0.01 rad/s, accelerometer noise 0.05 m/s^2): 'rich' (gait-like),
'supine_hip_flexion' (poorly excited, like the Wang 2023 recordings) and 'still_thigh'; plus one
spherical (hip) trial. Errors vs the simulated truth: axis angle (deg, signs included, both axes
fixed by the sensor orientations and the true axis_1 as 'right' reference), joint position (mm,
after eq 16 for the hinge). IPOPT is also run on the still-thigh trial with a prior axis 2.5 deg
off the truth (a population knee AoR stand-in). Usage: ``python scripts/bench_calibration.py``.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # small matrices: threads only contend

import time  # noqa: E402
from functools import partial  # noqa: E402

import numpy as np  # noqa: E402

from pipeline.calibration.calibrate import calibrate  # noqa: E402
from pipeline.calibration.ipopt import calibrate_ipopt  # noqa: E402
from pipeline.calibration.joint_constraints import (  # noqa: E402
    joint_data,
    project_hinge_positions,
)
from pipeline.rotations import angle_between, exp3, normalize  # noqa: E402
from pipeline.simulate.joint_trials import hinge_trial, spherical_trial  # noqa: E402

METHODS = ("gn", "dwpso", "gwo")
PAPER_SECONDS = {"dwpso": 1076.1, "gwo": 576.3, "gn": 1556.4}  # Hu 2021 Table 1 (mean of 15)


def errors(tr, r) -> tuple[float, float, float, float]:
    if tr.axis_1 is None:
        p1, p2 = tr.position_1, tr.position_2
        a1 = a2 = float("nan")
    else:
        p1, p2 = project_hinge_positions(tr.position_1, tr.position_2, tr.axis_1, tr.axis_2)
        a1 = float(np.degrees(angle_between(r.axis_1, tr.axis_1)))
        a2 = float(np.degrees(angle_between(r.axis_2, tr.axis_2)))
    return (
        a1,
        a2,
        1000 * float(np.linalg.norm(r.position_1_m - p1)),
        1000 * float(np.linalg.norm(r.position_2_m - p2)),
    )


def main() -> None:
    t_start = time.perf_counter()
    trials = [hinge_trial(k, seed=0) for k in ("rich", "supine_hip_flexion", "still_thigh")]
    trials.append(spherical_trial("rich", seed=0))
    rng = np.random.default_rng(7)
    print(
        "Hu 2021 joint-constraint calibration, simulated 15 s @ 100 Hz, gyro 0.01 rad/s, "
        "acc 0.05 m/s^2"
    )
    print(
        "paper (Table 1, whole lower limb, mean of 15 runs): "
        + ", ".join(f"{m.upper()} {s:.0f} s ({s / 60:.0f} min)" for m, s in PAPER_SECONDS.items())
    )
    head = f"{'trial':<30}{'method':<14}{'axis1 deg':>10}{'axis2 deg':>10}{'pos1 mm':>9}"
    print(head + f"{'pos2 mm':>9}{'time s':>8}  undetermined")
    for tr in trials:
        d = joint_data(tr.time, tr.imu_1.gyr, tr.imu_1.acc, tr.imu_2.gyr, tr.imu_2.acc)
        kw = {"quat_1": tr.imu_1.quat, "quat_2": tr.imu_2.quat, "reference_1": tr.axis_1}
        if tr.axis_1 is None:
            kw = {}
        # one solve each (the user path adds an independent verification start)
        runs = [(m, partial(calibrate, d, tr.joint, m, seed=0, verify_start=False, **kw))
                for m in METHODS]
        runs.append(("ipopt", partial(calibrate_ipopt, d, tr.joint, **kw)))
        runs.append(("ipopt-cauchy", partial(calibrate_ipopt, d, tr.joint, loss="cauchy", **kw)))
        if tr.kind == "still_thigh":
            tilt = exp3(normalize(np.cross(tr.axis_1, rng.normal(size=3))) * np.deg2rad(2.5))
            prior = partial(calibrate_ipopt, d, tr.joint, prior_axis_1=tilt @ tr.axis_1)
            runs.append(("ipopt+prior", prior))
        name = f"{tr.joint}/{tr.kind}"
        for method, run in runs:
            r = run()
            a1, a2, p1, p2 = errors(tr, r)
            und = ", ".join(r.observability.undetermined) or "-"
            print(
                f"{name:<30}{method:<14}{a1:>10.3f}{a2:>10.3f}{p1:>9.2f}{p2:>9.2f}"
                f"{r.seconds:>8.3f}  {und}"
            )
    print(f"total bench time {time.perf_counter() - t_start:.1f} s")


if __name__ == "__main__":
    main()
