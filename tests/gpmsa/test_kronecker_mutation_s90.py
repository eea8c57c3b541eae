"""Mutation testing of gpmsa.model.kronecker (session 90): exact checks of each piece on tiny
designs (3 x 4 and 3 x 2 x 2 runs) against the dense computation to ~1e-12, the refusals word
for word, and the limits (MAX_DENSE_RUNS, two factors, the 720 factor orders tried) at their
edges."""

from __future__ import annotations

import dataclasses
import itertools
import math
import re
from types import SimpleNamespace

import numpy as np
import pytest

import gpmsa
from gpmsa.errors import GPMSAError
from gpmsa.model import kronecker
from gpmsa.model.correlation import correlation
from gpmsa.model.kronecker import (
    KroneckerLikelihood,
    KronFactor,
    Separable,
    check_dense,
    factor_eigen,
    fit_nbytes,
    kron_matvec,
    kron_vector,
    parse_groups,
    refuse,
    structure,
    weights_loglik,
)
from gpmsa.model.likelihood import log_likelihood
from gpmsa.model.problem import prepare

XS = np.array([0.0, 0.5, 1.0])  # factor 0: x0
TS = np.array([[0.1, 0.9], [0.3, 0.2], [0.6, 0.5], [0.8, 0.0]])  # factor 1: [t0, t1]
NAMES = ("x0", "t0", "t1")
ORDER = (
    "the runs must be the product of the factors {} in C order (the first factor varying "
    "slowest, the last fastest, each factor's points in one order throughout)"
)


def _zt() -> np.ndarray:
    """The 3 x 4 design (12, 3) in Kronecker order: x0 slowest, [t0, t1] fastest."""
    return np.hstack([np.repeat(XS, 4)[:, None], np.tile(TS, (3, 1))])


def _zt3() -> tuple[np.ndarray, list[np.ndarray]]:
    """A 2 x 3 x 2 design over factors [t0] (slowest), [x0], [t1] (fastest), and the factors."""
    a, b, c = np.array([0.2, 0.7]), np.array([0.0, 0.4, 1.0]), np.array([0.1, 0.9])
    rows = [(bj, ai, ck) for ai in a for bj in b for ck in c]  # columns x0, t0, t1
    return np.array(rows), [a[:, None], b[:, None], c[:, None]]


def _full(message: str) -> str:
    return "^" + re.escape(message) + "$"


# --- the factor structure -----------------------------------------------------------------------
def test_separable_m_factor_designs_and_columns():
    sep = Separable(((0,), (1, 2)), (3, 4))
    assert sep.m == 12
    designs = sep.factor_designs(_zt())
    np.testing.assert_array_equal(designs[0], XS[:, None])
    np.testing.assert_array_equal(designs[1], TS)
    assert all(d.flags.c_contiguous for d in designs)
    np.testing.assert_array_equal(sep.factor_of_column(), [0.0, 1.0, 1.0])
    zt, factors = _zt3()
    sep3 = Separable(((1,), (0,), (2,)), (2, 3, 2))
    assert sep3.m == 12
    for got, want in zip(sep3.factor_designs(zt), factors, strict=True):
        np.testing.assert_array_equal(got, want)
    np.testing.assert_array_equal(sep3.factor_of_column(), [1.0, 0.0, 2.0])
    with pytest.raises(dataclasses.FrozenInstanceError):
        sep.sizes = (4, 3)
    assert hash(sep) == hash(Separable(((0,), (1, 2)), (3, 4)))


def test_structure_reads_the_sizes_and_accepts_the_product():
    assert structure(_zt(), [(0,), (1, 2)], NAMES) == Separable(((0,), (1, 2)), (3, 4))
    zt, _ = _zt3()
    assert structure(zt, [[1], [0], [2]], NAMES) == Separable(((1,), (0,), (2,)), (2, 3, 2))


