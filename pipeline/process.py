"""IMU inverse kinematics for OpenSim users: `.sto` orientations in, `.mot` joint angles out.

The workflow of OpenSim's OpenSense, on our scaled Pinocchio model:

1. **World.** Sensor orientations ``R_s(t)`` (sensor axes in the IMU world) are pre-multiplied by a
   fixed ``sensor_to_model`` rotation (OpenSense's ``sensor_to_opensim_rotations``, space-fixed XYZ
   angles; ``-pi/2 0 0`` for Xsens' z-up world) so that the world's y axis points up.
2. **Calibration pose.** The first sample is a standing pose: every segment frame is taken as the
   model's neutral pose turned by a heading rotation ``H`` about the vertical, and each IMU's
   placement on its segment follows as ``R_seg,imu = (H R_seg^0)^T R_s(t0)`` with ``R_seg^0`` the
   segment's orientation in the neutral pose (the identity for the free knee; a hinge about a
   tilted AoR turns the tibia and foot by the rotation aligning the tibial AoR onto the femoral).
3. **Heading.** OpenSense aligns a chosen axis of the pelvis sensor with the model's forward axis
   (``heading='pelvis_imu:-z'`` reproduces that). By default (``heading='anatomical'``) we find the
   subject's right from the motion itself, which does not depend on how the sensors were mounted:
   the hip flexes about +right and the knee about -right, so the dominant axis of the thigh's
   rotation relative to the pelvis, and minus that of the shank relative to the thigh (both
   expressed at t0, weighted by angle, over the frames of largest excursion), give the right
   direction; projected on the horizontal plane it fixes ``H`` (forward = up × right).
4. **IK.** Weighted orientation IK of all IMU frames (:func:`pipeline.ik.solver.solve_ik`) with a spherical
   pelvis root; ISB joint angles (:func:`pipeline.analysis.landmarks.joint_angles`) and landmark trajectories
   (pelvis fixed at the origin: translations are not observable from orientations) follow.

Outputs (all or nothing): ``<name>_ik.mot`` (OpenSim coordinate names, degrees),
``<name>_landmarks.csv`` (m), ``<name>.urdf`` (with the calibrated IMU frames), ``<name>.rrd``,
``<name>_summary.md``.
"""

from __future__ import annotations

import time as _time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pipeline.errors import InputError
from pipeline.io.opensim import (
    OrientationTrial,
    map_sensors,
    read_orientations_sto,
    rotate_world,
    sensor_to_opensim_matrix,
)
from pipeline.model.anthropometry import Measures
from pipeline.rotations import (
    angle_between,
    axis_angle,
    euler_zxy_from_matrix,
    matrix_from_quat,
    normalize,
    rot_y,
)

UP = np.array([0.0, 1.0, 0.0])
HEADINGS = ("anatomical",) + tuple(f"pelvis_imu:{s}{a}" for s in ("", "-") for a in "xyz")
#: OpenSim-style coordinate names (Rajagopal 2015 style: knee flexion positive) for our ISB angles.
MOT_NAMES = {
    "hip_flexion": "hip_flexion",
    "hip_adduction": "hip_adduction",
    "hip_rotation": "hip_rotation",
    "knee_flexion": "knee_angle",
    "knee_adduction": "knee_adduction",
    "knee_rotation": "knee_rotation",
}


@dataclass
class IKRun:
    """Everything the `.sto` IK produced (SI units)."""

    time: np.ndarray
    q: np.ndarray
    joint_angles: dict[str, np.ndarray]
    landmarks: dict[str, np.ndarray]
    heading_right: np.ndarray
    heading_method: str
    residual_rms: np.ndarray
    urdf: Path
    seconds_ik: float
    notes: list[str] = field(default_factory=list)


def _segment_rotations(trial: OrientationTrial) -> dict[str, np.ndarray]:
    mapped = map_sensors(trial)
    return {seg: matrix_from_quat(q) for seg, q in mapped.items()}


def _dominant_axis(R_ref: np.ndarray, R_moving: np.ndarray, top: float = 0.2) -> tuple:
    """Angle-weighted mean axis (world, at t0) of the moving sensor's rotation relative to the
    reference sensor since t0, over the ``top`` fraction of frames with the largest angle."""
    rel = np.swapaxes(R_ref, 1, 2) @ R_moving
    change = rel @ rel[0].T  # rotation in the reference sensor's coordinates
    axis, angle = axis_angle(change)
    ok = np.isfinite(angle) & (angle > 0)
    if ok.sum() < 10:
        return None, 0.0
    thresh = np.quantile(angle[ok], 1.0 - top)
    sel = ok & (angle >= thresh)
    v = np.sum(axis[sel] * angle[sel, None], axis=0)
    if np.linalg.norm(v) == 0:
        return None, 0.0
    return R_ref[0] @ normalize(v), float(np.max(angle[ok]))


