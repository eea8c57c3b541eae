"""Command-line checks and file writes the example scripts share (imported as ``_cli``: a
script's folder is the first entry of sys.path when it runs)."""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from gpmsa.io.atomic import atomic_write
from gpmsa.model.data import MAX_SEED
from roadgen.checks import home_path

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def path_option(text: str) -> str:
    """argparse ``type=`` of an option that names a file or folder: an empty string (which
    would mean the current folder, or no path at all) is a usage error."""
    if not text.strip():
        raise argparse.ArgumentTypeError("an empty path: give a file or folder name")
    return text


def check_seed(
    parser: argparse.ArgumentParser, seed: int, offset: int = 0, option: str = "--seed"
) -> None:
    """Usage error unless ``seed`` (given as ``option``) and ``seed + offset`` (the largest seed
    the script derives from it) are seeds the libraries take: integers in [0, 2**128)."""
    if seed < 0:
        parser.error(f"{option} must be >= 0, got {seed}")
    if seed + offset >= MAX_SEED:
        parser.error(f"{option} must be <= 2**128 - {offset + 1} (the seeds' range), got {seed}")


def check_option_memory(parser: argparse.ArgumentParser, nbytes: float, what: str) -> None:
    """Usage error (before any simulation) where an option's setting would need ``nbytes``
    (an estimate, a lower bound) beyond ``gpmsa.limits.MAX_MEMORY_BYTES``; ``what`` names the
    option and what needs the memory. E.g. `gpmsa.fit` keeps every sweep of its parameters
    (8 bytes an element, twice while its chains are stacked) and would refuse it only when it
    starts, after the campaign."""
    import gpmsa

    try:
        gpmsa.limits.check_memory(nbytes, what)
    except gpmsa.ResourceLimitError as exc:
        parser.error(str(exc))


def output_folder(parser: argparse.ArgumentParser, option: str, folder: str | Path) -> Path:
    """The folder an option names for a script's output, made (with its parents) if missing.

    Before any long work, so that a bad folder is a usage error (``parser.error``: exit status
    2, a one-line message naming the option and the folder) rather than a crash at the first
    file written: one that cannot be made (a file of that name, no permission) or that is not
    writable.
    """
    folder = home_path(folder)  # --out=~/x: the shell leaves that ~ to us
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        parser.error(f"{option} {str(folder)!r}: cannot make that folder: {exc.strerror or exc}")
    if not os.access(folder, os.W_OK | os.X_OK):
        parser.error(f"{option} {str(folder)!r}: the folder is not writable")
    return folder


def write_text(path: Path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` in one step: a script stopped while writing leaves the
    previous file or none, never a part of one."""
    with atomic_write(path, text=True) as fh:
        fh.write(text)


def save_figure(fig: Figure, path: Path, dpi: int = 120) -> None:
    """``fig.savefig`` to ``path`` in one step (the format from its suffix), as `write_text`."""
    with atomic_write(path) as fh:
        fig.savefig(fh, format=path.suffix.lstrip("."), dpi=dpi)


class _UntilTheReaderLeaves:
    """stdout that, once its reader has gone (``... | head``: BrokenPipeError), drops what is
    printed instead of raising, so that the script still finishes its work and its files."""

    def __init__(self, stream) -> None:
        self._stream, self._gone = stream, False

    def _call(self, name: str, *args):
        if not self._gone:
            try:
                return getattr(self._stream, name)(*args)
            except BrokenPipeError:
                self._gone = True  # and no error when Python flushes it at exit:
                devnull = os.open(os.devnull, os.O_WRONLY)  # closed once the stream holds it
                os.dup2(devnull, self._stream.fileno())
                os.close(devnull)
        return len(args[0]) if args else None

    def write(self, text: str) -> int:
        return self._call("write", text)

    def flush(self) -> None:
        self._call("flush")

    def __getattr__(self, name: str):
        return getattr(self._stream, name)


def run(main: Callable[[], object]) -> None:
    """Run a script's ``main`` as a command: Ctrl-C ends it with one line on stderr and exit
    status 130 instead of a traceback (the files are written in one step each, so none is left
    in part); a reader that stops reading its output does not stop it (nor does a closed
    stdout: Python's sys.stdout is then None, and print writes nothing); a character that
    stdout's encoding lacks (a folder named in cp1252 output) is escaped, not an error."""
    if sys.stdout is not None:
        if hasattr(sys.stdout, "reconfigure"):  # a path that the output's encoding (cp1252 in
            sys.stdout.reconfigure(errors="backslashreplace")  # a file on Windows) lacks
        sys.stdout = _UntilTheReaderLeaves(sys.stdout)
    try:
        main()
    except KeyboardInterrupt:
        print(f"{Path(sys.argv[0]).name}: interrupted (Ctrl-C)", file=sys.stderr)
        raise SystemExit(130) from None
