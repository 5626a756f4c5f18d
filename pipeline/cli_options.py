"""The flags of ``pipeline ik``, from the options' one definition (:mod:`pipeline.process.options`;
importable at no cost: ``--help`` loads no NumPy)."""

from __future__ import annotations

import argparse
from pathlib import Path

from pipeline.option import add_flags
from pipeline.process.options import all_specs

__all__ = ["add_ik_options"]


def add_ik_options(p: argparse.ArgumentParser) -> None:
    """``pipeline ik``'s flags: ``--config`` and one per option; every one defaults to None (not
    given), so that a configuration file's value is overridden only by a flag that was typed."""
    p.add_argument("--config", type=Path, help="subject.toml: subject, sensor names and any of "
                   "these options (flags override it); each run writes <name>_config.toml "
                   "(default: none)")
    add_flags(p, all_specs())
