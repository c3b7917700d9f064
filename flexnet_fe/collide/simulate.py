"""Drive the compiled collision kernel over the output intervals and collect the results.

:func:`simulate` is the physics of the collide stage without any file output (tests and
benchmarks call it directly); ``stage.run_collide`` writes its result into the run directory.

Sampling: every ``output_interval`` Δ the history gets one row at the interval's end t_k. The
accelerations in it are means over the interval, (v(t_k) − v(t_k − Δ))/Δ in body axes, so that
they do not depend on the (tiny) step or on which step a sample falls; velocities and attitudes
are the values at t_k. The fin loads are mean forces over each interval, attributed to its
midpoint (the impulse of every contact is kept exactly).
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field

import numpy as np

from flexnet_fe.collide import kernel as K
from flexnet_fe.collide.config import CollideConfig
from flexnet_fe.collide.crop import (active_segments, boundary_motion, boundary_nodes, crop_reach, free_nodes,
                                     wave_speed)
from flexnet_fe.collide.scene import HeldNet, fin_planes, place_missile
from flexnet_fe.collide.timestep import StepChoice, choose_step
from flexnet_fe.contact.law import DAMPING_CODE
from flexnet_fe.errors import NumericalError
from flexnet_fe.missile.geometry import Missile
from flexnet_fe.missile.shapes import pack_shapes, part_names
from flexnet_fe.progress import progress_bar
from flexnet_fe.rigid import quat_mul, quat_to_matrix


@dataclass(frozen=True)
class FinLoads:
    """Per-fin contact loads in the format of ``fin_contacts.npz`` (see ``stage``):
    t [s] (nt,) interval midpoints, row_start (nt+1,) int64, fin (ne,) int32, point [m] (ne, 3) B,
    force [N] (ne, 3) on the fin in B, width [m] (ne,); fin_names (nf,)."""

    fin_names: np.ndarray
    t: np.ndarray
    row_start: np.ndarray
    fin: np.ndarray
    point: np.ndarray
    force: np.ndarray
    width: np.ndarray


@dataclass(frozen=True)
class CollisionResult:
    """What a collision run produced (data). history: {column name with unit: (nt,) array};
    loads: fin loads; snapshots: (times [s] (k,), positions [m] (k, n, 3)) of the whole net,
    missile apex [m] (k, 3) and attitude (k, 4); summary: the ``collide`` section;
    step: the time-step choice; free: (n,) bool crop mask."""

    history: dict
    loads: FinLoads
    snap_t: np.ndarray
    snap_x: np.ndarray
    snap_apex: np.ndarray
    snap_q: np.ndarray
    summary: dict
    step: StepChoice
    free: np.ndarray = field(repr=False)


ENERGY_GROWTH_LIMIT = 0.5
"""A run whose total energy (kinetic + elastic + dissipated) grows by more than this fraction of
the energy the missile has given the net, at ENERGY_GROWTH_SAMPLES consecutive output samples,
stops with a NumericalError (a blow-up, not physics)."""
ENERGY_GROWTH_SAMPLES = 3
"""Consecutive samples the growth must persist. While a stiff penalty contact is being resolved
the symplectic step's energy error oscillates (it is bounded, O(ω dt) of the contact energy), so
one sample caught mid-contact can show a large error that is gone once the contact ends (the
infrared case: +25 J against the 22 J given so far at the 40 µs sample, when the dome first hits
a patch of net; 1.6 % of the energy given at the end). An unstable step grows and persists."""


def rotation_vector(q: np.ndarray) -> np.ndarray:
    """Rotation vector θ n̂ [rad] (3,) of a unit quaternion (w, x, y, z)."""
    q = q if q[0] >= 0 else -q
    s = float(np.linalg.norm(q[1:]))
    if s == 0.0:
        return np.zeros(3)
    return 2.0 * math.atan2(s, q[0]) * q[1:] / s


def _conj(q):
    return np.array([q[0], -q[1], -q[2], -q[3]])


def simulate(net: HeldNet, missile: Missile, cfg: CollideConfig, gravity: float,
             log: logging.Logger, *, crop: bool | None = None, fin_segment_test: bool | None = None,
             n_snapshots: int | None = None) -> CollisionResult:
    """Run the impact of ``missile`` on the held ``net`` per ``cfg`` (gravity g [m/s²] used only
    if ``cfg.gravity``). Keyword overrides (tests): crop, fin_segment_test, n_snapshots.
    Raises NumericalError on tunnelling (unless allowed), a non-finite state or energy growth.
    A crop too small is not an error: ``crop_boundary_motion_m`` in the summary says how far the
    free nodes next to the held ones moved."""
    t_wall = time.perf_counter()
    crop = cfg.crop if crop is None else crop
    seg_test = cfg.fin_segment_test if fin_segment_test is None else fin_segment_test
    n_snapshots = cfg.snapshots if n_snapshots is None else n_snapshots
    model = net.model
    shapes = pack_shapes(missile)
    start = place_missile(missile, net.x, cfg)
    aim = np.array([cfg.aim_point[0], cfg.aim_point[1], 0.0])

    # -- crop ----------------------------------------------------------------------------------
    n = model.n_nodes
    if crop:
        reach = crop_reach(start.bbox[2], wave_speed(net.rope_modulus, net.rope_density), cfg.duration,
                           cfg.crop_wave_speed_factor, cfg.crop_margin)
        free = free_nodes(net.x, aim, start.direction, reach)
    else:
        reach = math.inf
        free = np.ones(n, dtype=bool)
    seg_idx = active_segments(model.springs, free)
    # the kernel sees only the active sub-net: free nodes and the held nodes their segments reach
    used = np.unique(model.springs[seg_idx].ravel())
    local = np.full(n, -1, dtype=np.int64)
    local[used] = np.arange(used.size)
    seg = np.ascontiguousarray(local[model.springs[seg_idx]])
    free_full = free
    free = np.ascontiguousarray(free_full[used])
    boundary = local[boundary_nodes(model.springs, free_full)]
    seg_rest = np.ascontiguousarray(net.rest_length[seg_idx])
    seg_k = np.ascontiguousarray(model.stiffness_ea[seg_idx] / model.rest_length[seg_idx])
    seg_c = np.ascontiguousarray(model.damping[seg_idx])
    seg_off = np.ascontiguousarray(model.slack_offset[seg_idx])
    log.info("collide: %d of %d nodes free (crop reach %.3g m), %d of %d segments active",
             int(free.sum()), n, reach, seg.shape[0], model.n_springs)
    if not free.any():
        raise NumericalError("collide: no free net node near the flight path (check collide.aim_point)")

    # -- time step and contact stiffness ---------------------------------------------------------
    mass = np.array(model.mass[used], dtype=np.float64)
    # the lightest node the missile's shapes can reach (its swept footprint): sets the penalty
    # stiffness and the contact step limit, independently of the crop
    reachable = free_nodes(net.x, aim, start.direction, float(start.bbox[2]))
    if not reachable.any():
        raise NumericalError("collide: no net node within the missile's footprint (check collide.aim_point)")
    m_min = float(model.mass[reachable].min())
    step = choose_step(cfg, seg_k, mass[seg[:, 0]], mass[seg[:, 1]], m_min, net.rope_radius, net.rope_modulus,
                       float(shapes.fin_half_thickness.min()))
    n_sub = max(1, math.ceil(cfg.output_interval / step.dt))
    dt = cfg.output_interval / n_sub
    n_out = max(1, round(cfg.duration / cfg.output_interval))
    log.info("collide: dt = %.4g s (%s; limits: springs %.3g s, contact %.3g s, no-pass-through %.3g s; "
             "safety %.2g), K_n = %.4g N/m^%.2g (%s), expected penetration %.3g m = %.3g rope radii, "
             "%d steps", dt, step.governed_by, step.dt_spring, step.dt_contact, step.dt_pass, cfg.dt_safety,
             step.k_n, cfg.contact_exponent, cfg.stiffness_rule.value, step.expected_penetration,
             step.expected_penetration / net.rope_radius, n_sub * n_out)

    # -- state and parameters --------------------------------------------------------------------
    x_full = np.array(net.x, dtype=np.float64)
    x = np.ascontiguousarray(x_full[used])
    v = np.zeros_like(x)
    mx, mv, mq = start.x_cg.copy(), start.v_cg.copy(), start.q.copy()
    inertia = np.asarray(missile.inertia, dtype=np.float64)
    inv_inertia = np.linalg.inv(inertia)
    mh = np.zeros(3)
    cg_b = np.asarray(missile.cg, dtype=np.float64)
    ndet = cfg.detection_points_per_segment
    n_slots = n + seg.shape[0] * ndet + seg.shape[0]
    det_touch = np.zeros(n_slots, dtype=np.bool_)
    det_chi = np.zeros(n_slots)
    det_fin = np.full(n_slots, -1, dtype=np.int64)
    det_imp = np.zeros((n_slots, 3))
    det_pt = np.zeros((n_slots, 3))
    det_w = np.zeros(n_slots)
    cap = 2 * n_slots
    ev_fin = np.zeros(cap, dtype=np.int64)
    ev_pt = np.zeros((cap, 3))
    ev_imp = np.zeros((cap, 3))
    ev_w = np.zeros(cap)
    g_vec = np.array([0.0, -gravity, 0.0]) if cfg.gravity else np.zeros(3)
    par = np.zeros(K.N_PAR)
    par[K.P_KN] = step.k_n
    par[K.P_EXP] = cfg.contact_exponent
    par[K.P_E] = cfg.restitution
    par[K.P_MU] = cfg.friction_coefficient
    par[K.P_VREG] = cfg.friction_regularisation_speed
    par[K.P_RROPE] = net.rope_radius
    par[K.P_TUNNEL] = cfg.tunnelling_fraction
    par[K.P_GX:K.P_GZ + 1] = g_vec
    par[K.P_MMASS] = missile.mass
    par[K.P_VKMIN] = cfg.damping_min_impact_speed
    ipar = np.zeros(K.N_IPAR, dtype=np.int64)
    ipar[K.I_DAMP] = DAMPING_CODE[cfg.damping_model]
    ipar[K.I_NDET] = ndet
    ipar[K.I_SEGTEST] = int(seg_test)
    ipar[K.I_ALLOW] = int(cfg.allow_tunnelling)
    fin_limit = cfg.tunnelling_fraction * shapes.fin_half_thickness
    acc = np.zeros(K.N_ACC)
    planes = fin_planes(shapes)
    node_radius = np.ascontiguousarray(net.node_radius[used], dtype=np.float64)
    shape_t = tuple(shapes)

    # -- energy and momentum references ----------------------------------------------------------
    def energies():
        ke_n, pe_n = K.net_energy(x, v, mass, free, seg, seg_rest, seg_k, seg_off)
        w_b = inv_inertia @ (quat_to_matrix(mq).T @ mh)
        ke_m = 0.5 * missile.mass * float(mv @ mv) + 0.5 * float(w_b @ inertia @ w_b)
        pe_c = K.contact_energy(x, free, node_radius, seg, ndet, mx, mq, cg_b, start.bbox, planes, par, shape_t)
        return ke_m, ke_n, pe_n, pe_c

    ke_m0, ke_n0, pe_n0, pe_c0 = energies()
    e0 = ke_m0 + ke_n0 + pe_n0 + pe_c0
    p0 = missile.mass * mv + (mass[free, None] * v[free]).sum(axis=0)
    v0 = mv.copy()
    q0 = mq.copy()
    x_start = x.copy()

    # -- outputs -----------------------------------------------------------------------------------
    cols = {k: np.zeros(n_out + 1) for k in (
        "t_s", "accel_body_x_mps2", "accel_body_y_mps2", "accel_body_z_mps2", "accel_mag_mps2",
        "omega_body_x_rps", "omega_body_y_rps", "omega_body_z_rps",
        "alpha_body_x_rps2", "alpha_body_y_rps2", "alpha_body_z_rps2",
        "vel_x_mps", "vel_y_mps", "vel_z_mps", "speed_change_rel", "dv_rel",
        "pitch_change_rad", "yaw_change_rad", "roll_change_rad", "attitude_change_rad",
        "apex_along_path_m", "contact_force_mean_n", "contacts", "max_penetration_m",
        "net_kinetic_j", "net_elastic_j", "dissipated_j", "energy_error_j", "momentum_error_ns")}
    cols["vel_x_mps"][0], cols["vel_y_mps"][0], cols["vel_z_mps"][0] = mv
    cols["apex_along_path_m"][0] = float(start.apex @ start.direction)
    snap_at = set(np.unique(np.round(np.linspace(0, n_out, n_snapshots)).astype(int)).tolist())
    snap_t, snap_x, snap_apex, snap_q = [0.0], [x_full.copy()], [start.apex.copy()], [mq.copy()]
    ev_rows: list[tuple] = []
    row_start = [0]
    status = K.OK
    w_prev = inv_inertia @ (quat_to_matrix(mq).T @ mh)
    max_mom_err = 0.0
    max_energy_err = 0.0
    max_de_missile = 0.0
    growth_run = 0
    with progress_bar(n_out, "collide") as bar:
        for k in range(1, n_out + 1):
            status, mq_new, nev = K.advance(n_sub, dt, x, v, mass, free, node_radius, seg, seg_rest, seg_k, seg_c,
                                            seg_off, det_touch, det_chi, det_fin, det_imp, det_pt, det_w, mx, mv,
                                            mq, mh, inv_inertia, cg_b, start.bbox, planes, fin_limit, par, ipar,
                                            shape_t, acc, ev_fin, ev_pt,
                                            ev_imp, ev_w)
            mq[:] = mq_new
            t = k * cfg.output_interval
            if status == K.TUNNEL:
                raise NumericalError(
                    f"collide: tunnelling at t = {t:.4g} s: a rope centre line entered the missile deeper than "
                    f"{cfg.tunnelling_fraction} × (rope radius {net.rope_radius:.3g} m for the body, fin "
                    f"half-thickness for a fin) (depth/limit {acc[K.A_MAXRATIO]:.3g} on "
                    f"{part_names(missile)[int(acc[K.A_RATIO_PART])]}"
                    f"{' by the segment test' if acc[K.A_RATIO_SEG] else ''} at B "
                    f"({acc[K.A_RATIO_AT]:.3f}, {acc[K.A_RATIO_AT + 1]:.3f}, {acc[K.A_RATIO_AT + 2]:.3f}) m; "
                    f"largest penetration "
                    f"{acc[K.A_MAXPEN]:.3g} m; K_n = {step.k_n:.3g} from rule "
                    f"'{cfg.stiffness_rule.value}', dt = {dt:.3g} s, segment test "
                    f"{'on' if seg_test else 'off'}); use a stiffer contact rule, a smaller step, or "
                    f"collide.allow_tunnelling = true to finish and flag it")
            if status == K.NONFINITE:
                raise NumericalError(f"collide: non-finite state at t = {t:.4g} s with dt = {dt:.3g} s "
                                     f"(limits: springs {step.dt_spring:.3g} s, contact {step.dt_contact:.3g} s)")
            if status == K.EVENT_OVERFLOW:
                raise NumericalError("collide: fin event buffer overflow (a contact switched fins more than "
                                     "once in one output interval; lower collide.output_interval)")
            r = quat_to_matrix(mq)
            w_b = inv_inertia @ (r.T @ mh)
            a_b = acc[K.A_FB:K.A_FB + 3] / (missile.mass * cfg.output_interval)
            rot = rotation_vector(quat_mul(mq, _conj(q0)))  # world-axis rotation since t = 0
            cols["t_s"][k] = t
            cols["accel_body_x_mps2"][k], cols["accel_body_y_mps2"][k], cols["accel_body_z_mps2"][k] = a_b
            cols["accel_mag_mps2"][k] = float(np.linalg.norm(a_b))
            cols["omega_body_x_rps"][k], cols["omega_body_y_rps"][k], cols["omega_body_z_rps"][k] = w_b
            al = (w_b - w_prev) / cfg.output_interval
            cols["alpha_body_x_rps2"][k], cols["alpha_body_y_rps2"][k], cols["alpha_body_z_rps2"][k] = al
            w_prev = w_b
            cols["vel_x_mps"][k], cols["vel_y_mps"][k], cols["vel_z_mps"][k] = mv
            cols["speed_change_rel"][k] = (np.linalg.norm(mv) - np.linalg.norm(v0)) / np.linalg.norm(v0)
            cols["dv_rel"][k] = np.linalg.norm(mv - v0) / np.linalg.norm(v0)
            cols["pitch_change_rad"][k], cols["yaw_change_rad"][k], cols["roll_change_rad"][k] = rot
            cols["attitude_change_rad"][k] = float(np.linalg.norm(rot))
            apex = mx + r @ (-cg_b)
            cols["apex_along_path_m"][k] = float(apex @ start.direction)
            cols["contact_force_mean_n"][k] = acc[K.A_FCONTACT] / cfg.output_interval
            cols["contacts"][k] = acc[K.A_NCONTACT]
            cols["max_penetration_m"][k] = acc[K.A_PEN_INT]
            ke_m, ke_n, pe_n, pe_c = energies()
            diss = acc[K.A_DISS_ROPE] + acc[K.A_DISS_CONTACT] + acc[K.A_DISS_FRICTION]
            e_err = ke_m + ke_n + pe_n + pe_c + diss - acc[K.A_WORK_GRAVITY] - e0
            cols["net_kinetic_j"][k], cols["net_elastic_j"][k], cols["dissipated_j"][k] = ke_n, pe_n, diss
            cols["energy_error_j"][k] = e_err
            p = missile.mass * mv + (mass[free, None] * v[free]).sum(axis=0) + acc[K.A_PHELD:K.A_PHELD + 3]
            p_err = p - p0 - t * (missile.mass + mass.sum()) * g_vec  # mass: the sub-net's nodes
            cols["momentum_error_ns"][k] = float(np.linalg.norm(p_err))
            max_mom_err = max(max_mom_err, float(np.linalg.norm(p_err)))
            max_energy_err = max(max_energy_err, abs(e_err))
            max_de_missile = max(max_de_missile, ke_m0 - ke_m)
            growth_run = growth_run + 1 if e_err > ENERGY_GROWTH_LIMIT * max(max_de_missile, 1e-6 * ke_m0) else 0
            if growth_run >= ENERGY_GROWTH_SAMPLES:
                raise NumericalError(
                    f"collide: energy grew by {e_err:.3g} J by t = {t:.4g} s, more than {ENERGY_GROWTH_LIMIT:.0%} of "
                    f"the energy given at {ENERGY_GROWTH_SAMPLES} samples in a row; at the last, "
                    f"the {max_de_missile:.3g} J the missile has given the net: an unstable contact or step "
                    f"(dt = {dt:.3g} s, contact limit {step.dt_contact:.3g} s, K_n = {step.k_n:.3g})")
            row_start.append(row_start[-1] + nev)
            if nev:
                ev_rows.append((ev_fin[:nev].copy(), ev_pt[:nev].copy(), ev_imp[:nev].copy()))
            if k in snap_at:
                snap_t.append(t)
                x_full[used] = x
                snap_x.append(x_full.copy())
                snap_apex.append(apex.copy())
                snap_q.append(mq.copy())
            bar.update(1)

    # -- summary -------------------------------------------------------------------------------------
    a_mag = cols["accel_mag_mps2"]
    contact_rows = np.flatnonzero(cols["contacts"] > 0)
    duration = float(cols["t_s"][contact_rows[-1]] - cols["t_s"][contact_rows[0]] + cfg.output_interval) \
        if contact_rows.size else 0.0
    tail_along = cols["apex_along_path_m"][-1] - missile.length
    net_along = (x[free] @ start.direction).max() if free.any() else -math.inf
    passed = bool(cols["contacts"][-1] == 0 and net_along < tail_along)
    dp_total = missile.mass * float(np.max(cols["dv_rel"])) * float(np.linalg.norm(v0))
    k_peak = int(np.argmax(a_mag))
    crop_move = boundary_motion(x_start, x, boundary)
    summary = {
        "peak_accel_mps2": float(a_mag.max()),
        "peak_accel_time_s": float(cols["t_s"][k_peak]),
        "peak_accel_axis_mps2": [float(np.max(np.abs(cols[f"accel_body_{c}_mps2"]))) for c in "xyz"],
        "duration_s": duration,
        "dv_over_v": float(np.max(cols["dv_rel"])),
        "speed_change_rel": float(cols["speed_change_rel"][-1]),
        "max_attitude_change_rad": float(np.max(cols["attitude_change_rad"])),
        "passed_through": passed,
        "momentum_error_rel": max_mom_err / dp_total if dp_total > 0 else 0.0,
        "energy_error_rel": max_energy_err / max_de_missile if max_de_missile > 0 else 0.0,
        "max_penetration_m": float(acc[K.A_MAXPEN]),
        "max_penetration_ratio": float(acc[K.A_MAXRATIO]),
        "tunnelling": bool(acc[K.A_MAXRATIO] > 1.0),
        "segment_crossings_unresolved": int(acc[K.A_SEGCROSS]),
        "steps": int(n_sub * n_out),
        "dt_s": dt,
        "dt_governed_by": step.governed_by,
        "contact_stiffness": step.k_n,
        "stiffness_rule": cfg.stiffness_rule.value,
        "free_nodes": int(free.sum()),
        "active_segments": int(seg.shape[0]),
        "crop_reach_m": reach if math.isfinite(reach) else None,
        "crop_boundary_motion_m": crop_move,
        "fin_impulse_ns": {},
        "wall_s": time.perf_counter() - t_wall,
    }
    if summary["tunnelling"]:
        log.warning("collide: TUNNELLING flagged (allowed by the case): max penetration %.3g m, ratio %.3g",
                    summary["max_penetration_m"], summary["max_penetration_ratio"])
    loads = _fin_loads(missile, cfg, n_out, row_start, ev_rows, 2.0 * net.rope_radius)
    for i, name in enumerate(loads.fin_names):
        sel = loads.fin == i
        summary["fin_impulse_ns"][str(name)] = float(np.linalg.norm(loads.force[sel].sum(axis=0)) * cfg.output_interval)
    return CollisionResult(history=cols, loads=loads, snap_t=np.array(snap_t), snap_x=np.array(snap_x),
                           snap_apex=np.array(snap_apex), snap_q=np.array(snap_q), summary=summary, step=step,
                           free=free_full)


def _fin_loads(missile, cfg, n_out, row_start, ev_rows, width) -> FinLoads:
    """Assemble the per-interval fin impulses into :class:`FinLoads` (mean forces). The contact
    width of a rope on a fin is taken as the rope diameter ``width`` [m]."""
    if ev_rows:
        fin = np.concatenate([r[0] for r in ev_rows]).astype(np.int32)
        point = np.concatenate([r[1] for r in ev_rows])
        force = np.concatenate([r[2] for r in ev_rows]) / cfg.output_interval
    else:
        fin, point, force = np.zeros(0, np.int32), np.zeros((0, 3)), np.zeros((0, 3))
    t_mid = (np.arange(n_out) + 0.5) * cfg.output_interval
    return FinLoads(fin_names=np.array([f.name for f in missile.fins]), t=t_mid,
                    row_start=np.asarray(row_start, dtype=np.int64), fin=fin, point=point, force=force,
                    width=np.full(fin.shape[0], width))
