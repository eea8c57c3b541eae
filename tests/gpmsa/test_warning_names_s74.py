"""A fit's ConvergenceWarning names the input each flagged theta and betaU element stands for
("theta[0] (k)", "betaU[0,0] (s)"), as ``gpmsa info`` and calibrate name them (session 74's
walkthrough: a user of four thetas read "theta[2]" and had to count)."""

import warnings

import numpy as np

import gpmsa
from gpmsa.fitting.fit import element_names


def test_a_fits_warning_names_the_inputs():
    rng = np.random.default_rng(0)
    x, t = rng.random((20, 1)), rng.random((20, 1))
    sim = gpmsa.SimData(x, t, np.sin(3 * x[:, 0]) + t[:, 0], x_names=["s"], t_names=["k"])
    obs = gpmsa.ObsData(x=[[0.3], [0.6]], y=[[np.sin(0.9) + 0.4], [np.sin(1.8) + 0.4]])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        gpmsa.fit(sim, obs, n_iter=30, n_chains=2, seed=1, tune=False)
    text = " ".join(str(w.message) for w in caught if w.category is gpmsa.ConvergenceWarning)
    assert "theta[0] (k): R-hat" in text and "betaU[0,0] (s): R-hat" in text
    assert "betaU[1,0] (k): R-hat" in text and "lamUz[0]: R-hat" in text  # no input: as it was


def test_element_names_cover_every_component():
    names = element_names(["s"], ["k", "kind"], 2)
    assert names["theta[1]"] == "kind" and names["betaU[2,1]"] == "kind"
    assert names["betaU[0,1]"] == "s" and "betaU[3,0]" not in names and len(names) == 8
