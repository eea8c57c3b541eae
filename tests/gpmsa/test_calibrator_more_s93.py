"""Mutation testing of the Calibrator, a second part of the 1-in-3 sample (calr93b): exact cases
for the survivors of the first part (the refined nodes' least spacing, a categorical theta's
levels handed to a callable prior, q = 3 refused by the grid and sent to MCMC by 'auto')."""

from __future__ import annotations

import numpy as np
import pytest
from _calib_cases import one_t_emulator, recorded_edge_prior

import gpmsa
from gpmsa import Calibrator
from gpmsa.errors import GPMSAError
from gpmsa.fitting.emulator import Emulator

_PARAMS1 = {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [1e3], "lamWOs": [1e3]}


def _one_t(lo: float, priors=None, width: float = 1.0) -> Emulator:
    """y = x + t on 16 runs with t exactly spanning [lo, lo + width], at fixed parameters."""
    x = np.linspace(0.0, 1.0, 16)
    t = lo + width * np.roll(np.linspace(0.0, 1.0, 16), 5)
    sim = gpmsa.SimData(x[:, None], t[:, None], (x + t)[:, None], x_names=["x"], t_names=["t"])
    return Emulator.from_params(sim, _PARAMS1, priors)


def _three_t() -> Emulator:
    """y = x + a + b + c on 20 runs: q = 3, at fixed parameters."""
    rng = np.random.default_rng(0)
    x, t = rng.random(20), rng.random((20, 3))
    sim = gpmsa.SimData(x[:, None], t, x + t.sum(axis=1), x_names=["x"], t_names=["a", "b", "c"])
    return Emulator.from_params(sim, {"betaU": [[1.0]] * 4, "lamUz": [1.0], "lamWs": [1e3],
                                      "lamWOs": [1e3]})  # fmt: skip


def test_refined_nodes_are_at_least_eight_float_spacings_apart():
    """MIN_STEP_ULPS = 8 spacings of float64: on t in [0, 1] 8 x 2**-52 = 2**-49 of the range; on
    t in [2**20, 2**20 + 1] the native spacing 2**-32 (per unit of range) governs: 2**-29."""
    assert Calibrator(_one_t(0.0))._min_step == 2.0**-49
    assert Calibrator(_one_t(2.0**20))._min_step == 2.0**-29
    # t in [0, 2**10]: the native spacing at 2**10, 2**-42, is 2**-52 of the range: 2**-49
    assert Calibrator(_one_t(0.0, width=2.0**10))._min_step == 2.0**-49


def test_a_callable_prior_gets_a_categorical_thetas_exact_levels():
    """24 levels 0..23: the grid's node for level 13 maps back to 12.999999999999998 natively;
    the callable prior is handed every level as its exact integer."""
    x, t = np.linspace(0.0, 1.0, 48), np.arange(48) % 24
    emu = Emulator.from_params(gpmsa.SimData(x, t, x + t / 10, t_categorical=[0]), _PARAMS1)
    assert emu.standardizer.t_from_unit(np.array([[13 / 23]]))[0, 0] != 13.0
    seen = []

    def prior(th):
        seen.append(np.array(th, dtype=float))
        return np.zeros(len(th))

    Calibrator(emu).update([[0.5]], [[1.8]], prior=prior)
    assert np.concatenate(seen).tolist() == [float(k) for k in range(24)]


def test_three_calibration_parameters_are_refused_by_the_grid_and_auto_chooses_mcmc():
    """The grid handles q <= 2: q = 3 with method='grid' is refused by name, and 'auto' picks
    MCMC (the one-parameter case stays on the grid)."""
    emu = _three_t()
    with pytest.raises(GPMSAError, match=r"handles 1 or 2 calibration parameters, got q=3"):
        Calibrator(emu, method="grid")
    assert Calibrator(emu).method == "mcmc"
    assert Calibrator(one_t_emulator()[0]).method == "grid"


class _Recorder:
    """A bar in place of tqdm's: records its total and each ``update``."""

    made: list[_Recorder] = []

    def __init__(self, total, initial=0, **kwargs):
        self.total, self.n, self.steps = total, initial, []
        _Recorder.made.append(self)

    def update(self, n=1):
        self.steps.append(n)
        self.n += n

    def close(self):
        pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


