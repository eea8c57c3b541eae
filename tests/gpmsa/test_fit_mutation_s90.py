"""Mutation testing of gpmsa.fitting.fit (session 90): the refusals of ``fit`` word for word, its
defaults by value (recorded in the emulator's settings, or in the figure its memory check is
asked about before any sweep), its limits at their edges, and the helpers (thinning, point
estimate, advice, memory figures) against hand-computed values, on tiny fits of 5 runs and tens
of sweeps."""

from __future__ import annotations

import math
import re
import warnings

import numpy as np
import pytest
from _fit_cases import five_run_data

import gpmsa
from gpmsa.errors import GPMSAError
from gpmsa.fitting import fit as fit_module


class _Checked(Exception):
    """Carries what fit's memory check was asked about (bytes, what), stopping the fit there."""


def _full(message: str) -> str:
    return "^" + re.escape(message) + "$"


@pytest.fixture(scope="module")
def data() -> gpmsa.SimData:
    return five_run_data()


def _fit(data, obs=None, **kw) -> gpmsa.Emulator:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # short chains: convergence warnings
        return gpmsa.fit(data, obs, **({"n_iter": 20, "tune": False, "seed": 0} | kw))


def _checked(monkeypatch, data, **kw) -> tuple[float, str]:
    """(bytes, what) that fit's memory check is asked about; no sweep runs."""

    def record(nbytes, what):
        raise _Checked(nbytes, what)

    monkeypatch.setattr(fit_module, "check_memory", record)
    with pytest.raises(_Checked) as checked:
        gpmsa.fit(data, **kw)
    return checked.value.args


# --- defaults, by value --------------------------------------------------------------------


def test_the_default_n_keep_is_n_keep_1000_draws(monkeypatch, data):
    assert fit_module.N_KEEP == 1000
    monkeypatch.setattr(fit_module, "N_KEEP", 5)  # the default read at the call: 16 kept sweeps
    emu = _fit(data)  # thinned by 4 to 4 draws (by 3: 6 > 5)
    assert (emu.n_draws, emu.settings["thin"]) == (4, 4)
    emu = _fit(data, n_keep=6)
    assert (emu.n_draws, emu.settings["thin"]) == (6, 3)


def test_the_default_fit_is_30000_sweeps_of_one_chain(monkeypatch, data):
    _, what = _checked(monkeypatch, data)
    assert what.startswith("fit(n_iter=30000, n_chains=1) of 5 runs x ")


def test_a_default_fit_shows_no_progress(data, capfd):
    _fit(data, seed=1)
    assert capfd.readouterr().err == ""
    _fit(data, seed=1, progress=True)  # the same fit showing it: the check could see one
    assert "chain 1/1" in capfd.readouterr().err


def test_an_unknown_backend_is_refused_before_any_work(data):
    # n_pc=-1 is refused while the problem is prepared, after the backend is looked up
    with pytest.raises(GPMSAError, match=r"^unknown backend 'nope'; registered: \("):
        gpmsa.fit(data, backend="nope", n_pc=-1)


# --- memory figures -------------------------------------------------------------------------


def test_a_planned_fit_of_one_chain_by_default():
    m, p, q, p_u, n_iter = 7, 2, 3, 2, 50
    factors = 8.0 * m * m * (p + q + 4 * p_u + 2)
    sweeps = 16.0 * 1 * n_iter * ((p + q + 2) * p_u + 1 + 1)
    assert fit_module.simulation_fit_nbytes(m, p, q, p_u, n_iter) == sweeps + factors
    assert fit_module.simulation_fit_nbytes(m, p, q, p_u, n_iter, 1) == sweeps + factors
    assert fit_module.simulation_fit_nbytes(m, p, q, p_u, n_iter, 3) == 3 * sweeps + factors