# --- the declaration ----------------------------------------------------------------------------
def test_parse_groups_accepted_forms():
    assert parse_groups(None, NAMES) is None
    assert parse_groups(False, NAMES) is None
    assert parse_groups(True, NAMES) == ((0,), (1,), (2,))
    assert parse_groups(["x0", ["t0", "t1"]], NAMES) == ((0,), (1, 2))
    assert parse_groups([np.int64(2), (0, "t0")], NAMES) == ((2,), (0, 1))
    assert parse_groups([0, [2, 1]], NAMES) == ((0,), (2, 1))  # the order within kept
    assert parse_groups([[0], [1]], ("a", "b")) == ((0,), (1,))  # exactly two: enough


@pytest.mark.parametrize(
    ("separable", "shown"), [("x0", "'x0'"), (b"ab", "b'ab'"), (5, "5"), (2.5, "2.5")]
)
def test_parse_groups_refuses_a_non_sequence(separable, shown):
    with pytest.raises(GPMSAError, match=_full(
        "separable must be None, True or a sequence of factors (each an input name or index, "
        f"or a sequence of them), got {shown}"
    )):  # fmt: skip
        parse_groups(separable, NAMES)


@pytest.mark.parametrize(
    ("separable", "got"),
    [
        ([[0, 1, 2]], "[['x0', 't0', 't1']]"),  # one factor
        ([[0], [], [1, 2]], "[['x0'], [], ['t0', 't1']]"),  # an empty one
        ([[0], [1]], "[['x0'], ['t0']]"),  # an input missing
        ([[0, 1], [1, 2]], "[['x0', 't0'], ['t0', 't1']]"),  # an input twice
        ([[0, 1], [1]], "[['x0', 't0'], ['t0']]"),  # as many, one twice, one missing
    ],
)
def test_parse_groups_refuses_a_non_partition(separable, got):
    with pytest.raises(GPMSAError, match=_full(
        "separable must split the 3 inputs ['x0', 't0', 't1'] into at least two non-empty "
        f"factors, each input in exactly one; got {got}"
    )):  # fmt: skip
        parse_groups(separable, NAMES)


def test_parse_groups_true_with_one_input_is_one_factor():
    with pytest.raises(GPMSAError, match=re.escape("into at least two non-empty factors")):
        parse_groups(True, ("x0",))


@pytest.mark.parametrize(
    ("item", "message"),
    [
        ("v", "separable: 'v' is not an input (inputs ['x0', 't0', 't1'])"),
        (True, "separable: an input is a name or an index, got True"),
        (1.0, "separable: an input is a name or an index, got 1.0"),
        (-1, "separable: input index -1 outside 0..2"),
        (3, "separable: input index 3 outside 0..2"),
        (np.int64(3), "separable: input index 3 outside 0..2"),
    ],
)
def test_parse_groups_refuses_an_input(item, message):
    with pytest.raises(GPMSAError, match=_full(message)):
        parse_groups([[item], [1, 2]] if item != "v" else [["v"], [1, 2]], NAMES)


@pytest.mark.parametrize(("factor", "shown"), [(1.0, "1.0"), (None, "None"), (b"t0", "b't0'")])
def test_parse_groups_names_a_factor_that_is_no_input(factor, shown):
    # a factor that is neither an input nor a sequence of them was a TypeError ("'float' object
    # is not iterable"), and bytes were read as their character codes ("input index 116")
    message = _full(f"separable: an input is a name or an index, got {shown}")
    with pytest.raises(GPMSAError, match=message):
        parse_groups([0, factor, 2], NAMES)
    with pytest.raises(GPMSAError, match=message):
        gpmsa.SimData(x=_zt()[:, :1], t=_zt()[:, 1:], y=_y(_zt()), separable=[0, factor])


def test_parse_groups_index_edges_accepted():
    assert parse_groups([[2], [0, 1]], NAMES) == ((2,), (0, 1))  # the last index
    assert parse_groups([[np.int32(0)], [1, 2]], NAMES) == ((0,), (1, 2))
    assert type(parse_groups([[np.int32(0)], [1, 2]], NAMES)[0][0]) is int


# --- the product and its order ------------------------------------------------------------------
def test_structure_not_a_product_named_exactly():
    with pytest.raises(GPMSAError, match=_full(
        "separable: the design is not the product of its factors: 3 [x0] x 4 [t0, t1] distinct "
        "points make 12, but there are 11 runs"
    )):  # fmt: skip
        structure(_zt()[:-1], [(0,), (1, 2)], NAMES)


