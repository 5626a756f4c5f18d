"""Command-line interface: ``pipeline <command> ...`` (also ``python -m pipeline``).

Errors in user input are printed as one line naming the file and the field, with a non-zero exit
code and no traceback (``--debug`` shows it).
"""

from __future__ import annotations

import argparse
import sys

from pipeline.errors import InputError


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="pipeline",
        description="Lower-limb IMU-to-skeleton pipeline on Pinocchio.",
    )
    parser.add_argument("--debug", action="store_true", help="show tracebacks on errors")
    sub = parser.add_subparsers(dest="command", required=True)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except (InputError, FileNotFoundError) as exc:
        if args.debug:
            raise
        print(f"error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    raise SystemExit(main())
