"""Maximum net area under refinement of the lumped-mass discretisation (observed order)."""

import math

import numpy as np

from flexnet_fe.net.area import loop_area, raster_area
from flexnet_fe.net.config import RotaryNet
from flexnet_fe.net.state import Environment, initial_state, step_many
from flexnet_fe.net.timestep import spring_limit
from flexnet_fe.net.topology import build_rotary

NO_LOADS = Environment(gravity=np.zeros(3), rho=0.0, wind=np.zeros(3), air=False)
SMALL = dict(warps=8, warp_length=0.6, mesh_size=0.1, rope_diameter=5e-3, hub_spin=20.0, tip_speed=14.0, tip_mass=0.05,
             hub_mass=0.5)


def max_area(k: int) -> float:
    """First maximum of the area (perimeter loop, = union area while the outline does not fold;
    checked below) of a small rotary net whose bars are split into k segments, sampled at
    every step (dt = 0.3 dt_crit ∝ 1/k) and refined by a parabola through the top three samples."""
    # "material": the rope keeps one viscosity under refinement, so the lumped-mass model
    # converges to one continuum (the per-segment law damps a finer rope less per metre)
    model = build_rotary(RotaryNet(subdivisions=k, damping_law="material", **SMALL))
    st = initial_state(model)
    dt = 0.3 * spring_limit(model)
    a = np.empty(int(0.2 / dt))
    for i in range(len(a)):
        step_many(model, st, NO_LOADS, dt, 1)
        a[i] = loop_area(st.x[:, :2], model.boundary_loop)
    i = int(np.argmax(a))
    assert 0 < i < len(a) - 1
    if k == 1:  # the loop equals the definition (union of cells) to the raster's resolution
        st2 = initial_state(model)
        step_many(model, st2, NO_LOADS, dt, i + 1)
        perimeter = 8 * 2 * 0.7 * math.sin(math.pi / 8) * 2  # outline at most twice the initial one
        assert abs(raster_area(np.ascontiguousarray(st2.x[:, :2]), model.cells, 1e-3) - a[i]) < perimeter * 1e-3 / 2
    y0, y1, y2 = a[i - 1], a[i], a[i + 1]
    return y1 - (y2 - y0) ** 2 / (8 * (y0 - 2 * y1 + y2))


def test_max_area_converges_with_observed_order():
    areas = np.array([max_area(k) for k in (1, 2, 4, 8)])
    d = np.diff(areas)
    orders = np.log2(np.abs(d[:-1] / d[1:]))
    # expected: at least second order (lumped masses and straight segments are O(h²) models of
    # the rope; the integrator is second order in positions with dt ∝ h). Measured ≈ 4.2, 4.0.
    assert np.all(orders > 2.0), f"observed orders {orders}, areas {areas}"
    # and the finest two levels agree to 0.1 %
    assert abs(d[-1]) < 1e-3 * areas[-1]
