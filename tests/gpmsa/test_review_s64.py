"""Review of session 64's change (fd34097..): the cases it refused or misnamed.

- ``calibrate_study(fixed=)``: one dict for every model was refused ("the models sharing E hold
  it at different values") where the models' design ranges of the shared parameter differ
  within the 1e-12 the study's layout accepts (the same native value reads a unit value an ulp
  or so apart);
- ``SimData``'s resolution check read the largest |y| of every column, so an exactly constant
  large output column (nothing there to round) beside a varying one was refused (31 distinct
  values of 60 named as "near float64's resolution");
- the fast sampler named a held theta rejected by the constraint as "calibrate: ... the initial
  value ...; pass theta_init=", which cannot move a held value (the generic path said "fixed
  theta (held elements)" with the same advice).
"""

import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa import GPMSAError
from tests.gpmsa._calib_cases import two_param_emulator

RUN = {"n_samples": 60, "n_burn": 10, "tune_rounds": 3, "tune_levels": 4}


def _study_emulator(t_max: float):
    t = np.linspace(0.1, t_max, 12)[:, None]
    x = np.tile([[0.0], [1.0]], (6, 1))
    sim = gpmsa.SimData(x=x, t=t, y=(x + 2 * t), t_names=["E"])
    prm = {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [1e4], "lamWOs": [1e4]}
    return gpmsa.Emulator.from_params(sim, prm)


def _study(emus, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gpmsa.calibrate_study(emus, [[[0.5]], [[0.2]]], [[1.5], [1.2]], shared=["E"],
                                     seed=1, **{**RUN, **kw})  # fmt: skip


def test_one_fixed_dict_holds_a_shared_element_of_models_whose_ranges_differ_by_rounding():
    a, b = _study_emulator(0.9), _study_emulator(0.9 * (1 + 3e-13))
    assert a.standardizer.t_max[0] != b.standardizer.t_max[0]
    _study([a, b])  # the study takes the two models (their ranges agree to 1e-12)
    study = _study([a, b], fixed={"theta": {"E": 0.5}})
    assert np.allclose(study.posterior.samples["E"], 0.5, rtol=1e-12, atol=0)
    assert study.posterior.sd("E") == 0.0
    with pytest.raises(GPMSAError, match="the models sharing E hold it at different values"):
        _study([a, b], fixed=[{"theta": {"E": 0.5}}, {"theta": {"E": 0.5 + 1e-9}}])


def test_a_constant_large_output_column_beside_a_varying_one_is_not_a_resolution_problem():
    rng = np.random.default_rng(0)
    x, t = rng.random(30), rng.random(30)
    f = np.sin(3 * x) + t
    sim = gpmsa.SimData(x=x, t=t, y=np.column_stack([np.full(30, 1e14), f]))
    assert sim.y.shape == (30, 2)
    # a large column that varies (by its rounding) is still refused, naming its values
    with pytest.raises(GPMSAError, match=r"y varies by only sd .* 3 distinct values in 30"):
        gpmsa.SimData(x=x, t=t, y=np.column_stack([1e9 + 1e-7 * f, np.full(30, 1.0)]))
    with pytest.raises(GPMSAError, match="near float64's resolution"):
        gpmsa.SimData(x=x, t=t, y=np.column_stack([np.full(30, 1e14) + 1e-2 * f, f]))


@pytest.mark.parametrize("engine", [{}, {"fast": False}], ids=["fast", "numpy"])
def test_a_held_theta_the_constraint_rejects_is_named_with_its_way_out(engine):
    emu, xo, yo = two_param_emulator(), [[0.3], [0.7]], [[0.9], [1.2]]
    above = lambda t: t[0] > 0.5  # noqa: E731
    with pytest.raises(GPMSAError, match=r"^fixed theta \(held elements\): the theta constraint "
                       r"rejects .*a=0\.3.*hold them inside the allowed region, or pass "
                       "theta_init="):  # fmt: skip
        gpmsa.calibrate(emu, xo, yo, fixed={"theta": {"a": 0.3}}, constraint=above, **RUN,
                        **engine)  # fmt: skip
    with pytest.raises(GPMSAError, match=r"^fixed theta: the theta constraint rejects the fixed "
                       r"value a=0\.3, b=0\.6; fix theta inside the allowed region"):  # fmt: skip
        gpmsa.calibrate(emu, xo, yo, fixed={"theta": [0.3, 0.6]}, constraint=above, **RUN,
                        **engine)  # fmt: skip


def test_a_studys_held_discrepancy_elements_are_named_as_its_posterior_names_them():
    # settings["held"] (not judged for convergence) from the masks gpmsa.calibrate uses too
    from test_discrepancy_groups_s61 import BASIS, GROUPS, _data, _emulator

    _, obs = _data()
    emu = _emulator()
    run = {"n_samples": 40, "n_burn": 10, "tune_rounds": 2, "tune_levels": 3, "n_chains": 2}
    cases = [
        ({"lamVz": {1: 1e6}}, ["lamVz[1][model0]", "lamVz[1][model1]"]),
        ({"betaV": {(0, 1): 0.5}, "lamOs": 100.0},
         ["lamOs[model0]", "betaV[0,1][model0]", "lamOs[model1]", "betaV[0,1][model1]"]),
        ([{"lamVz": 1e6}, None], ["lamVz[0][model0]", "lamVz[1][model0]"]),
    ]  # fmt: skip
    for fixed, names in cases:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            study = gpmsa.calibrate_study([emu, emu], [obs, obs], None, shared=["t"], seed=1,
                                          discrepancy=BASIS, discrepancy_groups=GROUPS,
                                          fixed=fixed, **run)  # fmt: skip
        assert study.settings["held"] == names
        for name in names:
            assert study.posterior.sd(name) == 0.0


def test_the_fast_sampler_reports_no_step_and_no_acceptance_for_held_elements():
    # before: accept_rate 0.0 (read as a stuck chain) and a width tuned down to 2.8e-4 for a
    # held theta element and lamOs; the numpy, torch and pyro backends report NaN
    emu, xo, yo = two_param_emulator(), [[0.3], [0.7]], [[0.9], [1.2]]
    held = {"theta": {"a": 0.4}, "lamOs": 50.0}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        post = gpmsa.calibrate(emu, xo, yo, seed=1, fixed=held, n_chains=2, **RUN)
        free = gpmsa.calibrate(emu, xo, yo, seed=1, n_chains=2, **RUN)
    rates, widths = np.array(post.info["accept_rate"]), np.array(post.info["step_widths"])
    assert rates.shape == widths.shape == (2, 3)  # a, b, lamOs per chain
    assert np.isnan(rates[:, [0, 2]]).all() and np.isnan(widths[:, [0, 2]]).all()
    assert np.all(rates[:, 1] > 0) and np.all(widths[:, 1] > 0)
    assert np.isfinite(free.info["accept_rate"]).all()  # without fixed= as before
