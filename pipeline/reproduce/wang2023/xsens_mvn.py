"""Xsens MVN exports and the optical C3D files they are compared with (Wang et al. 2023, §II.D).

**What an MVN export holds.** The ``.c3d`` written by Xsens MVN (2021.2.0 in the paper) has the
64 virtual landmarks of MVN's scaled body model (labels ``p...``: ``pHipOrigin``, ``pRightASI``,
``pLeftASI``, ``pSacrum``, ``pTopOfHead``, ``pRightKneeMedEpicondyle`` ...), in mm at the MVN
rate (120 or 240 Hz on the published files); no joint centres (those are in the ``.xls`` export,
not published). §II.D: MVN scales its model from body height (static exports
``Test_static_<height cm>_...c3d``: sensors left still on a table, model in the N-pose, heights
150-190 cm) and the subjects' hip-flexion trials were exported as ``xsensHipF*.c3d``.

**Labels used.** Right-leg landmarks (:data:`MVN_LABELS`): ``pRightKneeMedEpicondyle``,
``pRightKneeLatEpicondyle``, ``pRightMedMalleolus``, ``pRightLatMalleolus`` = EFM, EFL, MM, LM;
pelvis: ``pHipOrigin``, ``pRightASI``, ``pLeftASI``, ``pSacrum``; ``pTopOfHead`` for the model
height. Optical files (:data:`OMC_LABELS`): Subject 1 ``REFM``, ``REFL``, ``RMM``, ``RLM``;
Subject 2 digitised points ``iW3_Digitized1/2`` = EFM/EFL, ``iW2_Digitized1/2`` = MM/LM
(identified by being rigidly equal, 0.0 mm, to the ``omcData`` landmarks of ``rawData.mat``).

**Hip centre.** The right hip joint centre (HJC) is not among the c3d labels. By the MVN manual
the pelvis origin ``pHipOrigin`` is the midpoint of the two hip centres, so the HJC lies on the
pelvis' lateral axis; its offset, as a fraction of the ASIS width and in a pelvis landmark frame
(:func:`pelvis_frames`), is measured on the MVN *motion* exports by a sphere fit of the
epicondyles in that frame (:func:`mvn_hip_offset`; on the three exports 0.340-0.343 of the ASIS
width, within 1.3 mm of the pelvis' lateral axis). Static models (:func:`static_model`) apply
that offset; motion trials use MVN's own right hip at every sample (:func:`mvn_hip_trajectory`),
because the MVN pelvis moves 15-34 mm during these trials (the reference code did the same).

**Static models (Table II).** Landmarks are the median over the static frames. Femoral frame as
the paper (:func:`pipeline.reproduce.wang2023.omc.femoral_frames`); tibial frame with the MVN tibia
z axis (medial to lateral epicondyle, §II.D: the substitute for the knee AoR in a static pose) as
knee axis. Each MVN coordinate is linear in height (:func:`linear_in_height`).

**Trials (Tables VI-VII).** :func:`compare_trial` for one ``Subject{1,2}/HipF{1,2}`` folder:
optical landmarks from ``OMCHipF*.c3d``; MVN landmarks from ``xsensHipF*.c3d`` resampled
linearly to the optical 100 Hz (:func:`resample`), or, without an export, ``imcData`` of
``rawData.mat`` (the MVN landmarks as the reference code extracted them, 100 Hz, hip-centred per
sample on MVN's hip). Hip centres: optical, one lab-fixed sphere fit of EFM and EFL (as the
paper); MVN, per sample as above. Then, alike for both systems and from landmarks only
(:func:`system_kinematics`): femoral frames, knee AoR (eq 1-8) from the femoral frames and a
landmark tibia frame (:func:`landmark_tibia_frames`: KJC, MM, LM; no tibia cluster is exported
for Subject 1), tibial frames. The lag is estimated from the femurs' angular speeds
(frame-free), frames are unified by eq 18-19 (y_temp at the first jointly valid sample, or the
mean femoral y), errors by eq 20 (RMS of the 3-D error) and ZYX orientation errors in both error
frames.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pipeline.calibration.aor import KneeAoR, knee_aor
from pipeline.errors import InputError
from pipeline.io.c3d import C3dMarkers, read_c3d
from pipeline.reproduce.wang2023.evaluation import (
    align,
    angular_speed,
    compare_trajectories,
    estimate_lag,
    frame_from_femur,
    initial_frame,
    points_to_omc,
    rms_orientation_error,
    rotations_to_omc,
    unify_frames,
)
from pipeline.reproduce.wang2023.omc import (
    femoral_frames,
    fit_sphere,
    landmarks_in_frames,
    tibial_frames,
)
from pipeline.reproduce.wang2023.statistics import rms_error
from pipeline.rotations import angle_between

LANDMARKS = ("EFM", "EFL", "MM", "LM")
MVN_LABELS = {
    "EFM": "pRightKneeMedEpicondyle",
    "EFL": "pRightKneeLatEpicondyle",
    "MM": "pRightMedMalleolus",
    "LM": "pRightLatMalleolus",
}
OMC_LABELS = {
    "REFM": "EFM",
    "REFL": "EFL",
    "RMM": "MM",
    "RLM": "LM",
    "iW3_Digitized1": "EFM",
    "iW3_Digitized2": "EFL",
    "iW2_Digitized1": "MM",
    "iW2_Digitized2": "LM",
}
RATE_HZ = 100.0
MAX_LAG = 500  # samples (5 s)
UNIFICATIONS = ("first", "mean")  # eq 18-19 y_temp: first paired sample / mean over samples


# --------------------------------------------------------------------------------------------
# geometry helpers


def _unit(v: np.ndarray) -> np.ndarray:
    with np.errstate(invalid="ignore", divide="ignore"):
        return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _perp(v: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Unit component of ``v`` perpendicular to the unit vectors ``y`` (row-wise)."""
    return _unit(v - np.sum(v * y, axis=-1, keepdims=True) * y)


