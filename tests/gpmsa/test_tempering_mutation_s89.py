"""Exact checks of ``gpmsa.mcmc.tempering`` (session 89, from mutation testing): the ladder's
geometric spacing and its bounds, ``swap_every``'s bounds, a swap round's decisions with the
acceptance draw placed just above and below exp(log ratio) worked out by hand, the adaptive
ladder's step on the log gaps (kappa_n = 0.1 * 200 / (n + 200)) and its Polyak average, and
``run_ladder``'s swap schedule, swap rates and progress counts, on stand-in copies whose log
likelihoods are fixed numbers."""

import math

import numpy as np
import pytest

from gpmsa.errors import GPMSAError
from gpmsa.mcmc import tempering


class _Copy:
    """A stand-in copy: a fixed log likelihood and a tag that travel together on a swap."""

    def __init__(self, loglik: float, tag: str, beta: float = 1.0, step: float = 1.0):
        self.loglik, self.tag, self.beta, self.step = loglik, tag, beta, step
        self.widths: list = []
        self.shifts: list = []

    def exchange(self, other: "_Copy") -> None:
        self.loglik, other.loglik = other.loglik, self.loglik
        self.tag, other.tag = other.tag, self.tag

    def sweep(self, widths, prop_mh, accepted) -> None:
        self.widths.append((np.array(widths), prop_mh))
        accepted += self.step

    def learn_level_shifts(self) -> None:
        self.shifts.append("learn")

    def use_level_shifts(self, cold) -> None:
        self.shifts.append(cold.tag)


class _Rng:
    """``random(n)`` from a script (a constant where the script runs out); sizes recorded."""

    def __init__(self, script=(), value=0.5):
        self.script, self.value, self.sizes = list(script), value, []

    def random(self, n):
        self.sizes.append(n)
        if self.script:
            return np.asarray(self.script.pop(0), dtype=float)
        return np.full(n, self.value)


class _Bar:
    def __init__(self):
        self.updates, self.texts = [], []

    def update(self, n):
        self.updates.append(n)

    def set_description(self, text):
        self.texts.append(text)


def test_integer_ladder_is_geometric_with_ratio_two():
    assert tempering.ladder(2) == (1.0, 2.0)
    assert tempering.ladder(5) == (1.0, 2.0, 4.0, 8.0, 16.0)
    top = tempering.ladder(32)
    assert len(top) == 32 and top[-1] == 2.0**31
    assert tempering.ladder(1) is None and tempering.ladder(np.int64(1)) is None
    with pytest.raises(GPMSAError, match=r"temperatures must be an integer in \[1, 32\]"):
        tempering.ladder(33)


@pytest.mark.parametrize("value", ["hot", b"hot", {1: 1.0}, 3.5, object()])
def test_non_sequence_refused_with_the_first_message(value):
    with pytest.raises(GPMSAError, match=r"an integer n in \[2, 32\] \(the ladder 2\*\*k\)"):
        tempering.ladder(value)


def test_ladder_sizes_at_the_bounds():
    assert tempering.ladder([1.0, 1.5]) == (1.0, 1.5)
    assert len(tempering.ladder(np.arange(1.0, 33.0))) == 32
    for bad in ([1.0], np.arange(1.0, 34.0), [], [1.0, "x"]):
        with pytest.raises(GPMSAError, match="a flat sequence of 2 to 32 numbers"):
            tempering.ladder(bad)
    with pytest.raises(GPMSAError, match="increase strictly"):
        tempering.ladder([1.0, 3.0, 2.0])
    with pytest.raises(GPMSAError, match="finite"):
        tempering.ladder([1.0, np.nan])