def anatomical_right(
    rotations: dict[str, np.ndarray], min_excursion: float = 0.35, notes: list[str] | None = None
) -> np.ndarray:
    """The subject's right at t0 from hip (+right) and knee (-right) flexion (module doc, step 3).

    Raises :class:`InputError` when the motion is too small to define an axis (less than
    ``min_excursion`` rad of hip or knee rotation). When a cue points more than 45 deg away from
    the others' mean (horizontal directions), a note says so: the heading may then be unreliable.
    """
    cues = []
    for side in ("right", "left"):
        pairs = (("pelvis", f"{side}_femur", 1.0), (f"{side}_femur", f"{side}_tibia", -1.0))
        for ref, mov, sign in pairs:
            if ref in rotations and mov in rotations:
                axis, excursion = _dominant_axis(rotations[ref], rotations[mov])
                if axis is not None and excursion >= min_excursion:
                    cues.append(sign * axis)
    if not cues:
        raise InputError(
            "the hips and knees barely move: the subject's right cannot be found from the motion; "
            "give the heading explicitly (e.g. --heading pelvis_imu:-z)",
            field="heading",
        )
    right = np.mean(cues, axis=0)
    if notes is not None and len(cues) > 1:
        flat = [c - UP * (c @ UP) for c in cues]
        spread = max(np.degrees(angle_between(c, right - UP * (right @ UP))) for c in flat)
        if spread > 45.0:
            notes.append(
                f"the hip and knee flexion axes disagree by up to {spread:.0f} deg: the anatomical "
                "heading may be unreliable; check the result or give --heading"
            )
    horizontal = right - UP * (right @ UP)
    if np.linalg.norm(horizontal) < 0.3 * np.linalg.norm(right):
        raise InputError(
            "the flexion axes point vertically: is the world's up axis y? Set --sensor-to-model "
            "(e.g. -1.5708 0 0 for an Xsens z-up world)",
            field="sensor_to_model",
        )
    return normalize(horizontal)


def heading_rotation(right: np.ndarray) -> np.ndarray:
    """Rotation about the vertical (y) taking the model's right (z) to the horizontal ``right``."""
    # Ry(psi) @ z = (sin psi, 0, cos psi) must equal (r_x, 0, r_z): psi = atan2(r_x, r_z)
    psi = np.arctan2(right[0], right[2])
    return rot_y(psi)


def _pelvis_axis_right(rotations, spec: str) -> np.ndarray:
    axis = spec.split(":")[1]
    sign = -1.0 if axis.startswith("-") else 1.0
    forward = sign * rotations["pelvis"][0][:, "xyz".index(axis[-1])]
    forward = forward - UP * (forward @ UP)
    if np.linalg.norm(forward) < 1e-3:
        raise InputError(f"pelvis sensor axis {axis} is vertical at t0", field="heading")
    return normalize(np.cross(normalize(forward), UP))  # right = forward x up