@pytest.mark.parametrize(
    ("case", "total", "steps"),
    [
        ("one", 3, [1, 1, 1, 0]),  # a GP, its predictor on the grid and on the refined grid
        ("two", 2, [1, 1, 0]),  # q = 2: no refined grid
        ("draws", 9, [1, 1, 1, 1, 1, 1, 1, 1, 1, 0]),  # three parameter sets, q = 1
        ("categorical", 2, [1, 1, 0]),  # a categorical theta: no refined grid
    ],
)
def test_the_constructors_bar_counts_three_steps_a_set_for_one_continuous_parameter(
    monkeypatch, case, total, steps
):
    """progress=True: per emulator parameter set its GP and its predictor on the grid, and (one
    continuous parameter) on the refined grid; each step one update, the last none."""
    from _calib_cases import categorical_emulator, two_param_emulator, with_draws

    from gpmsa import _progress

    monkeypatch.setattr(_progress, "_bar_class", lambda: _Recorder)
    _Recorder.made = []
    emu = {"one": lambda: one_t_emulator()[0], "two": two_param_emulator,
           "draws": lambda: with_draws(one_t_emulator()[0], 3),
           "categorical": categorical_emulator}[case]()  # fmt: skip
    kw = {"emulator_params": "draws", "n_emulator_draws": 3} if case == "draws" else {}
    Calibrator(emu, progress=True, **kw)
    (bar,) = _Recorder.made
    assert (bar.total, bar.steps) == (total, steps)


def test_the_predictors_charge_adds_the_grids_eight_arrays_of_g_floats(monkeypatch):
    """One parameter, m = 16 runs, one component, G = 129 nodes and R refined ones, Chebyshev
    degree d (both named in the charge): 8 x 8 G (the grid's own arrays), 8 m^2 (Sigma_W's
    factor), 8 (G + R) (m + (d + 1)^2) kept and 8 max(G, R) m (1 + 2 (d + 1)) while built."""
    import re

    from gpmsa.calibration import calibrator as calibrator_module

    charges = []
    monkeypatch.setattr(
        calibrator_module, "check_memory", lambda b, what: charges.append((b, what))
    )
    Calibrator(one_t_emulator()[0])
    (charge, what) = charges[-1]
    d, r = map(
        int, re.search(r"Chebyshev degree (\d+), and (\d+) nodes of a refined", what).groups()
    )
    g, m, na = 129, 16, d + 1
    kept = 8 * (g + r) * (m + na * na)
    building = 8 * max(g, r) * m * max(3, 1 + 2 * na)
    assert charge == 8 * 8 * g + 8 * m * m + kept + building


def test_the_grids_theta_prior_is_the_normal_log_density_of_each_continuous_element():
    """Priors(theta_mean=0.2, theta_sd=0.1): at the grid's ends of a continuous element (unit 0
    and 1) -0.5 (0.2 / 0.1)^2 = -2 and -0.5 (0.8 / 0.1)^2 = -32; a categorical element beside it
    adds nothing (uniform over its levels), whichever its level."""
    from _level_cases import level_sim

    priors = gpmsa.Priors(theta_mean=0.2, theta_sd=0.1)
    one = Calibrator(_one_t(0.0, priors))
    assert one._log_prior_theta.shape == (129,)
    assert one._log_prior_theta[[0, 64, -1]] == pytest.approx([-2.0, -4.5, -32.0], rel=1e-12)
    mixed = Emulator.from_params(level_sim(np.random.default_rng(0), 30),
                                 {"betaU": [[1.0]] * 3, "lamUz": [1.0], "lamWs": [1e3],
                                  "lamWOs": [1e3]}, priors)  # fmt: skip
    cal = Calibrator(mixed, n_grid=5)
    assert cal._theta_unit.shape == (15, 2)  # k on 5 nodes (unit 0, 1/4, ..., 1) x 3 levels
    values, counts = np.unique(np.round(cal._log_prior_theta, 12), return_counts=True)
    assert values.tolist() == [-32.0, -15.125, -4.5, -2.0, -0.125]
    assert counts.tolist() == [3] * 5


def test_a_constraint_on_one_parameter_cuts_the_first_grid_at_its_boundary():
    """t < 0.6137 (no prior): the constructor's cut of the grid puts the boundary, located
    between nodes to adjacent floats, as the marginal's last node."""
    import warnings

    emu, x, y = one_t_emulator()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        post = Calibrator(emu, seed=1, constraint=lambda th: th[0] < 0.6137).update(x, y)
    assert post.grids["t"].nodes[-1] == pytest.approx(0.6137, abs=1e-15)


