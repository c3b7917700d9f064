"""The coefficient of restitution a damping model actually achieves (a guard and a study map).

The three χ laws of ``contact.models.DampingModel`` are derived for e → 1; away from it
Lankarani–Nikravesh and Hunt–Crossley return more energy than requested (e = 0.5 requested:
0.725 and 0.663 achieved; Flores et al. 2011 stay within 0.01). For a Hertz contact
F = K δ^m (1 + χ δ̇) with χ = c/v_k the impact is self-similar, so the achieved e depends only on
the model and the requested e once the impact speed is above the approach-speed floor
(``collide.damping_min_approach_speed``); below it χ is smaller and e is higher.
"""

from __future__ import annotations

import math

from flexnet_fe.contact.law import hysteresis_factor, normal_force
from flexnet_fe.contact.models import DAMPING_CODE, DampingModel


def restitution_achieved(model_code: int, e_req: float, v: float, v_floor: float = 1.0,
                         k_n: float = 1e9, exponent: float = 1.5, mass: float = 0.01) -> float:
    """v_out / v_in [-] of a point mass ``mass`` [kg] hitting a rigid wall at ``v`` [m/s] under
    F = K δ^m (1 + χ δ̇) (``contact.law.normal_force``, Eq. (28)–(29)), χ from
    ``hysteresis_factor`` with the kernel's v_k rule (largest approach speed, at least
    ``v_floor`` [m/s]). RK4 with 4000 steps over the undamped Hertz contact time
    3.22 δ_max / v, δ_max = (5 m v² / 4K)^(2/5) (Johnson §11.4); NaN if the mass never leaves."""
    chi = hysteresis_factor(model_code, e_req, max(v, v_floor))
    dmax = (5.0 * mass * v * v / (4.0 * k_n)) ** 0.4 if exponent == 1.5 else 1e-3
    dt = 3.22 * dmax / v / 4000.0

    def acc(delta, rate):
        return -normal_force(delta, rate, k_n, exponent, chi) / mass

    x, u = 0.0, v  # x = δ (penetration), u = δ̇
    for _ in range(400000):
        k1x, k1u = u, acc(x, u)
        k2x, k2u = u + 0.5 * dt * k1u, acc(x + 0.5 * dt * k1x, u + 0.5 * dt * k1u)
        k3x, k3u = u + 0.5 * dt * k2u, acc(x + 0.5 * dt * k2x, u + 0.5 * dt * k2u)
        k4x, k4u = u + dt * k3u, acc(x + dt * k3x, u + dt * k3u)
        x += dt / 6.0 * (k1x + 2 * k2x + 2 * k3x + k4x)
        u += dt / 6.0 * (k1u + 2 * k2u + 2 * k3u + k4u)
        if x <= 0.0 and u < 0.0:
            return -u / v
    return math.nan


RESTITUTION_TOLERANCE = 0.05
"""Largest |e achieved − e requested| [-] a collision runs with without a warning. Measured on
radar × traction (rope_split 4, 12 ms): Lankarani–Nikravesh at e = 0.5 (achieves 0.725) against
Flores (0.470), Δe = 0.255, moves the total impulse by 1.9 % and the CFC-filtered peak by 4.3 %;
Δe ≤ 0.05 therefore moves the headlines by ≲ 1 % (the RK4 check itself is exact to 1e-4)."""


def restitution_warning(model_name: str, e_req: float, e_achieved: float) -> str | None:
    """One warning line when the damping model ``model_name`` achieves ``e_achieved``
    (:func:`restitution_achieved` above the approach-speed floor) instead of the requested
    ``e_req`` by more than :data:`RESTITUTION_TOLERANCE`, else None."""
    if abs(e_achieved - e_req) <= RESTITUTION_TOLERANCE:
        return None
    return (f"collide.damping_model = {model_name} achieves a restitution of {e_achieved:.3f} for the requested "
            f"collide.restitution = {e_req:g} (the law is derived for e near 1): use damping_model = \"flores\"")


def restitution_check(model_name: str, e_req: float, impact_speed: float, v_floor: float,
                      exponent: float = 1.5) -> tuple[float, str | None]:
    """(the restitution [-] the damping law ``model_name`` achieves for an impact at
    ``impact_speed`` [m/s] with the approach-speed floor ``v_floor`` [m/s], one warning line or
    None): the collision summary's guard. Above the floor the law's own miss is warned
    (:func:`restitution_warning`); below it the floor caps χ, e rises towards 1 whatever the law,
    and the line says so (the damping map of ``flexnet study stability`` found such impacts
    unflagged when the check was made at 10 m/s only)."""
    code = DAMPING_CODE[DampingModel(model_name)]
    e_ach = restitution_achieved(code, e_req, impact_speed, v_floor, exponent=exponent) if code else 1.0
    if impact_speed >= v_floor or abs(e_ach - e_req) <= RESTITUTION_TOLERANCE:
        return e_ach, restitution_warning(model_name, e_req, e_ach)
    return e_ach, (f"collide.impact_speed = {impact_speed:g} m/s is below collide.damping_min_approach_speed = "
                   f"{v_floor:g} m/s, which caps the damping: the contact achieves a restitution of {e_ach:.3f} "
                   f"for the requested collide.restitution = {e_req:g}; lower the floor below the impact speed")
