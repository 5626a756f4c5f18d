"""One definition per option: an option is a dataclass field declared with :func:`option`, and its
flag, its configuration-file key and its manifest column all follow from that one declaration.

::

    @dataclass(frozen=True)
    class IKOptions:
        knee: str = option("free", "choice", "knee model", choices=("hinge", "free"))

:func:`specs` lists a class's options as :class:`Spec` values; :func:`add_flags` adds them to an
``argparse`` parser (every flag defaults to None, "not given", so that a configuration file's
value is overridden only by a flag that was typed); :func:`from_toml` checks a configuration
file's value and :func:`from_cell` parses a manifest cell; :func:`to_toml` writes a value back.
What a value may be (a choice, a range) is checked once, by the dataclass itself.

Kinds (:data:`KINDS`): ``text``; ``words`` (several texts: ``--x a b``, ``x = ["a", "b"]``, a
cell ``"a b"``); ``choice`` (one of ``choices``); ``float``; ``int``; ``vec3``
(three numbers: ``--x 1 2 3``, ``x = [1, 2, 3]``, a cell ``"1 2 3"``); ``bool`` (``--x``, or
``--no-x`` when the default is true; ``x = true``; a cell ``true``/``false``/``yes``/``no``/
``1``/``0``); ``path`` (relative to the configuration file or the manifest); ``pairs``
(``NAME=VALUE`` words: ``--x a=1 b=2``, a table ``[section]`` in the file, a cell ``"a=1 b=2"``).

Importable at no cost (no NumPy): ``pipeline --help`` is built from it.
"""

from __future__ import annotations

import argparse
import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from pipeline.errors import InputError

__all__ = ["KINDS", "Spec", "add_flags", "from_cell", "from_toml", "option", "specs", "to_toml"]

KINDS = ("text", "words", "choice", "float", "int", "vec3", "bool", "path", "pairs")
_TRUE, _FALSE = ("true", "1", "yes"), ("false", "0", "no")


@dataclass(frozen=True)
class Spec:
    """One option: its ``name`` (the field's), ``kind`` (:data:`KINDS`), ``help`` text,
    ``default``, ``choices``, the configuration file's ``section`` (``subject``, ``sensors`` or
    ``ik``), whether it is ``required``, ``metavar``, hidden ``aliases`` of its flag and, for a
    true ``bool``, what its ``--no-`` flag does (``off``: that flag's help)."""

    name: str
    kind: str
    help: str
    default: object = None
    choices: tuple[str, ...] = ()
    section: str = "ik"
    required: bool = False
    metavar: str | tuple[str, ...] | None = None
    aliases: tuple[str, ...] = ()
    off: str | None = None

    @property
    def flag(self) -> str:
        """The command-line flag: ``--name-with-dashes``; ``--no-name`` for a true default."""
        dashed = self.name.replace("_", "-")
        return f"--no-{dashed}" if self.kind == "bool" and self.default is True else f"--{dashed}"

    @property
    def key(self) -> str:
        """Where the configuration file holds it: ``section.name`` (``sensors`` for pairs)."""
        return self.section if self.kind == "pairs" else f"{self.section}.{self.name}"

    def default_text(self) -> str:
        if self.required:
            return "required"
        if self.default is None or self.default == {}:
            return "default: none"
        if self.kind == "bool":
            return f"default: {'yes' if self.default else 'no'}"
        if self.kind == "vec3":
            return "default: " + " ".join(f"{v:g}" for v in self.default)  # type: ignore[attr-defined]
        return f"default: {self.default}"


def option(
    default: object,
    kind: str,
    help: str,  # noqa: A002 (argparse's word)
    *,
    choices: tuple[str, ...] = (),
    section: str = "ik",
    required: bool = False,
    metavar: str | tuple[str, ...] | None = None,
    aliases: tuple[str, ...] = (),
    off: str | None = None,
) -> object:
    """A dataclass field that is an option (module docstring); ``default`` is the field's."""
    if kind not in KINDS:
        raise ValueError(f"unknown option kind {kind!r}; expected one of {KINDS}")
    meta = {"option": dict(kind=kind, help=help, choices=tuple(choices), section=section,
                           required=required, metavar=metavar, aliases=tuple(aliases),
                           off=off)}
    if isinstance(default, dict):
        return dataclasses.field(default_factory=dict, metadata=meta)
    if required:
        return dataclasses.field(metadata=meta)
    return dataclasses.field(default=default, metadata=meta)