def test_the_memory_check_appends_nothing_and_counts_one_copy_by_default(monkeypatch, data):
    from gpmsa.model.problem import prepare

    problem = prepare(data, None).problem
    seen = []
    monkeypatch.setattr(
        fit_module, "check_memory", lambda nbytes, what: seen.append((nbytes, what))
    )
    fit_module._check_fit_memory(problem, 10, 2)
    elements = fit_module.parameter_elements(problem)
    p_u = problem.p_u
    factors = 8.0 * 25 * (1 + 1 + 4 * p_u + 2)
    what = f"fit(n_iter=10, n_chains=2) of 5 runs x {elements} parameter elements"
    assert seen == [(16.0 * 2 * 10 * (elements + 1) + factors, what)]


# --- advice ---------------------------------------------------------------------------------


def test_the_advice_of_an_untempered_fit():
    assert fit_module.more_advice(False, {}) == (
        "continue these: gpmsa.fit(..., init=the returned emulator)"
    )
    assert fit_module.more_advice(True, {"temperatures": None}) == (
        "append more: gpmsa.fit(..., init=the returned emulator, append=True)"
    )


def test_the_numpy_chains_of_a_callable_run_in_this_process(data):
    from concurrent.futures import ThreadPoolExecutor

    def ones(z):
        return np.ones((len(z), 1))

    with ThreadPoolExecutor(1) as pool, pytest.raises(GPMSAError, match=_full(
        "mean_basis is a callable of this process: it cannot go to executor=; leave executor= "
        "out: the chains then run here, one after another, with the draws the executor would "
        "give"
    )):  # fmt: skip
        _fit(data, mean_basis=ones, executor=pool)


# --- joint fits -----------------------------------------------------------------------------

GRID = np.arange(1, 5)
X_OBS = np.array([[0.3], [0.7]])


@pytest.fixture(scope="module")
def obs() -> gpmsa.ObsData:
    return gpmsa.ObsData(x=X_OBS, y=np.sin(GRID * (3 * X_OBS + 0.4)))


@pytest.fixture(scope="module")
def categorical() -> gpmsa.SimData:
    """6 runs of a categorical parameter t0 of levels 0, 1, 2."""
    rng = np.random.default_rng(0)
    x = rng.uniform(size=(6, 1))
    t = np.array([[0.0], [1.0], [2.0], [0.0], [1.0], [2.0]])
    return gpmsa.SimData(x=x, t=t, y=np.sin(GRID * (3 * x + t)), t_categorical=[0])


def test_a_joint_fit_without_a_discrepancy_records_none(data, obs):
    emu = _fit(data, obs)
    assert emu.settings["discrepancy"] is None
    assert not {k for k in emu.settings if k.startswith("discrepancy_")}
    emu = _fit(data, obs, discrepancy="constant")  # the record the check could miss
    assert "discrepancy_sha256" in emu.settings


def test_a_held_theta_near_its_bound_is_not_warned_at_bound(data, obs):
    top = float(data.t.max()) - 1e-6  # every draw within 1% of the domain's width of its top
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        emu = gpmsa.fit(data, obs, n_iter=20, tune=False, seed=0, fixed={"theta": [top]})
    assert np.all(emu.calibration["theta_native"] == top)  # exactly the value given
    unit = (top - data.t.min()) / (data.t.max() - data.t.min())  # held on the unit scale
    np.testing.assert_allclose(emu.calibration["theta"], unit, rtol=1e-12)
    assert not [w for w in caught if issubclass(w.category, gpmsa.AtBoundWarning)]


def test_a_categorical_theta_init_off_its_levels_is_refused(categorical, obs):
    with pytest.raises(GPMSAError, match=_full(
        "theta_init: categorical calibration parameter t0 must be one of its training levels"
    )):  # fmt: skip
        _fit(categorical, obs, theta_init=[0.5])
    emu = _fit(categorical, obs, theta_init=[1.0], n_iter=2, n_burn=0)
    assert emu.calibration["theta_native"][0, 0] in (0.0, 1.0, 2.0)


