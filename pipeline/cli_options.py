"""Argument types of the commands (:func:`int_from`, :data:`PORT`) and the flags of
``pipeline ik``, from the options' one definition (:mod:`pipeline.process.options`;
importable at no cost: ``--help`` loads no NumPy)."""

from __future__ import annotations

import argparse
from pathlib import Path

from pipeline.option import add_flags
from pipeline.process.options import all_specs

__all__ = ["PORT", "add_ik_options", "int_from"]


def add_ik_options(p: argparse.ArgumentParser) -> None:
    """``pipeline ik``'s flags: ``--config`` and one per option; every one defaults to None (not
    given), so that a configuration file's value is overridden only by a flag that was typed."""
    p.add_argument("--config", type=Path, help="subject.toml: subject, sensor names and any of "
                   "these options (flags override it); each run writes <name>_config.toml "
                   "(default: none)")
    add_flags(p, all_specs())


def int_from(least: int, most: int | None = None):
    """An argparse type: an integer in ``[least, most]`` (argparse's one-line error otherwise)."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
        if value < least or (most is not None and value > most):
            span = f"{least}-{most}" if most is not None else f"{least} or more"
            raise argparse.ArgumentTypeError(f"expected {span}, got {value}")
        return value

    return parse


PORT = int_from(1, 65535)
