"""Per-group lamVz priors (GPM/SA's one priors.lamVz.params row per lamVzGroup): each group's
lamVz under its own Gamma prior on every backend, equal priors as the shared one, the checks
of their number, and the emulator file."""

import math
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_discrepancy_groups_s61 import BASIS, GROUPS, _data, _emulator, _random_params

import gpmsa
from gpmsa import EmulatorFileError, GammaPrior, GPMSAError, Priors
from gpmsa.io.container import write_raw
from gpmsa.mcmc import starts
from gpmsa.mcmc.sampler import ChainState
from gpmsa.model.likelihood import log_likelihood, log_posterior
from gpmsa.model.problem import prepare

VAGUE = GammaPrior(1.0, 1e-3)  # GPM/SA's default lamVz prior
TIGHT = GammaPrior(1000.0, 0.1)  # mean 1e4, sd 316: far above group 1's data-driven ~800
SHIPPED = "control/emulators/jackal_A.gpmsa"
SHIPPED_MODEL_SHA256 = "123f5eb9efe8e989fca0b4b9d8f8c24239fc3c0a96697f092639980cf1116f2a"
"""Its model_sha256 as computed before per-group priors existed."""


def _problem(lam_vz, groups=GROUPS):
    data, obs = _data()
    return prepare(data, obs, priors=Priors(lamVz=lam_vz), discrepancy=BASIS,
                   discrepancy_groups=groups).problem  # fmt: skip


def _calibrate(emu, backend: str, **kw):
    _, obs = _data()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the toy's y_obs lies outside the emulator (on purpose)
        return gpmsa.calibrate(emu, obs, discrepancy=BASIS, discrepancy_groups=GROUPS, seed=1,
                               backend=backend, **kw)  # fmt: skip


def _joint_fit(priors, **kw):
    data, obs = _data()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gpmsa.fit(data, obs, tune=False, seed=0, discrepancy=BASIS,
                         discrepancy_groups=GROUPS, priors=priors, **kw)  # fmt: skip


def _hand_lamvz(priors: list[GammaPrior], lam: np.ndarray) -> float:
    return sum((g.a - 1.0) * math.log(x) - g.b * x for g, x in zip(priors, lam, strict=True))


# --- the model ----------------------------------------------------------------------------------
def test_priors_take_one_gamma_or_one_per_group():
    assert Priors(lamVz=[VAGUE, TIGHT]).lamVz == (VAGUE, TIGHT)  # stored as a tuple
    assert Priors(lamVz=VAGUE).lamvz_priors(3) == (VAGUE,) * 3
    assert Priors(lamVz=(VAGUE, TIGHT)).precision_prior("lamVz", 1) == TIGHT
    assert Priors(lamVz=(VAGUE, TIGHT)).precision_prior("lamUz", 1) == Priors().lamUz
    for bad in ([], (), [VAGUE, "x"], [VAGUE, (1.0, 1e-3)], "vague", {"a": 1, "b": 1}):
        with pytest.raises(GPMSAError, match="Priors.lamVz must be a gpmsa.GammaPrior .* or a "
                           "non-empty list or tuple of them"):  # fmt: skip
            Priors(lamVz=bad)
    with pytest.raises(GPMSAError, match="Priors.lamUz must be a gpmsa.GammaPrior"):
        Priors(lamUz=[VAGUE])