def test_fixed_must_be_a_dict(data):
    with pytest.raises(
        GPMSAError, match=_full("fixed must be None or a dict name -> value, got [1]")
    ):
        _fit(data, fixed=[1])


# --- checks at their edges ------------------------------------------------------------------


def test_n_keep_may_equal_n_chains(data):
    emu = _fit(data, n_chains=2, n_keep=2, n_jobs=1)
    assert (emu.n_draws, emu.settings["thin"]) == (2, 16)
    with pytest.raises(GPMSAError, match=_full(
        "n_keep=1 is fewer than n_chains=2: every chain keeps a draw"
    )):  # fmt: skip
        _fit(data, n_chains=2, n_keep=1)


def test_the_advice_at_a_ladder():
    assert fit_module.more_advice(False, {"temperatures": [1, 2, 4.5, 0.1 + 0.2]}) == (
        "continue these: gpmsa.fit(..., init=the returned emulator, "
        "temperatures=[1, 2, 4.5, 0.30000000000000004]), tempered as these chains ran"
    )
    assert fit_module.more_advice(True, {"temperatures": [1, 2], "swap_every": 3}) == (
        "append more: gpmsa.fit(..., init=the returned emulator, append=True, "
        "temperatures=[1, 2], swap_every=3), tempered as these chains ran"
    )
    adapted = {"temperatures": [1, 2, 4], "swap_every": 1, "adapted_temperatures": [[1, 3, 4]]}
    assert fit_module.more_advice(False, adapted) == (
        "continue these: gpmsa.fit(..., init=the returned emulator), tempered as these chains "
        "ran: by default at each chain's adapted ladder (settings['adapted_temperatures']; "
        "temperatures= gives another)"
    )


def test_n_iter_and_n_burn_at_their_edges(data):
    with pytest.raises(GPMSAError, match=_full("n_iter must be an integer >= 2, got 1")):
        _fit(data, n_iter=1)
    emu = _fit(data, n_iter=2)  # the default burn-in: n_iter // 5 = 0
    assert (emu.settings["n_burn"], emu.n_draws) == (0, 2)
    assert _fit(data, n_iter=14).settings["n_burn"] == 2
    emu = _fit(data, n_iter=5, n_burn=4)
    assert (emu.settings["n_burn"], emu.n_draws) == (4, 1)
    assert _fit(data, n_iter=5, n_burn=0).n_draws == 5
    with pytest.raises(GPMSAError, match=_full("n_burn must be an integer in [0, 4], got 5")):
        _fit(data, n_iter=5, n_burn=5)
    with pytest.raises(GPMSAError, match=_full("n_burn must be an integer in [0, 4], got -1")):
        _fit(data, n_iter=5, n_burn=-1)


def test_the_memory_check_of_an_append_holds_the_pooled_draws_three_times(monkeypatch, data):
    from gpmsa.model.problem import prepare

    problem = prepare(data, None).problem
    seen = []
    monkeypatch.setattr(
        fit_module, "check_memory", lambda nbytes, what: seen.append((nbytes, what))
    )
    fit_module._check_fit_memory(problem, 10, 2, pooled=7, copies=3)
    elements = fit_module.parameter_elements(problem)
    factors = 8.0 * 25 * (1 + 1 + 4 * problem.p_u + 2)
    assert seen == [(16.0 * 2 * 10 * (elements + 1) + 3 * factors + 1.5 * 16.0 * 7 * (elements + 1),
                     f"fit(n_iter=10, n_chains=2) of 5 runs x {elements} parameter elements "
                     "appending to 7 retained draws at 3 temperatures")]  # fmt: skip


# --- continuations --------------------------------------------------------------------------