def test_chain_ladders_and_recorded_ladders():
    assert tempering.chain_ladders(None, 3) is None and tempering.chain_ladders(1, 2) is None
    assert tempering.chain_ladders(2, 2) == [(1.0, 2.0), (1.0, 2.0)]
    rows = np.array([[1.0, 3.0], [1.0, 5.0]])
    assert tempering.chain_ladders(rows, 2) == [(1.0, 3.0), (1.0, 5.0)]
    with pytest.raises(GPMSAError, match=r"must have 3 rows \(n_chains\), got shape \(2, 2\)"):
        tempering.chain_ladders(rows, 3)
    plain = {"temperatures": [1.0, 2.0]}
    assert tempering.recorded_ladders(plain, {}) is plain
    rec = tempering.recorded_ladders({"temperatures": rows, "x": 1}, {"temperatures": (1, 4)})
    assert rec == {"temperatures": [1, 4], "x": 1, "adapted_temperatures": rows.tolist()}
    again = {"temperatures": rows, "adapted_temperatures": [[1.0, 9.0]]}
    assert tempering.recorded_ladders(again, {"temperatures": [1, 4]})[
        "adapted_temperatures"] == [[1.0, 9.0]]  # fmt: skip


def test_swap_every_bounds():
    lad = (1.0, 2.0)
    assert tempering.check_swap_every(1_000_000, lad) == 1_000_000
    with pytest.raises(GPMSAError, match=r"swap_every must be an integer in \[1, 1000000\]"):
        tempering.check_swap_every(1_000_001, lad)
    assert tempering.check_swap_every(1, None) == 1
    assert tempering.check_swap_every(5, lad, 5) == 5
    assert tempering.check_swap_every(7, lad) == 7  # no n_iter: no upper bound from it
    with pytest.raises(GPMSAError, match="swap_every=6 exceeds n_samples=5"):
        tempering.check_swap_every(6, lad, 5, "n_samples")
    with pytest.raises(GPMSAError, match="swap_every=2 needs temperatures"):
        tempering.check_swap_every(2, None, 10)


def test_swap_decisions_at_the_acceptance_draw():
    """Betas (1, 1/2, 1/4), log L (-1, -5, -2): pair 0's log ratio (1 - 1/2)(-5 + 1) = -2."""
    betas = (1.0, 0.5, 0.25)

    def copies():
        return [_Copy(-1.0, "a"), _Copy(-5.0, "b"), _Copy(-2.0, "c")]

    s, acc, probs = copies(), np.zeros(2), np.full(2, np.nan)
    # pair 0 refused (u just above e^-2); pair 1: (1/2 - 1/4)(-2 + 5) = 0.75 > 0, accepted
    tempering.swap(s, betas, np.array([math.exp(-2.0) * (1 + 1e-9), 0.999999]), acc, probs)
    assert [c.tag for c in s] == ["a", "c", "b"] and acc.tolist() == [0.0, 1.0]
    assert probs[0] == pytest.approx(math.exp(-2.0), rel=1e-14) and probs[1] == 1.0
    s, acc, probs = copies(), np.zeros(2), np.full(2, np.nan)
    # pair 0 accepted (u just below e^-2); pair 1 then holds -1: (1/4)(-2 + 1) = -0.25
    u1 = math.exp(-0.25)
    tempering.swap(s, betas, np.array([math.exp(-2.0) * (1 - 1e-9), u1 * (1 - 1e-9)]), acc, probs)
    assert [c.tag for c in s] == ["b", "c", "a"] and acc.tolist() == [1.0, 1.0]
    assert probs.tolist() == pytest.approx([math.exp(-2.0), u1], rel=1e-14)
    s, acc = copies(), np.array([3.0, 0.0])
    tempering.swap(s, betas, np.array([math.exp(-2.0) * (1 + 1e-9), u1 * (1 + 1e-9)]), acc)
    assert acc.tolist() == [3.0, 1.0] and [c.tag for c in s] == ["a", "c", "b"]


def test_swap_needs_log_u_strictly_below_the_log_ratio():
    """Equal log likelihoods: log ratio 0, and u = 1 (log u = 0) is not below it."""
    s, acc, probs = [_Copy(-3.0, "a"), _Copy(-3.0, "b")], np.zeros(1), np.zeros(1)
    tempering.swap(s, (1.0, 0.5), np.array([1.0]), acc, probs)
    assert acc[0] == 0.0 and [c.tag for c in s] == ["a", "b"] and probs[0] == 1.0


