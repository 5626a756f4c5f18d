"""Reader for the Wang et al. 2023 dataset (``raw/rawDataNN.mat``, one subject per file).

Each file holds two MATLAB class objects, ``omcData`` (NDI Optotrak, 100 Hz, millimetres) and
``imcData`` (FOHEART suit, 16 of 38 subjects); ``matio.load_from_mat`` decodes them and
``obj.properties`` is a dict of NumPy arrays. See ``shared/data/wang2023/README.md``.

What the reader does, and nothing more:

* converts to SI: millimetres -> metres, body height mm -> m; time ``t = k / 100`` s (no time
  stamps are stored; the rate is the documented 100 Hz);
* builds cluster rotation matrices from the stored ZYX Euler angles (MATLAB ``eul2rotm``:
  ``R = Rz(e0) Ry(e1) Rx(e2)``, columns = cluster axes in the lab frame);
* keeps missing samples as NaN (they are *not* interpolated; downstream code masks them);
* detects swapped cluster labels from the data: the landmarks are virtual points digitised in a
  cluster frame, so they are rigid in it. If the malleoli are rigid in the *femur* cluster rather
  than the tibia cluster, the two clusters are swapped back (subject 1 of the published data) and
  ``OmcTrial.clusters_swapped`` is set. For subject 1 the other cluster does not carry the
  epicondyles either (31 mm spread; it sits ~80 mm from the malleoli), which is noted in
  ``OmcTrial.notes``; the OMC processing only needs the tibia cluster (the femoral frame comes from
  the landmarks and the hip centre), so this does not matter there;
* for the IMC, keeps ``RTibiaRotm`` as stored and also gives it without the README's hand-tuned
  correction ``C`` (``R_uncorrected = R_stored C^T``).

Every problem with the input is an :class:`~pipeline.errors.InputError` (one line).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pipeline.errors import InputError
from pipeline.rotations import matrix_from_euler_zyx

__all__ = [
    "IMC_OMC_INDEX_OFFSET",
    "LANDMARKS",
    "OMC_RATE_HZ",
    "TIBIA_HAND_CORRECTION_DEG",
    "ImcTrial",
    "OmcTrial",
    "Subject",
    "hand_correction",
    "imc_from_fields",
    "load_subject",
    "omc_from_fields",
    "subject_paths",
]

OMC_RATE_HZ = 100.0
"""Optotrak and FOHEART nominal sampling rate (README)."""

LANDMARKS = ("EFM", "EFL", "MM", "LM")
"""Landmark names used in this package (file fields carry an ``R`` prefix: ``REFM`` ...)."""

IMC_OMC_INDEX_OFFSET: dict[int, int] = {1: 168, 2: -64, 11: -99, 12: -69, 14: -169, 17: -7}
"""Reference code's pairing ``omc_index = imc_index + offset`` (README); absent ids mean 0."""

TIBIA_HAND_CORRECTION_DEG: dict[int, tuple[float, float, float]] = {
    1: (-10.0, 0.0, 0.0),
    3: (10.0, 0.0, 0.0),
    6: (-5.0, 0.0, 5.0),
    7: (3.60, 10.18, -4.88),
    9: (-10.0, 0.0, 0.0),
    14: (5.0, 0.0, 0.0),
    15: (10.0, 0.0, 0.0),
    17: (0.0, 0.0, 5.0),
    19: (10.0, 0.0, -7.0),
}
"""Hand-tuned ZYX Euler angles (deg) right-multiplied into the stored ``RTibiaRotm`` (README)."""

_RIGID_TOL_M = 1e-3  # a landmark with < 1 mm spread in a cluster frame is rigid in it


def hand_correction(subject_id: int) -> np.ndarray:
    """The README's hand correction ``C`` (3x3) for a subject; identity when none was applied."""
    e = TIBIA_HAND_CORRECTION_DEG.get(int(subject_id), (0.0, 0.0, 0.0))
    return matrix_from_euler_zyx(np.deg2rad(e))


