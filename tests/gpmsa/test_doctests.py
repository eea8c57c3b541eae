"""The examples in the docstrings of the prediction, sensitivity, cross-validation and plotting
modules run and give what they show (``doctest``; the default ``python -m pytest`` runs them)."""

import doctest
import importlib
import warnings

import pytest

MODULES = [
    "gpmsa.predictive.emulator_draws",
    "gpmsa.predictive.full",
    "gpmsa.predictive.joint",
    "gpmsa.predictive.sobol",
    "gpmsa.predictive.crossval",
    "gpmsa.plots.data",
    "gpmsa.plots.mcmc",
    "gpmsa.plots.observations",
    "gpmsa.plots.emulator",
    "gpmsa.plots.prediction",
    "gpmsa.plots.rho",
    "gpmsa.plots.sensitivity",
    "gpmsa.model.categorical",
    "gpmsa.model.mean_basis",
    "gpmsa.model.constraints",
    "gpmsa.studies.run",
    "gpmsa.studies.study",
]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    module = importlib.import_module(name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the tiny example fits: designs near their edges
        result = doctest.testmod(module, optionflags=doctest.ELLIPSIS, report=True)
    assert result.attempted > 0, f"{name} has no docstring example"
    assert result.failed == 0, f"{result.failed} of {result.attempted} examples failed in {name}"


def test_every_public_function_has_an_example():
    """Each function exported by gpmsa.predictive (except the older calibrated_predict) and
    gpmsa.plots carries a runnable example."""
    import gpmsa.plots
    import gpmsa.predictive

    names = [(gpmsa.predictive, n) for n in gpmsa.predictive.__all__ if n[0].islower()]
    names += [(gpmsa.plots, n) for n in gpmsa.plots.__all__]
    for package, n in names:
        if n == "calibrated_predict":
            continue
        doc = getattr(package, n).__doc__ or ""
        assert ">>> " in doc, f"{package.__name__}.{n} has no example"
        assert getattr(package, n).__module__ in MODULES


def test_the_study_functions_have_examples():
    import gpmsa

    for fn in (gpmsa.calibrate_study, gpmsa.fit_study, gpmsa.load_study):
        assert ">>> " in (fn.__doc__ or ""), fn.__name__
        assert fn.__module__ in MODULES
