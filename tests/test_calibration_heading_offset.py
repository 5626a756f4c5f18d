"""pipeline.calibration.heading_offset: eq (1), the least-squares heading between two sensors'
views of one vector (a hinge axis, a joint centre's force), on cases checked by hand."""

import numpy as np
import pytest

from pipeline.calibration.heading_offset import (
    MIN_HORIZONTAL,
    heading_between,
    hinge_heading,
    turn_about_vertical,
)
from pipeline.errors import InputError
from pipeline.rotations import exp3, rot_y, rot_z

UP = np.array([0.0, 1.0, 0.0])


def test_turn_about_vertical_is_a_rotation_about_up():
    R = exp3(np.array([[0.3, -0.2, 0.5], [0.0, 0.0, 0.0]]))
    psi = np.array([0.7, -2.0])
    out = turn_about_vertical(R, psi, UP)
    np.testing.assert_allclose(out, rot_y(psi) @ R, atol=1e-12)
    np.testing.assert_allclose(turn_about_vertical(R, psi, np.array([0, 0, 2.0])), rot_z(psi) @ R,
                               atol=1e-12)


def test_a_constant_heading_is_recovered_exactly_from_a_horizontal_axis():
    # u = (1, 0, 0) seen by sensor 1; sensor 2's world is turned by -psi about y, so it sees
    # v = Ry(-psi) u: eq (1) must give psi = atan2(g.(v x u), u.v) = psi
    n = 400
    u = np.tile([1.0, 0.0, 0.0], (n, 1))
    v = (rot_y(-0.6) @ u.T).T
    d = heading_between(u, v, 100.0, up=UP)
    np.testing.assert_allclose(d.psi, 0.6, atol=1e-12)
    assert d.residual_deg < 1e-6 and d.drift_deg < 1e-9 and d.vertical_deg < 1e-9


def test_a_linear_drift_through_an_angle_of_pi_is_followed_and_unwrapped():
    n, rate = 3000, 100.0
    t = np.arange(n) / rate
    true = 0.5 + 0.12 * t  # 0.5 to 4.1 rad: crosses pi
    rng = np.random.default_rng(0)
    R_1 = exp3(rng.normal(0, 0.3, (n, 3)))  # any motion of the proximal sensor
    axis_1 = np.array([0.0, 0.0, 1.0])
    M = exp3(np.array([0.2, 0.1, -0.3]))  # the distal sensor on its segment
    flexion = np.sin(2 * t)[:, None] * axis_1  # the hinge turns about axis_1
    # the distal sensor's world is turned by -true: u = R_1 j_1 = Ry(true) R_2 j_2
    R_2 = rot_y(-true) @ R_1 @ exp3(flexion) @ M
    d = hinge_heading(R_1, R_2, axis_1, M.T @ axis_1, rate, up=UP)
    err = np.degrees(d.psi - true)
    # 14 deg of drift within each 2 s window; the window's weighted mean heading sits within a
    # fraction of a degree of its centre's (the axis' horizontal length varies with the motion)
    assert np.max(np.abs(err[100:-100])) < 0.2
    assert d.drift_deg == pytest.approx(np.degrees(true[-100] - true[100]), abs=1.0)
    assert d.residual_deg < 2.0 < 10 < d.before_deg  # the held ends: 1 s of drift each
    # with the axis horizontal throughout (equal weights) the centres are exact, and linear
    # interpolation between them too
    R_h = rot_y(rng.uniform(-3, 3, n))
    d = hinge_heading(R_h, rot_y(-true) @ R_h @ M, axis_1, M.T @ axis_1, rate, up=UP)
    assert np.max(np.abs(np.degrees(d.psi - true)[100:-100])) < 1e-9


def test_a_vertical_axis_is_refused_and_nan_rows_are_ignored():
    n = 300
    up = np.tile(UP, (n, 1))
    with pytest.raises(InputError, match="not observable"):
        heading_between(up, up, 100.0, up=UP)
    u = np.tile([0.0, 0.0, 1.0], (n, 1))
    v = (rot_y(0.4) @ u.T).T
    u[::7] = np.nan
    assert np.allclose(heading_between(u, v, 100.0, up=UP).psi, -0.4)