def test_one_parameter_prepares_the_whole_refined_axis_and_two_do_not():
    """q = 1 with Chebyshev plans: predictors prepared on `whole_refined_axis` of the grid, one
    per parameter set; q = 2 and a categorical theta: none."""
    from _calib_cases import categorical_emulator, two_param_emulator

    from gpmsa.calibration.grid import whole_refined_axis

    cal = Calibrator(one_t_emulator()[0])
    axis, predictors = cal._refined
    assert np.array_equal(axis, whole_refined_axis(np.linspace(0.0, 1.0, 129)))
    assert len(predictors) == 1 and predictors[0].theta.shape == (axis.size, 1)
    assert Calibrator(two_param_emulator())._refined is None
    assert Calibrator(categorical_emulator())._refined is None


def test_an_mcmc_calibrator_survives_pickling_without_a_grid():
    """An MCMC Calibrator has no grid and no refined predictors: unpickled, it is still MCMC with
    none prepared."""
    import pickle

    cal = pickle.loads(pickle.dumps(Calibrator(_three_t())))
    assert cal.method == "mcmc" and "_refined" not in cal.__dict__


def test_an_argument_without_effect_names_autos_choice_only_where_auto_chose():
    """n_grid with MCMC: 'auto' explains why it chose MCMC, method='mcmc' does not."""
    auto = r"runs MCMC \(method='auto' chooses MCMC here: more than 2 parameters, another backend"
    with pytest.raises(GPMSAError, match=auto):
        Calibrator(_three_t(), n_grid=33)
    with pytest.raises(GPMSAError, match=r"this Calibrator runs MCMC, which has no grid"):
        Calibrator(_three_t(), n_grid=33, method="mcmc")


def test_the_grid_takes_a_backend_in_mcmc_options_and_names_only_the_others():
    """method='grid' with mcmc_options={"backend": "numpy"} (its own backend): built; with another
    key beside it, refused naming that key alone."""
    emu = one_t_emulator()[0]
    assert Calibrator(emu, method="grid", mcmc_options={"backend": "numpy"}).method == "grid"
    with pytest.raises(GPMSAError, match=r"^mcmc_options \['n_samples'\] apply on the MCMC path"):
        Calibrator(emu, method="grid", mcmc_options={"backend": "numpy", "n_samples": 10})


def test_the_grid_reads_the_calibrators_emulator_params_not_mcmc_options():
    """On the grid ('auto', q = 1) emulator_params is the Calibrator's own: n_emulator_draws=3
    with the point estimate is refused though mcmc_options says "draws", and the draws with 3
    are built though mcmc_options says "point"."""
    from _calib_cases import with_draws

    emu = with_draws(one_t_emulator()[0], 5)
    with pytest.raises(GPMSAError, match=r"n_emulator_draws=3 sets how many"):
        Calibrator(emu, n_emulator_draws=3, mcmc_options={"emulator_params": "draws"})
    cal = Calibrator(emu, emulator_params="draws", n_emulator_draws=3,
                     mcmc_options={"emulator_params": "point"})  # fmt: skip
    assert (cal.method, cal.emulator_params) == ("grid", "draws")


def _bump_emulator(categorical: bool) -> Emulator:
    """y = x + exp(-((k - 0.3) / 0.15)^2) (+ 0.1 kind, kind in {0, 1, 2} categorical): a peak
    between the nodes 0, 0.5 and 1 of a 3-node grid; fixed parameters."""
    rng = np.random.default_rng(0)
    m = 90 if categorical else 60
    x, k = rng.random(m), rng.random(m)
    y = x + np.exp(-(((k - 0.3) / 0.15) ** 2))
    if categorical:
        kind = np.arange(m) % 3
        t = np.column_stack([k, kind])
        sim = gpmsa.SimData(x[:, None], t, (y + 0.1 * kind)[:, None], x_names=["x"],
                            t_names=["k", "kind"], t_categorical=["kind"])  # fmt: skip
        beta = [[1.0], [20.0], [1.0]]
    else:
        sim = gpmsa.SimData(x[:, None], k[:, None], y[:, None], x_names=["x"], t_names=["k"])
        beta = [[1.0], [20.0]]
    return Emulator.from_params(sim, {"betaU": beta, "lamUz": [1.0], "lamWs": [1e4],
                                      "lamWOs": [1e4]})  # fmt: skip


