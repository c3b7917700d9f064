"""Contact stiffness (from physics) and the time step that follows from it (logged, never clamped).

K (``contact_stiffness``): Eq. (30) for crossed cylinders (``contact.stiffness``), per part kind:
fins K_fin with R_e = sqrt(r · h/2) (the thinnest fin), body K_body with R_e = sqrt(r · R). A
rope lying flat on a fin face is a line contact for which Hertz gives no power law; the fin's one
K keeps the stored energy a single continuous function of the gap from face to edge to corner
(for the paper's cases r ≈ h/2, so R_e = sqrt(r h/2) ≈ r: the sphere-on-plane value too).

dt = min(safety × dt_spring, safety × dt_contact, dt_travel) where
* dt_spring = 2/ω_max of the stiffest rope segment's axial two-mass mode, ω² = K (1/m_i + 1/m_j);
* dt_contact = 2/ω_c (√(1+ζ²) − ζ): ω_c² = n_seg k_t / m, k_t = m_exp K δ_e^(m_exp−1) the tangent
  stiffness at the expected penetration δ_e (undamped Hertz estimate of the lightest free node
  hitting at the impact speed, at most r + h/2, where its centre line would reach the core),
  n_seg the most segments meeting at a node (their capsules touch together), m that node's mass,
  ζ the contact damping ratio there;
* dt_travel = f × min(r, h/2) / v: a point moves at most a fraction f of the thinnest contact
  layer per step.

With the line law (``collide.contact_law = "line"``, ``line_stiffnesses``) the contact is a
linear foundation k_l [N/m²] per unit of the rope's rest (material) length, whose stiffness on a
node is at most k_l times its tributary rest length L0_i: dt_contact = 2/ω_c (√(1+ζ²) − ζ) with
ω_c² = k_l / min_i (m_i / L0_i) (``line_contact_limit``, ``line_density_min``) — independent of how
finely the rope is cut and of how far it is stretched (m_i / L0_i is the rope's ρA at every
interior node; cuts and merges keep it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flexnet_fe.collide.config import CollideConfig, StiffnessRule
from flexnet_fe.contact.law import DAMPING_CODE, hysteresis_factor
from flexnet_fe.contact.stiffness import crossed_cylinders_stiffness, hertz_max_penetration, line_stiffness
from flexnet_fe.errors import NumericalError


@dataclass(frozen=True)
class StepChoice:
    """dt [s] and what set it; the three limits [s]; the expected penetration δ_e [m]."""

    dt: float
    dt_spring: float
    dt_contact: float
    dt_travel: float
    expected_penetration: float
    governed_by: str


def contact_stiffness(cfg: CollideConfig, rope_radius: float, e_transverse: float, nu: float,
                      fin_half_thickness: float, body_radius: float) -> tuple[float, float]:
    """(K_body, K_fin) [N/m^m] per ``cfg.stiffness_rule`` (module doc); radii [m], E_t [Pa]."""
    if cfg.stiffness_rule is StiffnessRule.given:
        return float(cfg.contact_stiffness), float(cfg.contact_stiffness)
    e_star = e_transverse / (1.0 - nu * nu)
    return (crossed_cylinders_stiffness(rope_radius, body_radius, e_star),
            crossed_cylinders_stiffness(rope_radius, fin_half_thickness, e_star))


def line_stiffnesses(cfg: CollideConfig, rope_radius: float, e_transverse: float, nu: float,
                     fin_half: np.ndarray, body_radius: float) -> tuple[float, np.ndarray]:
    """(k_l of the body [N/m²], k_l of each fin (nf,) [N/m²]) of the line law
    (``contact.stiffness.line_stiffness``), each from its part's own Eq. (30) K (``hertz_eq30``:
    crossed cylinders r × h/2 of that fin, r × R_body; ``given``: the case's K) and crossing
    radius r + h/2, r + R_body."""
    e_star = e_transverse / (1.0 - nu * nu)

    def point_k(radius: float) -> float:
        if cfg.stiffness_rule is StiffnessRule.given:
            return float(cfg.contact_stiffness)
        return crossed_cylinders_stiffness(rope_radius, radius, e_star)

    fin = np.array([line_stiffness(point_k(h), rope_radius + h) for h in np.asarray(fin_half, float)])
    return line_stiffness(point_k(body_radius), rope_radius + body_radius), fin


def line_density_min(seg: np.ndarray, rest: np.ndarray, mass: np.ndarray, free: np.ndarray) -> float:
    """Smallest mass per unit of rest (material) length [kg/m] at a free node, m_i / L0_i with L0_i
    half the rest length of its segments (seg (ns, 2), rest (ns,) [m], mass (n,) [kg], free (n,)
    bool): the line law's contact stiffness of a node is at most k_l L0_i (Gershgorin on the points'
    weights, ``kernel._line_grid``), so ω² ≤ k_l / (m_i / L0_i) however far the rope is stretched."""
    tributary = 0.5 * (np.bincount(seg[:, 0], rest, len(mass)) + np.bincount(seg[:, 1], rest, len(mass)))
    ok = free & (tributary > 0.0)
    return float((mass[ok] / tributary[ok]).min()) if ok.any() else math.inf


def line_contact_limit(k_l: float, line_density: float, speed: float, chi: float,
                       delta_max: float) -> tuple[float, float]:
    """(2/ω_c (√(1+ζ²) − ζ) [s], expected penetration δ_e [m]) of the line law: rope of
    ``line_density`` [kg/m] on the linear foundation k_l [N/m²], ω_c² = k_l / line_density; δ_e =
    speed/ω_c ≤ delta_max [m] (undamped); ζ = χ k_l δ_e / (2 √(k_l line_density)), χ [s/m]."""
    w = math.sqrt(k_l / line_density)
    delta = min(speed / w, delta_max)
    zeta = 0.5 * chi * delta * w
    return 2.0 / w * (math.sqrt(1.0 + zeta * zeta) - zeta), delta


def spring_limit(k: np.ndarray, m_i: np.ndarray, m_j: np.ndarray) -> float:
    """2/ω_max [s] of the stiffest segment, ω² = K (1/m_i + 1/m_j); k [N/m], masses [kg]."""
    w2 = np.max(k * (1.0 / m_i + 1.0 / m_j)) if k.size else 0.0
    return math.inf if w2 == 0.0 else 2.0 / math.sqrt(w2)


def contact_limit(k_n: float, exponent: float, mass: float, speed: float, chi: float, delta_max: float,
                  n_seg: int = 1) -> tuple[float, float]:
    """(2/ω_c (√(1+ζ²) − ζ) [s], expected penetration δ_e [m]) for a node of ``mass`` [kg]
    hitting at ``speed`` [m/s] with ``n_seg`` capsules; δ_e ≤ delta_max [m]; χ [s/m] the damping
    factor (damping coefficient K δ^m χ)."""
    delta = min(hertz_max_penetration(mass, speed, k_n, exponent), delta_max)
    k_t = n_seg * exponent * k_n * delta ** (exponent - 1.0)
    w = math.sqrt(k_t / mass)
    zeta = n_seg * k_n * delta ** exponent * chi / (2.0 * math.sqrt(k_t * mass))
    return 2.0 / w * (math.sqrt(1.0 + zeta * zeta) - zeta), delta


def choose_step(cfg: CollideConfig, k: np.ndarray, m_i: np.ndarray, m_j: np.ndarray, m_min: float, n_seg: int,
                rope_radius: float, min_fin_half_thickness: float, k_contact: float,
                line: tuple[float, float] | None = None) -> StepChoice:
    """Time step (module doc). k [N/m], m_i, m_j [kg] of the active segments; m_min [kg] lightest
    node the missile can reach; n_seg most segments at a node; k_contact [N/m^m] the stiffest
    part's K. ``line`` (line law): (largest k_l [N/m²], ``line_density_min`` [kg/m]); the contact
    limit is then ``line_contact_limit``'s."""
    v = cfg.impact_speed
    chi = hysteresis_factor(DAMPING_CODE[cfg.damping_model], cfg.restitution, v)
    dt_spring = spring_limit(k, m_i, m_j)
    dt_travel = cfg.pass_through_fraction * min(rope_radius, min_fin_half_thickness) / v
    if line is None:
        dt_contact, delta = contact_limit(k_contact, cfg.contact_exponent, m_min, v, chi,
                                          rope_radius + min_fin_half_thickness, n_seg)
    else:
        dt_contact, delta = line_contact_limit(line[0], line[1], v, chi, rope_radius + min_fin_half_thickness)
    limits = {"rope springs": cfg.dt_safety * dt_spring, "contact": cfg.dt_safety * dt_contact,
              "travel per step": dt_travel}
    governed_by = min(limits, key=limits.get)
    dt = limits[governed_by]
    if not (dt > 0.0 and math.isfinite(dt)):
        raise NumericalError(f"collide: no valid time step ({limits})")
    return StepChoice(dt, dt_spring, dt_contact, dt_travel, delta, governed_by)