def run_ik(
    trial: OrientationTrial,
    measures: Measures,
    out_urdf: Path,
    *,
    knee: str = "free",
    sensor_to_model: tuple[float, float, float] | None = None,
    heading: str = "anatomical",
) -> IKRun:
    """Steps 1-4 of the module docstring on a read trial; writes the calibrated URDF."""
    from pipeline.analysis.landmarks import joint_angles, landmark_trajectories
    from pipeline.ik.solver import solve_ik
    from pipeline.model.builder import build_urdf
    from pipeline.model.scaling import geometry_from_measures
    from pipeline.model.skeleton import Skeleton

    notes = list(trial.notes)
    if heading not in HEADINGS:
        raise InputError(f"expected one of {HEADINGS}, got {heading!r}", field="heading")
    if sensor_to_model is not None:
        trial = rotate_world(trial, sensor_to_opensim_matrix(tuple(sensor_to_model)))
    rotations = _segment_rotations(trial)
    if "pelvis" not in rotations:
        raise InputError("a pelvis sensor (pelvis_imu) is required", file=trial.source)
    legs = tuple(s for s in ("right", "left") if f"{s}_femur" in rotations)
    if not legs:
        raise InputError("no thigh sensor (femur_r_imu / femur_l_imu)", file=trial.source)
    ignored = sorted(set(trial.sensor_names) - {f"{n}" for n in _used_sensor_names(trial)})
    if ignored:
        notes.append(f"sensors without a segment in this lower-limb model, ignored: {ignored}")

    if heading == "anatomical":
        right = anatomical_right(rotations, notes=notes)
    else:
        right = _pelvis_axis_right(rotations, heading)
    H = heading_rotation(right)

    geometry, _ = geometry_from_measures(measures)
    # the model's segment orientations in its neutral (standing) pose: the world axes for a free
    # knee; a hinge about a tilted AoR turns the tibia (and foot) by the aligning rotation
    neutral_model = Skeleton.from_urdf(build_urdf(geometry, out_urdf, knee=knee, legs=legs))
    neutral_model.forward(neutral_model.neutral())
    placements = {}
    for seg, R in rotations.items():
        frame = f"{seg}_imu"
        if not neutral_model.has_frame(seg):
            continue
        R_seg0 = neutral_model.frame_rotation(seg)
        placements[frame] = np.eye(4)
        placements[frame][:3, :3] = (H @ R_seg0).T @ R[0]
    # keep the default positions of the IMU frames (orientation IK does not observe them)
    from pipeline.model.builder import default_imu_placements

    defaults = {}
    for side in legs:
        defaults.update(default_imu_placements(geometry.for_side(side)))
    for frame, T in placements.items():
        if frame in defaults:
            T[:3, 3] = defaults[frame][:3, 3]
    placements = {k: v for k, v in placements.items() if k in defaults}
    urdf = build_urdf(geometry, out_urdf, knee=knee, legs=legs, imu_placements=placements)
    sk = Skeleton.from_urdf(urdf, root="spherical")
    targets = {f"{seg}_imu": R for seg, R in rotations.items() if f"{seg}_imu" in placements}
    q0 = sk.neutral()
    q0[:4] = _quat_xyzw(H)
    t0 = _time.perf_counter()
    result = solve_ik(sk.model, targets, q0=q0)
    seconds = _time.perf_counter() - t0
    if not np.all(result.converged):
        notes.append(f"IK did not converge on {int(np.sum(~result.converged))} frames")
    angles = joint_angles(sk, result.q)
    pelvis_world = rotations["pelvis"] @ placements["pelvis_imu"][:3, :3].T
    zxy = euler_zxy_from_matrix(np.einsum("ij,njk->nik", H.T, pelvis_world))
    angles["pelvis_tilt"], angles["pelvis_list"], angles["pelvis_rotation"] = zxy.T
    landmarks = landmark_trajectories(sk, result.q)
    return IKRun(trial.time, result.q, angles, landmarks, right, heading, result.residual_rms,
                 urdf, seconds, notes)  # fmt: skip


def _used_sensor_names(trial: OrientationTrial) -> list[str]:
    from pipeline.io.opensim import SENSOR_TO_SEGMENT

    return [s for s in trial.sensor_names if SENSOR_TO_SEGMENT.get(s, "torso") != "torso"]


def _quat_xyzw(R: np.ndarray) -> np.ndarray:
    from pipeline.rotations import quat_from_matrix

    w, x, y, z = quat_from_matrix(R)
    return np.array([x, y, z, w])


def mot_columns(run: IKRun) -> dict[str, np.ndarray]:
    """OpenSim-style coordinate columns (radians; :func:`write_mot` converts to degrees)."""
    cols = {k: run.joint_angles[k] for k in ("pelvis_tilt", "pelvis_list", "pelvis_rotation")}
    for side, suffix in (("right", "r"), ("left", "l")):
        for ours, theirs in MOT_NAMES.items():
            key = f"{side}_{ours}"
            if key in run.joint_angles:
                cols[f"{theirs}_{suffix}"] = run.joint_angles[key]
    return cols


def load_orientations(
    path: str | Path, xsens_map: dict[str, str] | None = None
) -> OrientationTrial:
    """An OpenSim ``.sto`` file, or a folder of Xsens MT ``.txt`` exports (one per sensor).

    For a folder, ``xsens_map`` maps OpenSense sensor names to Xsens sensor ids (like OpenSense's
    ``myIMUMappings.xml``), e.g. ``{"pelvis_imu": "00B421AF", ...}``; files are found as
    ``<prefix><id>.txt`` with the common prefix of the export (``MT_012005D6_009-001_``).
    """
    from pipeline.io.xsens import read_xsens_trial

    path = Path(path)
    if not path.is_dir():
        return read_orientations_sto(path)
    if not xsens_map:
        raise InputError(
            "a folder of Xsens .txt files needs --xsens-map NAME=ID ... (e.g. "
            "pelvis_imu=00B421AF femur_r_imu=00B4227B)",
            file=path,
        )
    first_id = next(iter(xsens_map.values()))
    matches = sorted(path.glob(f"*{first_id}.txt"))
    if not matches:
        raise InputError(f"no file ending in {first_id}.txt", file=path, field="xsens_map")
    prefix = matches[0].name[: -len(f"{first_id}.txt")]
    return read_xsens_trial(path, {sid: name for name, sid in xsens_map.items()}, prefix=prefix)


