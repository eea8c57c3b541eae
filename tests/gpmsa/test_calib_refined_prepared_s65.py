"""Session 65: a one-parameter Calibrator prepares its predictor on the nodes of the usual
refinement (the whole axis at twice the nodes), so an update that refines so makes no dense
solves (the road case: 2.5% of updates, 2.4 ms each before, ~1.5 ms now), with the posterior of
the dense solves to round-off; other refinements still solve densely."""

import numpy as np
import pytest
from _calib_cases import road_emulator, two_param_emulator

import gpmsa
from gpmsa.calibration.grid import whole_refined_axis
from gpmsa.calibration.model import FixedGP


def _windows(emu, n: int, seed: int = 0):
    """n windows across the domain (v uniform, f from the road case's formula, 5% noise)."""
    rng = np.random.default_rng(seed)
    v = rng.uniform(*emu.domain["v"], n)
    gd = rng.uniform(*emu.domain["GD"], n)
    return v, 0.02 * gd * v**1.6 * (1 + 0.05 * rng.standard_normal(n))


def _refining(cal, emu, n: int = 3):
    v, f = _windows(emu, 600)
    found = []
    for vi, fi in zip(v, f, strict=True):
        if cal.update([[vi]], [[fi]]).info["n_nodes"] == cal._refined[0].size:
            found.append((vi, fi))
            if len(found) == n:
                return found
    raise AssertionError("no window refined over the whole axis")


def test_the_usual_refinement_needs_no_dense_solve_and_agrees_with_it(monkeypatch):
    emu = road_emulator()
    cal = gpmsa.Calibrator(emu, seed=0)
    axis, predictors = cal._refined
    np.testing.assert_array_equal(axis, whole_refined_axis(cal._axes[0]))
    assert axis.size == 2 * cal.n_grid - 1 and len(predictors) == 1
    windows = _refining(cal, emu)
    dense = gpmsa.Calibrator(emu, seed=0)
    dense._refined = None  # the refinement by dense solves, as before
    want = [dense.update([[v]], [[f]]) for v, f in windows]

    def no_solve(*args, **kwargs):
        raise AssertionError("a dense solve on the prepared refinement")

    monkeypatch.setattr(FixedGP, "predict", no_solve)
    for (v, f), ref in zip(windows, want, strict=True):
        post = cal.update([[v]], [[f]])
        assert post.info["refined"] and post.info["n_nodes"] == axis.size
        np.testing.assert_array_equal(post.grids["GD"].nodes, ref.grids["GD"].nodes)
        sd = ref.sd("GD")
        assert post.mean("GD") == pytest.approx(ref.mean("GD"), abs=1e-10 * sd)
        assert post.sd("GD") == pytest.approx(sd, rel=1e-10)
        assert post.prob_above("GD", 350.0) == pytest.approx(ref.prob_above("GD", 350.0), abs=1e-12)
        assert post.info["log_evidence"] == pytest.approx(ref.info["log_evidence"], abs=1e-10)


def test_other_refinements_and_grids_solve_densely():
    emu = road_emulator()
    cal = gpmsa.Calibrator(emu, seed=0)
    v, f = _refining(cal, emu, 1)[0]
    # a prior that holds the posterior to part of the axis: another refined axis, solved densely
    narrow = cal.update([[v]], [[f]], prior=lambda gd: np.where(gd < 450.0, 0.0, -np.inf))
    assert narrow.info["refined"] and narrow.info["n_nodes"] != cal._refined[0].size
    assert narrow.grids["GD"].nodes.max() <= 450.0 + 1e-9
    assert gpmsa.Calibrator(two_param_emulator())._refined is None  # two parameters: none