def specs(*classes: type) -> list[Spec]:
    """The options of dataclasses ``classes``, in field order."""
    out = []
    for cls in classes:
        for f in dataclasses.fields(cls):
            meta = f.metadata.get("option")
            if meta is None:
                continue
            default = {} if f.default_factory is dict else (
                None if f.default is dataclasses.MISSING else f.default)
            out.append(Spec(f.name, default=default, **meta))
    return out


# ------------------------------------------------------------------------------------- flags


def add_flags(parser: argparse.ArgumentParser, options: list[Spec]) -> None:
    """One flag per option (``dest`` = its name, default None = not given)."""
    for s in options:
        said = "(default:" in s.help  # the help says what its default means
        text = s.help if said else f"{s.help} ({s.default_text()})"
        if s.kind == "bool" and s.default is True:  # --no-x: what it does; by default, the help
            text = f"{s.off or 'not: ' + s.help} (by default: {s.help})"
        common = dict(dest=s.name, default=None, help=text)
        names = [s.flag]
        if s.kind == "bool":
            parser.add_argument(*names, action="store_const", const=not s.default, **common)
            if s.default is True:  # --x, the default said explicitly (e.g. over a config file)
                parser.add_argument(f"--{s.name.replace('_', '-')}", action="store_const",
                                    const=True, dest=s.name, default=None, help=argparse.SUPPRESS)
        elif s.kind == "vec3":
            parser.add_argument(*names, type=float, nargs=3, metavar=s.metavar or ("X", "Y", "Z"),
                                **common)
        elif s.kind == "words":  # a flag given twice adds to the first (--ignore a --ignore b)
            parser.add_argument(*names, action="extend", nargs="+", metavar=s.metavar, **common)
        elif s.kind == "pairs":
            parser.add_argument(*names, action="extend", nargs="+",
                                metavar=s.metavar or "NAME=VALUE", **common)
            for alias in s.aliases:
                parser.add_argument(alias, action="extend", nargs="+", dest=s.name, default=None,
                                    help=argparse.SUPPRESS)
        elif s.kind == "choice":
            parser.add_argument(*names, choices=s.choices, metavar=s.metavar, **common)
        else:
            kind = {"float": float, "int": int, "path": Path}.get(s.kind, str)
            parser.add_argument(*names, type=kind, metavar=s.metavar, **common)


def parse_pairs(words: list[str] | str, field: str) -> dict[str, str]:
    """``["a=1", "b=2"]`` (or ``"a=1 b=2"``) -> ``{"a": "1", "b": "2"}``; refused otherwise."""
    out: dict[str, str] = {}
    for item in words.split() if isinstance(words, str) else words:
        name, sep, value = item.partition("=")
        if not sep or not name or not value:
            raise InputError(f"expected NAME=VALUE pairs, got {item!r}", field=field)
        if name in out:
            raise InputError(f"{name!r} is given twice", field=field)
        out[name] = value
    return out


def from_flag(spec: Spec, value: object) -> object:
    """A parsed flag's value as the option takes it (paths as text, vectors as tuples)."""
    if value is None:
        return None
    if spec.kind == "pairs":
        return parse_pairs(value, spec.flag)  # type: ignore[arg-type]
    if spec.kind in ("vec3", "words"):
        return tuple(value)  # type: ignore[arg-type]
    if spec.kind == "path":
        return str(value)
    return value


# ----------------------------------------------------------------------- configuration file

_TOML_TYPES = {"text": (str,), "words": (list,), "choice": (str,), "path": (str,),
               "float": (float, int), "int": (int,), "bool": (bool,), "vec3": (list,),
               "pairs": (dict,)}
