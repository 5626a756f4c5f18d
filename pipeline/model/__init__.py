"""Subject-scaled lower-limb model: geometry (ISB frames, m), URDF builder, Pinocchio wrapper."""

from pipeline.model.builder import (
    LANDMARKS,
    SEGMENTS,
    build_urdf,
    default_imu_placements,
    imu_frame_names,
    joint_names,
    landmark_frame_names,
    resolve_package_uri,
    segment_frame_names,
)
from pipeline.model.geometry import (
    TEMPLATE_HEIGHT_M,
    SubjectGeometry,
    mirror_axis,
    mirror_point,
)
from pipeline.model.skeleton import ROOTS, Skeleton

__all__ = [
    "LANDMARKS",
    "ROOTS",
    "SEGMENTS",
    "TEMPLATE_HEIGHT_M",
    "Skeleton",
    "SubjectGeometry",
    "build_urdf",
    "default_imu_placements",
    "imu_frame_names",
    "joint_names",
    "landmark_frame_names",
    "mirror_axis",
    "mirror_point",
    "resolve_package_uri",
    "segment_frame_names",
]