@dataclass(frozen=True)
class OmcTrial:
    """Optical data of one subject, lab (Optotrak) frame, SI units.

    ``landmarks[name]`` is ``(N, 3)`` m; ``*_cluster_R`` ``(N, 3, 3)`` with the cluster axes as
    columns; NaN rows are missing samples. ``clusters_swapped`` says the file's femur/tibia
    cluster labels were exchanged on reading; ``notes`` lists anything else noticed.
    """

    subject_id: int
    sex: str
    height_m: float
    rate_hz: float
    time: np.ndarray
    landmarks: dict[str, np.ndarray]
    femur_cluster_R: np.ndarray
    femur_cluster_pos: np.ndarray
    tibia_cluster_R: np.ndarray
    tibia_cluster_pos: np.ndarray
    clusters_swapped: bool
    notes: tuple[str, ...]
    source: Path | None

    @property
    def n_frames(self) -> int:
        return int(self.time.size)


@dataclass(frozen=True)
class ImcTrial:
    """Inertial (FOHEART) segment orientations of one subject in the IMC world frame.

    ``tibia_R`` is ``RTibiaRotm`` as stored (hand correction included for nine subjects);
    ``tibia_R_uncorrected = tibia_R @ hand_correction.T`` is what the suit delivered.
    ``femur_quat`` / ``knee_quat`` are the raw suit quaternions, scalar first.
    """

    subject_id: int
    rate_hz: float
    time: np.ndarray
    femur_R: np.ndarray
    tibia_R: np.ndarray
    tibia_R_uncorrected: np.ndarray
    hand_correction: np.ndarray
    femur_quat: np.ndarray
    knee_quat: np.ndarray

    @property
    def n_frames(self) -> int:
        return int(self.time.size)


@dataclass(frozen=True)
class Subject:
    """One file: optical data, inertial data (``None`` when not recorded) and its path."""

    omc: OmcTrial
    imc: ImcTrial | None
    path: Path | None


# --------------------------------------------------------------------------------------------
# field helpers


def _get(fields: Mapping, name: str, path) -> np.ndarray:
    if name not in fields:
        raise InputError("field missing from omcData/imcData", file=path, field=name)
    return np.asarray(fields[name])


def _matrix(fields: Mapping, name: str, ncols: int, path, n: int | None = None) -> np.ndarray:
    a = _get(fields, name, path)
    expected = f"({'N' if n is None else n}, {ncols})"
    if a.ndim != 2 or a.shape[1] != ncols or a.shape[0] < 2 or (n is not None and a.shape[0] != n):
        raise InputError(f"expected shape {expected}, found {a.shape}", file=path, field=name)
    try:
        return a.astype(float)
    except (TypeError, ValueError):
        raise InputError(
            f"expected numbers, found dtype {a.dtype}", file=path, field=name
        ) from None


def _scalar(fields: Mapping, name: str, path) -> float:
    a = _get(fields, name, path)
    if a.size != 1:
        raise InputError(f"expected a 1x1 value, found shape {a.shape}", file=path, field=name)
    try:
        return float(a.ravel()[0])
    except (TypeError, ValueError):
        raise InputError(
            f"expected a number, found {a.ravel()[0]!r}", file=path, field=name
        ) from None


def _rotation_cells(fields: Mapping, name: str, path) -> np.ndarray:
    a = _get(fields, name, path)
    if a.dtype == object:
        cells = a.ravel()
        if cells.size < 2 or any(np.shape(c) != (3, 3) for c in cells):
            bad = next((np.shape(c) for c in cells if np.shape(c) != (3, 3)), None)
            raise InputError(
                f"expected a cell array of 3x3 matrices, found {cells.size} cells"
                + ("" if bad is None else f" with a cell of shape {bad}"),
                file=path,
                field=name,
            )
        out = np.stack([np.asarray(c, dtype=float) for c in cells])
    else:
        out = np.asarray(a, dtype=float)
        if out.ndim != 3 or out.shape[1:] != (3, 3):
            raise InputError(
                f"expected (N, 3, 3) rotation matrices, found shape {out.shape}",
                file=path,
                field=name,
            )
    return out


