"""The example each command's ``--help`` shows: every one runs as written from any folder of a
fresh clone or install (``tests/test_cli_examples.py``), on the shipped ``example:`` recordings,
but ``reproduce``, which needs the paper's published dataset."""

from __future__ import annotations

__all__ = ["EXAMPLES", "EXAMPLE_NEEDS"]

#: Command -> its example command line.
EXAMPLES = {
    "scale": "pipeline scale --sex f --height-m 1.62 --knee-width-m 0.095 --out out/subject.urdf",
    "ik": "pipeline ik --orientations example:ximu3_lower_body --sex m --height-m 1.80 "
    "--out out/ximu3",
    "simulate": "pipeline simulate --out out/sim --motion gait --seed 0",
    "orientations": "pipeline orientations --imu example:ximu3_lower_body --filter vqf "
    "--out out/ximu3_orientations.sto",
    "calibrate": "pipeline calibrate hinge --imu1 out/sim/imu/right_femur_imu.csv "
    "--imu2 out/sim/imu/right_tibia_imu.csv --method ipopt --json",
    "batch": "pipeline batch example:batch_manifest.csv --out out/batch --workers 2",
    "reproduce": "pipeline reproduce wang2023 --data ../shared/data/wang2023 --out out/wang2023",
    "demo": "pipeline demo --out out/demo",
    "view": "pipeline view out/demo/demo.rrd --web",
    "live": "pipeline live --replay example:ximu3_lower_body --sex m --height-m 1.80 "
    "--speed max --viewer none --out out/live",
}

#: What an example needs first.
EXAMPLE_NEEDS = {"calibrate": "the simulate example's output",
                 "reproduce": "the published dataset, from github.com/wangzhengtao1993/"
                 "AnatomicalLandmarkTrajectoriesBasedonIMUData"}
