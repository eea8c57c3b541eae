"""Mutation testing of gpmsa/calibration/observations.py (session 90): exact checks, on small
hand-built cases, of what the existing tests left open (limits at their edges, refusals named,
hand-computed reductions, probes and fits), and a NaN prediction at one probe node, which read
an observation far outside as inside."""

from __future__ import annotations

import dataclasses
import hashlib
import re
import warnings
from functools import cache
from types import SimpleNamespace

import numpy as np
import pytest
from _calib_cases import one_component_functional

import gpmsa
from gpmsa.calibration import observations as obsmod
from gpmsa.calibration.model import LamOsPrior
from gpmsa.errors import ExtrapolationWarning, GPMSAError
from gpmsa.fitting.emulator import Emulator

PARAMS = {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [5000.0], "lamWOs": [5000.0]}


@cache
def scalar_emulator() -> Emulator:
    """x in [0, 10] (the design's ends), t in [0, 1], scalar y = 0.1 x + t: 12 runs."""
    x = np.linspace(0.0, 10.0, 12)
    t = np.random.default_rng(0).permutation(np.linspace(0.0, 1.0, 12))
    sim = gpmsa.SimData(
        x=x[:, None], t=t[:, None], y=(0.1 * x + t)[:, None], x_names=["x"], t_names=["t"]
    )
    return Emulator.from_params(sim, PARAMS)


@cache
def level_x_emulator() -> Emulator:
    """A categorical known input c (levels 1, 2, 3) and a continuous t: 12 runs."""
    c = np.tile([1.0, 2.0, 3.0], 4)
    t = np.linspace(0.0, 1.0, 12)
    sim = gpmsa.SimData(
        x=c[:, None],
        t=t[:, None],
        y=(c + t)[:, None],
        x_names=["c"],
        t_names=["t"],
        x_categorical=["c"],
    )
    return Emulator.from_params(sim, PARAMS)


# --- module constants ----------------------------------------------------------------------------


def test_point_mode_takes_the_default_of_twenty_draws_only():
    obsmod.check_draws_mode("point", 20, "f")  # the documented default: no error
    obsmod.check_draws_mode("draws", 7, "f")
    for n in (19, 21):
        with pytest.raises(GPMSAError, match=rf"^f: n_emulator_draws={n} sets how many"):
            obsmod.check_draws_mode("point", n, "f")


def test_level_probe_budget_is_eight_full_probes():
    assert obsmod.LEVEL_PROBE_NODES == 33 * 33
    assert obsmod.LEVEL_PROBE_BUDGET == 8712


# --- x checks ------------------------------------------------------------------------------------


def test_check_x_refuses_an_unseen_level_of_a_categorical_known_input():
    emu = level_x_emulator()
    x, _ = obsmod.check_x(emu, [[2.0]], False)
    assert x.tolist() == [[2.0]]
    msg = r"^x_obs: categorical input c has level 2.5, never seen in training \(levels \[1"
    with pytest.raises(GPMSAError, match=msg):
        obsmod.check_x(emu, [[2.5]], False)


def test_emulator_record_holds_a_text_fingerprint_only():
    assert obsmod.emulator_record(SimpleNamespace(model_sha256="ab12")) == {
        "emulator_sha256": "ab12"
    }
    assert obsmod.emulator_record(SimpleNamespace(model_sha256=None)) == {}
    assert obsmod.emulator_record(SimpleNamespace()) == {}


# --- layout digest -------------------------------------------------------------------------------


def _sha(*parts: bytes) -> str:
    h = hashlib.sha256()
    for part in parts:
        h.update(part)
    return h.hexdigest()


def test_layout_digest_by_hand():
    grid = np.array([0.0, 1.0, 2.0])
    own = np.array([0.5, 1.5])
    lam = np.array([4.0, 9.0])
    f8 = lambda a: np.asarray(a, dtype="<f8").tobytes()  # noqa: E731
    assert obsmod.layout_digest([None, grid.copy()], None, grid) == _sha(
        b"0:grid:simulation;", b"1:grid:simulation;"
    )
    assert obsmod.layout_digest([own, None], [lam, lam[:1]], grid) == _sha(
        b"0:grid(2,):",
        f8(own),
        b"1:grid:simulation;",
        b"0:precision(2,):",
        f8(lam),
        b"1:precision(1,):",
        f8(lam[:1]),
    )
    # a grid of another shape, or equal in shape but not in values, is its own
    assert obsmod.layout_digest([grid[:2]], [], grid) == _sha(b"0:grid(2,):", f8(grid[:2]))
    moved = grid + [0.0, 0.0, 0.5]
    assert obsmod.layout_digest([moved], None, grid) == _sha(b"0:grid(3,):", f8(moved))


# --- the projector onto observed directions ------------------------------------------------------


def test_observed_projector_drops_the_unobserved_directions():
    # one experiment of two reduced values; the second's variance is above 0.5 / GLS_RIDGE
    big = 1.0 / obsmod.GLS_RIDGE
    obs = SimpleNamespace(
        n_null=1, scalar_out=False, z=np.zeros(2), n=1, sig_obs=np.diag([1.0, big])
    )
    assert np.array_equal(obsmod._observed_projector(obs), np.diag([1.0, 0.0]))
    # two experiments, component-major: experiment e's values at e, e + n
    sig = np.diag([1.0, 2.0, big, 3.0])  # experiment 0: (0, 2), experiment 1: (1, 3)
    obs = SimpleNamespace(n_null=1, scalar_out=False, z=np.zeros(4), n=2, sig_obs=sig)
    assert np.array_equal(obsmod._observed_projector(obs), np.diag([1.0, 1.0, 0.0, 1.0]))
    # at the threshold 0.5 / GLS_RIDGE itself a direction counts as observed
    half = 0.5 / obsmod.GLS_RIDGE
    obs = SimpleNamespace(
        n_null=1, scalar_out=False, z=np.zeros(2), n=1, sig_obs=np.diag([1.0, half])
    )
    assert np.array_equal(obsmod._observed_projector(obs), np.eye(2))
    for n_null, scalar in ((0, False), (1, True)):
        obs = SimpleNamespace(
            n_null=n_null, scalar_out=scalar, z=np.zeros(2), n=1, sig_obs=np.diag([1.0, big])
        )
        assert obsmod._observed_projector(obs) is None


# --- lamos start ---------------------------------------------------------------------------------


def _fit(excess: float) -> obsmod.Fit:
    return obsmod.Fit(outside_sds=1.0, excess_var=excess)


