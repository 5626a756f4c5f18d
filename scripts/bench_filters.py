"""Attitude filters on BROAD (Laidig et al. 2021): inclination (and 9-D heading) RMSE vs optical.

The three BROAD trials in ``../shared/data/broad/`` (one IMU moved by hand, OptiTrack truth,
285.7 Hz): the benchmark's metric over its ``movement`` samples, inclination = the angle between
the estimated and true vertical seen from the sensor, heading = the remaining rotation about the
vertical (9-D only; 6-D heading is unobservable). Filters: VQF (``vqf.offlineVQF``, 6-D and 9-D),
Hu 2021's PI filter with the paper's gains, and with the tuned gains and extensions that
``--filter pi`` uses (:data:`pipeline.calibration.attitude.TUNED`).

Usage: ``python scripts/bench_filters.py [--data ../shared/data/broad]``
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import scipy.io

from pipeline.calibration.attitude import TUNED, filter_orientations, mahony_filter, tilt_error
from pipeline.rotations import matrix_from_quat, quat_from_matrix

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "broad"


def load(path: Path) -> dict[str, np.ndarray]:
    d = scipy.io.loadmat(path, squeeze_me=True)
    out = {k: np.ascontiguousarray(d[k], dtype=float) for k in ("imu_gyr", "imu_acc", "imu_mag",
                                                                 "opt_quat")}
    out["rate"] = float(d["sampling_rate"])
    out["scored"] = np.asarray(d["movement"], bool) & np.all(np.isfinite(out["opt_quat"]), axis=1)
    out["opt_quat"] = np.where(np.isfinite(out["opt_quat"]), out["opt_quat"], [[1.0, 0, 0, 0]])
    return out


def inclination_rmse(quat: np.ndarray, trial: dict) -> float:
    e = tilt_error(quat, trial["opt_quat"])[trial["scored"]]
    return float(np.degrees(np.sqrt(np.mean(e**2))))


def heading_rmse(quat: np.ndarray, trial: dict) -> float:
    """RMS of the rotation about the world's vertical left in R_true R_est^T (deg)."""
    D = matrix_from_quat(trial["opt_quat"]) @ np.swapaxes(matrix_from_quat(quat), 1, 2)
    q = quat_from_matrix(D)
    e = 2 * np.arctan2(q[:, 3], q[:, 0])  # twist about z of the error rotation
    e = (e + np.pi) % (2 * np.pi) - np.pi
    return float(np.degrees(np.sqrt(np.mean(e[trial["scored"]] ** 2))))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", type=Path, default=DATA)
    args = ap.parse_args()
    rows = []
    for path in sorted(args.data.glob("*.mat")):
        tr = load(path)
        t = np.arange(len(tr["imu_gyr"])) / tr["rate"]
        res = {}
        t0 = time.perf_counter()
        q6 = filter_orientations(t, tr["imu_gyr"], tr["imu_acc"], method="vqf")
        res["vqf_s"] = time.perf_counter() - t0
        q9 = filter_orientations(t, tr["imu_gyr"], tr["imu_acc"], tr["imu_mag"], method="vqf")
        t0 = time.perf_counter()
        qpi = filter_orientations(t, tr["imu_gyr"], tr["imu_acc"], method="pi")
        res["pi_s"] = time.perf_counter() - t0
        paper = mahony_filter(t, tr["imu_gyr"], tr["imu_acc"]).quat
        rows.append((path.stem, inclination_rmse(q6, tr), inclination_rmse(q9, tr),
                     heading_rmse(q9, tr), inclination_rmse(paper, tr), inclination_rmse(qpi, tr),
                     res["vqf_s"], res["pi_s"], len(t)))
    print("BROAD, RMSE in degrees over the scored (movement) samples")
    print(f"PI tuned: {TUNED}")
    print("| trial | VQF 6-D incl. | VQF 9-D incl. | VQF 9-D heading | PI paper incl. | "
          "PI tuned incl. | PI tuned / VQF 6-D | VQF s | PI s | samples |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name, v6, v9, h9, pp, pt, sv, sp, n in rows:
        print(f"| {name} | {v6:.2f} | {v9:.2f} | {h9:.2f} | {pp:.2f} | {pt:.2f} | {pt / v6:.2f} "
              f"| {sv:.2f} | {sp:.2f} | {n} |")


if __name__ == "__main__":
    main()