@pytest.mark.parametrize(("categorical", "y_obs"), [(False, 1.6), (True, 1.75)])
def test_a_coarse_grid_reads_the_observations_distance_on_the_probe(categorical, y_obs):
    """An observation above the peak: a 3-node grid (nodes 0, 0.5, 1 miss the peak at 0.3)
    reports the distance the 129-node probe reads, as the default grid does (per level for a
    categorical theta beside k), not the larger one its own nodes read."""
    import warnings

    emu = _bump_emulator(categorical)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        coarse = Calibrator(emu, n_grid=3).update([[0.5]], [[y_obs]]).info["outside_sds"]
        fine = Calibrator(emu).update([[0.5]], [[y_obs]]).info["outside_sds"]
    assert 1.0 < coarse == pytest.approx(fine, rel=1e-9)


def test_each_grid_update_is_counted_and_seeds_its_own_draws():
    """Two updates of the same observation: counted 1 and 2 (the repr), and without a seed
    the second draws from its own stream (the count is part of its key)."""
    emu, x, y = one_t_emulator()
    cal = Calibrator(emu, seed=5, n_draws=50)
    first = cal.update(x, y)
    assert repr(cal).endswith("updates=1)")
    second = cal.update(x, y)
    assert repr(cal).endswith("updates=2)")
    assert not np.array_equal(first.samples["t"], second.samples["t"])


@pytest.mark.parametrize("case", ["one", "categorical"])
def test_the_observations_hashes_are_recorded_unless_the_prior_is_a_table(case):
    """info's obs_values_sha256 / obs_layout_sha256: with no prior and with a callable one (the
    same hashes), not with a gridded prior (maybe other windows' log-likelihood)."""
    import warnings

    from _calib_cases import categorical_emulator

    if case == "one":
        emu, x, y = one_t_emulator()
    else:
        emu, x, y = categorical_emulator(), [[0.5]], [[1.5]]
    cal = Calibrator(emu)
    keys = ("obs_values_sha256", "obs_layout_sha256")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        none = cal.update(x, y).info
        call = cal.update(x, y, prior=lambda t: np.zeros(np.shape(t)[0])).info
        table = cal.update(x, y, prior=np.zeros(cal.theta_grid.shape[0])).info
    assert all(len(none[k]) == 64 and call[k] == none[k] for k in keys)
    assert not any(k in table for k in keys)


def test_one_parameter_refines_past_four_passes_to_a_prior_of_sd_1e_11():
    """A normal prior of sd 1e-11 of the range at 0.61 (the likelihood flat beside it): one
    parameter refines up to MAX_REFINE_ONE = 9 passes, more than the 4 of two parameters, and
    resolves it: mean 0.61 and sd 1e-11 to 1e-6, no warning."""
    import warnings

    emu, x, y = one_t_emulator()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        post = Calibrator(emu, seed=1).update(
            x, y, prior=lambda t: -0.5 * ((np.asarray(t) - 0.61) / 1e-11) ** 2
        )
    assert post.mean("t") == pytest.approx(0.61, abs=1e-15)
    assert post.sd("t") == pytest.approx(1e-11, rel=1e-6)


def test_one_parameter_narrower_than_float64_warns():
    """A normal prior of sd 1e-18 at 0.61, below float64's spacing there (1.1e-16): refinement
    ends at float64's resolution and says so (GridResolutionWarning naming t)."""
    from gpmsa.errors import GridResolutionWarning

    emu, x, y = one_t_emulator()
    with pytest.warns(GridResolutionWarning, match=r"posterior of t is narrower than the grid"):
        Calibrator(emu, seed=1).update(
            x, y, prior=lambda t: -0.5 * ((np.asarray(t) - 0.61) / 1e-18) ** 2
        )


def test_two_parameters_record_their_resolution_after_the_last_pass():
    """A normal prior of sd 1e-6 on both parameters at 0.61: the grid refines pass after pass
    and records the resolution of the grid it ended with (both widths over 2.5 node spacings),
    without a warning."""
    import warnings

    from _calib_cases import two_param_emulator

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        post = Calibrator(two_param_emulator(), seed=1).update(
            [[0.5]], [[1.0]],
            prior=lambda t: -0.5 * np.sum(((np.asarray(t) - 0.61) / 1e-6) ** 2, axis=1),
        )  # fmt: skip
    res = post.info["resolution"]
    assert len(res) == 2 and min(res) > 2.5


