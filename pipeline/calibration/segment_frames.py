"""Segment frames from a joint calibration (Hu et al. 2021 §4, eq 30-38).

Convention: a frame "in sensor S" is the 3x3 matrix whose columns are the segment axes
expressed in the sensor frame, so the segment orientation in the world is ``R_S(t) @ F``. Hu's
eq 35-36 write the transpose (``[x, y, z]^T``, the map from sensor to segment coordinates).
Positions are joint centres seen from the sensor (sensor -> joint), as in
:mod:`pipeline.calibration.joint_constraints`.

* eq 31-34, thigh {L2} in the thigh sensor B: origin at the hip ``J_H``; ``N`` is the foot of the
  perpendicular from ``J_H`` to the knee axis (the line through the knee point along ``r``);
  ``y = (J_H - N)/|J_H - N|``, ``z = r`` (the knee axis, pointing right), ``x = y x z``.
* eq 36, shank {L3} in the shank sensor C: origin ``O``, the foot of the perpendicular from the
  ankle ``J_A`` to the knee axis; ``y = (O - J_A)/|O - J_A|``, ``z = r``, ``x = y x z``.
* eq 37: a segment frame parallel at time 0 to a neighbour's (foot {L4} parallel to {L3}):
  ``F_D = R_D(0)^T R_C(0) F_C``.
* eq 30/38: joint rotation = proximal segment -> distal segment, ``R_prox(t)^T R_dist(t)`` with
  ``R_seg(t) = R_S(t) F``; eq 38's ``R_C^B(0)`` terms re-express the same product through the
  static pose, which is not needed when both sensor orientations share a world frame.
* eq 39-42 (ZXY Cardan angles of the joint rotation):
  :func:`pipeline.rotations.euler_zxy_from_matrix` and
  :func:`pipeline.rotations.matrix_from_euler_zxy`.
"""

from __future__ import annotations

import numpy as np

from pipeline.errors import InputError
from pipeline.rotations import matrix_from_quat, normalize

__all__ = [
    "joint_rotation",
    "parallel_frame",
    "segment_orientation",
    "shank_frame",
    "thigh_frame",
]


def _foot_on_line(point: np.ndarray, line_point: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """Eq 32-33: foot of the perpendicular from ``point`` to a line."""
    d = normalize(np.asarray(direction, float))
    lp = np.asarray(line_point, float)
    return lp + np.dot(np.asarray(point, float) - lp, d) * d


def _frame(y: np.ndarray, z: np.ndarray) -> np.ndarray:
    y = normalize(y)
    z = normalize(z - np.dot(z, y) * y)
    return np.column_stack([np.cross(y, z), y, z])


def thigh_frame(hip: np.ndarray, knee: np.ndarray, knee_axis: np.ndarray) -> np.ndarray:
    """Eq 31-35: thigh {L2} axes (columns) in the thigh sensor frame."""
    n = _foot_on_line(hip, knee, knee_axis)
    if np.linalg.norm(np.asarray(hip) - n) < 1e-6:
        raise InputError("the hip centre lies on the knee axis; cannot build the thigh frame")
    return _frame(np.asarray(hip, float) - n, normalize(np.asarray(knee_axis, float)))


def shank_frame(ankle: np.ndarray, knee: np.ndarray, knee_axis: np.ndarray) -> np.ndarray:
    """Eq 36: shank {L3} axes (columns) in the shank sensor frame (origin on the knee axis)."""
    o = _foot_on_line(ankle, knee, knee_axis)
    if np.linalg.norm(o - np.asarray(ankle)) < 1e-6:
        raise InputError("the ankle centre lies on the knee axis; cannot build the shank frame")
    return _frame(o - np.asarray(ankle, float), normalize(np.asarray(knee_axis, float)))


def parallel_frame(frame_in_a: np.ndarray, R_a0: np.ndarray, R_b0: np.ndarray) -> np.ndarray:
    """Eq 37: the frame, in sensor b, parallel at time 0 to ``frame_in_a`` (sensor a);
    ``R_a0``/``R_b0`` are the sensors' orientations (sensor -> world) at time 0."""
    return np.asarray(R_b0).T @ np.asarray(R_a0) @ np.asarray(frame_in_a)


def segment_orientation(sensor: np.ndarray, frame_in_sensor: np.ndarray) -> np.ndarray:
    """Segment orientations ``R_S(t) F`` from sensor quaternions (N,4) or matrices (N,3,3)."""
    s = np.asarray(sensor, float)
    R = matrix_from_quat(s) if s.shape[-1] == 4 else s
    return R @ np.asarray(frame_in_sensor, float)


def joint_rotation(R_proximal: np.ndarray, R_distal: np.ndarray) -> np.ndarray:
    """Eq 38: the distal segment in the proximal segment's frame, ``R_prox^T R_dist``."""
    return np.swapaxes(np.asarray(R_proximal, float), -1, -2) @ np.asarray(R_distal, float)
