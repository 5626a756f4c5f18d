"""pipeline.calibration.observability: rank and SD diagnostics, by hand and on simulated motions."""

from __future__ import annotations

import numpy as np

from pipeline.calibration.joint_constraints import joint_data, project_hinge_positions
from pipeline.calibration.observability import diagnose, observability
from pipeline.simulate.joint_trials import hinge_trial


def test_observability_by_hand():
    # J = diag(4, 2, 0) on N = 4 rows: singular values of J / sqrt(4) are (2, 1, 0); the third
    # parameter is unobservable and named after its block
    J = np.zeros((4, 3))
    J[0, 0], J[1, 1] = 4.0, 2.0
    d = observability(J, {"a": slice(0, 1), "b": slice(1, 2), "c": slice(2, 3)})
    np.testing.assert_allclose(d.singular_values, [2.0, 1.0, 0.0])
    assert d.undetermined == ("c",) and "undetermined" in d.message
    # a residual of RMS 0.1 predicts SDs rms / (sqrt(N) s) = 0.1 / (2 * (2, 1)) = (0.025, 0.05)
    d2 = observability(J[:, :2], {"a": slice(0, 1), "b": slice(1, 2)}, residual=np.full(4, 0.1),
                       abs_tol=0.04)
    np.testing.assert_allclose(d2.sd, [0.025, 0.05])
    assert d2.undetermined == ("b",) and d2.condition == 2.0


def test_observability_flags_the_still_thigh():
    rich = hinge_trial("rich", duration=8.0)
    still = hinge_trial("still_thigh", duration=8.0)
    out = {}
    for name, tr in (("rich", rich), ("still", still)):
        d = joint_data(tr.time, tr.imu_1.gyr, tr.imu_1.acc, tr.imu_2.gyr, tr.imu_2.acc)
        p1, p2 = project_hinge_positions(tr.position_1, tr.position_2, tr.axis_1, tr.axis_2)
        out[name] = diagnose(d, tr.axis_1, tr.axis_2, p1, p2)
    assert out["rich"].undetermined == ()
    assert out["rich"].expected == ("position along the hinge axis",)
    assert "axis_1 (sensor 1)" in out["still"].undetermined
    assert "axis_2 (sensor 2)" not in out["still"].undetermined
    assert "position_1 (sensor 1)" in out["still"].undetermined
    assert "axis_1" in out["still"].message
