"""The subject's body measures, :class:`Measures`: what the regression equations (Wang 2023 Table
I, eq 14) take, each an option of ``pipeline ik``, ``pipeline scale`` and ``pipeline batch``
(:mod:`pipeline.option`). Importable at no cost (no NumPy): the CLI's flags come from here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from numbers import Real

from pipeline.errors import InputError
from pipeline.option import option

__all__ = ["FIELD_OF_INPUT", "PLAUSIBLE_M", "Measures", "check_length_m", "normalize_sex"]

#: Regression input ('h', 's_L', ...) -> the :class:`Measures` field that gives it.
FIELD_OF_INPUT = {
    "h": "height_m",
    "s_L": "shank_lateral_m",
    "s_M": "shank_medial_m",
    "k": "knee_width_m",
    "a": "ankle_width_m",
}
#: Plausible adult ranges (m); outside them the value is rejected, with a unit hint if it fits.
PLAUSIBLE_M = {
    "height_m": (1.0, 2.5),
    "shank_lateral_m": (0.2, 0.7),
    "shank_medial_m": (0.2, 0.7),
    "knee_width_m": (0.05, 0.2),
    "ankle_width_m": (0.03, 0.15),
    "pelvis_width_m": (0.15, 0.40),
}
_ABSENT = "default: not measured; the equations use the others"


def normalize_sex(sex: str, *, field: str = "sex") -> str:
    """'m' or 'f' from 'm', 'f', 'male', 'female' (any case); InputError otherwise."""
    s = str(sex).strip().lower()
    if s in ("m", "male"):
        return "m"
    if s in ("f", "female"):
        return "f"
    raise InputError(f"expected sex 'm' or 'f', got {sex!r}", field=field)


def check_length_m(value: float, name: str, low: float, high: float) -> float:
    """A length in metres within [low, high]; else InputError, hinting cm or mm when it fits."""
    if isinstance(value, bool) or not isinstance(value, Real):
        raise InputError(f"expected a length in metres, got {value!r}", field=name)
    v = float(value)
    if not math.isfinite(v) or v <= 0.0:
        raise InputError(f"expected a positive length in metres, got {v:g}", field=name)
    if low <= v <= high:
        return v
    for factor, unit in ((100.0, "centimetres"), (1000.0, "millimetres")):
        if low <= v / factor <= high:
            raise InputError(
                f"{v:g} looks like {unit}; give metres, e.g. {v / factor:.4g}", field=name
            )
    raise InputError(f"expected metres in [{low:g}, {high:g}], got {v:g}", field=name)


@dataclass(frozen=True)
class Measures:
    """A subject's body dimensions in metres (h required; the others optional, used if given)."""

    sex: str = option(None, "choice", "sex, for the regression equations", choices=("m", "f"),
                      section="subject", required=True)
    height_m: float = option(None, "float", "body height in metres", section="subject",
                             required=True)
    shank_lateral_m: float | None = option(None, "float", f"s_L = |EFL - LM| in metres "
                                           f"({_ABSENT})", section="subject")
    shank_medial_m: float | None = option(None, "float", f"s_M = |EFM - MM| in metres "
                                          f"({_ABSENT})", section="subject")
    knee_width_m: float | None = option(None, "float", f"k = |EFM - EFL| in metres ({_ABSENT})",
                                        section="subject")
    ankle_width_m: float | None = option(None, "float", f"a = |MM - LM| in metres ({_ABSENT})",
                                         section="subject")
    pelvis_width_m: float | None = option(None, "float", "the distance between the anterior "
                                          "superior iliac spines in metres: the hip centres "
                                          "0.72 of it apart (Bell 1989; default: not measured, "
                                          "the template's hips scaled with height)",
                                          section="subject")

    def __post_init__(self) -> None:
        object.__setattr__(self, "sex", normalize_sex(self.sex))
        for name, (low, high) in PLAUSIBLE_M.items():
            value = getattr(self, name)
            if value is not None or name == "height_m":
                object.__setattr__(self, name, check_length_m(value, name, low, high))

    def inputs_mm(self) -> dict[str, float]:
        """The available regression inputs ('h', 's_L', 's_M', 'k', 'a') in millimetres."""
        return {key: 1000.0 * getattr(self, name) for key, name in FIELD_OF_INPUT.items()
                if getattr(self, name) is not None}