def pelvis_frames(rasi: np.ndarray, lasi: np.ndarray, sacrum: np.ndarray) -> np.ndarray:
    """Pelvis landmark frames ``(N, 3, 3)``: ``z`` = LASI -> RASI (right), ``x`` = sacrum -> mid
    ASIS made perpendicular to ``z`` (anterior), ``y = z x x`` (up)."""
    z = _unit(np.asarray(rasi, float) - lasi)
    x = _perp(0.5 * (np.asarray(rasi, float) + lasi) - sacrum, z)
    return np.stack([x, np.cross(z, x), z], axis=-1)


def landmark_tibia_frames(kjc: np.ndarray, mm: np.ndarray, lm: np.ndarray) -> np.ndarray:
    """A tibia-fixed frame from landmarks only (for eq 1-2 when no tibia cluster exists):
    ``y`` = AJC -> KJC, ``z`` = MM -> LM perpendicular to ``y``, ``x = y x z``. The KJC is a
    femoral point; it stays (nearly) fixed in the tibia because the knee rotates about it."""
    ajc = 0.5 * (np.asarray(mm, float) + lm)
    y = _unit(np.asarray(kjc, float) - ajc)
    z = _perp(np.asarray(lm, float) - mm, y)
    return np.stack([np.cross(y, z), y, z], axis=-1)


def mvn_hip_offset(markers: C3dMarkers) -> tuple[np.ndarray, float]:
    """Right HJC of an MVN motion export in its pelvis frame, divided by the ASIS width.

    Sphere fit (algebraic, 5 Gauss-Newton steps) of the right epicondyles expressed in
    :func:`pelvis_frames` with origin ``pHipOrigin``. Returns ``(offset (3,), fit RMS m)``.
    """
    m = markers.marker
    P = pelvis_frames(m("pRightASI"), m("pLeftASI"), m("pSacrum"))
    origin = m("pHipOrigin")
    local = [np.einsum("nji,nj->ni", P, m(MVN_LABELS[n]) - origin) for n in ("EFM", "EFL")]
    fit = fit_sphere(np.concatenate(local), refine_steps=5)
    width = float(np.nanmedian(np.linalg.norm(m("pRightASI") - m("pLeftASI"), axis=1)))
    return fit.centre / width, fit.rms


