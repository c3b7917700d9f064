"""The deploy kernel's vector paths against its per-segment loop: over runs of a regular net
(``net.kernels.spring_blocks``) and, for a traction net's grid, tile by tile of knot rows with
the update fused (``net.kernels._grid_step``): the same forces in the same order, so the same
trajectory to the bit, air off and on, with taut and slack segments; and the blocks of a rotary
net."""

import numpy as np
import pytest

from flexnet_fe.net.config import RotaryNet, TractionNet
from flexnet_fe.net.kernels import MIN_RUN, TILE, _grid_shape, advance, spring_blocks
from flexnet_fe.net.state import Environment, initial_state, kernel_model, kernel_state
from flexnet_fe.net.timestep import spring_limit
from flexnet_fe.net.topology import build_rotary, build_traction

# 21 x 21 knots: 21 rows of 20 bars (s = 1, above MIN_RUN; 12 rows per chunk, so two chunks) and one
# layer of 420 (s = 21, two chunks); ropes 1 cm longer than the bars, so that some segments stay slack
NET = TractionNet(edge_length=1.0, mesh_size=0.05, corner_mass=0.2, corner_speed=30.0, launch_elevation_deg=20.0,
                  slack_offset=-0.01)


def _covered_in_order(blocks: np.ndarray, m: int) -> bool:
    starts, sizes = blocks[:, 0], blocks[:, 1] * blocks[:, 2]
    return starts[0] == 0 and np.array_equal(starts[1:], (starts + sizes)[:-1]) and starts[-1] + sizes[-1] == m


def _run_segments(run) -> tuple[np.ndarray, np.ndarray]:
    """(segment indices, their (i, j) node pairs as the run describes them) of a run block."""
    k0, rows, length, a0, stride, s = run
    q, r = np.divmod(np.arange(rows * length), length)
    i = a0 + q * stride + r
    return k0 + q * length + r, np.column_stack([i, i + s])


def test_traction_blocks_are_the_rows_and_the_layer():
    model = build_traction(NET)
    b = model.kernel_blocks
    assert _covered_in_order(b, model.n_springs)
    assert b.tolist() == [[0, 21, 20, 0, 21, 1], [420, 1, 420, 0, 0, 21]]  # 21 rows of 20 bars; one layer
    for run in b:
        k, ends = _run_segments(run)
        assert np.array_equal(model.springs[k], ends)


def test_rotary_blocks_cover_every_segment_and_skip_hub_links():
    model = build_rotary(RotaryNet())
    b = model.kernel_blocks
    assert _covered_in_order(b, model.n_springs)
    for run in b[b[:, 5] > 0]:
        k, ends = _run_segments(run)
        assert run[2] >= MIN_RUN and not model.hub_link[k].any()
        assert np.array_equal(model.springs[k], ends)


def test_short_and_irregular_segments_take_the_per_segment_loop():
    springs = np.array([[0, 1], [1, 2], [5, 3], [3, 4]] + [[10 + r, 12 + r] for r in range(MIN_RUN)]
                       + [[40 + r, 42 + r] for r in range(MIN_RUN)] + [[70 + r, 72 + r] for r in range(MIN_RUN)])
    b = spring_blocks(springs, np.zeros(len(springs), bool))
    # rows starting at nodes 10, 40, 70: a constant stride of 30, so one block of three rows
    assert b.tolist() == [[0, 1, 4, 0, 0, 0], [4, 3, MIN_RUN, 10, 30, 2]]


