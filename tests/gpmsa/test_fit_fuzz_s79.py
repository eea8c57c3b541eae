"""Bad arguments to the fit side (SimData, ObsData, gpmsa.fit), found by a systematic fuzz: each
is refused by a GPMSAError naming the argument and the problem, never a TypeError from inside a
backend, a crash of torch's thread pool, a repr kept as a name or an index silently ignored."""

import re

import numpy as np
import pytest

import gpmsa
from gpmsa import GPMSAError

pytestmark = pytest.mark.filterwarnings("ignore::gpmsa.ConvergenceWarning")  # 20 sweeps

GRID = np.linspace(0.0, 1.0, 6)
X_OBS = np.array([[0.3], [0.7]])
RUN = {"n_iter": 20, "tune": False, "seed": 0}


def _design():
    rng = np.random.default_rng(0)
    return rng.uniform(size=(12, 1)), rng.uniform(size=(12, 1))


def _scalar_sim() -> gpmsa.SimData:
    x, t = _design()
    return gpmsa.SimData(x=x, t=t, y=x + t**2)


def _vector_sim() -> gpmsa.SimData:
    x, t = _design()
    y = np.outer(x[:, 0] + t[:, 0], 1.0 + GRID) + 0.3 * np.outer(t[:, 0] ** 2, GRID**2)
    return gpmsa.SimData(x=x, t=t, y=y, index=GRID)


def _vector_obs(**kw) -> gpmsa.ObsData:
    return gpmsa.ObsData(**{"x": X_OBS, "y": np.outer(X_OBS[:, 0] + 0.4, 1.0 + GRID),
                            "index": GRID, **kw})  # fmt: skip


@pytest.mark.parametrize(
    "attr, value, problem",
    [
        ("t_names", [None], "t_names[0] must be a name (a string), got NoneType None"),
        ("x_names", [["a"]], "x_names[0] must be a name (a string), got list ['a']"),
        ("y_names", [b"y"], "y_names[0] must be a name (a string), got bytes b'y'"),
        ("t_names", [" "], "t_names[0] must be a non-empty name, got ' '"),
        ("x_units", [None], "x_units[0] must be a unit (a string), got NoneType None"),
    ],
)
def test_simdata_refuses_labels_that_are_no_text(attr, value, problem):
    # before: kept as their repr ("None", "['a']", "b'y'") or blank, the names of a posterior
    x, t = _design()
    with pytest.raises(GPMSAError, match="^" + re.escape(problem)):
        gpmsa.SimData(x=x, t=t, y=x + t**2, **{attr: value})
    # text, and integers (a table's column numbers), label the columns as before
    sim = gpmsa.SimData(x=x, t=t, y=x + t**2, x_names=[3], t_names=[np.str_("E")], x_units=[""])
    assert (sim.x_names, sim.t_names, sim.x_units) == (("3",), ("E",), ("",))


def test_a_scalar_outputs_observation_index_is_refused_not_ignored():
    sim, y_obs = _scalar_sim(), X_OBS + 0.25
    with pytest.raises(GPMSAError, match=r"^the index of experiment 0 is 3, but the simulation "
                                         r"output is scalar, one value at index 0: .*leave "
                                         r"ObsData's index out"):  # fmt: skip
        gpmsa.fit(sim, gpmsa.ObsData(x=X_OBS, y=y_obs, index=[3.0]), **RUN)
    # its own one point: the fit without an index, bit for bit
    at = gpmsa.fit(sim, gpmsa.ObsData(x=X_OBS, y=y_obs, index=[0.0]), **RUN)
    plain = gpmsa.fit(sim, gpmsa.ObsData(x=X_OBS, y=y_obs), **RUN)
    np.testing.assert_array_equal(at.calibration["theta"], plain.calibration["theta"])


def test_one_discrepancy_array_for_grids_of_other_lengths_asks_for_a_list():
    obs = _vector_obs(y=[np.linspace(1.0, 2.0, 6), np.linspace(1.0, 1.5, 3)],
                      index=[GRID, GRID[:3]])  # fmt: skip
    with pytest.raises(GPMSAError, match=r"^discrepancy: one basis of shape \(6, 1\) is for the "
                                         r"index grid every experiment shares, but the "
                                         r"experiments' grids have \[6, 3\] values: give a list "
                                         r"of one \(l_j, p_v\) array per experiment"):  # fmt: skip
        gpmsa.fit(_vector_sim(), obs, discrepancy=np.ones((6, 1)), **RUN)
    emu = gpmsa.fit(_vector_sim(), obs, discrepancy=[np.ones((6, 1)), np.ones((3, 1))], **RUN)
    assert [d.shape for d in emu.discrepancy_bases] == [(6, 1), (3, 1)]


def test_an_untuned_pyro_continuation_of_a_metropolis_fit_reaches_nuts():
    # before: TypeError: sample() got an unexpected keyword argument 'proportional_steps'
    pytest.importorskip("pyro")
    sim, obs = _vector_sim(), _vector_obs()
    source = gpmsa.fit(sim, obs, **RUN)  # numpy: its record says how the precisions stepped
    try:
        emu = gpmsa.fit(sim, obs, **RUN, init=source, backend="pyro")
    except GPMSAError as exc:  # NUTS untuned keeps a unit step, which may never move: said so
        assert "with tune=False NUTS keeps a unit step size" in str(exc)
    else:
        assert emu.settings["continued_from"] == source.model_sha256


def test_torch_refuses_a_thread_count_its_pool_cannot_start(monkeypatch):
    # before: torch.set_num_threads(10**9) aborted the process (libgomp out of memory)
    torch = pytest.importorskip("torch")
    asked = []
    monkeypatch.setattr(torch, "set_num_threads", asked.append)  # never start them here
    with pytest.raises(GPMSAError, match=r"^num_threads must be an integer in \[1, \d+\], got "
                                         r"1000000000: torch would start"):  # fmt: skip
        gpmsa.fit(_scalar_sim(), None, **RUN, backend="torch", num_threads=10**9)
    assert asked == []
