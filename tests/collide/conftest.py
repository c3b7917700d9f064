"""Small scenes for the collision tests (flat taut traction nets, single rope segments, the radar
preset missile)."""

from __future__ import annotations

import logging
import types

import numpy as np
import pytest

from flexnet_fe.collide import kernel as K
from flexnet_fe.collide import model as M
from flexnet_fe.collide.config import NetSource
from flexnet_fe.collide.scene import HeldNet, fin_planes, held_net, shape_bbox
from flexnet_fe.contact.law import DAMPING_CODE, hysteresis_factor
from flexnet_fe.missile.config import MissileConfig
from flexnet_fe.missile.build import build_missile
from flexnet_fe.missile.shapes import nose_cones, pack_shapes
from flexnet_fe.net.config import TractionNet

E_T = 1.0e11
"""Transverse modulus of the paper cases' rope [Pa] (cases/*/case.toml)."""


@pytest.fixture(scope="session")
def radar():
    return build_missile(MissileConfig(preset="radar"))


@pytest.fixture(scope="session")
def log():
    lg = logging.getLogger("test_collide")
    lg.setLevel(logging.WARNING)
    return lg


def flat_net(edge: float, mesh: float, **kw) -> HeldNet:
    """A flat taut traction net of the paper's rope (E = 1 MPa, ρ = 1000 kg/m³, d = 4.5 mm) with
    the cases' transverse modulus."""
    cfg = TractionNet(edge_length=edge, mesh_size=mesh, rope_diameter=4.5e-3, corner_mass=kw.pop("corner_mass", 1e-3),
                      transverse_modulus=kw.pop("transverse_modulus", E_T), **kw)
    return held_net(cfg, NetSource.flat_taut, None)


def moved(net: HeldNet, x: np.ndarray) -> HeldNet:
    """The same net held at other positions x [m] (n, 3)."""
    return HeldNet(net.model, np.asarray(x, dtype=float), net.rest_length, net.rope, net.source)


def segment_scene(missile, a_b, b_b, v_a, v_b, *, mass=1.6e-3, k=0.0, c=0.0, rest=None, free=(True, True),
                  k_contact=1e9, damping="none", mu=0.0, rope_radius=2.25e-3, break_stretch=np.inf,
                  allow_tunnel=False, k_line=0.0, line_h=None):
    """One rope segment a–b (positions [m] in the missile's body frame B, velocities [m/s]) next to
    ``missile``, which starts at rest with B = W (identity attitude, CG at cg_b). Returns
    (CollideModel, CollideState) for ``kernel.advance``. line_h [m]: the line contact law
    with k_l = k_line [N/m²] and that point spacing on every part (None: the segment law)."""
    sh = pack_shapes(missile)
    x = np.array([a_b, b_b], dtype=float)
    rest = float(np.linalg.norm(x[1] - x[0])) if rest is None else rest
    cg = np.asarray(missile.cg, dtype=float)
    km = M.CollideModel(
        seg=np.array([[0, 1]], np.int64), rest=np.array([rest]), k=np.array([k]), c=np.array([c]), off=np.zeros(1),
        break_stretch=np.array([break_stretch]), mass=np.full(2, mass), free=np.array(free, np.bool_),
        rope_radius=rope_radius, m_mass=float(missile.mass), inv_inertia=np.linalg.inv(np.asarray(missile.inertia)),
        cg_b=cg, bbox=shape_bbox(missile), prof_kind=sh.prof_kind, prof_data=sh.prof_data, prof_part=sh.prof_part,
        fin_origin=sh.fin_origin, fin_axes=sh.fin_axes, fin_poly=sh.fin_poly, fin_core=sh.fin_core, fin_ncore=sh.fin_ncore, fin_half=sh.fin_half_thickness,
        fin_planes=fin_planes(sh), k_body=k_contact, k_fin=k_contact, exponent=1.5,
        damp_c=hysteresis_factor(DAMPING_CODE[damping], 0.5, 1.0), v_floor=1.0, mu=mu, v_reg=0.1,
        allow_tunnel=allow_tunnel, gravity=np.zeros(3), nose_cones=nose_cones(sh.prof_kind, sh.prof_data),
        line_law=line_h is not None, kl_body=k_line, kl_fin=np.full(len(sh.fin_half_thickness), k_line),
        line_h_body=line_h or 0.0, line_h_fin=np.full(len(sh.fin_half_thickness), line_h or 0.0))
    st = M.new_state(x, 1, len(missile.fins), cg, np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0]))
    st.v[0], st.v[1] = v_a, v_b
    return km, st


def total_energy(km, st, missile) -> float:
    """Kinetic + stored + dissipated + released energy of a segment scene [J] (gravity off)."""
    ke_n, pe_n, pe_c = K.energies(km, st)
    w_b = km.inv_inertia @ st.mh  # B = W to O(rotation) in these scenes: Rᵀ h ≈ h
    ke_m = 0.5 * missile.mass * float(st.mv @ st.mv) + 0.5 * float(st.mh @ w_b)
    acc = st.acc
    return (ke_m + ke_n + pe_n + pe_c + acc[M.A_DISS_ROPE] + acc[M.A_DISS_CONTACT] + acc[M.A_DISS_FRICTION]
            + acc[M.A_BROKEN])


@pytest.fixture(scope="session")
def scenes():
    """The scene helpers of this module."""
    return types.SimpleNamespace(flat_net=flat_net, moved=moved, segment_scene=segment_scene,
                                 total_energy=total_energy)
