"""Mass properties against closed forms, the parallel-axis theorem and the preset's source."""

import numpy as np
import pytest
from scipy.integrate import quad

from flexnet_fe.missile.config import FinMaterial, FinSetConfig, MissileConfig, NoseShape
from flexnet_fe.missile.geometry import FinKind, build_fin
from flexnet_fe.missile.build import build_missile
from flexnet_fe.missile.mass import body_mass_properties, fin_mass_properties

RHO = 1800.0
L, R = 3.0, 0.1


def _assemble(parts):
    """Independent reference: combine axisymmetric parts given as (m, s_cg, I_axial, I_trans_cg)
    with the parallel-axis theorem along the axis. Returns (m, s_cg, I_axial, I_trans about CG)."""
    m = sum(p[0] for p in parts)
    s = sum(p[0] * p[1] for p in parts) / m
    return m, s, sum(p[2] for p in parts), sum(p[3] + p[0] * (p[1] - s) ** 2 for p in parts)


def _cylinder(s0, s1):
    # solid cylinder: m = ρπR²l, I_axial = mR²/2, I_trans(CG) = m(R²/4 + l²/12)
    l_ = s1 - s0
    m = RHO * np.pi * R**2 * l_
    return m, 0.5 * (s0 + s1), 0.5 * m * R**2, m * (R**2 / 4 + l_**2 / 12)


def _check(got, ref, rtol):
    m, cg, inertia = got
    m_ref, s_ref, ia, it = ref
    np.testing.assert_allclose(m, m_ref, rtol=rtol)
    np.testing.assert_allclose(cg, [-s_ref, 0, 0], rtol=rtol, atol=rtol * L)
    np.testing.assert_allclose(inertia, np.diag([ia, it, it]), rtol=rtol, atol=rtol * it)


def test_cone_and_cylinder_closed_form():
    ln = 0.5
    # right circular cone, apex at s=0: m = ρπR²Ln/3, centroid 3Ln/4 from the apex,
    # I_axial = 3mR²/10, I_trans(CG) = 3m(R²/4 + Ln²/16)/5 (= 3m/80 (4R² + Ln²))
    mc = RHO * np.pi * R**2 * ln / 3
    cone = (mc, 0.75 * ln, 0.3 * mc * R**2, 3 * mc / 80 * (4 * R**2 + ln**2))
    ref = _assemble([cone, _cylinder(ln, L)])
    # Gauss–Legendre with 64 points integrates the cone's polynomial integrands exactly:
    # round-off tolerance
    _check(body_mass_properties(L, R, NoseShape.CONE, ln, RHO), ref, 1e-12)


def test_plain_cylinder_limit():
    # a cone of vanishing length leaves the plain cylinder: m = ρπR²L, CG at L/2,
    # I = diag(mR²/2, m(R²/4 + L²/12), same); the residual cone changes it by O(Ln/L)
    ln = 1e-9
    _check(body_mass_properties(L, R, NoseShape.CONE, ln, RHO), _cylinder(0.0, L), 1e-8)


def test_hemisphere_and_cylinder_closed_form():
    # solid hemisphere, flat face at s = R, apex at s = 0: m = 2πρR³/3, centroid 3R/8 from the
    # flat face (s = 5R/8), I_axial = 2mR²/5, I_trans(CG) = 2mR²/5 - m(3R/8)² = 83mR²/320
    mh = 2 * np.pi * RHO * R**3 / 3
    hemi = (mh, 5 * R / 8, 0.4 * mh * R**2, 83 * mh * R**2 / 320)
    ref = _assemble([hemi, _cylinder(R, L)])
    _check(body_mass_properties(L, R, NoseShape.HEMISPHERE, R, RHO), ref, 1e-12)


def test_tangent_ogive_against_adaptive_quadrature():
    # second model: scipy's adaptive quadrature of the slice integrals of the tangent ogive
    # r(s) = sqrt(ρ_o² - (Ln - s)²) + R - ρ_o, ρ_o = (R² + Ln²)/(2R); quad's error ~1e-14
    ln = 0.6
    rho_o = (R**2 + ln**2) / (2 * R)

    def r(s):
        return np.sqrt(rho_o**2 - (ln - s) ** 2) + R - rho_o

    mo = quad(lambda s: RHO * np.pi * r(s) ** 2, 0, ln, epsabs=0, epsrel=1e-13)[0]
    so = quad(lambda s: RHO * np.pi * r(s) ** 2 * s, 0, ln, epsabs=0, epsrel=1e-13)[0] / mo
    ia = quad(lambda s: 0.5 * RHO * np.pi * r(s) ** 4, 0, ln, epsabs=0, epsrel=1e-13)[0]
    it_apex = quad(lambda s: RHO * np.pi * r(s) ** 2 * (r(s) ** 2 / 4 + s**2), 0, ln,
                   epsabs=0, epsrel=1e-13)[0]
    ogive = (mo, so, ia, it_apex - mo * so**2)
    ref = _assemble([ogive, _cylinder(ln, L)])
    _check(body_mass_properties(L, R, NoseShape.TANGENT_OGIVE, ln, RHO), ref, 1e-10)


def _fin(**kw):
    base = dict(root_chord=0.3, tip_chord=0.3, span=0.2, leading_edge_sweep_deg=0.0,
                thickness=0.005, root_le_station=1.0, roll_angles_deg=(30.0, 120.0, 210.0, 300.0))
    base.update(kw)
    return build_fin("wing_1", FinKind.WING, 0, FinSetConfig(**base), 30.0, R, FinMaterial())


