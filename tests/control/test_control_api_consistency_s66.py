"""API consistency (session 66): control takes what gpmsa's calls take for the same concept
(a numpy Generator as a seed) and refuses bad input with a ControlError naming it, before
anything is drawn."""

import numpy as np
import pytest

import control
import gpmsa
import roadgen
from control import ControlError


def test_run_closed_loop_takes_a_numpy_generator_as_gpmsas_calls_do(emulator_a, likelihood_a):
    track = roadgen.track([(3, 300), (3, 500)], seed=3)
    drawn = control.run_closed_loop(
        track, emulator_a, seed=np.random.default_rng(7), likelihood=likelihood_a
    )
    seed = drawn.settings["seed"]
    assert type(seed) is int and seed == np.random.default_rng(7).integers(2**63)
    again = control.run_closed_loop(track, emulator_a, seed=seed, likelihood=likelihood_a)
    np.testing.assert_array_equal(drawn.sample_accel, again.sample_accel)  # repeated
    with pytest.raises(ControlError, match="seed must be None or an integer >= 0, got 3.0"):
        control.run_closed_loop(track, emulator_a, seed=3.0)


@pytest.mark.parametrize("make", [
    lambda: control.ChangePointFilter(np.linspace(100.0, 1000.0, 40)),
    lambda: control.GDTracker((100.0, 1000.0)),
])  # fmt: skip
def test_a_filters_posterior_names_a_bad_name_and_refuses_too_many_draws_up_front(make):
    filt = make()
    for bad in (["GD"], 3, None, ""):  # a list raised TypeError, 3 a GPMSAError on info['names']
        with pytest.raises(ControlError, match=r"name must be the parameter's name \(a non-empty "
                           r"str\), got " + repr(bad).replace("[", r"\[")):  # fmt: skip
            filt.posterior(bad)
    with pytest.raises(gpmsa.ResourceLimitError, match=r"posterior\(n_draws=1000000000000\)"):
        filt.posterior(n_draws=10**12)  # numpy's MemoryError when samples were first read
    post = filt.posterior("gd", n_draws=5)
    assert post.names == ("gd",) and post.samples["gd"].shape == (5,)
