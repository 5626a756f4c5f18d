"""Optical (OMC) processing of one subject: hip centre, segment frames, landmarks, body dimensions.

Wang et al. 2023 §II.A and DESIGN.md §2 (ISB, right leg: x anterior, y proximal, z right).
Everything is computed from relative geometry, so no output expressed in a segment frame depends on
the lab axes (six subjects of the dataset have different lab axes; the tests apply a random rigid
transform to a subject and check that nothing changes).

* Hip joint centre (HJC): one least-squares sphere through all EFM and EFL samples, algebraic
  (Kasa) fit as the reference; ``hip_refine_steps > 0`` adds Gauss-Newton steps on the geometric
  residual ``|p - c| - r``. A fit with a common centre but one radius per epicondyle
  (``hip_fit='concentric'``) is offered but is ill-posed for this motion: supine hip flexion is
  nearly planar, both epicondyles then move on coaxial circles, and the centre can slide along
  their common axis (on the real data it moves the HJC by up to 0.25 m). Equal radii pin it to
  the plane bisecting EFM-EFL, which is why Wang Table I finds EFM/EFL ``z = -/+ k/2`` (R^2 = 1).
* Femoral frame: origin HJC; ``y = (HJC - KJC)/|.|`` with KJC = (EFM + EFL)/2;
  ``x`` normal to the plane HJC-EFM-EFL, anterior (``x = y x (EFL - EFM)`` normalised: EFL is
  lateral = right for a right leg); ``z = x x y``.
* Knee AoR (Wang eq 1-8, :mod:`pipeline.calibration.aor`) from the femoral frames and the tibia
  cluster.
* Tibial frame: origin KJC; ``y = (KJC - AJC)/|.|`` with AJC = (MM + LM)/2; ``z`` = world knee
  axis ``E_F^k V_F`` projected perpendicular to ``y``; ``x = y x z``.
* Landmark positions in segment frames: per-axis median over all valid frames (the reference took
  frame 1 only).
* Body dimensions (Wang eq 14 inputs): ``k = |EFM - EFL|`` and ``a = |MM - LM|`` are rigid
  (median over frames). ``s_L = |EFL - LM|`` and ``s_M = |EFM - MM|`` span the knee and change with
  knee flexion; they are taken as the median over the most extended frames (smallest angle
  between femoral and tibial y axes, lowest ``extended_fraction`` of valid frames), which is what
  a caliper measurement on the straight leg gives; supine subjects rest with the knee extended.

Missing samples (NaN) are excluded from every fit and the frames are marked invalid (their frames
and origins are NaN in the result).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pipeline.calibration.aor import KneeAoR, knee_aor, reexpress_tibia
from pipeline.errors import InputError
from pipeline.reproduce.wang2023.dataset import OmcTrial
from pipeline.rotations import angle_between

__all__ = [
    "BodyDimensions",
    "OmcResult",
    "SphereFit",
    "femoral_frames",
    "fit_concentric_spheres",
    "fit_sphere",
    "landmarks_in_frames",
    "process_subject",
    "tibial_frames",
]


@dataclass(frozen=True)
class SphereFit:
    """Sphere (or concentric spheres) fitted to points.

    ``radius`` is the radius of the first point set; ``radii`` one per set; ``rms`` the RMS of
    the geometric residuals ``|p - c| - r``; ``method`` 'algebraic' or 'geometric' (algebraic
    start + Gauss-Newton refinement).
    """

    centre: np.ndarray
    radius: float
    rms: float
    radii: tuple[float, ...]
    method: str
    n_points: int


@dataclass(frozen=True)
class BodyDimensions:
    """Wang eq 14 inputs, metres.

    Height ``h``, shank lengths ``s_L = |EFL-LM|`` and ``s_M = |EFM-MM|`` (straight knee), knee
    width ``k = |EFM-EFL|``, ankle width ``a = |MM-LM|``.
    """

    h: float
    s_L: float
    s_M: float
    k: float
    a: float


@dataclass(frozen=True)
class OmcResult:
    """Processed optical data of one subject (lab frame for world quantities, SI units)."""

    subject_id: int
    sex: str
    hjc: np.ndarray
    hip_fit: SphereFit
    hip_fit_rms_m: float
    femur_R: np.ndarray
    femur_origin: np.ndarray
    tibia_R: np.ndarray
    tibia_origin: np.ndarray
    landmarks_femur: dict[str, np.ndarray]
    landmarks_tibia: dict[str, np.ndarray]
    knee_aor: KneeAoR
    dims: BodyDimensions
    n_frames: int
    valid: np.ndarray


# --------------------------------------------------------------------------------------------
# sphere fits


def fit_concentric_spheres(point_sets: Sequence[np.ndarray], refine_steps: int = 5) -> SphereFit:
    """Common centre and one radius per point set, least squares.

    Algebraic step (linear): ``|p|^2 = 2 c . p + d_g`` with ``d_g = r_g^2 - |c|^2`` per set ``g``
    (points are centred first for conditioning). Then ``refine_steps`` Gauss-Newton steps on the
    geometric residuals ``|p - c| - r_g``. NaN rows are ignored.
    """
    sets = []
    for P in point_sets:
        P = np.asarray(P, dtype=float).reshape(-1, 3)
        sets.append(P[np.all(np.isfinite(P), axis=1)])
    n_total = sum(len(P) for P in sets)
    G = len(sets)
    if any(len(P) == 0 for P in sets) or n_total < 4 + G:
        raise InputError(f"too few valid points for a sphere fit ({n_total})")
    pts = np.concatenate(sets)
    group = np.concatenate([np.full(len(P), g) for g, P in enumerate(sets)])
    mu = pts.mean(axis=0)
    q = pts - mu
    onehot = np.eye(G)[group]
    A = np.hstack([2 * q, onehot])
    sol, *_ = np.linalg.lstsq(A, np.sum(q**2, axis=1), rcond=None)
    c = sol[:3]
    r2 = sol[3:] + c @ c
    if np.any(r2 <= 0):
        raise InputError("sphere fit failed: points do not lie on a sphere")
    r = np.sqrt(r2)
    for _ in range(refine_steps):
        d = q - c
        dist = np.linalg.norm(d, axis=1)
        res = dist - r[group]
        J = np.hstack([-d / dist[:, None], -onehot])
        delta, *_ = np.linalg.lstsq(J, -res, rcond=None)
        c, r = c + delta[:3], r + delta[3:]
        if np.linalg.norm(delta) < 1e-12:
            break
    res = np.linalg.norm(q - c, axis=1) - r[group]
    return SphereFit(
        centre=c + mu,
        radius=float(r[0]),
        rms=float(np.sqrt(np.mean(res**2))),
        radii=tuple(float(x) for x in r),
        method="geometric" if refine_steps > 0 else "algebraic",
        n_points=int(n_total),
    )


def fit_sphere(points: np.ndarray, refine_steps: int = 0) -> SphereFit:
    """Least-squares sphere through ``points`` ``(N, 3)``: algebraic (Kasa) fit
    ``|p|^2 = 2 c . p + (r^2 - |c|^2)``, optionally refined by Gauss-Newton steps on
    ``|p - c| - r``. The reference implementation's hip fit is ``refine_steps=0`` on all EFM and
    EFL samples together."""
    return fit_concentric_spheres([points], refine_steps)


# --------------------------------------------------------------------------------------------
# frames


def _unit(v: np.ndarray) -> np.ndarray:
    with np.errstate(invalid="ignore", divide="ignore"):
        return v / np.linalg.norm(v, axis=-1, keepdims=True)


def femoral_frames(
    hjc: np.ndarray, efm: np.ndarray, efl: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """ISB femoral frames ``(R (N,3,3), origin (N,3))`` of a right leg (module docstring)."""
    efm, efl = np.asarray(efm, float), np.asarray(efl, float)
    kjc = 0.5 * (efm + efl)
    y = _unit(hjc - kjc)
    x = _unit(np.cross(y, efl - efm))
    z = np.cross(x, y)
    origin = np.broadcast_to(np.asarray(hjc, float), kjc.shape).copy()
    return np.stack([x, y, z], axis=-1), origin


def tibial_frames(
    efm: np.ndarray, efl: np.ndarray, mm: np.ndarray, lm: np.ndarray, knee_axis_world: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Tibial frames ``(R, origin)``: origin KJC, ``y`` AJC -> KJC, ``z`` the knee axis
    ``(N, 3)`` projected perpendicular to ``y``, ``x = y x z``."""
    kjc = 0.5 * (np.asarray(efm, float) + np.asarray(efl, float))
    ajc = 0.5 * (np.asarray(mm, float) + np.asarray(lm, float))
    y = _unit(kjc - ajc)
    w = np.asarray(knee_axis_world, float)
    z = _unit(w - np.sum(w * y, axis=-1, keepdims=True) * y)
    x = np.cross(y, z)
    return np.stack([x, y, z], axis=-1), kjc


