"""Contact stiffness K_n [N/m^m]: the paper's Hertz rule, Eq. (30)–(31), or a mass/step penalty.

With the paper's rope (E = 1 MPa) Eq. (31) gives K_n ≈ 4e4 N/m^1.5 for a 2 mm rope radius: a
rope node of ~0.6 g arriving at 500 m/s sinks ~0.1 m into the missile — far deeper than the
rope radius or a fin's thickness. The penalty rule (LS-DYNA SOFT=1 idea, k = s·m/dt²) ties the
stiffness to the node mass and the time step so that the penetration stays a small fraction of
the step's travel, and hence of the rope radius once the no-pass-through step limit holds.
"""

from __future__ import annotations

import math


def hertz_stiffness(radius_1: float, radius_2: float, e_1: float, nu_1: float,
                    e_2: float, nu_2: float) -> float:
    """Eq. (30): K_n = 4/3 (1/R1 + 1/R2)^(-1/2) ((1−ν1²)/E1 + (1−ν2²)/E2)^(-1)  [N/m^1.5].

    radius_* [m] radii of curvature at the contact (math.inf for a plane), e_* [Pa] Young's
    moduli (math.inf for a rigid body), nu_* Poisson's ratios.
    """
    curv = 1.0 / radius_1 + 1.0 / radius_2
    compl = (1.0 - nu_1 ** 2) / e_1 + (1.0 - nu_2 ** 2) / e_2
    return 4.0 / 3.0 / math.sqrt(curv) / compl


def rigid_target_stiffness(radius: float, e_net: float, nu_net: float) -> float:
    """Eq. (31): rigid missile (E2 → ∞): K_n = 4/3 (2/R)^(-1/2) E1/(1−ν1²)  [N/m^1.5].

    As printed, Eq. (31) keeps a curvature sum 2/R, i.e. two equal radii R; here R is the rope
    radius (the paper does not say which radius; the rope is the curved body at the contact).
    """
    return 4.0 / 3.0 * math.sqrt(radius / 2.0) * e_net / (1.0 - nu_net ** 2)


def penalty_stiffness(scale: float, mass: float, dt: float, delta_ref: float, exponent: float) -> float:
    """Mass/step penalty (LS-DYNA SOFT=1 style): linear k = s·m/dt² [N/m], expressed for the
    power law F = K_n δ^m by matching the secant stiffness at the reference penetration δ_ref:
    K_n = k · δ_ref^(1−m)  [N/m^m].

    scale s (LS-DYNA SOFSCL, default 0.1), mass [kg] of the contacting node, dt [s] time step,
    delta_ref [m] > 0 the penetration at which the secant stiffness equals k.
    """
    return scale * mass / dt ** 2 * delta_ref ** (1.0 - exponent)


def hertz_max_penetration(mass: float, speed: float, k_n: float, exponent: float) -> float:
    """Largest penetration [m] of a mass ``mass`` [kg] hitting a rigid target at ``speed`` [m/s]
    with an undamped power-law contact: ½ m v² = K_n δ^(m+1)/(m+1) → δ = ((m+1) m v²/(2 K_n))^(1/(m+1)).
    For m = 1.5 this is (5 m v²/(4 K_n))^(2/5) (Hertz)."""
    return ((exponent + 1.0) * mass * speed ** 2 / (2.0 * k_n)) ** (1.0 / (exponent + 1.0))