def test_lamos_start_by_hand():
    start = obsmod.lamos_start
    assert start(_fit(0.0), LamOsPrior(50.0, 1.0)) == 50.0  # the prior's mean a / b
    assert start(_fit(0.0), LamOsPrior(5.0, 1.0)) == 5.0  # below 20: the mean still
    assert start(_fit(0.1), LamOsPrior(50.0, 1.0)) == 10.0  # 1 / excess_var, lower
    assert start(_fit(0.01), LamOsPrior(50.0, 1.0)) == 50.0  # 1 / excess_var = 100, higher
    # a lower bound above: 1.01 lower
    assert start(_fit(0.0), LamOsPrior(2.0, 1.0, lower=4.0)) == pytest.approx(4.04, rel=1e-15)
    assert start(_fit(0.0), LamOsPrior(5.0, 1.0, lower=4.0)) == 5.0
    # reaching the upper bound: the middle of (lower, upper)
    assert start(_fit(0.0), LamOsPrior(5.0, 1.0, lower=1.0, upper=5.0)) == 3.0
    assert start(_fit(0.0), LamOsPrior(5.0, 1.0, lower=1.0, upper=5.5)) == 5.0
    assert start(_fit(0.0), LamOsPrior(2.0, 1.0, lower=4.0, upper=4.04)) == 4.02


# --- probes for a categorical theta --------------------------------------------------------------


def _probe_size(n_cont: int, n_combos: int):
    probe = obsmod.continuous_probe(n_cont, n_combos)
    return None if probe is None else (probe[0].shape, probe[1])


def test_continuous_probe_at_the_budget_edges():
    assert obsmod.LEVEL_PROBE_BUDGET == 8 * 33 * 33
    # two parameters: 33 x 33 while n_combos x 1089 <= 8712, then 9 x 9, 3 x 3, the centre
    assert _probe_size(2, 8) == ((1089, 2), (33, 33))
    assert _probe_size(2, 9) == ((81, 2), (9, 9))
    assert _probe_size(2, 107) == ((81, 2), (9, 9))  # 107 x 81 = 8667
    assert _probe_size(2, 108) == ((9, 2), (3, 3))  # 108 x 81 = 8748
    assert _probe_size(2, 968) == ((9, 2), (3, 3))  # 968 x 9 = 8712
    assert _probe_size(2, 969) == ((1, 2), None)
    assert _probe_size(2, 8712) == ((1, 2), None)
    assert _probe_size(2, 8713) is None
    # one parameter: 129 nodes (67 x 129 = 8643), then 33
    assert _probe_size(1, 67) == ((129, 1), (129,))
    assert _probe_size(1, 68) == ((33, 1), (33,))
    # three: 27 + 256 nodes (30 x 283 = 8490), then the 27-node lattice, then the centre
    assert _probe_size(3, 30) == ((283, 3), (None))
    assert _probe_size(3, 31) == ((27, 3), None)
    assert _probe_size(3, 322) == ((27, 3), None)  # 8694
    assert _probe_size(3, 323) == ((1, 3), None)  # 8721
    # none: one node of no columns
    assert _probe_size(0, 8712) == ((1, 0), None)
    assert obsmod.continuous_probe(0, 8713) is None


def test_continuous_probe_nodes():
    base, layout = obsmod.continuous_probe(1, 68)
    assert np.array_equal(base[:, 0], np.linspace(0.0, 1.0, 33))
    base, _ = obsmod.continuous_probe(2, 108)
    assert base.tolist() == [[a, b] for a in (0.0, 0.5, 1.0) for b in (0.0, 0.5, 1.0)]
    # 11 x 985 > 8712: the 3^6 lattice, the seventh parameter at its middle
    base, _ = obsmod.continuous_probe(7, 11)
    assert base.shape == (729, 7)
    assert np.array_equal(base, obsmod.theta_probe(7)[:729])
    assert np.all(base[:, 6] == 0.5)
    base, _ = obsmod.continuous_probe(3, 323)
    assert base.tolist() == [[0.5, 0.5, 0.5]]


def test_level_probe_blocks_by_hand():
    # one categorical parameter (levels 0, 1) and one continuous (129 nodes): 1089 // 129 = 8
    # combinations a block, so both in one
    blocks = list(obsmod.level_probe_blocks([None, (0.0, 1.0)]))
    assert len(blocks) == 1
    theta, b, layout = blocks[0]
    assert (b, layout, theta.shape) == (2, (129,), (258, 2))
    assert np.array_equal(theta[:129, 0], np.linspace(0.0, 1.0, 129))
    assert np.array_equal(theta[129:, 0], np.linspace(0.0, 1.0, 129))
    assert np.all(theta[:129, 1] == 0.0) and np.all(theta[129:, 1] == 1.0)
    # three levels, nodes=2: blocks of 2 combinations of one node, then the rest
    blocks = list(obsmod.level_probe_blocks([(0.0, 0.5, 1.0)], nodes=2))
    assert [(t.tolist(), b, lay) for t, b, lay in blocks] == [
        ([[0.0], [0.5]], 2, None),
        ([[1.0]], 1, None),
    ]
    # fewer nodes than a combination's: one combination a block
    blocks = list(obsmod.level_probe_blocks([(0.0, 1.0), None], nodes=100))
    assert [b for _, b, _ in blocks] == [1, 1]
    assert [t.shape for t, _, _ in blocks] == [(129, 2), (129, 2)]
    assert np.all(blocks[1][0][:, 0] == 1.0)
    # over the budget: nothing
    assert list(obsmod.level_probe_blocks([tuple(np.linspace(0, 1, 8713))])) == []


# --- emulator checks -----------------------------------------------------------------------------


def test_check_emulator_refusals_named():
    emu = scalar_emulator()
    fake = SimpleNamespace(**{a: getattr(emu, a) for a in obsmod.EMULATOR_ATTRS if a != "K"})
    with pytest.raises(GPMSAError, match=r"^emulator lacks \['K'\]: calibration needs"):
        obsmod.check_emulator(fake)
    fake.K = emu.K
    fake.params = {k: v for k, v in emu.params.items() if k not in ("lamUz", "lamWOs")}
    with pytest.raises(GPMSAError, match=r"^emulator.params lacks \['lamUz', 'lamWOs'\]; it"):
        obsmod.check_emulator(fake)
    fake.params = emu.params
    fake.t_unit = np.zeros((3, 0))
    with pytest.raises(GPMSAError, match=r"^the emulator has no calibration parameter \(t has 0"):
        obsmod.check_emulator(fake)
    fake.t_unit = np.zeros((3, 1))
    fake.t_names, fake.x_names = ["t"], ["x"]
    obsmod.check_emulator(fake)  # no levels attribute: nothing categorical
    fake.levels = (None, (0, 1))
    with pytest.raises(GPMSAError, match=r"^calibration: calibration parameter t is categorical"):
        obsmod.check_emulator(fake)
    obsmod.check_emulator(fake, categorical_theta=True)
    fake.levels = ((0, 1), None)  # a categorical known input is no categorical theta
    obsmod.check_emulator(fake)


