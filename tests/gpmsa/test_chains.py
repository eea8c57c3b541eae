"""Several chains: the same draws wherever they run, convergence checked, failures reported."""

import dataclasses
import os
import warnings
from concurrent.futures import Future, ThreadPoolExecutor

import numpy as np
import pytest

import gpmsa
from gpmsa import backends
from gpmsa.fitting.fit import element_names
from gpmsa.mcmc import parallel, starts
from gpmsa.mcmc.sampler import require_finite
from tests._extras import PYRO


@pytest.fixture(scope="module")
def multi():
    from _backend_cases import multi_data

    return multi_data()


@pytest.fixture(scope="module")
def problem(multi):
    return gpmsa.prepare(multi[0]).problem


SHORT = {"n_iter": 60, "tune_rounds": 2, "tune_levels": 5}


def _same(a: gpmsa.Chains, b: gpmsa.Chains) -> None:
    for name, val in a.draws.items():
        np.testing.assert_array_equal(b.draws[name], val, err_msg=name)
    np.testing.assert_array_equal(b.log_post, a.log_post)


# --- the same numbers wherever the chains run ---------------------------------------------------
@pytest.fixture(scope="module")
def four_serial(problem):
    return backends.get("numpy").sample(problem, n_chains=4, seed=5, n_jobs=1, **SHORT)


def test_same_seed_same_draws_with_1_2_or_4_workers(problem, four_serial):
    numpy = backends.get("numpy")
    assert len({float(c[-1, 0, 0]) for c in four_serial.draws["betaU"]}) == 4  # chains differ
    _same(four_serial, numpy.sample(problem, n_chains=4, seed=5, n_jobs=2, **SHORT))
    with ThreadPoolExecutor(4) as ex:
        _same(four_serial, numpy.sample(problem, n_chains=4, seed=5, executor=ex, **SHORT))
    # chain c depends on (seed, c) only: the first two of four are the two of two
    two = numpy.sample(problem, n_chains=2, seed=5, n_jobs=2, **SHORT)
    for name, val in two.draws.items():
        np.testing.assert_array_equal(four_serial.draws[name][:2], val)


def test_dask_client_runs_the_chains_with_the_same_draws(problem, four_serial, dask_client):
    got = backends.get("numpy").sample(problem, n_chains=4, seed=5, executor=dask_client, **SHORT)
    _same(four_serial, got)


def test_fit_and_calibrate_same_draws_in_parallel(multi):
    sim, _ = multi
    kw = {"n_iter": 80, "n_chains": 2, "seed": 3, "tune": False}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)  # 80 sweeps: not converged
        one, two = (gpmsa.fit(sim, n_jobs=j, **kw) for j in (1, 2))
    for name, val in one.draws.items():
        np.testing.assert_array_equal(two.draws[name], val)
    from _backend_cases import road_data

    emu = gpmsa.Emulator.from_params(
        road_data()[0],
        {"betaU": [[0.924], [0.354]], "lamUz": [0.453], "lamWs": [164.6], "lamWOs": [837.1]},
    )
    x, y = [[1.25]], [[12.1]]
    a, b = (
        gpmsa.calibrate(emu, x, y, n_samples=3000, n_chains=2, seed=1, n_jobs=j) for j in (1, 2)
    )
    np.testing.assert_array_equal(a.chains["GD"], b.chains["GD"])
    assert not np.array_equal(a.chains["GD"][0], a.chains["GD"][1])


# --- convergence is checked --------------------------------------------------------------------
def test_short_chains_warn_naming_parameters_and_the_record_is_kept(multi, tmp_path):
    sim, _ = multi
    with pytest.warns(gpmsa.ConvergenceWarning, match=r"over 3 chains x 32 draws") as rec:
        emu = gpmsa.fit(sim, n_iter=40, n_chains=3, seed=2, tune=False, n_jobs=1)
    conv = emu.convergence
    assert conv["n_chains"] == 3 and conv["n_draws"] == 32 and not conv["converged"]
    assert set(conv["rhat"]) == set(conv["ess"]) == {"betaU", "lamUz", "lamWs", "lamWOs"}
    assert len(conv["rhat"]["betaU"]) == 4  # (p + q) x p_u = 2 x 2 elements
    message = str(rec[0].message)
    for element, why in conv["flagged"].items():  # every flagged element is named with its figure
        named = element_names(sim.x_names, sim.t_names, 2).get(element)  # betaU's input
        assert f"{element}{'' if named is None else f' ({named})'}: {why}" in message
        r = conv["rhat"][element.split("[")[0]]
        assert max(r) > 1.01 or min(conv["ess"][element.split("[")[0]]) < 100
    # the record goes into the file and comes back; gpmsa info shows it
    path = emu.save(tmp_path / "short.gpmsa")
    assert gpmsa.load(path).convergence == conv
    from gpmsa.cli.main import main

    assert main(["info", str(path)]) == 0