def test_check_adapt():
    assert tempering.check_adapt(False, None, False) is False
    assert tempering.check_adapt(np.bool_(True), (1.0, 2.0, 4.0), True) is True
    with pytest.raises(GPMSAError, match="needs temperatures="):
        tempering.check_adapt(True, None, True)
    with pytest.raises(GPMSAError, match=r"at least 3 temperatures, got \[1.0, 2.0\]"):
        tempering.check_adapt(True, (1.0, 2.0), True)
    with pytest.raises(GPMSAError, match="tune=False"):
        tempering.check_adapt(True, (1.0, 2.0, 4.0), False)
    with pytest.raises(GPMSAError, match="adapt_ladder must be True or False"):
        tempering.check_adapt(1, (1.0, 2.0, 4.0), True)


def _gaps_by_hand(log_gap, probs, n, top):
    kappa = 0.1 * 200.0 / (n + 200.0)
    moved = np.asarray(log_gap) + kappa * (np.asarray(probs) - np.mean(probs))
    return moved + math.log(top - 1.0) - math.log(np.exp(moved).sum())


def test_adapt_gaps_step_by_hand():
    """Ladder (1, 2, 4, 8): gaps 1, 2, 4; rates 0.2, 0.5, 0.8 at round 100: kappa = 1/15."""
    log_gap, probs = np.log([1.0, 2.0, 4.0]), np.array([0.2, 0.5, 0.8])
    out = tempering.adapt_gaps(log_gap, probs, 100, 8.0)
    moved = np.log([1.0, 2.0, 4.0]) + np.array([-0.3, 0.0, 0.3]) / 15.0
    shift = math.log(7.0) - math.log(math.exp(moved[0]) + 2.0 + 4.0 * math.exp(0.02))
    np.testing.assert_allclose(out, moved + shift, rtol=0, atol=1e-14)
    assert np.exp(out).sum() == pytest.approx(7.0, rel=1e-14)  # the hottest stays 8
    assert log_gap.tolist() == np.log([1.0, 2.0, 4.0]).tolist()  # the input unchanged
    first = tempering.adapt_gaps(log_gap, probs, 0, 8.0)  # kappa_0 = 0.1
    np.testing.assert_allclose(first, _gaps_by_hand(log_gap, probs, 0, 8.0), atol=1e-14)
    assert first[0] < np.log(1.0) + 0.0 and first[2] > np.log(4.0) - 0.03  # low rate: narrower


def test_adapt_gaps_one_ladder_per_chain():
    log_gap = np.log([[1.0, 2.0, 4.0], [3.0, 3.0, 3.0]])
    probs = np.array([[0.2, 0.5, 0.8], [0.9, 0.0, 0.3]])
    out = tempering.adapt_gaps(log_gap, probs, 7, 8.0)
    assert out.shape == (2, 3)
    for row in range(2):
        np.testing.assert_allclose(
            out[row], _gaps_by_hand(log_gap[row], probs[row], 7, 8.0), rtol=0, atol=1e-14
        )


def test_gap_ladder_and_kept_ladder():
    np.testing.assert_array_equal(tempering.gap_ladder(np.log([1.0, 2.0, 4.0]), 8.0), [1, 2, 4, 8])
    out = tempering.gap_ladder(np.log([[1.0, 2.0], [0.5, 0.5]]), 3.5)
    np.testing.assert_allclose(out, [[1.0, 2.0, 3.5], [1.0, 1.5, 3.5]], rtol=0, atol=1e-15)
    start = (1.0, 3.0, 9.0)
    np.testing.assert_allclose(tempering.kept_ladder(np.log([1.0, 7.0]), start), [1, 2, 9])
    # a gap below the rung's resolution: rungs 1 and 1 + 1e-300 merge, the start is kept
    np.testing.assert_array_equal(tempering.kept_ladder(np.array([-800.0, 0.0]), start), start)
    # a rung past the hottest (gaps 1 + 9 > 8): the start kept
    np.testing.assert_array_equal(tempering.kept_ladder(np.log([9.0, 1.0]), start), start)
    both = tempering.kept_ladder(np.log([[9.0, 1.0], [1.0, 7.0]]), start)  # row by row
    np.testing.assert_allclose(both, [[1.0, 3.0, 9.0], [1.0, 2.0, 9.0]])