def test_windows_of_a_steep_axis_are_skipped():
    # the first half: the axis 80 deg from horizontal (weight cos^2 80 = 0.03 < MIN_HORIZONTAL);
    # the second: horizontal at a heading of 0.3; psi is held at 0.3 over the steep half
    n = 1000
    steep = np.array([np.cos(np.radians(80)), np.sin(np.radians(80)), 0.0])
    u = np.vstack([np.tile(steep, (n // 2, 1)), np.tile([1.0, 0, 0], (n // 2, 1))])
    v = (rot_y(-0.3) @ u.T).T
    v[: n // 2] = (rot_y(1.0) @ u[: n // 2].T).T  # nonsense heading where it is unobservable
    assert np.cos(np.radians(80)) ** 2 < MIN_HORIZONTAL
    d = heading_between(u, v, 100.0, up=UP)
    assert d.used < d.windows
    # the windows across the change mix both halves; from the first all-horizontal one on, exact
    np.testing.assert_allclose(d.psi[n // 2 + 200:], 0.3, atol=1e-9)
    assert abs(d.psi[0] - 0.3) < 0.05  # held from the first informative window, not 1.0


def test_bad_shapes_are_refused():
    with pytest.raises(InputError, match="one length"):
        heading_between(np.zeros((5, 3)), np.zeros((4, 3)), 100.0)
    with pytest.raises(InputError, match="orientation"):
        hinge_heading(np.zeros((5, 3, 3)), np.zeros((5, 3)), np.ones(3), np.ones(3), 100.0)
    with pytest.raises(InputError, match="positive rate"):
        heading_between(np.ones((5, 3)), np.ones((5, 3)), 0.0)


def test_windows_whose_samples_disagree_are_left_out():
    # u horizontal and turning; v agrees (heading 0.3) except in the middle second, where every
    # other sample says -0.9: the mean resultant length there is ~0.6 < MIN_AGREEMENT
    n = 1000
    ang = np.linspace(0, 6, n)
    u = np.stack([np.cos(ang), np.zeros(n), np.sin(ang)], axis=1)
    turn = np.full(n, -0.3)
    turn[450:550:2] = 0.9
    v = np.einsum("nij,nj->ni", rot_y(turn), u)
    d = heading_between(u, v, 100.0, up=UP)
    everything = heading_between(u, v, 100.0, up=UP, min_agreement=0.0)
    assert d.used < d.windows == everything.used
    # the window centred on the bad second (half its samples contradict) is left out; the ones
    # reaching into it by a quarter still pass, so psi stays within 0.15 rad there, where
    # averaging every window swings it by more than 0.2 rad (measured 0.13 and 0.27)
    assert np.max(np.abs(d.psi - 0.3)) < 0.15 < 0.2 < np.max(np.abs(everything.psi - 0.3))
    np.testing.assert_allclose(d.psi[:250], 0.3, atol=1e-9)
    bad = v.copy()
    bad[::2] = np.einsum("nij,nj->ni", rot_y(np.full(n // 2, 2.0)), u[::2])
    with pytest.raises(InputError, match="do not agree within any window"):
        heading_between(u, bad, 100.0, up=UP)


def test_no_window_crosses_a_break_and_each_run_has_its_own_heading():
    """A distal filter that started again after a gap (``breaks``): its heading jumps there.
    Each run's windows alone give its heading (exact on both sides, where a window across the
    break would average the two); a run without an informative window is NaN, not held."""
    n = 1200
    u = np.tile([1.0, 0.0, 0.0], (n, 1))
    true = np.where(np.arange(n) < 600, 0.6, -2.0)  # the heading jumps at the gap
    v = np.einsum("nij,nj->ni", rot_y(-true), u)
    breaks = np.zeros(n, dtype=bool)
    breaks[560:600] = True
    v[560:600] = np.nan  # the distal sensor's gap
    d = heading_between(u, v, 100.0, up=UP, breaks=breaks)
    np.testing.assert_allclose(d.psi[:560], 0.6, atol=1e-12)
    np.testing.assert_allclose(d.psi[600:], -2.0, atol=1e-12)
    ignored = heading_between(u, v, 100.0, up=UP)  # without the break: windows mix the two
    assert np.max(np.abs(ignored.psi[600:] + 2.0)) > 0.1
    u_still = u.copy()
    u_still[600:] = [0.0, 1.0, 0.0]  # vertical after the gap: nothing shows the heading there
    d = heading_between(u_still, v, 100.0, up=UP, breaks=breaks)
    assert np.isnan(d.psi[600:]).all() and np.isfinite(d.psi[:560]).all()
