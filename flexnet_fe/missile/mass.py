"""Rigid-body mass properties of the missile (mass, centre of gravity, inertia about the CG).

Model (an estimate; the paper's Table 1 is lost): the body of revolution (nose + cylinder) is a
solid of uniform mean density, each fin a solid plate of the fin material. Coordinates in the body
frame B (:mod:`flexnet_fe.frames`); inertia tensors in B axes, ``I = ∫ (|r|² 1 - r rᵀ) dm``.
"""

from __future__ import annotations

from typing import Iterable

import numpy as np

from flexnet_fe.missile.config import NoseShape
from flexnet_fe.missile.geometry import Fin, nose_radius

_GAUSS_POINTS = 64  # Gauss–Legendre on the nose: exact for cone and hemisphere (r², r⁴ are
# polynomials of degree ≤ 4 in s) and converged to round-off for the smooth tangent ogive.


def _about_origin_to_cg(m: float, first: np.ndarray, i_o: np.ndarray):
    """(m, cg, I_cg) from mass m [kg], first moment ∫ r dm [kg m] and I about the B origin."""
    c = first / m
    # Parallel-axis (Huygens–Steiner) theorem: I_o = I_cg + m (|c|² 1 - c cᵀ).
    return m, c, i_o - m * (c @ c * np.eye(3) - np.outer(c, c))


def body_mass_properties(length: float, radius: float, nose_shape: NoseShape,
                         nose_length: float, density: float):
    """Mass [kg], CG [m] (3,) and inertia about the CG [kg m^2] (3, 3) of the solid body of
    revolution (uniform ``density`` [kg/m^3]) in B.

    Slices of thickness ds at station s (x_b = -s) of radius r(s): dm = ρ π r² ds, axial moment
    dI_xx = ½ r² dm, transverse moment about the apex dI_yy = (r²/4 + s²) dm.
    Cylinder part in closed form, nose by Gauss–Legendre quadrature.
    """
    L, R, Ln, rho = float(length), float(radius), float(nose_length), float(density)
    xg, wg = np.polynomial.legendre.leggauss(_GAUSS_POINTS)
    s = 0.5 * Ln * (xg + 1.0)
    w = 0.5 * Ln * wg
    r = nose_radius(s, R, nose_shape, Ln)
    dm = rho * np.pi * r**2 * w
    m_n, sm_n = dm.sum(), (dm * s).sum()
    ixx_n, iyy_n = (0.5 * r**2 * dm).sum(), ((0.25 * r**2 + s**2) * dm).sum()
    # Cylinder s ∈ [L_n, L]: m = ρ π R² l, ∫ s dm = m (L_n + L)/2, ∫ s² dm = m (L³ - L_n³)/(3 l).
    lc = L - Ln
    m_c = rho * np.pi * R**2 * lc
    sm_c = m_c * 0.5 * (Ln + L)
    ixx_c = 0.5 * m_c * R**2
    iyy_c = m_c * R**2 / 4.0 + m_c * (L**3 - Ln**3) / (3.0 * lc)
    m = m_n + m_c
    first = np.array([-(sm_n + sm_c), 0.0, 0.0])  # x_b = -s
    i_o = np.diag([ixx_n + ixx_c, iyy_n + iyy_c, iyy_n + iyy_c])
    return _about_origin_to_cg(m, first, i_o)


def fin_mass_properties(fin: Fin):
    """Mass [kg], CG [m] (3,) and inertia about the CG [kg m^2] (3, 3) of a solid fin plate.

    The trapezoid (two triangles) of thickness h, density ρ: exact second moment of a triangle of
    vertices a, b, c and area A, ∫ r rᵀ dA = A/12 (a aᵀ + b bᵀ + c cᵀ + s sᵀ), s = a + b + c,
    plus the through-thickness term ρ A h³/12 n nᵀ.
    """
    rho, h = fin.material.density, fin.thickness
    m_tot, first, second = 0.0, np.zeros(3), np.zeros((3, 3))
    c = fin.corners
    for a, b, d in ((c[0], c[1], c[2]), (c[0], c[2], c[3])):
        area = 0.5 * np.linalg.norm(np.cross(b - a, d - a))
        ssum = a + b + d
        m = rho * h * area
        m_tot += m
        first += m * ssum / 3.0
        second += rho * h * area / 12.0 * (np.outer(a, a) + np.outer(b, b) + np.outer(d, d)
                                            + np.outer(ssum, ssum))
    second += m_tot * h**2 / 12.0 * np.outer(fin.n, fin.n)
    i_o = np.trace(second) * np.eye(3) - second
    return _about_origin_to_cg(m_tot, first, i_o)


def combine(parts: Iterable[tuple[float, np.ndarray, np.ndarray]]):
    """Mass, CG and inertia about the common CG of rigidly joined parts (each (m, cg, I_cg))."""
    parts = list(parts)
    m = sum(p[0] for p in parts)
    first = sum(p[0] * p[1] for p in parts)
    i_o = sum(p[2] + p[0] * (p[1] @ p[1] * np.eye(3) - np.outer(p[1], p[1])) for p in parts)
    return _about_origin_to_cg(m, first, i_o)


def missile_mass_properties(length: float, radius: float, nose_shape: NoseShape,
                            nose_length: float, body_density: float, fins: Iterable[Fin]):
    """Mass [kg], CG [m] (3,), inertia about the CG [kg m^2] (3, 3) of body + fin plates in B."""
    parts = [body_mass_properties(length, radius, nose_shape, nose_length, body_density)]
    parts += [fin_mass_properties(f) for f in fins]
    return combine(parts)