def test_log_posterior_adds_each_groups_gamma_log_density():
    """At a fixed point the log posterior under per-group priors differs from that under the
    default (shared Gamma(1, 1e-3)) by the hand-computed per-group Gamma log densities; the
    sampler's element priors and its running log posterior agree."""
    priors = [GammaPrior(3.0, 0.5), GammaPrior(40.0, 0.2)]
    per, shared = _problem(priors), _problem(VAGUE)
    prm = _random_params(per, np.random.default_rng(3))
    lam = prm["lamVz"]
    want = _hand_lamvz(priors, lam) - _hand_lamvz([VAGUE, VAGUE], lam)
    got = log_posterior(per, prm) - log_posterior(shared, prm)
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-9)
    assert log_likelihood(per, prm) == log_likelihood(shared, prm)
    state = ChainState(per, prm, np.random.default_rng(0))
    assert state.log_prior == log_posterior(per, prm) - log_likelihood(per, prm)
    for i, (name, idx) in enumerate(state.els):
        if name == "lamVz":
            want = _hand_lamvz([priors[idx[0]]], [7.5])
            np.testing.assert_allclose(state.el_prior[i](7.5), want, rtol=1e-15)
    bounded = _problem([VAGUE, GammaPrior(1.0, 1e-3, 100.0)])
    assert log_posterior(bounded, {**prm, "lamVz": np.array([50.0, 50.0])}) == -np.inf
    assert np.isfinite(log_posterior(bounded, {**prm, "lamVz": np.array([50.0, 150.0])}))


def test_torch_and_pyro_log_posteriors_apply_each_groups_prior():
    torch = pytest.importorskip("torch")
    tb = pytest.importorskip("gpmsa.backends.torch_backend")
    priors = [GammaPrior(3.0, 0.5), GammaPrior(40.0, 0.2, 1.0)]
    problem = _problem(priors)
    rng = np.random.default_rng(8)
    chains = [_random_params(problem, rng) for _ in range(3)]
    want = np.array([log_posterior(problem, c) for c in chains])
    start = {k: np.stack([c[k] for c in chains]) for k in problem.init}
    with tb.torch_threads(1):
        state = tb.BatchState(problem, 3, torch.float64, "cpu", start=start)
        np.testing.assert_allclose(state.log_post().numpy(), want, rtol=1e-9)
        for g, prior in enumerate(priors):  # a sweep's element prior: its group's
            x = torch.tensor([2.0, 7.5], dtype=torch.float64)
            np.testing.assert_allclose(
                tb.log_prior_elements(problem.priors, "lamVz", x, g).numpy(),
                (prior.a - 1) * np.log([2.0, 7.5]) - prior.b * np.array([2.0, 7.5]),
            )
    pytest.importorskip("pyro")
    from gpmsa.backends.pyro_backend import PyroModel

    model = PyroModel(problem)
    prm = {k: torch.as_tensor(v, dtype=torch.float64) for k, v in start.items()}
    got = (model.log_likelihood(prm) + model.log_prior(prm)).numpy()
    np.testing.assert_allclose(got, want, rtol=1e-9)


def test_equal_per_group_priors_give_the_shared_log_posterior_on_torch_and_pyro():
    torch = pytest.importorskip("torch")
    tb = pytest.importorskip("gpmsa.backends.torch_backend")
    per, shared = _problem([VAGUE, VAGUE]), _problem(VAGUE)
    rng = np.random.default_rng(9)
    chains = [_random_params(per, rng) for _ in range(3)]
    start = {k: np.stack([c[k] for c in chains]) for k in per.init}
    with tb.torch_threads(1):
        lp = [tb.BatchState(p, 3, torch.float64, "cpu", start=start).log_post().numpy()
              for p in (per, shared)]  # fmt: skip
    np.testing.assert_array_equal(lp[0], lp[1])
    pytest.importorskip("pyro")
    from gpmsa.backends.pyro_backend import PyroModel

    prm = {k: torch.as_tensor(v, dtype=torch.float64) for k, v in start.items()}
    models = [PyroModel(p) for p in (per, shared)]
    post = [(m.log_likelihood(prm) + m.log_prior(prm)).numpy() for m in models]
    np.testing.assert_array_equal(post[0], post[1])
    assert repr(models[0].support["lamVz"]) == repr(models[1].support["lamVz"])