def mvn_hip_trajectory(markers: C3dMarkers, offset: np.ndarray | None = None) -> np.ndarray:
    """MVN's right HJC in the world at every sample, ``(N, 3)``: ``pHipOrigin`` plus ``offset``
    (default: :func:`mvn_hip_offset` of the same export) times the ASIS width, in the pelvis
    frame. The MVN pelvis is not still during supine hip flexion (15-34 mm, 9-12 deg on the
    published exports), so a lab-fixed sphere centre would misplace the hip."""
    m = markers.marker
    if offset is None:
        offset, _ = mvn_hip_offset(markers)
    P = pelvis_frames(m("pRightASI"), m("pLeftASI"), m("pSacrum"))
    width = np.linalg.norm(m("pRightASI") - m("pLeftASI"), axis=1)[:, None]
    return m("pHipOrigin") + np.einsum("nij,nj->ni", P, np.asarray(offset, float) * width)


def height_from_filename(path: str | Path) -> float:
    """Body height (m) entered in MVN, from ``Test_static_<cm>_...c3d``."""
    match = re.search(r"static_(\d{3})_", Path(path).name)
    if not match:
        raise InputError("expected a file name like Test_static_170_....c3d", file=path)
    return int(match.group(1)) / 100.0


# --------------------------------------------------------------------------------------------
# static MVN models


@dataclass(frozen=True)
class MvnStaticModel:
    """One static MVN model: heights (m), world landmarks, landmarks in segment frames (m)."""

    path: Path
    height_m: float
    model_height_m: float
    hjc: np.ndarray
    landmarks: dict[str, np.ndarray]
    segment_landmarks: dict[str, np.ndarray]
    malleolar_vs_knee_axis_deg: float


def static_model(path: str | Path, hip_offset: np.ndarray) -> MvnStaticModel:
    """Read a static MVN export and express its landmarks in the paper's segment frames.

    Model height: ``pTopOfHead`` height above the lowest point. HJC: ``pHipOrigin`` plus
    ``hip_offset`` (:func:`mvn_hip_offset`) times the ASIS width in the pelvis frame. Tibial z: the
    MVN tibia z axis, medial to lateral epicondyle (the paper's knee AoR substitute).
    """
    c = read_c3d(path)
    pt = {lab: np.nanmedian(c.points[:, i], axis=0) for i, lab in enumerate(c.labels)}
    need = [*MVN_LABELS.values(), "pHipOrigin", "pRightASI", "pLeftASI", "pSacrum", "pTopOfHead"]
    missing = [n for n in need if n not in pt]
    if missing:
        raise InputError(f"not an MVN export: missing {missing}", file=path, field="POINT:LABELS")
    lowest = float(np.nanmin(np.stack(list(pt.values()))[:, 2]))
    P = pelvis_frames(pt["pRightASI"][None], pt["pLeftASI"][None], pt["pSacrum"][None])[0]
    width = float(np.linalg.norm(pt["pRightASI"] - pt["pLeftASI"]))
    hjc = pt["pHipOrigin"] + P @ (np.asarray(hip_offset, float) * width)
    lm = {n: pt[label][None] for n, label in MVN_LABELS.items()}
    F, Fo = femoral_frames(hjc, lm["EFM"], lm["EFL"])
    knee_axis = lm["EFL"] - lm["EFM"]
    T, To = tibial_frames(lm["EFM"], lm["EFL"], lm["MM"], lm["LM"], knee_axis)
    seg = {n: landmarks_in_frames(lm[n], F, Fo) for n in ("EFM", "EFL")}
    seg |= {n: landmarks_in_frames(lm[n], T, To) for n in ("MM", "LM")}
    return MvnStaticModel(
        path=Path(path),
        height_m=height_from_filename(path),
        model_height_m=float(pt["pTopOfHead"][2] - lowest),
        hjc=hjc,
        landmarks={n: v[0] for n, v in lm.items()},
        segment_landmarks=seg,
        malleolar_vs_knee_axis_deg=float(
            np.degrees(angle_between(knee_axis[0], lm["LM"][0] - lm["MM"][0]))
        ),
    )


