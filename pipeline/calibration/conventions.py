"""Names of the calibration, importable at no cost (the CLI's choices come from here): the
joint-constraint joints, methods and default method (:mod:`pipeline.calibration.calibrate`), the
knee-AoR orientation corrections (:mod:`pipeline.calibration.correction`) and the calibration
poses (:func:`pipeline.calibration.placement.pose_rotations`)."""

from __future__ import annotations

__all__ = [
    "CALIBRATION_POSES",
    "CALIBRATIONS",
    "CORRECTIONS",
    "DEFAULT_CALIBRATION_POSE",
    "DEFAULT_CORRECTION",
    "DRIFT_CORRECTIONS",
    "DEFAULT_FILTER",
    "DEFAULT_METHOD",
    "FILTERS",
    "HEADINGS",
    "JOINTS",
    "METHODS",
    "POSTURES",
]

METHODS = ("gn", "dwpso", "gwo", "ipopt")
DEFAULT_METHOD = "ipopt"
JOINTS = ("hinge", "spherical")

#: Knee-AoR orientation corrections: none, Wang eq 9-13 (closed form), the whole-trial IPOPT NLP,
#: and the closed form towards the knee's joint-constraint hinge axis (Hu 2021 eq 4-6, from the
#: gyroscopes; only where that calibration is trusted, else eq 1-8 as ``aor``).
CORRECTIONS = ("none", "aor", "aor-ipopt", "functional")
#: The correction used when none is asked for: none. Across the real S02 walk, OpenSense's walking
#: file and the simulator (``results/bench_defaults.txt``) no correction measures best: eq 1-8
#: read a knee that is not a hinge as a turned sensor. The closed form is for recordings whose
#: sensors are turned on the shank: on the Wang dataset's ``uncorrected`` IMC input it halves the
#: malleolus errors (mean MM/LM 105/109 mm without it, 67/72 mm with it; ``results/wang2023``).
DEFAULT_CORRECTION = "none"
#: Poses the first sample (or a static trial) may show: the model's neutral standing pose,
#: lying on the back with the same joint angles, or sitting (hips and knees flexed 90 deg).
CALIBRATION_POSES = ("standing", "supine", "seated")
#: The ``calibration_pose`` option's choices: a pose held in a still window (found in the
#: recording, :mod:`pipeline.process.pose_source`), or ``walking``: no pose, each sensor's
#: placement from the walk itself (:mod:`pipeline.process.walking_pose`).
CALIBRATIONS = (*CALIBRATION_POSES, "walking")
DEFAULT_CALIBRATION_POSE = "standing"
#: Attitude filters for raw signals: VQF (Laidig & Seel 2023, the default) and Hu's PI filter.
FILTERS = ("vqf", "pi")
DEFAULT_FILTER = "vqf"
#: The standing posture at the calibration pose (:mod:`pipeline.process.posture`): measured from
#: the joint centres, or the model's neutral pose.
POSTURES = ("measured", "neutral")
#: Heading alignment by the joints (:mod:`pipeline.process.heading_alignment`): ``'auto'`` turns
#: every sensor whose heading is its own (6-D filter output, a disturbed magnetometer's sensor)
#: into its neighbour's world by the joint constraints; ``'joints'`` every sensor; ``'none'`` none.
DRIFT_CORRECTIONS = ("auto", "joints", "none")
#: How the subject's forward direction is found at the calibration pose
#: (:mod:`pipeline.calibration.heading`): from the motion, or an axis of the pelvis sensor
#: (OpenSense's convention, e.g. ``pelvis_imu:-z``).
HEADINGS = ("anatomical",) + tuple(f"pelvis_imu:{s}{a}" for s in ("", "-") for a in "xyz")
