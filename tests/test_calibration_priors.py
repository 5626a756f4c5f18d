"""Population priors of the full correction (pipeline.calibration.priors): the rest-pose
residual by hand, the rest rotation, and priors learned from simulated optical knees."""

from __future__ import annotations

import numpy as np
import pytest
from test_calibration_full_correction import (
    ANKLE,
    KNEE,
    REST_FLEXION,
    angle,
    knee_rotation,
    supine_flexion,
)

from pipeline.calibration.aor import knee_aor
from pipeline.calibration.priors import KneeTrial, correction_priors, rest_error, rest_rotation
from pipeline.errors import InputError
from pipeline.rotations import angle_between, exp3, normalize, rot_z


def test_rest_error_is_sine_times_axis():
    # by hand: Rz(30 deg) - Rz(30 deg)^T has (1,0) - (0,1) = 2 sin 30 deg
    e = rest_error(rot_z(np.radians(30.0)))
    assert np.allclose(e, [0.0, 0.0, 0.5])
    axis = normalize(np.array([1.0, 2.0, -2.0]))
    assert np.allclose(rest_error(exp3(0.4 * axis)), np.sin(0.4) * axis)


def test_rest_rotation_averages_the_first_valid_samples():
    F, T = supine_flexion()
    F = F.copy()
    F[:3] = np.nan
    K = rest_rotation(F, T, 10)
    assert angle(K, knee_rotation(REST_FLEXION)) < 1e-4


def test_priors_from_optical_knees():
    F, T = supine_flexion()
    aor = knee_aor(F, T)
    knee = F @ KNEE
    ankle = knee + T @ ANKLE
    trials = []
    for twist in (-4.0, 0.0, 4.0):
        Tk = T @ rot_z(np.radians(twist))  # rest flexion differs by subject
        trials.append(KneeTrial(F, Tk, aor, knee, ankle))
    p = correction_priors(trials)
    assert angle_between(p.femur_axis, aor.femur_axis) < 1e-9
    assert p.sd_femur_axis < 1e-9
    assert p.plane_sd < 1e-6  # a planar motion through the hip
    # rest flexion SD of (-4, 0, 4) deg, about the tibial z axis
    assert np.degrees(np.sqrt(p.rest_knee_cov[2, 2])) == pytest.approx(4.0, rel=0.02)
    with pytest.raises(InputError, match="at least two"):
        correction_priors(trials[:1])