def test_structure_names_the_factors_that_differ_by_rounding():
    tail = (
        ": points that agree to 1e-9 of the range count as distinct; give each factor's points "
        "as the same numbers in every run)"
    )
    zt = _zt()
    zt[5, 0] += 1e-12
    with pytest.raises(GPMSAError, match=_full(
        "separable: the design is not the product of its factors: 4 [x0] x 4 [t0, t1] distinct "
        "points make 16, but there are 12 runs ([x0]" + tail
    )):  # fmt: skip
        structure(zt, [(0,), (1, 2)], NAMES)
    zt[7, 2] += 1e-13
    with pytest.raises(GPMSAError, match=_full(
        "separable: the design is not the product of its factors: 4 [x0] x 5 [t0, t1] distinct "
        "points make 20, but there are 12 runs ([x0], [t0, t1]" + tail
    )):  # fmt: skip
        structure(zt, [(0,), (1, 2)], NAMES)


def test_rounding_hint_on_a_constant_column_and_far_points():
    zt = np.hstack([_zt(), np.zeros((12, 1))])  # a constant column: span 0, no hint from it
    assert kronecker._rounding_hint(zt, [(0,), (1, 2, 3)], (3, 4), ["[a]", "[b]"]) == ""
    zt[3, 0] = 0.25  # a fourth x point far from the others: distinct, no hint
    assert kronecker._rounding_hint(zt, [(0,), (1, 2, 3)], (4, 4), ["[a]", "[b]"]) == ""
    zt[3, 0] = 1e-11  # one within 1e-9 of the span of 0.0
    assert kronecker._rounding_hint(zt, [(0,), (1, 2, 3)], (4, 4), ["[a]", "[b]"]).startswith(
        " ([a]: points that agree"
    )


def test_rounding_hint_at_1e9_of_the_span():
    zt = _zt()
    zt[:, 0] = 2.0 + 10.0 * zt[:, 0]  # x0 points 2, 7, 12: span 10
    zt[5, 0] = 7.0 + 3e-9  # 3e-10 of the span: the same point, rounded
    assert kronecker._rounding_hint(zt, [(0,), (1, 2)], (4, 4), ["[a]", "[b]"]).startswith(
        " ([a]: points that agree"
    )
    zt[5, 0] = 7.0 + 2e-8  # 2e-9 of the span: another point
    assert kronecker._rounding_hint(zt, [(0,), (1, 2)], (4, 4), ["[a]", "[b]"]) == ""


def test_rounding_hint_scaled_from_the_minimum_by_the_span():
    zt = _zt()
    zt[:, 0] = 0.01 * zt[:, 0]  # span 0.01 (below 1: divided by it all the same)
    zt[5, 0] = 0.005 + 2e-11  # 2e-9 of the span: another point
    assert kronecker._rounding_hint(zt, [(0,), (1, 2)], (4, 4), ["[a]", "[b]"]) == ""
    zt = _zt()
    zt[:, 0] = 1e-10 + zt[:, 0]  # minimum 1e-10, span 1
    zt[4:8, 0] += 0.2e-9  # x0 = 0.5 + 0.2e-9 from the minimum, run 5's 0.5 + 0.4e-9: both
    zt[5, 0] += 0.2e-9  # round to 0.5 from the minimum (from -1e-10 they would not)
    assert kronecker._rounding_hint(zt, [(0,), (1, 2)], (4, 4), ["[a]", "[b]"]).startswith(
        " ([a]: points that agree"
    )


def test_rounding_hint_with_a_constant_column_in_the_factor():
    zt = np.hstack([_zt(), np.full((12, 1), 0.3)])
    zt[5, 1] += 1e-12  # t0 of run 5 rounds to run 1's; column 3 constant (span 0)
    hint = kronecker._rounding_hint(zt, [(0,), (1, 2, 3)], (3, 5), ["[a]", "[b]"])
    assert hint.startswith(" ([b]: points that agree")