def test_adapt_ladder_by_hand():
    """Copies never swap (u near 1, every log ratio < 0); 2 rounds x 3 levels; the ladder kept is
    the mean of the log gaps after swap rounds n = 3, 4, 5 (the second half)."""
    temps = (1.0, 2.0, 8.0)
    logliks = [-1.0, -3.0, -9.0]
    states = [_Copy(ll, t) for ll, t in zip(logliks, "abc", strict=True)]
    for s, t in zip(states, temps, strict=True):
        s.beta = 1.0 / t
    rng, rounds = _Rng(value=0.999999999), []
    widths = np.array([0.2])
    out = tempering.adapt_ladder(states, temps, rng, ["theta"], widths, 2, 3, rounds.append)
    ladder, seen = np.array(temps), []
    for n in range(6):
        b = 1.0 / ladder
        probs = np.array([min(1.0, math.exp((b[k] - b[k + 1]) * (logliks[k + 1] - logliks[k])))
                          for k in range(2)])  # fmt: skip
        gaps = _gaps_by_hand(np.log(np.diff(ladder)), probs, n, 8.0)
        ladder = np.concatenate([[1.0], 1.0 + np.cumsum(np.exp(gaps))])
        ladder[-1] = 8.0
        seen.append(gaps)
    mean = (seen[3] + seen[4] + seen[5]) / 3.0
    want = [1.0, 1.0 + math.exp(mean[0]), 8.0]
    assert out == pytest.approx(want, rel=1e-13) and out[0] == 1.0 and out[-1] == 8.0
    assert out[1] != pytest.approx(2.0, rel=1e-3)  # it moved
    assert [s.beta for s in states] == [1.0 / t for t in out] and [s.tag for s in states] == [
        "a", "b", "c"]  # fmt: skip
    assert rounds == [9, 9] and rng.sizes == [2] * 6
    cands = [w for w, _ in states[1].widths]
    assert len(cands) == 6 and cands[0] != cands[1] and np.array_equal(cands[0], cands[3])
    assert all(mh is False for s in states for _, mh in s.widths)  # GPM/SA's tuning sweeps


def test_run_ladder_schedule_rates_and_progress():
    """No tuning: 250 sweeps, a swap round after sweeps 3, 6, ... (swap_every 3): 83 rounds."""
    states = [_Copy(-1.0, "a", 1.0), _Copy(-1.0, "b", 0.5, 2.0), _Copy(-1.0, "c", 0.25, 3.0)]
    calls = []
    rng = _Rng(value=0.5)  # equal log L: every proposal accepted (log 0.5 < 0)
    rng_random = rng.random

    def random(n):
        calls.append(len(kept))
        return rng_random(n)

    rng.random, kept, bar, out = random, [], _Bar(), {}
    hot = [np.array([0.3]), np.array([0.4])]
    acc, w, rates, temps = tempering.run_ladder(
        states, rng, 250, np.array([0.1]), ["theta"], kept.append, swap_every=3, tune=False,
        tune_rounds=2, tune_levels=2, prop_mh=True, bar=bar, desc="d", copy_widths=hot, out=out,
    )  # fmt: skip
    assert kept == list(range(250)) and calls == list(range(2, 250, 3)) and len(calls) == 83
    np.testing.assert_array_equal(rates, [1.0, 1.0])  # 83 swaps of 250 // 3 = 83 rounds
    assert temps is None and acc.tolist() == [250.0] and w.tolist() == [0.1]
    assert bar.updates == [300, 300, 150] and sum(bar.updates) == 3 * 250
    assert [x.tolist() for x in out["widths"]] == [[0.1], [0.3], [0.4]]
    assert states[2].widths[0][0].tolist() == [0.4] and states[2].widths[0][1] is True
    assert states[1].shifts == ["a"] and states[0].shifts == ["learn"]
    assert rng.sizes == [2] * 83
    bar = _Bar()
    tempering.run_ladder(
        states, _Rng(), 200, np.array([0.1]), ["theta"], lambda it: None, swap_every=1,
        tune=False, tune_rounds=1, tune_levels=1, prop_mh=True, bar=bar, desc="d",
    )  # fmt: skip
    assert bar.updates == [300, 300, 0]