def run_ik_from_sto(
    sto: str | Path,
    measures: Measures,
    out_dir: str | Path,
    *,
    knee: str = "free",
    sensor_to_model: tuple[float, float, float] | None = None,
    heading: str = "anatomical",
    rerun: bool = True,
    xsens_map: dict[str, str] | None = None,
) -> str:
    """``pipeline ik``: read, calibrate, IK, write `.mot`, landmarks `.csv`, URDF, `.rrd`."""
    from pipeline.io.atomic import output_set
    from pipeline.io.opensim import write_mot
    from pipeline.io.tables import csv_text

    sto, out_dir = Path(sto), Path(out_dir)
    trial = load_orientations(sto, xsens_map)
    name = sto.stem if sto.suffix else sto.name
    out_dir.mkdir(parents=True, exist_ok=True)
    with output_set() as out:
        run = run_ik(trial, measures, out.path(out_dir / f"{name}.urdf"), knee=knee,
                     sensor_to_model=sensor_to_model, heading=heading)  # fmt: skip
        write_mot(out.path(out_dir / f"{name}_ik.mot"), run.time, mot_columns(run))
        rows = []
        for k, t in enumerate(run.time):
            row = {"time": float(t)}
            for lm, xyz in run.landmarks.items():
                row.update({f"{lm}_{a}": float(xyz[k, i]) for i, a in enumerate("xyz")})
            rows.append(row)
        columns = ["time"] + [f"{lm}_{a}" for lm in run.landmarks for a in "xyz"]
        with out.open(out_dir / f"{name}_landmarks.csv") as fh:
            fh.write(csv_text(rows, columns))
        if rerun:
            _log(run, out.path(out_dir / f"{name}.rrd"), name)
        summary = _summary(sto, run, measures)
        with out.open(out_dir / f"{name}_summary.md") as fh:
            fh.write(summary)
    return summary


def _log(run: IKRun, path: Path, name: str) -> None:
    from pipeline.model.skeleton import Skeleton

    try:
        from pipeline.viz.recording import log_motion
    except ImportError:
        log_motion = None
    if log_motion is not None:
        sk = Skeleton.from_urdf(run.urdf, root="spherical")
        log_motion(path, run.time - run.time[0], sk, run.q, recording_name=name)
        return
    from pipeline.viz.recording import log_trial

    log_trial(path, run.time - run.time[0], run.landmarks,
              joint_angles=run.joint_angles, recording_name=name, up_axis="y")  # fmt: skip


def _summary(sto: Path, run: IKRun, measures: Measures) -> str:
    name = sto.stem if sto.suffix else sto.name
    fps = len(run.time) / max(run.seconds_ik, 1e-9)
    lines = [
        f"# IK of {sto.name}",
        "",
        f"- subject: sex {measures.sex}, height {measures.height_m:.2f} m; model: {name}.urdf",
        f"- {len(run.time)} frames, {run.time[-1] - run.time[0]:.2f} s; IK {run.seconds_ik:.2f} s "
        f"({fps:.0f} frames/s)",
        f"- heading: {run.heading_method}; subject's right at t0 (world): "
        + "("
        + ", ".join(f"{v:.3f}" for v in run.heading_right)
        + ")",
        f"- orientation residual RMS: median {np.degrees(np.nanmedian(run.residual_rms)):.2f} deg, "
        f"95th percentile {np.degrees(np.nanpercentile(run.residual_rms, 95)):.2f} deg",
        "",
        "| angle | min (deg) | max (deg) |",
        "|---|---|---|",
    ]
    for k, v in run.joint_angles.items():
        lines.append(f"| {k} | {np.degrees(np.nanmin(v)):.1f} | {np.degrees(np.nanmax(v)):.1f} |")
    if run.notes:
        lines += ["", "Notes:", ""] + [f"- {n}" for n in run.notes]
    return "\n".join(lines) + "\n"
