"""Exceptions raised by gpmsa."""


class GPMSAError(ValueError):
    """Invalid input to a gpmsa function (a ValueError subclass)."""


class EmulatorFileError(GPMSAError):
    """An emulator file is damaged, foreign, of a newer schema, or unsafe to read."""


class BackendUnavailableError(ImportError):
    """A backend's optional packages are not installed; the message names the extra to install."""
