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


def _byte_grid_count(xy, cells, pixel):
    """The covered pixel centres counted on a byte grid, in plain Python with ``raster_area``'s
    scanline arithmetic (its form before the bit grid): the reference for the bit marking."""
    xmin, ymin = xy[:, 0].min(), xy[:, 1].min()
    nx = int(math.ceil((xy[:, 0].max() - xmin) / pixel)) + 1
    ny = int(math.ceil((xy[:, 1].max() - ymin) / pixel)) + 1
    grid = np.zeros((ny, nx), dtype=np.uint8)
    h = 1.0 / pixel
    for tri in cells:
        (ax, ay), (bx, by), (cx, cy) = (((float(xy[k, 0]) - xmin) * h, (float(xy[k, 1]) - ymin) * h) for k in tri)
        if (bx - ax) * (cy - ay) - (by - ay) * (cx - ax) == 0.0:
            continue
        if ay > by:
            ax, ay, bx, by = bx, by, ax, ay
        if by > cy:
            bx, by, cx, cy = cx, cy, bx, by
        if ay > by:
            ax, ay, bx, by = bx, by, ax, ay
        s_ac = (cx - ax) / (cy - ay)
        s_ab = (bx - ax) / (by - ay) if by > ay else 0.0
        s_bc = (cx - bx) / (cy - by) if cy > by else 0.0
        for j in range(max(0, math.ceil(ay - 0.5)), min(ny - 1, math.floor(cy - 0.5)) + 1):
            py = j + 0.5
            x1 = ax + (py - ay) * s_ac
            x2 = ax + (py - ay) * s_ab if py < by else bx + (py - by) * s_bc
            if by == ay and py <= by:
                x2 = bx
            i0 = max(0, math.ceil(min(x1, x2) - 0.5))
            i1 = min(nx - 1, math.floor(max(x1, x2) - 0.5))
            grid[j, i0:i1 + 1] = 1
    return int(grid.sum())


def test_bit_grid_counts_the_byte_grid_pixels():
    """The bit grid marks the pixels the byte grid marked, spans within one 64-pixel word and
    across words (pixels 2 mm to 5 cm on a 1 m net: rows of 21 to 500 pixels), folded,
    rotated and randomly crumpled."""
    t = build_traction(TractionNet(edge_length=1.0, mesh_size=0.1))
    xy = np.ascontiguousarray(t.x0[:, :2])
    rng = np.random.default_rng(7)
    folded = xy.copy()
    folded[:, 0] = -np.abs(folded[:, 0])
    shapes = [xy, folded, np.ascontiguousarray(xy @ np.array([[0.8, 0.6], [-0.6, 0.8]]))]
    shapes += [xy + rng.normal(0.0, 0.04, xy.shape) for _ in range(3)]
    for shape in shapes:
        for pixel in (0.002, 0.0037, 0.01, 0.05):
            count = _byte_grid_count(shape, t.cells, pixel)
            assert count > 0
            assert raster_area(shape, t.cells, pixel) == count * pixel * pixel
