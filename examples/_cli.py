"""Command-line checks the example scripts share (imported as ``_cli``: a script's folder is the
first entry of sys.path when it runs)."""

from __future__ import annotations

import argparse
import os
from pathlib import Path


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