def test_structure_order_break_named_exactly():
    zt = _zt()[[0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 11, 10]]
    with pytest.raises(GPMSAError, match=_full(
        "separable: run 10 has [t0, t1] = [0.8, 0.0], but the Kronecker order gives [0.6, 0.5]: "
        + ORDER.format("[x0] x [t0, t1]")
    )):  # fmt: skip
        structure(zt, [(0,), (1, 2)], NAMES)
    assert kronecker._order_break(zt, Separable(((0,), (1, 2)), (3, 4)))[:2] == (1, 10)
    np.testing.assert_array_equal(
        kronecker._order_break(zt, Separable(((0,), (1, 2)), (3, 4)))[2], [0.6, 0.5]
    )
    assert kronecker._order_break(_zt(), Separable(((0,), (1, 2)), (3, 4))) is None


def test_structure_order_break_in_the_slowest_factor():
    zt = _zt()
    zt[4:8, 0], zt[8:12, 0] = 1.0, 0.5  # x0's points in the order 0, 1, 0.5: no break
    assert kronecker._order_break(zt, Separable(((0,), (1, 2)), (3, 4))) is None
    structure(zt, [(0,), (1, 2)], NAMES)
    zt[8:12, 0] = 0.5
    zt[9, 0] = 0.0  # run 9 holds 0.0 where x0 = 0.5 repeats
    with pytest.raises(GPMSAError, match=re.escape("run 9 has [x0] = [0.0], but the Kronecker "
                                                   "order gives [0.5]")):  # fmt: skip
        structure(zt, [(0,), (1, 2)], NAMES)


def test_structure_names_the_order_that_fits():
    zt = np.hstack([np.tile(XS, 4)[:, None], np.repeat(TS, 3, axis=0)])  # [t0, t1] slowest
    with pytest.raises(GPMSAError, match=_full(
        "separable: run 1 has [x0] = [0.5], but the Kronecker order gives [0.0]: "
        + ORDER.format("[x0] x [t0, t1]")
        + "; these runs are that product with the factors in the order [t0, t1] x [x0]: give "
        "separable=[['t0', 't1'], ['x0']]"
    )):  # fmt: skip
        structure(zt, [(0,), (1, 2)], NAMES)


def _seven(order: tuple[int, ...]) -> np.ndarray:
    """2^7 runs of seven two-point factors (column c: points c/10, c/10 + 0.5), in C order over
    the factors taken in ``order``."""
    runs = []
    for idx in itertools.product((0, 1), repeat=7):  # idx[i]: factor order[i]'s point
        row = np.empty(7)
        for i, c in enumerate(order):
            row[c] = c / 10 + 0.5 * idx[i]
        runs.append(row)
    return np.array(runs)


def test_structure_tries_the_first_720_factor_orders():
    names = tuple(f"v{c}" for c in range(7))
    groups = [(c,) for c in range(7)]
    perms = list(itertools.islice(itertools.permutations(range(7)), 721))
    with pytest.raises(GPMSAError, match=re.escape("in the order [v0] x [v6] x [v5] x [v4] x")):
        structure(_seven(perms[719]), groups, names)  # the 720th order: named
    with pytest.raises(GPMSAError) as err:
        structure(_seven(perms[720]), groups, names)  # the 721st: not tried
    assert str(err.value).endswith("each factor's points in one order throughout)")
    assert perms[720] == (1, 0, 2, 3, 4, 5, 6)


# --- refusals and limits ------------------------------------------------------------------------
def test_refuse_message():
    with pytest.raises(GPMSAError, match=_full(
        "a separable design (SimData(separable=...)) supports a simulation-only fit on the numpy "
        "backend with the zero-mean GP; a thing is not supported with it (drop separable= to "
        "fit the same model densely)"
    )):  # fmt: skip
        refuse("a thing")


def test_check_dense_at_the_limit():
    assert kronecker.MAX_DENSE_RUNS == 5000
    sep = Separable(((0,), (1,)), (1, 1))
    check_dense(SimpleNamespace(separable=sep, m=5000), "x")  # at the limit: allowed
    check_dense(SimpleNamespace(separable=None, m=10**6), "x")  # dense: never refused here
    check_dense(SimpleNamespace(m=10**6), "x")  # no separable attribute (an old object)
    with pytest.raises(GPMSAError, match=_full(
        "op builds the dense 5001 x 5001 Sigma_W of this separable emulator (5001 runs, above "
        "gpmsa.model.kronecker.MAX_DENSE_RUNS = 5000); predict, predict_mean and loo use the "
        "Kronecker structure. Raise MAX_DENSE_RUNS where the machine has the memory and time"
    )):  # fmt: skip
        check_dense(SimpleNamespace(separable=sep, m=5001), "op")