def test_rectangular_plate_closed_form():
    fin = _fin()
    m, cg, inertia = fin_mass_properties(fin)
    c, b, h, rho = 0.3, 0.2, 0.005, fin.material.density
    m_ref = rho * c * b * h
    # rectangular plate (box) about its centroid, in fin axes (e1 span, e2 chord, n):
    # I_e1 = m(c² + h²)/12, I_e2 = m(b² + h²)/12, I_n = m(b² + c²)/12
    axes = np.stack([fin.e1, fin.e2, fin.n])
    i_ref = axes.T @ np.diag([c**2 + h**2, b**2 + h**2, b**2 + c**2]) * m_ref / 12 @ axes
    cg_ref = fin.origin + 0.5 * b * fin.e1 + 0.5 * c * fin.e2
    np.testing.assert_allclose(m, m_ref, rtol=1e-13)
    np.testing.assert_allclose(cg, cg_ref, rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(inertia, i_ref, rtol=1e-10, atol=1e-12 * np.abs(i_ref).max())


def test_trapezoid_mass_and_centroid():
    cr, ct, b = 0.4, 0.1, 0.25
    fin = _fin(root_chord=cr, tip_chord=ct, span=b, leading_edge_sweep_deg=40.0)
    m, cg, _ = fin_mass_properties(fin)
    # trapezoid area (c_r + c_t) b / 2; centroid from the shoelace formula on the (u, v) corners
    u, v = fin.uv[:, 0], fin.uv[:, 1]
    cross = u * np.roll(v, -1) - np.roll(u, -1) * v
    a = 0.5 * cross.sum()
    cu = ((u + np.roll(u, -1)) * cross).sum() / (6 * a)
    cv = ((v + np.roll(v, -1)) * cross).sum() / (6 * a)
    np.testing.assert_allclose(a, 0.5 * (cr + ct) * b, rtol=1e-13)
    np.testing.assert_allclose(m, fin.material.density * fin.thickness * a, rtol=1e-13)
    np.testing.assert_allclose(cg, fin.origin + cu * fin.e1 + cv * fin.e2, rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("preset", ["radar", "infrared"])
def test_missile_inertia_symmetric_positive_definite(preset):
    mis = build_missile(MissileConfig(preset=preset))
    inertia = mis.inertia
    np.testing.assert_allclose(inertia, inertia.T, atol=1e-12 * np.abs(inertia).max())
    assert np.linalg.eigvalsh(inertia).min() > 0
    # principal moments of a rigid body obey the triangle inequality I1 + I2 >= I3
    ev = np.sort(np.linalg.eigvalsh(inertia))
    assert ev[0] + ev[1] >= ev[2]
    # cruciform layout (4 equal fins at 90°): I_yy = I_zz, no products of inertia, CG on the axis
    np.testing.assert_allclose(inertia[1, 1], inertia[2, 2], rtol=1e-12)
    assert np.abs(inertia - np.diag(np.diag(inertia))).max() < 1e-12 * inertia.max()
    np.testing.assert_allclose(mis.cg[1:], 0.0, atol=1e-15)


def test_radar_preset_mass_matches_source():
    # AIM-7M launch mass 231 kg (designation-systems.net); body_density is calibrated to it,
    # rounded to 1 kg/m^3 -> |Δm| <= 0.11 m^3 * 0.5 kg/m^3 ≈ 0.06 kg
    assert abs(build_missile(MissileConfig(preset="radar")).mass - 231.0) < 0.06


def test_moving_the_wings_obeys_parallel_axis_theorem():
    d_station = 0.25  # wings moved 0.25 m aft
    cfg0 = MissileConfig(preset="radar")
    cfg1 = MissileConfig(preset="radar",
                         wings={"root_le_station": cfg0.wings.root_le_station + d_station})
    m0, m1 = build_missile(cfg0), build_missile(cfg1)
    shift = np.array([-d_station, 0.0, 0.0])
    wings = [f for f in m0.fins if f.kind is FinKind.WING]
    m_w = np.array([fin_mass_properties(f)[0] for f in wings])
    c_w = np.array([fin_mass_properties(f)[1] for f in wings])
    # the total mass is unchanged; the CG moves by Σ m_w d / M
    np.testing.assert_allclose(m1.mass, m0.mass, rtol=1e-14)
    np.testing.assert_allclose(m1.cg, m0.cg + m_w.sum() * shift / m0.mass, atol=1e-14)

    def about_origin(mis):  # parallel-axis theorem: I_o = I_cg + M (|c|² 1 - c cᵀ)
        c = mis.cg
        return mis.inertia + mis.mass * (c @ c * np.eye(3) - np.outer(c, c))

    # each translated wing keeps its own I_cg; only its m(|c|² 1 - c cᵀ) term about O changes
    d_io = sum(m * (((c + shift) @ (c + shift) - c @ c) * np.eye(3)
                    - (np.outer(c + shift, c + shift) - np.outer(c, c)))
               for m, c in zip(m_w, c_w))
    np.testing.assert_allclose(about_origin(m1) - about_origin(m0), d_io,
                               atol=1e-10 * np.abs(m0.inertia).max())
    assert m1.inertia[1, 1] != m0.inertia[1, 1]
