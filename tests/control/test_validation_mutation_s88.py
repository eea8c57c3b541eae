"""Mutation testing of control.validation (s88): each shared check accepts the boundary values
its docstring allows and refuses the ones just beyond, with a message naming the argument."""

from dataclasses import dataclass
from fractions import Fraction

import numpy as np
import pytest

from control import ControlError
from control.validation import (
    check_flags,
    check_lookup,
    check_n_draws,
    check_not_masked,
    check_posterior_name,
    float_array,
    is_choice,
    is_integer,
    is_real,
    path_argument,
    python_value,
    replace_fields,
    require_integers,
    require_reals,
    within,
)
from gpmsa import ResourceLimitError, limits


def test_is_real_holds_ints_numpy_holds_and_nothing_else():
    assert is_real(1.5) and is_real(3) and is_real(np.float32(1.0)) and is_real(np.int64(-3))
    assert is_real(-(2**63)) and is_real(2**64 - 1) and is_real(0)
    assert not is_real(-(2**63) - 1) and not is_real(2**64)
    assert not any(map(is_real, (True, np.bool_(False), "1.5", None, 1j, Fraction(1, 2))))


def test_is_integer_and_is_choice():
    assert is_integer(3) and is_integer(np.int64(0)) and is_integer(-(2**70))
    assert not any(map(is_integer, (True, np.bool_(True), 3.0, "3", None)))
    assert is_choice("a", ("a", "b")) and not is_choice("c", ("a", "b"))
    assert not is_choice(np.array(["a"]), ("a",)) and not is_choice(None, ("a",))


def test_within_widens_each_end_by_a_billionth_of_the_width():
    assert within(0.0, 0.0, 10.0) and within(10.0, 0.0, 10.0) and within(5.0, 0.0, 10.0)
    assert within(10.0 + 0.5e-8, 0.0, 10.0) and within(-0.5e-8, 0.0, 10.0)
    assert not within(10.0 + 2e-8, 0.0, 10.0) and not within(-2e-8, 0.0, 10.0)
    assert within(20.0 + 0.5e-8, 10.0, 20.0) and not within(20.0 + 2e-8, 10.0, 20.0)
    assert within(0.0 - 1e-8, 0.0, 10.0) and within(10.0 + 1e-8, 0.0, 10.0)  # the ends: inside
    assert within(5.0, 5.0, 5.0) and not within(5.0 + 1e-12, 5.0, 5.0)  # no width: no widening


def test_n_draws_from_one_up_to_the_memory_limit(monkeypatch):
    check_n_draws(1)
    check_n_draws(np.int64(2))
    for bad in (0, -1, True, 1.0, None):
        with pytest.raises(ControlError, match="n_draws must be an integer >= 1"):
            check_n_draws(bad)
    monkeypatch.setattr(limits, "MAX_MEMORY_BYTES", 240)  # 24 bytes a draw
    check_n_draws(10)
    with pytest.raises(ResourceLimitError, match="n_draws=11"):
        check_n_draws(11)
    monkeypatch.setattr(limits, "MAX_MEMORY_BYTES", 239)
    with pytest.raises(ResourceLimitError, match="n_draws=10"):
        check_n_draws(10)


def test_posterior_name_is_a_non_empty_str():
    check_posterior_name("gd")
    for bad in ("", None, 1, b"gd"):
        with pytest.raises(ControlError, match="name must be the parameter's name"):
            check_posterior_name(bad)


@dataclass(frozen=True)
class Settings:
    a: object = 1.0
    b: object = None
    n: object = 3


def test_require_reals_and_integers_with_optional_fields():
    require_reals(Settings(), ("a",), optional=("b",))
    require_integers(Settings(), ("n",), optional=("b",))
    with pytest.raises(ControlError, match=r"Settings\.b must be a real number, got None"):
        require_reals(Settings(), ("a", "b"))
    with pytest.raises(ControlError, match=r"Settings\.a must be a real number or None, got '1'"):
        require_reals(Settings(a="1"), ("a",), optional=("a",))
    with pytest.raises(ControlError, match=r"Settings\.a must be a real number numpy holds"):
        require_reals(Settings(a=2**64), ("a",))
    with pytest.raises(ControlError, match=r"Settings\.a must be a real number, got True"):
        require_reals(Settings(a=True), ("a",))
    with pytest.raises(ControlError, match=r"Settings\.b must be an integer, got None"):
        require_integers(Settings(), ("n", "b"))
    with pytest.raises(ControlError, match=r"Settings\.n must be an integer or None, got 3\.0"):
        require_integers(Settings(n=3.0), ("n",), optional=("n",))
    s = Settings(a=np.float32(0.5), n=np.int64(4))
    require_reals(s, ("a",))
    require_integers(s, ("n",))
    assert type(s.a) is float and s.a == 0.5 and type(s.n) is int and s.n == 4


def test_python_value_and_flags():
    assert type(python_value(np.float32(0.5))) is float and type(python_value(np.int8(3))) is int
    assert python_value("x") == "x" and python_value(None) is None
    check_flags(a=True, b=False, c=np.bool_(True))
    with pytest.raises(ControlError, match="b must be True or False, got 1"):
        check_flags(a=True, b=1)


def test_masked_arrays_and_float_arrays_are_named():
    check_not_masked(np.zeros(2), "x")
    with pytest.raises(ControlError, match="x is a masked array"):
        check_not_masked(np.ma.masked_array([1.0, 2.0]), "x")
    out = float_array([1, 2.5, np.inf], "x")
    assert out.dtype == float and list(out) == [1.0, 2.5, np.inf]


def test_path_argument_refuses_empty_and_bytes_naming_the_argument(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert path_argument("a/b", "out") == tmp_path.joinpath("a/b").relative_to(tmp_path)
    with pytest.raises(ControlError, match=r"out must be the path \(a str or os.PathLike\) of x"):
        path_argument("", "out", " of x")
    with pytest.raises(ControlError, match="decode bytes with os.fsdecode"):
        path_argument(b"a", "out")
    with pytest.raises(ControlError, match=r"out must be the path.*\(NoneType\)$"):
        path_argument(None, "out")


def test_check_lookup_passes_a_missing_path_and_names_a_nul(tmp_path):
    check_lookup(tmp_path / "missing" / "deeper", "path")
    with pytest.raises(ControlError, match="path='a\\\\x00b' is not a usable path"):
        check_lookup("a\x00b", "path")


@dataclass
class Loose:
    x: int = 1


@dataclass(frozen=True)
class Outer:
    inner: Settings = Settings()
    y: int = 2


def test_replace_fields():
    s = Outer()
    assert replace_fields(s, {}) is s  # frozen: the same settings
    loose = Loose()
    assert replace_fields(loose, {}) is not loose and replace_fields(loose, {}) == loose
    assert replace_fields(s, {"y": 3}).y == 3
    with pytest.raises(ControlError, match=r"'n': no Outer field; 'n' is a field of Settings"):
        replace_fields(s, {"n": 4})
    with pytest.raises(ControlError, match=r"^'z': no Outer field \(its fields: inner, y\)$"):
        replace_fields(s, {"z": 4})
