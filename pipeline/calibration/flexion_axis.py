"""A segment's flexion axis in its sensor's frame, from the sensor's own gait: the principal axis of
its horizontal angular velocity.

In walking the thigh, shank and foot turn mostly in the sagittal plane, about the medio-lateral
axis: each segment's flexion axis, a direction fixed in its sensor's frame. With ``w`` the
sensor's angular velocity (sensor frame) and ``u`` the world's vertical seen in that frame (from
the sensor's inclination, which a 6-D filter observes), the horizontal part

    w_h = w - (w . u) u                                                           (1)

leaves out the turns of the whole body about the vertical (and, for a segment close to vertical,
the axial soft-tissue wobble of its sensor). Low-passed (:func:`pipeline.filtering.lowpass`) and
taken over the samples in motion, its principal axis (the first right singular vector of the
stack of ``w_h``) is the flexion axis: a direction in the sensor's frame that needs no heading, so
sensors whose worlds differ by a heading (6-D filters, disturbed magnetometers) see the same
physical axis. Kong et al. 2016 (Sensors 16:2011) estimate the sagittal plane from walking the
same way, from the accelerations' principal axes; the principal axis of the angular velocity is
the joint-axis view of it (Seel et al. 2012's hinge axis, without the second sensor).

``share`` is the fraction of the horizontal angular velocity's power along the axis (near 1 for
a segment flexing in one plane); ``moving`` the fraction of samples used.

**Signs** (:func:`leg_flexion_axes`): a principal axis has no sign, and the two sensors of a joint
must agree on one. The knee flexes one way only: with each segment's pitch ``p_s(t)``, the turn
of the world's vertical seen in its sensor's frame about ``j_s`` since the first sample (the
sensor turns the other way), the knee's flexion ``p_shank - p_thigh`` rests near extension through
the stance and reaches some 60 deg in the swing. From an extended knee's first sample (a still
start, standing: both sensors' verticals within :data:`STILL_START_DEG` over its first half second)
it spans far more on the flexion side than on the other (a wrong relative sign gives the thigh's
and the shank's pitches added, two-sided): of the four sign pairs the one that makes it most
positive (``P98 + P2 - 2 k_0``) points both axes to the subject's right. A recording that starts
moving (mid-swing, the knee flexed 60 deg) has no such sample (from it, S02 cut to start at
sample 1300 read both axes pointing left); there the shank is signed by its swing (below: its
rotation rate about the axis skewed to the positive side, 1.0-1.2 on S02, 1.5 on the simulated
walk) and the thigh alike with it, the pair whose knee flexion spans less (alike: the knee's
60-70 deg; unlike: the thigh's and the shank's swings added). The knee's own skew would not do:
the simulated walk's knee flexes as much in stance as it extends (its ``P98 + P2 - 2 P50``
-5 to 1 deg, S02's +31).
The foot turns with the shank through most of the stride: its axis takes the sign that
correlates its angular rate with the shank's (measured correlation 0.92-0.94 on a real walk,
0.87-0.91 on the simulator's). A shank alone is signed by its swing: the swing forward of the
distal end (positive about the subject's right in ISB: ``+z`` turns ``x`` towards ``y``), its
fastest rotation in real gait, gives ``w_h . j`` a positive skew (not the simulator's sinusoidal
gait, whose skew is near zero).

**The pelvis** barely flexes, but in walking it lists (obliquity, a few degrees) once per stride
about its antero-posterior axis and tilts twice per stride about its medio-lateral one (Perry &
Burnfield 2010, Gait Analysis, ch. 8). Kept to a band around the stride frequency (the thigh's
flexion rate's spectral peak, :func:`stride_frequency`), the horizontal angular velocity's
principal axis is the antero-posterior line (:func:`pelvis_lateral_line`: 1-5 deg from the
truth on the simulated walk, 5 deg from the calibrated 9-D pelvis frame on S02, 13 on the x-IMU3
walk; twice the stride frequency, the tilt's, gave a line 30 deg off on S02), and ``up x`` it the
medio-lateral line, its sign free: :mod:`pipeline.process.heading_alignment` signs it by the hip
centres.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.errors import InputError
from pipeline.filtering import lowpass

__all__ = ["CUTOFF_HZ", "MIN_LIST_RATE", "MIN_SPEED", "MIN_STRIDE_SHARE", "STILL_START_DEG",
           "STRIDE_BAND_HZ", "FlexionAxis", "flexion_axis", "knee_signs", "leg_flexion_axes",
           "pelvis_lateral_line", "stride_frequency"]

#: Low-pass cut-off of the angular velocity (Hz): gait's rotations, not the soft tissue's.
CUTOFF_HZ = 3.0
#: Samples whose horizontal angular speed is below this (rad/s) are left out (standing still).
MIN_SPEED = 0.5
_MIN_SAMPLES = 50


@dataclass(frozen=True)
class FlexionAxis:
    """``axis`` (3,) unit, in the sensor frame, pointing to the subject's right; ``share`` of
    the horizontal angular velocity's power along it; ``moving``: fraction of samples used."""

    axis: np.ndarray
    share: float
    moving: float