# --- x: rows and the domain ----------------------------------------------------------------------


def test_as_rows_shapes():
    rows = obsmod._as_rows
    assert rows(3.0, "a", 1).shape == (1, 1)
    assert rows([1.0, 2.0], "a", 2).tolist() == [[1.0, 2.0]]  # one row of ncols
    assert rows([1.0, 2.0, 3.0], "a", 1).tolist() == [[1.0], [2.0], [3.0]]  # a column
    assert rows([[1.0, 2.0]], "a", 2).shape == (1, 2)
    for bad, shape in (
        ([1.0, 2.0, 3.0], "(3,)"),
        (np.zeros((0, 2)), "(0, 2)"),
        ([[[1.0, 2.0]]], "(1, 1, 2)"),
        ([[1.0], [2.0]], "(2, 1)"),
    ):
        with pytest.raises(
            GPMSAError, match=rf"^a must have shape \(n, 2\), got {re.escape(shape)}$"
        ):
            rows(bad, "a", 2)
    with pytest.raises(GPMSAError, match="^a"):
        rows([1.0, np.nan], "a", 2)


def _warned(fn, *args):
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        out = fn(*args)
    return out, [str(w.message) for w in seen if issubclass(w.category, ExtrapolationWarning)]


def test_check_x_domain_edges():
    emu = scalar_emulator()  # x in [0, 10]
    (x, xu), seen = _warned(obsmod.check_x, emu, [[0.0], [10.0], [2.5]], False)
    assert seen == [] and xu[:, 0].tolist() == [0.0, 1.0, 0.25] and x[:, 0].tolist() == [0, 10, 2.5]
    for value, shown in ((-1.0, "-1"), (11.0, "11"), (-0.5, "-0.5"), (10.5, "10.5")):
        (x, xu), seen = _warned(obsmod.check_x, emu, [[value]], False)  # within 10 %: a warning
        assert seen == [
            f"x_obs x={shown} lies outside the emulator's domain [0, 10]; the emulator extrapolates"
        ]
    for value, shown in ((-1.5, "-1.5"), (11.5, "11.5")):
        with pytest.raises(
            GPMSAError,
            match=rf"^x_obs x={shown} lies outside the emulator's "
            r"domain \[0, 10\] by more than 10% of its width; pass extrapolate",
        ):
            obsmod.check_x(emu, [[value]], False)
        _, seen = _warned(obsmod.check_x, emu, [[value]], True)
        assert seen == [
            f"x_obs x={shown} lies outside the emulator's domain [0, 10]; the emulator extrapolates"
        ]
    # the row named is the first farther than 10 %, not the first outside
    with pytest.raises(GPMSAError, match=r"^new x=12 lies"):
        obsmod.check_x(emu, [[10.5], [12.0], [-3.0]], False, "new")
    _, seen = _warned(obsmod.check_x, emu, [[5.0], [-0.5], [10.5]], False)
    assert len(seen) == 1 and seen[0].startswith("x_obs x=-0.5 lies")


def test_check_x_takes_none_only_without_known_inputs():
    emu = scalar_emulator()
    with pytest.raises(GPMSAError, match=r"^x_obs is a gpmsa.ObsData: pass its inputs"):
        obsmod.check_x(emu, gpmsa.ObsData(x=[[1.0]], y=[[1.0]]), False)
    with pytest.raises(GPMSAError):
        obsmod.check_x(emu, None, False)
    p0 = SimpleNamespace(
        x_unit=np.zeros((3, 0)), x_names=[], standardizer=SimpleNamespace(x_to_unit=lambda x: x)
    )
    x, xu = obsmod.check_x(p0, None, False)
    assert x.shape == (1, 0) and xu.shape == (1, 0)


# --- y -------------------------------------------------------------------------------------------


def test_refuse_ragged():
    obsmod.refuse_ragged([[1.0, 2.0], [3.0, 4.0]])  # even
    obsmod.refuse_ragged(np.zeros((2, 3)))  # no list
    obsmod.refuse_ragged([[1.0, [2.0]], [3.0]])  # ragged inside: as_float's to refuse
    obsmod.refuse_ragged([1.0, 2.0])  # scalars, not experiments
    obsmod.refuse_ragged([[[1.0, 2.0]], [[3.0]]])  # not one-dimensional experiments
    with pytest.raises(GPMSAError, match=r"^y_obs holds experiments of different lengths \[2, 3\]"):
        obsmod.refuse_ragged([[1.0, 2.0], (3.0, 4.0, 5.0)])
    with pytest.raises(GPMSAError, match=r"lengths \[1, 1, 2\]"):
        obsmod.refuse_ragged(([1.0], [2.0], [3.0, 4.0]))


def test_obs_inputs_without_known_inputs():
    def emu(p: int, l_sim: int):
        return SimpleNamespace(
            x_unit=np.zeros((3, p)), x_names=["a"] * p, K=np.zeros((l_sim, 1)), y_names=None
        )

    given = [[1.0]]
    assert obsmod.obs_inputs(emu(1, 1), given, [[2.0]]) is given
    with pytest.raises(
        GPMSAError,
        match=r"^y_obs is required: the observed outputs \(n, l_sim\), "
        r"native units$",
    ):
        obsmod.obs_inputs(emu(1, 1), given, None)
    with pytest.raises(GPMSAError, match=r"native units; this emulator has no known inputs, so"):
        obsmod.obs_inputs(emu(0, 1), given, None)
    with pytest.raises(GPMSAError, match=r"native units$"):
        obsmod.obs_inputs(emu(0, 1), None, None)
    with pytest.raises(GPMSAError, match=r"^xo is required: the emulator has p = 1 known input"):
        obsmod.obs_inputs(emu(1, 1), None, [[2.0]], "xo")
    # a scalar output: every value one observation
    assert obsmod.obs_inputs(emu(0, 1), None, [[1.0, 2.0, 3.0]]).shape == (3, 0)
    assert obsmod.obs_inputs(emu(0, 1), None, [1.0, 2.0]).shape == (2, 0)
    # a functional output: one row an experiment, a 1-D y one experiment
    assert obsmod.obs_inputs(emu(0, 3), None, [[1.0, 2.0, 3.0]] * 2).shape == (2, 0)
    assert obsmod.obs_inputs(emu(0, 3), None, [1.0, 2.0, 3.0]).shape == (1, 0)


# --- limits --------------------------------------------------------------------------------------


