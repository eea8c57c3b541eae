"""Backend registry, missing packages, lazy imports, seeds and bad options."""

import subprocess
import sys

import numpy as np
import pytest

import gpmsa
from gpmsa import backends
from gpmsa.errors import BackendUnavailableError, GPMSAError
from gpmsa.mcmc import diagnostics
from tests._extras import PYRO, TORCH


def _road_calibration_problem():
    from _backend_cases import road_problem

    prob = road_problem(True).problem
    fixed = {"betaU": [[0.92], [0.35]], "lamUz": [0.45], "lamWs": [165.0], "lamWOs": [837.0]}
    return prob.with_init(fixed, fixed=frozenset(fixed))


@PYRO
def test_available_lists_all_three_backends():
    assert set(backends.available()) == {"numpy", "torch", "pyro"}


def test_unknown_backend_lists_the_available_ones():
    with pytest.raises(GPMSAError, match=r"unknown backend 'jax'.*numpy.*torch.*pyro"):
        backends.get("jax")
    from _backend_cases import road_data

    sim, _ = road_data()
    with pytest.raises(GPMSAError, match="unknown backend 'stan'"):
        gpmsa.fit(sim, n_iter=10, backend="stan")


@pytest.mark.parametrize(("name", "package"), [("torch", "torch"), ("pyro", "pyro")])
def test_missing_packages_name_the_extra(monkeypatch, name, package):
    for mod in list(sys.modules):
        if mod.startswith("gpmsa.backends.") and mod != "gpmsa.backends.numpy_backend":
            monkeypatch.delitem(sys.modules, mod)
    monkeypatch.setitem(sys.modules, package, None)  # makes `import <package>` fail
    with pytest.raises(BackendUnavailableError, match=r'pip install "terrain-gpmsa\[torch\]"'):
        backends.get(name)
    assert name not in backends.available()
    assert "numpy" in backends.available()


