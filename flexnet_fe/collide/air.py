"""Air on the rope during the collision (``[collide] air``): the deploy stage's aerodynamic rope
law, Eq. (5)–(8) (``net.forces.segment_aero_force``), on every live rope segment of the kernel.

Frame: the air is at rest in W, the frame of the held net (the net's deploy velocity is discarded
with the paper's assumption 3, "the net is static"; the missile's own air loads are not part of
the impact model). A segment's velocity relative to the air is the mean of its end velocities
(held ends are at rest), its length the current one, its diameter the rope's. Half the force
acts on each end (Eq. (9)–(10), as ``net.kernels._segment_air``); a held end's half is taken by
the held node like any other force, i.e. booked in the held-node impulse (``kernel._integrate``).

Bookkeeping (``collide.model``): the air's work is −F·v̄ dt per step with v̄ the segment's mean
velocity (exactly the power of the two halves on the two ends), ≥ 0 because the law opposes the
relative velocity; it is booked as dissipated (``A_DISS_AIR``) so the energy balance closes.
The air impulse F dt (whole force, both halves) is external: ``A_IMP_AIR`` (3) enters the
momentum closure (``simulate``).

Explicit drag is stable while dt < 2 m / (∂F/∂v) at each node; ``drag_step_ratio`` gives the
bound the collision's step is checked against (``simulate.build``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from flexnet_fe.collide.model import A_DISS_AIR, A_IMP_AIR
from flexnet_fe.net.forces import CD_FRICTION, C_CROSS, segment_aero_force


@njit(cache=True, error_model="numpy", _nrt=False)
def segment_air(model, state, f, e, u, length, dt, scale):
    """Adds ``scale`` × the air force on live segment e, Eq. (5)–(8), half to each end node's row of
    f [N] (n, 3); books its work and impulse over dt [s], the time the force acts (scale × the
    step the caller multiplies f by: the far net's air impulse of several windows,
    ``kernel._far_window``). u unit vector i → j (3 floats), length [m] the segment's current
    length. A no-op (no arithmetic on f) when ``model.air_density`` is 0 (air off). Compiled
    without reference counting, as the kernel's loops that call it per segment (``collide.kernel``,
    "Call cost")."""
    if model.air_density == 0.0:
        return
    if e >= model.diameter.shape[0]:  # a hand-built model with air but no diameters (no bounds check in numba)
        raise ValueError("collide.air: CollideModel.diameter needs one entry per segment")
    v = state.v
    i, j = model.seg[e, 0], model.seg[e, 1]
    vm0, vm1, vm2 = 0.5 * (v[i, 0] + v[j, 0]), 0.5 * (v[i, 1] + v[j, 1]), 0.5 * (v[i, 2] + v[j, 2])
    fx, fy, fz, _ = segment_aero_force(u, length, (vm0, vm1, vm2), model.air_density, model.diameter[e])
    h = 0.5 * scale
    f[i, 0] += h * fx
    f[i, 1] += h * fy
    f[i, 2] += h * fz
    f[j, 0] += h * fx
    f[j, 1] += h * fy
    f[j, 2] += h * fz
    acc = state.acc
    acc[A_DISS_AIR] -= (fx * vm0 + fy * vm1 + fz * vm2) * dt
    acc[A_IMP_AIR] += fx * dt
    acc[A_IMP_AIR + 1] += fy * dt
    acc[A_IMP_AIR + 2] += fz * dt


def drag_step_ratio(mass: np.ndarray, seg: np.ndarray, length: np.ndarray, diameter: np.ndarray, rho: float,
                    speed: float, dt: float) -> float:
    """Largest dt · (∂F/∂v)_i / m_i over the nodes [-] for segments of length [m] (s,) and
    diameter [m] (s,) between nodes seg (s, 2) of mass [kg] (n,), in air of density rho
    [kg/m³], at relative speed ``speed`` [m/s]. The law's derivative with respect to the
    segment's mean velocity is at most ρ d l (C_f + C_x) |v| (|∂(|v| v)/∂v| = 2|v|); each end
    takes half the force and moves v̄ by half its own change, so a node's share is at most a
    quarter of it per segment — half is counted (a factor 2 of margin). Explicit Euler on the
    drag alone is stable (dt λ < 2) and monotone (dt λ < 1) while the ratio is < 1."""
    rate = rho * diameter * length * (CD_FRICTION + C_CROSS) * speed
    per_node = np.zeros(mass.shape[0])
    np.add.at(per_node, seg[:, 0], 0.5 * rate)
    np.add.at(per_node, seg[:, 1], 0.5 * rate)
    return float(np.max(dt * per_node / mass)) if mass.size else 0.0
