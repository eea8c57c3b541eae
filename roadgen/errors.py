"""Exceptions raised by roadgen."""


class RoadgenError(ValueError):
    """Invalid input to a roadgen function (a ValueError subclass)."""