def test_importing_gpmsa_never_imports_torch():
    code = (
        "import sys, gpmsa, gpmsa.backends, gpmsa.fitting.fit, gpmsa.calibration.calibrate;"
        "gpmsa.backends.get('numpy');"
        "assert 'torch' not in sys.modules and 'pyro' not in sys.modules, 'torch imported'"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


@TORCH
def test_torch_bad_options_raise():
    tb = backends.get("torch")
    prob = _road_calibration_problem()
    with pytest.raises(GPMSAError, match="dtype must be 'float64' or 'float32', got 'float16'"):
        tb.sample(prob, n_iter=2, dtype="float16")
    with pytest.raises(GPMSAError, match="n_chains must be an integer >= 1, got 0"):
        tb.sample(prob, n_iter=2, n_chains=0)
    with pytest.raises(GPMSAError, match=r"tune_rounds must be an integer in \[1, 1000000\]"):
        tb.sample(prob, n_iter=2, tune_rounds=0)
    with pytest.raises(GPMSAError, match=r"step_widths\['lamOs'\] must be finite and > 0"):
        tb.sample(prob, n_iter=2, step_widths={"lamOs": 0.0})
    with pytest.raises(GPMSAError, match="seed must be None or an integer"):
        tb.sample(prob, n_iter=2, seed="abc")
    for name in backends.available():  # numpy refuses a negative seed deep in SeedSequence
        with pytest.raises(GPMSAError, match=r"seed=-1 is out of range"):
            backends.get(name).sample(prob, n_iter=2, seed=-1)
    import torch

    if not torch.cuda.is_available():
        with pytest.raises(GPMSAError, match="device='cuda'.*no CUDA device"):
            tb.sample(prob, n_iter=2, device="cuda")


@PYRO
def test_pyro_rejects_step_widths():
    pb = backends.get("pyro")
    with pytest.raises(GPMSAError, match="takes no step_widths"):
        pb.sample(_road_calibration_problem(), n_iter=2, step_widths={"theta": 0.1})


@TORCH
def test_torch_same_seed_same_numbers_and_fixed_params_stay():
    tb = backends.get("torch")
    prob = _road_calibration_problem()
    a = tb.sample(prob, n_iter=30, n_chains=3, seed=11, tune_rounds=1, tune_levels=4)
    b = tb.sample(prob, n_iter=30, n_chains=3, seed=11, tune_rounds=1, tune_levels=4)
    c = tb.sample(prob, n_iter=30, n_chains=3, seed=12, tune_rounds=1, tune_levels=4)
    np.testing.assert_array_equal(a.draws["theta"], b.draws["theta"])
    assert not np.array_equal(a.draws["theta"], c.draws["theta"])
    assert a.draws["theta"].shape == (3, 30, 1) and a.log_post.shape == (3, 30)
    np.testing.assert_array_equal(a.draws["lamUz"], np.full((3, 30, 1), 0.45))
    assert np.all(np.isnan(a.step_widths["lamUz"])) and np.all(a.step_widths["theta"] > 0)
    # draws differ between chains (independent random numbers per chain)
    assert not np.array_equal(a.draws["theta"][0], a.draws["theta"][1])


@PYRO
def test_pyro_same_seed_same_numbers():
    pb = backends.get("pyro")
    prob = _road_calibration_problem()
    kw = {"n_iter": 15, "n_warmup": 15, "jit": False}
    a = pb.sample(prob, seed=3, **kw)
    b = pb.sample(prob, seed=3, **kw)
    np.testing.assert_array_equal(a.draws["theta"], b.draws["theta"])
    np.testing.assert_array_equal(a.draws["lamWs"], np.full((1, 15, 1), 165.0))
    assert np.all(np.isfinite(a.log_post))


def test_calibrator_checks_its_backend_at_construction():
    """Calibrator(backend=...) validates the name, and the method it goes with, at construction,
    whether the backend's packages are installed or not."""
    from _calib_cases import road_emulator

    emu = road_emulator()
    with pytest.raises(GPMSAError, match="unknown backend 'jax'"):
        gpmsa.Calibrator(emu, backend="jax")
    with pytest.raises(GPMSAError, match="unknown backend 'jax'"):
        gpmsa.Calibrator(emu, method="grid", backend="jax")
    for name in ("torch", "pyro"):  # before (without torch): BackendUnavailableError
        with pytest.raises(GPMSAError, match="method='grid' runs on numpy"):
            gpmsa.Calibrator(emu, method="grid", backend=name)


@TORCH
@pytest.mark.filterwarnings("ignore::gpmsa.ConvergenceWarning")  # 8 x 500 kept draws: R-hat ~1.02
def test_calibrator_takes_a_backend():
    """Calibrator(backend=...) runs its MCMC path on that backend; its posterior agrees with the
    exact numpy grid within Monte-Carlo error."""
    from _calib_cases import road_emulator, road_obs

    emu = road_emulator()
    cal = gpmsa.Calibrator(
        emu, backend="torch", seed=5, mcmc_options={"n_chains": 8, "n_samples": 1500}
    )
    assert cal.method == "mcmc" and cal.backend == "torch"
    x, y = road_obs()
    post = cal.update(x, y)
    exact = gpmsa.Calibrator(emu).update(x, y)
    draws = post.samples["GD"].reshape(8, -1)
    ess = diagnostics.ess(draws)  # kept draws are pooled chain after chain
    tol = 4.0 * exact.sd("GD") / np.sqrt(ess)
    assert post.mean("GD") == pytest.approx(exact.mean("GD"), abs=tol)


def test_numpy_scalar_options_are_recorded_as_plain_values(tmp_path):
    """An option given as a numpy scalar (np.int64 from an array of settings) changes the draws
    as the plain value does: the record keeps it, not drops it as an unknown object."""
    from _backend_cases import multi_data

    given = {"tune_rounds": np.int64(1), "tune_levels": np.int64(3), "ridge_moves": np.int64(0),
             "init": np.str_("prior")}  # fmt: skip
    assert backends.recorded_options(given) == {"init": "prior", "ridge_moves": 0,
                                                "tune_levels": 3,
                                                "tune_rounds": 1}  # fmt: skip
    assert type(backends.recorded_options(given)["tune_rounds"]) is int
    assert backends.recorded_options({"jit": np.bool_(False)}) == {"jit": False}
    emu = gpmsa.fit(multi_data()[0], n_iter=10, seed=1, **given)
    assert emu.settings["backend_options"] == backends.recorded_options(given)
    path = emu.save(tmp_path / "np.gpmsa")
    assert gpmsa.load(path).settings["backend_options"] == emu.settings["backend_options"]
