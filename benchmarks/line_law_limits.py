"""Where the line contact law (``collide.contact_law = "line"``, the default since 2026-11-28) needs
more resolution than the per-segment law, measured side by side in one process
(docs/validation.md, "Line contact as the default"):

1. ``apex``: tests/collide/test_kernel_speedups.py's 0.4 m flat net (5 cm bars, E_t = 100 GPa), the
   radar's nose tip aimed at a rope (and between two), 500 m/s, 4 000 kernel steps, both laws, the rope
   split 1 / 2 / 4 / 8 near the path: largest penetration [m], tunnelling.
2. ``quick``: the quick collide study's scene (2 m net, 20 cm bars) uncut and with the rope cut to 2 cm
   at the fins (``study.scenes.COARSE_FIN_CUT``): penetration / (r + h), Δv/v, CPU.
3. ``strike``: tests/collide/test_adapt.py's fin-edge scene cut to the edge limit, run to 8 ms (its rope
   meets rudder_1 at ≈ 7 ms): the energy balance against dt_safety. (Until 2026-11-28 the line law was
   per metre of current length and this part also compared two rules for its step; the rows of that
   day with a ``horizon`` key are those, docs/validation.md.)

    PYTHONPATH=.:tests/collide .venv/bin/python benchmarks/line_law_limits.py OUT.jsonl [apex quick strike]

Each row: the part, its settings and measured values, CPU [s], load, machine, date."""

from __future__ import annotations

import json
import logging
import os
import platform
import sys
import time
import types

import numpy as np

LOG = logging.getLogger("line_law_limits")
LOG.setLevel(logging.ERROR)


def _row(out, **kw):
    kw.update(load=os.getloadavg()[0], machine=platform.processor() or platform.machine(),
              date=time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()))
    out.write(json.dumps(kw) + "\n")
    out.flush()
    print(kw, flush=True)


def apex(out):
    from conftest import flat_net  # tests/collide/conftest.py (on PYTHONPATH)

    from flexnet_fe.collide import kernel as K
    from flexnet_fe.collide import model as M
    from flexnet_fe.collide.config import CollideConfig
    from flexnet_fe.collide.refine import split_near_path
    from flexnet_fe.collide.simulate import build
    from flexnet_fe.missile.build import build_missile
    from flexnet_fe.missile.config import MissileConfig

    radar = build_missile(MissileConfig(preset="radar"))
    net = flat_net(0.4, 0.05)
    for law in ("segment", "line"):
        for split in (1, 2, 4, 8):
            for aim in ((0.0, 0.02), (0.025, 0.02)):
                cfg = CollideConfig(net_source="flat_taut", duration=1e-3, aim_point=aim, crop=False,
                                    contact_law=law, rope_split=split)
                c0 = time.process_time()
                split_net = split_near_path(net, radar, cfg)
                setup = build(split_net, radar, cfg, 9.81, LOG, False)
                km, s = setup.model, setup.start
                st = M.new_state(split_net.x[setup.used], km.seg.shape[0], km.fin_half.shape[0], s.x_cg, s.v_cg, s.q)
                dt = 0.5 * setup.step.dt
                status, n = M.OK, 0
                while n < 4000 and status == M.OK:
                    status = K.advance(km, st, 100, dt)
                    n += 100
                _row(out, part="apex", law=law, rope_split=split, aim=list(aim), dt_s=dt, steps=n,
                     tunnelled=bool(status == M.TUNNEL), max_penetration_m=float(st.acc[M.A_PEN]),
                     tunnel_speed_mps=float(st.acc[M.A_TUN_SPEED]), cpu_s=time.process_time() - c0)


def quick(out):
    from flexnet_fe.errors import NumericalError
    from flexnet_fe.study.collide import simulate_case
    from flexnet_fe.study.scenes import CASE, COARSE_FIN_CUT, QUICK_COLLIDE, case_with

    uncut = tuple(o for o in QUICK_COLLIDE if o not in COARSE_FIN_CUT) + (
        "collide.fin_piece_length=1.0", "collide.fin_piece_chord=1.0")
    for law in ("segment", "line"):
        for name, base in (("uncut", uncut), ("cut 2 cm", QUICK_COLLIDE)):
            case = case_with(CASE, base + (f"collide.contact_law='{law}'",))
            c0 = time.process_time()
            try:
                s = simulate_case(case, None)[2].summary
                _row(out, part="quick", law=law, rope=name, tunnelled=False,
                     max_penetration_ratio=s["max_penetration_ratio"], dv_over_v=s["dv_over_v"],
                     cpu_s=time.process_time() - c0)
            except NumericalError as err:
                _row(out, part="quick", law=law, rope=name, tunnelled=True, message=str(err)[:200],
                     cpu_s=time.process_time() - c0)


def strike(out):
    import conftest as C  # tests/collide/conftest.py (on PYTHONPATH)

    from flexnet_fe.collide import simulate as S
    from flexnet_fe.collide.config import CollideConfig
    from flexnet_fe.missile.build import build_missile
    from flexnet_fe.missile.config import MissileConfig

    sys.path.insert(0, ".")
    from tests.collide.test_collide import _fin_edge_scene

    radar = build_missile(MissileConfig(preset="radar"))
    scenes = types.SimpleNamespace(flat_net=C.flat_net, moved=C.moved)
    limit = (2.25e-3 + 2.0e-3) / 3
    for law in ("line", "segment"):
        for safety in (0.5, 0.4, 0.25):
            cfg = CollideConfig(net_source="flat_taut", duration=8e-3, crop=False, fin_piece_length=limit,
                                fin_piece_chord=limit, fin_split_margin=0.03, contact_law=law, dt_safety=safety)
            c0 = time.process_time()
            r = S.simulate(_fin_edge_scene(scenes), radar, cfg, 9.81, LOG)
            s, h = r.summary, r.history
            jump = np.diff(h["energy_balance_j"])
            k = int(np.argmax(np.abs(jump)))
            _row(out, part="strike", law=law, line_per="rest length", dt_safety=safety,
                 energy_error_rel=s["energy_error_rel"], dt_s=s["dt_s"], steps=s["steps"],
                 worst_jump_j=float(jump[k]), worst_jump_t_s=float(h["t_s"][k + 1]),
                 rudder_1_ns=s["fin_impulse_ns"]["rudder_1"], wing_1_ns=s["fin_impulse_ns"]["wing_1"],
                 cpu_s=time.process_time() - c0)


def main() -> None:
    parts = sys.argv[2:] or ["apex", "quick", "strike"]
    with open(sys.argv[1], "a") as out:
        for p in parts:
            {"apex": apex, "quick": quick, "strike": strike}[p](out)


if __name__ == "__main__":
    main()