def test_reduced_values_limit_at_its_edge(monkeypatch):
    from gpmsa import limits
    from gpmsa.errors import ResourceLimitError

    monkeypatch.setattr(limits, "MAX_OBS_VALUES", 12)
    obsmod._check_obs_values(4, 3)  # 12 values: allowed
    obsmod._check_obs_values(12, 1)
    msg = (
        r"^x_obs/y_obs have 13 rows x 1 basis components = 13 reduced values, above "
        r"gpmsa.limits.MAX_OBS_VALUES = 12: "
    )
    with pytest.raises(ResourceLimitError, match=msg):
        obsmod._check_obs_values(13, 1)
    with pytest.raises(ResourceLimitError, match=r"^x_obs/y_obs have 5 rows x 3 basis compo"):
        obsmod._check_obs_values(5, 3)
    monkeypatch.setattr(limits, "MAX_OBS_VALUES", float("nan"))
    with pytest.raises(ResourceLimitError):
        obsmod._check_obs_values(1, 1)


# --- the reduction -------------------------------------------------------------------------------


def test_scalar_reduction_by_hand():
    emu = scalar_emulator()
    std = emu.standardizer
    y = [1.5, 0.5, 2.0]
    data = obsmod.reduce(emu, [[1.0], [5.0], [9.0]], y)
    u = (np.array(y) - float(np.ravel(std.y_mean)[0])) / float(np.ravel(std.y_sd)[0])
    assert np.allclose(data.z, u, rtol=1e-15, atol=0)
    assert data.x[:, 0].tolist() == [0.1, 0.5, 0.9]
    assert np.allclose(data.obs_chol, np.eye(3) / np.sqrt(1.0 + obsmod.SIGOBS_RIDGE), rtol=1e-15)
    assert data.os_corr == (0.0, 0.0)
    base = emu.priors.lamOs
    assert (data.lamos.shape, data.lamos.rate) == (base.a, base.b)
    assert [v.tolist() for v in data.values] == [[1.5], [0.5], [2.0]]
    assert data.grids == (None,) * 3 and data.precisions == (None,) * 3
    # a scalar output's y as one row (1, n) reads as n observations, the same reduction
    row = obsmod.reduce(emu, [[1.0], [5.0], [9.0]], [y])
    assert np.array_equal(row.z, data.z) and row.values_sha256 == data.values_sha256
    assert row.layout_sha256 == obsmod.layout_digest([None] * 3, None, std.grid)
    with pytest.raises(GPMSAError, match=r"^y_obs must have one row per x_obs row \(3\), got 2$"):
        obsmod.reduce(emu, [[1.0], [5.0], [9.0]], [[1.0], [2.0]])
    one = obsmod.reduce(emu, [[1.0]], [1.5])
    assert one.obs_chol.shape == (1, 1)
    assert one.obs_chol[0, 0] == np.sqrt(1.0 / (1.0 + obsmod.SIGOBS_RIDGE))


def test_reduced_data_limit_of_max_std_obs():
    base = LamOsPrior(2.0, 3.0, 0.5, 7.0)
    emu = SimpleNamespace(
        priors=SimpleNamespace(lamOs=SimpleNamespace(a=2.0, b=3.0, lower=0.5, upper=7.0))
    )

    def make(z, sig):
        obs = SimpleNamespace(z=np.asarray(z, dtype=float), sig_obs=np.asarray(sig, dtype=float))
        return obsmod._observations(
            emu, obs, (1.5, 0.25), ("v", "l"), np.zeros((1, 0)), ((), (), ())
        )

    data = make([1e6, -1e6], [[4.0, 2.0], [2.0, 5.0]])  # at the limit: allowed
    assert np.array_equal(data.obs_chol, [[2.0, 0.0], [1.0, 2.0]])
    assert data.lamos == LamOsPrior(3.5, 3.25, base.lower, base.upper)
    assert (data.values_sha256, data.layout_sha256, data.os_corr) == ("v", "l", (1.5, 0.25))
    assert make([3.0], [[9.0]]).obs_chol.tolist() == [[3.0]]
    for z, shown in (([0.0, -2e6], "2e+06"), ([np.inf], "more than 1.8e308 (overflow)")):
        with pytest.raises(
            GPMSAError,
            match=rf"^y_obs lies {re.escape(shown)} standard deviations "
            r"of the simulation outputs from their mean; allowed at most 1e\+06 "
            r"\(wrong units\?\)$",
        ):
            make(z, np.eye(len(z)))
    with pytest.raises(GPMSAError, match=r"^y_obs lies"):
        make([np.nan], [[1.0]])
    with pytest.raises(GPMSAError, match=r"^y_obs lies 1000001 standard"):
        make([1e6 + 1.0], [[1.0]])


def test_obs_data_for_a_scalar_output_index_checked_before_sizes():
    emu = scalar_emulator()  # its one output point: index 0
    two = gpmsa.ObsData(x=[[1.0]], y=[[1.0, 2.0]], index=[0.0, 1.0])
    with pytest.raises(
        GPMSAError,
        match=r"^the index of experiment 0 is 2 values \(0, \.\.\.\), "
        "but the simulation output is scalar",
    ):
        obsmod.reduce(emu, two, None)
    sizes = gpmsa.ObsData(x=[[1.0], [2.0], [3.0]], y=[[1.0], [2.0, 3.0, 4.0], [5.0, 6.0]])
    with pytest.raises(
        GPMSAError,
        match=r"^the emulator's output is a scalar: each ObsData "
        r"experiment needs one value, got 2 \(give y as a column",
    ):
        obsmod.reduce(emu, sizes, None)
    x, xu = obsmod.checked_obs_data(emu, gpmsa.ObsData(x=[[5.0]], y=[[1.0]], index=[0.0]), False)
    assert x.tolist() == [[5.0]] and xu.tolist() == [[0.5]]


# --- categorical theta levels --------------------------------------------------------------------


def _level_fake(levels, x_names=("c",), t_names=("a", "b", "k")):
    t_min, t_max = np.array([0.0, 2.0, 1.0]), np.array([1.0, 10.0, 3.0])
    std = SimpleNamespace(t_min=t_min, t_to_unit=lambda t: (t - t_min) / (t_max - t_min))
    return SimpleNamespace(
        levels=levels,
        x_unit=np.zeros((4, len(x_names))),
        standardizer=std,
        x_names=list(x_names),
        t_names=list(t_names),
    )


def test_theta_levels_by_hand():
    emu = _level_fake(((5, 6), None, (2, 4, 10), (1, 3)))
    assert obsmod.theta_levels(emu) == [None, (0.0, 0.25, 1.0), (0.0, 1.0)]
    assert obsmod.theta_levels_native(emu) == {"b": [2, 4, 10], "k": [1, 3]}
    # a categorical known input alone: no categorical theta
    emu = _level_fake(((5, 6), None, None, None))
    assert obsmod.theta_levels(emu) is None
    assert obsmod.theta_levels_native(emu) == {}
    assert obsmod.theta_levels(_level_fake(None)) is None
    assert obsmod.theta_levels_native(_level_fake(None)) == {}
    emu = _level_fake((None, (2, 6), None), x_names=(), t_names=("k", "a", "b"))  # p = 0
    assert obsmod.theta_levels(emu) == [None, (0.0, 0.5), None]  # column 1's range: [2, 10]
    assert obsmod.theta_levels_native(emu) == {"a": [2, 6]}


