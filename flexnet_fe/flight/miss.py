"""Miss distance: the closest approach between two integration steps.

Across one step [t0, t1] the relative position r(t) (target minus missile) is the cubic Hermite
interpolant of r and ṙ at both ends (error O(dt⁴), the order of the RK4 solution itself); the
miss is the minimum of |r(t)| on the step, found by golden-section search on |r|² (unimodal on a
step that contains the sign change of r·ṙ).
"""

from __future__ import annotations

import math

import numpy as np


def hermite(tau: float, h: float, r0, v0, r1, v1) -> np.ndarray:
    """Cubic Hermite r(t0 + tau h), tau ∈ [0, 1]; r [m], v [m/s], h [s]; shape (3,)."""
    t2, t3 = tau * tau, tau * tau * tau
    return ((2 * t3 - 3 * t2 + 1) * r0 + (t3 - 2 * t2 + tau) * h * v0
            + (-2 * t3 + 3 * t2) * r1 + (t3 - t2) * h * v1)


def closest_approach(t0: float, r0, v0, t1: float, r1, v1) -> tuple[float, float]:
    """(time [s], distance [m]) of the closest approach on [t0, t1] from relative positions
    r0, r1 [m] and velocities v0, v1 [m/s] at both ends (shape (3,) each)."""
    r0, v0, r1, v1 = (np.asarray(x, dtype=float) for x in (r0, v0, r1, v1))
    h = t1 - t0
    f = lambda tau: float(np.dot(hermite(tau, h, r0, v0, r1, v1), hermite(tau, h, r0, v0, r1, v1)))
    g = (math.sqrt(5) - 1) / 2
    a, b = 0.0, 1.0
    c, d = b - g * (b - a), a + g * (b - a)
    fc, fd = f(c), f(d)
    for _ in range(80):  # bracket shrinks by 0.618^80 ≈ 2e-17
        if fc < fd:
            b, d, fd = d, c, fc
            c = b - g * (b - a)
            fc = f(c)
        else:
            a, c, fc = c, d, fd
            d = a + g * (b - a)
            fd = f(d)
    tau = 0.5 * (a + b)
    candidates = [(f(0.0), 0.0), (f(1.0), 1.0), (f(tau), tau)]
    dist2, tau = min(candidates)
    return t0 + tau * h, math.sqrt(dist2)