def flexion_axis(
    gyr: np.ndarray,
    up: np.ndarray,
    rate_hz: float,
    *,
    cutoff_hz: float = CUTOFF_HZ,
    min_speed: float = MIN_SPEED,
) -> FlexionAxis:
    """Eq (1) of the module docstring: ``gyr`` (N, 3) rad/s and ``up`` (N, 3), the world's
    vertical in the sensor frame at each sample (unit), both in the sensor frame. Refused when
    fewer than 50 samples move (a segment that does not walk)."""
    w = lowpass(np.asarray(gyr, dtype=float), rate_hz, cutoff_hz)
    u = np.asarray(up, dtype=float)
    if u.shape != w.shape:
        raise InputError(f"expected the vertical per sample, {w.shape}, got {u.shape}",
                         field="up")
    w_h = w - np.sum(w * u, axis=1, keepdims=True) * u
    moving = np.linalg.norm(w_h, axis=1) > min_speed
    if moving.sum() < _MIN_SAMPLES:
        raise InputError(f"the segment turns faster than {min_speed:g} rad/s in only "
                         f"{int(moving.sum())} samples: no flexion axis (does it walk?)",
                         field="gyr")
    X = w_h[moving]
    _, S, Vt = np.linalg.svd(X, full_matrices=False)
    axis = Vt[0]
    if np.mean((X @ axis) ** 3) < 0:  # the swing forward is the fastest, positive rotation
        axis = -axis
    return FlexionAxis(axis, float(S[0] ** 2 / np.sum(S**2)), float(moving.mean()))