def _spread(points: np.ndarray, R: np.ndarray, pos: np.ndarray) -> float:
    """Largest per-axis SD (m) of ``points`` expressed in the cluster frame ``(R, pos)``."""
    local = np.einsum("nji,nj->ni", R, points - pos)
    local = local[np.all(np.isfinite(local), axis=1)]
    return float(np.max(np.std(local, axis=0))) if len(local) > 1 else float("nan")


# --------------------------------------------------------------------------------------------
# builders from decoded fields


def omc_from_fields(fields: Mapping, path: str | Path | None = None) -> OmcTrial:
    """Build an :class:`OmcTrial` from the ``omcData`` properties (file units: mm, rad)."""
    sid = int(round(_scalar(fields, "SubjectID", path)))
    sex_raw = _get(fields, "Gender", path).ravel()
    sex = str(sex_raw[0]).strip().lower() if sex_raw.size else ""
    if sex not in ("m", "f"):
        raise InputError(f"expected 'm' or 'f', found {sex_raw!r}", file=path, field="Gender")
    height_mm = _scalar(fields, "Height", path)
    if not 1000.0 <= height_mm <= 2500.0:
        raise InputError(
            f"expected a body height in mm (1000-2500), found {height_mm:g}",
            file=path,
            field="Height",
        )
    lm = {name: _matrix(fields, "R" + name, 3, path) for name in LANDMARKS}
    n = lm["EFM"].shape[0]
    lm = {name: _matrix(fields, "R" + name, 3, path, n) / 1000.0 for name in LANDMARKS}
    eul_f = _matrix(fields, "RFemoralClusterEul", 3, path, n)
    eul_t = _matrix(fields, "RTibiaClusterEul", 3, path, n)
    pos_f = _matrix(fields, "RFemoralClusterPos", 3, path, n) / 1000.0
    pos_t = _matrix(fields, "RTibiaClusterPos", 3, path, n) / 1000.0
    R_f = matrix_from_euler_zyx(eul_f)  # NaN Euler angles give NaN matrices: kept missing
    R_t = matrix_from_euler_zyx(eul_t)

    notes: list[str] = []
    mall_in_f = max(_spread(lm[m], R_f, pos_f) for m in ("MM", "LM"))
    mall_in_t = max(_spread(lm[m], R_t, pos_t) for m in ("MM", "LM"))
    swapped = bool(mall_in_f < mall_in_t)
    if swapped:
        R_f, R_t, pos_f, pos_t = R_t, R_f, pos_t, pos_f
        notes.append(
            f"cluster labels swapped on reading: the malleoli are rigid in the file's femur "
            f"cluster (spread {mall_in_f * 1e3:.3g} mm) not in its tibia cluster "
            f"({mall_in_t * 1e3:.3g} mm)"
        )
    elif mall_in_t > _RIGID_TOL_M:
        notes.append(f"malleoli not rigid in the tibia cluster (spread {mall_in_t * 1e3:.3g} mm)")
    epi_in_f = max(_spread(lm[m], R_f, pos_f) for m in ("EFM", "EFL"))
    if epi_in_f > _RIGID_TOL_M:
        notes.append(
            f"epicondyles not rigid in the femur cluster (spread {epi_in_f * 1e3:.3g} mm): "
            "femur_cluster_R is not the thigh cluster they were digitised in"
        )
    for name in LANDMARKS:
        n_missing = int(np.sum(~np.all(np.isfinite(lm[name]), axis=1)))
        if n_missing:
            notes.append(f"{name}: {n_missing} missing samples (kept as NaN)")
    return OmcTrial(
        subject_id=sid,
        sex=sex,
        height_m=height_mm / 1000.0,
        rate_hz=OMC_RATE_HZ,
        time=np.arange(n) / OMC_RATE_HZ,
        landmarks=lm,
        femur_cluster_R=R_f,
        femur_cluster_pos=pos_f,
        tibia_cluster_R=R_t,
        tibia_cluster_pos=pos_t,
        clusters_swapped=swapped,
        notes=tuple(notes),
        source=None if path is None else Path(path),
    )


