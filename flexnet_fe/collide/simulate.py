"""Drive the compiled collision kernel over the output intervals and collect the results.

:func:`simulate` is the physics of the collide stage without any file output (tests and
benchmarks call it directly); ``stage.run_collide`` writes its result into the run directory.

Sampling: every ``output_interval`` Δ the history gets one row at the interval's end t_k. The
accelerations in it are means over the interval, (v(t_k) − v(t_k − Δ))/Δ in body axes (the
signal the CFC filter of the summary works on); velocities, attitudes and energies are the
values at t_k. The fin loads are mean forces over each ``load_interval`` (a whole fraction of the
output interval; unset: the output interval), attributed to its midpoint (the impulse of every
contact is kept exactly): the kernel is called once per load interval and the history's per-interval
sums and maxima are gathered over the calls of an output interval (``_Interval``). The calls keep
the kernel's scratch (``kernel.advance_kept``) and the far net's windows run on across them, ending
at the output times (where the whole net's state is read): a finer load interval costs its extra
calls only (≈ 60 µs each on radar × traction), not shorter windows.

Energy (history columns ending in ``_j``): missile kinetic (translation + rotation), net
kinetic, rope elastic, contact stored (Σ K δ^(m+1)/(m+1)), dissipated by rope damping, by
contact damping, by friction, by the air (``dissipated_air_j``, 0 unless ``collide.air``),
released by broken ropes, taken out by cutting rope pieces during the run (``rope_refinement_j``,
``collide.adapt``), work of gravity and at the crop boundary (zero: held nodes do not
move), and ``energy_balance_j`` = (sum of the stored and dissipated terms − external work) − its
initial value. Momentum: missile, free net, the impulse taken by the held nodes and the air's
impulse on the net (``air_impulse_*_ns``; W, [N s]); missile + net + held − air − gravity
impulse is constant (``momentum_error_ns`` is its drift).
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from flexnet_fe.collide import kernel as K
from flexnet_fe.collide.air import drag_step_ratio
from flexnet_fe.collide import model as M
from flexnet_fe.collide.config import CollideConfig, ContactLaw
from flexnet_fe.collide.crop import (active_segments, boundary_motion, boundary_nodes, crop_reach, free_nodes,
                                     wave_speed)
from flexnet_fe.collide.adapt import Lineage, cut_counts, cut_live, lineage_cut, lineage_start, merge_roots
from flexnet_fe.collide.refine import refine_near_fins, split_near_path
from flexnet_fe.collide.metrics import (ALTERNATION_RUN_LIMIT, FinContacts, MissileHistory, collision_metrics,
                                       load_alternation_runs)
from flexnet_fe.collide.scene import HeldNet, MissileStart, fin_planes, place_missile
from flexnet_fe.collide.timestep import (StepChoice, choose_step, contact_stiffness,
                                        line_density_min, line_stiffnesses, spring_limit)
from flexnet_fe.contact.law import DAMPING_CODE, DampingModel, hysteresis_factor
from flexnet_fe.contact.restitution import restitution_check
from flexnet_fe.errors import FlexnetError, NumericalError
from flexnet_fe.missile.geometry import Missile
from flexnet_fe.missile.shapes import nose_cones, pack_shapes, part_names
from flexnet_fe.net.topology import rope_area
from flexnet_fe.progress import progress_bar
from flexnet_fe.frames import quat_exp_step, quat_mul, quat_to_matrix


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
    loads: fin loads; snapshots: (times [s] (k,), positions [m] and velocities [m/s] (k, n, 3)) of
    the whole net (nodes outside the crop keep their held x and v = 0), missile apex [m] (k, 3)
    and attitude (k, 4); summary: the ``collide`` section; step: the time-step choice; free: (n,) bool crop mask; alive: (m,) bool intact segments;
    net: the held net the run used (split per ``rope_split``; n, m count its nodes and segments)."""

    history: dict
    loads: FinLoads
    snap_t: np.ndarray
    snap_x: np.ndarray
    snap_v: np.ndarray
    snap_apex: np.ndarray
    snap_q: np.ndarray
    summary: dict
    step: StepChoice
    free: np.ndarray = field(repr=False)
    alive: np.ndarray = field(repr=False, default=None)
    net: HeldNet | None = field(repr=False, default=None)


ENERGY_TOLERANCE = 0.005
"""max |energy_balance_j| above this fraction of the energy exchanged (missile kinetic energy
lost) is a warning in the summary."""
ENERGY_GROWTH_LIMIT = 0.5
"""A run whose energy balance grows by more than this fraction of the energy exchanged at
ENERGY_GROWTH_SAMPLES consecutive samples stops with a NumericalError (a blow-up, not physics)."""
ENERGY_GROWTH_SAMPLES = 3

ENERGY_COLUMNS = ("missile_kinetic_j", "net_kinetic_j", "rope_elastic_j", "contact_stored_j", "rope_damping_j",
                  "contact_damping_j", "friction_j", "dissipated_air_j", "broken_release_j", "rope_refinement_j",
                  "gravity_work_j",
                  "crop_boundary_work_j", "fin_motion_work_j", "step_term_j", "energy_balance_j")
HISTORY_COLUMNS = (
    "t_s", "accel_body_x_mps2", "accel_body_y_mps2", "accel_body_z_mps2", "accel_mag_mps2",
    "omega_body_x_rps", "omega_body_y_rps", "omega_body_z_rps", "alpha_body_x_rps2", "alpha_body_y_rps2",
    "alpha_body_z_rps2", "vel_x_mps", "vel_y_mps", "vel_z_mps", "speed_change_rel", "dv_rel",
    "pitch_change_rad", "yaw_change_rad", "roll_change_rad", "attitude_change_rad", "apex_along_path_m",
    "contact_force_mean_n", "contacts", "max_penetration_m", "broken_segments",
    "missile_momentum_x_ns", "missile_momentum_y_ns", "missile_momentum_z_ns",
    "net_momentum_x_ns", "net_momentum_y_ns", "net_momentum_z_ns",
    "held_impulse_x_ns", "held_impulse_y_ns", "held_impulse_z_ns",
    "air_impulse_x_ns", "air_impulse_y_ns", "air_impulse_z_ns", "momentum_error_ns") + ENERGY_COLUMNS


def rotation_vector(q: np.ndarray) -> np.ndarray:
    """Rotation vector θ n̂ [rad] (3,) of a unit quaternion (w, x, y, z)."""
    q = q if q[0] >= 0 else -q
    s = float(np.linalg.norm(q[1:]))
    if s == 0.0:
        return np.zeros(3)
    return 2.0 * math.atan2(s, q[0]) * q[1:] / s


def _conj(q):
    return np.array([q[0], -q[1], -q[2], -q[3]])


@dataclass(frozen=True)
class Setup:
    """A built collision (data): the kernel model, the sub-net map (used node ids (k,) into the
    full net, free_full (n,) crop mask, boundary node ids (local)), crop reach [m], step choice."""

    model: M.CollideModel
    start: MissileStart
    used: np.ndarray
    seg_idx: np.ndarray
    free_full: np.ndarray
    boundary: np.ndarray
    reach: float
    step: StepChoice
    m_reach: float = math.inf
    """[kg] the lightest node the missile can reach (the step's contact limit)"""


