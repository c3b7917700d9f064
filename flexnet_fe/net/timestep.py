"""The net's time step from physics: spring stability limit (with damping) and the
aerodynamic drag time scale. Never clamped silently: a forced step above the limit is refused.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flexnet_fe.errors import NumericalError
from flexnet_fe.net.forces import C_CROSS, CD_FRICTION
from flexnet_fe.net.topology import NetModel


def dt_critical_damped(omega: float | np.ndarray, zeta: float | np.ndarray):
    """Stability limit [s] of the central-difference / symplectic-Euler scheme for an oscillator
    of circular frequency ω [rad/s] and damping ratio ζ with lagged-velocity damping:
    ω dt_crit = 2 (√(1 + ζ²) - ζ)  (Belytschko, Liu & Moran, Nonlinear FE, §6.2)."""
    return 2.0 * (np.sqrt(1.0 + zeta * zeta) - zeta) / omega


def spring_limit(model: NetModel) -> float:
    """Stability limit of the net's springs [s].

    Bound on the highest frequency by Irons' element-eigenvalue theorem: each node's mass is
    shared equally among its deg(i) segments, so for segment s = (i, j)
    ω_s² = K_s (deg_i / m_i + deg_j / m_j) [+ deg_hub r0² / J for a hub link, the hub's spin
    being one more degree of freedom], and ω_max <= max_s ω_s. The axial tangent stiffness of a
    linear rope is K whatever its stretch, and the transverse (geometric) stiffness T/l < K, so
    the bound holds for any stretch. Each segment's damping ratio in that mode is
    ζ_s = c_s ω_s / (2 K_s) (element damping proportional to element stiffness).
    """
    k = model.stiffness
    deg = np.bincount(model.springs.ravel(), minlength=model.n_nodes).astype(float)
    i, j = model.springs[:, 0], model.springs[:, 1]
    w2 = k * (deg[i] / model.mass[i] + deg[j] / model.mass[j])
    if model.hub_node >= 0:
        nh = np.count_nonzero(model.hub_link)
        w2 = w2 + np.where(model.hub_link, k * nh * model.hub_radius**2 / model.hub_inertia, 0.0)
    w = np.sqrt(w2)
    zeta = model.damping * w / (2.0 * k)
    return float(np.min(dt_critical_damped(w, zeta)))


def drag_limit(model: NetModel, x: np.ndarray, v: np.ndarray, rho: float) -> float:
    """Stability limit of the explicit drag update [s] at state x [m], v [m/s] (n, 3).

    Node i feels F ≈ Σ_s ½ ½ ρ C d l_s |v_s| v_s (Eq. 5–10); linearised, dv/dt = -λ_i v with
    λ_i = 2 Σ_s ¼ ρ C_max d l_s |v_s| / m_i (C_max = 0.022 + 1.1), and the lagged-velocity update
    is stable for λ dt <= 2, i.e. dt <= 2 / max λ_i. Returns inf without air (ρ = 0)."""
    if rho == 0.0:
        return math.inf
    i, j = model.springs[:, 0], model.springs[:, 1]
    l = np.linalg.norm(x[j] - x[i], axis=1)
    vs = np.linalg.norm(0.5 * (v[i] + v[j]), axis=1)
    per = 0.25 * rho * (CD_FRICTION + C_CROSS) * model.diameter * l * vs
    lam = np.zeros(model.n_nodes)
    np.add.at(lam, i, 2.0 * per)
    np.add.at(lam, j, 2.0 * per)
    lam /= model.mass
    top = float(lam.max())
    return math.inf if top == 0.0 else 2.0 / top


@dataclass(frozen=True)
class TimeStep:
    """dt [s] used, the spring and drag limits [s] it was derived from, and whether forced."""

    dt: float
    spring_limit: float
    drag_limit: float
    forced: bool

    @property
    def limit(self) -> float:
        return min(self.spring_limit, self.drag_limit)


def choose_time_step(model: NetModel, x: np.ndarray, v: np.ndarray, rho: float,
                     safety_factor: float, forced: float | None = None) -> TimeStep:
    """dt = safety × min(spring limit, drag limit), or the forced dt if it is below the limit.

    Raises NumericalError if a forced dt exceeds the stability limit."""
    ts, td = spring_limit(model), drag_limit(model, x, v, rho)
    lim = min(ts, td)
    if forced is not None:
        if forced > lim:
            raise NumericalError(
                f"forced time step dt = {forced:.4g} s exceeds the net's stability limit "
                f"dt_crit = {lim:.4g} s (springs {ts:.4g} s, drag {td:.4g} s)")
        return TimeStep(float(forced), ts, td, True)
    return TimeStep(safety_factor * lim, ts, td, False)
