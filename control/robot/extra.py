"""The optional packages of the ``robot`` extra, imported only when a function needs them."""

from __future__ import annotations

import importlib
from types import ModuleType

from control.errors import MissingExtraError

#: import name -> distribution name of each optional package this sub-package uses.
PACKAGES = {"rosbags": "rosbags", "mcap": "mcap"}
INSTALL_HINT = (
    'pip install "terrain-gpmsa[robot]"  (from a checkout of the repository: '
    'pip install -e ".[robot]")'
)


def require(module: str, purpose: str) -> ModuleType:
    """Import ``module`` (a name in PACKAGES or one of its sub-modules) or raise
    `MissingExtraError` naming the package, what needed it and the extra to install."""
    top = module.split(".")[0]
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        dist = PACKAGES.get(top, top)
        raise MissingExtraError(
            f"{purpose} needs the optional package {dist!r}, which is not installed; "
            f"install the 'robot' extra: {INSTALL_HINT}"
        ) from exc
