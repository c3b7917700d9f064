"""Net state (what changes), the loads environment, and stepping a model in compiled chunks."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from flexnet_fe.errors import NumericalError
from flexnet_fe.net.forces import rope_elastic_energy
from flexnet_fe.net.hub import wrap_geometry
from flexnet_fe.net.kernels import DeployModel, DeployState, advance, net_forces
from flexnet_fe.net.topology import NetModel


@dataclass
class NetState:
    """t [s]; x, v (n, 3) [m], [m/s]; hub = (θ [rad], ω [rad/s]) (2,); wrap (m,) wound angle of
    each hub link [rad]; tension (m,) [N] at the last force evaluation; losses (2,) [J] since
    t = 0: (energy dissipated by the rope dashpots, work of the air on the motion about the
    centre of mass) — the terms that close the energy balance (``net.kernels.advance``)."""

    t: float
    x: np.ndarray
    v: np.ndarray
    hub: np.ndarray
    wrap: np.ndarray
    tension: np.ndarray
    losses: np.ndarray = field(default_factory=lambda: np.zeros(2))


@dataclass(frozen=True)
class Environment:
    """gravity (3,) [m/s^2]; rho air density [kg/m^3]; wind (3,) [m/s] (air velocity in W);
    air: aerodynamic loads on/off."""

    gravity: np.ndarray
    rho: float
    wind: np.ndarray
    air: bool


def initial_state(model: NetModel, flight_velocity=(0.0, 0.0, 0.0)) -> NetState:
    """The model's t = 0 state, every node also moving with ``flight_velocity`` (3,) [m/s]."""
    return NetState(0.0, model.x0.copy(), model.v0 + np.asarray(flight_velocity, dtype=float),
                    np.array([0.0, model.hub_spin0]), np.zeros(model.n_springs), np.zeros(model.n_springs))


def kernel_model(model: NetModel, env: Environment) -> DeployModel:
    """The deploy kernel's read-only data: ``model`` under the loads ``env``."""
    return DeployModel(model.kernel_springs, model.rest_length, model.stiffness, model.damping,
                       model.slack_offset, model.diameter, model.hub_link, model.links,
                       model.anchor_angle, model.mass, int(model.hub_node),
                       float(model.hub_radius), 0.5 * float(model.hub_length),
                       float(model.hub_inertia) if model.hub_node >= 0 else 1.0,
                       np.asarray(env.gravity, dtype=float), float(env.rho),
                       np.asarray(env.wind, dtype=float), bool(env.air), model.kernel_blocks)


def kernel_state(state: NetState, wrap: np.ndarray | None = None) -> DeployState:
    """The deploy kernel's view of ``state`` (same arrays: the kernel changes them in place);
    ``wrap`` replaces ``state.wrap`` when given."""
    return DeployState(state.x, state.v, state.hub, state.wrap if wrap is None else wrap, state.tension,
                       state.losses)


def step_many(model: NetModel, state: NetState, env: Environment, dt: float, n_steps: int,
              dt_limit: float = math.nan) -> tuple[float, float]:
    """Advance ``state`` in place by ``n_steps`` × ``dt`` [s] in one compiled call.

    Returns (largest rope tension [N] seen, largest drag stability number λ dt seen; must stay
    <= 2). Raises NumericalError if the state is no longer finite, naming dt and ``dt_limit``
    (the stability limit it was chosen against) and the drag number."""
    peak, drag_number = advance(kernel_model(model, env), kernel_state(state), int(n_steps), float(dt))
    state.t += n_steps * dt
    if not (np.isfinite(state.x).all() and np.isfinite(state.v).all() and np.isfinite(state.hub).all()):
        raise NumericalError(
            f"net state became non-finite by t = {state.t:.6g} s: dt = {dt:.4g} s against a "
            f"stability limit dt_crit = {dt_limit:.4g} s (drag stability number λ·dt = {drag_number:.3g}, limit 2)")
    return float(peak), float(drag_number)


