"""The vectorised traction-net topology for unsplit bars (k = 1) builds the same springs, cells
and perimeter, in the same order, as the general per-bar builder (reference: the general path,
``_traction_bars`` / ``_traction_cells_and_loop`` with k = 1) — exact integer equality."""

from __future__ import annotations

import numpy as np
import pytest

from flexnet_fe.net import topology as T


@pytest.mark.parametrize("nk", [2, 3, 6, 21])
def test_unsplit_traction_topology_equals_general_builder(nk):
    kid = np.arange(nk * nk).reshape(nk, nk)
    c = np.arange(nk, dtype=float)
    X, Y = np.meshgrid(c, c)
    knots = np.column_stack([X.ravel(), Y.ravel(), np.zeros(nk * nk)])
    nodes = T._Nodes(knots, 1)
    springs, bars = T._traction_bars(nk, kid.tolist(), nodes, knots)
    cells, loop = T._traction_cells_and_loop(nk, kid.tolist(), bars)
    cells2, loop2 = T._traction_cells_and_loop_unsplit(kid)
    np.testing.assert_array_equal(T._traction_springs_unsplit(kid), np.asarray(springs, dtype=np.int64))
    np.testing.assert_array_equal(cells2, cells)
    np.testing.assert_array_equal(loop2, loop)
    np.testing.assert_array_equal(nodes.coordinates(), knots)  # no interior nodes: x0 = the knots