def test_check_dense_follows_a_raised_limit(monkeypatch):
    monkeypatch.setattr(kronecker, "MAX_DENSE_RUNS", 12)
    sep = Separable(((0,), (1, 2)), (3, 4))
    check_dense(SimpleNamespace(separable=sep, m=12), "op")
    with pytest.raises(GPMSAError, match=re.escape("(13 runs, above gpmsa.model.kronecker."
                                                   "MAX_DENSE_RUNS = 12)")):  # fmt: skip
        check_dense(SimpleNamespace(separable=sep, m=13), "op")


def test_fit_nbytes_exact():
    assert fit_nbytes(Separable(((0,), (1, 2)), (3, 4)), 2) == 8.0 * 2 * 2 * (9 + 16 + 4 * 12)
    assert fit_nbytes(Separable(((1,), (0,), (2,)), (2, 3, 2)), 1) == 16.0 * (4 + 9 + 4 + 48)


# --- the algebra --------------------------------------------------------------------------------
def test_kron_matvec_and_vector_against_numpy():
    rng = np.random.default_rng(90)
    a, b, c = rng.random((2, 3)), rng.random((4, 2)), rng.random((3, 3))  # not square
    full = np.kron(np.kron(a, b), c)
    v = rng.random(18)
    np.testing.assert_allclose(kron_matvec([a, b, c], v), full @ v, rtol=1e-13)
    assert kron_matvec([a, b, c], v).shape == (24,)
    v2 = rng.random((18, 2))
    np.testing.assert_allclose(kron_matvec([a, b, c], v2), full @ v2, rtol=1e-13)
    e = [rng.random(2), rng.random(3), rng.random(4)]
    np.testing.assert_allclose(kron_vector(e), np.kron(np.kron(e[0], e[1]), e[2]), rtol=1e-15)


def test_part_and_factor_eigen():
    assert kronecker._part(None, (0, 1)) is None
    np.testing.assert_array_equal(kronecker._part(np.array([True, False, True]), (2, 1)),
                                  [True, False])  # fmt: skip
    beta, cat = np.array([2.0, 0.7]), np.array([False, True])
    e, Q = factor_eigen(TS, beta, cat)
    R = correlation(TS, None, beta, cat)
    np.testing.assert_allclose(Q @ np.diag(e) @ Q.T, R, atol=1e-14)
    np.testing.assert_allclose(Q.T @ Q, np.eye(4), atol=1e-14)
    assert np.all(np.diff(e) >= 0)


def test_weights_loglik_by_hand():
    lam, wt = np.array([1.0, 2.0]), np.array([1.0, 2.0])
    d = np.array([1.0, 1.5])  # lam * 0.5 + 0.5
    want = -0.5 * math.log(1.5) - 0.5 * (1.0 + 4.0 / 1.5)
    assert weights_loglik(lam, wt, 0.5, 0.5) == pytest.approx(want, rel=1e-15)
    assert want == -0.5 * np.sum(np.log(d)) - 0.5 * np.sum(wt**2 / d)
    assert weights_loglik(lam, wt, 0.5, -0.5) == -np.inf  # d = [0, 0.5]: zero is not PD
    assert weights_loglik(lam, wt, -1.0, 1.5) == -np.inf  # d = [0.5, -0.5]
    assert weights_loglik(lam, wt, np.nan, 1.0) == -np.inf


# --- one component's Sigma_W --------------------------------------------------------------------
def _dense_sigma(beta, scale, nug, cat=None):
    return correlation(_zt(), None, beta, cat) * scale + nug * np.eye(12)


