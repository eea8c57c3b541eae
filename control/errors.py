"""Exceptions and warnings raised by control."""

import sys

_OWN = ("control", "dataclasses")


def user_stacklevel() -> int:
    """``warnings.warn``'s stacklevel, in the function that calls this, of the first frame
    outside control (the user's call, however deep control's own calls run; as
    ``gpmsa.errors.user_stacklevel`` for gpmsa) and outside ``dataclasses`` (whose ``replace``
    makes a settings class anew: its ``__post_init__``'s warnings point at the line that
    called ``replace``)."""
    frame, level = sys._getframe(1), 1
    while frame is not None and frame.f_globals.get("__name__", "").split(".")[0] in _OWN:
        frame, level = frame.f_back, level + 1
    return level


class ControlError(ValueError):
    """Invalid input to a control function (a ValueError subclass)."""


class EmulatorMismatchError(ControlError):
    """The emulator was made for another vehicle, feature or domain than the loop it serves."""


class ControlWarning(UserWarning):
    """A setting that works but is probably not what the user meant (e.g. mismatched noise)."""


class BagError(ControlError):
    """A robot recording that cannot be replayed: a missing or mistyped topic, no messages, an
    IMU slower than the emulator's rate (the message names the topic or the setting)."""


class MissingExtraError(ControlError, ImportError):
    """An optional package of the ``robot`` extra is not installed (the message says how to
    install it)."""
