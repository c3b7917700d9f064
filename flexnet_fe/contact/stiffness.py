"""Contact stiffness K_n [N/m^m] from the Hertz law, Eq. (30)–(31) — from physics, never from dt.

The rope is a cylinder of radius r; on a fin edge (a cylinder of radius h/2) and on the body
(radius R) it touches as two crossed cylinders, whose Hertz contact is a point contact of
effective radius R_e = sqrt(R1 R2) (Johnson, Contact Mechanics, §4.2; exact for R1 = R2).
The modulus is the rope's TRANSVERSE compressive modulus (its cross-section is squeezed), the
missile is rigid. With the paper's 1 MPa rope (if its transverse modulus were also 1 MPa) a
rope node of ~1.6 g arriving at 500 m/s would sink ~0.14 m into a fin edge — the rope would
pass through a 6 mm fin: see ``collide.config`` and docs/validation.md for the stated contact
modulus of the cases.
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


def crossed_cylinders_stiffness(radius_1: float, radius_2: float, e_star: float) -> float:
    """Eq. (30) for two cylinders of radii R1, R2 [m] crossed at right angles: K = 4/3 E* sqrt(R_e),
    R_e = sqrt(R1 R2) [N/m^1.5]; e_star [Pa] the contact modulus ((1−ν1²)/E1 + (1−ν2²)/E2)^(-1)."""
    return 4.0 / 3.0 * e_star * math.sqrt(math.sqrt(radius_1 * radius_2))


def hertz_max_penetration(mass: float, speed: float, k_n: float, exponent: float) -> float:
    """Largest penetration [m] of a mass ``mass`` [kg] hitting a rigid target at ``speed`` [m/s]
    with an undamped power-law contact: ½ m v² = K_n δ^(m+1)/(m+1) → δ = ((m+1) m v²/(2 K_n))^(1/(m+1)).
    For m = 1.5 this is (5 m v²/(4 K_n))^(2/5) (Hertz)."""
    return ((exponent + 1.0) * mass * speed ** 2 / (2.0 * k_n)) ** (1.0 / (exponent + 1.0))


def line_stiffness(k_point: float, crossing_radius: float) -> float:
    """Stiffness k_l [N/m²] of the linear line-load law q = k_l δ [N/m] whose integral along a
    straight rope crossing a part's curved surface at right angles is the point law K δ0^1.5.

    The rope's centre line passes the surface's axis of curvature (fin edge: the core edge, radius
    R = h/2; body: its axis, R = R_body) at the distance d0 = R' − δ0, R' = r + R
    (``crossing_radius`` [m]), so a cross-section at x along the rope penetrates
    δ(x) = R' − √(d0² + x²) ≈ δ0 − x²/(2R') for δ0 ≪ R', and
    ∫ k_l δ(x)₊ dx = (4√2/3) k_l √R' δ0^1.5 = K δ0^1.5  ⇔  k_l = 3 K / (4√2 √R').
    With K of Eq. (30) for crossed cylinders (``crossed_cylinders_stiffness``) the first contact of a
    rope with an edge or the body is the paper's Hertz law, to O(δ0/R'); a rope lying along a face
    takes k_l δ per metre, where Eq. (30) gives no power law. The collision applies k_l per metre of
    the rope's rest length (``collide.kernel._line_contact``): a rope stretched s× presses with
    k_l δ / s per metre of its current length, as its mass per metre is 1/s. k_point [N/m^1.5]."""
    return 3.0 * k_point / (4.0 * math.sqrt(2.0) * math.sqrt(crossing_radius))