def _pitch(up: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """The turn (rad) of the world's vertical about ``axis`` since the first sample, seen in the
    sensor's frame."""
    u = np.asarray(up, dtype=float)
    return np.arctan2(np.cross(u[0], u) @ axis, u @ u[0])


#: A knee whose two sensors' verticals keep within this (deg) over the first half second starts
#: still: its flexion is read from its first sample (a standing start: extended).
STILL_START_DEG = 2.0


def knee_signs(
    up_thigh: np.ndarray,
    up_shank: np.ndarray,
    axis_thigh: np.ndarray,
    axis_shank: np.ndarray,
    rate_hz: float,
) -> tuple[float, float]:
    """The signs ``(s_thigh, s_shank)`` that point a knee's two axes (each in its sensor's
    frame) alike and to the subject's right: the pair that skews the knee's flexion from the
    segments' pitches, ``s_shank p_shank - s_thigh p_thigh``, most to the positive side
    (``P98 + P2 - 2 k_0``, ``k_0`` the first sample's or the median: module docstring).
    ``up_*``: the world's vertical in each sensor's frame per sample; ``rate_hz`` their rate."""
    p_f, p_t = _pitch(up_thigh, axis_thigh), _pitch(up_shank, axis_shank)
    first = slice(0, max(2, int(round(0.5 * rate_hz))))
    if max(np.ptp(p_f[first]), np.ptp(p_t[first])) >= np.radians(STILL_START_DEG):
        return _moving_knee_signs(p_f, p_t, rate_hz)

    def positive(s_f: float, s_t: float) -> float:
        k = s_t * p_t - s_f * p_f
        return float(np.percentile(k, 98) + np.percentile(k, 2) - 2 * k[0])

    return max(((a, b) for a in (1.0, -1.0) for b in (1.0, -1.0)), key=lambda s: positive(*s))


def _moving_knee_signs(p_f: np.ndarray, p_t: np.ndarray, rate_hz: float) -> tuple[float, float]:
    """:func:`knee_signs` of a recording that starts moving (module docstring): the shank's by
    its swing (its rotation rate about its axis, ``-dp/dt``, skewed to the positive side), the
    thigh's alike with it (the knee's flexion the narrower of ``s_t p_t -+ p_f``)."""
    rate = -np.gradient(lowpass(p_t, rate_hz, CUTOFF_HZ)) * rate_hz
    s_t = 1.0 if np.mean(rate**3) >= 0 else -1.0

    def spread(s_f: float) -> float:
        k = s_t * p_t - s_f * p_f
        return float(np.percentile(k, 98) - np.percentile(k, 2))

    return min((1.0, -1.0), key=spread), s_t


def _flip(a: FlexionAxis, sign: float) -> FlexionAxis:
    return a if sign > 0 else FlexionAxis(-a.axis, a.share, a.moving)


def leg_flexion_axes(
    rate_hz: float,
    segments: dict[str, tuple[np.ndarray, np.ndarray]],
) -> dict[str, FlexionAxis]:
    """The flexion axes of one leg's ``'femur'``, ``'tibia'`` and ``'foot'`` (those given, each
    ``(gyr, up)`` as :func:`flexion_axis` takes), signed alike, pointing to the subject's right
    (module docstring)."""
    axes = {seg: flexion_axis(g, u, rate_hz) for seg, (g, u) in segments.items()}
    if "femur" in axes and "tibia" in axes:
        s_f, s_t = knee_signs(segments["femur"][1], segments["tibia"][1], axes["femur"].axis,
                              axes["tibia"].axis, rate_hz)
        axes["femur"], axes["tibia"] = _flip(axes["femur"], s_f), _flip(axes["tibia"], s_t)
    if "foot" in axes and "tibia" in axes:
        rates = [lowpass(segments[seg][0], rate_hz, CUTOFF_HZ) @ axes[seg].axis
                 for seg in ("tibia", "foot")]
        axes["foot"] = _flip(axes["foot"], float(np.sign(np.corrcoef(*rates)[0, 1])) or 1.0)
    return axes


#: Where a stride frequency is looked for (Hz): slow to brisk walking.
STRIDE_BAND_HZ = (0.4, 1.6)
#: A walking thigh's flexion rate has at least this share of its power within 0.6-1.4 times
#: the stride frequency (0.70-0.86 on S02, the x-IMU3 walk and the simulated walks; a supine
#: hip flexion 0.11).
MIN_STRIDE_SHARE = 0.5
#: A walking pelvis lists at least this fast (RMS rad/s within the band; 0.10-0.28 walking,
#: 0.002-0.006 lying or seated).
MIN_LIST_RATE = 0.03


def _band(freq: np.ndarray, stride_hz: float) -> np.ndarray:
    return (freq >= 0.6 * stride_hz) & (freq <= 1.4 * stride_hz)


def stride_frequency(rate: np.ndarray, rate_hz: float) -> float:
    """The stride frequency (Hz): the spectral peak within :data:`STRIDE_BAND_HZ` of a thigh's
    flexion rate ``rate`` (N,) rad/s (its angular velocity along its flexion axis): a thigh
    swings once per stride. Refused unless the band around it holds
    :data:`MIN_STRIDE_SHARE` of the power (not walking)."""
    x = lowpass(np.asarray(rate, dtype=float), rate_hz, CUTOFF_HZ)
    x = (x - x.mean()) * np.hanning(len(x))
    power = np.abs(np.fft.rfft(x)) ** 2
    freq = np.fft.rfftfreq(len(x), 1.0 / rate_hz)
    search = (freq >= STRIDE_BAND_HZ[0]) & (freq <= STRIDE_BAND_HZ[1])
    if not search.any() or not np.any(power[search] > 0):
        raise InputError("the thigh does not swing: no stride frequency", field="gyr")
    f = float(freq[search][np.argmax(power[search])])
    share = power[_band(freq, f)].sum() / power[1:].sum()
    if share < MIN_STRIDE_SHARE:
        raise InputError(f"the thigh does not swing once per stride ({share:.2f} of its flexion "
                         f"rate's power near {f:.2f} Hz, walking: >= {MIN_STRIDE_SHARE:g})",
                         field="gyr")
    return f


def pelvis_lateral_line(
    gyr: np.ndarray, up: np.ndarray, rate_hz: float, stride_hz: float
) -> FlexionAxis:
    """The pelvis's medio-lateral line in its sensor's frame (module docstring), its sign free:
    ``gyr`` (N, 3) rad/s and ``up`` (N, 3) the world's vertical in the sensor's frame; the
    horizontal angular velocity kept between 0.6 and 1.4 ``stride_hz`` (its Fourier transform's
    other bins set to zero: the tilt at twice the stride frequency is as fast as the list), its
    principal axis ``a`` (antero-posterior), and ``mean(up) x a``. ``share``: the band's
    horizontal power along ``a``."""
    g, u = np.asarray(gyr, dtype=float), np.asarray(up, dtype=float)
    w_h = g - np.sum(g * u, axis=1, keepdims=True) * u
    spectrum = np.fft.rfft(w_h - w_h.mean(axis=0), axis=0)
    freq = np.fft.rfftfreq(len(w_h), 1.0 / rate_hz)
    spectrum[~_band(freq, stride_hz)] = 0.0
    w_h = np.fft.irfft(spectrum, n=len(w_h), axis=0)
    speed = float(np.sqrt(np.mean(np.sum(w_h**2, axis=1))))
    if not speed >= MIN_LIST_RATE:
        raise InputError(f"the pelvis does not list ({speed:.3f} rad/s at the stride frequency, "
                         f"walking: >= {MIN_LIST_RATE:g})", field="gyr")
    _, S, Vt = np.linalg.svd(w_h, full_matrices=False)
    line = np.cross(u.mean(axis=0), Vt[0])
    return FlexionAxis(line / np.linalg.norm(line), float(S[0] ** 2 / np.sum(S**2)), 1.0)
