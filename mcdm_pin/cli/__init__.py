"""Command line: a thin package of one module per command; no library module imports it.

Every command module has ``add(subparsers)`` and ``run(args) -> exit status``. Errors raised as
:class:`~mcdm_pin.exceptions.McdmError` exit with status 2 and one line on stderr.
"""

from __future__ import annotations

import argparse
import sys

from ..exceptions import McdmError
from . import compile, export_opensim, import_caspr, info, plot, solve, verify, view, workspace
from ._common import Parser, UsageError

COMMANDS = [info, solve, import_caspr, view, plot, verify, export_opensim, workspace, compile]


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(prog="mcdm-pin", description="Inverse dynamics of multilink cable-driven "
                                                  "manipulators with joint interaction forces.")
    from .. import __version__

    parser.add_argument("--version", action="version", version=f"mcdm-pin {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)
    for command in COMMANDS:
        command.add(sub)
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
        if not getattr(args, "func", None):
            parser.print_help()
            return 2
        return int(args.func(args) or 0)
    except McdmError as exc:
        print(f"mcdm-pin: error: {exc}".replace("\n", " "), file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:  # the message, if any, says what was kept
        print(f"mcdm-pin: {exc}" if str(exc) else "mcdm-pin: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # the reader of our output went away (e.g. `| head`): not an error of ours
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0


__all__ = ["main", "build_parser", "UsageError", "COMMANDS"]