def build(net: HeldNet, missile: Missile, cfg: CollideConfig, gravity: float, log: logging.Logger,
          crop: bool, air_density: float = 0.0) -> Setup:
    """Crop the net, choose the contact stiffness and the time step, pack the kernel model
    (air_density ρ [kg/m³] is the model's when ``cfg.air``, else the model has no air)."""
    model, rope = net.model, net.rope
    shapes = pack_shapes(missile)
    start = place_missile(missile, net.x, cfg)
    aim = np.array([cfg.aim_point[0], cfg.aim_point[1], 0.0])
    reach = crop_reach(start.bbox[2], wave_speed(rope.youngs_modulus, rope.density), cfg.end_time,
                       cfg.crop_wave_speed_factor, cfg.crop_margin) if crop else math.inf
    free_full = free_nodes(net.x, aim, start.direction, reach) if crop else np.ones(model.n_nodes, dtype=bool)
    if not free_full.any():
        raise NumericalError("collide: no free net node near the flight path (check collide.aim_point)")
    seg_idx = active_segments(model.springs, free_full)
    used = np.unique(model.springs[seg_idx].ravel())
    local = np.full(model.n_nodes, -1, dtype=np.int64)
    local[used] = np.arange(used.size)
    seg = np.ascontiguousarray(local[model.springs[seg_idx]])
    k = np.ascontiguousarray(model.stiffness[seg_idx])
    reachable = free_nodes(net.x, aim, start.direction, float(start.bbox[2]))
    if not reachable.any():
        raise NumericalError("collide: no net node within the missile's footprint (check collide.aim_point)")
    half_min = float(shapes.fin_half_thickness.min()) if len(shapes.fin_half_thickness) else rope.radius
    k_body, k_fin = contact_stiffness(cfg, rope.radius, rope.transverse_modulus, rope.poisson_ratio, half_min,
                                      missile.radius)
    n_seg = int(np.bincount(seg.ravel()).max())
    m_reach = float(model.mass[reachable].min())
    line = cfg.contact_law is ContactLaw.line
    kl_body, kl_fin = line_stiffnesses(cfg, rope.radius, rope.transverse_modulus, rope.poisson_ratio,
                                       shapes.fin_half_thickness, missile.radius) if line else (0.0, np.zeros(0))
    h_line = rope.radius / cfg.line_points_per_radius  # the line law's point spacing [m]
    mass = np.array(model.mass[used], dtype=np.float64)
    line_dt = (max(kl_body, float(kl_fin.max(initial=0.0))),
               line_density_min(seg, net.rest_length[seg_idx], mass, free_full[used])) if line else None
    step = choose_step(cfg, k, mass[seg[:, 0]], mass[seg[:, 1]], m_reach, n_seg,
                       rope.radius, half_min, max(k_body, k_fin), line_dt)
    g_vec = np.array([0.0, -gravity, 0.0]) if cfg.gravity else np.zeros(3)
    km = M.CollideModel(
        seg=seg, rest=np.ascontiguousarray(net.rest_length[seg_idx]), k=k,
        c=np.ascontiguousarray(model.damping[seg_idx]), off=np.ascontiguousarray(model.slack_offset[seg_idx]),
        break_stretch=rope.breaking_load / k, mass=mass, free=np.ascontiguousarray(free_full[used]),
        rope_radius=rope.radius, m_mass=float(missile.mass),
        inv_inertia=np.linalg.inv(np.asarray(missile.inertia, dtype=np.float64)),
        cg_b=np.asarray(missile.cg, dtype=np.float64), bbox=start.bbox, prof_kind=shapes.prof_kind,
        prof_data=shapes.prof_data, prof_part=shapes.prof_part, fin_origin=shapes.fin_origin,
        fin_axes=shapes.fin_axes, fin_poly=shapes.fin_poly, fin_core=shapes.fin_core, fin_ncore=shapes.fin_ncore,
        fin_half=shapes.fin_half_thickness,
        fin_planes=fin_planes(shapes), k_body=k_body, k_fin=k_fin, exponent=cfg.contact_exponent,
        damp_c=hysteresis_factor(DAMPING_CODE[cfg.damping_model], cfg.restitution, 1.0),
        v_floor=cfg.damping_min_approach_speed, mu=cfg.friction_coefficient,
        v_reg=cfg.friction_regularisation_speed, allow_tunnel=bool(cfg.allow_tunnelling), gravity=g_vec,
        air_density=float(air_density) if cfg.air else 0.0,
        diameter=np.ascontiguousarray(model.diameter[seg_idx], dtype=np.float64),
        nose_cones=nose_cones(shapes.prof_kind, shapes.prof_data),
        line_law=line, kl_body=kl_body, kl_fin=kl_fin, line_h_body=h_line,
        line_h_fin=np.full(len(kl_fin), h_line))
    boundary = local[boundary_nodes(model.springs, free_full)]
    log.info("collide: %d of %d nodes free (crop reach %.3g m), %d of %d segments active; K_body = %.4g, "
             "K_fin = %.4g N/m^%.2g (%s, rope E_t = %.3g Pa)", int(free_full.sum()), model.n_nodes, reach,
             seg.shape[0], model.n_springs, k_body, k_fin, cfg.contact_exponent, cfg.stiffness_rule.value,
             rope.transverse_modulus)
    if line:
        log.info("collide: line contact law: k_l body %.4g, fins %s N/m^2 (the line integral of a rope crossing "
                 "each part = K delta^1.5 above), points %.3g mm apart along the rope", kl_body,
                 " ".join(f"{v:.4g}" for v in kl_fin), 1e3 * h_line)
    return Setup(km, start, used, seg_idx, free_full, boundary, reach, step, m_reach)


STEP_TERM_EPS = 1e-3
"""[-] shift of ``_step_term``'s central difference, as a fraction of dt (50 nm at 500 m/s and
dt = 1e-7 s: the rope and contact energies are C¹, so its error is far below the term itself)."""


def _step_term(km: M.CollideModel, st: M.CollideState, dt: float) -> float:
    """The O(dt) part of the energy the kernel's step conserves [J]. A kick then a drift
    (v += dt F(x)/m, x += dt v: symplectic Euler, ``kernel._integrate``) conserves
    Ẽ = T + U + ½ dt v·F(x) = T + U − ½ dt dU/dt to O(dt²) — exactly, for a harmonic oscillator
    (½ m v² + ½ k x² − ½ dt k x v) — while T + U swings by ½ dt dU/dt whenever a contact is storing
    or giving back energy: at the line law's soft contacts, 0.40 / 0.20 / 0.096 % of the energy
    exchanged on tests/collide/test_refine.py's scene at dt × 1 / ½ / ¼, first order in dt, though
    nothing is created (0.077 / 0.026 / 0.0034 % with this term). dU/dt [W]: central difference of ``kernel.energies``' rope elastic + contact stored
    energy along the current velocities of the free nodes and the missile (translation, rotation),
    shifted by ± STEP_TERM_EPS dt. The column ``step_term_j`` of history.csv; dt [s] the last step."""
    if dt <= 0.0:
        return 0.0
    tau = STEP_TERM_EPS * dt
    w_b = km.inv_inertia @ (quat_to_matrix(st.mq).T @ st.mh)
    u = []
    for sgn in (1.0, -1.0):
        moved = st._replace(x=st.x + (sgn * tau) * np.where(km.free[:, None], st.v, 0.0),
                            mx=st.mx + (sgn * tau) * st.mv, mq=quat_exp_step(st.mq, w_b, sgn * tau))
        _, pe_n, pe_c = K.energies(km, moved)
        u.append(pe_n + pe_c)
    return -0.5 * dt * (u[0] - u[1]) / (2.0 * tau)


def _energy_terms(km: M.CollideModel, st: M.CollideState, missile: Missile, inertia: np.ndarray,
                  advanced: bool = True, dt: float = 0.0) -> dict:
    """The energy columns (without the balance) of the state [J]. ``advanced``: the state is the end
    of a successful ``kernel.advance`` call, whose contact stored energy is in acc[A_U_CONTACT] (the
    same value as ``kernel.energies`` computes, to the last bit); otherwise it is computed. dt [s]:
    the last step, for ``step_term_j`` (0: none, the state has not been stepped)."""
    if advanced:
        ke_n, pe_n = K.net_energies(km, st)
        pe_c = float(st.acc[M.A_U_CONTACT])
    else:
        ke_n, pe_n, pe_c = K.energies(km, st)
    w_b = km.inv_inertia @ (quat_to_matrix(st.mq).T @ st.mh)
    acc = st.acc
    return {"missile_kinetic_j": 0.5 * missile.mass * float(st.mv @ st.mv) + 0.5 * float(w_b @ inertia @ w_b),
            "net_kinetic_j": ke_n, "rope_elastic_j": pe_n, "contact_stored_j": pe_c,
            "rope_damping_j": acc[M.A_DISS_ROPE], "contact_damping_j": acc[M.A_DISS_CONTACT],
            "friction_j": acc[M.A_DISS_FRICTION], "dissipated_air_j": acc[M.A_DISS_AIR],
            "broken_release_j": acc[M.A_BROKEN], "rope_refinement_j": acc[M.A_REFINE],
            "gravity_work_j": acc[M.A_WORK_GRAVITY], "crop_boundary_work_j": 0.0,
            "fin_motion_work_j": acc[M.A_FIN_WORK],
            "step_term_j": _step_term(km, st, dt)}


def _balance(e: dict) -> float:
    """Stored + dissipated − external work [J] (gravity, the crop boundary, a prescribed fin motion)."""
    external = ("gravity_work_j", "crop_boundary_work_j", "fin_motion_work_j")
    return sum(v for k, v in e.items() if k not in external) - sum(e[k] for k in external)