def test_an_infinite_r_hat_is_the_worst_element_not_left_out():
    """Chains stuck at different values have R-hat inf: the record named a milder element as
    the worst (max R-hat 2.5 of b while a[1] was inf)."""
    from gpmsa.mcmc.diagnostics import convergence

    summary = {"a": {"rhat": [1.2, float("inf")], "ess": [50.0, 3.0]},
               "b": {"rhat": [2.5], "ess": [10.0]}}  # fmt: skip
    rec = convergence(summary, {"a": (2,), "b": ()}, n_chains=2, n_draws=100)
    assert rec["max_rhat"] == ["a[1]", None] and rec["min_ess"] == ["a[1]", 3.0]
    assert rec["flagged"]["a[1]"] == "R-hat inf, ESS 3" and not rec["converged"]
    none = convergence({"c": {"rhat": [None], "ess": [None]}}, {"c": ()}, 2, 100)
    assert none["max_rhat"] == ["", None] and "constant" in none["flagged"]["c"]
    # gpmsa info: the file's JSON holds inf as null; an element with it is an infinite R-hat
    from gpmsa.cli.info import _convergence_line

    line = _convergence_line(rec)
    assert "max R-hat inf (a[1]), min bulk ESS 3 (a[1]); NOT converged" in line, line
    assert "R-hat and ESS undefined (constant draws)" in _convergence_line(none)


def test_the_convergence_warning_names_the_argument_that_lengthens_the_chains():
    from _calib_cases import two_param_emulator

    with pytest.warns(gpmsa.ConvergenceWarning, match=r"Run longer chains \(n_samples\)"):
        gpmsa.calibrate(
            two_param_emulator(), x_obs=[[0.5]], y_obs=[[0.7]], n_chains=2, n_samples=20,
            n_burn=5, seed=0,
        )  # fmt: skip


def test_info_shows_the_verdict(multi, tmp_path, capsys):
    from gpmsa.cli.main import main

    sim, _ = multi
    with pytest.warns(gpmsa.ConvergenceWarning):
        emu = gpmsa.fit(sim, n_iter=40, n_chains=2, seed=2, tune=False, n_jobs=1)
    path = emu.save(tmp_path / "a.gpmsa")
    capsys.readouterr()
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    first = next(iter(emu.convergence["flagged"]))
    assert "convergence:     2 chains x 32 draws" in out and "NOT converged" in out
    assert first in out and "R-hat [" in out


