"""Ctrl-C while the Exudyn solver runs stops the drive as a KeyboardInterrupt.

The interrupt lands, almost always, in a road-force user function that the solver calls from
C++; Exudyn reports it as a RuntimeError ("Error in Python USER FUNCTION ...: KeyboardInterrupt
..."), which `SimulationDivergedError` took in: ``examples/closed_loop.py`` then exited with
status 2 and "the vehicle left the road ...; lower the track's GD", and a campaign recorded
the run as failed and drove on to the next one instead of stopping."""

import pytest

import roadgen
import vehicle
from vehicle import campaign, exudyn_models


class _InterruptedTable:
    """The road table of a user function, read normally until the ``after``-th read, which
    raises ``error`` (KeyboardInterrupt: as Ctrl-C does inside the function)."""

    def __init__(self, data: tuple, after: int, error: type[BaseException]) -> None:
        self._data, self._left, self._error = data, after, error

    def _read(self):
        self._left -= 1
        if self._left < 0:
            raise self._error("raised inside the user function")
        return self._data

    def __iter__(self):  # the Jackal's road_force unpacks it
        return iter(self._read())

    def __getitem__(self, key):  # the half car's tyres index it
        return self._read()[key]


def _raise_in_user_function(monkeypatch, error: type[BaseException]) -> None:
    update = exudyn_models._TyreInput.update

    def update_then_raise(self, *args):
        update(self, *args)
        self.data = _InterruptedTable(self.data, after=40, error=error)

    monkeypatch.setattr(exudyn_models._TyreInput, "update", update_then_raise)


@pytest.fixture
def interrupted(monkeypatch):
    _raise_in_user_function(monkeypatch, KeyboardInterrupt)


@pytest.mark.parametrize("model", [vehicle.Jackal(), vehicle.HalfCar()], ids=["jackal", "halfcar"])
def test_an_interrupt_inside_the_solver_reaches_the_caller(model, interrupted):
    sim = vehicle.Simulation(model, roadgen.track([(8, 300)], seed=3))
    with pytest.raises(KeyboardInterrupt):
        sim.advance(0.2, 1.0)
    # the solver stopped part way: its state is no longer valid, as after a divergence
    with pytest.raises(vehicle.SimulationDivergedError, match="interrupted"):
        sim.advance(0.2, 1.0)


def test_an_interrupted_campaign_run_is_no_failed_run(interrupted):
    spec = campaign.RunSpec(
        model=vehicle.Jackal(), v=1.0, gd=300.0, seed=1, road_length_m=6.0, dx_m=0.006,
        rate_hz=120.0, noise_std=0.0, window=120, lead_in_m=0.5, keep_samples=0,
        substeps=campaign.SUBSTEPS, band=None,
    )  # fmt: skip
    with pytest.raises(KeyboardInterrupt):
        campaign.run_one(spec)


def test_another_error_inside_the_solver_is_still_a_divergence(monkeypatch):
    _raise_in_user_function(monkeypatch, ValueError)
    sim = vehicle.Simulation(vehicle.Jackal(), roadgen.track([(8, 300)], seed=3))
    with pytest.raises(vehicle.SimulationDivergedError, match="ValueError: raised inside"):
        sim.advance(0.2, 1.0)