def landmarks_in_frames(
    points: np.ndarray, R: np.ndarray, origin: np.ndarray, valid: np.ndarray | None = None
) -> np.ndarray:
    """Per-axis median over valid frames of ``R_k^T (p_k - o_k)`` (landmark in a segment frame)."""
    local = np.einsum("nji,nj->ni", R, np.asarray(points, float) - origin)
    ok = np.all(np.isfinite(local), axis=1)
    if valid is not None:
        ok &= valid
    if not ok.any():
        raise InputError("no valid frame to locate a landmark in its segment frame")
    return np.median(local[ok], axis=0)


# --------------------------------------------------------------------------------------------
# subject


def process_subject(
    omc: OmcTrial,
    *,
    hip_fit: str = "single",
    hip_refine_steps: int = 0,
    window: tuple[float, float] = (0.15, 0.85),
    window_coordinate: str = "elevation",
    min_window: int = 10,
    step: int | None = None,
    rel_angle_threshold: float = 0.5,
    min_axis_z: float = 0.6,
    extended_fraction: float = 0.05,
) -> OmcResult:
    """HJC, femoral/tibial frames, knee AoR, segment-frame landmarks and body dimensions.

    ``hip_fit``: 'single' (one sphere through all EFM and EFL samples, as the reference) or
    'concentric' (shared centre, own radii; ill-posed for planar motion, see module docstring).
    AoR options as :func:`pipeline.calibration.aor.knee_aor`.
    """
    lm = omc.landmarks
    efm, efl, mm, lm_ = lm["EFM"], lm["EFL"], lm["MM"], lm["LM"]
    if hip_fit == "concentric":
        fit = fit_concentric_spheres([efm, efl], hip_refine_steps)
    elif hip_fit == "single":
        fit = fit_sphere(np.concatenate([efm, efl]), hip_refine_steps)
    else:
        raise ValueError(f"hip_fit must be 'concentric' or 'single', got {hip_fit!r}")
    hjc = fit.centre
    finite = lambda a: np.all(np.isfinite(a.reshape(len(a), -1)), axis=1)  # noqa: E731
    valid = finite(efm) & finite(efl) & finite(mm) & finite(lm_) & finite(omc.tibia_cluster_R)
    if valid.sum() < 2 * min_window:
        raise InputError(f"only {int(valid.sum())} frames with all landmarks present")

    F, F_o = femoral_frames(hjc, efm, efl)
    F[~valid], F_o[~valid] = np.nan, np.nan
    aor = knee_aor(
        F,
        omc.tibia_cluster_R,
        window=window,
        window_coordinate=window_coordinate,
        min_window=min_window,
        step=step,
        rel_angle_threshold=rel_angle_threshold,
        min_axis_z=min_axis_z,
    )
    axis_world = F @ aor.femur_axis
    T, T_o = tibial_frames(efm, efl, mm, lm_, axis_world)
    T[~valid], T_o[~valid] = np.nan, np.nan
    aor = reexpress_tibia(aor, T)

    lf = {n: landmarks_in_frames(lm[n], F, F_o, valid) for n in ("EFM", "EFL")}
    lt = {n: landmarks_in_frames(lm[n], T, T_o, valid) for n in ("MM", "LM")}

    flex = np.full(len(valid), np.inf)
    flex[valid] = angle_between(F[valid][:, :, 1], T[valid][:, :, 1])
    n_ext = max(1, int(round(extended_fraction * valid.sum())))
    ext = np.argsort(flex)[:n_ext]
    dist = lambda a, b, idx: float(np.median(np.linalg.norm(a[idx] - b[idx], axis=1)))  # noqa: E731
    vidx = np.flatnonzero(valid)
    dims = BodyDimensions(
        h=omc.height_m,
        s_L=dist(efl, lm_, ext),
        s_M=dist(efm, mm, ext),
        k=dist(efm, efl, vidx),
        a=dist(mm, lm_, vidx),
    )
    return OmcResult(
        subject_id=omc.subject_id,
        sex=omc.sex,
        hjc=hjc,
        hip_fit=fit,
        hip_fit_rms_m=fit.rms,
        femur_R=F,
        femur_origin=F_o,
        tibia_R=T,
        tibia_origin=T_o,
        landmarks_femur=lf,
        landmarks_tibia=lt,
        knee_aor=aor,
        dims=dims,
        n_frames=omc.n_frames,
        valid=valid,
    )