def test_run_ladder_rates_count_the_draws_rounds_only():
    """Tuning's swap rounds (all accepted) are not counted; then 4 sweeps, swap_every 2: two
    rounds, one accepted (u 0.5) and one refused (u 1: log u = 0 is not below 0)."""
    states = [_Copy(-2.0, "a", 1.0), _Copy(-2.0, "b", 0.5)]
    rng = _Rng(script=[[0.5]] * 4 + [[0.5], [1.0]])
    bar = _Bar()
    _, w, rates, _ = tempering.run_ladder(
        states, rng, 4, np.array([0.1]), ["theta"], lambda it: None, swap_every=2, tune=True,
        tune_rounds=2, tune_levels=2, prop_mh=True, bar=bar, desc="d",
    )  # fmt: skip
    np.testing.assert_array_equal(rates, [0.5])
    cands = tempering.tuning.level_widths(["theta"], np.array([0.1]), 2)
    for s in states:  # 2 rounds x 2 levels of tuning sweeps, then 4 draws' sweeps
        assert [mh for _, mh in s.widths] == [False] * 4 + [True] * 4
        assert [x[0] for x, _ in s.widths[:4]] == [cands[0, 0], cands[1, 0]] * 2
    assert w.tolist() == [cands[:, 0].max()]  # every proposal accepted: the widest
    assert bar.updates == [4, 4, 8] and rng.sizes == [1] * 6
    assert "tuning step widths (2 temperatures)" in bar.texts[0]
    _, _, rates, _ = tempering.run_ladder(
        [_Copy(-2.0, "a", 1.0), _Copy(-2.0, "b", 0.5)], _Rng(value=0.5), 5, np.array([0.1]),
        ["theta"], lambda it: None, swap_every=5, tune=False, tune_rounds=1, tune_levels=1,
        prop_mh=False, bar=_Bar(), desc="d",
    )  # fmt: skip
    np.testing.assert_array_equal(rates, [1.0])  # 1 round of 5 // 5


def test_run_ladder_shares_the_level_shifts_and_adapts_first():
    """Adapt, tune, draw: the T = 1 copy's level shifts learnt and shared before each phase;
    the ladder adapted (as `adapt_ladder` on the same copies and draws) and frozen."""
    temps = (1.0, 2.0, 8.0)

    def copies():
        states = [_Copy(ll, t, 1.0 / temp) for ll, t, temp in
                  zip([-1.0, -3.0, -9.0], "abc", temps, strict=True)]  # fmt: skip
        return states

    states, bar, rng = copies(), _Bar(), _Rng(value=0.999999999)
    _, _, _, adapted = tempering.run_ladder(
        states, rng, 3, np.array([0.1]), ["theta"], lambda it: None, swap_every=1, tune=True,
        tune_rounds=2, tune_levels=2, prop_mh=False, bar=bar, desc="d", adapt=temps,
    )  # fmt: skip
    ref = copies()
    want = tempering.adapt_ladder(ref, temps, _Rng(value=0.999999999), ["theta"],
                                  np.array([0.1]), 2, 2, lambda n: None)  # fmt: skip
    assert adapted == want and adapted != temps
    assert [s.beta for s in states] == [1.0 / t for t in want]
    assert states[0].shifts == ["learn"] * 3 and states[2].shifts == ["a"] * 3
    assert bar.texts == ["d: adapting the ladder (3 temperatures)",
                         "d: tuning step widths (3 temperatures)",
                         "d: sampling (3 temperatures)"]  # fmt: skip
    assert bar.updates == [6, 6, 6, 6, 9] and len(states[1].widths) == 4 + 4 + 3
    assert len(rng.sizes) == 4 + 4 + 3


def test_run_ladder_without_elements_or_tuning_runs_no_tuning():
    states, bar = [_Copy(-1.0, "a"), _Copy(-1.0, "b", 0.5)], _Bar()
    tempering.run_ladder(
        states, _Rng(), 2, np.zeros(0), [], lambda it: None, swap_every=1, tune=True,
        tune_rounds=2, tune_levels=2, prop_mh=False, bar=bar, desc="d", adapt=(1.0, 2.0, 4.0),
    )  # fmt: skip
    assert bar.texts == ["d: sampling (2 temperatures)"] and states[0].shifts == ["learn"]
    assert len(states[0].widths) == 2 and states[1].beta == 0.5


class _FakeBar:
    def __init__(self, total):
        self.total, self.updates = total, []

    def update(self, n):
        self.updates.append(n)

    def set_description(self, text):
        pass