def test_a_levels_refined_row_on_the_fixed_axis_is_the_fixed_grids_row():
    """A categorical theta beside k (Priors(theta_mean=0.2, theta_sd=0.1), so that the prior
    matters): `_level_row` on the fixed grid's own k nodes (dense solves) gives, per level, the
    fixed grid's log posterior there (its predictors, and `_log_prior_theta`) to 1e-7."""
    from _level_cases import level_sim

    from gpmsa.calibration import calibrator as calibrator_module

    priors = gpmsa.Priors(theta_mean=0.2, theta_sd=0.1)
    emu = Emulator.from_params(level_sim(np.random.default_rng(0), 30),
                               {"betaU": [[1.0]] * 3, "lamUz": [1.0], "lamWs": [1e3],
                                "lamWOs": [1e3]}, priors)  # fmt: skip
    cal = Calibrator(emu, n_grid=5)
    data = calibrator_module.reduce(emu, [[0.5]], [[1.3]], False)
    free = cal._combine(cal._marginals(data, None)) + cal._log_prior_theta
    rows = free.reshape(5, 3).T  # (levels, k nodes)
    for r in range(3):
        _, row = cal._level_row(data, 0, r, cal._axes[0], None, None)
        assert row == pytest.approx(rows[r], rel=1e-7)  # dense vs Chebyshev: ~2e-9


def test_a_continuous_parameter_beside_a_level_narrower_than_float64_warns():
    """A categorical theta beside k, a normal prior of sd 1e-18 on k at 0.61 (below float64's
    spacing): its width given the level spans no node spacing (resolution 0), and the grid
    says it does not resolve k given the level."""
    from _level_cases import level_sim

    from gpmsa.errors import GridResolutionWarning

    emu = Emulator.from_params(level_sim(np.random.default_rng(0), 30),
                               {"betaU": [[1.0]] * 3, "lamUz": [1.0], "lamWs": [1e3],
                                "lamWOs": [1e3]})  # fmt: skip
    with pytest.warns(GridResolutionWarning, match=r"does not resolve the posterior of k given"):
        post = Calibrator(emu, n_grid=5).update(
            [[0.5]], [[1.3]], prior=lambda t: -0.5 * ((np.asarray(t)[:, 0] - 0.61) / 1e-18) ** 2
        )
    assert post.info["resolution"][0] == 0.0


@pytest.mark.parametrize("shift", [(0.6, 0.5), (0.3, 1.01)])
def test_refined_levels_keep_the_continuous_axis_end_and_a_small_levels_mass(shift):
    """A categorical kind beside k, 6 observations of sin(3 x) + k + 0.5 kind near (k, kind) =
    (0.6, 1) or (0.3, 2), n_grid=9: levels refined along k; the k marginal's nodes still start
    at k's design minimum, and in the second case kind 0 keeps its small probability (1.5e-10,
    its refined density scaled as the others', not 0)."""
    import warnings

    from _level_cases import level_sim

    emu = Emulator.from_params(level_sim(np.random.default_rng(0), 30),
                               {"betaU": [[1.0]] * 3, "lamUz": [1.0], "lamWs": [1e3],
                                "lamWOs": [1e3]})  # fmt: skip
    xo = np.linspace(0.1, 0.9, 6)[:, None]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        post = Calibrator(emu, n_grid=9, seed=1).update(xo, np.sin(3 * xo) + sum(shift))
    assert post.grids["k"].nodes[0] == emu.standardizer.t_min[0]
    p0 = post.grids["kind"].probabilities()[0.0]
    assert p0 > 1e-7 if shift[0] == 0.6 else p0 == pytest.approx(1.5286e-10, rel=1e-3)


def test_a_callable_priors_zero_edge_beside_a_constraint_is_bisected_point_by_point():
    """With a constraint (t < 0.9) the prior's zero edge near 0.6137 is bisected one point an edge a
    call (the constraint's function is called point by point), still to adjacent floats."""
    import warnings

    emu, x, y = one_t_emulator()
    sizes = []
    prior = recorded_edge_prior(0.6137, sizes)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        post = Calibrator(emu, seed=1, constraint=lambda th: th[0] < 0.9).update(x, y, prior=prior)
    assert sizes[0] == (129,) and len(sizes) > 40 and set(sizes[1:]) <= {(1,), (2,)}
    assert post.grids["t"].nodes[0] == pytest.approx(0.6137, abs=1e-15)
