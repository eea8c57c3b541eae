"""to_arviz keeps the parameters' order: ArviZ 0.x flattens a group with dm-tree where that is
installed (ArviZ 0.19 required it), which sorts a dict's keys, so "GD", "E" came back as "E",
"GD" (in ``arviz.summary``'s rows and the saved file) in such an environment only."""

from __future__ import annotations

import numpy as np
import pytest

from gpmsa.mcmc import diagnostics

az = pytest.importorskip("arviz")


def test_the_posterior_keeps_the_order_of_the_draws_where_arviz_sorts_them(monkeypatch):
    if diagnostics.arviz_major() >= 1:
        pytest.skip("ArviZ 1.x builds a DataTree without dm-tree")
    real = az.from_dict

    def sorting_from_dict(posterior=None, **groups):  # as ArviZ 0.x does with dm-tree
        return real(posterior=dict(sorted(posterior.items())), **groups)

    monkeypatch.setattr(az, "from_dict", sorting_from_dict)
    draws = {"GD": np.zeros((2, 5)), "E": np.ones((2, 5)), "b": np.full((2, 5, 3), 2.0)}
    idata = diagnostics.to_inference_data(draws, log_post=np.zeros((2, 5)), units={"GD": "mm"})
    assert tuple(idata.posterior.data_vars) == ("GD", "E", "b")
    for name, value in draws.items():
        np.testing.assert_array_equal(idata.posterior[name].values, value)
    assert idata.posterior["GD"].attrs["units"] == "mm"
    np.testing.assert_array_equal(idata.sample_stats["lp"].values, np.zeros((2, 5)))
