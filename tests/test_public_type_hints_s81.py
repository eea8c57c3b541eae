"""The public type hints (the packages ship py.typed, so users' type checkers trust them).

Without a type checker at test time: every public callable's hints resolve at run time
(`typing.get_type_hints`, as pydantic, typeguard and Sphinx read them; a forward reference to a
name the module never binds is a NameError there), and the hints that correct user code needs
say what the functions take and give: a constructor that takes lists, where the docs pass lists
(``SimData(x_names=["v"])``, ``ObsData(x=[[0.3]], precision=[1e4])``,
``Priors(theta_mean=[0.3, 0.5])``, ``FeatureSpec(quantiles=[0.9])``, whose stored fields read
as the tuples they always are); a number for a number and an array for an array
(``Posterior.quantile``, ``Track.gd_at``); a numpy integer as a seed.
"""

from __future__ import annotations

import ast
import dataclasses
import importlib
import inspect
import sys
import textwrap
import typing
from collections.abc import Sequence

import numpy as np
import pytest

import control
import gpmsa
import roadgen
import vehicle

PACKAGES = (gpmsa, control, roadgen, vehicle)
MORE_MODULES = ("control.robot", "control.training", "control.plotting", "control.feature")
LAZY = {"Figure": ("matplotlib.figure", "Figure"), "signal": ("scipy", "signal")}
"""Names a module binds only for type checkers, because importing the packages loads neither
matplotlib nor scipy.signal (tests/test_import_cost.py): resolved here by importing them."""


def _modules() -> list:
    out = list(PACKAGES)
    for pkg in PACKAGES:
        out += [getattr(pkg, n) for n in pkg.__all__ if inspect.ismodule(getattr(pkg, n))]
    return out + [importlib.import_module(name) for name in MORE_MODULES]


def _callables() -> list[tuple[str, object]]:
    """(name, callable) of every function and class in a public ``__all__``, and each such
    class's public methods, properties and constructor."""
    found: dict[int, tuple[str, object]] = {}
    for mod in _modules():
        for name in getattr(mod, "__all__", ()):
            obj = getattr(mod, name)
            where = f"{mod.__name__}.{name}"
            if inspect.isfunction(obj):
                found.setdefault(id(obj), (where, obj))
            elif inspect.isclass(obj):
                found.setdefault(id(obj), (where, obj))
                for attr, member in vars(obj).items():
                    if attr.startswith("_") and attr != "__init__":
                        continue
                    if isinstance(member, (staticmethod, classmethod)):
                        member = member.__func__
                    if isinstance(member, property):
                        member = member.fget
                    if inspect.isfunction(member):
                        found.setdefault(id(member), (f"{where}.{attr}", member))
    return list(found.values())


def _hints(obj) -> dict:
    try:
        return typing.get_type_hints(obj)
    except NameError as exc:  # only a lazily imported name may be missing, and only here
        assert exc.name in LAZY, f"{obj!r}: {exc}"
        local = {}
        for name, (module, attr) in LAZY.items():
            local[name] = getattr(importlib.import_module(module), attr)
        return typing.get_type_hints(obj, localns=local)


CALLABLES = _callables()


def test_the_public_surface_is_found() -> None:
    names = {name for name, _ in CALLABLES}
    assert len(CALLABLES) > 300
    for name in (
        "gpmsa.fit",
        "gpmsa.Posterior.quantile",
        "control.BCR.update",
        "control.robot.Recording",
        "roadgen.Track.gd_at",
        "vehicle.run_campaign",
    ):
        assert name in names


@pytest.mark.parametrize("name, obj", CALLABLES, ids=[name for name, _ in CALLABLES])
def test_every_public_hint_resolves(name, obj) -> None:
    hints = _hints(obj)
    assert isinstance(hints, dict), name


# -- constructors: a dataclass that converts its inputs declares what it takes -------------------


