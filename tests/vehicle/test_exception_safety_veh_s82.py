"""An exception inside `vehicle.Simulation.advance` once the solver moved on (session 82): the
simulation refuses to go on, as after an interrupt inside the solver; one refused for its
arguments changes nothing."""

import numpy as np
import pytest

import roadgen
import vehicle
from vehicle import simulation

TRACK = roadgen.track([(8, 300)], seed=3)


def _samples(s: vehicle.simulation.Samples) -> tuple:
    return s.t.tolist(), s.position.tolist(), s.accel_front.tolist()


@pytest.mark.parametrize("error", [KeyboardInterrupt, RuntimeError])
def test_an_exception_after_the_solver_moved_on_stops_the_simulation(monkeypatch, error):
    """Before: the time had moved 0.2 -> 0.5 s and the noise stream drawn part of the lost
    samples; the next advance went on from there (its first sample at 0.508 s, acceleration
    0.767 against the twin's 0.412 at 0.208 s) without a word."""
    sim = vehicle.Simulation(vehicle.Jackal(), TRACK, seed=1)
    sim.advance(0.2, 1.0)

    def fail(*args, **kwargs):
        raise error("raised while the samples were made")

    with monkeypatch.context() as patch:
        patch.setattr(simulation, "contact_flags", fail)
        with pytest.raises(error):
            sim.advance(0.3, 1.2)
    with pytest.raises(vehicle.SimulationDivergedError, match=f"interrupted \\({error.__name__}"):
        sim.advance(0.3, 1.2)


@pytest.mark.parametrize(
    "bad", [{"dt": -1.0}, {"speed": np.nan}, {"speed": -3.0}, {"dt": "a"}, {"speed": 99.0}]
)
def test_a_refused_advance_changes_nothing(bad):
    sim, twin = (vehicle.Simulation(vehicle.Jackal(), TRACK, seed=1) for _ in range(2))
    sim.advance(0.2, 1.0), twin.advance(0.2, 1.0)
    with pytest.raises(vehicle.VehicleError):
        sim.advance(**{"dt": 0.2, "speed": 1.0, **bad})
    assert _samples(sim.advance(0.3, 1.2)) == _samples(twin.advance(0.3, 1.2))
