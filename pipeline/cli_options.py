"""The flags of ``pipeline ik`` (argparse; importable at no cost: ``--help`` loads no NumPy)."""

from __future__ import annotations

import argparse
from pathlib import Path

from pipeline.calibration.conventions import (
    CALIBRATION_POSES,
    CORRECTIONS,
    DEFAULT_CALIBRATION_POSE,
    DEFAULT_CORRECTION,
    DEFAULT_FILTER,
    DEFAULT_METHOD,
    DRIFT_CORRECTIONS,
    FILTERS,
    METHODS,
)
from pipeline.io.config import IK_KEYS, SUBJECT_KEYS
from pipeline.model.conventions import DEFAULT_KNEE, KNEE_MODES

__all__ = ["IK_FLAGS", "add_ik_options"]

#: The ``pipeline ik`` flags (argparse ``dest`` names): exactly the configuration file's keys.
IK_FLAGS = (*SUBJECT_KEYS, *IK_KEYS)


def add_ik_options(p: argparse.ArgumentParser) -> None:
    """``pipeline ik``'s flags; every one defaults to None (not given), so that a configuration
    file's value is overridden only by a flag that was typed (the defaults are IKOptions')."""
    p.add_argument("--config", type=Path, help="subject.toml: subject, sensor names and any of "
                   "these options (flags override it); each run writes <name>_config.toml "
                   "(default: none)")
    p.add_argument("--orientations", type=Path, help="OpenSim .sto quaternions, a folder of "
                   "Xsens MT .txt exports (with --sensor-map), or a folder of raw IMU recordings "
                   "(<sensor>.csv as pipeline simulate writes, Movella DOT .csv, x-IMU3 device "
                   "folders) (required, here or in --config)")
    for flag in ("--sensor-map", "--xsens-map"):
        p.add_argument(flag, nargs="+", metavar="NAME=ID", dest="sensor_map",
                       help=argparse.SUPPRESS if flag == "--xsens-map" else
                       "our sensor name = the recording's sensor name, label or device id (a "
                       "unique part of it), e.g. pelvis_imu=00B421AF femur_r_imu=thigh_R; a "
                       "folder of Xsens files needs it (default: the names as they are)")
    p.add_argument("--sex", choices=["m", "f"], help="sex, for the regression equations "
                   "(required, here or in --config)")
    p.add_argument("--height-m", type=float, help="body height in metres (required, ditto)")
    absent = "default: not measured; the equations use the others"
    p.add_argument("--shank-lateral-m", type=float, help=f"s_L = |EFL - LM| in metres ({absent})")
    p.add_argument("--shank-medial-m", type=float, help=f"s_M = |EFM - MM| in metres ({absent})")
    p.add_argument("--knee-width-m", type=float, help=f"k = |EFM - EFL| in metres ({absent})")
    p.add_argument("--ankle-width-m", type=float, help=f"a = |MM - LM| in metres ({absent})")
    p.add_argument("--foot-length-m", type=float, help="heel-to-toe foot length in metres "
                   "(default: 0.152 x height, Drillis & Contini 1966)")
    p.add_argument("--sensor-to-model", type=float, nargs=3, metavar=("RX", "RY", "RZ"),
                   help="fixed world rotation (rad, space-fixed XYZ) as OpenSense's "
                   "sensor_to_opensim_rotations, making the world's y axis point up; default 0 0 0 "
                   "(already y-up); an Xsens z-up world needs -1.5708 0 0")
    p.add_argument("--heading", help="how the subject's forward direction is found at the "
                   "calibration pose: 'anatomical' (from hip and knee flexion, independent of "
                   "sensor mounting; default) or OpenSense's 'pelvis_imu:-z' style")
    p.add_argument("--segment-orientations", action="store_const", const=True, help="the "
                   "orientations are segment frames (ISB), e.g. an Xsens MVN or FOHEART suit "
                   "export: no sensor placement is estimated (default: sensor orientations)")
    p.add_argument("--calibration-pose", choices=CALIBRATION_POSES, help="the pose at the first "
                   f"sample (or in --static-trial) (default {DEFAULT_CALIBRATION_POSE})")
    p.add_argument("--static-trial", type=Path, help="a separate static recording (same sensors) "
                   "that gives the calibration pose (default: the first sample of the trial)")
    p.add_argument("--filter", choices=FILTERS, help="attitude filter for raw gyroscope and "
                   "accelerometer (and magnetometer) signals: VQF or Hu's PI filter; also replaces "
                   "orientations the recording has (default: the recording's own orientations, "
                   f"{DEFAULT_FILTER} where it has none)")
    p.add_argument("--calibration-method", choices=(*METHODS, "none"), help="joint-constraint "
                   "calibration of knees with raw signals, reported with its trust decision "
                   f"(default {DEFAULT_METHOD}; none skips it)")
    p.add_argument("--drift", choices=DRIFT_CORRECTIONS, help="heading drift between the "
                   "sensors: each leg's sensors turned into the pelvis sensor's heading by the "
                   "joint constraints (hip and ankle centres, knee hinge axis) where their "
                   "calibrations hold (joints), only for 6-D filter output, whose headings are "
                   "each sensor's own (auto, default), or never (none)")
    p.add_argument("--knee", choices=KNEE_MODES, help=f"knee model (default {DEFAULT_KNEE})")
    p.add_argument("--correction", choices=CORRECTIONS, help="knee-AoR orientation correction: "
                   "Wang eq 9-13 closed form (aor), whole-trial IPOPT (aor-ipopt), the closed form "
                   "towards the gyroscopes' hinge axis where the knee's functional calibration "
                   f"is trusted (functional) or none (default {DEFAULT_CORRECTION})")
    for seg in ("femur", "tibia"):
        p.add_argument(f"--knee-axis-{seg}", type=float, nargs=3, metavar=("X", "Y", "Z"),
                       help=f"the subject's knee AoR in the {seg} frame (pointing right), for "
                       "the hinge and the correction; default: the population mean of the "
                       "subject's sex (Wang 2023 dataset)")
    p.add_argument("--no-joint-limits", action="store_const", const=False, dest="joint_limits",
                   help="let the joints leave the model's ranges (default: limited)")
    p.add_argument("--no-rerun", action="store_const", const=False, dest="rerun",
                   help="do not write the .rrd recording (default: written)")
    p.add_argument("--osim", action="store_const", const=True, help="also write <name>.osim, an "
                   "OpenSim model whose coordinates are the .mot's columns (default: not written)")
    p.add_argument("--strict", action="store_const", const=True,
                   help="implausible results (e.g. a large orientation residual) exit with code 3 "
                   "and write nothing (default: they are flagged in the summary and on stderr)")
    p.add_argument("--out", type=Path, help="output directory (required, here or in --config)")