# --- the user's log prior ------------------------------------------------------------------------


def test_check_log_prior_values_and_refusals():
    names, theta = ("a", "b"), [0.25, 0.5]
    check = obsmod.check_log_prior
    assert check(0.5, names, theta) == 0.5
    assert check(np.array([[-1.0]]), names, theta) == -1.0
    assert check(3, names, theta) == 3.0 and isinstance(check(3, names, theta), float)
    assert check(np.uint8(2), names, theta) == 2.0
    assert check(-np.inf, names, theta) == -np.inf
    with pytest.raises(
        GPMSAError, match=r"^log_prior must return numbers, got \[\[1\], \[1, 2\]\]"
    ):
        check([[1], [1, 2]], names, theta)
    with pytest.raises(GPMSAError, match=r"^log_prior must return real log densities, got None$"):
        check(None, names, theta)
    with pytest.raises(GPMSAError, match=r"got True \(dtype bool\) \(a mask\? return 0.0 where"):
        check(True, names, theta)
    with pytest.raises(GPMSAError, match=r"got 1j \(dtype complex128\)$"):
        check(1j, names, theta)
    with pytest.raises(GPMSAError, match=r"got 'x' \(dtype <U1\)$"):
        check("x", names, theta)
    for bad, n in (([1.0, 2.0], 2), (np.zeros((0,)), 0)):
        with pytest.raises(
            GPMSAError,
            match=rf"^log_prior must return one log density per theta "
            rf"row, got {n} values$",
        ):
            check(bad, names, theta)
    for bad, shown in ((np.nan, "nan"), (np.inf, "inf")):
        with pytest.raises(
            GPMSAError,
            match=rf"^log_prior returned {shown} at a=0.25, b=0.5: it "
            r"must return a log density \(a finite number, or -inf where",
        ):
            check(bad, names, theta)


# --- sign changes between probe nodes ------------------------------------------------------------


def test_crossed_by_hand():
    resid = np.array([[1.0, 2.0, 1.0], [-1.0, 3.0, 0.0], [2.0, 4.0, 1.0]])  # 3 nodes, 3 data
    assert obsmod._crossed(resid, (3,)).tolist() == [True, False, True]
    # a 2 x 2 grid ('ij': (0,0), (0,1), (1,0), (1,1)); a change along axis 1, axis 0, none
    resid = np.array([[1.0, 1.0, 1.0], [-1.0, 1.0, 2.0], [1.0, -1.0, 3.0], [1.0, -1.0, 4.0]])
    assert obsmod._crossed(resid, (2, 2)).tolist() == [True, True, False]
    # a change between nodes that are not neighbours is no crossing
    resid = np.array([[1.0], [1.0], [-1.0]])
    assert obsmod._crossed(resid[[0, 2, 1]], (3,)).tolist() == [True]
    assert obsmod._crossed(np.array([[-1.0], [-2.0], [-3.0]]), (3,)).tolist() == [False]


# --- warnings ------------------------------------------------------------------------------------


def test_warn_if_outside_at_the_edge_and_its_text():
    from gpmsa.errors import OutsideEmulatorWarning

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        obsmod.warn_if_outside(obsmod.Fit(obsmod.OUTSIDE_SDS, 0.0))  # at the limit: inside
    with pytest.warns(OutsideEmulatorWarning) as seen:
        obsmod.warn_if_outside(obsmod.Fit(7.25, 0.0))
    assert str(seen[0].message) == (
        "y_obs lies 7.25 predictive sds from the nearest emulator prediction at x_obs over the "
        "whole theta domain (more than 5): the observation is outside what the emulator has "
        "seen. The posterior then explains it by a large observation error (small lamOs) and "
        "theta falls back towards its prior, or, just beyond the outputs' range, piles up at "
        "the theta bound nearest the observation; check the units, the feature and the "
        "emulator's domain"
    )
    with pytest.warns(OutsideEmulatorWarning) as seen:
        obsmod.warn_if_outside(obsmod.Fit(7.25, 0.0), discrepancy=True, model="m")
    text = str(seen[0].message)
    assert text.startswith("model 'm': y_obs lies 7.25 predictive sds")
    assert "(more than 5) (the emulator alone): the observation" in text
    assert "seen. The discrepancy term and the observation error must then explain" in text
    assert text.endswith(
        "than the discrepancy you expect, check the units, the feature and the emulator's domain"
    )


def test_far_value_not_looked_at_for_a_scalar_output_read_inside():
    data = obsmod.reduce(scalar_emulator(), [[5.0]], [1.0])
    assert obsmod.far_value(SimpleNamespace(), data) is None  # no runs' outputs
    emu = scalar_emulator()
    inside = obsmod.Fit(obsmod.OUTSIDE_SDS, 0.0)
    assert obsmod.far_value(emu, data, inside) is None
    far_y = obsmod.reduce(emu, [[5.0]], [40.0])  # far above every run's y (0 ... 2)
    assert obsmod.far_value(emu, far_y, inside) is None
    assert obsmod.far_value(emu, far_y, obsmod.Fit(5.5, 0.0)) is not None
    assert obsmod.far_value(emu, far_y) is not None


# --- the closer outside check --------------------------------------------------------------------


def _one_datum(z: float = 5.0, os_corr=(0.0, 0.0)) -> obsmod.Observations:
    """One reduced datum z (d = 1), Sigma_obs = 1; no error estimate (os_corr 0)."""
    obs = SimpleNamespace(n_null=0, scalar_out=True, n=1, z=np.array([z]), sig_obs=np.eye(1))
    return obsmod.Observations(
        np.zeros((1, 0)),
        np.array([z]),
        np.eye(1),
        LamOsPrior(2.0, 1.0),
        obs,
        os_corr,
        "",
        "",
        (),
        (),
        (),
    )


def _line_predict(x, theta):
    """mean 10 theta (G, 1, 1), sd 0.1; NaN at theta 0.9."""
    theta = np.asarray(theta, dtype=float)
    mean = 10.0 * theta[:, :1, None]
    mean[np.isclose(theta[:, 0], 0.9)] = np.nan
    return mean, np.full((theta.shape[0], 1, 1, 1), 0.01)


@pytest.fixture
def scripted_searches(monkeypatch):
    """scipy.optimize.minimize replaced: search i evaluates its misfit at ``points[i]``."""
    import scipy.optimize

    calls: list = []
    points: list = []

    def minimize(fun, x0, method=None, bounds=None, options=None):
        calls.append([list(x0), method, bounds, options])
        calls[-1].append(fun(np.array([points[len(calls) - 1]])))

    monkeypatch.setattr(scipy.optimize, "minimize", minimize)
    return calls, points