def _typed_init(cls) -> ast.FunctionDef:
    """The ``__init__`` a class declares under ``if TYPE_CHECKING:`` (for type checkers only)."""
    tree = ast.parse(textwrap.dedent(inspect.getsource(cls)))
    for node in ast.walk(tree.body[0]):
        if isinstance(node, ast.If) and ast.unparse(node.test) == "TYPE_CHECKING":
            for item in node.body:
                if isinstance(item, ast.FunctionDef) and item.name == "__init__":
                    return item
    raise AssertionError(f"{cls.__name__} declares no typed __init__ for type checkers")


def _default(cls, node: ast.expr) -> object:
    """The value of a default written in the typed ``__init__``: a literal, or a module constant."""
    if isinstance(node, ast.Constant):
        return node.value
    if isinstance(node, ast.Name):
        return getattr(sys.modules[cls.__module__], node.id)
    return ast.literal_eval(node)


@pytest.mark.parametrize("cls", [gpmsa.SimData, gpmsa.ObsData, gpmsa.Priors, control.FeatureSpec])
def test_the_typed_constructor_matches_the_dataclass(cls) -> None:
    """Its parameters are the dataclass's init fields, in order, with the same defaults (a
    default factory's: ``...``), so that it cannot drift from what the class takes."""
    init = _typed_init(cls)
    params = init.args.args[1:]
    fields = [f for f in dataclasses.fields(cls) if f.init]
    assert [p.arg for p in params] == [f.name for f in fields]
    assert not init.args.kwonlyargs and init.args.vararg is None and init.args.kwarg is None
    assert len(init.args.defaults) == len(params)
    for f, default in zip(fields, init.args.defaults, strict=True):
        value = _default(cls, default)
        if f.default is dataclasses.MISSING:
            assert value is Ellipsis, f.name
        else:
            assert value == f.default, f.name


def _annotations(cls) -> dict[str, str]:
    init = _typed_init(cls)
    return {p.arg: ast.unparse(p.annotation) for p in init.args.args[1:]}


def test_simdata_and_obsdata_take_array_likes_and_lists_of_names() -> None:
    sim = _annotations(gpmsa.SimData)
    for name in ("x", "t", "y", "index"):
        assert sim[name] == "ArrayLike | None"
    for part in ("x", "t", "y"):
        assert sim[f"{part}_names"] == sim[f"{part}_units"] == "Sequence[str] | None"
    obs = _annotations(gpmsa.ObsData)
    assert obs["x"] == "ArrayLike | None"
    for name in ("y", "index", "precision"):
        assert obs[name] == "ArrayLike | Sequence[ArrayLike] | None"
    priors = _annotations(gpmsa.Priors)
    assert priors["theta_mean"] == priors["theta_sd"] == "float | Sequence[float]"
    assert priors["lamVz"] == "GammaPrior | Sequence[GammaPrior]"
    # as the docs pass them, at run time
    runs = [[0.0], [1.0], [2.0], [3.0]]
    sim_data = gpmsa.SimData(x=runs, t=[[0.0], [2.0], [1.0], [3.0]], y=runs[::-1], x_names=["v"])
    assert sim_data.x_names == ("v",) and isinstance(sim_data.x, np.ndarray)
    obs_data = gpmsa.ObsData(x=[[0.3], [0.7]], y=[[1.0], [2.0]], precision=[1e4, 2.5e3])
    assert isinstance(obs_data.x, np.ndarray) and len(obs_data.precisions) == 2
    assert gpmsa.Priors(theta_mean=[0.3, 0.5]).theta_mean == (0.3, 0.5)


def test_a_feature_spec_takes_sequences_and_stores_tuples() -> None:
    """``FeatureSpec(bands_hz=[...], quantiles=[...])`` type-checks (the constructor takes any
    sequence, or None for the default levels), and ``spec.quantiles`` reads as the tuple it
    always is once made (``len(spec.quantiles)`` type-checks: never None)."""
    init = _annotations(control.FeatureSpec)
    assert init["bands_hz"] == "Sequence[float] | np.ndarray"
    assert init["quantiles"] == "Sequence[float] | np.ndarray | None"
    stored = typing.get_type_hints(control.FeatureSpec)
    assert stored["bands_hz"] == stored["quantiles"] == tuple[float, ...]
    for name in ("log_band_power", "log_var"):  # None given: the default levels, or none
        assert type(control.FeatureSpec(name=name).quantiles) is tuple
    spec = control.FeatureSpec(bands_hz=np.array([1.5, 4.5, 7.0]), quantiles=[0.9])
    assert spec.bands_hz == (1.5, 4.5, 7.0) and spec.quantiles == (0.9,)


