"""The pyro model's log density is the numpy reference log posterior (betas sampled as rho)."""

import numpy as np
import pytest

pyro = pytest.importorskip("pyro")
torch = pytest.importorskip("torch")
pb = pytest.importorskip("gpmsa.backends.pyro_backend")


@pytest.mark.parametrize("case", ["road-joint", "multi-discrepancy", "road-calibration"])
def test_model_log_density_equals_numpy_log_posterior(case):
    from _backend_cases import multi_problem, road_problem

    from gpmsa.model.likelihood import log_posterior

    if case == "multi-discrepancy":
        prob = multi_problem("constant").problem
    else:
        prob = road_problem(True).problem
    if case == "road-calibration":
        fixed = {"betaU": [[0.92], [0.35]], "lamUz": [0.45], "lamWs": [165.0], "lamWOs": [837.0]}
        prob = prob.with_init(fixed, fixed=frozenset(fixed))
    model = pb.PyroModel(prob)
    rng = np.random.default_rng(1)
    for _ in range(3):
        params = {}
        for name, val in prob.init.items():
            v = val if name in prob.fixed else val * rng.uniform(0.7, 1.3, val.shape)
            params[name] = np.clip(v, 0.05, 0.95) if name == "theta" else v
        sites = {
            (f"{k}_rho" if k in ("betaU", "betaV") else k): torch.as_tensor(
                np.exp(-v / 4) if k in ("betaU", "betaV") else v
            )
            for k, v in params.items()
            if k not in prob.fixed
        }
        trace = pyro.poutine.trace(pyro.poutine.condition(model, data=sites)).get_trace()
        np.testing.assert_allclose(
            float(trace.log_prob_sum()), log_posterior(prob, params), rtol=1e-9, atol=1e-7
        )


@pytest.mark.parametrize(
    ("options", "match"),
    [
        ({"n_iter": 3}, r"needs at least 4 draws a chain .* got n_iter = 3"),
        ({"n_warmup": 2.7}, "n_warmup must be an integer >= 1, got 2.7"),
        ({"n_warmup": -5}, "n_warmup must be an integer >= 1, got -5"),
        ({"max_tree_depth": 0}, "max_tree_depth must be an integer >= 1, got 0"),
        ({"target_accept": "0.5"}, "target_accept must be a number, got str"),
        ({"target_accept": 1.0}, r"target_accept must be a number in \(0, 1\), got 1.0"),
        ({"num_threads": 0}, "num_threads must be an integer >= 1, got 0"),
        ({"jit": "no"}, "jit must be True or False"),
    ],
)
def test_nuts_options_are_checked_before_sampling(options, match):
    from _backend_cases import road_problem

    from gpmsa import GPMSAError

    with pytest.raises(GPMSAError, match=match):
        pb.sample(road_problem(True).problem, **{"n_iter": 10, "seed": 0, **options})


def test_a_chain_that_never_moves_is_refused_not_returned():
    """With tune=False NUTS keeps a unit step size; on the road case it accepts no step, and
    the draws would all be the starting values."""
    from _backend_cases import road_problem

    from gpmsa import GPMSAError

    with pytest.raises(GPMSAError, match=r"NUTS never left its starting point in 20 draws .* "
                                         r"use tune=True"):  # fmt: skip
        pb.sample(road_problem(True).problem, n_iter=20, seed=0, tune=False)
