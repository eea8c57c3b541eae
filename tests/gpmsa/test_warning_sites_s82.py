"""gpmsa's warnings that kept a fixed stacklevel point at the user's line: a posterior's theta
outside the emulator's domain pointed inside gpmsa (calibrated_predict's and full_prediction's
own lines), and a wrapper marked with ``__gpmsa_wrapper__`` was not passed over by the
prediction inputs' and calibrate_study's warnings (they stopped at the wrapper's line)."""

import warnings
from pathlib import Path

import numpy as np
from _calib_cases import road_emulator, road_obs, with_draws

import gpmsa
from tests.gpmsa import _study_cases as sc


def sites(call) -> set[tuple[str, str]]:
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        call()
    return {(w.category.__name__, w.filename) for w in got}


def _beyond(emu) -> float:
    """A GD 5% of the domain's width past its top: a warning, not a refusal."""
    lo, hi = float(emu.standardizer.t_min[0]), float(emu.standardizer.t_max[0])
    return hi + 0.05 * (hi - lo)


def test_a_posterior_theta_outside_the_domain_warns_at_the_users_line():
    emu = with_draws(road_emulator(), 3)
    x, y = road_obs()
    post = gpmsa.Posterior(samples={"GD": np.full(20, _beyond(emu)), "lamOs": np.full(20, 10.0)})
    obs = gpmsa.ObsData(x=np.array(x), y=np.array(y))
    here = {("ExtrapolationWarning", __file__)}
    assert sites(lambda: gpmsa.calibrated_predict(emu, post, x)) == here
    full = sites(lambda: gpmsa.full_prediction(emu, obs, x, posterior=post, n_draws=2, seed=0))
    assert full == here, full


def _marked_wrapper():
    """A module marked as gpmsa's wrapper whose functions call gpmsa's."""
    code = (
        "import gpmsa\n"
        "__gpmsa_wrapper__ = True\n"
        "def predict(emu, x, t):\n"
        "    return gpmsa.emulator_prediction(emu, x, t, n_draws=2, seed=0)\n"
        "def study(*args, **kwargs):\n"
        "    return gpmsa.calibrate_study(*args, **kwargs)\n"
    )
    names = {"__name__": "wrapper_s82_sites"}
    exec(compile(code, "/wrapper_s82_sites.py", "exec"), names)
    return names


def test_a_marked_wrapper_is_passed_over_by_the_prediction_and_study_warnings():
    wrapper = _marked_wrapper()
    emu = with_draws(road_emulator(), 3)
    lo, hi = float(emu.standardizer.x_min[0]), float(emu.standardizer.x_max[0])
    x = hi + 0.05 * (hi - lo)  # past the x domain too, within the margin
    got = sites(lambda: wrapper["predict"](emu, [[x]], [[_beyond(emu)]]))
    assert got == {("ExtrapolationWarning", __file__)}, got
    small = sc.emulator()
    inside = float(sc.simulator(0.5, 0.4))
    got = sites(lambda: wrapper["study"](
        [small, small], [[[0.5]], [[0.5]]], [[inside], [1e3 * inside]], labels=["a", "b"],
        shared=["t"], n_samples=60, n_burn=10, tune=False, seed=1,
    ))  # fmt: skip
    assert ("OutsideEmulatorWarning", __file__) in got
    assert all(name == __file__ for _, name in got), got


def test_the_internals_errors_row_names_every_warning_class():
    """docs/internals.md says every warning gpmsa issues is one of the classes its errors row
    names; BasisWarning and ReductionWarning were missing from it."""
    row = next(
        line
        for line in (Path(gpmsa.__file__).parents[1] / "docs" / "internals.md")
        .read_text(encoding="utf-8")
        .splitlines()
        if line.startswith("| `errors.py` | `GPMSAError")
    )
    classes = [n for n, c in vars(gpmsa.errors).items() if isinstance(c, type)
               and issubclass(c, Warning)]  # fmt: skip
    assert len(classes) >= 14
    assert [n for n in classes if f"`{n}(" not in row] == []