# --- sampling: a tight prior on group 1 holds its lamVz, group 0 stays data-driven ---------------
def _assert_group_one_held(post) -> None:
    """Under the shared vague prior lamVz[0] ~ 3 and lamVz[1] ~ 800 (sd ~1,000) on this toy;
    TIGHT (mean 1e4, sd 316) on group 1 only."""
    lam0, lam1 = post.samples["lamVz[0]"], post.samples["lamVz[1]"]
    assert np.median(lam0) < 30
    assert abs(np.median(lam1) / 1e4 - 1.0) < 0.1
    assert np.std(lam1) < 1000


def test_numpy_calibrate_holds_the_tight_groups_lamvz_at_its_prior():
    emu = _emulator().with_calibration_priors(lamVz=[VAGUE, TIGHT])
    _assert_group_one_held(_calibrate(emu, "numpy", n_samples=800, n_burn=200, tune_rounds=10))


def test_numpy_joint_fit_holds_the_tight_groups_lamvz_at_its_prior():
    emu = _joint_fit(Priors(lamVz=[VAGUE, TIGHT]), n_iter=1500)
    _assert_group_one_held(gpmsa.calibration_posterior(emu))


def test_torch_calibrate_holds_the_tight_groups_lamvz_at_its_prior():
    pytest.importorskip("torch")
    emu = _emulator().with_calibration_priors(lamVz=[VAGUE, TIGHT])
    _assert_group_one_held(_calibrate(emu, "torch", n_samples=300, n_burn=100, tune_rounds=5))


def test_pyro_calibrate_holds_the_tight_groups_lamvz_at_its_prior():
    """Group 1's lower bound 1 differs from group 0's 0: per-element bounds for NUTS. Trees of
    depth <= 4 (default 10): 3.5 s, not 10 s; over seeds 0-9 group 1's median within 1.3 % of
    1e4, its sd 250-360, group 0's median 1.1-4.2 (VAGUE on group 1 too: median 1,000)."""
    pytest.importorskip("pyro")
    tight = GammaPrior(TIGHT.a, TIGHT.b, 1.0)
    emu = _emulator().with_calibration_priors(lamVz=[VAGUE, tight])
    post = _calibrate(emu, "pyro", n_samples=40, n_burn=10, n_warmup=40, max_tree_depth=4)
    _assert_group_one_held(post)


def test_pyro_refuses_per_group_bounds_of_mixed_finiteness_before_sampling():
    pytest.importorskip("pyro")
    emu = _emulator().with_calibration_priors(lamVz=[VAGUE, GammaPrior(1.0, 1e-3, 0.0, 1e5)])
    with pytest.raises(GPMSAError, match=r"upper bounds \[inf, 100000.0\] mix finite and infinite"):
        _calibrate(emu, "pyro", n_samples=10, n_burn=0, n_warmup=5)


def test_prior_starts_draw_each_group_from_its_own_prior():
    priors = [GammaPrior(1e6, 2e5), GammaPrior(1e6, 100.0)]  # ~5 and ~1e4, sd 0.1 %
    problem = _problem(priors)
    _, firsts = starts.chain_starts(problem, "prior", np.random.SeedSequence(0).spawn(2))
    for start in firsts:
        np.testing.assert_allclose(start["lamVz"], [5.0, 1e4], rtol=0.01)


def test_starts_outside_a_groups_bounds_are_refused_naming_them():
    """GPM/SA's start lamVz 20 outside group 1's bounds starts at that prior's median inside
    them (``starts.default_start``, test_starts_support_s67); a given start there is refused."""
    problem = _problem([VAGUE, GammaPrior(1.0, 1e-3, 1000.0)])
    with pytest.raises(GPMSAError, match=r"lamVz = \[20.0, 20.0\] .* per-group Priors.lamVz "
                       r"\[\(0, inf\), \(1000, inf\)\]"):  # fmt: skip
        starts.chain_starts(problem, {"lamVz": [20.0, 20.0]}, np.random.SeedSequence(0).spawn(1))
    for how, n in (("gpmsa", 1), ("jitter", 2)):
        for start in starts.chain_starts(problem, how, np.random.SeedSequence(0).spawn(n))[1]:
            assert start["lamVz"][1] > 1000.0


