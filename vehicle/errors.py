"""Exceptions raised by vehicle."""


class VehicleError(ValueError):
    """Invalid input to a vehicle function (a ValueError subclass)."""


class SimulationDivergedError(RuntimeError):
    """A simulation left its numerically valid range (NaN/inf or runaway states)."""


class CampaignFileError(VehicleError):
    """A campaign file (or a cached run) is missing, damaged or of an unknown format."""


class SolverStepWarning(UserWarning):
    """The solver's fixed step is too coarse for the model's stiffest mode (results biased)."""
