"""A review of the session's bad-argument and odd-data fixes: valid inputs they refused, and a
far-value warning given for values within their own stated noise.

- names: ``y_names=df.columns`` of a table whose labels are numbers (wavelengths), dates or a
  MultiIndex's tuples was refused, while the same table without names was taken (its labels
  read as text);
- the far-value check named a value beyond the runs at an output element they barely vary
  (scaled columnwise) although its given precision says the value's noise is that large, with
  a false "theta falls back towards its prior";
- a scalar output's ObsData index at its one point: taken by ``gpmsa.fit`` and documented, but
  refused by calibrate and the Calibrator;
- several outputs given without an index: the far value was placed at "output index 2", not
  named by its output.
"""

from __future__ import annotations

import numpy as np
import pytest

import gpmsa
from gpmsa import GPMSAError
from gpmsa.fitting.emulator import Emulator
from tests.gpmsa._far_cases import design as _design
from tests.gpmsa._far_cases import outside_texts as _outside

GRID = np.linspace(0.0, 1.0, 12)
PARAMS_2 = {"betaU": [[1.0, 1.0], [1.5, 1.5]], "lamUz": [1.0, 1.0],
            "lamWs": [2000.0, 2000.0], "lamWOs": [2000.0]}  # fmt: skip
X_OBS = np.array([[0.2], [0.4], [0.7]])


# --- names: a table's own column labels -------------------------------------------------------


def test_names_given_as_a_tables_own_column_labels_are_taken_as_the_table_alone():
    pd = pytest.importorskip("pandas")
    x, t = _design(10)
    y = np.column_stack([x + t, x * t + 1.0, np.sin(t)])
    for labels in ([1.5, 2.0, 2.5], list(pd.date_range("2020-01-01", periods=3))):
        frame = pd.DataFrame(y, columns=labels)
        alone = gpmsa.SimData(x=x, t=t, y=frame)
        named = gpmsa.SimData(x=x, t=t, y=frame, y_names=frame.columns)
        assert named.y_names == alone.y_names == tuple(str(c) for c in labels)
    table = pd.DataFrame(x[:, None], columns=pd.MultiIndex.from_tuples([("in", "v")]))
    sim = gpmsa.SimData(x=table, t=t, y=y, x_names=table.columns)
    assert sim.x_names == gpmsa.SimData(x=table, t=t, y=y).x_names == ("('in', 'v')",)
    for bad, problem in [(None, "NoneType None"), (True, "bool True"),
                         (float("nan"), "float nan"), (b"v", "decode it")]:  # fmt: skip
        with pytest.raises(GPMSAError, match=r"^x_names\[0\] must be a name \(a string\).*"
                                             + problem):  # fmt: skip
            gpmsa.SimData(x=x, t=t, y=y, x_names=[bad])


# --- a far value within its own stated noise ---------------------------------------------------


@pytest.fixture(scope="module")
def columnwise_emulator() -> Emulator:
    """Outputs that every run takes within 1e-3 at s = 0 (and up to about 2 elsewhere), each
    element scaled by its own sd."""
    x, t = _design()
    y = (np.sin(3 * x[:, None] + 2 * GRID) + t[:, None] ** 2 * GRID) * (GRID + 1e-3)
    sim = gpmsa.SimData(x=x, t=t, y=y, index=GRID, y_scale="columnwise")
    return Emulator.from_params(sim, PARAMS_2, n_pc=2)


def _columnwise_obs() -> np.ndarray:
    s = GRID
    clean = (np.sin(3 * X_OBS + 2 * s) + 0.25 * s) * (s + 1e-3)
    return clean + 0.02 * np.random.default_rng(0).standard_normal((3, s.size))  # noise sd 0.02


def test_a_value_within_its_stated_noise_is_not_named(columnwise_emulator):
    """y_obs[1] at s = 0 is -0.046, 126 of that element's sds below every run: with the data's
    precision (noise sd 0.02) that is noise, and the posterior is sharp (t 0.49 +- 0.02)."""
    y = _columnwise_obs()
    obs = gpmsa.ObsData(x=X_OBS, y=y, precision=1 / 0.02**2)
    texts, post = _outside(lambda: gpmsa.Calibrator(columnwise_emulator).update(obs))
    assert texts == [] and post.sd("t0") < 0.05
    # without a precision the noise is taken on the element's own (tiny) scale: then the
    # value does pull theta back to its prior, and is named
    texts, post = _outside(lambda: gpmsa.Calibrator(columnwise_emulator).update(X_OBS, y))
    assert post.sd("t0") > 0.2
    assert len(texts) == 1 and texts[0].startswith("y_obs[1] holds -0.0455686 at output index 0")
    # a missing-value code stays named with the precision given (per value, or a matrix)
    y[2, 6] = -999.0
    for precision in (1 / 0.02**2, [np.full(12, 2500.0)] * 3, [np.eye(12) * 2500.0] * 3):
        obs = gpmsa.ObsData(x=X_OBS, y=y, precision=precision)
        texts, _ = _outside(lambda o=obs: gpmsa.Calibrator(columnwise_emulator).update(o))
        assert len(texts) == 1 and texts[0].startswith("y_obs[2] holds -999 at output index"), texts


# --- a scalar output's one index point ---------------------------------------------------------


@pytest.fixture(scope="module")
def scalar_emulator() -> Emulator:
    x, t = _design()
    sim = gpmsa.SimData(x=x, t=t, y=np.sin(3 * x) + t**2, x_names=["v"], t_names=["k"])
    params = {"betaU": [[1.0], [1.5]], "lamUz": [1.0], "lamWs": [2000.0], "lamWOs": [2000.0]}
    return Emulator.from_params(sim, params)


def test_a_scalar_outputs_one_index_point_is_calibrated_as_without_it(scalar_emulator):
    """ObsData documents a scalar output's index as None or its one point, and gpmsa.fit takes
    it; the Calibrator refused any index ("ObsData index (an output grid) is for a functional
    output")."""
    x = np.array([[0.3], [0.7]])
    y = np.sin(3 * x) + 0.25
    plain = gpmsa.Calibrator(scalar_emulator, seed=0).update(gpmsa.ObsData(x=x, y=y))
    at = gpmsa.Calibrator(scalar_emulator, seed=0).update(gpmsa.ObsData(x=x, y=y, index=[0.0]))
    assert at.summary() == plain.summary()
    with pytest.raises(GPMSAError, match=r"^the index of experiment 0 is 3, but the simulation "
                                         r"output is scalar, one value at index 0: .*leave "
                                         r"ObsData's index out"):  # fmt: skip
        gpmsa.Calibrator(scalar_emulator).update(gpmsa.ObsData(x=x, y=y, index=[3.0]))


# --- several outputs without an index ----------------------------------------------------------


def test_a_far_value_among_several_named_outputs_is_named_by_its_output():
    x, t = _design()
    y = np.column_stack([np.sin(3 * x) + t**2, x * t, np.cos(2 * x) + t, x + t])
    sim = gpmsa.SimData(x=x, t=t, y=y, y_names=["force", "disp", "temp", "p"])
    emu = Emulator.from_params(sim, PARAMS_2, n_pc=2)
    xs = X_OBS[:, 0]
    y_obs = np.column_stack([np.sin(3 * xs) + 0.25, 0.5 * xs, np.cos(2 * xs) + 0.5, xs + 0.5])
    y_obs[1, 2] = -999.0
    texts, _ = _outside(lambda: gpmsa.Calibrator(emu).update(X_OBS, y_obs))
    assert len(texts) == 1
    assert "y_obs[1] holds -999 at output 'temp', " in texts[0], texts[0]
