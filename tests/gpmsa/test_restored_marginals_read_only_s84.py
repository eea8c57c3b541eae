"""Grid and level marginals stay read-only through pickle and ``copy.deepcopy`` (session 84),
as made by ``from_log_density`` / ``from_probabilities`` and as a restored Calibrator's grid
(session 83). Before: numpy restores an array writable, so a restored posterior's marginal took
a write (``nodes *= 1e-6``, a unit conversion in place) that a fresh one refuses. A shallow
``copy.copy`` leaves the original's arrays as they were."""

import copy
import pickle

import numpy as np
import pytest

from gpmsa.calibration.posterior import GridMarginal, LevelMarginal

RESTORES = pytest.mark.parametrize(
    "restore", [lambda m: pickle.loads(pickle.dumps(m)), copy.deepcopy, copy.copy],
    ids=["pickle", "deepcopy", "copy"],
)  # fmt: skip


def _marginals():
    nodes = np.linspace(200.0, 600.0, 9)
    grid = GridMarginal.from_log_density(nodes, -0.5 * ((nodes - 350.0) / 60.0) ** 2)
    levels = LevelMarginal.from_probabilities([1.0, 2.0, 3.0], [0.2, 0.3, 0.5])
    return grid, levels


@RESTORES
@pytest.mark.parametrize("field", ["nodes", "density", "weights"])
def test_a_restored_marginal_refuses_writes_and_keeps_its_summaries(restore, field):
    for marginal in _marginals():
        twin = restore(marginal)
        with pytest.raises(ValueError, match="read-only"):
            getattr(twin, field)[...] *= 1e-6
        assert twin.mean() == marginal.mean() and twin.sd() == marginal.sd()
        np.testing.assert_array_equal(getattr(twin, field), getattr(marginal, field))


def test_a_shallow_copy_leaves_the_originals_arrays_as_they_are():
    nodes, density = np.array([0.0, 1.0, 2.0]), np.array([0.25, 0.5, 0.25])
    weights = np.array([0.5, 1.0, 0.5])
    made_by_hand = GridMarginal(nodes, density, weights)  # the dataclass's own constructor
    twin = copy.copy(made_by_hand)
    assert nodes.flags.writeable and density.flags.writeable and weights.flags.writeable
    assert not twin.nodes.flags.writeable and twin.mean() == made_by_hand.mean()


def test_a_deepcopy_beside_its_own_nodes_shares_nothing_with_them():
    """Review: ``copy.deepcopy([m, m.nodes])`` restored the marginal's nodes as a read-only view
    of the list's writable copy, so a write through the list moved the marginal."""
    grid, _ = _marginals()
    twin, nodes = copy.deepcopy([grid, grid.nodes])
    nodes *= 1e-6
    np.testing.assert_array_equal(twin.nodes, grid.nodes)
    assert twin.mean() == grid.mean()