def test_an_untuned_continuation_steps_the_precisions_as_its_source(data):
    source = _fit(data, proportional_steps=False)  # untuned: GPM/SA's rule would step them so
    assert source.settings["proportional_steps"] is False
    on = _fit(data, init=source, seed=3)
    assert on.settings["proportional_steps"] is False
    again = _fit(data, init=source, seed=3, proportional_steps=False)  # the same, said
    np.testing.assert_array_equal(on.draws["lamUz"], again.draws["lamUz"])
    other = _fit(data, init=source, seed=3, proportional_steps=True)
    assert other.settings["proportional_steps"] is True


def test_a_point_other_than_mean_or_map_is_refused(data):
    for point in ("median", ["mean"], None):
        with pytest.raises(
            GPMSAError, match=_full(f"point must be 'mean' or 'map', got {point!r}")
        ):
            _fit(data, point=point)


def test_constraint_and_theta_init_need_observations(data, obs):
    message = _full("constraint= and theta_init= apply to theta: they need obs= (a joint fit)")
    for kw in ({"constraint": lambda theta: True}, {"theta_init": [0.5]}):
        with pytest.raises(GPMSAError, match=message):
            _fit(data, **kw)
    emu = _fit(data, obs, theta_init=[0.7], n_iter=2, n_burn=0, constraint=lambda theta: True)
    assert emu.settings["constraint"] is True


def test_the_basis_is_recorded_as_pca_or_given(data):
    emu = _fit(data)
    assert emu.settings["basis"] == "pca"
    assert _fit(data, basis=emu.K).settings["basis"] == "given"


def test_the_hot_copies_are_recorded_up_to_max_hot_values(monkeypatch):
    info = {"temperatures": np.array([1.0, 2.0]), "swap_every": 2, "swap_rate": [[0.25]],
            "hot_states": {"lamUz": np.array([[1.0, 2.0]])},
            "hot_step_widths": {"lamUz": np.array([[0.5]])}}  # fmt: skip
    base = {"temperatures": [1.0, 2.0], "swap_every": 2, "swap_rate": [[0.25]]}
    hot = {"hot_states": {"lamUz": [[1.0, 2.0]]}, "hot_step_widths": {"lamUz": [[0.5]]}}
    monkeypatch.setattr(fit_module, "MAX_HOT_VALUES", 3)
    assert fit_module.tempering_record(info, None) == base | hot
    monkeypatch.setattr(fit_module, "MAX_HOT_VALUES", 2)
    assert fit_module.tempering_record(info, None) == base


# --- helpers --------------------------------------------------------------------------------


@pytest.mark.parametrize(("n_chains", "kept", "n_keep", "thin"), [
    (1, 16, 5, 4), (1, 16, 16, 1), (2, 2, 100, 1), (2, 5, 4, 3), (3, 5, 4, 5), (3, 10, 7, 5),
])  # fmt: skip
def test_thinning_is_the_smallest_step_that_keeps_at_most_n_keep(n_chains, kept, n_keep, thin):
    assert fit_module.thinning(n_chains, kept, n_keep) == thin
    assert n_chains * math.ceil(kept / thin) <= n_keep
    assert thin == 1 or n_chains * math.ceil(kept / (thin - 1)) > n_keep


def test_the_point_estimate_is_the_mean_or_the_draw_of_highest_log_posterior(data):
    emu = _fit(data, n_chains=2, n_jobs=1)
    for k in ("betaU", "lamUz", "lamWs", "lamWOs"):
        np.testing.assert_allclose(emu.params[k], emu.draws[k].mean(axis=0), rtol=1e-12)
    best = int(np.argmax(emu.log_post))
    emu = _fit(data, n_chains=2, n_jobs=1, point="map")
    assert emu.settings["point"] == "map"
    for k in ("betaU", "lamUz", "lamWs", "lamWOs"):
        np.testing.assert_array_equal(emu.params[k], emu.draws[k][best])


def test_a_parameter_that_never_moved_keeps_its_value_exactly():
    draws = {k: np.full((3, 2), 0.1) for k in fit_module.EMULATOR_PARAMS}  # mean 0.1 + 1 ulp
    out = fit_module.point_estimate(draws, np.zeros(3), "mean")
    assert all(np.all(v == 0.1) and v.shape == (2,) for v in out.values())


