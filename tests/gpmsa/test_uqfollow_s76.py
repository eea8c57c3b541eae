"""A UQ engineer's follow-up walkthrough (session 76): a calibration piled against a bound of
the emulator's domain is flagged (offline only); a single name for a vector output; concise
reprs of SimData and ObsData; ``gpmsa calibrate --y-csv``."""

from __future__ import annotations

import re
import warnings
from functools import cache

import numpy as np
import pytest

import gpmsa
from gpmsa.mcmc.bounds import at_bound

GRID = np.linspace(0.0, 1.0, 40)
X_OBS = np.array([[0.3], [0.7]])


def simulator(x: np.ndarray, c: np.ndarray) -> np.ndarray:
    """A 40-value output (n, 40) at x (n,) and c (n,)."""
    return (1.0 + c[:, None]) * np.sin(np.pi * GRID * (0.5 + x[:, None])) + 0.3 * c[:, None]


@cache
def sim_data() -> gpmsa.SimData:
    """40 runs, c in [0.1, 1] (both ends run)."""
    rng = np.random.default_rng(1)
    x, c = rng.uniform(0, 1, 40), rng.uniform(0.1, 1.0, 40)
    c[:2] = 0.1, 1.0
    return gpmsa.SimData(x=x[:, None], t=c[:, None], y=simulator(x, c), index=GRID,
                         x_names=["x"], t_names=["c"])  # fmt: skip


@cache
def emulator() -> gpmsa.Emulator:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        return gpmsa.fit(sim_data(), n_iter=1500, seed=0, n_pc=2)


def observed(c_unit: float, seed: int = 0) -> np.ndarray:
    """Observations (2, 40) at X_OBS of the truth c at ``c_unit`` of the domain's width."""
    truth = np.full(2, 0.1 + 0.9 * c_unit)
    noise = np.random.default_rng(seed).standard_normal((2, 40))
    return simulator(X_OBS[:, 0], truth) + 0.01 * noise


def calibrate(y, **kw) -> tuple[gpmsa.Posterior, list]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        post = gpmsa.calibrate(emulator(), X_OBS, y, seed=0, **kw)
    return post, [w for w in caught if issubclass(w.category, gpmsa.AtBoundWarning)]


@pytest.mark.parametrize(("c_unit", "side", "bound"), [(1.3, "upper", "1"), (-0.3, "lower", "0.1")])
def test_calibrate_flags_a_posterior_piled_against_the_domain_bound(c_unit, side, bound):
    """Before: c = 0.9966 +- 0.0034 on [0.1, 1] (truth 1.27) with no word of the bound."""
    post, caught = calibrate(observed(c_unit))
    assert post.info["at_bound"] == {"c": side}
    assert len(caught) == 1
    text = str(caught[0].message)
    assert f"c at its {side} bound {bound} (domain [0.1, 1]" in text
    assert "Widen the design" in text and "discrepancy" in text
    assert issubclass(gpmsa.AtBoundWarning, gpmsa.OutsideEmulatorWarning)


@pytest.mark.parametrize("c_unit", [0.5, 0.97, 0.03])
def test_calibrate_inside_or_near_an_edge_is_not_flagged(c_unit):
    post, caught = calibrate(observed(c_unit))
    assert post.info["at_bound"] == {} and not caught
    if c_unit == 0.97:  # it does approach the edge: a quarter of the draws within 1 %
        assert 0.05 < np.mean(post.samples["c"] >= 0.991) < 0.5


def test_a_held_element_is_not_judged():
    held = {"theta": {"c": 0.999}}  # inside the band at the upper bound
    post, caught = calibrate(observed(1.3), fixed=held, n_samples=400, n_burn=100)
    assert np.all(post.samples["c"] == 0.999)
    assert post.info["at_bound"] == {} and not caught


def test_the_online_calibrator_stays_silent():
    for method in ("grid", "mcmc"):
        cal = gpmsa.Calibrator(emulator(), method=method, seed=0)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            post = cal.update(X_OBS, observed(1.3))
        assert not [w for w in caught if issubclass(w.category, gpmsa.AtBoundWarning)]
        assert post.mean("c") > 0.99  # piled up, yet not flagged online
        assert "at_bound" not in post.info


