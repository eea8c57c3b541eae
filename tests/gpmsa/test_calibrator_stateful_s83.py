"""Random interleavings of a `gpmsa.Calibrator`'s calls (hypothesis state machines, session
83): updates of random windows, with and without a seed and a gridded prior, refused updates,
``copy.copy``, ``copy.deepcopy`` and a pickle round trip, in any order. After every update: its
posterior is the one a new Calibrator gives for that window alone (each update is its own
window; with no seed its lazy draws follow the count of updates made, a refused one not
counted); a twin fed only the accepted updates, and a copy, give the same draws bit for bit."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from _calib_cases import road_emulator
from hypothesis import strategies as st
from hypothesis.stateful import (
    RuleBasedStateMachine,
    initialize,
    invariant,
    rule,
)

import gpmsa
from tests._stateful import COPIES, run_machine

SPEEDS = (0.6, 1.0, 1.25, 1.9)
FEATURES = (9.0, 12.1, 15.0, 20.0)


def summary(post: gpmsa.Posterior) -> tuple:
    """The posterior's exact numbers (the grid's), and its first lazy draws."""
    grid = post.grids["GD"]
    return (post.mean("GD"), post.sd("GD"), post.quantile("GD", 0.9),
            grid.nodes.tobytes(), grid.density.tobytes())  # fmt: skip


def draws(post: gpmsa.Posterior) -> bytes:
    return post.samples["GD"][:50].tobytes()


@st.composite
def windows(draw) -> tuple[list, list]:
    rows = draw(st.lists(st.tuples(st.sampled_from(SPEEDS), st.sampled_from(FEATURES)),
                         min_size=1, max_size=3))  # fmt: skip
    return [[v] for v, _ in rows], [[f] for _, f in rows]


class CalibratorMachine(RuleBasedStateMachine):
    steps = 0

    @initialize(seed=st.integers(0, 2))
    def start(self, seed: int) -> None:
        self.seed = seed
        self.main = gpmsa.Calibrator(road_emulator(), seed=seed)
        self.twin = gpmsa.Calibrator(road_emulator(), seed=seed)
        self.alone = gpmsa.Calibrator(road_emulator(), seed=seed)  # one update per window

    def check(self, window, prior, seed) -> None:
        """An accepted update: main and twin alike, and as a new Calibrator's for the window."""
        self.steps += 1
        got = self.main.update(*window, prior=prior, seed=seed)
        same = self.twin.update(*window, prior=prior, seed=seed)
        assert summary(got) == summary(same) and draws(got) == draws(same)
        fresh = copy.deepcopy(self.alone).update(*window, prior=prior, seed=seed)
        assert summary(got) == summary(fresh)
        if seed is not None:
            assert draws(got) == draws(fresh)
        assert self.main._count == self.twin._count

    @rule(window=windows(), seed=st.sampled_from([None, None, 5]), gridded=st.booleans())
    def update(self, window, seed, gridded: bool) -> None:
        prior = None
        if gridded:  # another window's log-likelihood, as a filter passes it
            prior = self.alone.log_likelihood_grid([[1.0]], [[12.0]])[1]
        self.check(window, prior, seed)

    @rule(kind=st.sampled_from(["nan", "shape", "outside", "prior", "none"]), window=windows())
    def refused(self, kind: str, window) -> None:
        self.steps += 1
        x, y = window
        prior = None
        if kind == "nan":
            y = [[np.nan] for _ in y]
        elif kind == "shape":
            y = [row * 2 for row in y]
        elif kind == "outside":
            x = [[9.0] for _ in x]
        elif kind == "prior":
            prior = np.zeros(3)
        else:
            y = None
        with pytest.raises((gpmsa.GPMSAError, ValueError)):
            self.main.update(x, y, prior=prior)

    @rule(how=st.sampled_from(sorted(COPIES)), keep_copy=st.booleans(), window=windows())
    def copied(self, how: str, keep_copy: bool, window) -> None:
        self.steps += 1
        clone = COPIES[how](self.main)
        first = clone.update(*window)
        got = self.main.update(*window)
        same = self.twin.update(*window)
        assert summary(first) == summary(got) == summary(same)
        assert draws(first) == draws(got) == draws(same)
        if keep_copy:
            self.main = clone

    @invariant()
    def counted_alike(self) -> None:
        if hasattr(self, "main"):
            assert self.main._count == self.twin._count


def run(max_examples: int, steps: int = 20, derandomize: bool = True) -> None:
    run_machine(CalibratorMachine, max_examples, steps, derandomize)


@pytest.mark.filterwarnings("ignore::gpmsa.OutsideEmulatorWarning")  # (far windows: wanted)
def test_calibrator_random_interleavings():
    run(max_examples=8)
