"""Helpers shared by several test files (not collected: no ``test_`` prefix)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pipeline.model import SubjectGeometry
from pipeline.rotations import exp3, normalize, quat_from_matrix

#: Reflection through the sagittal plane (z -> -z), right leg <-> left leg.
MIRROR = np.diag([1.0, 1.0, -1.0])
RATE = 100.0
#: The shared data folder and the real walk S02's sensor map (its README).
DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
S02 = DATA / "gaittoolbox_s02"
S02_MAP = {"pelvis_imu": "00B40B91", "femur_l_imu": "00B40C45", "femur_r_imu": "00B40C3C",
           "tibia_l_imu": "00B40C44", "tibia_r_imu": "00B40C47", "calcn_l_imu": "00B40C55",
           "calcn_r_imu": "00B40C48"}


def s02_cut(start: int, stop: int | None = None, path: str = "vendor"):
    """S02 (read with its map) cut to samples ``[start, stop)``, its time from 0, as a recording
    that starts or ends there; ``path``: ``'vendor'`` (its orientations, in its z-up world) or
    ``'vqf6'`` (raw signals without the orientations and magnetometers). None without the data."""

    from pipeline.io.formats import read_recording

    if not S02.exists():
        return None
    rec = read_recording(S02 / "imu", S02_MAP).cropped(start, stop)
    if path == "vqf6":
        rec = rec.with_sensors({n: s.replace(quat=None, mag=None) for n, s in rec.sensors.items()})
    return rec


def asymmetric_subject(**over: object) -> SubjectGeometry:
    """An asymmetric, non-trivial right-leg geometry (tilted knee axes, off-plane landmarks)."""
    kw = dict(
        sex="f",
        height_m=1.62,
        femur_landmarks={"EFM": [0.006, -0.372, -0.047], "EFL": [-0.004, -0.386, 0.045]},
        tibia_landmarks={"MM": [-0.012, -0.356, -0.031], "LM": [0.010, -0.374, 0.033]},
        knee_axis_femur=normalize(np.array([0.08, -0.12, 1.0])),
        knee_axis_tibia=normalize(np.array([-0.05, 0.10, 1.0])),
    )
    kw.update(over)
    return SubjectGeometry(**kw)


def times(n: int = 200, rate: float = RATE) -> np.ndarray:
    return np.arange(n) / rate


def rotation_about_axis(t: np.ndarray, axis=(1.0, 2.0, 2.0), w: float = 1.5) -> np.ndarray:
    """Quaternions of a constant-rate rotation about a fixed axis (a geodesic: slerp is exact)."""
    a = np.asarray(axis) / np.linalg.norm(axis)
    R0 = exp3(np.array([0.3, -0.2, 0.1]))
    return quat_from_matrix(R0 @ exp3(w * t[:, None] * a))


def read_blueprint(path: str | Path) -> dict[str, dict[str, list]]:
    """A file's (default) blueprint: entity path -> ``Archetype:field`` -> first row's value."""
    from rerun.chunk import RrdReader

    reader = RrdReader(path)
    (store,) = reader.blueprints()
    out: dict[str, dict[str, list]] = {}
    for c in reader.stream(store=store).to_chunks():
        rb = c.to_record_batch()
        row = {n: rb.column(n).to_pylist()[0] for n in rb.schema.names if ":" in n}
        out.setdefault(c.entity_path, {}).update(row)
    return out


def blueprint_views(bp: dict[str, dict[str, list]]) -> dict[str, tuple[str, str, str]]:
    """View title -> (class, origin, blueprint entity path)."""
    return {
        v["ViewBlueprint:display_name"][0]: (
            v["ViewBlueprint:class_identifier"][0],
            v["ViewBlueprint:space_origin"][0],
            path,
        )
        for path, v in bp.items()
        if "ViewBlueprint:class_identifier" in v
    }


def imu_recording(time, gyr, acc, quat=None):
    """A one-sensor recording of raw signals (what an IMU CSV holds)."""
    from pipeline.io.recording import Recording

    return Recording.single("imu", time, gyr=gyr, acc=acc, quat=quat)


def knee_truth(sim):
    """``(truth, axis_1, axis_2, position_1, position_2)`` of the right knee written by
    ``pipeline simulate`` into ``sim/truth.json``, positions projected as Hu eq 16 does."""
    import json

    from pipeline.calibration.joint_constraints import project_hinge_positions

    truth = json.loads((sim / "truth" / "truth.json").read_text())
    k = truth["joints"]["right_knee"]
    j1, j2 = np.array(k["axis_1"]), np.array(k["axis_2"])
    o1, o2 = project_hinge_positions(
        np.array(k["position_1_m"]), np.array(k["position_2_m"]), j1, j2
    )
    return truth, j1, j2, o1, o2


def qmt_recording(data: Path):
    """The qmt_full_body recording's pelvis and leg sensors (gyroscopes and accelerometers) under
    our names, or None where ``data`` (the shared data folder) does not hold it."""
    import scipy.io as sio

    from pipeline.io.recording import Recording, SensorSignals

    path = Path(data) / "qmt_full_body" / "full_body_example_data.mat"
    if not path.exists():
        return None
    d = sio.loadmat(path, squeeze_me=True, struct_as_record=False)
    names = {"hip": "pelvis_imu", "upper_leg_left": "femur_l_imu",
             "upper_leg_right": "femur_r_imu", "lower_leg_left": "tibia_l_imu",
             "lower_leg_right": "tibia_r_imu", "foot_left": "calcn_l_imu",
             "foot_right": "calcn_r_imu"}
    return Recording(d["t"] - d["t"][0], 100.0, {n: SensorSignals(
        gyr=np.asarray(d[k].gyr, float), acc=np.asarray(d[k].acc, float))
        for k, n in names.items()})
