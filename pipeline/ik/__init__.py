"""Inverse kinematics (stage 4): a model and world orientations of some of its frames in, joint
configurations ``q(t)`` out (:func:`solve_ik`: exact log-map Jacobians, box limits, warm start).

The public names below load their module on first use (:mod:`pipeline._lazy`).
"""

from pipeline._lazy import lazy_exports

_EXPORTS = {
    "block_frame_rotations": "block",
    "block_setup": "block",
    "BlockSetup": "block",
    "box_margin": "bounds",
    "box_step": "bounds",
    "frame_id": "problem",
    "frame_rotations": "solver",
    "IKProblem": "problem",
    "IKResult": "solver",
    "joint_box": "bounds",
    "orientation_residuals": "solver",
    "OrientationTask": "problem",
    "remove_limits": "bounds",
    "setup_ik": "problem",
    "solve_block": "block",
    "solve_frame": "solver",
    "solve_ik": "solver",
    "solve_linear": "bounds",
    "UNBOUNDED": "bounds",
    "anchor_frames": "anchors",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