# -- a number for a number, an array for an array ---------------------------------------------

needs_overloads = pytest.mark.skipif(
    sys.version_info < (3, 11), reason="typing.get_overloads is new in Python 3.11"
)


def _overload_returns(func) -> list:
    return [typing.get_type_hints(o)["return"] for o in typing.get_overloads(func)]


@needs_overloads
@pytest.mark.parametrize(
    "func",
    [
        gpmsa.Posterior.quantile,
        roadgen.Track.gd_at,
        roadgen.Profile.gd_at,
        roadgen.Road.height_at,
        control.feature.feature_of_variance,
    ],  # fmt: skip
    ids=lambda f: f.__qualname__,
)
def test_scalar_in_scalar_out_is_declared(func) -> None:
    assert _overload_returns(func) == [float, np.ndarray]
    hints = typing.get_type_hints(func)
    first = next(k for k in hints if k not in ("self", "name", "return"))
    assert Sequence[float] in typing.get_args(hints[first])  # a list of them: an array


def test_the_runtime_answers_the_overloads() -> None:
    track = roadgen.track([(5.0, 300.0), (5.0, 500.0)], seed=np.int64(1))
    assert type(track.gd_at(7.0)) is float and isinstance(track.gd_at([1.0, 7.0]), np.ndarray)
    assert type(track.height_at(np.float32(1.0))) is float
    post = gpmsa.Posterior({"GD": np.linspace(0.0, 1.0, 101)})
    assert type(post.quantile("GD", 0.5)) is float
    assert post.quantile("GD", [0.25, 0.75]).shape == (2,)
    assert type(control.feature.feature_of_variance(2.0)) is np.float64  # a float


@pytest.mark.parametrize(
    "func",
    [gpmsa.predictive.FullPrediction.quantile, gpmsa.predictive.EmulatorPrediction.quantile],
    ids=lambda f: f.__qualname__,
)
def test_prediction_quantiles_take_a_list(func) -> None:
    assert Sequence[float] in typing.get_args(typing.get_type_hints(func)["q"])


# -- other hints correct code needs --------------------------------------------------------------


@pytest.mark.parametrize(
    "func",
    [
        roadgen.track,
        roadgen.iso8608_profile,
        vehicle.simulate,
        vehicle.Simulation.__init__,
        vehicle.lhs_design,
        control.run_closed_loop,
    ],  # fmt: skip
    ids=lambda f: f.__qualname__,
)
def test_a_numpy_integer_is_a_seed(func) -> None:
    assert np.integer in typing.get_args(typing.get_type_hints(func)["seed"])


def test_a_profile_and_a_track_have_heights() -> None:
    """`roadgen.estimate_gd` and co. take "anything with z and dx_m": read-only members, or a
    type checker refuses the frozen Profile and Track (their fields cannot be set)."""
    from roadgen.psd import HasHeights

    assert isinstance(vars(HasHeights)["z"], property)
    assert isinstance(vars(HasHeights)["dx_m"], property)


@pytest.mark.parametrize(
    "func",
    [
        control.shipped_emulator,
        control.training.fit_band_emulator,
        control.training.fit_window_emulator,
    ],  # fmt: skip
    ids=lambda f: f.__qualname__,
)
def test_emulator_makers_say_they_give_an_emulator(func) -> None:
    assert typing.get_type_hints(func)["return"] is gpmsa.Emulator


def test_figure_makers_say_they_give_a_figure() -> None:
    from matplotlib.figure import Figure

    makers = [getattr(gpmsa.plots, name) for name in gpmsa.plots.__all__]
    for func in [*makers, gpmsa.Posterior.plot, roadgen.plot_profile_psd]:
        assert _hints(func)["return"] is Figure, func.__qualname__