def test_a_categorical_element_has_no_such_bound():
    rng = np.random.default_rng(2)
    x = rng.random((45, 1))
    t = np.column_stack([rng.uniform(0, 1, 45), np.arange(45) % 3])
    sim = gpmsa.SimData(x, t, np.sin(3 * x[:, 0]) + t[:, 0] + 0.5 * t[:, 1],
                        t_names=["k", "kind"], t_categorical=["kind"])  # fmt: skip
    emu = gpmsa.Emulator.from_params(sim, {"betaU": [[1.0], [1.0], [1.0]], "lamUz": [1.0],
                                           "lamWs": [5000.0], "lamWOs": [5000.0]})  # fmt: skip
    xo = np.linspace(0.1, 0.9, 6)[:, None]
    yo = np.sin(3 * xo[:, 0]) + 0.5 + 0.5 * 2 + 0.01 * rng.standard_normal(6)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        post = gpmsa.calibrate(emu, xo, yo, seed=0, n_samples=1500, n_burn=300)
    assert np.mean(post.samples["kind"] == 2.0) > 0.9  # at its top level
    assert post.info["at_bound"] == {}
    assert not [w for w in caught if issubclass(w.category, gpmsa.AtBoundWarning)]


def test_joint_fit_flags_it_and_the_calibration_posterior_records_it():
    obs = gpmsa.ObsData(x=X_OBS, y=observed(1.3), index=GRID)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        emu = gpmsa.fit(sim_data(), obs, n_iter=600, seed=0, n_pc=2)
    bound = [w for w in caught if issubclass(w.category, gpmsa.AtBoundWarning)]
    assert len(bound) == 1 and "gpmsa.fit" in str(bound[0].message)
    assert "c at its upper bound 1" in str(bound[0].message)
    assert gpmsa.calibration_posterior(emu).info["at_bound"] == {"c": "upper"}


def test_the_rule_is_half_the_draws_within_one_percent_of_the_width():
    lo, hi = [0.1], [1.0]  # the band: c >= 0.991 (upper), c <= 0.109 (lower)
    assert at_bound({"c": np.array([0.5, 0.991, 0.995, 1.0])}, ["c"], lo, hi) == {"c": "upper"}
    assert at_bound({"c": np.array([0.5, 0.6, 0.995, 1.0])}, ["c"], lo, hi) == {"c": "upper"}
    assert at_bound({"c": np.array([0.5, 0.6, 0.7, 1.0])}, ["c"], lo, hi) == {}
    assert at_bound({"c": np.array([0.1, 0.1, 0.5, 0.6])}, ["c"], lo, hi) == {"c": "lower"}
    assert at_bound({"c": np.array([0.1, 0.1, 0.5, 0.6])}, ["c"], lo, hi, skip={"c"}) == {}


def test_one_name_for_a_functional_output_is_refused_with_how_to_name_it():
    """Before: "y_names must have 40 entries, got 1: ('disp',)" and no word of how."""
    data = sim_data()
    with pytest.raises(gpmsa.GPMSAError) as err:
        gpmsa.SimData(x=data.x, t=data.t, y=data.y, index=GRID, y_names=["disp"])
    text = str(err.value)
    assert "y_names must have 40 entries, got 1" in text
    assert '[f"disp{k}" for k in range(40)]' in text and "y_obs tables" in text
    names = [f"disp{k}" for k in range(40)]  # as advised: accepted
    assert gpmsa.SimData(x=data.x, t=data.t, y=data.y, y_names=names).y_names == tuple(names)


def test_simdata_and_obsdata_reprs_are_concise():
    """Before: every array printed (a 40-run x 40-output SimData: thousands of characters)."""
    data = sim_data()
    text = repr(data)
    assert text == str(data) and len(text) < 200
    assert text.startswith("SimData(40 runs; x: x [") and "t: c [0.1, 1]" in text
    assert "y: 40 outputs [" in text and text.endswith("on index [0, 1])")
    obs = gpmsa.ObsData(x=X_OBS, y=observed(0.5), index=GRID, precision=4.0)
    assert repr(obs).startswith("ObsData(2 experiments; x: x_obs[:, 0] [0.3, 0.7]; y: 40 value")
    assert repr(obs).endswith("; index given; precision given)")
    ragged = gpmsa.ObsData(y=[np.ones(3), np.arange(5.0)], index=[GRID[:3], GRID[:5]])
    text = "ObsData(2 experiments; x: none; y: 3 to 5 value(s) each [0, 4]; index given)"
    assert repr(ragged) == text
    same = gpmsa.SimData(x=data.x, t=data.t, y=data.y)
    assert data == data and data != same  # equality: identity, as before