@pytest.mark.parametrize(
    ("tune", "adapt", "n_tune"), [(True, True, 2 * 3 * 2), (True, False, 2 * 3), (False, False, 0)]
)
def test_run_tempered_chain_copies_and_records(monkeypatch, tune, adapt, n_tune):
    """The copies at 1 / T, the hot ones at their starts; the arguments ``run_ladder`` gets; the
    progress total K (n_iter + tuning sweeps); the record of the hot copies."""
    from contextlib import contextmanager

    from _tempering_cases import two_mode_case

    from gpmsa.mcmc.sampler import ChainState
    from gpmsa.model.problem import prepare

    problem = prepare(*two_mode_case()).problem
    rng = np.random.default_rng(0)
    made, seen, bars = [], {}, []

    def new_state(at):
        made.append(at)
        return ChainState(problem, problem.init if at is None else at, rng)

    def run_ladder(states, rng_, n_iter, widths, kinds, record, **kw):
        seen.update(kw, betas=[s.beta for s in states], n_iter=n_iter, widths=widths)
        for it in range(n_iter):
            record(it)
        kw["out"]["widths"] = [widths * (k + 1) for k in range(len(states))]
        kw["bar"].update(states[0].beta)
        return np.zeros(widths.size), widths, np.array([0.25, 0.5]), (1.0, 3.0, 9.0)

    @contextmanager
    def progress_bar(progress, total, desc, unit="draw"):
        bars.append((progress, total, desc, unit))
        yield _FakeBar(total)

    checked = []
    monkeypatch.setattr(ChainState, "check_start", lambda self: checked.append(self))
    monkeypatch.setattr(tempering, "run_ladder", run_ladder)
    monkeypatch.setattr(tempering, "progress_bar", progress_bar)
    hot = {**problem.init, "theta": np.array([0.7])}
    widths = {n: np.full(problem.init[n].shape, 0.1) for n in problem.names}
    record = {}
    out = tempering.run_tempered_chain(
        problem, 4, new_state, temperatures=(1.0, 2.0, 4.0), swap_every=1, tune=tune,
        widths=widths, rng=rng, tune_rounds=2, tune_levels=3, desc="x", record=record,
        copies=[(hot, widths), (None, widths)], **({"adapt_ladder": True} if adapt else {}),
    )  # fmt: skip
    assert made[0] is None and made[1] is hot and made[2] is None
    assert len(checked) == 1 and checked[0].beta == 1.0  # the T = 1 copy's start checked
    np.testing.assert_array_equal(out[0]["theta"], np.tile(problem.init["theta"], (4, 1)))
    assert seen["betas"] == [1.0, 0.5, 0.25] and seen["n_iter"] == 4
    assert seen["prop_mh"] is (not tune) and seen["tune"] is tune and seen["swap_every"] == 1
    assert seen["adapt"] == ((1.0, 2.0, 4.0) if adapt else None)
    assert len(seen["copy_widths"]) == 2 and seen["desc"] == "x"
    assert bars == [(False, 3 * (4 + n_tune), "x", "it")]
    assert len(out) == (6 if adapt else 5) and out[1].shape == (4,)
    if adapt:
        np.testing.assert_array_equal(out[5], [1.0, 3.0, 9.0])
    np.testing.assert_array_equal(out[4], [0.25, 0.5])
    states, hot_widths = record["hot"]
    assert len(states) == 2 and states[0]["theta"].tolist() == [0.7]
    assert states[1]["theta"].tolist() == problem.init["theta"].tolist()
    assert len(hot_widths) == 2 and all(set(h) <= set(problem.names) for h in hot_widths)
    assert "level" in record


def test_swap_at_a_zero_uniform_accepts():
    """``Generator.random`` draws from [0, 1): u = 0 (log u = -inf) accepts any finite log
    ratio (it raised 'math domain error' from math.log, ending the chain)."""
    s, acc, probs = [_Copy(-1.0, "a"), _Copy(-50.0, "b")], np.zeros(1), np.zeros(1)
    tempering.swap(s, (1.0, 0.5), np.array([0.0]), acc, probs)
    assert acc[0] == 1.0 and [c.tag for c in s] == ["b", "a"]
    assert probs[0] == pytest.approx(math.exp(-24.5), rel=1e-14)