def linear_in_height(models: list[MvnStaticModel]) -> tuple[dict, float]:
    """Least-squares ``p = a + b h`` per landmark coordinate over the static models.

    Returns ``({landmark: (a (3,), b (3,))}, largest residual m)``.
    """
    h = np.array([m.height_m for m in models])
    if len(h) < 2:
        raise InputError("need at least two static MVN models to interpolate in height")
    A = np.column_stack([np.ones_like(h), h])
    out, worst = {}, 0.0
    for n in LANDMARKS:
        Y = np.stack([m.segment_landmarks[n] for m in models])
        coef, *_ = np.linalg.lstsq(A, Y, rcond=None)
        worst = max(worst, float(np.abs(A @ coef - Y).max()))
        out[n] = (coef[0], coef[1])
    return out, worst


# --------------------------------------------------------------------------------------------
# motion trials (Tables VI-VII)


@dataclass(frozen=True)
class SystemKinematics:
    """One system's hip-centred landmarks (incl. KJC), femoral/tibial frames, hip fit, AoR."""

    landmarks: dict[str, np.ndarray]
    femur_R: np.ndarray
    tibia_R: np.ndarray
    hip_rms_m: float
    aor: KneeAoR


def system_kinematics(landmarks: dict[str, np.ndarray], fit_hip: bool = True) -> SystemKinematics:
    """Frames and knee AoR from landmarks alone. ``fit_hip``: hip centre by a sphere fit of EFM and
    EFL (optical data: lab-fixed hip); else the landmarks are already hip-centred (MVN: per
    sample, :func:`mvn_hip_trajectory`) and ``hip_rms_m`` is NaN."""
    centre, rms = np.zeros(3), float("nan")
    if fit_hip:
        fit = fit_sphere(np.concatenate([landmarks["EFM"], landmarks["EFL"]]))
        centre, rms = fit.centre, fit.rms
    lm = {n: np.asarray(landmarks[n], float) - centre for n in LANDMARKS}
    lm["KJC"] = 0.5 * (lm["EFM"] + lm["EFL"])
    F, _ = femoral_frames(np.zeros(3), lm["EFM"], lm["EFL"])
    aor = knee_aor(F, landmark_tibia_frames(lm["KJC"], lm["MM"], lm["LM"]))
    T, _ = tibial_frames(lm["EFM"], lm["EFL"], lm["MM"], lm["LM"], F @ aor.femur_axis)
    return SystemKinematics(lm, F, T, rms, aor)


def resample(time_s: np.ndarray, x: np.ndarray, rate_hz: float = RATE_HZ) -> np.ndarray:
    """Linear interpolation of ``x`` (N, 3) onto ``k / rate_hz`` within the recording."""
    t = np.arange(0.0, float(time_s[-1]) + 1e-9, 1.0 / rate_hz)
    return np.stack([np.interp(t, time_s, x[:, j]) for j in range(x.shape[1])], axis=1)


def _sensitivity_to_t(op, mp, Fo, Fm, frames) -> dict[str, tuple[float, float]]:
    """Min and max RMS per landmark when eq 18-19 takes y_temp at each of ``frames``."""
    out = []
    for t in frames:
        R = unify_frames(frame_from_femur(op["KJC"], Fo, t), frame_from_femur(mp["KJC"], Fm, t))
        out.append([rms_error(points_to_omc(R, mp[n]) - op[n]) for n in LANDMARKS])
    out = np.array(out)
    return {n: (float(out[:, i].min()), float(out[:, i].max())) for i, n in enumerate(LANDMARKS)}


@dataclass(frozen=True)
class TrialResult:
    """Tables VI-VII for one trial (:func:`compare_trial`); lengths in m, angles in rad."""

    subject: str
    trial: str
    label: str
    source: str
    lag: int
    n_frames: int
    rms_m: dict[tuple[str, str], float]  # (unification, landmark) -> RMS
    orientation_rad: dict[tuple[str, str, str], np.ndarray]  # (unification, segment, error frame)
    rms_range_over_t_m: dict[str, tuple[float, float]]  # 'first' RMS, min/max over frame t
    omc_hip_rms_m: float  # optical hip sphere-fit RMS
    aor_angle_deg: float  # between the two systems' femoral AoRs