@pytest.mark.parametrize("cat", [None, np.array([False, True, False])])
def test_kron_factor_against_dense(cat):
    rng = np.random.default_rng(91)
    beta, w = np.array([1.7, 0.4, 3.0]), rng.standard_normal(12)
    f = KronFactor(Separable(((0,), (1, 2)), (3, 4)).factor_designs(_zt()), ((0,), (1, 2)), cat,
                   beta, 0.8, 0.05, w)  # fmt: skip
    S = _dense_sigma(beta, 0.8, 0.05, cat)
    np.testing.assert_allclose(np.sort(f.d), np.linalg.eigvalsh(S), rtol=1e-12)
    np.testing.assert_allclose(f.alpha, np.linalg.solve(S, w), rtol=1e-12)
    np.testing.assert_allclose(f.precision_diagonal(), np.diag(np.linalg.inv(S)), rtol=1e-12)
    assert len(f.Q) == 2 and f.Q[0].shape == (3, 3) and f.Q[1].shape == (4, 4)


@pytest.mark.parametrize(("scale", "nug"), [(0.0, 0.0), (1.0, -5.0), (np.nan, 1.0)])
def test_kron_factor_refuses_not_pd(scale, nug):
    designs = Separable(((0,), (1, 2)), (3, 4)).factor_designs(_zt())
    with pytest.raises(GPMSAError, match=_full(
        "Sigma_W is not positive definite at these parameters"
    )):  # fmt: skip
        KronFactor(designs, ((0,), (1, 2)), None, np.ones(3), scale, nug, np.ones(12))


# --- the likelihood -----------------------------------------------------------------------------
def _y(zt: np.ndarray) -> np.ndarray:
    s = np.linspace(1.0, 2.0, 5)
    return np.sin(3 * zt[:, :1]) * s + zt[:, 1:2] ** 2 - 0.7 * zt[:, 2:3] * s[::-1]


def _problem(three: bool = False, categorical: bool = False):
    if three:
        zt, _ = _zt3()
        groups = [["t0"], ["x0"], ["t1"]]
    else:
        zt, groups = _zt(), [["x0"], ["t0", "t1"]]
    x = np.round(zt[:, :1] * 2) if categorical else zt[:, :1]
    sim = gpmsa.SimData(x=x, t=zt[:, 1:], y=_y(zt), separable=groups,
                        x_categorical=[0] if categorical else None)  # fmt: skip
    return prepare(sim, n_pc=2).problem


def _params(prob, seed):
    rng = np.random.default_rng(seed)
    return dict(prob.init, betaU=rng.uniform(0.2, 6.0, prob.init["betaU"].shape),
                lamUz=rng.uniform(0.3, 3.0, 2), lamWs=rng.uniform(30.0, 3e3, 2),
                lamWOs=np.array([rng.uniform(50.0, 500.0)]))  # fmt: skip


def _dense(prob, prm):
    return log_likelihood(dataclasses.replace(prob, separable=None), prm)


MOVES = [("betaU", (k, j), v) for j in (0, 1) for k, v in ((0, 2.2), (1, 0.3), (2, 4.1))] + [
    ("lamUz", (0,), 0.6), ("lamUz", (1,), 2.4), ("lamWs", (0,), 77.0), ("lamWs", (1,), 900.0),
    ("lamWOs", (0,), 123.0),
]  # fmt: skip


@pytest.mark.parametrize(("three", "categorical"), [(False, False), (False, True), (True, False)])
def test_likelihood_proposals_and_accepts_match_dense(three, categorical):
    prob = _problem(three, categorical)
    assert prob.p_u == 2 and prob.m == 12
    prm = _params(prob, 92)
    lik = KroneckerLikelihood(prob, prm)
    assert lik.loglik == pytest.approx(_dense(prob, prm), rel=1e-12, abs=1e-12)
    for name, idx, value in MOVES:
        new = {**prm, name: prm[name].copy()}
        new[name][idx] = value
        want = _dense(prob, new)
        assert lik.propose(name, idx, value) == pytest.approx(want, rel=1e-12, abs=1e-12)
        assert lik.params[name][idx] == prm[name][idx]  # pending: nothing changed yet
        lik.accept()
        prm = new
        assert lik._pending is None
        assert lik.loglik == pytest.approx(want, rel=1e-12, abs=1e-12)
        assert lik.params[name][idx] == value
        fresh = KroneckerLikelihood(prob, prm)
        np.testing.assert_allclose(lik.llw, fresh.llw, rtol=1e-12)
    # a proposal not accepted leaves the state: the next one starts from the accepted values
    lik.propose("betaU", (1, 0), 5.5)
    lik.propose("lamUz", (0,), 1.1)
    new = {**prm, "lamUz": prm["lamUz"].copy()}
    new["lamUz"][0] = 1.1
    lik.accept()
    assert lik.loglik == pytest.approx(_dense(prob, new), rel=1e-12, abs=1e-12)