# --- equal per-group priors are the shared prior, bit for bit ----------------------------------
def test_equal_per_group_priors_give_the_shared_draws_numpy():
    a = _joint_fit(Priors(lamVz=VAGUE), n_iter=60)
    b = _joint_fit(Priors(lamVz=[VAGUE, VAGUE]), n_iter=60)
    for k in a.calibration:
        np.testing.assert_array_equal(a.calibration[k], b.calibration[k])
    np.testing.assert_array_equal(a.log_post, b.log_post)
    emu = _emulator()
    for init in ("prior", "jitter"):
        kw = dict(n_samples=60, n_burn=0, tune_rounds=2, n_chains=2, init=init)
        pa = _calibrate(emu, "numpy", **kw)
        pb = _calibrate(emu.with_calibration_priors(lamVz=(VAGUE, VAGUE)), "numpy", **kw)
        for k in pa.samples:
            np.testing.assert_array_equal(pa.samples[k], pb.samples[k])


# --- the number of priors must be the number of groups ------------------------------------------
WRONG = r"Priors.lamVz gives 3 per-group prior\(s\) but the discrepancy has 2 precision group"


def test_wrong_number_of_group_priors_is_refused_everywhere():
    data, obs = _data()
    three = [VAGUE] * 3
    with pytest.raises(GPMSAError, match=WRONG):
        _joint_fit(Priors(lamVz=three), n_iter=10)
    emu = _emulator()
    with pytest.raises(GPMSAError, match=WRONG):
        _calibrate(emu.with_calibration_priors(lamVz=three), "numpy", n_samples=10, n_burn=0)
    with pytest.raises(GPMSAError, match=WRONG):
        gpmsa.fit_study([data, data], [obs, obs], shared=["t"], n_iter=10, tune=False, seed=0,
                        discrepancy=BASIS, discrepancy_groups=GROUPS,
                        priors=Priors(lamVz=three))  # fmt: skip
    with pytest.raises(GPMSAError, match="but the discrepancy has 1 precision group"):
        _problem([VAGUE, VAGUE], groups=None)
    for bad in ([], [VAGUE, 1.0]):
        with pytest.raises(GPMSAError, match="lamVz must be a gpmsa.GammaPrior"):
            emu.with_calibration_priors(lamVz=bad)
    # a hand-made posterior (no emulator record) with an emulator of three group priors
    post = _calibrate(emu, "numpy", n_samples=10, n_burn=0, tune=False)
    info = {k: v for k, v in post.info.items() if k != "emulator_sha256"}
    with pytest.raises(GPMSAError, match=WRONG):
        gpmsa.full_prediction(emu.with_calibration_priors(lamVz=three), obs, [[0.5]],
                              posterior=gpmsa.Posterior(dict(post.samples), info=info),
                              discrepancy=BASIS)  # fmt: skip


def test_group_priors_without_a_discrepancy_are_unused():
    data, obs = _data()
    problem = prepare(data, obs, priors=Priors(lamVz=[VAGUE] * 3)).problem
    assert "lamVz" not in problem.init


def test_continuation_compares_priors_group_by_group():
    first = _joint_fit(Priors(lamVz=VAGUE), n_iter=20)
    again = _joint_fit(Priors(lamVz=[VAGUE, VAGUE]), n_iter=20, init=first)  # the same model
    assert again.settings["continued_from"]
    with pytest.raises(GPMSAError, match="its priors differ"):
        _joint_fit(Priors(lamVz=[VAGUE, TIGHT]), n_iter=20, init=first)


