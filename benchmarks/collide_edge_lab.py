"""One rope across a swept leading edge: how the contact's normal and friction impulses depend on
the rope's subdivision (docs/collide_convergence.md, "The traction runs past 12 ms", fourth pass).

Scene (the production kernel, ``collide.kernel.advance``): the radar preset, its wing_1 in the
plane z_b = 0 with a 55° swept leading edge; one rope of the paper (E = 1 MPa, ρ = 1000 kg/m³,
d = 4.5 mm, damping ratio 0.05 of the whole rope kept as a material viscosity), 0.4 m long along
z_b, crossing the fin plane 12.3 mm off its middle (no node in the plane), 1 cm ahead of the
leading edge at span station y_b; both ends held; the missile flies at ``--speed`` along +x_b.
For each number of pieces N the run lasts ``--time`` and prints wing_1's axial normal impulse
N_x (the vector part that moves the missile), the scalar sums Σ|F_n| dt and Σ|F_t| dt
(``CollideState.part_imp``), their ratio, and when the contact ended. A resolved wrap of the
rounded edge (both legs trailing, wrap angle θ ≤ π) has Σ|F_n| / |Σ F_n| ≤ θ / (2 sin(θ/2)) ≤ π/2,
i.e. Σ|F_n| / N_x ≤ (π/2) / cos 55° = 2.74.

    PYTHONPATH=. .venv/bin/python benchmarks/collide_edge_lab.py --speed 500 --pieces 32 64 128 256
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from flexnet_fe.collide import kernel as K
from flexnet_fe.collide import model as M
from flexnet_fe.collide.scene import fin_planes, shape_bbox
from flexnet_fe.contact.law import DAMPING_CODE, hysteresis_factor
from flexnet_fe.contact.stiffness import crossed_cylinders_stiffness
from flexnet_fe.missile.build import build_missile
from flexnet_fe.missile.config import MissileConfig
from flexnet_fe.missile.shapes import pack_shapes

ROPE_E, ROPE_RHO, ROPE_D, ROPE_ZETA, ROPE_L = 1.0e6, 1000.0, 4.5e-3, 0.05, 0.4
E_T = 1.0e11  # the cases' transverse (contact) modulus [Pa]


def rope_scene(missile, n: int, y_span: float, speed: float, damping: str, mu: float):
    """(CollideModel, CollideState) of the scene above with n pieces."""
    sh = pack_shapes(missile)
    cg = np.asarray(missile.cg, dtype=float)
    area = np.pi * ROPE_D ** 2 / 4
    x_le = -1.3 - (y_span - 0.1015) * np.tan(np.radians(55.0))  # wing_1 leading edge at y_span (preset geometry)
    z = np.linspace(-ROPE_L / 2, ROPE_L / 2, n + 1) + 0.0123
    x = np.column_stack([np.full(n + 1, x_le + 0.01), np.full(n + 1, y_span), z])
    l0 = ROPE_L / n
    mass = np.full(n + 1, ROPE_RHO * area * l0)
    mass[[0, -1]] /= 2
    free = np.ones(n + 1, np.bool_)
    free[[0, -1]] = False
    c_bar = 2 * ROPE_ZETA * np.sqrt(ROPE_E * area / ROPE_L * ROPE_RHO * area * ROPE_L / 2)
    kc = crossed_cylinders_stiffness(ROPE_D / 2, missile.fins[0].thickness / 2, E_T / 0.91)
    km = M.CollideModel(
        seg=np.column_stack([np.arange(n), np.arange(1, n + 1)]).astype(np.int64), rest=np.full(n, l0),
        k=np.full(n, ROPE_E * area / l0), c=np.full(n, n * c_bar), off=np.zeros(n), break_stretch=np.full(n, np.inf),
        mass=mass, free=free, rope_radius=ROPE_D / 2, m_mass=float(missile.mass),
        inv_inertia=np.linalg.inv(np.asarray(missile.inertia)), cg_b=cg, bbox=shape_bbox(missile),
        prof_kind=sh.prof_kind, prof_data=sh.prof_data, prof_part=sh.prof_part, fin_origin=sh.fin_origin,
        fin_axes=sh.fin_axes, fin_poly=sh.fin_poly, fin_core=sh.fin_core, fin_ncore=sh.fin_ncore, fin_half=sh.fin_half_thickness, fin_planes=fin_planes(sh),
        k_body=kc, k_fin=kc, exponent=1.5, damp_c=hysteresis_factor(DAMPING_CODE[damping], 0.5, 1.0), v_floor=1.0,
        mu=mu, v_reg=0.1, allow_tunnel=False, gravity=np.zeros(3))
    st = M.new_state(x, n, len(missile.fins), cg, np.array([speed, 0.0, 0.0]), np.array([1.0, 0.0, 0.0, 0.0]))
    return km, st


def run(missile, n: int, args) -> dict:
    """One run; dt = 0.4 × the smaller of the piece's spring limit and a contact limit scaled as the
    cases' (1e-7 s at 6.25 mm pieces, ∝ l0^0.4: the split node's mass sets it)."""
    km, st = rope_scene(missile, n, args.span, args.speed, args.damping, args.mu)
    l0 = ROPE_L / n
    m_node = ROPE_RHO * np.pi * ROPE_D ** 2 / 4 * l0
    dt = min(0.4 * np.sqrt(m_node / (ROPE_E * np.pi * ROPE_D ** 2 / 4 / l0)), 0.4e-7 * (l0 / 6.25e-3) ** 0.4)
    steps, chunk, t_end_contact = int(args.time / dt), 1000, 0.0
    wall = time.perf_counter()
    for s0 in range(0, steps, chunk):
        st.acc[M.A_FCONTACT] = 0.0
        if K.advance(km, st, min(chunk, steps - s0), dt) != M.OK:
            raise RuntimeError(f"kernel stopped (status) at N = {n}")
        if st.acc[M.A_FCONTACT] > 0.0:
            t_end_contact = (s0 + chunk) * dt
    imp_x = float(missile.mass) * (st.mv[0] - args.speed)
    return {"n": n, "piece_mm": l0 * 1e3, "dt": dt, "missile_impulse_x": imp_x,
            "n_sum": st.part_imp[1, 0], "f_sum": st.part_imp[1, 1], "contact_end_ms": t_end_contact * 1e3,
            "wall": time.perf_counter() - wall}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--speed", type=float, default=500.0, help="missile speed along x_b [m/s]")
    ap.add_argument("--time", type=float, default=3e-3, help="simulated time [s]")
    ap.add_argument("--span", type=float, default=0.3, help="span station y_b of the rope [m]")
    ap.add_argument("--mu", type=float, default=0.1, help="friction coefficient")
    ap.add_argument("--damping", default="lankarani_nikravesh", choices=sorted(DAMPING_CODE))
    ap.add_argument("--pieces", type=int, nargs="+", default=[32, 64, 128, 256])
    args = ap.parse_args()
    missile = build_missile(MissileConfig(preset="radar"))
    print(f"speed {args.speed:g} m/s, mu {args.mu:g}, damping {args.damping}, {args.time * 1e3:g} ms")
    print("| pieces | piece [mm] | missile impulse x [N s] | wing_1 Σ|F_n| dt [N s] | Σ|F_t| dt [N s] "
          "| Σ|F_n| / |impulse_x| | contact ends [ms] |")
    print("|---|---|---|---|---|---|---|")
    for n in args.pieces:
        r = run(missile, n, args)
        print(f"| {n} | {r['piece_mm']:.3g} | {r['missile_impulse_x']:.4f} | {r['n_sum']:.4f} | {r['f_sum']:.4f} | "
              f"{r['n_sum'] / abs(r['missile_impulse_x']):.2f} | {r['contact_end_ms']:.2f} |", flush=True)


if __name__ == "__main__":
    main()
