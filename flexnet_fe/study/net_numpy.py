"""A second, plain-numpy model of the net's laws, and the kernel's throughput against it (issue 15).

``NumpyNet`` evaluates the same laws as the production kernel ``net.kernels`` with whole-array
numpy operations (no numba, no Python loop over segments or nodes):

- rope tension, Eq. (1)–(4): T = K (l − (l0 − offset)) + c l̇ while l > l0 − offset, else 0,
  and T >= 0 (a rope cannot push);
- gravity m g on every node;
- rope aerodynamics, Eq. (5)–(10) (when air is on), in the cross-flow form of
  ``net.forces.segment_aero_force``: F = −½ ρ d l (0.022 |v| v + 1.1 |v_n| v_n), half to each end;
- symplectic Euler: v += dt f / m, then x += dt v.

Departure: the rotary net's hub (its rim links and spin, Eq. (12)–(19)) is not modelled here;
``NumpyNet`` refuses a model with a hub. The traction net has none.

How it is written (so that the speed ratio means something): index arrays and the taut length
l0 − offset are computed once; each step gathers the end positions and velocities with
``np.take(..., out=)`` into preallocated buffers, forms lengths and dot products with
``np.einsum``, and scatters the segment forces to the nodes with ``np.bincount`` (one call per
component and end, the fastest scatter-add numpy offers; ``np.add.at`` is ~10× slower). There
is no per-segment Python and no per-step allocation of the large (m, 3) buffers.
"""

from __future__ import annotations

import os
import statistics
import time

import numpy as np

from flexnet_fe.net.forces import C_CROSS, CD_FRICTION


