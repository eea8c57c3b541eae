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