def test_closer_fit_searches_from_the_best_nodes_until_inside(scripted_searches):
    calls, points = scripted_searches
    data = _one_datum()
    theta = np.array([[0.0], [1.0], [0.4]])  # distances 50, 50, 10: all outside
    points[:] = [0.3, 0.9, 0.52]  # 20 sds; NaN; 2 sds but an excess variance: not settled
    fit = obsmod.closer_fit(_line_predict, data, theta)
    assert [c[0] for c in calls] == [[0.4], [0.0], [1.0]]
    assert tuple(calls[0][1:4]) == ("L-BFGS-B", [(0.0, 1.0)], {"maxiter": 40})
    assert calls[0][4] == pytest.approx(400.0) and calls[1][4] == 1e300
    assert fit.outside_sds == pytest.approx(2.0)
    assert fit.excess_var == pytest.approx(0.04 - 0.01)
    # a search that reads it inside ends the searching; one that reads it outside does not
    calls.clear()
    points[:] = [0.52, 0.3]
    fit = obsmod.closer_fit(_line_predict, data, theta)
    assert len(calls) == 1 and fit.outside_sds == pytest.approx(2.0)
    calls.clear()
    points[:] = [0.3, 0.2, 0.1]
    fit = obsmod.closer_fit(_line_predict, data, theta)
    assert len(calls) == obsmod.CLOSER_STARTS == 3 and fit.outside_sds == pytest.approx(10.0)
    # a theta reading it exactly, with no excess variance: settled, the search stopped there
    calls.clear()
    points[:] = [0.5, 0.3]
    fit = obsmod.closer_fit(_line_predict, data, theta)
    assert len(calls) == 1 and len(calls[0]) == 4  # its misfit raised (_Settled)
    assert fit == obsmod.Fit(0.0, 0.0)


def test_closer_fit_without_a_search_where_a_node_reads_inside(scripted_searches):
    calls, _ = scripted_searches
    data = _one_datum()
    fit = obsmod.closer_fit(_line_predict, data, np.array([[0.0], [0.45]]))  # 50 and 5 sds
    assert calls == [] and fit == obsmod.Fit(pytest.approx(5.0), pytest.approx(0.25 - 0.01))
    probe = _line_predict(None, np.array([[0.47]]))  # the caller's predictions: 3 sds
    fit = obsmod.closer_fit(_line_predict, data, np.array([[0.0]]), probe)
    assert calls == [] and fit.outside_sds == pytest.approx(3.0)


# --- a categorical theta: fit over its levels ----------------------------------------------------


def _level_predict(x, theta):
    """mean 10 theta_0 + 20 theta_1 (G, 1, 1), sd 0.1."""
    theta = np.asarray(theta, dtype=float)
    mean = (10.0 * theta[:, 0] + 20.0 * theta[:, 1])[:, None, None]
    return mean, np.full((theta.shape[0], 1, 1, 1), 0.01)


def test_fit_at_levels_alone_meets_a_datum_between_nodes_of_one_level():
    # level 1 (unit 1.0) crosses 25.04 between nodes 64/128 and 65/128; level 0 reaches 10
    fit = obsmod.fit_at_levels(_level_predict, _one_datum(25.04), [None, (0.0, 1.0)])
    assert fit == obsmod.Fit(0.0, 0.0)
    # no level reaches 35: the nearest node is theta_0 = 1 at level 1, 5 / 0.1 = 50 sds
    fit = obsmod.fit_at_levels(_level_predict, _one_datum(35.0), [None, (0.0, 1.0)])
    assert fit.outside_sds == pytest.approx(50.0) and fit.excess_var == pytest.approx(25 - 0.01)
    # between the levels (mean 20 theta_1 jumps 0 -> 20 at theta_0 = 0) is no crossing
    fit = obsmod.fit_at_levels(_level_predict, _one_datum(-1.0), [(0.0, 1.0), None])
    assert fit.outside_sds == pytest.approx(10.0)


def test_fit_at_levels_with_an_error_estimate_one_theta_for_all():
    data = _one_datum(25.3, os_corr=(1.0, 0.0))  # noise obs_chol^2 / (a / b) = 0.5
    fit = obsmod.fit_at_levels(_level_predict, data, [None, (0.0, 1.0)])
    # the nearest node: 68/128 at level 1, mean 25.3125
    assert fit.outside_sds == pytest.approx(0.0125 / np.sqrt(0.01 + 0.5), rel=1e-12)
    assert fit.excess_var == 0.0


def test_fit_at_levels_over_the_budget_is_none():
    levels = [tuple(np.linspace(0.0, 1.0, 8713))]
    assert obsmod.fit_at_levels(_level_predict, _one_datum(), levels) is None


def test_observations_compare_by_identity_and_hash():
    emu = scalar_emulator()
    a = obsmod.reduce(emu, [[5.0]], [1.0])
    b = obsmod.reduce(emu, [[5.0]], [1.0])
    assert a == a and a != b  # no field-wise comparison of arrays
    assert len({a, b, a}) == 2


# --- a NaN prediction is no nearer ---------------------------------------------------------------


def test_a_nan_prediction_at_a_probe_node_is_no_nearer():
    # a NaN at one node read the datum "inside" (NaN is not > OUTSIDE_SDS): no warning
    mean = np.array([[[np.nan]], [[10.0]], [[9.0]]])  # nodes 2: 50, 3: 40 sds from z = 5
    cov = np.full((3, 1, 1, 1), 0.01)
    for data in (_one_datum(), _one_datum(os_corr=(1.0, 0.0))):
        sd = 0.1 if data.os_corr[0] == 0 else np.sqrt(0.01 + 0.5)
        fit = obsmod.fit_of(mean, cov, data)
        assert fit.outside_sds == pytest.approx(4.0 / sd)
        assert fit.excess_var == pytest.approx(16.0 - 0.01)
        assert obsmod.outside_sds(mean, cov, data) == pytest.approx(4.0 / sd)


def test_a_nan_prediction_at_a_level_probe_node_is_no_nearer():
    def predict(x, theta):
        mean, cov = _level_predict(x, theta)
        mean[theta[:, 0] == 1.0] = np.nan  # theta_0 = 1: mean 10 (level 0), 30 (level 1)
        return mean, cov

    # z = 35: the nearest readable node is theta_0 = 127/128 at level 1, 5.078125 from z
    for os_corr, sd in (((0.0, 0.0), 0.1), ((1.0, 0.0), np.sqrt(0.51))):
        fit = obsmod.fit_at_levels(predict, _one_datum(35.0, os_corr), [None, (0.0, 1.0)])
        assert fit.outside_sds == pytest.approx(5.078125 / sd, rel=1e-12)
        assert fit.excess_var == pytest.approx(5.078125**2 - 0.01, rel=1e-12)


