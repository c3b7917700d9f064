"""The collide stage (paper §IV, §V-C): held net vs rigid missile, written into ``stage_dir``.

Files written
    history.csv        one row per output interval (t_s = interval end): missile CG acceleration in
                       body axes (mean over the interval) and its magnitude, body rates and angular
                       accelerations, world velocity, speed change, pitch/yaw/roll change (rotation
                       about world x, y, z since t = 0, paper Fig. 13), contacts, penetration, broken
                       segments, momentum of missile / net / held nodes (W) and every energy term
                       (columns ending in _j, with energy_balance_j; see ``simulate``)
    fin_contacts.npz   (allow_pickle=False) per-fin contact loads for the shell stage, EXACTLY:
                       fin_names (nf,) unicode; t [s] (nt,) sample times (midpoints of the
                       collide.load_interval intervals, by default the output intervals);
                       row_start (nt+1,) int64 CSR offsets (events of sample k are rows
                       row_start[k]:row_start[k+1]); fin (ne,) int32; point [m] (ne, 3) contact point
                       in B; force [N] (ne, 3) mean force ON the fin over the interval, in B;
                       width [m] (ne,) rope contact width (the rope diameter)
    accel_body.npz     t [s] and accel_body [m/s²] (nt, 3) — the rigid-body CG acceleration history
                       at the same times as history.csv, for inertial loads
    snapshots/net_*.vtu, snapshots/missile_*.vtu, net.pvd, missile.pvd   (ParaView / PyVista)
    collide_*.png      plots like the paper's Fig. 11–13, 15(a), 16, 17(a)
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from flexnet_fe.atmosphere import Air
from flexnet_fe.collide.config import CollideConfig
from flexnet_fe.collide.check import finish_check, start_check
from flexnet_fe.collide.scene import held_net
from flexnet_fe.collide.simulate import CollisionResult, simulate
from flexnet_fe.io import write_history_csv
from flexnet_fe.missile.config import MissileConfig
from flexnet_fe.missile.geometry import Missile
from flexnet_fe.missile.build import build_missile
from flexnet_fe.net.snapshots import write_pvd, write_vtu
from flexnet_fe.frames import quat_to_matrix
from flexnet_fe.runs import FIN_CONTACTS, HISTORY, MISSILE_PVD, NET_PVD


def run_collide(net_cfg, deploy_cfg, missile_cfg: MissileConfig, collide_cfg: CollideConfig, air: Air,
                deploy_dir: Path | None, stage_dir: Path, log: logging.Logger, *, fin_motion=None,
                plots: bool = True) -> dict:
    """Run the collision and write its files (module docstring). ``deploy_cfg`` is not used by the
    physics (the held net comes from ``deploy_dir/net_state.npz`` or the flat net); it is accepted
    so the pipeline passes the same tables to every stage. ``fin_motion``: the fins moving as
    prescribed (``collide.model.FinMotion``; the staggered coupling, ``shell.coupling``), in the
    impact and its resolution check; ``plots``: False skips the PNGs. Returns the ``collide``
    summary section (DESIGN.md §3 keys plus extras). Raises NumericalError on tunnelling (unless
    the case allows it) or a blow-up."""
    del deploy_cfg
    stage_dir = Path(stage_dir)
    stage_dir.mkdir(parents=True, exist_ok=True)
    net = held_net(net_cfg, collide_cfg.net_source, deploy_dir)
    missile = build_missile(missile_cfg)
    log.info("collide: %s net (%s, %d nodes), %s missile (%.1f kg), %.0f m/s, incidence %.3g rad, "
             "aim (%.3g, %.3g) m", net.model.kind, net.source.value, net.model.n_nodes, missile.name,
             missile.mass, collide_cfg.impact_speed, collide_cfg.incidence_angle, *collide_cfg.aim_point)
    check = start_check(net, missile, collide_cfg, air, log, fin_motion) if collide_cfg.resolution_check else None
    try:
        res = simulate(net, missile, collide_cfg, air.gravity, log, air_density=air.density, fin_motion=fin_motion)
        # the files and plots while the check (beside) runs on: they do not depend on it
        net = res.net  # split near the path per collide.rope_split
        write_outputs(res, net.model.springs[res.alive], net.rest_length[res.alive],
                      net.model.stiffness[res.alive], missile, stage_dir)
        if plots:
            from flexnet_fe.collide.plots import plot_all

            plot_all(res, missile, collide_cfg, stage_dir, title=f"{missile.name} missile vs {net.model.kind} net")
        if check is not None:
            finish_check(res.summary, check, collide_cfg, log)
    finally:
        if check is not None:
            check.stop()
    s = res.summary
    log.info("collide: peak |a| = %.4g m/s² at %.4g s, |Δv|/v = %.3g, attitude change %.3g rad, contact "
             "duration %.4g s (stopped: %s at %.4g s), %s, max penetration %.3g m, momentum error %.2g, energy error %.2g, %d broken "
             "segments, %d steps of %.3g s in %.1f s", s["peak_accel_mps2"], s["peak_accel_time_s"], s["dv_over_v"],
             s["max_attitude_change_rad"], s["duration_s"], s["stop_reason"], s["end_time_s"],
             "passed through" if s["passed_through"] else "net carried forward / still in contact",
             s["max_penetration_m"], s["momentum_error_rel"], s["energy_error_rel"], s["broken_segments"], s["steps"], s["dt_s"],
             s["wall_s"])
    return s


def write_outputs(res: CollisionResult, springs: np.ndarray, rest: np.ndarray, k: np.ndarray,
                  missile: Missile, stage_dir: Path) -> None:
    """history.csv, fin_contacts.npz, accel_body.npz and the snapshots (see the module doc)."""
    write_history_csv(stage_dir / HISTORY, res.history)
    ld = res.loads
    np.savez(stage_dir / FIN_CONTACTS, fin_names=ld.fin_names.astype(str), t=ld.t,
             row_start=ld.row_start.astype(np.int64), fin=ld.fin.astype(np.int32), point=ld.point,
             force=ld.force, width=ld.width)
    h = res.history
    np.savez(stage_dir / "accel_body.npz", t=h["t_s"],
             accel_body=np.column_stack([h[f"accel_body_{c}_mps2"] for c in "xyz"]))
    snap = stage_dir / "snapshots"
    snap.mkdir(exist_ok=True)
    net_entries, mis_entries = [], []
    wire_pts, wire_lines = missile_wireframe(missile)
    for i, t in enumerate(res.snap_t):
        x = res.snap_x[i]
        ln = np.linalg.norm(x[springs[:, 1]] - x[springs[:, 0]], axis=1)
        tension = k * np.maximum(ln - rest, 0.0)  # elastic part (the dashpots' share is not kept)
        name = f"net_{i:04d}.vtu"
        write_vtu(snap / name, x, res.snap_v[i], springs, tension)
        net_entries.append((float(t), f"snapshots/{name}"))
        r = quat_to_matrix(res.snap_q[i])
        pts = res.snap_apex[i] + wire_pts @ r.T
        name = f"missile_{i:04d}.vtu"
        _write_lines(snap / name, pts, wire_lines)
        mis_entries.append((float(t), f"snapshots/{name}"))
    write_pvd(stage_dir / NET_PVD, net_entries)
    write_pvd(stage_dir / MISSILE_PVD, mis_entries)


def missile_wireframe(missile: Missile, n_around: int = 24) -> tuple[np.ndarray, np.ndarray]:
    """A line drawing of the missile in B (points [m] (p, 3), lines (l, 2)): body rings at the
    profile's stations, four generator lines, and each fin's outline."""
    from flexnet_fe.missile.geometry import nose_radius

    pts, lines = [], []
    stations = np.concatenate([np.linspace(0.0, missile.nose_length, 8)[1:], [missile.length]])
    radii = np.concatenate([nose_radius(stations[:-1], missile.radius, missile.nose_shape, missile.nose_length),
                            [missile.radius]])
    ang = np.linspace(0.0, 2 * np.pi, n_around, endpoint=False)
    pts.append(np.zeros(3))  # apex
    ring_start = []
    for s, r in zip(stations, radii):
        ring_start.append(len(pts))
        for a in ang:
            pts.append(np.array([-s, r * np.cos(a), r * np.sin(a)]))
        for j in range(n_around):
            lines.append((ring_start[-1] + j, ring_start[-1] + (j + 1) % n_around))
    for j in range(0, n_around, n_around // 4):
        prev = 0
        for rs in ring_start:
            lines.append((prev, rs + j))
            prev = rs + j
    for fin in missile.fins:
        base = len(pts)
        pts.extend(np.asarray(fin.corners))
        lines.extend((base + c, base + (c + 1) % 4) for c in range(4))
    return np.array(pts), np.array(lines, dtype=np.int64)


def _write_lines(path: Path, pts: np.ndarray, lines: np.ndarray) -> None:
    import pyvista as pv

    cells = np.hstack([np.full((len(lines), 1), 2, dtype=np.int64), lines]).ravel()
    grid = pv.UnstructuredGrid(cells, np.full(len(lines), pv.CellType.LINE, dtype=np.uint8),
                               np.ascontiguousarray(pts, dtype=np.float64))
    grid.save(str(path), binary=True)