class NumpyNet:
    """The traction-net laws in vectorised numpy. ``model`` a ``net.topology.NetModel`` without
    a hub; gravity (3,) [m/s²]; rho [kg/m³]; wind (3,) [m/s]; air: aerodynamic loads on/off."""

    def __init__(self, model, gravity, rho: float, wind, air: bool):
        if model.hub_node >= 0:
            raise ValueError("NumpyNet: the hub (rotary net) is not modelled by the numpy reference")
        self.i = np.ascontiguousarray(model.springs[:, 0])
        self.j = np.ascontiguousarray(model.springs[:, 1])
        self.n = len(model.mass)
        self.mass = model.mass
        self.taut = model.rest_length - model.slack_offset
        self.k = model.stiffness
        self.c = model.damping
        self.weight = model.mass[:, None] * np.asarray(gravity, dtype=float)[None, :]
        self.air = bool(air)
        self.wind = np.asarray(wind, dtype=float)
        self.q = -0.5 * float(rho) * model.diameter  # −½ ρ d, (m,)
        m = len(self.i)
        self._a, self._b = np.empty((m, 3)), np.empty((m, 3))
        self._d, self._w = np.empty((m, 3)), np.empty((m, 3))

    def forces(self, x: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Forces f (n, 3) [N] on the nodes at positions x (n, 3) [m], velocities v (n, 3) [m/s];
        also returns the segment tensions T (m,) [N]."""
        i, j, n = self.i, self.j, self.n
        d, w, a, b = self._d, self._w, self._a, self._b
        np.take(x, j, axis=0, out=a)
        np.take(x, i, axis=0, out=b)
        np.subtract(a, b, out=d)
        np.take(v, j, axis=0, out=a)
        np.take(v, i, axis=0, out=b)
        np.subtract(a, b, out=w)
        l = np.sqrt(np.einsum("ij,ij->i", d, d))
        d /= l[:, None]  # d is now the unit vector u from i to j
        ldot = np.einsum("ij,ij->i", w, d)
        stretch = l - self.taut
        t = np.where(stretch > 0.0, np.maximum(self.k * stretch + self.c * ldot, 0.0), 0.0)  # Eq. (1)-(2)
        fs = d * t[:, None]
        f = self.weight.copy()
        for k in range(3):
            f[:, k] += np.bincount(i, fs[:, k], n) - np.bincount(j, fs[:, k], n)
        if self.air:  # Eq. (5)-(10): a + b = v_i + v_j
            a += b
            a *= 0.5
            a -= self.wind  # relative velocity of the segment
            vm = np.sqrt(np.einsum("ij,ij->i", a, a))
            ve = np.einsum("ij,ij->i", a, d)
            vnm = np.sqrt(np.maximum(vm * vm - ve * ve, 0.0))
            ql = self.q * l
            fa = a * (ql * (CD_FRICTION * vm + C_CROSS * vnm))[:, None] - d * (ql * C_CROSS * vnm * ve)[:, None]
            for k in range(3):
                f[:, k] += 0.5 * (np.bincount(i, fa[:, k], n) + np.bincount(j, fa[:, k], n))
        return f, t

    def step(self, x: np.ndarray, v: np.ndarray, dt: float, n_steps: int = 1) -> None:
        """Advance x, v (n, 3) in place by ``n_steps`` symplectic-Euler steps of dt [s]."""
        inv_m = (1.0 / self.mass)[:, None]
        for _ in range(n_steps):
            f, _t = self.forces(x, v)
            f *= inv_m
            f *= dt
            v += f
            x += dt * v


def _traction(n_side: int):
    """The paper's 5 m traction net with ``n_side`` knots per side (101: the 5 cm default)."""
    from flexnet_fe.net.config import TractionNet
    from flexnet_fe.net.topology import build_traction

    return build_traction(TractionNet(mesh_size=5.0 / (n_side - 1)))


def throughput_scene(n_side: int, air: bool):
    """The scene the net kernel and ``NumpyNet`` are timed on: the traction net with ``n_side``
    knots per side, Mach 3 at 8 km with gravity, air on/off, dt = ¼ of the spring limit. Returns
    (model, kernel model, NumpyNet, dt [s], flight velocity (3,) [m/s])."""
    from flexnet_fe.atmosphere import isa
    from flexnet_fe.net.state import Environment, kernel_model
    from flexnet_fe.net.timestep import spring_limit

    model = _traction(n_side)
    atm = isa(8000.0)
    env = Environment(np.array([0.0, -atm.gravity, 0.0]), atm.density if air else 0.0, np.zeros(3), air)
    return (model, kernel_model(model, env), NumpyNet(model, env.gravity, env.rho, env.wind, air),
            0.25 * spring_limit(model), (0.0, 0.0, 3.0 * atm.speed_of_sound))


def net_kernel_throughput(n_side: int, air: bool, steps: int, repeats: int = 5) -> dict:
    """Time per spring-step [ns] of the production kernel (``net.kernels.advance``) and of
    ``NumpyNet`` on the traction net with ``n_side`` knots per side, air on/off, from the same
    state (Mach 3 at 8 km, gravity, dt = ¼ of the spring limit), ``steps`` steps per timing.
    Repetitions alternate kernel / numpy (so both see the same machine load); the medians are
    reported. One core: the kernel is serial; numpy's operations here do not use threads.

    Returns {ns_per_spring_step_kernel, ns_per_spring_step_numpy, ratio (numpy / kernel),
    n_springs, n_nodes, steps, repeats, max_dx_m (|x_kernel − x_numpy| after the timed steps)}."""
    from flexnet_fe.net.kernels import advance
    from flexnet_fe.net.state import initial_state, kernel_state

    model, km, ref, dt, flight = throughput_scene(n_side, air)
    advance(km, kernel_state(initial_state(model, flight)), 1, dt)  # compile / load the cache
    t_nb, t_np = [], []
    for _ in range(repeats):
        s = initial_state(model, flight)
        ks = kernel_state(s)
        t0 = time.perf_counter()
        advance(km, ks, steps, dt)
        t_nb.append(time.perf_counter() - t0)
        s2 = initial_state(model, flight)
        t0 = time.perf_counter()
        ref.step(s2.x, s2.v, dt, steps)
        t_np.append(time.perf_counter() - t0)
    per = 1e9 / (steps * model.n_springs)
    nb, nq = statistics.median(t_nb) * per, statistics.median(t_np) * per
    return {"ns_per_spring_step_kernel": nb, "ns_per_spring_step_numpy": nq, "ratio": nq / nb,
            "n_springs": int(model.n_springs), "n_nodes": int(model.n_nodes), "steps": int(steps),
            "repeats": int(repeats), "max_dx_m": float(np.abs(s.x - s2.x).max()),
            "numba_threads": os.environ.get("NUMBA_NUM_THREADS", "default")}