def test_a_sign_change_across_nan_predictions_is_a_crossing():
    # session 91: +, NaN, - along the grid hid the crossing (NaN * -1 is not < 0), so with the
    # NaN no nearer the datum read as outside, at 40 sds, though the nodes bracket it
    mean = np.array([[[9.0]], [[np.nan]], [[1.0]]])  # z = 5: residuals +4, NaN, -4
    cov = np.full((3, 1, 1, 1), 0.01)
    assert obsmod.fit_of(mean, cov, _one_datum(), layout=(3,)).outside_sds == 0.0
    assert obsmod.outside_sds(mean, cov, _one_datum(), layout=(3,)) == 0.0
    same_side = np.array([[[9.0]], [[np.nan]], [[10.0]]])
    assert obsmod.fit_of(same_side, cov, _one_datum(), layout=(3,)).outside_sds == pytest.approx(
        40.0
    )


def test_crossed_carries_the_last_known_sign_over_nan_nodes_along_each_axis():
    nan = np.nan
    line = np.array([nan, 1.0, nan, nan, -1.0, nan])[:, None]
    assert obsmod._crossed(line, (6,)).tolist() == [True]
    assert obsmod._crossed(np.array([nan, 1.0, nan, 2.0, nan])[:, None], (5,)).tolist() == [False]
    assert obsmod._crossed(np.full((4, 1), nan), (4,)).tolist() == [False]
    # 2 x 2 grid ('ij'): the sign changes across the NaN only along axis 1 (rows)
    grid = np.array([1.0, nan, 2.0, 3.0])[:, None]  # [[1, nan], [2, 3]]: no change
    assert obsmod._crossed(grid, (2, 2)).tolist() == [False]
    grid = np.array([1.0, nan, 2.0, -3.0])[:, None]  # [[1, nan], [2, -3]]: row 2 changes
    assert obsmod._crossed(grid, (2, 2)).tolist() == [True]
    # a row with a NaN between + and -, three nodes long, in a 2 x 3 grid
    grid = np.array([1.0, nan, -1.0, 1.0, 1.0, 1.0])[:, None]
    assert obsmod._crossed(grid, (2, 3)).tolist() == [True]
    # columns are independent: the last known sign never crosses from one line to the next
    grid = np.array([1.0, nan, nan, -1.0])[:, None]  # [[1, nan], [nan, -1]]
    assert obsmod._crossed(grid, (2, 2)).tolist() == [False]
    # per datum: two data, the second crosses
    two = np.array([[1.0, 1.0], [nan, nan], [1.0, -1.0]])
    assert obsmod._crossed(two, (3,)).tolist() == [False, True]


def test_fit_is_a_frozen_value():
    fit = obsmod.Fit(1.5, 0.25)
    assert fit == obsmod.Fit(1.5, 0.25) and hash(fit) == hash(obsmod.Fit(1.5, 0.25))
    with pytest.raises(dataclasses.FrozenInstanceError):
        fit.outside_sds = 0.0


# --- the excess variance and its inverse factor ------------------------------------------------


def _data_with_chol(chol: np.ndarray, n_null: int = 0) -> obsmod.Observations:
    d = chol.shape[0]
    obs = SimpleNamespace(n_null=n_null, scalar_out=d == 1, n=d, z=np.zeros(d), sig_obs=None)
    return obsmod.Observations(
        np.zeros((d, 0)),
        np.zeros(d),
        chol,
        LamOsPrior(2.0, 1.0),
        obs,
        (0.0, 0.0),
        "",
        "",
        (),
        (),
        (),
    )


def test_chol_inverse_and_excess_by_hand():
    one = _data_with_chol(np.array([[2.0]]))
    assert obsmod._chol_inverse(one) is None
    # d = 1: (resid^2 - var) / L^2 = (9 - 0.5) / 4
    cov = np.full((2, 1, 1, 1), 0.5)
    got = obsmod._excess(np.array([[3.0], [0.1]]), np.array([[0.5], [0.5]]), cov, one, None)
    assert got.tolist() == [2.125, 0.0]
    two = _data_with_chol(np.array([[2.0, 0.0], [1.0, 2.0]]))
    assert np.allclose(obsmod._chol_inverse(two), [[0.5, 0.0], [-0.25, 0.5]], rtol=0, atol=1e-15)
    # d = 2, one experiment of two components (n = 1): L = diag(2, 1), S = diag(0.5, 0.25)
    diag = _data_with_chol(np.diag([2.0, 1.0]))
    cov = np.array([[[[0.5]], [[0.25]]]])  # (G, p_u, n, n)
    resid, var = np.array([[2.0, 3.0]]), np.array([[0.5, 0.25]])
    Linv = obsmod._chol_inverse(diag)
    # (|L^-1 r|^2 - tr(L^-1 S L^-T)) / d = ((1 + 9) - (0.125 + 0.25)) / 2
    assert obsmod._excess(resid, var, cov, diag, Linv).tolist() == [4.8125]
    # an unobserved direction is left out of the count: / (d - n_null)
    diag = _data_with_chol(np.diag([2.0, 1.0]), n_null=1)
    assert obsmod._excess(resid, var, cov, diag, Linv).tolist() == [9.625]
    # one experiment of one component, two data: S (1, 1, 2, 2) a block
    pair = _data_with_chol(np.diag([2.0, 1.0]))
    cov = np.array([[[[0.5, 0.1], [0.1, 0.25]]]])
    assert obsmod._excess(resid, var, cov, pair, Linv).tolist() == [4.8125]


def test_theta_probe_nodes():
    one = obsmod.theta_probe(1)
    assert one.shape == (129, 1) and one[1, 0] == 1 / 128 and one[-1, 0] == 1.0
    two = obsmod.theta_probe(2)
    assert two.shape == (1089, 2)
    assert two[:3].tolist() == [[0.0, 0.0], [0.0, 1 / 32], [0.0, 2 / 32]]
    assert two[-1].tolist() == [1.0, 1.0] and two[33].tolist() == [1 / 32, 0.0]
    three = obsmod.theta_probe(3)
    assert three.shape == (27 + 256, 3) and three[:3].tolist() == [
        [0, 0, 0],
        [0, 0, 0.5],
        [0, 0, 1],
    ]
    assert three[27].tolist() == [0.0, 0.0, 0.0]  # Sobol's first point
    assert obsmod.probe_layout(1) == (129,) and obsmod.probe_layout(2) == (33, 33)
    assert obsmod.probe_layout(3) is None