# --- the emulator file -------------------------------------------------------------------------
def test_file_round_trip_of_per_group_priors(tmp_path):
    emu = _emulator().with_calibration_priors(lamVz=[VAGUE, TIGHT])
    manifest, _ = emu.to_record()
    assert manifest["priors"]["lamVz"] == [
        {"a": 1.0, "b": 0.001, "lower": 0.0, "upper": "inf"},
        {"a": 1000.0, "b": 0.1, "lower": 0.0, "upper": "inf"},
    ]
    emu.save(tmp_path / "e.gpmsa")
    back = gpmsa.load(tmp_path / "e.gpmsa")
    assert back.priors == emu.priors and back.priors.lamVz == (VAGUE, TIGHT)
    assert back.model_sha256 == emu.model_sha256 != _emulator().model_sha256
    one = _emulator().with_calibration_priors(lamVz=[VAGUE, VAGUE])
    assert one.model_sha256 != _emulator().model_sha256  # the digest covers the form too
    joint = _joint_fit(Priors(lamVz=[VAGUE, TIGHT]), n_iter=20)
    joint.save(tmp_path / "j.gpmsa")
    assert gpmsa.load(tmp_path / "j.gpmsa").priors.lamVz == (VAGUE, TIGHT)


def test_old_file_with_one_lamvz_prior_loads_unchanged():
    emu = gpmsa.load(SHIPPED)
    assert emu.priors.lamVz == VAGUE and not emu.priors.per_group
    assert emu.priors.to_dict()["lamVz"] == {"a": 1.0, "b": 0.001, "lower": 0.0, "upper": "inf"}
    assert emu.model_sha256 == SHIPPED_MODEL_SHA256


@pytest.mark.parametrize(
    ("lam_vz", "match"),
    [
        ([{"a": 1.0, "b": 0.001, "lower": 0.0, "upper": "inf"}] * 3,
         r"priors.lamVz: 3 per-group priors, but arrays/cal_lamVz holds draws of 2"),
        ([], r"priors.lamVz: an empty list"),
        ([{"a": 1.0, "b": 0.001, "lower": 0.0, "upper": "inf"},
          {"a": -1.0, "b": 0.001, "lower": 0.0, "upper": "inf"}], r"priors.lamVz\[1\].a: -1.0"),
        ([{"a": 1.0, "b": 0.001, "lower": 0.0, "upper": "inf"}, "x"],
         r"priors.lamVz\[1\]: must be an object"),
    ],
)  # fmt: skip
def test_corrupted_group_priors_in_a_file_are_refused_by_field(tmp_path, lam_vz, match):
    joint = _joint_fit(Priors(lamVz=[VAGUE, TIGHT]), n_iter=20)
    manifest, arrays = joint.to_record()
    manifest["priors"]["lamVz"] = lam_vz
    path = write_raw(tmp_path / "bad.gpmsa", manifest, arrays)
    with pytest.raises(EmulatorFileError, match=match):
        gpmsa.load(path)


def test_from_dict_names_a_bad_group_entry():
    d = Priors(lamVz=[VAGUE, TIGHT]).to_dict()
    d["lamVz"][1] = {"a": 0.0, "b": 1.0}
    with pytest.raises(GPMSAError, match=r"Priors.from_dict: lamVz\[1\]: Gamma prior needs"):
        Priors.from_dict(d)
    d["lamVz"] = []
    with pytest.raises(GPMSAError, match="lamVz as a list needs one prior per"):
        Priors.from_dict(d)


_gamma = st.builds(
    GammaPrior,
    a=st.floats(1e-3, 1e6),
    b=st.floats(1e-6, 1e6),
    lower=st.floats(0.0, 10.0),
    upper=st.one_of(st.just(math.inf), st.floats(20.0, 1e8)),
)


@settings(max_examples=50, deadline=None)
@given(st.one_of(_gamma, st.lists(_gamma, min_size=1, max_size=5)))
def test_priors_dict_round_trip(lam_vz):
    priors = Priors(lamVz=lam_vz)
    back = Priors.from_dict(priors.to_dict())
    assert back == priors
    assert isinstance(priors.to_dict()["lamVz"], list) == isinstance(lam_vz, list)