def _has_imc(fields: Mapping | None) -> bool:
    return fields is not None and np.asarray(fields.get("RFemoralRotm", np.empty(0))).size > 0


def imc_from_fields(fields: Mapping, subject_id: int, path: str | Path | None = None) -> ImcTrial:
    """Build an :class:`ImcTrial` from the ``imcData`` properties."""
    femur_R = _rotation_cells(fields, "RFemoralRotm", path)
    tibia_R = _rotation_cells(fields, "RTibiaRotm", path)
    n = femur_R.shape[0]
    if tibia_R.shape[0] != n:
        raise InputError(
            f"expected {n} matrices (as RFemoralRotm), found {tibia_R.shape[0]}",
            file=path,
            field="RTibiaRotm",
        )
    fq = _matrix(fields, "RFemoralQuat", 4, path, n)
    kq = _matrix(fields, "RKneeQuat", 4, path, n)
    C = hand_correction(subject_id)
    return ImcTrial(
        subject_id=int(subject_id),
        rate_hz=OMC_RATE_HZ,
        time=np.arange(n) / OMC_RATE_HZ,
        femur_R=femur_R,
        tibia_R=tibia_R,
        tibia_R_uncorrected=tibia_R @ C.T,
        hand_correction=C,
        femur_quat=fq,
        knee_quat=kq,
    )


# --------------------------------------------------------------------------------------------
# files


def load_subject(path: str | Path, require_imc: bool = False) -> Subject:
    """Read one ``rawDataNN.mat``; ``require_imc`` refuses a file without inertial data."""
    p = Path(path)
    if not p.is_file():
        raise InputError("file not found (expected a Wang 2023 rawDataNN.mat)", file=p)
    try:
        from pipeline.optional import need

        load_from_mat = need("matio", "reading MATLAB files").load_from_mat

        data = load_from_mat(str(p))
    except Exception as exc:  # noqa: BLE001 - any decoder failure means "not this format"
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise InputError(f"not a readable MATLAB .mat file ({msg})", file=p) from None
    omc_obj = data.get("omcData") if isinstance(data, Mapping) else None
    if omc_obj is None or not hasattr(omc_obj, "properties"):
        found = sorted(data) if isinstance(data, Mapping) else type(data).__name__
        raise InputError(
            f"not a Wang 2023 subject file: expected an omcData object, found {found}", file=p
        )
    omc = omc_from_fields(omc_obj.properties, p)
    imc_obj = data.get("imcData")
    imc_fields = getattr(imc_obj, "properties", None)
    imc = imc_from_fields(imc_fields, omc.subject_id, p) if _has_imc(imc_fields) else None
    if require_imc and imc is None:
        raise InputError("inertial data requested but imcData is empty in this file", file=p)
    return Subject(omc=omc, imc=imc, path=p)


def subject_paths(data_dir: str | Path) -> list[Path]:
    """``rawDataNN.mat`` files of a dataset folder (or its ``raw/``), sorted by subject number."""
    d = Path(data_dir)
    if (d / "raw").is_dir():
        d = d / "raw"
    if not d.is_dir():
        raise InputError("not a folder (expected the wang2023 dataset folder)", file=d)
    found = []
    for f in d.glob("rawData*.mat"):
        m = re.fullmatch(r"rawData(\d+)\.mat", f.name)
        if m:
            found.append((int(m.group(1)), f))
    if not found:
        raise InputError("no rawDataNN.mat files found", file=d)
    return [f for _, f in sorted(found)]