def test_the_element_names_of_a_warning():
    assert fit_module.element_names(["x0"], ["t0", "t1"], 2) == {
        "theta[0]": "t0", "theta[1]": "t1",
        "betaU[0,0]": "x0", "betaU[0,1]": "x0", "betaU[1,0]": "t0", "betaU[1,1]": "t0",
        "betaU[2,0]": "t1", "betaU[2,1]": "t1",
    }  # fmt: skip


# --- a categorical t0 beside a continuous t1 ------------------------------------------------


@pytest.fixture(scope="module")
def mixed() -> tuple[gpmsa.SimData, gpmsa.ObsData]:
    """9 runs of a categorical t0 (levels 0, 1, 2) and a continuous t1, and 2 observations."""
    rng = np.random.default_rng(0)
    x = rng.uniform(size=(9, 1))
    t = np.column_stack([np.tile([0.0, 1.0, 2.0], 3), rng.uniform(size=9)])
    y = np.sin(GRID * (3 * x + t[:, :1] / 2 + t[:, 1:]))
    sim = gpmsa.SimData(x=x, t=t, y=y, t_categorical=[0])
    return sim, gpmsa.ObsData(x=X_OBS, y=np.sin(GRID * (3 * X_OBS + 1.5)))


def test_only_the_categorical_theta_is_rounded_and_left_unjudged_at_its_bound(mixed):
    sim, obs = mixed
    top = float(sim.t[:, 1].max()) - 1e-6  # t1 starts (and here stays) at its domain's top
    with warnings.catch_warnings(record=True) as caught:  # the top level 2: a closed bound
        warnings.simplefilter("always")
        emu = gpmsa.fit(sim, obs, n_iter=4, n_burn=0, tune=False, seed=0, theta_init=[2.0, top])
    native = emu.calibration["theta_native"]
    assert set(native[:, 0]) <= {0.0, 1.0, 2.0}
    lo, hi = sim.t[:, 1].min(), sim.t[:, 1].max()
    np.testing.assert_array_equal(native[:, 1], emu.calibration["theta"][:, 1] * (hi - lo) + lo)
    assert np.all(np.abs(native[:, 1] - top) < 1e-3 * (hi - lo))
    bound = [str(w.message) for w in caught if issubclass(w.category, gpmsa.AtBoundWarning)]
    assert len(bound) == 1 and " t1 at its upper bound " in bound[0] and " t0 " not in bound[0]


def test_a_categorical_element_that_keeps_one_level_in_one_chain_is_not_flagged(mixed):
    from gpmsa.mcmc.diagnostics import summarize
    from gpmsa.model.problem import prepare

    sim, obs = mixed
    problem = prepare(sim, obs).problem
    rng = np.random.default_rng(1)
    draws = {k: rng.uniform(1, 2, size=(1, 50, *problem.init[k].shape)) for k in problem.sampled}
    draws["theta"][..., 0] = 0.5  # the level 1 throughout
    draws["theta"][..., 1] = 0.25  # a continuous element that never moved
    record = fit_module.sampled_convergence(problem, summarize(draws), 1, 50)
    assert "theta[0]" not in record["flagged"]
    assert record["flagged"]["theta[1]"] == "constant draws (no proposal accepted)"


def test_the_convergence_warning_names_every_components_inputs(data):
    with pytest.warns(gpmsa.ConvergenceWarning) as caught:  # 3 components of 2 inputs
        gpmsa.fit(data, n_iter=20, tune=False, seed=0, n_pc=3)
    (message,) = [str(w.message) for w in caught if w.category is gpmsa.ConvergenceWarning]
    for name in ("betaU[0,2] (x0)", "betaU[1,2] (t0)", "betaU[1,0] (t0)"):
        assert name in message
    assert "or continue these: gpmsa.fit(..., init=the returned emulator)." in message
