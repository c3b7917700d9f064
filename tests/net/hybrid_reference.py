"""The paper's reduced "hybrid" model of the rotary net, Eq. (13), (16) and (17)–(19): a rigid
hub spinning about a fixed centre and n identical warps, each a massless rope with a tip mass,
solved as an ODE with scipy. Used to cross-check the lumped-mass rotary model (tests).

Straight warp (|φ| < π/2), state (θ, ω, φ, φ̇, L, L̇) — θ hub angle, φ radial declination of the
warp, L its length from the rim anchor to the mass:
    J ω̇ = M + n F r0 sin φ                                                   Eq. (13)
    m [r0 (ω̇ sin φ - ω² cos φ) + L̈ - L (ω + φ̇)²] = -F                        Eq. (16a)
    m [r0 (ω̇ cos φ + ω² sin φ) + 2 (ω + φ̇) L̇ + L (ω̇ + φ̈)] = 0                Eq. (16b)
Wound warp (φ = s π/2, s = ±1), state (θ, ω, χ, ω_a, L, L̇) — χ the signed wound angle, the
rope leaving the rim tangentially at θ_a = θ + χ which turns at ω_a = ω + χ̇ (Eq. (19)); the same
equations with θ → θ_a, ω → ω_a, φ = s π/2, and J ω̇ = M + n F r0 s (Eq. (17)).

Departures from the paper, and why:
- Eq. (16b) as printed reads r0 (ω² cos φ + ω̇ sin φ); differentiating R = r0 e(θ) + L e(θ+φ)
  (Eq. (15)) twice gives r0 (ω̇ cos φ + ω² sin φ) (the printed one is not 0 for a rigidly
  spinning straight warp at φ = 0 with L̈ = φ̈ = ω̇ = 0... it gives r0 ω² ≠ 0). We use the derived one.
- The rope is elastic (Eq. (2)–(3) on the whole warp: F = K (L + r0|χ| - L0) + c d/dt(...),
  tension-only) instead of inextensible, so Eq. (18) L + r0 ϕ = L_max becomes the elastic law
  on the total length and L̇ is free (Eq. (19)'s L̇ = -sign(φ) r ϕ̇ is its inextensible limit).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from flexnet_fe.net.forces import rope_tension


@dataclass(frozen=True)
class HybridWarp:
    """n warps [-]; hub_radius r0 [m]; hub_inertia J [kg m^2]; tip_mass m [kg];
    stiffness_ea EA [N]; rest_length L0 (rim to mass, unstretched) [m]; damping c [N s/m];
    torque M (control torque on the hub) [N m]."""

    n: int
    hub_radius: float
    hub_inertia: float
    tip_mass: float
    stiffness_ea: float
    rest_length: float
    damping: float = 0.0
    torque: float = 0.0

    def tension(self, length: float, rate: float) -> float:
        """Warp tension [N], Eq. (2)–(3) on the whole warp."""
        return rope_tension(length, self.rest_length, self.stiffness_ea / self.rest_length,
                            self.damping, 0.0, rate)


def _rhs_straight(w: HybridWarp):
    r0, m = w.hub_radius, w.tip_mass

    def f(t, y):
        th, om, ph, phd, L, Ld = y
        F = w.tension(L, Ld)
        omd = (w.torque + w.n * F * r0 * math.sin(ph)) / w.hub_inertia
        Ldd = -F / m + L * (om + phd) ** 2 - r0 * (omd * math.sin(ph) - om * om * math.cos(ph))
        phdd = (-r0 * (omd * math.cos(ph) + om * om * math.sin(ph)) - 2.0 * (om + phd) * Ld) / L - omd
        return [om, omd, phd, phdd, Ld, Ldd]
    return f


def _rhs_wound(w: HybridWarp, s: float):
    r0, m = w.hub_radius, w.tip_mass

    def f(t, y):
        th, om, chi, oma, L, Ld = y
        F = w.tension(L + r0 * s * chi, Ld + r0 * s * (oma - om))
        omd = (w.torque + w.n * F * r0 * s) / w.hub_inertia
        omad = -(r0 * oma * oma * s + 2.0 * oma * Ld) / L
        Ldd = -F / m + L * oma * oma - r0 * s * omad
        return [om, omd, oma - om, omad, Ld, Ldd]
    return f


def initial_state(w: HybridWarp, hub_spin: float, radial_speed: float, tangential_speed: float) -> np.ndarray:
    """Straight-phase state for a warp lying radially (θ = φ = 0, L = L0) whose tip moves with
    radial_speed / tangential_speed [m/s] (in the frame of the hub centre)."""
    L = w.rest_length
    phd = (tangential_speed - (w.hub_radius + L) * hub_spin) / L
    return np.array([0.0, hub_spin, 0.0, phd, L, radial_speed])


def tip_position(w: HybridWarp, phase_s: float, y: np.ndarray) -> np.ndarray:
    """Tip mass position [m], shape (2,), from a straight (phase_s = 0) or wound (±1) state."""
    r0 = w.hub_radius
    if phase_s == 0.0:
        th, _, ph, _, L, _ = y
        a, psi = th, th + ph
    else:
        th, _, chi, _, L, _ = y
        a = th + chi
        psi = a + phase_s * math.pi / 2
    return np.array([r0 * math.cos(a) + L * math.cos(psi), r0 * math.sin(a) + L * math.sin(psi)])


def simulate(w: HybridWarp, y0: np.ndarray, t_end: float, t_eval: np.ndarray, rtol: float = 1e-10,
             atol: float = 1e-12) -> dict[str, np.ndarray]:
    """Integrate the hybrid model from a straight-phase state ``y0`` to ``t_end`` [s], switching
    between the straight and wound phases at the events |φ| = π/2 and χ = 0.

    Returns arrays at ``t_eval``: ``t`` [s], ``hub_angle`` [rad], ``hub_spin`` [rad/s],
    ``tip`` [m] (k, 2), ``wrap`` χ [rad], ``tension`` [N]; and ``switches`` (times [s])."""
    t_eval = np.asarray(t_eval, dtype=float)
    out = {"t": t_eval, "hub_angle": np.full(len(t_eval), np.nan), "hub_spin": np.full(len(t_eval), np.nan),
           "tip": np.full((len(t_eval), 2), np.nan), "wrap": np.zeros(len(t_eval)),
           "tension": np.full(len(t_eval), np.nan)}
    switches: list[float] = []
    t, y, s = 0.0, np.asarray(y0, dtype=float), 0.0
    r0 = w.hub_radius
    while t < t_end:
        if s == 0.0:
            rhs = _rhs_straight(w)

            def ev(t_, y_):
                return abs(y_[2]) - math.pi / 2
        else:
            rhs = _rhs_wound(w, s)
            sign = s

            def ev(t_, y_):
                return sign * y_[2]
        ev.terminal, ev.direction = True, (1.0 if s == 0.0 else -1.0)
        mask = (t_eval >= t) & (t_eval <= t_end)
        sol = solve_ivp(rhs, (t, t_end), y, method="DOP853", rtol=rtol, atol=atol, events=ev,
                        dense_output=True)
        if not sol.success:
            raise RuntimeError(f"hybrid model integration failed at t = {sol.t[-1]:.6g} s: {sol.message}")
        t_stop = sol.t[-1]
        idx = np.flatnonzero(mask & (t_eval <= t_stop))
        for k in idx:
            yk = sol.sol(t_eval[k])
            out["hub_angle"][k], out["hub_spin"][k] = yk[0], yk[1]
            out["tip"][k] = tip_position(w, s, yk)
            if s == 0.0:
                out["tension"][k] = w.tension(yk[4], yk[5])
            else:
                out["wrap"][k] = yk[2]
                out["tension"][k] = w.tension(yk[4] + r0 * s * yk[2], yk[5] + r0 * s * (yk[3] - yk[1]))
        if sol.status == 1 and t_stop < t_end:  # phase switch
            ye = sol.y_events[0][0]
            switches.append(t_stop)
            # continuity of the tip velocity: along the rope it is L̇ + s r0 ω (straight, the
            # anchor moving with the hub) or L̇ + s r0 ω_a (wound, the tangent point moving at
            # ω_a = ω + φ̇), hence the free length's rate jumps by ∓ s r0 φ̇ (Eq. (19))
            if s == 0.0:
                s = 1.0 if ye[2] > 0 else -1.0
                y = np.array([ye[0], ye[1], 0.0, ye[1] + ye[3], ye[4], ye[5] - s * r0 * ye[3]])
            else:
                y = np.array([ye[0], ye[1], s * math.pi / 2, ye[3] - ye[1], ye[4],
                              ye[5] + s * r0 * (ye[3] - ye[1])])
                s = 0.0
        t = t_stop
    out["switches"] = np.asarray(switches)
    return out
