"""A list of per-experiment discrepancy bases (SEPIA's ``create_D_basis(D_obs=[...])``, GPM/SA's
per-experiment ``obsData(k).Dobs``) for experiments on their own index grids (session 66).

Before: ``discrepancy=[D_0, D_1]`` was refused ("a list of 2 matrices ... is not taken"). Now
fit, calibrate, prepare and full_prediction take it, normalised jointly (one scale: the largest
diag(D_j D_j^T) over the experiments is 1), and a joint fit keeps it in its file."""

import functools
import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa import EmulatorFileError, GPMSAError
from tests.gpmsa.test_file_hostile import read_members, write_members

GRID = np.linspace(0.0, 1.0, 8)
GRIDS = [np.linspace(0.0, 1.0, 5), np.array([0.0, 0.4, 1.0])]  # ragged, the same reach
CENTRES = np.array([0.2, 0.6, 0.9])


def _simulator(x, t):
    return np.exp(-(0.5 + x) * GRID[None]) * t + GRID[None] * x


def _kernels(grids, width=0.2):
    """Gaussian kernels on each experiment's own grid (GPM/SA's Neddermeyer example's kind)."""
    return [np.exp(-0.5 * ((g[:, None] - CENTRES[None]) / width) ** 2) for g in grids]


@functools.cache
def _case():
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(24, 1)), rng.uniform(size=(24, 1))
    data = gpmsa.SimData(x=x, t=t, y=_simulator(x, t), x_names=["x"], t_names=["t"], index=GRID)
    xo = np.array([[0.3], [0.7]])
    ys = [np.interp(g, GRID, _simulator(xo[j : j + 1], 0.4)[0]) + 0.02 for j, g in enumerate(GRIDS)]
    return data, gpmsa.ObsData(xo, ys, index=GRIDS)


def _fit(discrepancy, **kw):
    data, obs = _case()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # short chains
        return gpmsa.fit(data, obs, n_iter=30, tune=False, seed=3, discrepancy=discrepancy, **kw)


@functools.cache
def _kernel_fit():
    return _fit(_kernels(GRIDS), discrepancy_groups=[0, 1, 1])


@pytest.mark.parametrize("kind", ["constant", "linear"])
def test_a_hand_built_list_gives_the_named_kinds_draws(kind):
    ones = [np.ones((g.size, 1)) for g in GRIDS]
    lines = [np.column_stack([o, g]) for o, g in zip(ones, GRIDS, strict=True)]
    per = ones if kind == "constant" else lines
    named, listed = _fit(kind), _fit(per)
    for k in named.draws:
        np.testing.assert_array_equal(named.draws[k], listed.draws[k])
    for k in named.calibration:
        np.testing.assert_array_equal(named.calibration[k], listed.calibration[k])
    assert listed.settings["discrepancy"] == "list"
    assert listed.settings["discrepancy_sha256"] == named.settings["discrepancy_sha256"]


def test_a_list_is_normalised_jointly_and_wrong_ones_are_refused_naming_the_experiment():
    data, obs = _case()
    per = _kernels(GRIDS)
    D = gpmsa.prepare(data, obs, discrepancy=[5.0 * d for d in per]).problem.obs.D
    top = max(np.max(np.sum(d**2, axis=1)) for d in D)
    same = gpmsa.prepare(data, obs, discrepancy=per).problem.obs
    assert gpmsa.model.basis.basis_digest(D) == gpmsa.model.basis.basis_digest(same.D)
    assert top == pytest.approx(1.0, abs=1e-15)
    scale = per[0][0, 0] / D[0][0, 0]  # one scale for every experiment
    np.testing.assert_allclose(D[1] * scale, per[1], rtol=1e-14)
    bad = {
        r"a list of 1 bases for 2 experiments": per[:1],
        r"discrepancy\[1\] \(experiment 1's basis\) must be \(3, p_v\).*got shape \(2, 3\)":
            [per[0], per[1][:2]],
        r"experiment 0's basis\) must be \(5, p_v\).*pass its transpose": [per[0].T, per[1]],
        r"discrepancy\[1\].* has 2 column\(s\) but discrepancy\[0\] has 3": [per[0], per[1][:, :2]],
        r"discrepancy\[1\] \(experiment 1's basis\) must be finite":
            [per[0], np.where(per[1] > 0.5, np.nan, per[1])],
        r"discrepancy bases are all zeros, every experiment's": [0 * per[0], 0 * per[1]],
    }  # fmt: skip
    for message, given in bad.items():
        with pytest.raises(GPMSAError, match=message):
            gpmsa.prepare(data, obs, discrepancy=given)
    with pytest.raises(GPMSAError, match=r"one group per discrepancy basis vector: 3"):
        gpmsa.prepare(data, obs, discrepancy=per, discrepancy_groups=[0, 1])
    # fit_study reads a list as one entry per model (session 76), as calibrate_study does
    with pytest.raises(GPMSAError, match=r"2 entries for 1 models.*per-experiment bases \(a "):
        gpmsa.fit_study([data], [obs], n_iter=5, discrepancy=per)