def _load_trial(folder: Path, mvn_source: str = "auto") -> tuple[dict, dict, str]:
    """Optical landmarks (m, lab) and MVN landmarks (m, centred on MVN's own right hip at every
    sample) of one trial folder; ``mvn_source`` 'auto' (the MVN c3d export if present, else
    ``rawData.mat``, whose ``imcData`` the reference code centred the same way), 'c3d' or
    'rawData.mat'."""
    c = read_c3d(folder / f"OMC{folder.name}.c3d")
    omc = {OMC_LABELS[lab]: c.marker(lab) for lab in c.labels if lab in OMC_LABELS}
    if sorted(omc) != sorted(LANDMARKS):
        raise InputError(f"optical landmarks {sorted(omc)} incomplete", file=c.source)
    export = folder / f"xsens{folder.name}.c3d"
    if mvn_source == "c3d" or (mvn_source == "auto" and export.is_file()):
        x = read_c3d(export)
        hip = mvn_hip_trajectory(x)
        mvn = {n: resample(x.time, x.marker(label) - hip) for n, label in MVN_LABELS.items()}
        return omc, mvn, "c3d"
    if mvn_source not in ("auto", "rawData.mat"):
        raise ValueError(f"mvn_source must be 'auto', 'c3d' or 'rawData.mat', got {mvn_source!r}")
    from pipeline.optional import need

    load_from_mat = need("matio", "reading MATLAB files").load_from_mat

    path = folder / "rawData.mat"
    if not path.is_file():
        raise InputError("no MVN data: neither the c3d export nor rawData.mat", file=folder)
    imc = load_from_mat(str(path))["imcData"].properties
    return omc, {n: 1e-3 * np.asarray(imc["R" + n], float) for n in LANDMARKS}, "rawData.mat"


def compare_trial(folder: str | Path, label: str = "", mvn_source: str = "auto") -> TrialResult:
    """Tables VI-VII for one ``Subject*/HipF*`` folder (module docstring); ``mvn_source`` as
    :func:`_load_trial`."""
    folder = Path(folder)
    omc_lm, mvn_lm, source = _load_trial(folder, mvn_source)
    o, m = system_kinematics(omc_lm), system_kinematics(mvn_lm, fit_hip=False)
    lag = estimate_lag(angular_speed(o.femur_R), angular_speed(m.femur_R), MAX_LAG)
    Fo, Fm = align(o.femur_R, m.femur_R, lag)
    To, Tm = align(o.tibia_R, m.tibia_R, lag)
    op = {n: align(v, m.femur_R, lag)[0] for n, v in o.landmarks.items()}
    mp = {n: align(o.femur_R, v, lag)[1] for n, v in m.landmarks.items()}
    ok = np.all(np.isfinite(Fo), axis=(1, 2)) & np.all(np.isfinite(Fm), axis=(1, 2))
    if not ok.any():
        raise InputError("no sample where both femoral frames exist", file=folder)
    t = int(np.flatnonzero(ok)[0])
    rms, orient = {}, {}
    for how in UNIFICATIONS:
        if how == "first":
            G_o = frame_from_femur(op["KJC"], Fo, t)
            G_m = frame_from_femur(mp["KJC"], Fm, t)
        else:  # y_temp = mean femoral y over the paired samples (no single frame t)
            G_o = initial_frame(op["KJC"], Fo[ok][:, :, 1].mean(axis=0), Fo[ok][:, :, 2])
            G_m = initial_frame(mp["KJC"], Fm[ok][:, :, 1].mean(axis=0), Fm[ok][:, :, 2])
        R = unify_frames(G_o, G_m)
        comp = compare_trajectories({n: mp[n] for n in LANDMARKS}, {n: op[n] for n in LANDMARKS}, R)
        rms |= {(how, n): comp[n].rms for n in LANDMARKS}
        for seg, Rm, Ro in (("femur", Fm, Fo), ("tibia", Tm, To)):
            for frame in ("world", "body"):
                orient[(how, seg, frame)] = rms_orientation_error(
                    rotations_to_omc(R, Rm), Ro, frame
                )
    return TrialResult(
        subject=folder.parent.name,
        trial=folder.name,
        label=label,
        source=source,
        lag=lag,
        n_frames=min(c.n_frames for c in comp.values()),
        rms_m=rms,
        rms_range_over_t_m=_sensitivity_to_t(op, mp, Fo, Fm, np.flatnonzero(ok)[::50]),
        orientation_rad=orient,
        omc_hip_rms_m=o.hip_rms_m,
        aor_angle_deg=float(np.degrees(angle_between(o.aor.femur_axis, m.aor.femur_axis))),
    )
