"""Net area: rasterised union of projected cells vs exact polygon areas."""

import math

import numpy as np
import pytest

from flexnet_fe.net.area import loop_area, raster_area
from flexnet_fe.net.config import RotaryNet, TractionNet
from flexnet_fe.net.topology import build_rotary, build_traction


def test_flat_nets_initial_area():
    t = build_traction(TractionNet(edge_length=2.0, mesh_size=0.1))
    r = build_rotary(RotaryNet())
    pixel = 0.01
    # exact: square 2 × 2 m; regular octagon of circumradius R = 3.1 m: (n/2) R² sin(2π/n)
    for model, exact, perim in ((t, 4.0, 8.0), (r, 4 * 3.1**2 * math.sin(math.pi / 4), 16 * 3.1 * math.sin(math.pi / 8))):
        xy = np.ascontiguousarray(model.x0[:, :2])
        assert loop_area(xy, model.boundary_loop) == pytest.approx(exact, rel=1e-12)
        # resolution bound: only pixels cut by the outline can be wrong -> perimeter × pixel / 2
        assert abs(raster_area(xy, model.cells, pixel) - exact) <= perim * pixel / 2


def test_union_counts_overlap_once_and_rotation_invariant():
    t = build_traction(TractionNet(edge_length=1.0, mesh_size=0.1))
    xy = np.ascontiguousarray(t.x0[:, :2])
    # fold the right half of the net over the left half: the union is the left half only
    folded = xy.copy()
    folded[:, 0] = -np.abs(folded[:, 0])
    assert raster_area(folded, t.cells, 0.002) == pytest.approx(0.5, abs=4 * 0.002 / 2)
    # a rotated net covers the same area (within the resolution bound)
    c, s = math.cos(0.3), math.sin(0.3)
    rot = np.ascontiguousarray(xy @ np.array([[c, s], [-s, c]]))
    assert raster_area(rot, t.cells, 0.002) == pytest.approx(1.0, abs=4 * 0.002 / 2)
