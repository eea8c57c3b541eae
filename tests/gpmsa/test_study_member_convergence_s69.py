"""``fit_study`` judges each model's emulator parameters for convergence, as ``gpmsa.fit`` does:
the study's own record covers only theta, lamOs and the hyperparameters, and chains whose lamWs
lay apart (R-hat 2-3) were reported neither in a warning nor in the members' records."""

import warnings
from functools import cache

import numpy as np
from _backend_cases import multi_data

import gpmsa


@cache
def _study() -> tuple[gpmsa.Study, list[str]]:
    sim, obs = multi_data()
    _, obs_b = multi_data(1)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        study = gpmsa.fit_study([sim, sim], [obs, obs_b], labels=["a", "b"], shared=["t0"],
                                n_iter=150, n_chains=2, seed=2, tune_rounds=2,
                                tune_levels=5)  # fmt: skip
    texts = [str(w.message) for w in caught if issubclass(w.category, gpmsa.ConvergenceWarning)]
    return study, texts


def test_each_member_records_the_convergence_of_what_it_sampled():
    study, _ = _study()
    for member in study.members:
        record = member.convergence
        assert record is not None
        assert record["n_chains"] == 2 and record["n_draws"] == 120
        for name in ("betaU", "lamUz", "lamWs", "lamWOs", "theta", "lamOs"):
            np.testing.assert_array_equal(record["rhat"][name], member.diagnostics[name]["rhat"])
        assert not record["converged"]


def test_unconverged_emulator_parameters_are_named_in_a_warning():
    study, texts = _study()
    for label, member in zip(study.labels, study.members, strict=True):
        emulator_flags = [el for el in member.convergence["flagged"]
                          if not el.startswith(("theta", "lamOs"))]  # fmt: skip
        assert "lamWs[0]" in emulator_flags  # ESS 5, R-hat 2-3 over short chains
        mine = [t for t in texts if f"model {label!r}" in t]
        assert len(mine) == 1
        for el in emulator_flags:
            assert f"{el}: " in mine[0]
        assert "theta" not in mine[0] and "lamOs" not in mine[0]  # the study's warning names them
    assert sum("gpmsa.fit_study:" in t for t in texts) == 1
