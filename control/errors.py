"""Exceptions raised by control."""


class ControlError(ValueError):
    """Invalid input to a control function (a ValueError subclass)."""