def test_far_warning_at_the_outside_limit():
    from gpmsa.errors import OutsideEmulatorWarning

    emu = scalar_emulator()
    far = obsmod.far_value(emu, obsmod.reduce(emu, [[5.0]], [40.0]))
    for sds in (obsmod.OUTSIDE_SDS, 4.0):  # read inside: the far value's own warning
        with pytest.warns(OutsideEmulatorWarning) as seen:
            obsmod.warn_if_outside(obsmod.Fit(sds, 0.0), far=far)
        assert len(seen) == 1 and str(seen[0].message).startswith(far.text() + ": a missing")
    with pytest.warns(OutsideEmulatorWarning) as seen:
        obsmod.warn_if_outside(obsmod.Fit(6.0, 0.0), far=far)
    assert len(seen) == 1
    assert str(seen[0].message).endswith(f"emulator's domain. The farthest value: {far.text()}")


def test_reduced_values_limit_counts_basis_components(monkeypatch):
    from _calib_cases import vector_emulator

    from gpmsa import limits
    from gpmsa.errors import ResourceLimitError

    emu = vector_emulator()  # l_sim = 8 on a grid of [0, 1], p_u = 2
    assert emu.K.shape == (8, 2)
    x = [[0.3], [0.5], [0.7]]
    y = np.ones((3, 8))
    monkeypatch.setattr(limits, "MAX_OBS_VALUES", 6)
    assert obsmod.reduce(emu, x, y).z.size == 6
    assert obsmod.reduce(emu, gpmsa.ObsData(x=x, y=y), None).z.size == 6
    monkeypatch.setattr(limits, "MAX_OBS_VALUES", 5)
    for args in ((x, y), (gpmsa.ObsData(x=x, y=y), None)):
        with pytest.raises(ResourceLimitError, match=r"have 3 rows x 2 basis components = 6 "):
            obsmod.reduce(emu, *args)


def test_obs_data_far_outside_allowed_with_extrapolate():
    emu = scalar_emulator()
    obs = gpmsa.ObsData(x=[[12.0]], y=[[1.0]])
    with pytest.warns(ExtrapolationWarning, match=r"the ObsData's input x=12 lies outside"):
        data = obsmod.reduce(emu, obs, None, extrapolate=True)
    assert data.x.tolist() == [[1.2]]


def test_fit_of_meets_a_datum_between_grid_nodes():
    data = _one_datum()  # z = 5, sd 0.1
    mean = np.array([4.0, 6.0, 8.0])[:, None, None]  # 10, 10, 30 sds; 5 between nodes 0, 1
    cov = np.full((3, 1, 1, 1), 0.01)
    assert obsmod.fit_of(mean, cov, data).outside_sds == pytest.approx(10.0)
    assert obsmod.fit_of(mean, cov, data, (3,)) == obsmod.Fit(0.0, pytest.approx(1.0 - 0.01))
    assert obsmod.outside_sds(mean, cov, data, (3,)) == 0.0
    below = np.array([4.0, 3.0, 2.0])[:, None, None]  # no sign change: 10 sds
    assert obsmod.outside_sds(below, cov, data, (3,)) == pytest.approx(10.0)


def test_closer_fit_searches_first_from_the_least_sum_of_squares(scripted_searches):
    calls, points = scripted_searches
    # two data z = (0, 0), sd 0.1, judged each on its own; node 0.1 reads (30, 30) sds, node
    # 0.2 (0, 40): sums of squares 1800 and 1600 (of cubes 54000 and 64000)
    table = {0.1: (3.0, 3.0), 0.2: (0.0, 4.0)}

    def predict(x, theta):
        mean = np.array([table.get(round(float(t[0]), 6), (9.0, 9.0)) for t in theta])
        return mean[:, None, :], np.tile(0.01 * np.eye(2), (len(theta), 1, 1, 1))

    data = _data_with_chol(np.eye(2))
    points[:] = [0.7, 0.8]
    fit = obsmod.closer_fit(predict, data, np.array([[0.1], [0.2]]))
    assert [c[0] for c in calls] == [[0.2], [0.1]]
    assert fit.outside_sds == pytest.approx(30.0)  # datum 0 at node 0.2, datum 1 at node 0.1


def test_excess_with_no_observed_direction_divides_by_one():
    data = _data_with_chol(np.diag([2.0, 1.0]), n_null=2)
    cov = np.array([[[[0.5]], [[0.25]]]])
    got = obsmod._excess(
        np.array([[2.0, 3.0]]), np.array([[0.5, 0.25]]), cov, data, obsmod._chol_inverse(data)
    )
    assert got.tolist() == [9.625]


def test_residual_noise_by_hand():
    data = _data_with_chol(np.array([[2.0, 0.0], [1.0, 2.0]]))
    assert obsmod._residual_noise(data) == 0.0
    noisy = dataclasses.replace(data, lamos=LamOsPrior(8.0, 2.0), os_corr=(1.0, 0.5))
    # diag(L L^T) / (a / b) = (4, 5) / 4
    assert obsmod._residual_noise(noisy).tolist() == [1.0, 1.25]


def test_scalar_reduction_problem_fields():
    emu = scalar_emulator()
    data = obsmod.reduce(emu, [[1.0], [5.0]], [1.5, 0.5])
    obs = data.obs
    assert obs.scalar_out is True and obs.D is None and obs.v.shape == (2, 0)
    assert [k.tolist() for k in obs.K] == [[[1.0]], [[1.0]]]
    assert obs.x.tolist() == [[0.1], [0.5]]
    assert np.array_equal(obs.sig_obs, np.eye(2) / (1.0 + obsmod.SIGOBS_RIDGE))
    via = obsmod.reduce(emu, gpmsa.ObsData(x=[[1.0], [5.0]], y=[[1.5], [0.5]]), None)
    assert [k.tolist() for k in via.obs.K] == [k.tolist() for k in obs.K]
    assert np.allclose(via.z, data.z, rtol=1e-15, atol=0)


def test_fit_at_levels_with_more_combinations_a_block_than_nodes():
    # 1000 levels: 3 continuous nodes each (3000 <= 8712), 363 combinations a block
    levels = [None, tuple(np.linspace(0.0, 1.0, 1000))]
    blocks = list(obsmod.level_probe_blocks(levels))
    assert [b for _, b, _ in blocks] == [363, 363, 274]
    assert {lay for _, _, lay in blocks} == {(3,)}
    fit = obsmod.fit_at_levels(_level_predict, _one_datum(5.0), levels)
    assert fit == obsmod.Fit(0.0, 0.0)  # theta (0.5, level 0) reads z exactly


def test_functional_output_of_one_component_takes_whole_experiments():
    emu, grid = one_component_functional()
    assert emu.K.shape == (4, 1)
    data = obsmod.reduce(emu, gpmsa.ObsData(x=[[0.5]], y=[2.0 * (1.0 + grid)]), None)
    assert data.z.shape == (1,) and data.values[0].tolist() == (2.0 * (1.0 + grid)).tolist()
