"""Time step and contact stiffness of the collision (logged by the stage, never clamped silently).

dt = min(safety × dt_spring, safety × dt_contact, dt_pass) where
* dt_spring = 2/ω_max (central-difference limit) of the stiffest rope segment's axial two-mass
  mode, ω² = K (1/m_i + 1/m_j);
* dt_contact = 2/ω_c (√(1+ζ²) − ζ), ω_c² = k_t/m the tangent stiffness k_t = m_exp K_n δ^(m_exp−1)
  at the expected largest penetration δ (undamped Hertz estimate of the lightest free node hitting
  at the impact speed) over that node's mass, ζ the contact damping ratio there;
* dt_pass = f × min(rope radius, thinnest fin half-thickness) / v (no-pass-through: a point
  moves at most a fraction f of the thinnest contact layer per step).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flexnet_fe.collide.config import CollideConfig, StiffnessRule
from flexnet_fe.contact.law import DAMPING_CODE, hysteresis_factor
from flexnet_fe.contact.stiffness import hertz_max_penetration, penalty_stiffness, rigid_target_stiffness
from flexnet_fe.errors import NumericalError


@dataclass(frozen=True)
class StepChoice:
    """dt [s] and what set it; k_n [N/m^m]; the three limits [s]; expected penetration [m]."""

    dt: float
    k_n: float
    dt_spring: float
    dt_contact: float
    dt_pass: float
    expected_penetration: float
    governed_by: str


def spring_limit(k: np.ndarray, m_i: np.ndarray, m_j: np.ndarray) -> float:
    """2/ω_max [s] of the stiffest segment, ω² = K (1/m_i + 1/m_j); k [N/m], masses [kg]."""
    w2 = np.max(k * (1.0 / m_i + 1.0 / m_j)) if k.size else 0.0
    return math.inf if w2 == 0.0 else 2.0 / math.sqrt(w2)


def contact_limit(k_n: float, exponent: float, mass: float, speed: float, chi: float) -> tuple[float, float]:
    """(2/ω_c (√(1+ζ²) − ζ) [s], expected penetration δ [m]) for a node of ``mass`` [kg]
    hitting at ``speed`` [m/s]; χ [s/m] the damping factor (damping coefficient K δ^m χ)."""
    delta = hertz_max_penetration(mass, speed, k_n, exponent)
    k_t = exponent * k_n * delta ** (exponent - 1.0)
    w = math.sqrt(k_t / mass)
    zeta = k_n * delta ** exponent * chi / (2.0 * math.sqrt(k_t * mass))
    return 2.0 / w * (math.sqrt(1.0 + zeta * zeta) - zeta), delta


def choose_step(cfg: CollideConfig, k: np.ndarray, m_i: np.ndarray, m_j: np.ndarray, m_min: float,
                rope_radius: float, e_rope: float, min_fin_half_thickness: float) -> StepChoice:
    """Time step and contact stiffness (module doc). k [N/m], m_i, m_j [kg] of the active
    segments; m_min [kg] lightest free node; e_rope [Pa] rope modulus (Eq. (31))."""
    v = cfg.impact_speed
    chi = hysteresis_factor(DAMPING_CODE[cfg.damping_model], cfg.restitution, v)
    dt_spring = spring_limit(k, m_i, m_j)
    dt_pass = cfg.pass_through_fraction * min(rope_radius, min_fin_half_thickness) / v
    dt_pre = min(cfg.dt_safety * dt_spring, dt_pass)
    if cfg.stiffness_rule is StiffnessRule.hertz_eq31:
        k_n = rigid_target_stiffness(rope_radius, e_rope, cfg.rope_poisson_ratio)
    elif cfg.stiffness_rule is StiffnessRule.penalty:
        k_n = penalty_stiffness(cfg.penalty_scale, m_min, dt_pre, cfg.penalty_reference_fraction * rope_radius,
                                cfg.contact_exponent)
    elif cfg.stiffness_rule is StiffnessRule.given:
        k_n = float(cfg.contact_stiffness)
    else:
        raise ValueError(f"unknown stiffness rule {cfg.stiffness_rule!r}")
    dt_contact, delta = contact_limit(k_n, cfg.contact_exponent, m_min, v, chi)
    limits = {"rope springs": cfg.dt_safety * dt_spring, "contact": cfg.dt_safety * dt_contact,
              "no-pass-through": dt_pass}
    governed_by = min(limits, key=limits.get)
    dt = limits[governed_by]
    if not (dt > 0.0 and math.isfinite(dt)):
        raise NumericalError(f"collide: no valid time step ({limits})")
    return StepChoice(dt, k_n, dt_spring, dt_contact, dt_pass, delta, governed_by)