def test_likelihood_factor_of_each_input():
    lik = KroneckerLikelihood(_problem(three=True), _params(_problem(three=True), 93))
    assert lik.factor_of == [1, 0, 2] and lik.groups == ((1,), (0,), (2,))


def test_likelihood_minus_inf_where_not_pd():
    prob = _problem()
    prm = _params(prob, 94)
    lik = KroneckerLikelihood(prob, prm)
    assert lik.propose("lamWs", (1,), -1e-3) == -np.inf  # a negative nugget: not PD
    assert lik.loglik == pytest.approx(_dense(prob, prm), rel=1e-12)


@pytest.mark.parametrize("field", ["obs", "mean_basis"])
def test_likelihood_refuses_obs_and_mean_basis(field):
    prob = _problem()
    value = SimpleNamespace(p_v=0) if field == "obs" else object()
    bad = dataclasses.replace(prob, **{field: value})
    with pytest.raises(GPMSAError, match=_full(
        "a separable design (SimData(separable=...)) supports a simulation-only fit on the numpy "
        "backend with the zero-mean GP; observations or a mean_basis is not supported with it "
        "(drop separable= to fit the same model densely)"
    )):  # fmt: skip
        KroneckerLikelihood(bad, prob.init)


# --- the predictive -----------------------------------------------------------------------------
def _emulators(three: bool = False):
    zt, groups = (_zt3()[0], [["t0"], ["x0"], ["t1"]]) if three else (_zt(), [[0], [1, 2]])
    prm = {"betaU": [[1.3, 0.4], [2.1, 3.3], [0.6, 1.9]], "lamUz": [0.8, 1.7],
           "lamWs": [300.0, 60.0], "lamWOs": [150.0]}  # fmt: skip
    out = []
    for sep in (None, groups):
        sim = gpmsa.SimData(x=zt[:, :1], t=zt[:, 1:], y=_y(zt), separable=sep)
        out.append(gpmsa.Emulator.from_params(sim, prm, n_pc=2))
    return out


@pytest.mark.parametrize("three", [False, True])
def test_predictive_matches_dense(three):
    dense, sep = _emulators(three)
    assert sep.separable is not None and dense.separable is None and sep.p_u == 2
    z = np.random.default_rng(95).random((5, 3))
    fd, fs = dense._predict_factors(dense.params), sep._predict_factors(sep.params)
    assert len(fs) == 2 and isinstance(fs[0], KronFactor)
    for resid in (False, True):
        md, vd = dense._predict_std(z, dense.params, fd, resid)
        ms, vs = sep._predict_std(z, sep.params, fs, resid)
        np.testing.assert_allclose(ms, md, rtol=1e-12, atol=1e-13)
        np.testing.assert_allclose(vs, vd, rtol=1e-10, atol=1e-13)
        mean, var = kronecker.predict_std(sep, z, sep.params, fs, resid)  # var=True: default
        np.testing.assert_array_equal(var, vs)
        mean, var = sep._predict_std(z, sep.params, fs, resid, var=False)
        assert var is None
        np.testing.assert_array_equal(mean, ms)
    _, v0 = sep._predict_std(z, sep.params, fs, False)
    _, v1 = sep._predict_std(z, sep.params, fs, True)
    nug = 1.0 / np.array([300.0, 60.0])
    want = np.broadcast_to((sep.K**2) @ nug + 1.0 / 150.0, v0.shape)  # every point alike
    np.testing.assert_allclose(v1 - v0, want, rtol=1e-12)
    la, lb = dense.loo(), sep.loo()
    np.testing.assert_allclose(lb.mean, la.mean, rtol=1e-11)
    np.testing.assert_allclose(lb.var, la.var, rtol=1e-10)
