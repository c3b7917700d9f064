"""Target (aircraft) model: constant-speed level turn, in closed form (exact at every t).

A level turn at load factor n (lift/weight) has horizontal acceleration a = g √(n² − 1)
perpendicular to the velocity, turn rate ω = a/V and radius R = V/ω. Before ``t_start`` the
aircraft flies straight. Vectors in the flight frame F (``flexnet_fe.flight``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


def turn_rate(speed: float, load_factor: float, gravity: float) -> float:
    """ω = g √(n² − 1) / V [rad/s] of a level turn at load factor n (speed [m/s], g [m/s²])."""
    return gravity * math.sqrt(load_factor * load_factor - 1.0) / speed


@njit(cache=True)
def level_turn(t, p0, forward, centre, speed, omega, t_start):
    """Position [m], velocity [m/s], acceleration [m/s²] (each shape (3,)) at time t [s].

    p0: initial position; forward: initial unit velocity (horizontal); centre: horizontal unit
    vector towards the turn centre; omega: turn rate [rad/s] (0 = straight flight).
    """
    ts = min(t, t_start)
    tt = max(t - t_start, 0.0)
    pos = p0 + speed * ts * forward
    if omega == 0.0:
        return pos + speed * tt * forward, speed * forward, np.zeros(3)
    c, s = math.cos(omega * tt), math.sin(omega * tt)
    radius = speed / omega
    pos = pos + radius * s * forward + radius * (1.0 - c) * centre
    vel = speed * (c * forward + s * centre)
    acc = speed * omega * (-s * forward + c * centre)
    return pos, vel, acc
