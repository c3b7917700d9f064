"""Pure force laws of the rope net (numba ``@njit``), reusable from any kernel.

Paper §III-A: rope tension Eq. (1)–(4) (tension-only spring-damper with an LS-DYNA LINK167
style offset) and the rope-segment aerodynamic force Eq. (5)–(10).
"""

from __future__ import annotations

import math
from typing import NamedTuple

from numba import njit

CD_FRICTION = 0.022
"""Skin-friction part of the rope drag coefficient, Eq. (7) [-]."""
C_CROSS = 1.1
"""Cross-flow coefficient of the rope, Eq. (7)–(8) [-]."""


@njit(cache=True)
def rope_tension(length, rest_length, stiffness, damping, offset, length_rate):
    """Tension T [N] of one rope segment, Eq. (1)–(2) with a LINK167 offset.

    length, rest_length [m]; stiffness K = EA/l0 [N/m] (Eq. 3); damping c [N s/m] (Eq. 4);
    offset [m] (taut length l0 - offset; > 0 pretension, < 0 slack); length_rate dl/dt [m/s].

    T = K (l - (l0 - offset)) + c dl/dt while l > l0 - offset, else 0 (slack: no force and no
    damping). A rope cannot push: when a fast shortening makes the damped value negative, T = 0
    (the rope goes slack for that instant). This is the law, not a stabiliser.
    """
    stretch = length - (rest_length - offset)
    if stretch <= 0.0:
        return 0.0
    t = stiffness * stretch + damping * length_rate
    return t if t > 0.0 else 0.0


@njit(cache=True, error_model="numpy")
def spring_force(d, w, extra, law):
    """The one rope-segment mapper of the package (deploy ``net.kernels`` and collide
    ``collide.kernel``): Eq. (1)–(4) on a segment whose end j is at d = x_j − x_i [m] from end i
    and moves at w = v_j − v_i [m/s] relative to it (d, w: tuples of 3 floats); ``extra`` [m]
    is rope length not on the straight line (the hub wrap, Eq. 12–19; 0 otherwise); ``law`` =
    (rest length l0 [m], stiffness K [N/m], damping c [N s/m], offset [m]), the arguments of
    :func:`rope_tension`.

    Returns (T [N] by :func:`rope_tension`'s law, unit vector u (3 floats) from i to j, straight
    length |d| [m], length rate l̇ [m/s], stretch l − (l0 − offset) [m]); the force on node i is
    +T u, on node j −T u. A zero-length segment returns T = 0 and u = 0. Written with
    selects, not branches, and one division: this is the deploy kernel's hot loop."""
    d0, d1, d2 = d
    rest_length, stiffness, damping, offset = law
    lf = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    inv = 1.0 / lf if lf > 0.0 else 0.0
    u0 = d0 * inv
    u1 = d1 * inv
    u2 = d2 * inv
    ldot = w[0] * u0 + w[1] * u1 + w[2] * u2
    stretch = lf + extra - (rest_length - offset)
    t = stiffness * stretch + damping * ldot
    t = max(t, 0.0) if stretch > 0.0 and lf > 0.0 else 0.0
    return t, u0, u1, u2, lf, ldot, stretch


@njit(cache=True)
def rope_elastic_energy(stretch, stiffness):
    """Elastic energy ½ K s² [J] of one segment with stretch s = l − (l0 − offset) [m] > 0 (the
    potential of :func:`rope_tension`'s spring part; 0 when slack)."""
    return 0.5 * stiffness * stretch * stretch if stretch > 0.0 else 0.0


@njit(cache=True)
def aero_coefficients(sin_alpha):
    """Drag and lift coefficients of a rope at angle of attack α, Eq. (7)–(8).

    C_D = 0.022 + 1.1 sin^3 α, C_L = 1.1 sin^2 α cos α, for α in [0, π/2] (sin α >= 0).
    Returns (C_D, C_L).
    """
    s = sin_alpha
    c = math.sqrt(max(0.0, 1.0 - s * s))
    return CD_FRICTION + C_CROSS * s * s * s, C_CROSS * s * s * c


@njit(cache=True, error_model="numpy")
def segment_aero_force(u, length, vrel, rho, diameter):
    """Aerodynamic force on one rope segment [N], Eq. (5)–(8). Returns (Fx, Fy, Fz, |v| [m/s]).

    u : unit vector along the segment (3 floats); length l [m]; vrel : segment velocity
    relative to the air [m/s] (3 floats: mean of its end velocities minus the wind);
    rho [kg/m^3]; diameter d [m]. |v| is returned for the caller's drag stability bound.

    Drag F_D = ½ ρ C_D d l |v|^2 along -v̂; lift F_L = ½ ρ C_L d l |v|^2 along ê_L, the unit
    vector perpendicular to v̂ in the plane of v̂ and the segment, on the side opposite to the
    cross-flow velocity v_n = v - (v·ê)ê; C_D, C_L from Eq. (7)–(8) at sin α = |v_n| / |v|.
    Departure from the paper: Eq. (5)–(6) as printed read ½ ρ C d ||v|| l, which is not a
    force; the dimensionally correct ½ ρ C d l |v|^2 is used. With Eq. (7)–(8) the sum is
    F = -½ ρ d l (0.022 |v| v + 1.1 |v_n| v_n) (cross-flow principle), which is how it is
    evaluated (exact, and free of the α = 0 / 90° singularities of ê_L).
    """
    u0, u1, u2 = u
    vx, vy, vz = vrel
    v2 = vx * vx + vy * vy + vz * vz
    ve = vx * u0 + vy * u1 + vz * u2
    vm = math.sqrt(v2)
    vnm = math.sqrt(max(0.0, v2 - ve * ve))
    q = -0.5 * rho * diameter * length
    a = q * CD_FRICTION * vm
    b = q * C_CROSS * vnm
    return (a * vx + b * (vx - ve * u0), a * vy + b * (vy - ve * u1), a * vz + b * (vz - ve * u2), vm)


class RopeMaterial(NamedTuple):
    """The rope of a net, one home for its material (issue 14): youngs_modulus E [Pa] (axial,
    Eq. (3)), poisson_ratio ν [-], density ρ [kg/m³], diameter d [m], transverse_modulus E_t [Pa]
    (the contact law's E1, Eq. (30)), breaking_strength σ_b [Pa] (inf: unbreakable), damping_ratio
    ζ [-] and damping_law ('segment' or 'material') of the dashpots, Eq. (4)
    (``net.config.RopeNet.damping_law``)."""

    youngs_modulus: float
    poisson_ratio: float
    density: float
    diameter: float
    transverse_modulus: float
    breaking_strength: float
    damping_ratio: float = 0.0
    damping_law: str = "segment"

    @property
    def radius(self) -> float:
        """Rope radius d/2 [m]."""
        return 0.5 * self.diameter

    @property
    def breaking_load(self) -> float:
        """Tension at failure σ_b π d²/4 [N] (inf: unbreakable)."""
        return self.breaking_strength * math.pi * self.diameter ** 2 / 4.0


def rope_material(net_cfg) -> RopeMaterial:
    """The ``RopeMaterial`` of a ``[net]`` table (``net.config.RopeNet``)."""
    e = float(net_cfg.youngs_modulus)
    return RopeMaterial(e, float(net_cfg.poisson_ratio), float(net_cfg.density), float(net_cfg.rope_diameter),
                        net_cfg.contact_modulus,
                        math.inf if net_cfg.breaking_strength is None else float(net_cfg.breaking_strength),
                        float(net_cfg.damping_ratio), str(net_cfg.damping_law))
