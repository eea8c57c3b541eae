"""Command-line checks and file writes the example scripts share (imported as ``_cli``: a
script's folder is the first entry of sys.path when it runs)."""

from __future__ import annotations

import argparse
import os
from pathlib import Path
from typing import TYPE_CHECKING

from gpmsa.io.atomic import atomic_write

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def output_folder(parser: argparse.ArgumentParser, option: str, folder: str | Path) -> Path:
    """The folder an option names for a script's output, made (with its parents) if missing.

    Before any long work, so that a bad folder is a usage error (``parser.error``: exit status
    2, a one-line message naming the option and the folder) rather than a crash at the first
    file written: one that cannot be made (a file of that name, no permission) or that is not
    writable.
    """
    folder = Path(folder)
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