def test_converged_chains_do_not_warn(multi):
    from _backend_cases import road_data

    emu = gpmsa.Emulator.from_params(
        road_data()[0],
        {"betaU": [[0.924], [0.354]], "lamUz": [0.453], "lamWs": [164.6], "lamWOs": [837.1]},
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error", gpmsa.ConvergenceWarning)
        post = gpmsa.calibrate(emu, [[1.25]], [[12.1]], n_samples=8000, n_chains=4, seed=3)
    conv = post.info["convergence"]
    assert conv["converged"] and conv["max_rhat"][1] <= 1.01 and conv["min_ess"][1] >= 100
    assert set(post.info["diagnostics"]) == {"GD", "lamOs"}
    assert post.info["diagnostics"]["GD"]["rhat"][0] == conv["rhat"]["GD"][0]


def test_one_chain_is_judged_and_older_files_have_no_record(multi):
    sim, _ = multi
    with pytest.warns(gpmsa.ConvergenceWarning, match="over 1 chain x 24 draws"):  # session 76
        emu = gpmsa.fit(sim, n_iter=30, seed=1, tune=False)
    assert emu.convergence["n_chains"] == 1 and not emu.convergence["converged"]
    for name in ("jackal_A", "jackal_B"):  # the shipped files, written before the check
        shipped = gpmsa.load(f"control/emulators/{name}.gpmsa")
        assert shipped.convergence is None and shipped.n_draws > 0


# --- bad input --------------------------------------------------------------------------------
def test_bad_chain_arguments_raise_naming_them(multi, problem):
    sim, _ = multi
    cpus = parallel.available_cpus()
    with pytest.raises(gpmsa.GPMSAError, match="n_chains must be an integer >= 1, got 0"):
        gpmsa.fit(sim, n_iter=10, n_chains=0)
    with pytest.raises(gpmsa.GPMSAError, match=f"n_jobs={cpus + 1} is more than the {cpus} CPUs"):
        gpmsa.fit(sim, n_iter=10, n_chains=cpus + 1, n_jobs=cpus + 1)
    # only the workers that would run count, and a numpy integer is an integer
    assert parallel.n_workers(cpus + 3, 1) == 1
    assert parallel.n_workers(np.int64(1), 2) == 1
    # -1 is joblib's "every CPU", as None; other values below 1 are refused
    assert parallel.n_workers(-1, 5) == parallel.n_workers(None, 5) == min(cpus, 5)
    assert parallel.n_workers(np.int64(-1), 1) == 1
    for bad in (0, -2, True, 1.0):
        with pytest.raises(gpmsa.GPMSAError, match="n_jobs must be None or -1"):
            parallel.n_workers(bad, 2)
    with pytest.raises(gpmsa.GPMSAError, match="n_jobs must be None or -1"):
        gpmsa.fit(sim, n_iter=10, n_chains=2, n_jobs=0)
    with ThreadPoolExecutor(1) as ex:
        with pytest.raises(gpmsa.GPMSAError, match="give n_jobs or executor, not both"):
            gpmsa.fit(sim, n_iter=10, n_chains=2, n_jobs=1, executor=ex)
    with pytest.raises(gpmsa.GPMSAError, match="executor must be a concurrent.futures.Executor"):
        gpmsa.fit(sim, n_iter=10, n_chains=2, executor="cluster")
    with pytest.raises(gpmsa.GPMSAError, match="init must be one of"):
        backends.get("numpy").sample(problem, n_iter=5, init="random")


@PYRO
def test_the_torch_and_pyro_backends_refuse_a_placement_they_cannot_use(multi):
    sim, _ = multi
    with pytest.raises(gpmsa.GPMSAError, match="n_jobs=2: the pyro backend runs its chains one"):
        gpmsa.fit(sim, n_iter=10, n_chains=2, backend="pyro", n_jobs=2)
    with ThreadPoolExecutor(1) as ex:
        with pytest.raises(gpmsa.GPMSAError, match="backend 'pyro' runs its chains in one pro"):
            gpmsa.fit(sim, n_iter=10, n_chains=2, backend="pyro", executor=ex)
    with pytest.raises(gpmsa.GPMSAError, match="n_jobs=2 with chain_groups=1: the torch backend"):
        gpmsa.fit(sim, n_iter=10, n_chains=2, backend="torch", n_jobs=2)


def test_a_chain_that_produces_nan_is_named(problem):
    w = problem.w.copy()
    w[3, 0] = np.nan  # the likelihood is NaN at every parameter value
    bad = dataclasses.replace(problem, w=w)
    with pytest.raises(gpmsa.ChainError, match=r"chain 0 of 2 failed: .*log posterior of NaN"):
        backends.get("numpy").sample(bad, n_chains=2, seed=1, n_jobs=1, **SHORT)
    with pytest.raises(gpmsa.ChainError, match=r"chain [01] of 2 failed: .*log posterior of NaN"):
        backends.get("numpy").sample(bad, n_chains=2, seed=1, n_jobs=2, **SHORT)
    draws = {"a": np.zeros((3, 10)), "b": np.zeros((3, 10, 2))}
    draws["b"][1, 4, 1] = np.nan
    lp = np.zeros((3, 10))
    lp[2, 7] = np.inf
    with pytest.raises(gpmsa.ChainError, match=r"2 of 3 .*chain 1 \(from draw 4\), chain 2 \(fr"):
        require_finite(draws, lp)
    try:
        require_finite(draws, lp)
    except gpmsa.ChainError as exc:
        assert exc.chains == (1, 2)


# --- failing executors ------------------------------------------------------------------------
def _double(x, progress=False, desc=""):
    return 2 * x


def _fails_on_input(x, progress=False, desc=""):
    if x == 2:
        raise gpmsa.GPMSAError("x=2 is out of range")
    return x


def _die_once(x, marker, progress=False, desc=""):
    if x == 1 and not os.path.exists(marker):
        open(marker, "w").close()
        os._exit(3)  # the worker process dies
    return 2 * x


class RefusingExecutor(ThreadPoolExecutor):
    """submit raises, as a shut-down or disconnected executor does."""

    def submit(self, fn, /, *args, **kwargs):
        raise RuntimeError("executor refuses new tasks")


class LosesFirstTask(ThreadPoolExecutor):
    """The first task's future fails as if its worker died; later ones run."""

    def __init__(self):
        super().__init__(2)
        self.lost = 0

    def submit(self, fn, /, *args, **kwargs):
        if not self.lost:
            self.lost += 1
            fut = Future()
            fut.set_exception(ConnectionError("worker tcp://10.0.0.7 died"))
            return fut
        return super().submit(fn, *args, **kwargs)


def test_an_executor_that_fails_a_task_is_retried_then_reported():
    tasks = [{"x": i} for i in range(3)]
    with LosesFirstTask() as ex:
        with pytest.warns(RuntimeWarning, match=r"chain 0 of 3 failed \(ConnectionError: worker"):
            assert parallel.run_chains(_double, tasks, executor=ex) == [0, 2, 4]
    with RefusingExecutor(1) as ex:
        with pytest.warns(RuntimeWarning, match="running it again"):
            with pytest.raises(
                gpmsa.ChainError,
                match=r"chain 0 of 3 failed after 2 attempts: RuntimeError: executor refuses",
            ):
                parallel.run_chains(_double, tasks, executor=ex)
    shut = ThreadPoolExecutor(1)
    shut.shutdown()
    with warnings.catch_warnings():  # a shut-down executor: one clear error, no retry
        warnings.simplefilter("error", RuntimeWarning)
        why = r"the executor refused chain 0 of 3: .*shutdown"
        with pytest.raises(gpmsa.GPMSAError, match=why):
            parallel.run_chains(_double, tasks, executor=shut)
    with LosesFirstTask() as ex, pytest.raises(gpmsa.ChainError, match="chain 0 of 3 failed"):
        parallel.run_chains(_double, tasks, executor=ex, retries=0)
    # a chain whose input is wrong fails the same everywhere: no retry
    with ThreadPoolExecutor(2) as ex, warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        with pytest.raises(gpmsa.ChainError, match="chain 2 of 3 failed: GPMSAError: x=2 is out"):
            parallel.run_chains(_fails_on_input, tasks, executor=ex)


class ReturnsOther(ThreadPoolExecutor):
    """Returns something else than the task's result: ``garbage`` itself, or (None) the result
    of the task run with other arguments (``changes``)."""

    def __init__(self, garbage=None, **changes):
        super().__init__(1)
        self.garbage, self.changes = garbage, changes

    def submit(self, fn, /, *args, **kwargs):
        if self.garbage is not None:
            fut = Future()
            fut.set_result(self.garbage)
            return fut
        return super().submit(fn, *args, **{**kwargs, **self.changes})


@pytest.mark.parametrize("executor", [
    ReturnsOther(("garbage",)), ReturnsOther(0.0), ReturnsOther(n_iter=20)
], ids=["tuple", "float", "shorter-chain"])  # fmt: skip
def test_an_executor_that_returns_wrong_results_is_a_chain_error(problem, executor):
    """Not a TypeError deep in the stacking, nor (other draws than asked) a silent success."""
    why = r"chain 0 of 2 returned a \w+ that is not its draws \(60 sweeps\); an executor must"
    with executor, pytest.raises(gpmsa.ChainError, match=why) as exc:
        backends.get("numpy").sample(problem, n_chains=2, seed=5, executor=executor, **SHORT)
    assert exc.value.chains == (0,)


@pytest.mark.parametrize("executor", [
    ReturnsOther(("garbage",)), ReturnsOther(n_samples=20)
], ids=["tuple", "shorter-chain"])  # fmt: skip
def test_calibrate_and_a_study_check_what_an_executor_returns(executor):
    """The fast calibration and the study sampler run their chains through run_chains too: a
    wrong result is a ChainError there as well (was an AttributeError or KeyError while the
    draws were stacked, or another chain length silently)."""
    from _study_cases import emulator, observations

    emu = emulator()
    x, y = observations(0.4, 6, 0.05, np.random.default_rng(3))
    run = {"n_samples": 40, "n_burn": 10, "n_chains": 2, "seed": 1, "tune_rounds": 2,
           "tune_levels": 5, "executor": executor}  # fmt: skip
    with executor:
        with pytest.raises(gpmsa.ChainError, match=r"chain 0 of 2 returned a \w+ that is not "
                           r"its draws \(40 samples\)"):  # fmt: skip
            gpmsa.calibrate(emu, x, y, **run)
        if executor.changes:  # the study's task takes n_iter: another length through that name
            executor.changes = {"n_iter": 20}
        with pytest.raises(gpmsa.ChainError, match=r"chain 0 of 2 returned a \w+ that is not "
                           r"its draws \(40 sweeps\)"):  # fmt: skip
            gpmsa.calibrate_study([emu, emu], [x[::2], x[1::2]], [y[::2], y[1::2]],
                                  shared=["t"], **run)  # fmt: skip


@pytest.mark.skipif(parallel.available_cpus() < 2, reason="needs two CPUs for a pool")
def test_a_worker_that_dies_is_replaced_and_its_chain_rerun(tmp_path):
    marker = str(tmp_path / "died")
    tasks = [{"x": i, "marker": marker} for i in range(4)]
    # chain 1's worker dies; the broken pool fails the futures still running, and which of
    # them the warning names first depends on timing (on a loaded machine chain 3's)
    with pytest.warns(RuntimeWarning, match="chain [1-3] of 4 failed .*BrokenProcessPool"):
        got = parallel.run_chains(_die_once, tasks, n_jobs=2)
    assert got == [0, 2, 4, 6] and os.path.exists(marker)


# --- starting values --------------------------------------------------------------------------
def test_dispersed_starts_are_inside_the_prior_and_differ(problem):
    for how in ("jitter", "prior"):
        seen = []
        for seq in np.random.SeedSequence(1).spawn(8):
            start = starts.draw_start(problem, how, starts.start_generator(seq))
            for name, val in start.items():
                assert val.shape == problem.init[name].shape
                assert np.isfinite(problem.priors.log_prior(name, val)), (how, name, val)
            seen.append(start["lamWs"][0])
        assert len(set(seen)) == 8
    assert starts.check_init("auto", 1) == "gpmsa" and starts.check_init("auto", 4) == "jitter"
    chains = backends.get("numpy").sample(problem, n_chains=3, seed=4, **SHORT)
    first = chains.info["starts"]["lamUz"][:, 0]
    assert len(set(first.tolist())) == 3


def test_progress_with_parallel_chains_is_one_bar_over_the_chains(problem, capsys):
    chains = backends.get("numpy").sample(
        problem, n_chains=2, seed=5, n_jobs=2, progress=True, **SHORT
    )
    err = capsys.readouterr().err
    assert "chain: 100%" in err and "2/2" in err and chains.n_chains == 2


def _road_emulator():
    from _backend_cases import road_data

    return gpmsa.Emulator.from_params(
        road_data()[0],
        {"betaU": [[0.924], [0.354]], "lamUz": [0.453], "lamWs": [164.6], "lamWOs": [837.1]},
    )


def test_calibrate_refuses_bad_placement():
    emu = _road_emulator()
    x, y = [[1.25]], [[12.1]]
    cpus = parallel.available_cpus()
    more = cpus + 1  # chains and workers beyond the CPUs
    with pytest.raises(gpmsa.GPMSAError, match=f"n_jobs={more} is more than"):
        gpmsa.calibrate(emu, x, y, n_chains=more, n_jobs=more)
    with pytest.raises(gpmsa.GPMSAError, match=f"n_jobs={more} is more than"):
        gpmsa.calibrate(emu, x, y, n_chains=more, n_jobs=more, log_prior=lambda t: 0.0 * t)
    with ThreadPoolExecutor(1) as ex, pytest.raises(gpmsa.GPMSAError, match="cannot go to exec"):
        gpmsa.calibrate(emu, x, y, n_chains=2, executor=ex, log_prior=lambda t: 0.0 * t)


@PYRO
def test_calibrate_on_pyro_refuses_n_jobs():
    with pytest.raises(gpmsa.GPMSAError, match="n_jobs=2: the pyro backend runs its chains one"):
        gpmsa.calibrate(_road_emulator(), [[1.25]], [[12.1]], n_chains=2, backend="pyro", n_jobs=2)
