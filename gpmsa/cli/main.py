"""The ``gpmsa`` console command: argparse with one module per subcommand (info, calibrate)."""

from __future__ import annotations

import argparse
import os
import sys

from gpmsa._version import __version__
from gpmsa.cli import calibrate, info


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand."""
    parser = argparse.ArgumentParser(prog="gpmsa", description="GPM/SA emulator tools")
    parser.add_argument("--version", action="version", version=f"gpmsa {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    info.add_parser(sub)
    calibrate.add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``gpmsa`` console script (and of ``python -m gpmsa`` and
    ``python -m gpmsa.cli``)."""
    args = build_parser().parse_args(argv)
    if hasattr(sys.stdout, "reconfigure"):  # a name that the output's encoding (cp1252 in a
        sys.stdout.reconfigure(errors="backslashreplace")  # file on Windows) lacks: \u03c3
    try:
        return args.func(args)
    except BrokenPipeError:  # the reader went away (`gpmsa info FILE | head`): not an error
        devnull = os.open(os.devnull, os.O_WRONLY)  # closed once stdout holds it
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
        return 0
    except KeyboardInterrupt:  # Ctrl-C: one line, not a traceback
        print("gpmsa: interrupted (Ctrl-C)", file=sys.stderr)
        return 130


if __name__ == "__main__":  # python -m gpmsa.cli.main, as the console script runs it
    sys.exit(main())