@pytest.fixture(scope="module")
def emu_file(tmp_path_factory):
    return str(emulator().save(tmp_path_factory.mktemp("emu") / "disp.gpmsa"))


def _cli(capsys, *args) -> tuple[int, str, str]:
    from gpmsa.cli.main import main

    code = main(["calibrate", *args])
    out, err = capsys.readouterr()
    return code, out, err


def test_cli_reads_a_functional_observation_from_a_csv(emu_file, tmp_path, capsys):
    """Before: 40 --y flags (argparse refused --y-csv)."""
    y = observed(0.5)[0]
    row, column = tmp_path / "row.csv", tmp_path / "column.txt"
    row.write_text(",".join(repr(float(v)) for v in y) + "\n")
    np.savetxt(column, y)  # one value per line
    outs = []
    for path in (row, column):
        code, out, err = _cli(capsys, emu_file, "--x", "x=0.3", "--y-csv", str(path), "--json",
                              "--seed", "1")  # fmt: skip
        assert code == 0, err
        outs.append(json_posterior(out))
    assert outs[0] == outs[1]
    pairs = [f"--y=y{k}={v!r}" for k, v in enumerate(y.tolist())]
    code, out, _ = _cli(capsys, emu_file, "--x", "x=0.3", *pairs, "--json", "--seed", "1")
    assert code == 0 and json_posterior(out) == outs[0]  # the same as 40 --y flags
    named = tmp_path / "named.csv"  # a header row: read by name, in any order
    named.write_text(",".join(f"y{k}" for k in range(39, -1, -1)) + "\n"
                     + ",".join(repr(float(v)) for v in y[::-1]) + "\n")  # fmt: skip
    code, out, _ = _cli(capsys, emu_file, "--x", "x=0.3", "--y-csv", str(named), "--json",
                        "--seed", "1")  # fmt: skip
    assert code == 0 and json_posterior(out) == outs[0]


def json_posterior(out: str) -> dict:
    import json

    record = json.loads(out)
    return {"y": record["y"], "posterior": record["posterior"]}


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (
            "1,2,3\n",
            r"1 row\(s\) x 3 column\(s\) of values; the file's outputs are 40 \(y0, y1, "
            r"\.\.\., y39\)",
        ),
        ("1," * 39 + "abc\n", r"line 1, column 40 'abc' is not a number"),
        ("1," * 39 + "nan\n", r"line 1, column 40 'nan' is not a finite number"),
        ("1,,3\n", r"line 1, column 2 is empty \(a missing value\?\)"),
        ("1," * 39 + "1\n" + "1," * 38 + "1\n", r"line 2 has 39 fields, line 1 40"),
        (("1," * 39 + "1\n") * 2, r"2 row\(s\) x 40 column\(s\).*calibrates on one observation"),
        ("# nothing\n\n", r"holds no values"),
        ("a,b\n1,2\n", r"the header row must name the file's outputs .*unknown \['a', 'b'\]"),
    ],
)
def test_cli_refuses_a_bad_csv_naming_the_problem(emu_file, tmp_path, capsys, text, message):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    code, out, err = _cli(capsys, emu_file, "--x", "x=0.3", "--y-csv", str(path))
    assert code == 2 and not out
    assert re.search(message, err), err


def test_cli_y_csv_and_y_together_or_neither(emu_file, tmp_path, capsys):
    path = tmp_path / "y.csv"
    path.write_text(",".join(["1.0"] * 40))
    code, _, err = _cli(capsys, emu_file, "--x", "x=0.3", "--y-csv", str(path), "--y", "y0=1")
    assert code == 2 and "not both" in err
    code, _, err = _cli(capsys, emu_file, "--x", "x=0.3")
    assert code == 2 and "or --y-csv PATH: the 40 values in one row or one column" in err
    code, _, err = _cli(capsys, emu_file, "--x", "x=0.3", "--y-csv", str(tmp_path / "none.csv"))
    assert code == 2 and "cannot read it (FileNotFoundError" in err