def _take_fin_events(km: M.CollideModel, st: M.CollideState):
    """(fin (k,), point [m] (k, 3) B, impulse [N s] (k, 3) B, segment (k,), chord [m] (k,)) of the
    fin-load slots written in the last call (chord: the segment's impulse-weighted current length
    while it pressed); the slots are cleared."""
    nt = int(st.ntouched[0])
    fs = st.touched[:nt].copy()
    nf = km.fin_half.shape[0]
    out = (fs % nf, st.fin_pt[fs] / st.fin_w[fs, None], st.fin_imp[fs].copy(), fs // nf, st.fin_len[fs] / st.fin_w[fs])
    st.fin_imp[fs] = 0.0
    st.fin_pt[fs] = 0.0
    st.fin_w[fs] = 0.0
    st.fin_len[fs] = 0.0
    st.ntouched[0] = 0
    return out


def _stop_message(status, st, cfg, t, names, setup, dt) -> str:
    acc = st.acc
    if status == M.TUNNEL:
        return (f"collide: tunnelling at t ≈ {t:.4g} s: a rope centre line reached the core of "
                f"{names[int(acc[M.A_TUN_PART])]} at a relative speed of {acc[M.A_TUN_SPEED]:.4g} m/s (largest "
                f"penetration {acc[M.A_PEN]:.3g} m = {acc[M.A_PEN_RATIO]:.3g} × (rope radius + half-thickness)); "
                f"K_body = {setup.model.k_body:.3g}, K_fin = {setup.model.k_fin:.3g} from rule "
                f"'{cfg.stiffness_rule.value}', dt = {dt:.3g} s. The contact is too soft for this impact: raise "
                f"the rope's net.transverse_modulus, or set collide.allow_tunnelling = true to finish and flag it")
    if status == M.FAR:
        return (f"collide: at t ≈ {t:.4g} s a net node moved farther within one far-net window than its bound "
                f"(kernel.FAR_BOUND_FACTOR × the window × the largest speed relative to the missile at its start): "
                f"the split into near and far net is not proven for this motion; set collide.far_net_ratio = 1 "
                f"(every segment every step)")
    return (f"collide: non-finite state at t = {t:.4g} s with dt = {dt:.3g} s (limits: springs "
            f"{setup.step.dt_spring:.3g} s, contact {setup.step.dt_contact:.3g} s)")


def simulate(net: HeldNet, missile: Missile, cfg: CollideConfig, gravity: float,
             log: logging.Logger, *, air_density: float | None = None, crop: bool | None = None,
             n_snapshots: int | None = None, dt_scale: float = 1.0,
             fin_motion: M.FinMotion | None = None) -> CollisionResult:
    """Run the impact of ``missile`` on the held ``net`` per ``cfg`` (gravity g [m/s²] used only
    if ``cfg.gravity``; air_density ρ [kg/m³], the [atmosphere]'s, needed and used only if
    ``cfg.air``). The rope near the path is first split per ``cfg.rope_split``, then cut to
    ``cfg.fin_piece_length`` near the fins (``collide.refine``; the result's ``net`` is the split net),
    and with ``cfg.fin_piece_chord`` the rope is cut again during the run where it presses on a fin
    or is about to (``collide.adapt``; summary ``cut_segments``, ``cut_nodes``, ``rope_refinement_j``). Keyword overrides (tests,
    convergence studies): crop, n_snapshots, dt_scale (the chosen dt is multiplied by it); fin_motion: the fins'
    mid-surfaces move as prescribed (``model.FinMotion``: the one-way check, ``study.one_way``; its work on
    the rope is the history's ``fin_motion_work_j``).

    End rule: the run lasts at least ``cfg.duration``; from then on it stops at the first output
    time at which the interaction is over (:func:`interaction_over`: no contact in the last
    interval and the missile's tail ``cfg.end_clearance`` past every free net node), or at
    ``cfg.end_time`` (max_duration), whichever comes first. ``summary['stop_reason']`` says which;
    stopping at the cap while force still acts is a warning (Δv and impulses are then not final).

    Raises NumericalError on tunnelling (unless allowed), a non-finite state or a growing energy
    balance. A crop too small is not an error: ``crop_boundary_motion_m`` in the summary says how
    far the free nodes next to the held ones moved."""
    t_wall = time.perf_counter()
    if cfg.air and air_density is None:
        raise FlexnetError("collide: collide.air = true needs the air density of the [atmosphere] (simulate's "
                           "air_density)")
    net = refine_near_fins(split_near_path(net, missile, cfg), missile, cfg)
    setup = build(net, missile, cfg, gravity, log, cfg.crop if crop is None else crop, air_density or 0.0)
    if fin_motion is not None:
        setup = replace(setup, model=M.with_fin_motion(setup.model, fin_motion))
    km, start, step = setup.model, setup.start, setup.step
    n_sub, dt = _sub_steps(cfg, step.dt * dt_scale)
    ratio = min(far_ratio(cfg, step.dt_spring, dt, step.dt_contact if setup.model.line_law else math.inf),
                n_sub * cfg.loads_per_output)  # (windows end at outputs)
    n_min = max(1, round(cfg.duration / cfg.output_interval))
    n_max = max(n_min, round(cfg.end_time / cfg.output_interval))
    log.info("collide: dt = %.4g s (%s; limits: springs %.3g s, contact %.3g s, travel per step %.3g s; "
             "safety %.2g), expected penetration %.3g m = %.3g rope radii, %d–%d steps", dt, step.governed_by,
             step.dt_spring, step.dt_contact, step.dt_travel, cfg.dt_safety, step.expected_penetration,
             step.expected_penetration / net.rope.radius, n_sub * cfg.loads_per_output * n_min,
             n_sub * cfg.loads_per_output * n_max)
    st = M.new_state(net.x[setup.used], km.seg.shape[0], km.fin_half.shape[0], start.x_cg, start.v_cg, start.q)
    air_ratio = _air_step_check(km, st, cfg, dt * ratio)
    setup = replace(setup, model=km._replace(air_every=air_windows(air_ratio) if ratio > 1 else 1))
    km = setup.model
    log.info("collide: far net stepped once per %d steps (%.3g s; rope springs' limit %.3g s)%s", ratio, dt * ratio,
             step.dt_spring, f", air once per {km.air_every} windows" if km.air_density > 0.0 and ratio > 1 else "")
    rec = _Recorder(km, st, missile, np.asarray(missile.inertia, dtype=np.float64), cfg, start, n_max)
    snap_at = set(np.unique(np.round(np.linspace(0, n_min, cfg.snapshots if n_snapshots is None
                                                  else n_snapshots)).astype(int)).tolist())
    x_start = st.x.copy()
    run = _drive(_Drive(setup, st, rec, cfg, net, missile, dt, n_sub, ratio, dt_scale), n_min, n_max, snap_at, log)
    rec.truncate(run.n_done)
    loads = _fin_loads(missile, cfg, run.n_done, run.row_start, run.ev_rows, net.rope.diameter)
    steps = run.steps
    summary = rec.summary(setup, loads, x_start, min(dt, run.dt_min), steps, time.perf_counter() - t_wall)
    _end_summary(summary, run, rec, cfg, net)
    km, st = rec.km, rec.st  # the model and state at the end (cuts append nodes and segments)
    summary.update(_air_summary(km, st, cfg, air_ratio))
    summary.update(far_net_ratio=ratio, far_net_dt_s=dt * ratio, near_net_segment_share=(
        1.0 if ratio == 1 else float(st.acc[M.A_FAST_SEG_STEPS]) / max(steps * km.seg.shape[0], 1)))
    summary.update(fin_piece_chord_m=cfg.fin_piece_chord, cut_segments=run.cut_segments, cut_nodes=run.cut_nodes,
                   merged_segments=run.merged_segments, merged_nodes=run.merged_nodes,
                   rope_refinement_j=float(st.acc[M.A_REFINE]))
    alive = np.ones(net.model.n_springs, dtype=bool)
    alive[setup.seg_idx] = st.alive[:setup.seg_idx.size]  # (a cut segment: its first piece)
    snaps = run.snaps
    return CollisionResult(history=rec.cols, loads=loads, snap_t=np.array(snaps[0]), snap_x=np.array(snaps[1]),
                           snap_v=np.array(snaps[4]), snap_apex=np.array(snaps[2]), snap_q=np.array(snaps[3]),
                           summary=summary, step=step, free=setup.free_full, alive=alive, net=net)


FAR_RATIO_CAP = 16
"""Largest automatic far-net window [steps] (``far_ratio``). The far springs' O(window) error shows
in the energy balance: radar_traction 0.009 / 0.039 / 0.23 / 1.34 % of the energy exchanged at
windows of 1 / 16 / 32 / 64 steps, for 166.6 / 42.6 / 34.8 / 32.0 s (docs/performance.md, "Collide:
the far net in windows"): beyond 16 the error grows ~6× per doubling for < 20 % less time."""

FAR_PHASE = 0.125
"""[rad] Largest phase ω_max × window of the stiffest rope segment's axial mode in an automatic
far-net window (``far_ratio``). The impulse method's error grows with it, not with the window's
length in steps: radar_traction's energy balance error (largest |balance| / energy exchanged) was
4.1e-5 / 8.6e-5 / 3.9e-4 / 9.7e-4 / 2.6e-3 at phases 0.054 / 0.077 / 0.109 / 0.154 / 0.218 (rope pieces
0.175 … 0.7 mm at the fins, windows 4 … 16; docs/collide_convergence.md, "Rounded tip corners and
the far net's phase"). A fixed window of 16 steps let it grow ~2.6× per halving of the pieces (the
pieces' ω ∝ 1/l, the contact step ∝ √l); at this phase it was 3.9e-4 / 3.3e-4 / 4.3e-4 at 0.7 / 0.35 /
0.175 mm (windows 16 / 12 / 9)."""


FAR_CONTACT_PHASE = 1.0
"""[rad] Largest phase ω_c × window of the line law's contact mode (ω_c = 2 / its undamped limit) in an
automatic far-net window: the slow rope's impulse, once per window, kicks the struck nodes, and the
impulse method resonates when the window nears half their contact period (ω_c × window = π).
Measured on tests/collide/test_adapt.py's fin-edge scene (pieces of 0.09 mm): windows of 16 steps of
0.4 µs (ω_c × window ≈ 16) grew the energy balance by 42 J of 73 J exchanged and stopped the run;
single rate closed it to 0.11 %. The segment law's contact is stiffer and intermittent (it was never
seen to resonate) and keeps the rope springs' rule alone."""


def far_ratio(cfg: CollideConfig, dt_spring: float, dt: float, dt_contact: float = math.inf) -> int:
    """Steps per far-net window [-]: ``cfg.far_net_ratio`` when set, else the largest whole number
    of steps dt [s] in which the stiffest rope segment's axial mode (ω_max = 2 / dt_spring, dt_spring
    [s] its stability limit, ``timestep.spring_limit``) turns by at most FAR_PHASE and the line law's
    contact mode (dt_contact [s] its limit; inf: none) by at most FAR_CONTACT_PHASE, at most
    FAR_RATIO_CAP."""
    if cfg.far_net_ratio:
        return int(cfg.far_net_ratio)
    steps = min(FAR_RATIO_CAP, FAR_PHASE * dt_spring / (2.0 * dt), FAR_CONTACT_PHASE * dt_contact / (2.0 * dt))
    return int(max(1, math.floor(steps)))  # (dt_spring, dt_contact may be inf)


AIR_WINDOWS_CAP = 16
"""Most far-net windows one air impulse covers (``air_windows``)."""

AIR_RATE_WINDOW = 0.01
"""[-] Largest λ × (the time one air impulse covers), λ the air drag's rate (∂F/∂v)/m at the
node it acts on most, bounded as in ``_air_step_check``: the drag alone changes a node's velocity
by at most ~1 % between two impulses (explicit drag is then stable and monotone). The contacts
change a struck node's velocity faster; its air then lags by one impulse (≤ AIR_WINDOWS_CAP
windows, ≈ 10 µs at the paper cases' 0.7 mm) of the ~10 ms over which the air acts. At 0.7 mm the
window's λ × window is ≈ 3e-4, so the cap binds. Measured against one impulse per window:
tests/collide/test_air.py, docs/performance.md ("air once per 16 windows")."""


def air_windows(window_ratio: float) -> int:
    """Far-net windows per air impulse [-] (``CollideModel.air_every``): the most whose λ ×
    time stays ≤ AIR_RATE_WINDOW, window_ratio = λ × one window (``_air_step_check``), at most
    AIR_WINDOWS_CAP; 1 without air (window_ratio 0)."""
    if window_ratio <= 0.0:
        return 1
    return int(max(1, min(AIR_WINDOWS_CAP, math.floor(AIR_RATE_WINDOW / window_ratio))))


AIR_SPEED_FACTOR = 2.0
"""The air's explicit-step check assumes rope speeds up to this × the impact speed and segment
lengths up to this × their held lengths (a rope dragged by the missile moves at about its speed)."""


def _air_step_check(km: M.CollideModel, st: M.CollideState, cfg: CollideConfig, dt: float) -> float:
    """The air drag's explicit-step ratio (``air.drag_step_ratio``) at AIR_SPEED_FACTOR × the
    impact speed and the held lengths × AIR_SPEED_FACTOR; 0 without air. Raises NumericalError
    when ≥ 1 (the drag alone could make the step unstable)."""
    if km.air_density == 0.0:
        return 0.0
    length = np.linalg.norm(st.x[km.seg[:, 1]] - st.x[km.seg[:, 0]], axis=1) * AIR_SPEED_FACTOR
    ratio = drag_step_ratio(km.mass, km.seg, length, km.diameter, km.air_density,
                            AIR_SPEED_FACTOR * cfg.impact_speed, dt)
    if ratio >= 1.0:
        raise NumericalError(f"collide: with collide.air the rope drag needs dt < {dt / ratio:.3g} s (the step is "
                             f"{dt:.3g} s): the lightest rope nodes are too light for explicit drag")
    return ratio


def _air_summary(km: M.CollideModel, st: M.CollideState, cfg: CollideConfig, ratio: float) -> dict:
    """The air's summary keys: on/off, density [kg/m³], work [J], impulse on the net [N s] (3,) W,
    explicit-step ratio [-]."""
    return {"air": bool(cfg.air), "air_density_kgpm3": float(km.air_density),
            "dissipated_air_j": float(st.acc[M.A_DISS_AIR]),
            "air_impulse_ns": [float(x) for x in st.acc[M.A_IMP_AIR:M.A_IMP_AIR + 3]], "air_drag_step_ratio": ratio,
            "air_every_windows": int(km.air_every)}


def edge_piece_limit(rope_radius: float, fin_half: np.ndarray) -> float | None:
    """min over the fins of (r + h/2)/3 [m] (rope radius r, fin half-thickness h/2 (nf,)): the
    longest chord a rope piece may press on a fin with — a measured rule, not a law. Radar ×
    traction converges (Δv within 0.25 % of its finest run, every fin within 1.8 %) when its pieces
    press at chords ≤ 1.24 mm (1.42 mm on its rudders), and reads 2.4 % low at 2.45 mm (docs/
    collide_convergence.md, thirteenth pass); a single rope across a swept edge
    (benchmarks/collide_edge_lab.py) is within 2 % already at ~7 mm chords. None without fins."""
    return float((rope_radius + np.min(fin_half)) / 3.0) if len(fin_half) else None


def edge_resolution(piece_max: float, rope_radius: float, fin_half: np.ndarray, imp_long: float = 0.0,
                    imp_all: float = 0.0) -> dict:
    """Summary keys of the rope's resolution at the fin edges: ``fin_contact_piece_max_m`` the
    longest rope piece [m] that pressed on a fin, as long as it was then (its chord, stretched by
    the rope's tension: the paper's 1 MPa rope stretches its pieces up to ~10× at the fins, docs/
    collide_convergence.md, thirteenth pass), ``edge_piece_limit_m`` (:func:`edge_piece_limit`),
    and ``fin_impulse_share_long_pieces`` = imp_long / imp_all, the share of the fins' Σ |impulse|
    [N s] that pieces longer than the limit delivered (0 when no fin was loaded)."""
    return {"fin_contact_piece_max_m": float(piece_max), "edge_piece_limit_m": edge_piece_limit(rope_radius, fin_half),
            "fin_impulse_share_long_pieces": float(imp_long / imp_all) if imp_all > 0.0 else 0.0}


def interaction_over(contacts_last: float, tail_along: float, net_front_along: float, clearance: float) -> bool:
    """The end rule of a collision: no (segment, part) contact in the last output interval and the
    missile's tail (along the flight path [m]) at least ``clearance`` [m] beyond the foremost free
    net node (``net_front_along`` [m])."""
    return contacts_last == 0 and tail_along - net_front_along >= clearance


@dataclass(frozen=True)
class _Drive:
    """What the output loop needs (data)."""

    setup: Setup
    st: M.CollideState
    rec: "_Recorder"
    cfg: CollideConfig
    net: HeldNet
    missile: Missile
    dt: float
    n_sub: int
    ratio: int
    dt_scale: float = 1.0


@dataclass
class _Run:
    """What the output loop produced: intervals done, why it stopped, fin-load rows, snapshots."""

    n_done: int
    stop_reason: str
    row_start: list
    ev_rows: list
    snaps: tuple
    fin_piece_max: float = 0.0
    """current (stretched) length [m] of the longest rope piece that pressed on a fin (per output
    interval, the impulse-weighted mean of its chord while it pressed)"""
    fin_imp_long: float = 0.0
    """Σ |impulse| [N s] on the fins from pieces longer than the edge limit"""
    fin_imp_all: float = 0.0
    """Σ |impulse| [N s] on the fins"""
    steps: int = 0
    """steps taken"""
    dt_min: float = math.inf
    """smallest step [s] (the step is chosen again after each cut, collide.adapt)"""
    cut_segments: int = 0
    """segments cut during the run (collide.adapt)"""
    cut_nodes: int = 0
    """nodes added by those cuts"""
    merged_segments: int = 0
    """start segments whose pieces were merged back during the run (``_merge_idle``)"""
    merged_nodes: int = 0
    """nodes those merges removed"""
    lineage: Lineage | None = None
    """where each segment of the running model comes from (``collide.adapt.Lineage``)"""


class _Interval:
    """The kernel's per-call accumulators (``model.A_IMP_B``, ``A_FCONTACT``: sums; ``A_NCONTACT``,
    ``A_PEN_INT``: maxima) gathered over the calls of one output interval (one call per fin-load
    interval), and put back for the history row."""

    SUMS = [M.A_IMP_B, M.A_IMP_B + 1, M.A_IMP_B + 2, M.A_FCONTACT]
    MAXIMA = [M.A_NCONTACT, M.A_PEN_INT]

    def __init__(self):
        self.sums = np.zeros(len(self.SUMS))
        self.maxima = np.zeros(len(self.MAXIMA))

    def add(self, acc: np.ndarray) -> None:
        self.sums += acc[self.SUMS]
        np.maximum(self.maxima, acc[self.MAXIMA], out=self.maxima)

    def put(self, acc: np.ndarray) -> None:
        acc[self.SUMS] = self.sums
        acc[self.MAXIMA] = self.maxima


def _drive(d: _Drive, n_min: int, n_max: int, snap_at: set, log) -> _Run:
    """Advance the kernel interval by interval from 1 to at most ``n_max`` (end rule: ``simulate``)."""
    st, setup, cfg, km = d.st, d.setup, d.cfg, d.setup.model
    dt, n_sub, ratio = d.dt, d.n_sub, d.ratio
    limit = edge_piece_limit(km.rope_radius, km.fin_half) or np.inf
    x_full = np.array(d.net.x, dtype=np.float64)
    v_full = np.zeros_like(x_full)  # the held net is at rest (HeldNet)
    snaps = ([0.0], [x_full.copy()], [setup.start.apex.copy()], [st.mq.copy()], [v_full.copy()])
    run = _Run(0, "max_duration" if cfg.max_duration is not None else "duration", [0], [], snaps,
               lineage=lineage_start(km.seg.shape[0]))
    names = part_names(d.missile)
    wk = K.new_work(km, st)  # kept across the calls while the model stays (a cut or merge makes a new one)
    with progress_bar(n_max, "collide") as bar:
        for k in range(1, n_max + 1):
            t = k * cfg.output_interval
            gather = _Interval()
            pressed, chords = [], []
            for j in range(cfg.loads_per_output):
                st.acc[M.A_TIME] = (k - 1) * cfg.output_interval + j * cfg.load_dt
                status = K.advance_kept(km, st, wk, n_sub, dt, ratio, n_sub * (cfg.loads_per_output - j))
                run.steps += n_sub
                run.dt_min = min(run.dt_min, dt)
                if status != M.OK:
                    t_call = (k - 1) * cfg.output_interval + (j + 1) * cfg.load_dt
                    raise NumericalError(_stop_message(status, st, cfg, t_call, names, setup, dt))
                gather.add(st.acc)
                fin, pt, imp, seg, chord = _take_fin_events(km, st)
                if seg.size:
                    run.fin_piece_max = max(run.fin_piece_max, float(chord.max()))
                    mag = np.linalg.norm(imp, axis=1)
                    run.fin_imp_all += float(mag.sum())
                    run.fin_imp_long += float(mag[chord > limit].sum())
                    pressed.append(seg)
                    chords.append(chord)
                run.row_start.append(run.row_start[-1] + fin.size)
                if fin.size:
                    run.ev_rows.append((fin, pt, imp))
            gather.put(st.acc)
            if cfg.fin_piece_chord is not None:
                seg = np.concatenate(pressed) if pressed else np.zeros(0, np.int64)
                chord = np.concatenate(chords) if chords else np.zeros(0)
                adapted = _adapt(d, km, st, seg, chord, run, log, t)
                if adapted is not None:
                    km, st, dt, n_sub, ratio = adapted
                    d.rec.km, d.rec.st = km, st
                    wk = K.new_work(km, st)
            apex = d.rec.sample(k, t, log, dt)
            run.n_done = k
            over = k >= n_min and interaction_over(
                d.rec.cols["contacts"][k], d.rec.cols["apex_along_path_m"][k] - d.missile.length,
                float((st.x[km.free] @ setup.start.direction).max()), cfg.end_clearance)
            if k in snap_at or over or k == n_max:
                x_full[setup.used], v_full[setup.used] = st.x[:setup.used.size], st.v[:setup.used.size]
                for lst, val in zip(snaps, (t, x_full.copy(), apex.copy(), st.mq.copy(), v_full.copy())):
                    lst.append(val)
            bar.update(1)
            if over:
                run.stop_reason = "interaction_over"
                break
    return run


LONG_SHARE_WARN = 0.01
"""The edge-resolution warning needs pieces longer than the limit to have delivered at least this
share of the fins' Σ|impulse|. The largest error measured on an unresolved piece's load is ~30 %
(radar × traction's rudders 2–3 at the former 0.7 mm, docs/collide_convergence.md): below 1 %
of the impulse that is ≤ 0.3 % of the fin loads (infrared × traction with fin_piece_chord: 1.7 mm
chords for 0.12 % of the impulse, and its resolution check moves no headline by more than 1 %)."""

ADAPT_REACH = 2.0
"""``fin_piece_chord`` also cuts the segments within this many output intervals' travel at the
impact speed of a fin (a lower bound of their gap, ``kernel.fin_gaps``), so rope is cut before it
strikes rather than after its first interval of contact."""

CUT_MAX = 8
"""Most pieces one segment is cut into per output interval (``collide.adapt``): a long segment that
passes near a fin (rotary nets: up to 2.8 m) is cut progressively — its pieces near the fin again
at the next interval, the rest not — instead of into thousands of pieces at once. A pressing
piece of the paper cases (chords ≤ ~11 mm against 1.4 mm) is cut in one go."""

CUT_NODES_CAP = 200_000
"""Most nodes ``fin_piece_chord`` may add in one run (a rope cut without end is an error)."""


MERGE_REACH = 3.0
"""The pieces of a start segment are merged back (``_merge_idle``) once every one of them is at least
this many output intervals' travel at the impact speed from every fin (3 cm in the paper cases),
three times the reach at which rope is cut (ADAPT_REACH): a merged segment is not cut again at the
next interval."""

MERGE_STRAIGHT = 1.0e-3
"""… and its pieces lie within this fraction of the straight line: Σ piece chords ≤ (1 + this) ×
the chord between the start segment's end nodes, so the merge changes the rope's elastic energy by
at most ~2 × this × its tension × chord (booked in ``rope_refinement_j``)."""


def _line_step_input(km: M.CollideModel, st: M.CollideState) -> tuple[float, float]:
    """(largest k_l [N/m²], the live rope's smallest mass per rest length [kg/m]) of a line-law model:
    what its contact limit needs (``timestep.choose_step``'s ``line``). With the rest lengths the
    limit does not change as the rope stretches (``timestep.line_density_min``), so it is chosen
    again only when a cut or merge changes the model (``_restep``)."""
    return (max(km.kl_body, float(km.kl_fin.max(initial=0.0))),
            line_density_min(km.seg[st.alive], km.rest[st.alive], km.mass, km.free))


def _adapt(d: _Drive, km: M.CollideModel, st: M.CollideState, seg: np.ndarray, chord: np.ndarray, run: _Run, log,
           t: float):
    """``fin_piece_chord`` between two output intervals: cut where the rope presses or is about to
    (``_cut_pressing``), merge back the pieces of rope that has left the fins (``_merge_idle``), and
    choose the step again when either changed the model. Returns (model, state, dt, n_sub, ratio) or
    None when nothing changed."""
    gaps = K.fin_gaps(km, st)  # (the cut appends: the ids of the segments gapped here do not change)
    cut = _cut_pressing(d, km, st, seg, chord, gaps, run, log, t)
    if cut is not None:
        km, st = cut
    merged = _merge_idle(d, km, st, seg, gaps, run, log, t)
    if merged is not None:
        km, st = merged
    if cut is None and merged is None:
        return None
    km, dt, n_sub, ratio = _restep(d, km, st)
    return km, st, dt, n_sub, ratio


def _cut_pressing(d: _Drive, km: M.CollideModel, st: M.CollideState, seg: np.ndarray, chord: np.ndarray,
                  gaps: np.ndarray, run: _Run, log, t: float):
    """Cut the segments ``seg`` (k,) that pressed on a fin with a chord [m] (k,) longer than
    ``cfg.fin_piece_chord``, and those whose chord is now longer than it among their rope
    neighbours (sharing a node with them: the rope that slides onto the fin next) and the segments
    within ADAPT_REACH intervals' travel of a fin (gaps [m] (ns,), ``kernel.fin_gaps``: the rope about
    to be struck; ``collide.adapt``; both ends free). Returns (model, state) or None when nothing is
    cut."""
    cfg, rope = d.cfg, d.net.rope
    worst = np.zeros(km.seg.shape[0])
    np.maximum.at(worst, seg, chord)
    reach = ADAPT_REACH * cfg.impact_speed * cfg.output_interval
    near = (np.isin(km.seg, np.unique(km.seg[seg])).any(axis=1) | (gaps <= reach)) & st.alive
    now = np.linalg.norm(st.x[km.seg[near, 1]] - st.x[km.seg[near, 0]], axis=1)
    worst[near] = np.maximum(worst[near], now)
    idx = np.flatnonzero(worst > cfg.fin_piece_chord)
    idx = idx[km.free[km.seg[idx, 0]] & km.free[km.seg[idx, 1]]]
    if idx.size == 0:
        return None
    n_piece = np.minimum(cut_counts(worst[idx], cfg.fin_piece_chord), CUT_MAX)
    run.cut_nodes += int((n_piece - 1).sum())
    if run.cut_nodes > CUT_NODES_CAP:
        raise NumericalError(f"collide: collide.fin_piece_chord = {cfg.fin_piece_chord:.3g} m has cut more than "
                             f"{CUT_NODES_CAP} nodes into the rope by t = {t:.4g} s: the rope keeps stretching on the "
                             f"fins (raise fin_piece_chord)")
    km, st, d_e = cut_live(km, st, idx, n_piece, rope.density * rope_area(rope.diameter),
                           rope.damping_law, rope.damping_ratio)
    run.lineage = lineage_cut(run.lineage, idx, n_piece)
    run.cut_segments += int(idx.size)
    log.debug("collide: t = %.4g s: cut %d pressing rope segments into %d pieces (ΔE %.3g J)", t, idx.size,
              int(n_piece.sum()), d_e)
    return km, st


def _merge_idle(d: _Drive, km: M.CollideModel, st: M.CollideState, pressed: np.ndarray, gaps: np.ndarray, run: _Run,
                log, t: float):
    """Merge back (``collide.adapt.merge_roots``) the pieces of every start segment that are all
    intact, out of contact (no contact slot open), at least MERGE_REACH intervals' travel from every
    fin (gaps [m] (ns_before,) before this interval's cut, which only appends: a piece appended now
    counts as near), share no node with a segment that pressed in the interval (``pressed``, indices
    before the cut), and lie within MERGE_STRAIGHT of the straight line. Returns (model, state) or
    None when nothing is merged."""
    lin, km0, cfg = run.lineage, d.setup.model, d.cfg
    pieces = np.flatnonzero(km.always_fast)
    if pieces.size == 0:
        return None
    nf = km.fin_half.shape[0]
    root = lin.root[pieces]
    gap = np.zeros(pieces.size)
    old = pieces < gaps.size
    gap[old] = gaps[pieces[old]]
    quiet = (st.alive[pieces] & (st.vk.reshape(-1, 1 + nf)[pieces] == 0.0).all(axis=1)
             & (gap > MERGE_REACH * cfg.impact_speed * cfg.output_interval)
             & ~np.isin(km.seg[pieces], km.seg[pressed]).any(axis=1))
    busy = np.zeros(km0.seg.shape[0], dtype=np.bool_)
    busy[root[~quiet]] = True
    path = np.bincount(root, np.linalg.norm(st.x[km.seg[pieces, 1]] - st.x[km.seg[pieces, 0]], axis=1),
                       minlength=km0.seg.shape[0])
    line = np.linalg.norm(st.x[km0.seg[:, 1]] - st.x[km0.seg[:, 0]], axis=1)
    roots = np.unique(root)
    roots = roots[~busy[roots] & (path[roots] <= (1.0 + MERGE_STRAIGHT) * line[roots])]
    if roots.size == 0:
        return None
    n_before = km.mass.shape[0]
    km, st, run.lineage, _, d_e = merge_roots(km, st, km0, lin, roots, d.net.rope.damping_law,
                                               d.net.rope.damping_ratio)
    run.merged_segments += int(roots.size)
    run.merged_nodes += n_before - km.mass.shape[0]
    log.debug("collide: t = %.4g s: merged the pieces of %d rope segments that left the fins (%d nodes, ΔE %.3g J)",
              t, roots.size, n_before - km.mass.shape[0], d_e)
    return km, st


def _sub_steps(cfg: CollideConfig, dt_max: float) -> tuple[int, float]:
    """(steps per fin-load interval, dt [s]): the fewest steps of at most ``dt_max`` [s] that fill
    one load interval (``cfg.load_dt``) exactly, so load and output times fall on steps."""
    n_sub = max(1, math.ceil(cfg.load_dt / dt_max))
    return n_sub, cfg.load_dt / n_sub


def _restep(d: _Drive, km: M.CollideModel, st: M.CollideState) -> tuple[M.CollideModel, float, int, int]:
    """(model with its air_every, dt [s], steps per fin-load interval, far-net window [steps]) chosen
    again for a model the rope's cuts or merges changed: the lightest node cut in (or the lightest the
    missile can reach) sets the contact limit."""
    cfg = d.cfg
    k_contact = max(km.k_body, km.k_fin)
    cut_in = km.mass[d.setup.used.size:]
    light = min(float(cut_in.min()), d.setup.m_reach) if cut_in.size else d.setup.m_reach
    line = _line_step_input(km, st) if km.line_law else None
    new = choose_step(cfg, km.k, km.mass[km.seg[:, 0]], km.mass[km.seg[:, 1]], light,
                      int(np.bincount(km.seg.ravel()).max()), km.rope_radius,
                      float(km.fin_half.min()), k_contact, line)
    n_sub, dt = _sub_steps(cfg, new.dt * d.dt_scale)
    uncut = ~km.always_fast  # the pieces are stepped every step: the window is the uncut rope's
    ratio = min(far_ratio(cfg, spring_limit(km.k[uncut], km.mass[km.seg[uncut, 0]], km.mass[km.seg[uncut, 1]]), dt,
                          new.dt_contact if km.line_law else math.inf),
                n_sub * cfg.loads_per_output)
    air_ratio = _air_step_check(km, st, cfg, dt * ratio)
    km = km._replace(air_every=air_windows(air_ratio) if ratio > 1 else 1)
    return km, dt, n_sub, ratio


def _end_summary(summary: dict, run: _Run, rec: "_Recorder", cfg: CollideConfig, net: HeldNet) -> None:
    """Add the end rule's keys (stop reason, end time, force at the end) and its warning to ``summary``."""
    c = rec.cols
    force_end = float(c["contact_force_mean_n"][-1])
    summary.update({"stop_reason": run.stop_reason, "end_time_s": float(c["t_s"][-1]), "force_at_end_n": force_end,
           "rope_split": int(cfg.rope_split), "rope_split_margin_m": float(cfg.rope_split_margin),
           "fin_piece_length_m": cfg.fin_piece_length, "fin_split_margin_m": float(cfg.fin_split_margin),
           "net_nodes": int(net.model.n_nodes), "net_segments": int(net.model.n_springs)})
    summary.update(edge_resolution(run.fin_piece_max, net.rope.diameter / 2, rec.km.fin_half, run.fin_imp_long,
                                   run.fin_imp_all))
    limit = summary["edge_piece_limit_m"]
    if limit is not None and run.fin_piece_max > limit and summary["fin_impulse_share_long_pieces"] >= LONG_SHARE_WARN:
        summary["warnings"].append(
            f"collide: rope pieces up to {1e3 * run.fin_piece_max:.3g} mm long (stretched) pressed on the fins (they delivered "
            f"{100 * summary['fin_impulse_share_long_pieces']:.3g} % of the fins' Σ|impulse|), longer than "
            f"(r + h/2)/3 = {1e3 * summary['edge_piece_limit_m']:.3g} mm: measured at 500 m/s, a rope on a fin's "
            f"rounded edge needs pieces that short for its impulse to be within 2 % (at 50 m/s, 12.5 mm pieces were "
            f"within 1.5 %; benchmarks/collide_edge_lab.py): Δv and the fin impulses may not be converged in "
            f"the rope split (cut collide.fin_piece_length by the ratio of the two lengths — the rope's tension stretches "
            f"its pieces — or raise fin_split_margin if it is set)")
    if run.stop_reason != "interaction_over":
        what = (f"contact force {force_end:.4g} N still acting" if force_end > 0 else
                f"no contact, but the missile's tail is not {cfg.end_clearance:g} m past the net")
        summary["warnings"].append(f"collide: stopped at the {run.stop_reason.replace('_', ' ')} {c['t_s'][-1]:.4g} s with "
                            f"{what}: Δv, impulses and duration may not be final (raise collide.max_duration)")


class _Recorder:
    """Fills the history rows from the state after each output interval and builds the summary."""

    def __init__(self, km, st, missile, inertia, cfg, start, n_out):
        self.km, self.st, self.missile, self.inertia, self.cfg, self.start = km, st, missile, inertia, cfg, start
        self.cols = {c: np.zeros(n_out + 1) for c in HISTORY_COLUMNS}
        e = _energy_terms(km, st, missile, inertia, advanced=False)
        self.e0 = _balance(e)
        self.ke_m0 = e["missile_kinetic_j"]
        self.v0, self.q0 = st.mv.copy(), st.mq.copy()
        self.p0 = missile.mass * st.mv + (km.mass[km.free, None] * st.v[km.free]).sum(axis=0)
        self.w_prev = np.zeros(3)
        self.max_exchanged = 0.0
        self.growth_run = 0
        self.warnings: list[str] = []
        c = self.cols
        c["vel_x_mps"][0], c["vel_y_mps"][0], c["vel_z_mps"][0] = st.mv
        c["apex_along_path_m"][0] = float(start.apex @ start.direction)
        self._write_momentum(0, 0.0)
        for name, val in e.items():
            c[name][0] = val

    def _write_momentum(self, k, t):
        km, st, c = self.km, self.st, self.cols
        pm = self.missile.mass * st.mv
        pn = (km.mass[km.free, None] * st.v[km.free]).sum(axis=0)
        held = st.acc[M.A_PHELD:M.A_PHELD + 3]
        air = st.acc[M.A_IMP_AIR:M.A_IMP_AIR + 3]
        for i, ax in enumerate("xyz"):
            c[f"missile_momentum_{ax}_ns"][k], c[f"net_momentum_{ax}_ns"][k] = pm[i], pn[i]
            c[f"held_impulse_{ax}_ns"][k], c[f"air_impulse_{ax}_ns"][k] = held[i], air[i]
        g_imp = t * (self.missile.mass + km.mass[km.free].sum()) * km.gravity
        c["momentum_error_ns"][k] = float(np.linalg.norm(pm + pn + held - air - self.p0 - g_imp))

    def sample(self, k, t, log, dt) -> np.ndarray:
        """Row k at time t [s] after steps of dt [s]; returns the nose apex [m] (3,) W. Raises on a
        growing energy balance."""
        km, st, c, cfg, acc = self.km, self.st, self.cols, self.cfg, self.st.acc
        r = quat_to_matrix(st.mq)
        w_b = km.inv_inertia @ (r.T @ st.mh)
        a_b = acc[M.A_IMP_B:M.A_IMP_B + 3] / (self.missile.mass * cfg.output_interval)
        rot = rotation_vector(quat_mul(st.mq, _conj(self.q0)))
        c["t_s"][k] = t
        c["accel_body_x_mps2"][k], c["accel_body_y_mps2"][k], c["accel_body_z_mps2"][k] = a_b
        c["accel_mag_mps2"][k] = float(np.linalg.norm(a_b))
        c["omega_body_x_rps"][k], c["omega_body_y_rps"][k], c["omega_body_z_rps"][k] = w_b
        al = (w_b - self.w_prev) / cfg.output_interval
        c["alpha_body_x_rps2"][k], c["alpha_body_y_rps2"][k], c["alpha_body_z_rps2"][k] = al
        self.w_prev = w_b
        c["vel_x_mps"][k], c["vel_y_mps"][k], c["vel_z_mps"][k] = st.mv
        v0 = np.linalg.norm(self.v0)
        c["speed_change_rel"][k] = (np.linalg.norm(st.mv) - v0) / v0
        c["dv_rel"][k] = np.linalg.norm(st.mv - self.v0) / v0
        c["pitch_change_rad"][k], c["yaw_change_rad"][k], c["roll_change_rad"][k] = rot
        c["attitude_change_rad"][k] = float(np.linalg.norm(rot))
        apex = st.mx + r @ (-km.cg_b)
        c["apex_along_path_m"][k] = float(apex @ self.start.direction)
        c["contact_force_mean_n"][k] = acc[M.A_FCONTACT] / cfg.output_interval
        c["contacts"][k] = acc[M.A_NCONTACT]
        c["max_penetration_m"][k] = acc[M.A_PEN_INT]
        c["broken_segments"][k] = acc[M.A_NBROKEN]
        self._write_momentum(k, t)
        e = _energy_terms(km, st, self.missile, self.inertia, dt=dt)
        for name, val in e.items():
            c[name][k] = val
        bal = _balance(e) - self.e0
        c["energy_balance_j"][k] = bal
        self.k_last = k
        self._check_energy(bal, t, log)
        return apex

    def _check_energy(self, bal, t, log):
        """Stop when the balance keeps growing far beyond any step error (a blow-up)."""
        self.max_exchanged = max(self.max_exchanged, self.ke_m0 - self.cols["missile_kinetic_j"][self.k_last])
        ref = max(self.max_exchanged, 1e-6 * self.ke_m0)
        self.growth_run = self.growth_run + 1 if bal > ENERGY_GROWTH_LIMIT * ref else 0
        if self.growth_run >= ENERGY_GROWTH_SAMPLES:
            raise NumericalError(
                f"collide: energy balance grew by {bal:.3g} J by t = {t:.4g} s, more than {ENERGY_GROWTH_LIMIT:.0%} "
                f"of the {self.max_exchanged:.3g} J exchanged at {ENERGY_GROWTH_SAMPLES} samples in a row: an "
                f"unstable contact or step")

    def truncate(self, n_done: int) -> None:
        """Keep rows 0..n_done (the run stopped there)."""
        self.cols = {name: col[:n_done + 1] for name, col in self.cols.items()}

    def summary(self, setup, loads, x_start, dt, steps, wall) -> dict:
        return _summary(self, setup, loads, x_start, dt, steps, wall)


def _alternation(loads: FinLoads, load_dt: float, warnings: list[str]) -> dict[str, int]:
    """Each fin's longest run of step-to-step load alternation [samples]
    (``metrics.load_alternation_runs``); a warning appended for each run beyond
    ALTERNATION_RUN_LIMIT (``load_dt`` [s]: the fin loads' sample interval)."""
    runs = load_alternation_runs(loads.row_start, loads.fin, loads.force, len(loads.fin_names))
    for name, run in zip(loads.fin_names, runs):
        if run > ALTERNATION_RUN_LIMIT:
            warnings.append(f"collide: {name}'s load alternates from one sample to the next for {run} samples "
                            f"({run * load_dt * 1e6:.3g} µs): an explicit step past its stability limit, not a "
                            f"load — its shell stresses are not defined; halve dt (collide.pass_through_fraction)")
    return {str(n): int(r) for n, r in zip(loads.fin_names, runs)}


def _summary(rec: _Recorder, setup: Setup, loads: FinLoads, x_start, dt, steps, wall) -> dict:
    """The ``collide`` section of summary.json (DESIGN.md §3 keys plus extras)."""
    c, st, cfg, missile, km = rec.cols, rec.st, rec.cfg, rec.missile, rec.km
    acc = st.acc
    a_mag = c["accel_mag_mps2"]
    contact_rows = np.flatnonzero(c["contacts"] > 0)
    duration = float(c["t_s"][contact_rows[-1]] - c["t_s"][contact_rows[0]] + cfg.output_interval) \
        if contact_rows.size else 0.0
    tail_along = c["apex_along_path_m"][-1] - missile.length
    net_along = (st.x[km.free] @ setup.start.direction).max()
    exchanged = rec.max_exchanged
    dp_total = missile.mass * float(np.max(c["dv_rel"])) * float(np.linalg.norm(rec.v0))
    k_peak = int(np.argmax(a_mag))
    warnings = list(rec.warnings)
    e_rel = float(np.max(np.abs(c["energy_balance_j"]))) / exchanged if exchanged > 0 else 0.0
    if e_rel > ENERGY_TOLERANCE:
        warnings.append(f"collide: energy balance off by {e_rel:.2%} of the {exchanged:.4g} J exchanged (tolerance "
                        f"{ENERGY_TOLERANCE:.1%}): step error of a stiff contact; halve dt to check")
    if acc[M.A_CROSS] > 0:
        warnings.append(f"collide: TUNNELLING (allowed by the case): {int(acc[M.A_CROSS])} segment-steps passed "
                        f"through a part, skipping ≈ {acc[M.A_SKIPPED]:.3g} N s of impulse")
    metrics = collision_metrics(
        MissileHistory(t_s=c["t_s"], vel_world_mps=np.column_stack([c[f"vel_{a}_mps"] for a in "xyz"]),
                       accel_body_mps2=np.column_stack([c[f"accel_body_{a}_mps2"] for a in "xyz"]),
                       contact_force_n=c["contact_force_mean_n"], gravity_mps2=km.gravity, mass_kg=missile.mass),
        FinContacts(list(loads.fin_names), loads.fin, loads.force, cfg.load_dt), cfc=cfg.cfc_class)
    warnings += metrics.pop("warnings")
    alternation = _alternation(loads, cfg.load_dt, warnings)
    e_ach, bad_e = restitution_check(DampingModel(cfg.damping_model).value, cfg.restitution, cfg.impact_speed,
                                     cfg.damping_min_approach_speed, cfg.contact_exponent)
    warnings += [bad_e] if bad_e else []
    summary = {
        # headline numbers: CFC-filtered peak (collide.metrics) and window-free Δv, impulses, duration
        "peak_accel_mps2": metrics["peak_accel_mps2"],
        "peak_accel_time_s": metrics["peak_accel_time_s"],
        "peak_accel_axis_mps2": metrics["peak_accel_axis_mps2"],
        "duration_s": metrics["contact_duration_s"],
        "dv_over_v": metrics["dv_over_v"],
        **{k: v for k, v in metrics.items() if k not in ("peak_accel_mps2", "peak_accel_time_s",
                                                          "peak_accel_axis_mps2", "dv_over_v")},
        "raw_interval_peak_time_s": float(c["t_s"][k_peak]),
        "contact_rows_duration_s": duration,
        "speed_change_rel": float(c["speed_change_rel"][-1]),
        "max_attitude_change_rad": float(np.max(c["attitude_change_rad"])),
        "passed_through": bool(c["contacts"][-1] == 0 and net_along < tail_along),
        "momentum_error_rel": float(np.max(c["momentum_error_ns"])) / dp_total if dp_total > 0 else 0.0,
        "energy_exchanged_j": exchanged,
        "energy_error_rel": e_rel,
        "max_penetration_m": float(acc[M.A_PEN]),
        "max_penetration_ratio": float(acc[M.A_PEN_RATIO]),
        "max_penetration_over_rope_radius": float(acc[M.A_PEN]) / km.rope_radius,
        "tunnelling": bool(acc[M.A_CROSS] > 0),
        "tunnelling_segment_steps": int(acc[M.A_CROSS]),
        "tunnelling_skipped_impulse_ns": float(acc[M.A_SKIPPED]),
        "broken_segments": int(acc[M.A_NBROKEN]),
        "fin_load_alternation_samples": alternation,
        "fin_load_alternation_limit_samples": ALTERNATION_RUN_LIMIT,
        "steps": int(steps),
        "dt_s": dt,
        "dt_governed_by": setup.step.governed_by,
        "dt_limits_s": {"rope_springs": setup.step.dt_spring, "contact": setup.step.dt_contact,
                        "travel_per_step": setup.step.dt_travel},
        "contact_stiffness_body": km.k_body,
        "contact_stiffness_fin": km.k_fin,
        "stiffness_rule": cfg.stiffness_rule.value,
        "contact_law": cfg.contact_law.value,
        "line_stiffness_body": float(km.kl_body) if km.line_law else None,
        "line_stiffness_fin": [float(v) for v in km.kl_fin] if km.line_law else None,
        "line_spacing_m": float(km.line_h_body) if km.line_law else None,
        **_damping_summary(acc, e_ach),
        "free_nodes": int(km.free.sum()),
        "active_segments": int(km.seg.shape[0]),
        "crop_reach_m": setup.reach if math.isfinite(setup.reach) else None,
        "crop_boundary_motion_m": boundary_motion(x_start, st.x, setup.boundary),
        "warnings": warnings,
        "wall_s": wall,
        **part_impulse_sums(st.part_imp, [f.name for f in missile.fins]),
    }
    return summary


def _damping_summary(acc: np.ndarray, e_ach: float) -> dict:
    """``restitution_achieved``: the restitution the damping law gives an impact above the
    approach-speed floor; ``contact_damping_capped_share``: the share of contact point-steps
    whose dashpot was capped at the explicit step (``contact.law.normal_force``, ``damp_cap``;
    0 when nothing touched) — the damping there is less than Eq. (29)'s."""
    points = acc[M.A_DAMP_POINTS]
    return {"restitution_achieved": e_ach,
            "contact_damping_capped_share": float(acc[M.A_DAMP_CAPPED] / points) if points > 0 else 0.0}


def part_impulse_sums(part_imp: np.ndarray, fin_names: list[str]) -> dict:
    """Summary keys of the per-part scalar impulse sums (``CollideState.part_imp`` (1 + nf, 2)):
    ``normal_impulse_sum_ns`` {part: Σ |F_n| dt} and ``friction_impulse_sum_ns`` {part: Σ |F_t| dt}
    [N s], parts "body" then the fins. Unlike the (vector) impulses they do not cancel around an
    edge: Σ |F_n| dt over |Σ F_n dt| measures how much of the normal force a rope wrapped over a
    fin's edge spends against itself, and friction (Eq. (32)) acts on Σ |F_n|."""
    names = ["body"] + list(fin_names)
    return {"normal_impulse_sum_ns": {n: float(part_imp[i, 0]) for i, n in enumerate(names)},
            "friction_impulse_sum_ns": {n: float(part_imp[i, 1]) for i, n in enumerate(names)}}


def _fin_loads(missile, cfg, n_out, row_start, ev_rows, width) -> FinLoads:
    """Assemble the per-interval fin impulses into :class:`FinLoads` (mean forces). The contact
    width of a rope on a fin is taken as the rope diameter ``width`` [m]."""
    if ev_rows:
        fin = np.concatenate([r[0] for r in ev_rows]).astype(np.int32)
        point = np.concatenate([r[1] for r in ev_rows])
        force = np.concatenate([r[2] for r in ev_rows]) / cfg.load_dt
    else:
        fin, point, force = np.zeros(0, np.int32), np.zeros((0, 3)), np.zeros((0, 3))
    t_mid = (np.arange(n_out * cfg.loads_per_output) + 0.5) * cfg.load_dt
    return FinLoads(fin_names=np.array([f.name for f in missile.fins]), t=t_mid,
                    row_start=np.asarray(row_start, dtype=np.int64), fin=fin, point=point, force=force,
                    width=np.full(fin.shape[0], width))
