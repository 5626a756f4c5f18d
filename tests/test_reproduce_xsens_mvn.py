"""Xsens MVN exports and optical C3D files (pipeline.reproduce.wang2023.xsens_mvn): hand cases, a
synthetic leg with a known hip, and the published files' labels."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from pipeline.errors import InputError
from pipeline.io.c3d import C3dMarkers
from pipeline.reproduce.wang2023.xsens_mvn import (
    LANDMARKS,
    MVN_LABELS,
    OMC_LABELS,
    MvnStaticModel,
    height_from_filename,
    landmark_tibia_frames,
    linear_in_height,
    mvn_hip_offset,
    mvn_hip_trajectory,
    pelvis_frames,
    resample,
)
from pipeline.rotations import exp3, rot_z

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "wang2023"


# ------------------------------------------------------------------------------ hand cases

# ------------------------------------------------------------------------------ hand cases


def test_height_from_filename():
    assert height_from_filename("x/Test_static_170_24.7_t.c3d") == pytest.approx(1.70)
    assert height_from_filename("Test_static_160__23.33_t.c3d") == pytest.approx(1.60)
    with pytest.raises(InputError):
        height_from_filename("static.c3d")


def test_pelvis_and_landmark_tibia_frames_on_hand_cases():
    # ASIS on the z axis, sacrum behind: the pelvis frame is the world frame
    P = pelvis_frames(np.array([[0, 0, 0.1]]), np.array([[0, 0, -0.1]]), np.array([[-0.1, 0, 0]]))
    np.testing.assert_allclose(P[0], np.eye(3), atol=1e-12)
    # knee above the ankle, lateral malleolus to the right: the tibia frame is the world frame
    T = landmark_tibia_frames(
        np.array([[0, 0.4, 0]]), np.array([[0, 0, -0.03]]), np.array([[0, 0, 0.03]])
    )
    np.testing.assert_allclose(T[0], np.eye(3), atol=1e-12)


def test_resample_linear_signal_exactly():
    t = np.arange(241) / 240.0  # 1 s at 240 Hz
    x = np.column_stack([t, 2 * t, -t])
    y = resample(t, x, 100.0)
    assert y.shape == (101, 3)
    np.testing.assert_allclose(y[:, 1], 2 * np.arange(101) / 100.0, atol=1e-12)


def test_mvn_hip_offset_recovers_the_hip_of_a_synthetic_leg():
    """A leg swings about a hip 0.34 ASIS widths lateral of pHipOrigin in a moving pelvis."""
    rng = np.random.default_rng(0)
    n, width = 200, 0.24
    hip_local = np.array([0.0, 0.0, 0.34 * width])
    pelvis_local = {"pRightASI": [0.1, 0.05, width / 2], "pLeftASI": [0.1, 0.05, -width / 2],
                    "pSacrum": [-0.04, 0.05, 0.0], "pHipOrigin": [0.0, 0.0, 0.0]}
    knee_local = {"EFM": np.array([0.0, -0.4, -0.045]), "EFL": np.array([0.0, -0.4, 0.045])}
    angles = np.linspace(0, 1.4, n)
    # the pelvis rotates (up to ~10 deg) and translates during the motion, as MVN's does
    R_pelvis = [exp3(np.array([0.05, 0.3, -0.02]) + 0.15 * np.sin(a) * np.array([1, 0, 1]))
                for a in angles]
    origin = np.array([0.5, 0.9, 0.2]) + 0.02 * np.sin(3 * angles)[:, None]
    axis_tilt = exp3(rng.normal(scale=0.2, size=3))
    points = {
        name: np.stack([R @ np.asarray(p) + o for R, o in zip(R_pelvis, origin, strict=True)])
        for name, p in pelvis_local.items()
    }
    hip_world = np.stack([R @ hip_local + o for R, o in zip(R_pelvis, origin, strict=True)])
    for name, p in knee_local.items():
        # hip flexion about a (tilted) z axis plus some abduction so the fit is well posed
        rot = [rot_z(a) @ axis_tilt @ exp3(np.array([0.3 * np.sin(3 * a), 0, 0])) for a in angles]
        points[MVN_LABELS[name]] = np.stack(
            [R @ (hip_local + r @ p) + o for R, r, o in zip(R_pelvis, rot, origin, strict=True)]
        )
    labels = tuple(points)
    m = C3dMarkers(labels, np.stack([points[k] for k in labels], axis=1), 100.0,
                   np.arange(n) / 100.0, "m")
    offset, rms = mvn_hip_offset(m)
    np.testing.assert_allclose(offset, hip_local / width, atol=1e-9)
    assert rms < 1e-9
    np.testing.assert_allclose(mvn_hip_trajectory(m), hip_world, atol=1e-9)


def _fake_model(h: float, a: dict, b: dict) -> MvnStaticModel:
    seg = {n: a[n] + b[n] * h for n in LANDMARKS}
    return MvnStaticModel(Path("x.c3d"), h, h, np.zeros(3), seg, seg, 0.0)


def test_linear_in_height_by_hand():
    a = {n: np.array([0.01, -0.02, 0.03]) * (i + 1) for i, n in enumerate(LANDMARKS)}
    b = {n: np.array([0.0, -0.25, 0.02]) for n in LANDMARKS}
    models = [_fake_model(h, a, b) for h in (1.5, 1.6, 1.7, 1.8, 1.9)]
    line, resid = linear_in_height(models)
    assert resid < 1e-12
    for n in LANDMARKS:
        np.testing.assert_allclose(line[n][0], a[n], atol=1e-12)
        np.testing.assert_allclose(line[n][1], b[n], atol=1e-12)
    with pytest.raises(InputError):
        linear_in_height(models[:1])
    assert replace(models[0], height_m=2.0).height_m == 2.0  # frozen dataclass stays usable


# ------------------------------------------------------------------------------ published data


@pytest.mark.dataset
def test_subject2_digitised_points_are_the_landmarks_of_rawdata():
    if not (DATA / "xsens").is_dir():
        pytest.skip(f"dataset not found at {DATA}")
    from matio import load_from_mat

    from pipeline.io.c3d import read_c3d

    folder = DATA / "xsens" / "Subject2" / "HipF1"
    c = read_c3d(folder / "OMCHipF1.c3d")
    ref = load_from_mat(str(folder / "rawData.mat"))["omcData"].properties
    for label, name in OMC_LABELS.items():
        if label in c.labels:
            d = c.marker(label) - 1e-3 * ref["R" + name]  # constant = the hip centre
            assert np.nanstd(d, axis=0).max() < 1e-4, label
