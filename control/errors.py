"""Exceptions and warnings raised by control."""

# control's package sets gpmsa.errors.WRAPPER_MARK: ``warnings.warn``'s stacklevel of the first
# frame outside control, gpmsa and ``dataclasses``, for control's modules
from gpmsa.errors import user_stacklevel as user_stacklevel


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