_TYPE_NAMES = {"text": "text", "words": "a list of texts", "choice": "text",
               "path": "text (a path)", "float": "a number", "int": "a whole number",
               "bool": "true or false", "vec3": "a list of three numbers",
               "pairs": "a table of name = text"}


def from_toml(spec: Spec, value: object, base: Path, file: Path) -> object:
    """A configuration file's value of ``spec`` checked for its type (paths made absolute
    against ``base``); refused naming ``file`` and the key."""
    ok = isinstance(value, _TOML_TYPES[spec.kind]) and not (
        isinstance(value, bool) and spec.kind != "bool")
    if ok and spec.kind == "vec3":
        ok = len(value) == 3 and all(  # type: ignore[arg-type]
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)  # type: ignore[union-attr]
    if ok and spec.kind == "words":
        ok = all(isinstance(v, str) for v in value)  # type: ignore[union-attr]
    if ok and spec.kind == "pairs":
        for k, v in value.items():  # type: ignore[union-attr]
            if not isinstance(v, str):
                raise InputError(f"expected text, got {v!r}", file=file,
                                 field=f"{spec.section}.{k}")
    if not ok:
        raise InputError(f"expected {_TYPE_NAMES[spec.kind]}, got {value!r}", file=file,
                         field=spec.key)
    if spec.kind == "path":
        return _absolute(str(value), base)
    if spec.kind == "vec3":
        return tuple(float(v) for v in value)  # type: ignore[union-attr]
    if spec.kind == "words":
        return tuple(value)  # type: ignore[arg-type]
    if spec.kind == "pairs":
        return dict(value)  # type: ignore[arg-type]
    if spec.kind == "float":
        return float(value)  # type: ignore[arg-type]
    return value


def to_toml(spec: Spec, value: object) -> object:
    """A value as the configuration file writes it (None: left out; TOML has no null)."""
    if value is None:
        return None
    if spec.kind == "vec3":
        return [float(v) for v in value]  # type: ignore[union-attr]
    if spec.kind == "words":
        return list(value)  # type: ignore[call-overload]
    if spec.kind == "path":  # an installed example's name is kept as it is
        text = str(value)
        return text if text.startswith("example:") else str(Path(text).resolve())
    if spec.kind == "pairs":
        return dict(value)  # type: ignore[call-overload]
    return value


# ------------------------------------------------------------------------------ manifest cells


def from_cell(spec: Spec, text: str, base: Path, file: Path, line: int) -> object:
    """A manifest cell (non-empty text) as the option takes it; refused naming the column and
    the line."""
    field = f"{spec.name} (line {line})"
    try:
        if spec.kind == "path":
            return _absolute(text, base)
        if spec.kind == "float":
            return float(text)
        if spec.kind == "int":
            return int(text)
        if spec.kind == "vec3":
            v = tuple(float(x) for x in text.split())
            if len(v) != 3:
                raise ValueError
            return v
    except ValueError:
        what = {"float": "a number", "int": "a whole number",
                "vec3": "three numbers separated by spaces"}[spec.kind]
        raise InputError(f"expected {what}, got {text!r}", file=file, field=field) from None
    if spec.kind == "bool":
        low = text.strip().lower()
        if low not in _TRUE + _FALSE:
            raise InputError(f"expected true or false, got {text!r}", file=file, field=field)
        return low in _TRUE
    if spec.kind == "words":
        return tuple(text.split())
    if spec.kind == "pairs":
        try:
            return parse_pairs(text, field)
        except InputError as exc:
            raise InputError(exc.message, file=file, field=field) from None
    return text


def _absolute(text: str, base: Path) -> str:
    """``text`` as an absolute path against ``base``; an installed example's name
    (``example:<name>``, :mod:`pipeline.examples`) is kept as it is."""
    if text.startswith("example:"):
        return text
    p = Path(text).expanduser()
    return str(p if p.is_absolute() else (base / p).resolve())


def given(values: Mapping[str, object]) -> dict[str, object]:
    """The values that were given (not None)."""
    return {k: v for k, v in values.items() if v is not None}