@pytest.mark.parametrize("air", [False, True], ids=["air_off", "air_on"])
def test_runs_give_the_per_segment_trajectory_to_the_bit(air):
    model = build_traction(NET)
    env = Environment(np.array([0.0, -9.81, 0.0]), 0.5 if air else 0.0, np.array([3.0, 0.0, -1.0]), air)
    runs = kernel_model(model, env)
    loop = runs._replace(blocks=np.array([[0, 1, model.n_springs, 0, 0, 0]], dtype=np.int64))
    dt = 0.25 * spring_limit(model)
    a, b = initial_state(model, (0.0, 0.0, 20.0)), initial_state(model, (0.0, 0.0, 20.0))
    out_a = advance(runs, kernel_state(a), 300, dt)
    out_b = advance(loop, kernel_state(b), 300, dt)
    assert np.count_nonzero(a.tension == 0.0) > 0 and np.count_nonzero(a.tension > 0.0) > 0
    assert np.array_equal(a.x, b.x) and np.array_equal(a.v, b.v) and np.array_equal(a.tension, b.tension)
    assert out_a == out_b  # peak tension, drag number
    # the dissipation and the air's work are sums: the run path adds them in another order
    assert a.losses == pytest.approx(b.losses, rel=1e-12, abs=1e-15)


def test_rows_stepping_down_stay_separate_runs():
    springs = np.array([[70 + r, 71 + r] for r in range(MIN_RUN)] + [[40 + r, 41 + r] for r in range(MIN_RUN)])
    b = spring_blocks(springs, np.zeros(len(springs), bool))
    assert b.tolist() == [[0, 1, MIN_RUN, 70, 0, 1], [MIN_RUN, 1, MIN_RUN, 40, 0, 1]]


def _split_rows(blocks: np.ndarray) -> np.ndarray:
    """A traction net's blocks with its rows of horizontal bars cut in two blocks: the same
    segments, no longer the grid's two blocks, so the kernel takes its run path."""
    k0, rows, length, a0, stride, s = blocks[0]
    half = rows // 2
    second = [k0 + half * length, rows - half, length, a0 + half * stride, stride, s]
    return np.array([[k0, half, length, a0, stride, s], second, blocks[1]], dtype=np.int64)


# 101 and 61 knots a side: tiles of TILE // W knot rows, the last one a single row without bars up
# (101 = 5 x 20 + 1) or several rows, all but the last with bars up (61 = 33 + 28)
@pytest.mark.parametrize("mesh", [0.01, 1.0 / 60.0], ids=["101", "61"])
@pytest.mark.parametrize("air", [False, True], ids=["air_off", "air_on"])
def test_grid_tiles_and_runs_give_the_per_segment_trajectory_to_the_bit(mesh, air):
    model = build_traction(NET.model_copy(update={"mesh_size": mesh}))
    env = Environment(np.array([0.0, -9.81, 0.0]), 0.5 if air else 0.0, np.array([3.0, 0.0, -1.0]), air)
    grid = kernel_model(model, env)
    w, rows_per_tile = _grid_shape(grid)
    assert w == round(1.0 / mesh) + 1 and rows_per_tile == TILE // w and w > rows_per_tile > 1  # several tiles
    runs = grid._replace(blocks=_split_rows(grid.blocks))
    loop = grid._replace(blocks=np.array([[0, 1, model.n_springs, 0, 0, 0]], dtype=np.int64))
    assert _grid_shape(runs) == (0, 0) and _grid_shape(loop) == (0, 0)
    dt = 0.25 * spring_limit(model)
    states = [initial_state(model, (0.0, 0.0, 20.0)) for _ in range(3)]
    outs = [advance(m, kernel_state(st), 200, dt) for m, st in zip((grid, runs, loop), states)]
    ref = states[2]
    assert np.count_nonzero(ref.tension == 0.0) > 0 and np.count_nonzero(ref.tension > 0.0) > 0
    for st, out in zip(states[:2], outs[:2]):
        assert np.array_equal(st.x, ref.x) and np.array_equal(st.v, ref.v) and np.array_equal(st.tension, ref.tension)
        assert out == outs[2]  # peak tension, drag number
        assert st.losses == pytest.approx(ref.losses, rel=1e-12, abs=1e-15)  # sums, added in another order


def test_only_a_traction_grid_takes_the_grid_path():
    still = Environment(np.zeros(3), 0.0, np.zeros(3), False)
    assert _grid_shape(kernel_model(build_rotary(RotaryNet()), still)) == (0, 0)
    sub = build_traction(NET.model_copy(update={"subdivisions": 2}))  # split bars: the per-segment loop
    assert _grid_shape(kernel_model(sub, still)) == (0, 0)
