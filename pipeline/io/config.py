"""The configuration file of ``pipeline ik`` (TOML): the subject, the sensor names and the options.

::

    [subject]
    sex = "m"
    height_m = 1.80            # optional: shank_lateral_m, shank_medial_m, knee_width_m, ...

    [sensors]                  # our sensor name = the recording's name or device id
    pelvis_imu = "00B421AF"
    femur_r_imu = "thigh_R"

    [ik]                       # any other option of `pipeline ik`, named as its flag
    orientations = "walk.sto"  # paths relative to this file
    sensor_to_model = [-1.5708, 0.0, 0.0]
    correction = "none"

Which keys exist, in which table, and of which type, comes from the options' one definition
(:mod:`pipeline.option`, :mod:`pipeline.process.options`): this module only reads and writes the
file. Reading uses the standard library (``tomllib``); writing uses ``tomli-w`` (the file is data
the user reads and edits). Unknown tables and keys, wrong types, a file that is not UTF-8 TOML and
anything but a regular file are refused naming the file and the key.
"""

from __future__ import annotations

import stat
from collections.abc import Mapping
from pathlib import Path

from pipeline.errors import InputError
from pipeline.option import Spec, from_toml

__all__ = ["MAX_CONFIG_BYTES", "config_text", "read_config"]

#: A configuration file is a few hundred bytes; anything this large is not one.
MAX_CONFIG_BYTES = 1_000_000


def read_config(path: str | Path, options: list[Spec]) -> dict[str, object]:
    """Option name -> value of every option the file ``path`` gives (module docstring); paths
    made absolute against the file's folder."""
    import tomllib  # here: ~10 ms of import that a command without --config does not pay

    path = Path(path)
    text = _read_text(path)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"not valid TOML: {exc}", file=path) from None
    sections = sorted({s.section for s in options})
    unknown = set(data) - set(sections)
    if unknown:
        expected = ", ".join(f"[{s}]" for s in sections)
        raise InputError(f"unknown section(s) {sorted(unknown)}; expected {expected}", file=path,
                         field=sorted(unknown)[0])
    for section, table in data.items():
        if not isinstance(table, dict):
            raise InputError("expected a table", file=path, field=section)
    out: dict[str, object] = {}
    by_key = {(s.section, s.name): s for s in options if s.kind != "pairs"}
    tables = {s.section: s for s in options if s.kind == "pairs"}
    for section, table in data.items():
        if section in tables:
            spec = tables[section]
            out[spec.name] = from_toml(spec, table, path.parent, path)
            continue
        for key, value in table.items():
            spec = by_key.get((section, key))
            if spec is None:
                names = [n for (sec, n) in by_key if sec == section]
                raise InputError(f"unknown key; expected one of {names}", file=path,
                                 field=f"{section}.{key}")
            out[key] = from_toml(spec, value, path.parent, path)
    return out


def _read_text(path: Path) -> str:
    """The file's text, refused unless it is a regular UTF-8 file of a plausible size (a FIFO or a
    device would block or never end)."""
    try:
        info = path.stat()
    except FileNotFoundError:
        raise InputError("no such configuration file", file=path) from None
    except OSError as exc:
        raise InputError(f"cannot read it: {exc.strerror}", file=path) from None
    if not stat.S_ISREG(info.st_mode):
        raise InputError("expected a regular file (a TOML configuration)", file=path)
    if info.st_size > MAX_CONFIG_BYTES:
        raise InputError(f"{info.st_size} bytes: too large for a configuration file", file=path)
    raw = path.read_bytes()
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputError(f"not UTF-8 text (byte {exc.start}): save it as UTF-8",
                         file=path) from None
    if "\x00" in text:
        raise InputError("not a text file (it holds NUL bytes)", file=path)
    return text


def config_text(doc: Mapping[str, Mapping[str, object]], header: str = "") -> str:
    """``doc`` (table -> key -> value) as TOML text after ``header`` as comment lines."""
    import tomli_w

    comment = "".join(f"# {line}\n" if line else "#\n" for line in header.splitlines())
    return comment + tomli_w.dumps({k: dict(v) for k, v in doc.items()})
