"""Full sensor-to-segment correction (pipeline.calibration.full_correction): recovery of known
sensor errors on a simulated supine hip-knee flexion, and bad input."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.calibration.aor import correction_rotations, knee_aor
from pipeline.calibration.full_correction import full_correction_ipopt
from pipeline.calibration.priors import CorrectionPriors
from pipeline.errors import InputError
from pipeline.rotations import angle_between, exp3, normalize, rot_x, rotation_aligning

B_F = normalize(np.array([-0.12, -0.10, 0.99]))  # knee axis, femoral frame
B_T = normalize(np.array([0.05, 0.08, 0.99]))  # knee axis, tibial frame
# knee centre in the femoral frame (m, hip at the origin) and ankle centre in the tibial frame
# (knee at the origin), both in the plane of the motion (perpendicular to the knee axis)
KNEE = -0.42 * normalize(np.cross(B_F, np.cross([0.0, 1.0, 0.0], B_F)))
ANKLE = -0.40 * normalize(np.cross(B_T, np.cross([0.0, 1.0, 0.0], B_T)))
REST_FLEXION = np.radians(6.0)


def angle(A: np.ndarray, B: np.ndarray) -> float:
    c = np.clip((np.trace(A.T @ B) - 1) / 2, -1.0, 1.0)
    return float(np.degrees(np.arccos(c)))


def knee_rotation(theta: np.ndarray) -> np.ndarray:
    """Anatomical knee ``E_Fᵀ E_T``: a hinge about ``B_T`` (tibia) = ``B_F`` (femur)."""
    A = rotation_aligning(B_T, B_F)
    return A @ exp3(np.multiply.outer(-np.asarray(theta), B_T))


def supine_flexion(n: int = 1500, rate: float = 100.0):
    """Anatomical femur and tibia of a planar supine hip-knee flexion: 0.4 s at rest, then three
    flexion cycles (hip 0-70 deg, knee 6-100 deg), femur rotating about its knee axis."""
    t = np.arange(n) / rate
    s = np.clip(t - 0.4, 0.0, None)
    cyc = 0.5 * (1 - np.cos(2 * np.pi * s / 4.5))
    hip, knee = np.radians(70.0) * cyc, REST_FLEXION + np.radians(94.0) * cyc
    F0 = rot_x(np.pi / 2)  # supine: anterior up
    n_world = F0 @ B_F
    F = exp3(np.multiply.outer(hip, n_world)) @ F0
    T = F @ knee_rotation(knee)
    return F, T


def exact_priors(**kw) -> CorrectionPriors:
    base = dict(femur_axis=B_F, tibia_axis=B_T, sd_femur_axis=np.radians(5.0),
                sd_tibia_axis=np.radians(5.0), rest_knee=knee_rotation(REST_FLEXION),
                rest_knee_cov=np.radians(5.0) ** 2 * np.eye(3), hinge_sd=np.radians(2.0),
                plane_sd=0.02, n_subjects=10)
    return CorrectionPriors(**{**base, **kw})


def test_recovers_known_sensor_errors_the_axis_alone_cannot():
    F, T = supine_flexion()
    W = exp3(np.array([0.3, -1.1, 0.7]))  # unknown IMU world (heading and tilt)
    D_F = exp3(np.radians(8.0) * normalize(np.cross(B_F, [1.0, 0.0, 0.0])))  # ⟂ the knee axis
    D_T = exp3(np.radians([6.0, 9.0, -12.0]))  # any rotation, incl. a flexion offset
    F_imu, T_imu = W @ F @ D_F, W @ T @ D_T
    c = full_correction_ipopt(F_imu, T_imu, KNEE, ANKLE, exact_priors())
    assert c.success, c.status
    assert angle(c.R_co_femur, D_F.T) < 0.2
    assert angle(c.R_co_tibia, D_T.T) < 0.2
    assert c.hinge_rms < np.radians(0.1) and c.rest_deg[1] < 0.2 and c.plane_rms[1] < 1e-3
    # eq 9-12 align the axes only: the tibia's flexion offset stays
    R0F, R0T = correction_rotations(knee_aor(F_imu, T_imu), B_F, B_T)
    assert angle(R0T, D_T.T) > 5.0
    assert c.rest_deg[0] > 5.0
    # the corrected knee is the true one at every sample
    K_true = np.einsum("nji,njk->nik", F, T)
    K_hat = np.einsum("ij,nkj,nkl,lm->nim", c.R_co_femur.T, F_imu, T_imu, c.R_co_tibia)
    assert max(angle(a, b) for a, b in zip(K_true[::50], K_hat[::50], strict=True)) < 0.3


def test_the_femurs_rotation_about_the_knee_axis_is_left_to_the_closed_form():
    # a femur error about the knee axis cannot be seen without the world's vertical: the
    # correction keeps the smallest rotation (the closed form's) for it
    F, T = supine_flexion()
    D_F = exp3(np.radians(10.0) * B_F)
    c = full_correction_ipopt(F @ D_F, T, KNEE, ANKLE, exact_priors())
    R0F, _ = correction_rotations(knee_aor(F @ D_F, T), B_F, B_T)
    assert angle(c.R_co_femur, R0F) < 0.05
    assert angle_between(c.R_co_femur @ B_F, D_F.T @ B_F) < np.radians(0.1)


def test_bad_input_is_refused_with_the_field():
    F, T = supine_flexion()
    with pytest.raises(InputError, match="knee_centre"):
        full_correction_ipopt(F, T, np.array([0.0, np.nan, 0.0]), ANKLE, exact_priors())
    still = np.repeat(F[:1], 200, axis=0)
    with pytest.raises(InputError, match="never moves|moving knee"):
        full_correction_ipopt(still, still, KNEE, ANKLE, exact_priors())
    with pytest.raises(InputError, match="loss"):
        full_correction_ipopt(F, T, KNEE, ANKLE, exact_priors(), loss="l1")
