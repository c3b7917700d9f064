"""Navier series of a simply supported Reissner–Mindlin plate (reference solutions).

Rectangular plate a × b, thickness t, plane-stress modulus E' = E/(1−ν²), bending stiffness
D = E't³/12, shear stiffness k_s = κ G t, translational inertia ρt, rotary inertia
I = s ρt³/12 (s: the rotary-inertia factor the solver uses). Kinematics as in
:mod:`flexnet_fe.shell.forms`: u_α(z) = zθ_α, curvature κ = sym ∇θ, shear γ = ∇w + θ.
Equations of motion (Mindlin 1951):

    ρt ẅ = ∇·Q + p,    I θ̈ = ∇·M − Q,    M = D[(1−ν)κ + ν tr κ I],   Q = k_s (∇w + θ)

"Hard" simple support on all edges (w = 0, tangential rotation = 0, normal moment = 0) is
satisfied term by term by

    w = W sin αx sin βy,  θ_x = X cos αx sin βy,  θ_y = Y sin αx cos βy,   α = mπ/a, β = nπ/b

which turns the equations into 3 × 3 systems M_mn q̈ + K_mn q = F_mn(t), q = (W, X, Y):

    M_mn = diag(ρt, I, I)
    K_mn = [[k_s(α²+β²), k_s α,                     k_s β                    ],
            [k_s α,      D(α² + (1−ν)β²/2) + k_s,   D(1+ν)αβ/2               ],
            [k_s β,      D(1+ν)αβ/2,                D(β² + (1−ν)α²/2) + k_s  ]]
    F_mn = (p_mn(t), 0, 0)

(derivation: substitute the ansatz; e.g. (∇·M)_x = −D[(α² + (1−ν)β²/2)X + (1+ν)αβY/2]
cos αx sin βy). Load coefficients: uniform p0 → p_mn = 16 p0 / (π² m n) (m, n odd);
a centred rectangular patch u × v of total force F → p_mn = 16 F/(uv π² m n) sin(mπ/2)
sin(nπ/2) sin(mπu/(2a)) sin(nπv/(2b)).

Transient: each of the 3 modes r of (K_mn, M_mn) (M-orthonormal φ_r, frequency ω_r) answers a
load g(t) that is piecewise linear (knots t_k, values g_k, g(0) = 0) exactly through the unit
ramp response R(τ) = (τ − sin(ω τ)/ω)/ω² for τ > 0: q_r(t) = φ_r,W p_mn Σ_k Δs_k R(t − t_k),
Δs_k the slope changes of g. Surface stress (z = ±t/2): σ = ±(t/2) C κ with
κ_xx = −αX sin sin, κ_yy = −βY sin sin, 2κ_xy = (βX + αY) cos αx cos βy.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class PlateData:
    a: float
    """side along x [m]"""
    b: float
    """side along y [m]"""
    thickness: float
    youngs_modulus: float
    poisson_ratio: float
    density: float
    shear_correction: float = 5.0 / 6.0
    rotary_scale: float = 1.0

    @property
    def plane_modulus(self) -> float:
        return self.youngs_modulus / (1 - self.poisson_ratio ** 2)

    @property
    def D(self) -> float:
        return self.plane_modulus * self.thickness ** 3 / 12.0

    @property
    def ks(self) -> float:
        G = self.youngs_modulus / (2 * (1 + self.poisson_ratio))
        return self.shear_correction * G * self.thickness


def _modes(p: PlateData, n_max: int):
    """Odd (m, n) ≤ n_max with α, β and the 3 × 3 K, M, shapes (k,), (k, 3, 3)."""
    m, n = np.meshgrid(np.arange(1, n_max + 1, 2), np.arange(1, n_max + 1, 2), indexing="ij")
    m, n = m.ravel(), n.ravel()
    al, be = m * np.pi / p.a, n * np.pi / p.b
    D, ks, nu = p.D, p.ks, p.poisson_ratio
    K = np.zeros((len(m), 3, 3))
    K[:, 0, 0] = ks * (al ** 2 + be ** 2)
    K[:, 0, 1] = K[:, 1, 0] = ks * al
    K[:, 0, 2] = K[:, 2, 0] = ks * be
    K[:, 1, 1] = D * (al ** 2 + (1 - nu) * be ** 2 / 2) + ks
    K[:, 2, 2] = D * (be ** 2 + (1 - nu) * al ** 2 / 2) + ks
    K[:, 1, 2] = K[:, 2, 1] = D * (1 + nu) * al * be / 2
    I_rot = p.rotary_scale * p.density * p.thickness ** 3 / 12
    Mdiag = np.array([p.density * p.thickness, I_rot, I_rot])
    return m, n, al, be, K, Mdiag


def uniform_coefficients(p: PlateData, m, n, p0: float = 1.0) -> np.ndarray:
    return 16.0 * p0 / (np.pi ** 2 * m * n)


def patch_coefficients(p: PlateData, m, n, force: float, u: float, v: float) -> np.ndarray:
    """Centred u × v patch of total force ``force`` [N]."""
    return (16.0 * force / (u * v * np.pi ** 2 * m * n) * np.sin(m * np.pi / 2)
            * np.sin(n * np.pi / 2) * np.sin(m * np.pi * u / (2 * p.a))
            * np.sin(n * np.pi * v / (2 * p.b)))


def static_amplitudes(p: PlateData, n_max: int, coeff_fn) -> tuple:
    """(m, n, α, β, q (k, 3)) for the static load with coefficients coeff_fn(p, m, n)."""
    m, n, al, be, K, _ = _modes(p, n_max)
    F = np.zeros((len(m), 3))
    F[:, 0] = coeff_fn(p, m, n)
    return m, n, al, be, np.linalg.solve(K, F[:, :, None])[:, :, 0]


def transient_amplitudes(p: PlateData, n_max: int, t: np.ndarray, knots_t, knots_g,
                         coeff_fn=uniform_coefficients) -> tuple:
    """(m, n, α, β, q (nt, k, 3)) for the load p_mn g(t), g piecewise linear through
    (knots_t, knots_g) with g(knots_t[0] = 0) = 0, constant after the last knot."""
    m, n, al, be, K, Md = _modes(p, n_max)
    s = 1.0 / np.sqrt(Md)
    B = s[None, :, None] * K * s[None, None, :]  # M^{-1/2} K M^{-1/2}
    w2, V = np.linalg.eigh(B)  # (k, 3), (k, 3, 3)
    phi = s[None, :, None] * V  # M-orthonormal mode shapes, columns
    om = np.sqrt(w2)
    kt, kg = np.asarray(knots_t, float), np.asarray(knots_g, float)
    slopes = np.diff(kg) / np.diff(kt)
    ds = np.diff(np.concatenate([[0.0], slopes, [0.0]]))  # slope changes at each knot
    pm = coeff_fn(p, m, n)
    q = np.zeros((len(t), len(m), 3))
    for tk, dsk in zip(kt, ds):
        tau = np.maximum(np.asarray(t)[:, None, None] - tk, 0.0)
        R = (tau - np.sin(om[None] * tau) / om[None]) / w2[None]  # (nt, k, 3 modes)
        # modal force φ_r,W p_mn; back to (W, X, Y): q = Σ_r φ_r (φ_r,W p_mn R_r)
        q += dsk * np.einsum("kir,kr,tkr->tki", phi, phi[:, 0, :] * pm[:, None], R)
    return m, n, al, be, q


def fields(p: PlateData, amps: tuple, x: np.ndarray, y: np.ndarray):
    """Deflection w [m] and top-surface stress (σxx, σyy, σxy) [Pa] at points (x, y) (np,)
    for amplitudes from :func:`static_amplitudes` (q (k, 3)) or :func:`transient_amplitudes`
    (q (nt, k, 3)); shapes (..., np) and (..., np, 3)."""
    m, n, al, be, q = amps
    ss = np.sin(np.outer(al, x)) * np.sin(np.outer(be, y))  # (k, np)
    cc = np.cos(np.outer(al, x)) * np.cos(np.outer(be, y))
    W, X, Y = q[..., 0], q[..., 1], q[..., 2]
    w = W @ ss
    kxx = -(X * al) @ ss
    kyy = -(Y * be) @ ss
    k2xy = (X * be + Y * al) @ cc
    E, nu, z = p.plane_modulus, p.poisson_ratio, 0.5 * p.thickness
    sig = np.stack([E * z * (kxx + nu * kyy), E * z * (kyy + nu * kxx),
                    E * (1 - nu) * z * 0.5 * k2xy], axis=-1)
    return w, sig
