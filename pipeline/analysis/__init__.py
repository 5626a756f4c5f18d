"""Analysis (stage 5): a model and its configurations in, what biomechanists read out: anatomical
landmark trajectories (Wang eq 15-17 as forward kinematics of landmark frames) and ISB joint
angles (Grood & Suntay JCS, ZXY).

The public names below load their module on first use (:mod:`pipeline._lazy`).
"""

from pipeline._lazy import lazy_exports

_EXPORTS = {
    "AT_LIMIT_SHARE": "quality",
    "AT_LIMIT_TOL": "quality",
    "frame_trajectories": "landmarks",
    "jcs_angles": "joint_angles",
    "joint_angles": "joint_angles",
    "landmark_trajectories": "landmarks",
    "quality_flags": "quality",
    "RESIDUAL_BOUND_DEG": "quality",
    "wang_trajectories": "landmarks",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
