"""Exceptions and warnings raised by control."""


class ControlError(ValueError):
    """Invalid input to a control function (a ValueError subclass)."""


class EmulatorMismatchError(ControlError):
    """The emulator was made for another vehicle, feature or domain than the loop it serves."""


class ControlWarning(UserWarning):
    """A setting that works but is probably not what the user meant (e.g. mismatched noise)."""
