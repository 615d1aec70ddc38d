"""A command of subcommands (``rodcad catalog ...``, ``rodcad calibrate ...``): its parser, which
prints its help and exits 2 when no subcommand is given."""

from __future__ import annotations

import argparse
import sys

__all__ = ["command_group"]


def command_group(subparsers: argparse._SubParsersAction, name: str, *, help: str,  # type: ignore[type-arg]
                  description: str, dest: str) -> argparse._SubParsersAction:  # type: ignore[type-arg]
    """Add the command ``name`` and return its subparsers (the chosen one in ``dest``)."""
    parser = subparsers.add_parser(name, help=help, description=description)
    sub = parser.add_subparsers(dest=dest, metavar="SUBCOMMAND")

    def usage(args: argparse.Namespace) -> int:
        parser.print_help(sys.stderr)
        return 2

    parser.set_defaults(handler=usage)
    return sub