def test_the_list_round_trips_the_file_and_full_prediction_uses_it(tmp_path):
    emu = _kernel_fit()
    _, obs = _case()
    back = gpmsa.load(emu.save(tmp_path / "d.gpmsa"))
    assert back.settings["discrepancy"] == "list" and back.model_sha256 == emu.model_sha256
    for a, b in zip(emu.discrepancy_bases, back.discrepancy_bases, strict=True):
        np.testing.assert_array_equal(a, b)
    a = gpmsa.full_prediction(emu, obs, [[0.5]], grid=GRIDS[1], n_draws=4, seed=0)
    b = gpmsa.full_prediction(back, obs, [[0.5]], grid=GRIDS[1], n_draws=4, seed=0)
    np.testing.assert_array_equal(a.y, b.y)
    np.testing.assert_allclose(a.D, emu.discrepancy_bases[1], rtol=1e-14)
    with pytest.raises(GPMSAError, match=r"known on their experiments' index grids only.*grid="):
        gpmsa.full_prediction(back, obs, [[0.5]], n_draws=4)
    other = [D + 0.1 for D in _kernels(GRIDS)]
    with pytest.raises(GPMSAError, match="discrepancy basis differs from the one the draws"):
        gpmsa.full_prediction(back, obs, [[0.5]], grid=GRIDS[0], discrepancy=other, n_draws=4)
    with pytest.raises(GPMSAError, match=r"discrepancy=an array differs .*\(a list of per-exp"):
        gpmsa.full_prediction(back, obs, [[0.5]], discrepancy=np.ones((5, 3)), n_draws=4)
    post = gpmsa.calibration_posterior(back)  # the joint fit's own: its kept list (s78)
    kept = gpmsa.full_prediction(back, obs, [[0.5]], posterior=post, grid=GRIDS[0], n_draws=4,
                                 seed=0)  # fmt: skip
    given = gpmsa.full_prediction(back, obs, [[0.5]], posterior=post, grid=GRIDS[0], n_draws=4,
                                  discrepancy=_kernels(GRIDS), seed=0)  # fmt: skip
    np.testing.assert_allclose(kept.y, given.y, rtol=0, atol=1e-12)


def test_calibrate_takes_a_list_and_records_its_kind():
    emu = _kernel_fit()
    _, obs = _case()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        post = gpmsa.calibrate(
            emu, obs, n_samples=40, n_burn=10, tune=False, seed=0,
            discrepancy=_kernels(GRIDS), discrepancy_groups=[0, 1, 1],
        )  # fmt: skip
    assert post.info["discrepancy"] == "list"
    assert post.info["discrepancy_sha256"] == emu.settings["discrepancy_sha256"]
    assert {"lamVz[0]", "lamVz[1]"} <= set(post.samples)
    with pytest.raises(GPMSAError, match=r"a list of 3 bases for 2 experiments"):
        gpmsa.calibrate(emu, obs, n_samples=10, n_burn=2,
                        discrepancy=_kernels([*GRIDS, GRIDS[0]]))  # fmt: skip


def _edit_array(a):
    a["discrepancy_D"] = a["discrepancy_D"][:-1]


@pytest.mark.parametrize(
    ("edit", "field"),
    [
        (lambda m, a: _edit_array(a), r"arrays/discrepancy_D: has 7 rows"),
        (lambda m, a: a["discrepancy_D"].__setitem__((1, 1), np.nan), "must be finite"),
        (
            lambda m, a: m["settings"].__setitem__("obs_lengths", [4, 4]),
            r"split by settings.obs_lengths \[4, 4\], differs from the bases",
        ),
        (lambda m, a: a.__setitem__("discrepancy_D", 2 * a["discrepancy_D"]), "not normalised"),
        (lambda m, a: a.pop("discrepancy_D"), r"'list', but the file holds no arrays/discrepa"),
        (lambda m, a: m["settings"].__setitem__("discrepancy", "given"), r"but it is 'given'"),
    ],
)
def test_a_hostile_list_record_is_refused(tmp_path, edit, field):
    manifest, arrays = read_members(_kernel_fit().save(tmp_path / "d.gpmsa"))
    edit(manifest, arrays)
    path = write_members(tmp_path / "edit.gpmsa", manifest, arrays)
    with pytest.raises(EmulatorFileError, match=field):
        gpmsa.load(path)
