"""Flight stage: run the engagement of a ``[flight]`` table, write history/plots, summarise.

Public API:
    simulate_flight(flight, altitude_m, damage=None) -> FlightResult     (no files)
    run_flight(flight, altitude_m, stage_dir, log, shell_dir=None) -> dict (the stage)
    run_flight_sweep(flight, altitude_m, stage_dir, log) -> dict         (miss vs damage)
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flexnet_fe.atmosphere import isa
from flexnet_fe.errors import FlexnetError, NumericalError
from flexnet_fe.flight import aero as A
from flexnet_fe.flight import simulate as S
from flexnet_fe.flight.autopilot import (
    ThreeLoopGains, linearize, plane_derivatives, roll_gains, three_loop_gains)
from flexnet_fe.flight.config import (
    DamageConfig, FlightConfig, LaunchDirection, StabilityDamage, SweepParameter, TurnDirection, VerticalAxis)
from flexnet_fe.flight.damage import damage_from_shell
from flexnet_fe.flight.miss import closest_approach
from flexnet_fe.flight.target import level_turn, turn_rate
from flexnet_fe.io import atomic_write_json, write_history_csv
from flexnet_fe.rigid import quat_from_matrix

G0 = 9.80665
"""standard gravity [m/s²], used only to express accelerations in g for people"""
REPORT_RADII_M = (1.0, 5.0, 10.0)
MACH_MIN = 1.2
"""below this Mach the linear supersonic panel theory of the airframe is not used (error)"""
AIR_TABLE_STEP_M = 100.0
"""ISA table spacing [m]: linear interpolation error ≈ h²/(8 H²) ≈ 2e-5 of ρ (scale height H ≈ 8 km)"""
AIR_TABLE_HALF_RANGE_M = 15000.0
"""the table spans the scene altitude ± this [m]; leaving it stops the run with an error"""


def case_to_flight_matrix(axis: VerticalAxis) -> np.ndarray:
    """M with v_F = M v_P (case frame P → flight frame F, module doc of flexnet_fe.flight)."""
    if axis is VerticalAxis.y:
        return np.eye(3)
    return np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])


def damage_multipliers(damage: DamageConfig) -> tuple[float, float, float]:
    """(k_lift, k_moment, k_ctrl) of paper §VI: lift/side-force slopes × (1 − d); stability
    moment × (1 + d) (``magnitude``) or × (1 − d) (``toward_instability``: m + d|m| with m < 0);
    control derivatives × e."""
    d = damage.wing_damage
    k_mom = 1.0 + d if damage.stability is StabilityDamage.magnitude else 1.0 - d
    return 1.0 - d, k_mom, damage.rudder_effectiveness


def air_table(altitude_m: float) -> np.ndarray:
    """ISA (``flexnet_fe.atmosphere.isa``) density and speed of sound tabulated every 100 m over
    ±15 km around the scene altitude (clipped to ISA's −5 km ... 80 km): (alt0, dalt, n, ρ[n], a[n])."""
    lo = max(altitude_m - AIR_TABLE_HALF_RANGE_M, -5000.0)
    hi = min(altitude_m + AIR_TABLE_HALF_RANGE_M, 80000.0)
    alts = np.arange(lo, hi + 0.5 * AIR_TABLE_STEP_M, AIR_TABLE_STEP_M)
    airs = [isa(h) for h in alts]
    rho = np.array([a.density for a in airs])
    snd = np.array([a.speed_of_sound for a in airs])
    return np.concatenate([[lo, AIR_TABLE_STEP_M, len(alts)], rho, snd])


@dataclass(frozen=True)
class Autopilot:
    """Fixed autopilot gains (designed for the undamaged missile at launch)."""

    three_loop: ThreeLoopGains
    k_phi: float
    k_p: float
    design_alpha_rad: float
    omega_af: float
    zeta_af: float


def design_autopilot(flight: FlightConfig, rho: float, sound: float, gravity: float) -> Autopilot:
    """Zarchan's three-loop design at the launch flight condition (undamaged airframe)."""
    af, ap = flight.airframe, flight.autopilot
    a = A.aero_coefficients(af)
    inertia = A.inertia_diagonal(af)
    v = flight.missile_speed
    mach = v / sound
    if mach < MACH_MIN:
        raise NumericalError(f"launch Mach {mach:.2f} < {MACH_MIN}: outside the airframe's supersonic panel theory")
    beta_m = A.supersonic_beta(mach)
    qbar = 0.5 * rho * v * v
    cn_trim = af.mass * gravity * ap.design_load_g / (qbar * a[A.SREF])
    der = plane_derivatives(a, beta_m, cn_trim)
    lin = linearize(der, qbar, v, af.mass, inertia[1], a[A.SREF], a[A.DREF])
    gains = three_loop_gains(lin, v, ap.crossover_rad_s, ap.damping, ap.time_constant_s)
    # roll: L_p, L_delta of the undamaged airframe at launch
    l_delta = A.roll_moment(qbar, v, 0.0, 1.0, beta_m, a, 1.0, 1.0) / inertia[0]
    l_p = A.roll_moment(qbar, v, 1.0, 0.0, beta_m, a, 1.0, 1.0) / inertia[0]
    k_phi, k_p = roll_gains(l_p, l_delta, ap.roll_bandwidth_rad_s, ap.roll_damping)
    return Autopilot(gains, k_phi, k_p, der.alpha_trim, lin.omega_af, lin.zeta_af)


def initial_geometry(flight: FlightConfig, gravity: float):
    """(target tuple (9,), target turn rate [rad/s], missile state s0 (N_STATE,)) in F."""
    m = case_to_flight_matrix(flight.vertical_axis)
    pt0 = m @ np.asarray(flight.target_position, dtype=float)
    fwd = m @ np.asarray(flight.target_direction, dtype=float)
    fwd /= np.linalg.norm(fwd)
    up = np.array([0.0, 1.0, 0.0])
    left = np.cross(up, fwd)                       # facing fwd with y up, up × fwd points left
    centre = left if flight.turn_direction is TurnDirection.left else -left
    omega_t = turn_rate(flight.target_speed, flight.target_load_factor, gravity)
    tgt = np.concatenate([pt0, fwd, centre])
    pm0 = m @ np.asarray(flight.missile_position, dtype=float)
    los = pt0 - pm0
    u_r = los / np.linalg.norm(los)
    if flight.launch_direction is LaunchDirection.line_of_sight:
        d = u_r
    else:
        vt = flight.target_speed * fwd
        v_perp = vt - np.dot(vt, u_r) * u_r
        if np.linalg.norm(v_perp) >= flight.missile_speed:
            raise NumericalError("no collision course: target crossing speed exceeds missile speed")
        d = (math.sqrt(flight.missile_speed ** 2 - np.dot(v_perp, v_perp)) * u_r + v_perp) / flight.missile_speed
    zb = np.cross(d, up)
    if np.linalg.norm(zb) < 1e-9:
        raise NumericalError("vertical launch: roll reference undefined")
    zb /= np.linalg.norm(zb)
    yb = np.cross(zb, d)
    q0 = quat_from_matrix(np.column_stack([d, yb, zb]))
    s0 = np.zeros(S.N_STATE)
    s0[0:3] = pm0
    s0[3:6] = flight.missile_speed * d
    s0[6:10] = q0
    r, v = pt0 - pm0, flight.target_speed * fwd - s0[3:6]
    s0[23:26] = np.cross(r, v) / np.dot(r, r)      # seeker filter starts on the true LOS rate
    return tgt, omega_t, s0


def build_parameters(flight: FlightConfig, ap: Autopilot, omega_t: float, gravity: float,
                     altitude_m: float, damage: DamageConfig) -> np.ndarray:
    """The kernel's parameter vector P (indices in flexnet_fe.flight.simulate)."""
    af, act = flight.airframe, flight.actuator
    inertia = A.inertia_diagonal(af)
    k_lift, k_mom, k_ctrl = damage_multipliers(damage)
    p = np.zeros(S.N_PARAM)
    p[S.P_NAV] = flight.navigation_constant
    p[S.P_TAU_S] = flight.seeker.time_constant_s
    p[S.P_AMAX] = flight.autopilot.max_accel_command_g * G0
    p[S.P_GCOMP] = 1.0 if flight.autopilot.gravity_compensation else 0.0
    p[S.P_G] = gravity
    p[S.P_MASS] = af.mass
    p[S.P_IXX], p[S.P_IYY] = inertia[0], inertia[1]
    p[S.P_KLIFT], p[S.P_KMOM], p[S.P_KCTRL] = k_lift, k_mom, k_ctrl
    g3 = ap.three_loop
    p[S.P_KA], p[S.P_WI], p[S.P_KR], p[S.P_KDC] = g3.k_a, g3.omega_i, g3.k_r, g3.k_dc
    p[S.P_KPHI], p[S.P_KP] = ap.k_phi, ap.k_p
    p[S.P_WACT], p[S.P_ZACT] = act.natural_frequency_rad_s, act.damping
    p[S.P_DMAX] = math.radians(act.max_deflection_deg)
    p[S.P_RMAX] = math.radians(act.max_rate_deg_s)
    p[S.P_TSPEED] = flight.target_speed
    p[S.P_TOMEGA] = omega_t
    p[S.P_TSTART] = flight.maneuver_start
    p[S.P_ALT0] = altitude_m
    p[S.P_MACH_MIN] = MACH_MIN
    return p


def critical_step(flight: FlightConfig, ap: Autopilot) -> float:
    """RK4 stability limit |λ| dt ≤ 2.78 on the fastest known linear mode: actuator (ω_a),
    seeker lag (1/τ_s), airframe short period (ω_af), three-loop crossover (ω_cr) [s]."""
    lam = max(flight.actuator.natural_frequency_rad_s, 1.0 / flight.seeker.time_constant_s,
              ap.omega_af, flight.autopilot.crossover_rad_s)
    return 2.78 / lam


@dataclass(frozen=True)
class FlightResult:
    """One engagement. Arrays in the flight frame F; see flexnet_fe.flight.simulate for states."""

    times: np.ndarray
    """[s], shape (m,)"""
    states: np.ndarray
    """shape (m, N_STATE)"""
    diags: np.ndarray
    """shape (m, N_DIAG), columns simulate.DIAG_COLUMNS"""
    closest_approach_found: bool
    miss_distance_m: float
    time_of_closest_approach_s: float
    autopilot: Autopilot
    dt_s: float
    dt_crit_s: float
    steps: int
    kernel_wall_s: float


def simulate_flight(flight: FlightConfig, altitude_m: float, damage: DamageConfig | None = None) -> FlightResult:
    """Run one engagement (no files). ``damage`` overrides ``flight.damage`` (used by sweeps)."""
    damage = damage or flight.damage
    air0 = isa(altitude_m)
    m_alt = altitude_m + (case_to_flight_matrix(flight.vertical_axis) @ np.asarray(flight.missile_position))[1]
    air_m = isa(m_alt)
    ap = design_autopilot(flight, air_m.density, air_m.speed_of_sound, air0.gravity)
    dt_crit = critical_step(flight, ap)
    if flight.dt > dt_crit:
        raise NumericalError(f"flight.dt = {flight.dt:.3g} s exceeds the RK4 stability limit "
                             f"dt_crit = {dt_crit:.3g} s of the fastest loop")
    tgt, omega_t, s0 = initial_geometry(flight, air0.gravity)
    p = build_parameters(flight, ap, omega_t, air0.gravity, altitude_m, damage)
    n_steps = int(math.ceil(flight.t_end / flight.dt))
    every = max(1, int(round(flight.output_dt / flight.dt)))
    aero, air = A.aero_coefficients(flight.airframe), air_table(altitude_m)
    t0 = time.perf_counter()
    times, states, diags, status, t_a, s_a, t_b, s_b = S.run_engagement(
        s0, p, aero, air, tgt, flight.dt, n_steps, every)
    wall = time.perf_counter() - t0
    if status == S.STATUS_NONFINITE:
        raise NumericalError(f"flight state became non-finite at t = {t_b:.4f} s (dt = {flight.dt:.3g} s, "
                             f"dt_crit = {dt_crit:.3g} s)")
    if status == S.STATUS_OUT_OF_AIR_TABLE:
        raise NumericalError(f"missile left the tabulated altitude band (scene altitude ± "
                             f"{AIR_TABLE_HALF_RANGE_M:.0f} m) at t = {t_b:.3f} s")
    if status == S.STATUS_SUBSONIC:
        raise NumericalError(f"missile Mach fell below {MACH_MIN} at t = {t_b:.3f} s: outside the "
                             "airframe's supersonic panel theory")
    found = status == S.STATUS_CLOSEST
    if found:
        rel = []
        for t, s in ((t_a, s_a), (t_b, s_b)):
            pt, vt, _ = level_turn(t, tgt[0:3], tgt[3:6], tgt[6:9], flight.target_speed, omega_t,
                                   flight.maneuver_start)
            rel.append((pt - s[0:3], vt - s[3:6]))
        t_ca, miss = closest_approach(t_a, rel[0][0], rel[0][1], t_b, rel[1][0], rel[1][1])
    else:  # no closest approach before t_end: report the smallest sampled range
        i = int(np.argmin(diags[:, 10]))
        t_ca, miss = float(times[i]), float(diags[i, 10])
    return FlightResult(times, states, diags, found, miss, t_ca, ap, flight.dt, dt_crit,
                        int(round(t_b / flight.dt)), wall)


def euler_angles(states: np.ndarray) -> np.ndarray:
    """(yaw ψ, pitch θ, roll φ) [rad], shape (m, 3), for R = R_y(ψ) R_z(θ) R_x(φ) (flexnet_fe.flight)."""
    q = states[:, 6:10] / np.linalg.norm(states[:, 6:10], axis=1)[:, None]
    w, x, y, z = q.T
    r00 = 1 - 2 * (y * y + z * z)
    r10 = 2 * (x * y + w * z)
    r20 = 2 * (x * z - w * y)
    r11 = 1 - 2 * (x * x + z * z)
    r12 = 2 * (y * z - w * x)
    return np.column_stack([np.arctan2(-r20, r00), np.arcsin(np.clip(r10, -1, 1)), np.arctan2(-r12, r11)])


def history_columns(res: FlightResult, flight: FlightConfig) -> dict[str, np.ndarray]:
    """history.csv columns; positions in the case frame P."""
    m_inv = case_to_flight_matrix(flight.vertical_axis).T
    pm = res.states[:, 0:3] @ m_inv.T
    pt = res.diags[:, 0:3] @ m_inv.T
    vm = res.states[:, 3:6] @ m_inv.T
    eul = euler_angles(res.states)
    cols = {"t_s": res.times,
            "missile_x_m": pm[:, 0], "missile_y_m": pm[:, 1], "missile_z_m": pm[:, 2],
            "missile_vx_mps": vm[:, 0], "missile_vy_mps": vm[:, 1], "missile_vz_mps": vm[:, 2],
            "target_x_m": pt[:, 0], "target_y_m": pt[:, 1], "target_z_m": pt[:, 2],
            "yaw_rad": eul[:, 0], "pitch_rad": eul[:, 1], "roll_rad": eul[:, 2],
            "p_radps": res.states[:, 10], "q_radps": res.states[:, 11], "r_radps": res.states[:, 12]}
    for i in range(4):
        cols[f"fin{i}_rad"] = res.states[:, 13 + i]
    for j, name in enumerate(S.DIAG_COLUMNS):
        if not name.startswith("target_"):
            cols[name] = res.diags[:, j]
    return cols


def flight_summary(res: FlightResult, flight: FlightConfig) -> dict:
    """The ``flight`` section of summary.json. Achieved acceleration = the aerodynamic specific
    force normal to the missile axis (what the accelerometer at the CG measures)."""
    acc = np.hypot(res.diags[:, 5], res.diags[:, 6])
    alpha_t = np.hypot(res.diags[:, 7], res.diags[:, 8])
    k_lift, k_mom, k_ctrl = damage_multipliers(flight.damage)
    return {
        "miss_distance_m": res.miss_distance_m,
        "hit": bool(res.closest_approach_found and res.miss_distance_m <= flight.lethal_radius),
        "lethal_radius_m": flight.lethal_radius,
        "hit_within_m": {f"{r:g}": bool(res.closest_approach_found and res.miss_distance_m <= r)
                         for r in REPORT_RADII_M},
        "closest_approach_found": res.closest_approach_found,
        "time_of_closest_approach_s": res.time_of_closest_approach_s,
        "max_achieved_accel_g": float(acc.max() / G0),
        "max_total_incidence_deg": float(np.degrees(alpha_t.max())),
        "max_fin_deflection_deg": float(np.degrees(np.abs(res.states[:, 13:17]).max())),
        "wing_damage": flight.damage.wing_damage,
        "stability_interpretation": flight.damage.stability.value,
        "rudder_effectiveness": flight.damage.rudder_effectiveness,
        "multipliers": {"lift": k_lift, "stability_moment": k_mom, "control": k_ctrl},
        "autopilot": {"k_a_s_per_m": res.autopilot.three_loop.k_a, "omega_i_radps": res.autopilot.three_loop.omega_i,
                      "k_r_s": res.autopilot.three_loop.k_r, "k_dc": res.autopilot.three_loop.k_dc,
                      "k_phi": res.autopilot.k_phi, "k_p_s": res.autopilot.k_p,
                      "design_alpha_deg": math.degrees(res.autopilot.design_alpha_rad),
                      "airframe_omega_radps": res.autopilot.omega_af, "airframe_zeta": res.autopilot.zeta_af},
        "steps": res.steps,
        "dt_s": res.dt_s,
        "dt_crit_s": res.dt_crit_s,
        "ns_per_step": 1e9 * res.kernel_wall_s / max(res.steps, 1),
    }


def run_flight(flight: FlightConfig, altitude_m: float, stage_dir: Path, log: logging.Logger,
               shell_dir: Path | None = None) -> dict:
    """The flight stage: nominal engagement (history.csv, plots) and, if ``flight.sweep`` is set,
    the sweep (sweep.csv, miss-vs-damage plot). Returns the ``flight`` section of summary.json.

    With ``flight.damage_from_shell``, ``shell_dir`` (the shell stage's output folder) sets the
    damage fractions (flexnet_fe.flight.damage) before anything runs."""
    from flexnet_fe.flight import plots

    t0 = time.perf_counter()
    stage_dir = Path(stage_dir)
    from_shell = None
    if flight.damage_from_shell:
        if shell_dir is None:
            raise FlexnetError("flight.damage_from_shell = true needs the shell stage's results")
        from_shell = damage_from_shell(shell_dir, flight.damage_allowable_stress)
        flight = flight.model_copy(update={"damage": flight.damage.model_copy(update={
            "wing_damage": from_shell.wing_damage, "rudder_effectiveness": from_shell.rudder_effectiveness})})
        log.info("flight: damage from the shell stage (allowable %.3g Pa): wing_damage %.3f, "
                 "rudder_effectiveness %.3f, per fin %s", flight.damage_allowable_stress,
                 from_shell.wing_damage, from_shell.rudder_effectiveness, from_shell.per_fin)
    res = simulate_flight(flight, altitude_m)
    summary = flight_summary(res, flight)
    if from_shell is not None:
        summary["damage_from_shell"] = {"allowable_stress_pa": flight.damage_allowable_stress,
                                        "overstressed_area_fraction": from_shell.per_fin}
    log.info("flight: dt = %.3g s (dt_crit %.3g s), %d steps, %.0f ns/step", res.dt_s, res.dt_crit_s,
             res.steps, summary["ns_per_step"])
    log.info("flight: miss %.3f m at t = %.3f s (%s, lethal radius %.1f m), max accel %.1f g, max incidence %.1f deg",
             res.miss_distance_m, res.time_of_closest_approach_s, "hit" if summary["hit"] else "miss",
             flight.lethal_radius, summary["max_achieved_accel_g"], summary["max_total_incidence_deg"])
    if summary["max_total_incidence_deg"] > 30.0:
        log.warning("flight: total incidence reached %.0f deg: beyond the linear aerodynamics' range; "
                    "the trajectory after that is qualitative", summary["max_total_incidence_deg"])
    write_history_csv(stage_dir / "history.csv", history_columns(res, flight))
    plots.plot_engagement(history_columns(res, flight), flight, stage_dir)
    if flight.sweep is not None:
        summary["sweep"] = run_flight_sweep(flight, altitude_m, stage_dir, log)
    summary["wall_s"] = time.perf_counter() - t0
    return summary


def first_miss_value(values, misses, radius: float):
    """The first swept value (listed from undamaged to damaged) whose miss exceeds ``radius``
    [m] (∞ = diverged counts as a miss), or None if every point hits."""
    return next((v for v, mm in zip(values, misses) if not mm <= radius), None)


def run_flight_sweep(flight: FlightConfig, altitude_m: float, stage_dir: Path, log: logging.Logger) -> dict:
    """Miss distance vs ``flight.sweep`` values for both stability interpretations (a wing-damage
    sweep) or for the rudder effectiveness; writes sweep.csv, sweep.json and
    flight_miss_vs_damage.png. The threshold is the first swept value (values are listed from
    undamaged to damaged) whose miss exceeds the lethal radius (also given for 1, 5, 10 m).
    A point whose integration fails (NumericalError, e.g. the damaged missile slows below the
    aero model's Mach range) is logged as a warning and counted as a miss (∞ in sweep.csv)."""
    from flexnet_fe.flight import plots

    sw = flight.sweep
    if sw is None:
        raise ValueError("flight.sweep is not set")
    readings = (list(StabilityDamage) if sw.parameter is SweepParameter.wing_damage
                else [flight.damage.stability])
    cols: dict[str, list[float]] = {"value": list(sw.values)}
    out: dict = {"parameter": sw.parameter.value, "values": list(sw.values), "lethal_radius_m": flight.lethal_radius}
    for reading in readings:
        misses = []
        for v in sw.values:
            upd = {"stability": reading}
            upd[sw.parameter.value] = v
            dmg = flight.damage.model_copy(update=upd)
            try:
                r = simulate_flight(flight, altitude_m, dmg)
                miss = r.miss_distance_m if r.closest_approach_found else math.inf
            except NumericalError as err:  # a diverging damaged missile is a miss; say so in the log
                log.warning("sweep %s=%g (%s): %s", sw.parameter.value, v, reading.value, err)
                miss = math.inf
            misses.append(miss)
        suffix = f"_{reading.value}" if len(readings) > 1 else ""
        cols[f"miss_m{suffix}"] = misses
        first_miss = first_miss_value(sw.values, misses, flight.lethal_radius)
        out[f"miss_m{suffix}"] = [mm if math.isfinite(mm) else None for mm in misses]
        out[f"threshold{suffix}"] = first_miss
        out[f"threshold_by_radius{suffix}"] = {
            f"{r:g}": first_miss_value(sw.values, misses, r) for r in REPORT_RADII_M}
        log.info("sweep %s%s: misses %s m; first miss at %s", sw.parameter.value, suffix,
                 ", ".join(f"{m:.2f}" for m in misses), first_miss)
    write_history_csv(stage_dir / "sweep.csv", {k: np.asarray(v, dtype=float) for k, v in cols.items()})
    plots.plot_sweep(cols, sw.parameter.value, flight.lethal_radius, stage_dir)
    atomic_write_json(stage_dir / "sweep.json", out)
    return out
