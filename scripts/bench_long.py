"""Long recordings through ``pipeline ik``: wall time and peak memory for 10k, 100k and 360k frames.

The real walking trial (OpenSim's ``xsens_walking_orientations.sto``, 2,432 frames at 100 Hz, 8
sensors) is tiled end to end (each copy continuing the time axis) to the requested lengths and
written as ``.sto``; each length runs the whole ``pipeline ik`` command in a child process (the
recording included, default options), whose peak resident memory is read from
``getrusage(RUSAGE_CHILDREN)``. Targets (issue: hour-long recordings): 360k frames (1 h) in < 1.5
GB, time linear in length.

Usage: ``python scripts/bench_long.py [--frames 10000 100000 360000]``
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from pipeline.io.opensim import read_orientations_sto, write_orientations_sto
from pipeline.io.recording import Recording

WALK = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "opensim" / \
    "xsens_walking_orientations.sto"


def tiled(n: int) -> Recording:
    rec = read_orientations_sto(WALK)
    reps = -(-n // rec.n_samples)
    quats = {k: np.tile(q, (reps, 1))[:n] for k, q in rec.orientations().items()}
    return Recording.from_orientations(np.arange(n) / rec.rate_hz, rec.rate_hz, quats)


def run(n: int, tmp: Path) -> tuple[float, float, int]:
    sto = tmp / f"walk_{n}.sto"
    write_orientations_sto(sto, tiled(n))
    out = tmp / f"out_{n}"
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "pipeline", "ik", "--orientations", str(sto), "--sex",
                    "m", "--height-m", "1.80", "--sensor-to-model", "-1.5708", "0", "0",
                    "--out", str(out)], check=True, capture_output=True)
    wall = time.perf_counter() - t0
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss  # KiB, max over children
    size = sum(p.stat().st_size for p in out.iterdir())
    return wall, max(peak, before) / 1024**2, size


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--frames", type=int, nargs="+", default=[10_000, 100_000, 360_000])
    args = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in sorted(args.frames):  # ascending: RUSAGE_CHILDREN is a running maximum
            wall, peak, size = run(n, Path(tmp))
            rows.append((n, wall, peak, size))
    print(f"pipeline ik on the walking trial tiled to N frames (100 Hz, 8 sensors), "
          f"{os.cpu_count()} cores; peak RSS of the command's process")
    print("| frames | duration | wall s | s per 10k frames | peak RSS GB | outputs MB |")
    print("|---|---|---|---|---|---|")
    for n, wall, peak, size in rows:
        print(f"| {n} | {n / 6000:.1f} min | {wall:.1f} | {1e4 * wall / n:.2f} | {peak:.2f} | "
              f"{size / 1e6:.0f} |")


if __name__ == "__main__":
    main()
