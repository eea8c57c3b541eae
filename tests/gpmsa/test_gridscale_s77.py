"""``full_prediction(grid_discrepancy=)`` with the scale a joint fit records (settings
"discrepancy_scale", the divisor that normalised a discrepancy basis given as an array or a
list). Before: the fit kept its bases normalised and not their scale, so a saved and loaded fit
could not predict delta on a new grid from its kept list (refused), and a copy of the kept list
(or of a normalised array) was taken as the basis given to the fit: grid_discrepancy= divided by
1, delta 3.3 times too large, silently. A file without the record keeps that behaviour."""

from __future__ import annotations

import functools
import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.io.container import ENVELOPE, read_raw, write_raw
from tests.gpmsa.test_review_rev5_s76 import G0, H_SIM, _kernels

G1 = np.array([4.5, 9.0, 13.5, 18.0, 22.5])
KW = {"seed": 1, "n_draws": 5}


def _sim():
    rng = np.random.default_rng(0)
    r, c = rng.uniform(0.05, 0.45, 20), rng.uniform(0.05, 0.25, 20)
    y = np.sqrt(H_SIM[None, :]) * (0.45 + c[:, None] / r[:, None] * 0.1)
    return gpmsa.SimData(x=r[:, None], t=c[:, None], y=y, index=H_SIM)


@functools.cache
def _fit():
    """test_review_rev5_s76's joint fit: two experiments on their own grids, kernel bases of
    height 3 (normalised by 3.30126)."""
    ys = [np.sqrt(g) * (0.5 + 0.03 / ro) + 0.01 * g / 20 for g, ro in ((G0, 0.1), (G1, 0.2))]
    obs = gpmsa.ObsData(x=[[0.1], [0.2]], y=ys, index=[G0, G1])
    D = [_kernels(G0), _kernels(G1)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.fit(_sim(), obs, n_iter=30, tune=False, seed=0, n_pc=2, discrepancy=D)
    return emu, obs, D


def _on_sim(emu, obs, **kw):
    return gpmsa.full_prediction(emu, obs, [[0.2]], grid=H_SIM, grid_discrepancy=_kernels(H_SIM),
                                 **kw, **KW)  # fmt: skip


def _rewritten(emu, path, edit):
    emu.save(path)
    manifest, arrays = read_raw(path)
    manifest = {k: v for k, v in manifest.items() if k not in ENVELOPE}
    edit(manifest["settings"])
    write_raw(path, manifest, arrays)
    return path


def test_the_fit_records_the_scale_and_a_loaded_fit_predicts_on_a_new_grid(tmp_path):
    emu, obs, D = _fit()
    scale = np.sqrt(max(np.max(np.sum(d**2, axis=1)) for d in D))
    assert emu.settings["discrepancy_scale"] == pytest.approx(scale, rel=1e-15)  # 3.3
    given = _on_sim(emu, obs, discrepancy=D)
    back = gpmsa.load(emu.save(tmp_path / "e.gpmsa"))
    assert back.settings["discrepancy_scale"] == emu.settings["discrepancy_scale"]
    for model in (emu, back):  # the kept list (the default, or passed itself)
        for kept in ({}, {"discrepancy": model.discrepancy_bases}):
            np.testing.assert_array_equal(_on_sim(model, obs, **kept).delta, given.delta)
    on_obs = gpmsa.full_prediction(back, obs, [[0.2]], grid=G0, grid_discrepancy=_kernels(G0),
                                   **KW)  # fmt: skip
    np.testing.assert_array_equal(
        on_obs.delta, gpmsa.full_prediction(back, obs, [[0.2]], grid=G0, **KW).delta
    )


def test_a_normalised_copy_or_a_multiple_of_the_list_is_refused():
    emu, obs, D = _fit()
    copy = [np.array(d) for d in emu.discrepancy_bases]
    for other, own in ((copy, "1"), ([2.0 * d for d in D], "6.60251")):
        with pytest.raises(gpmsa.GPMSAError, match=rf"\(3\.30126, settings\['discrepancy_scale'"
                           rf"\]\), but discrepancy= .* normalises by {own}: .*leave "
                           "discrepancy= at its default"):  # fmt: skip
            _on_sim(emu, obs, discrepancy=other)


def test_a_normalised_copy_of_an_array_basis_is_refused():
    sim = _sim()
    obs = gpmsa.ObsData(x=[[0.1], [0.3]], y=[np.sqrt(G0) * 0.8, np.sqrt(G0) * 0.6], index=G0)
    d = _kernels(G0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.fit(sim, obs, n_iter=20, tune=False, seed=0, n_pc=2, discrepancy=d)
    _on_sim(emu, obs, discrepancy=d)  # the array given to the fit
    normalised = d / np.sqrt(np.max(np.sum(d**2, axis=1)))  # the fit's normalisation
    with pytest.raises(gpmsa.GPMSAError, match="normalises by 1: .*pass the array given to the"):
        _on_sim(emu, obs, discrepancy=normalised)


def test_a_file_without_the_scale_loads_and_says_what_to_pass(tmp_path):
    emu, obs, D = _fit()
    old = gpmsa.load(_rewritten(emu, tmp_path / "e.gpmsa",
                                lambda s: s.pop("discrepancy_scale", None)))  # fmt: skip
    assert "discrepancy_scale" not in old.settings
    with pytest.raises(
        gpmsa.GPMSAError,
        match=r"does not record \(settings\['discrepancy_scale'\], absent from files.*pass "
        "the list given to the fit again",
    ):
        _on_sim(old, obs)
    np.testing.assert_array_equal(_on_sim(old, obs, discrepancy=D).delta,
                                  _on_sim(emu, obs, discrepancy=D).delta)  # fmt: skip


@pytest.mark.parametrize("value", [0.0, -3.3, "3.3", True, None])
def test_a_damaged_scale_is_refused_on_loading(tmp_path, value):
    emu, _, _ = _fit()
    path = _rewritten(emu, tmp_path / "e.gpmsa", lambda s: s.update(discrepancy_scale=value))
    with pytest.raises(
        gpmsa.EmulatorFileError, match="settings.discrepancy_scale: must be a finite number > 0"
    ):
        gpmsa.load(path)


def test_a_continuation_given_the_kept_list_keeps_the_sources_scale():
    emu, obs, D = _fit()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        more = gpmsa.fit(_sim(), obs, n_iter=4, init=emu, discrepancy=emu.discrepancy_bases,
                         n_pc=2, seed=2)  # fmt: skip
    assert more.settings["discrepancy_scale"] == emu.settings["discrepancy_scale"]
    np.testing.assert_allclose(_on_sim(more, obs).delta,
                               _on_sim(more, obs, discrepancy=D).delta, rtol=1e-12)  # fmt: skip


def test_a_continuation_of_a_file_without_the_scale_records_none_for_the_kept_list(tmp_path):
    """The kept list is normalised (scale 1) and the source's scale unknown: recording 1 would
    divide grid_discrepancy= wrongly; the list given to the fit records its own."""
    emu, obs, D = _fit()
    old = gpmsa.load(_rewritten(emu, tmp_path / "e.gpmsa",
                                lambda s: s.pop("discrepancy_scale", None)))  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        kept, given = (gpmsa.fit(_sim(), obs, n_iter=4, init=old, discrepancy=d, n_pc=2, seed=2)
                       for d in (old.discrepancy_bases, D))  # fmt: skip
    assert "discrepancy_scale" not in kept.settings
    assert given.settings["discrepancy_scale"] == emu.settings["discrepancy_scale"]
