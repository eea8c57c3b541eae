"""`grid.trimmed_marginal` keeps exactly one zero-density node past the outermost nodes of
positive density on each side, and the marginal it returns lies on the nodes of the slice it
returns (session 85, mutation testing of the grid helpers)."""

from __future__ import annotations

import numpy as np
import pytest

from gpmsa.calibration.grid import trimmed_marginal


@pytest.mark.parametrize(
    ("live", "kept"),
    [((4, 7), (3, 8)), ((0, 5), (0, 6)), ((6, 11), (5, 11)), ((0, 11), (0, 11))],
)
def test_one_zero_node_is_kept_on_each_side_of_the_mass(live, kept):
    nodes = np.linspace(0.0, 1.0, 11)
    log_density = np.full(11, -np.inf)
    log_density[live[0] : live[1]] = 0.0
    gm, got = trimmed_marginal(nodes, log_density)
    assert (got.start, got.stop) == kept
    np.testing.assert_array_equal(gm.nodes, nodes[got])
    assert gm.ppf(1.0) == pytest.approx(nodes[kept[1] - 1])  # the mass ends at the zero node
    assert gm.ppf(0.0) == pytest.approx(nodes[kept[0]])
