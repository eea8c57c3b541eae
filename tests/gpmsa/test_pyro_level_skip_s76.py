"""The pyro backend's level move skips the likelihood of a candidate the theta constraint
rejects (session 76; it evaluated it, then rejected it on its -inf prior): the same draws, the
random stream consumed alike."""

import numpy as np
import pytest
from _level_cases import level_case

from gpmsa.calibration.calibrate import calibration_problem

torch = pytest.importorskip("torch")
pytest.importorskip("pyro")
pb = pytest.importorskip("gpmsa.backends.pyro_backend")


def no_kind0_above(th) -> bool:
    """Kind 0 only with k < 0.7 (the level case's kind-0 mode, k = 0.9, cut off)."""
    return bool(th[1] != 0 or th[0] < 0.7)


def _jumps(constraint):
    """A `LevelJumps` on the level case, its offsets set by hand (kind 0 at k + 0.5, kind 2
    at k - 0.2), without NUTS (the moves alone)."""
    _, emu, xo, yo = level_case()
    model = pb.PyroModel(calibration_problem(emu, xo, yo, constraint=constraint))
    jumps = pb.LevelJumps(None, model, np.random.default_rng(3))
    cat = int(model.cat[0])
    jumps.offsets = {cat: np.array([[0.5], [0.0], [-0.2]])}  # unit-scale k's shift per level
    prm = model.params({pb._site(a): v.unsqueeze(0) for a, v in model.init_values(
        {**model.problem.init, "theta": np.array([0.4, 0.5])}).items()})  # fmt: skip
    return jumps, prm


def _spied(jumps, monkeypatch, minus_inf_at_kind0=False):
    """Record (k, kind) (unit scale: kind 0, 1, 2 at 0, 0.5, 1) of every candidate `_moves`
    evaluates; optionally give kind 0's candidates (all at k = 0.9) the -inf the constraint's
    prior term would (the old path)."""
    seen, real = [], jumps.model.log_post_at

    def spy(at, combo):
        k, kind = float(at["theta"][0, 0]), float(combo[0])
        seen.append((k, kind))
        if minus_inf_at_kind0 and kind == 0.0:
            return torch.full((1,), -torch.inf, dtype=torch.float64)
        return real(at, combo)

    monkeypatch.setattr(jumps.model, "log_post_at", spy)
    return seen


def test_a_rejected_candidate_is_not_evaluated_and_the_stream_is_unchanged(monkeypatch):
    """From kind 1 at k = 0.4 a move to kind 0 lands at k = 0.9 (rejected), to kind 2 at
    k = 0.2 (asked). The random stream after 40 moves equals that of the old path (every
    candidate evaluated, kind 0's at -inf), so seeded chains draw as before."""
    jumps, prm = _jumps(no_kind0_above)
    seen = _spied(jumps, monkeypatch)
    old, old_prm = _jumps(None)
    old_seen = _spied(old, monkeypatch, minus_inf_at_kind0=True)
    for _ in range(40):
        assert jumps._moves(prm, 1, 1e300)[0] is None  # never accepted (from a huge lp)
        old._moves(old_prm, 1, 1e300)
    assert jumps.moves == old.moves == 40
    assert {kind for _, kind in seen} == {1.0}, seen  # kind 2 only
    assert sum(kind == 0.0 for _, kind in old_seen) == 40 - len(seen) > 0
    assert jumps.rng.bit_generator.state == old.rng.bit_generator.state


def test_without_a_constraint_every_candidate_inside_the_prior_is_evaluated(monkeypatch):
    jumps, prm = _jumps(None)
    seen = _spied(jumps, monkeypatch)
    for _ in range(20):
        jumps._moves(prm, 1, 1e300)
    assert len(seen) == jumps.moves == 20
