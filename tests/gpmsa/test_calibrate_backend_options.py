"""``calibrate`` passes backend options (torch's device and dtype) to the backend's sampler, and
refuses options the sampler does not take, its own arguments, and options with the fast path."""

import numpy as np
import pytest
from _calib_cases import road_emulator, road_obs

import gpmsa

pytest.importorskip("torch")

SHORT = {"n_samples": 60, "n_burn": 10, "tune_rounds": 2, "tune_levels": 5, "seed": 3}


def test_torch_options_reach_the_sampler():
    x, y = road_obs()
    single = gpmsa.calibrate(road_emulator(), x, y, backend="torch", dtype="float32", **SHORT)
    double = gpmsa.calibrate(road_emulator(), x, y, backend="torch", dtype="float64", **SHORT)
    assert single.info["backend_options"] == {"dtype": "float32"}
    assert single.samples["GD"].shape == (50,) and np.all(np.isfinite(single.samples["GD"]))
    assert not np.array_equal(single.samples["GD"], double.samples["GD"])  # float32 arithmetic
    with pytest.raises(gpmsa.GPMSAError, match="torch sees no CUDA device|cuda:0 to cuda:"):
        gpmsa.calibrate(road_emulator(), x, y, backend="torch", device="cuda:64", **SHORT)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"backend": "torch", "dtyp": "float32"},
         r"calibrate: unknown option\(s\) \['dtyp'\] for the 'torch' backend; it takes "
         r"\[.*'dtype'"),
        ({"backend": "numpy", "fast": False, "n_iter": 9},
         r"calibrate: \['n_iter'\] are calibrate's own arguments"),
        # gpmsa.fit's n_iter on the fast path: the advice was "pass fast=False", which then
        # refused it as "calibrate's own argument" that calibrate does not have
        ({"backend": "numpy", "n_iter": 9},
         r"calibrate: \['n_iter'\] are calibrate's own arguments, not backend options; "
         r"calibrate sets n_iter from its argument n_samples"),
        ({"backend": "numpy", "ridge_moves": 0},
         r"options \['ridge_moves'\] go to a backend's sampler, .* pass fast=False"),
    ],
)  # fmt: skip
def test_options_the_sampler_would_not_take_are_refused(kwargs, match):
    x, y = road_obs()
    with pytest.raises(gpmsa.GPMSAError, match=match):
        gpmsa.calibrate(road_emulator(), x, y, **{**SHORT, **kwargs})


def test_pyro_with_a_constraint_checks_its_start():
    """(The constraint's chains run in this process: calibrate asked pyro for n_jobs=1, which
    it refused, naming an n_jobs the caller never gave; until session 75 pyro refused a
    constraint.) A constraint that rejects the start: numpy's error, naming theta_init=."""
    x, y = road_obs()
    short = {k: v for k, v in SHORT.items() if not k.startswith("tune_")}
    with pytest.raises(gpmsa.GPMSAError, match="the theta constraint rejects the initial value "
                       r"GD=.*; pass theta_init="):  # fmt: skip
        gpmsa.calibrate(
            road_emulator(), x, y, backend="pyro", constraint=lambda t: t[0] < -1e9, **short
        )


def test_pyro_takes_n_jobs_1_as_the_chains_run_there():
    """n_jobs=1 asks for what pyro does (chains one after another here): accepted, as torch
    accepts it; its NUTS options pass through calibrate."""
    x, y = road_obs()
    post = gpmsa.calibrate(
        road_emulator(), x, y, backend="pyro", n_jobs=1, n_samples=8, n_burn=2, seed=1,
        n_warmup=10, jit=False,
    )  # fmt: skip
    assert post.samples["GD"].shape == (6,) and np.all(np.isfinite(post.samples["GD"]))
    assert post.info["backend_options"] == {"jit": False, "n_warmup": 10}