def evaluate_tensions(model: NetModel, state: NetState, env: Environment) -> None:
    """Fill ``state.tension`` [N] from the current state without advancing it."""
    net_forces(kernel_model(model, env), kernel_state(state, state.wrap.copy()), np.empty_like(state.x),
               np.zeros(len(state.x)))


@njit(cache=True)
def _lengths(model, state):
    """Segment lengths [m] (m,) of a DeployState under a DeployModel (hub links: free part +
    wound part, the wound angle from ``state.wrap`` updated by the current geometry)."""
    x = state.x
    springs, hub, r0 = model.springs, model.hub, model.r0
    theta = state.hub[0]
    m = springs.shape[0]
    out = np.empty(m)
    for s in range(m):
        j = springs[s, 1]
        if model.hub_link[s]:
            if abs(x[j, 2] - x[hub, 2]) > model.half_length:
                gamma, w = theta + model.anchor[s], 0.0
            else:
                gamma, w = wrap_geometry(x[j, 0] - x[hub, 0], x[j, 1] - x[hub, 1], theta + model.anchor[s], r0,
                                         state.wrap[s])
            d0 = x[j, 0] - x[hub, 0] - r0 * math.cos(gamma)
            d1 = x[j, 1] - x[hub, 1] - r0 * math.sin(gamma)
            d2 = x[j, 2] - x[hub, 2]
            out[s] = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2) + r0 * abs(w)
        else:
            i = springs[s, 0]
            d0 = x[j, 0] - x[i, 0]; d1 = x[j, 1] - x[i, 1]; d2 = x[j, 2] - x[i, 2]
            out[s] = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    return out


@njit(cache=True)
def _elastic_energy(stretch, stiffness):
    """Σ ½ K s² [J] over taut segments (``net.forces.rope_elastic_energy``, the collide kernel's too)."""
    pe = 0.0
    for s in range(stretch.shape[0]):
        pe += rope_elastic_energy(stretch[s], stiffness[s])
    return pe


_NO_LOADS = Environment(gravity=np.zeros(3), rho=0.0, wind=np.zeros(3), air=False)


def segment_lengths(model: NetModel, state: NetState) -> np.ndarray:
    """Current length of each segment [m], shape (m,) (hub links: free part + wound part)."""
    return _lengths(kernel_model(model, _NO_LOADS), kernel_state(state))


def energies(model: NetModel, state: NetState, gravity=(0.0, 0.0, 0.0)) -> dict[str, float]:
    """kinetic (translation + hub spin), elastic and gravitational potential energy [J]."""
    sq = state.v**2  # |v|² per node summed as np.sum(axis=1) sums three (q0 + q1 + q2, left to right):
    ke = 0.5 * float(np.sum(model.mass * ((sq[:, 0] + sq[:, 1]) + sq[:, 2])))  # the same bits, 1/7 the time
    if model.hub_node >= 0:
        ke += 0.5 * model.hub_inertia * state.hub[1] ** 2
    l = segment_lengths(model, state)
    stretch = l - (model.rest_length - model.slack_offset)
    pe = _elastic_energy(stretch, model.stiffness)
    pg = -float(np.sum(model.mass * (state.x @ np.asarray(gravity, dtype=float))))
    return {"kinetic": ke, "elastic": pe, "gravity": pg}


def momentum(model: NetModel, state: NetState) -> np.ndarray:
    """Linear momentum Σ m v [kg m/s], shape (3,)."""
    return (model.mass[:, None] * state.v).sum(axis=0)


def spin_angular_momentum(model: NetModel, state: NetState) -> float:
    """Angular momentum about the +z axis through the origin [kg m^2/s], hub spin included."""
    lz = float(np.sum(model.mass * (state.x[:, 0] * state.v[:, 1] - state.x[:, 1] * state.v[:, 0])))
    if model.hub_node >= 0:
        lz += model.hub_inertia * state.hub[1]
    return lz
