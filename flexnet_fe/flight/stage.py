"""Flight stage: run the engagement of a ``[flight]`` table, write history/plots, summarise.

Public API:
    simulate_flight(flight, altitude_m, damage=None) -> FlightResult     (no files)
    run_flight(flight, altitude_m, stage_dir, log, shell_dir=None) -> dict (the stage)
    run_flight_sweep(flight, altitude_m, stage_dir, log) -> dict         (miss vs damage)
"""

from __future__ import annotations

import functools
import logging
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flexnet_fe.atmosphere import isa
from flexnet_fe.errors import FlexnetError, NumericalError
from flexnet_fe.flight import airframe as AF
from flexnet_fe.flight import simulate as S
from flexnet_fe.flight.aero import CoefficientScale, loads, supersonic_beta
from flexnet_fe.flight.autopilot import (
    ThreeLoopGains, linearize, loop_margins, loop_matrix, plane_derivatives, roll_gains, three_loop_gains)
from flexnet_fe.flight.config import (
    DamageConfig, DamageModel, FlightConfig, LaunchDirection, SweepParameter, TurnDirection, VerticalAxis)
from flexnet_fe.flight.damage import FinDamage, damage_from_shell
from flexnet_fe.flight.miss import closest_approach
from flexnet_fe.flight.target import level_turn, turn_rate
from flexnet_fe.io import atomic_write_json, write_history_csv
from flexnet_fe.missile.config import MissileConfig
from flexnet_fe.missile.build import build_missile
from flexnet_fe.frames import quat_from_matrix
from flexnet_fe.runs import HISTORY, SWEEP_TABLE

G0 = 9.80665
"""standard gravity [m/s²], used only to express accelerations in g for people"""
REPORT_RADII_M = (1.0, 5.0, 10.0)
AIR_TABLE_STEP_M = 100.0
"""ISA table spacing [m]: linear interpolation error ≈ h²/(8 H²) ≈ 2e-5 of ρ (scale height H ≈ 8 km)"""
AIR_TABLE_HALF_RANGE_M = 15000.0
"""the table spans the scene altitude ± this [m]; leaving it stops the run with an error"""


def case_to_flight_matrix(axis: VerticalAxis) -> np.ndarray:
    """M with v_F = M v_P (case frame P → flight frame F, module doc of flexnet_fe.flight)."""
    if axis is VerticalAxis.y:
        return np.eye(3)
    return np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])


def airframe_of(missile: MissileConfig | None) -> AF.Airframe:
    """The component airframe of the case's ``[missile]`` (the radar preset if the case has none)."""
    return AF.build_airframe(build_missile(missile or MissileConfig(preset="radar")))


def fin_damage(damage: DamageConfig) -> FinDamage:
    """Uniform damage of the ``[flight.damage]`` table: every wing keeps 1 − d, every rudder e."""
    return FinDamage.uniform(damage.wing_damage, damage.rudder_effectiveness)


def damaged_airframe(af: AF.Airframe, model: DamageModel, fins: FinDamage) -> tuple[AF.Airframe, CoefficientScale]:
    """(airframe, coefficient scale) for a damage ``model``: ``geometry`` removes each panel's
    lost share; the paper's readings keep the geometry and scale whole-airframe derivatives
    (lift × (1 − d), stability moment × (1 ± d), control × e; d, e the fin-set means)."""
    if model is DamageModel.geometry:
        return AF.damaged(af, fins.remaining), CoefficientScale(1.0, 1.0, 1.0)
    d, e = fins.wing_damage, fins.rudder_effectiveness
    k_mom = 1.0 + d if model is DamageModel.magnitude else 1.0 - d
    return af, CoefficientScale(1.0 - d, k_mom, e)


@functools.lru_cache(maxsize=16)
def air_table(altitude_m: float) -> S.AirTable:
    """ISA (``flexnet_fe.atmosphere.isa``) density and speed of sound tabulated every 100 m over
    ±15 km around the scene altitude (clipped to ISA's −5 km ... 80 km). Cached per altitude
    (≈ 300 ISA calls; the arrays are read-only)."""
    lo = max(altitude_m - AIR_TABLE_HALF_RANGE_M, -5000.0)
    hi = min(altitude_m + AIR_TABLE_HALF_RANGE_M, 80000.0)
    airs = [isa(h) for h in np.arange(lo, hi + 0.5 * AIR_TABLE_STEP_M, AIR_TABLE_STEP_M)]
    rho, sound = np.array([a.density for a in airs]), np.array([a.speed_of_sound for a in airs])
    rho.setflags(write=False)
    sound.setflags(write=False)
    return S.AirTable(float(lo), AIR_TABLE_STEP_M, rho, sound)


@dataclass(frozen=True)
class Autopilot:
    """Fixed autopilot gains (designed for the undamaged missile at launch) and the design's
    linear airframe and loop margins."""

    three_loop: ThreeLoopGains
    k_phi: float
    k_p: float
    design_alpha_rad: float
    linear: object
    """AirframeLinear of the design point"""
    margins: dict
    """loop_margins with the actuator"""
    l_p: float
    """roll damping L_p of the undamaged airframe [1/s]"""


def design_point(af: AF.Airframe, scale: CoefficientScale, flight: FlightConfig, rho: float, sound: float,
                 gravity: float, alpha: float | None = None):
    """(AirframeLinear, its incidence [rad], (L_p, L_δ) roll derivatives [1/s, 1/s² per rad]) of
    airframe ``af`` at the launch flight condition (speed ``flight.missile_speed``): at the trim of
    ``design_load_g``, or at incidence ``alpha`` if given (damaged airframe at the design point)."""
    v = flight.missile_speed
    mach = v / sound
    if mach < af.mach_min:
        raise NumericalError(f"launch Mach {mach:.2f} < {af.mach_min:.2f}: a fin leading edge is subsonic, "
                             "outside the airframe's linear supersonic panel theory")
    beta_m = supersonic_beta(mach)
    qbar = 0.5 * rho * v * v
    sl = AF.pitch_slopes(af, beta_m)
    sl = sl._replace(cn_alpha=sl.cn_alpha * scale.lift, cn_alpha2=sl.cn_alpha2 * scale.lift,
                     cm_alpha=sl.cm_alpha * scale.moment, cm_alpha2=sl.cm_alpha2 * scale.moment,
                     cn_delta=sl.cn_delta * scale.control, cm_delta=sl.cm_delta * scale.control)
    cn_trim = af.mass * gravity * flight.autopilot.design_load_g / (qbar * af.sref)
    der = plane_derivatives(sl, cn_trim, alpha)
    lin = linearize(der, qbar, v, af.mass, af.inertia[1], af.sref, af.dref)
    lin_alpha = der.alpha_trim
    vb, zero = np.array([v, 0.0, 0.0]), np.zeros(3)
    l_delta = loads(af, scale, vb, zero, np.ones(4), qbar, beta_m)[1][0] / af.inertia[0]
    l_p = loads(af, scale, vb, np.array([1.0, 0.0, 0.0]), np.zeros(4), qbar, beta_m)[1][0] / af.inertia[0]
    return lin, lin_alpha, (l_p, l_delta)


def design_autopilot(af: AF.Airframe, flight: FlightConfig, rho: float, sound: float, gravity: float) -> Autopilot:
    """Three-loop design at the launch flight condition of the undamaged airframe ``af``."""
    ap, act = flight.autopilot, flight.actuator
    lin, alpha_trim, (l_p, l_delta) = design_point(af, CoefficientScale(1.0, 1.0, 1.0), flight, rho, sound, gravity)
    if lin.m_alpha >= 0:
        raise FlexnetError(f"the undamaged airframe is statically unstable (M_alpha = {lin.m_alpha:.3g} 1/s^2): "
                           "the three-loop design needs M_alpha < 0 ([missile] CG aft of the centre of pressure)")
    gains = three_loop_gains(lin, flight.missile_speed, ap.crossover_rad_s, ap.damping, ap.time_constant_s)
    k_phi, k_p = roll_gains(l_p, l_delta, ap.roll_bandwidth_rad_s, ap.roll_damping)
    margins = loop_margins(lin, gains, flight.missile_speed, (act.natural_frequency_rad_s, act.damping))
    return Autopilot(gains, k_phi, k_p, alpha_trim, lin, margins, l_p)


def initial_geometry(flight: FlightConfig, gravity: float):
    """(Target, missile state s0 (N_STATE,)) in F."""
    m = case_to_flight_matrix(flight.vertical_axis)
    pt0 = m @ np.asarray(flight.target_position, dtype=float)
    fwd = m @ np.asarray(flight.target_direction, dtype=float)
    fwd /= np.linalg.norm(fwd)
    up = np.array([0.0, 1.0, 0.0])
    left = np.cross(up, fwd)                       # facing fwd with y up, up × fwd points left
    centre = left if flight.turn_direction is TurnDirection.left else -left
    omega_t = turn_rate(flight.target_speed, flight.target_load_factor, gravity)
    tgt = S.Target(pt0, fwd, centre, float(flight.target_speed), float(omega_t), float(flight.maneuver_start))
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
    s0 = np.zeros(S.N_STATE)
    s0[S.POS:S.POS + 3] = pm0
    s0[S.VEL:S.VEL + 3] = flight.missile_speed * d
    s0[S.QUAT:S.QUAT + 4] = quat_from_matrix(np.column_stack([d, yb, zb]))
    r, v = pt0 - pm0, flight.target_speed * fwd - s0[S.VEL:S.VEL + 3]
    s0[S.LOS:S.LOS + 3] = np.cross(r, v) / np.dot(r, r)      # seeker filter starts on the true LOS rate
    return tgt, s0


def flight_model(flight: FlightConfig, af: AF.Airframe, scale: CoefficientScale, ap: Autopilot,
                 target: S.Target, gravity: float, altitude_m: float) -> S.FlightModel:
    """The kernel's model (data only)."""
    g3, act = ap.three_loop, flight.actuator
    return S.FlightModel(
        airframe=af, scale=scale,
        guidance=S.Guidance(flight.navigation_constant, flight.seeker.time_constant_s,
                            flight.autopilot.max_accel_command_g * G0, flight.autopilot.gravity_compensation, gravity),
        gains=S.Gains(g3.k_a, g3.omega_i, g3.k_r, g3.k_dc, ap.k_phi, ap.k_p),
        actuator=S.Actuator(act.natural_frequency_rad_s, act.damping, math.radians(act.max_deflection_deg),
                            math.radians(act.max_rate_deg_s)),
        target=target, air=air_table(altitude_m), alt0=float(altitude_m))


def critical_step(flight: FlightConfig, ap: Autopilot) -> float:
    """RK4 stability limit |λ| dt ≤ 2.78 on the fastest known linear mode: actuator (ω_a),
    seeker lag (1/τ_s), airframe short period (ω_af), three-loop crossover (ω_cr), roll damping
    (|L_p|) and roll loop [s]."""
    lam = max(flight.actuator.natural_frequency_rad_s, 1.0 / flight.seeker.time_constant_s,
              ap.linear.omega_af, flight.autopilot.crossover_rad_s, abs(ap.l_p),
              flight.autopilot.roll_bandwidth_rad_s)
    return 2.78 / lam


@dataclass(frozen=True)
class FlightResult:
    """One engagement. Arrays in the flight frame F; states as flexnet_fe.flight.simulate."""

    times: np.ndarray
    """[s], shape (m,)"""
    states: np.ndarray
    """shape (m, N_STATE)"""
    diag: dict
    """name (simulate.DIAG_COLUMNS) → values, each shape (m,)"""
    closest_approach_found: bool
    miss_distance_m: float
    """at the closest approach; else the smallest sampled range"""
    time_of_closest_approach_s: float
    end_reason: str
    """why the engagement ended (closest approach, t_end, Mach below the aero model's range)"""
    autopilot: Autopilot
    fins: FinDamage
    model: DamageModel
    airframe: dict
    """static margin, C_Nα, centre of pressure of the undamaged and flown airframe (launch Mach)"""
    damaged_loop_poles: np.ndarray
    """eigenvalues of the flown (damaged) airframe's pitch loop with the fixed gains and the
    actuator at the launch condition [1/s], shape (5,)"""
    dt_s: float
    dt_crit_s: float
    steps: int
    kernel_wall_s: float


def airframe_facts(af: AF.Airframe, beta_m: float) -> dict:
    """Static margin [calibres], C_Nα [1/rad], centre of pressure station [m] at β_M (linear)."""
    sl = AF.pitch_slopes(af, beta_m)
    return {"static_margin_cal": AF.static_margin(af, beta_m), "cn_alpha_per_rad": sl.cn_alpha,
            "cm_alpha_per_rad": sl.cm_alpha, "cm_q": sl.cm_q, "cn_delta_per_rad": sl.cn_delta,
            "centre_of_pressure_m": AF.centre_of_pressure(af, beta_m), "cg_m": af.s_cg}


def simulate_flight(flight: FlightConfig, altitude_m: float, missile: MissileConfig | None = None,
                    damage: DamageConfig | None = None, fins: FinDamage | None = None) -> FlightResult:
    """Run one engagement (no files) of the case's ``missile`` (radar preset if None).
    ``damage`` overrides ``flight.damage`` (sweeps); ``fins`` (per-fin remaining shares, e.g. from
    the shell stage) overrides its uniform wing_damage / rudder_effectiveness."""
    damage = damage or flight.damage
    fins = fins or fin_damage(damage)
    af0 = airframe_of(missile)
    air0 = isa(altitude_m)
    m_alt = altitude_m + (case_to_flight_matrix(flight.vertical_axis) @ np.asarray(flight.missile_position))[1]
    air_m = isa(m_alt)
    ap = design_autopilot(af0, flight, air_m.density, air_m.speed_of_sound, air0.gravity)
    dt_crit = critical_step(flight, ap)
    if flight.dt > dt_crit:
        raise NumericalError(f"flight.dt = {flight.dt:.3g} s exceeds the RK4 stability limit "
                             f"dt_crit = {dt_crit:.3g} s of the fastest loop")
    af, scale = damaged_airframe(af0, damage.model, fins)
    lin_d, _a, _roll = design_point(af, scale, flight, air_m.density, air_m.speed_of_sound, air0.gravity,
                                    alpha=ap.design_alpha_rad)
    act = (flight.actuator.natural_frequency_rad_s, flight.actuator.damping)
    poles = np.linalg.eigvals(loop_matrix(lin_d, ap.three_loop, flight.missile_speed, act))
    beta0 = supersonic_beta(flight.missile_speed / air_m.speed_of_sound)
    facts = {"undamaged": airframe_facts(af0, beta0), "flown": airframe_facts(af, beta0)}
    target, s0 = initial_geometry(flight, air0.gravity)
    model = flight_model(flight, af, scale, ap, target, air0.gravity, altitude_m)
    n_steps = int(math.ceil(flight.t_end / flight.dt))
    every = max(1, int(round(flight.output_dt / flight.dt)))
    t0 = time.perf_counter()
    times, states, diags, status, t_a, s_a, t_b, s_b = S.advance(model, s0, flight.dt, n_steps, every)
    wall = time.perf_counter() - t0
    if status == S.STATUS_NONFINITE:
        raise NumericalError(f"flight state became non-finite at t = {t_b:.4f} s (dt = {flight.dt:.3g} s, "
                             f"dt_crit = {dt_crit:.3g} s)")
    if status == S.STATUS_OUT_OF_AIR_TABLE:
        raise NumericalError(f"missile left the tabulated altitude band (scene altitude ± "
                             f"{AIR_TABLE_HALF_RANGE_M:.0f} m) at t = {t_b:.3f} s")
    end_reason = {S.STATUS_CLOSEST: "closest approach", S.STATUS_T_END: f"t_end = {flight.t_end:g} s reached",
                  S.STATUS_SUBSONIC: f"Mach fell below {af.mach_min:.2f} at t = {t_b:.3f} s (a fin leading edge turns "
                                     "subsonic: outside the supersonic panel theory; the missile has lost its "
                                     "speed and cannot reach the target)"}[status]
    diag = dict(zip(S.DIAG_COLUMNS, diags.T))
    found = status == S.STATUS_CLOSEST
    if found:
        rel = []
        for t, s in ((t_a, s_a), (t_b, s_b)):
            pt, vt = S.target_state(t, target)
            rel.append((pt - s[S.POS:S.POS + 3], vt - s[S.VEL:S.VEL + 3]))
        t_ca, miss = closest_approach(t_a, rel[0][0], rel[0][1], t_b, rel[1][0], rel[1][1])
    else:  # no closest approach before t_end: report the smallest sampled range
        i = int(np.argmin(diag["range_m"]))
        t_ca, miss = float(times[i]), float(diag["range_m"][i])
    return FlightResult(times, states, diag, found, miss, t_ca, end_reason, ap, fins, damage.model, facts, poles,
                        flight.dt, dt_crit, int(round(t_b / flight.dt)), wall)


def euler_angles(states: np.ndarray) -> np.ndarray:
    """(yaw ψ, pitch θ, roll φ) [rad], shape (m, 3), for R = R_y(ψ) R_z(θ) R_x(φ) (flexnet_fe.flight)."""
    q = states[:, S.QUAT:S.QUAT + 4] / np.linalg.norm(states[:, S.QUAT:S.QUAT + 4], axis=1)[:, None]
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
    pm = res.states[:, S.POS:S.POS + 3] @ m_inv.T
    pt = np.column_stack([res.diag["target_x_m"], res.diag["target_y_m"], res.diag["target_z_m"]]) @ m_inv.T
    vm = res.states[:, S.VEL:S.VEL + 3] @ m_inv.T
    eul = euler_angles(res.states)
    cols = {"t_s": res.times,
            "missile_x_m": pm[:, 0], "missile_y_m": pm[:, 1], "missile_z_m": pm[:, 2],
            "missile_vx_mps": vm[:, 0], "missile_vy_mps": vm[:, 1], "missile_vz_mps": vm[:, 2],
            "target_x_m": pt[:, 0], "target_y_m": pt[:, 1], "target_z_m": pt[:, 2],
            "yaw_rad": eul[:, 0], "pitch_rad": eul[:, 1], "roll_rad": eul[:, 2],
            "p_radps": res.states[:, S.RATE], "q_radps": res.states[:, S.RATE + 1],
            "r_radps": res.states[:, S.RATE + 2]}
    for i in range(4):
        cols[f"fin{i}_rad"] = res.states[:, S.FIN + i]
    cols.update({k: v for k, v in res.diag.items() if not k.startswith("target_")})
    return cols


def _finite(x: float):
    return float(x) if math.isfinite(x) else None


def flight_summary(res: FlightResult, flight: FlightConfig) -> dict:
    """The ``flight`` section of summary.json. Achieved acceleration = the aerodynamic specific
    force normal to the missile axis (what the accelerometer at the CG measures)."""
    acc = np.hypot(res.diag["accel_y_mps2"], res.diag["accel_z_mps2"])
    alpha_t = np.hypot(res.diag["alpha_rad"], res.diag["alpha_yaw_rad"])
    ap = res.autopilot
    return {
        "miss_distance_m": res.miss_distance_m,
        "hit": bool(res.closest_approach_found and res.miss_distance_m <= flight.lethal_radius),
        "lethal_radius_m": flight.lethal_radius,
        "hit_within_m": {f"{r:g}": bool(res.closest_approach_found and res.miss_distance_m <= r)
                         for r in REPORT_RADII_M},
        "closest_approach_found": res.closest_approach_found,
        "end_reason": res.end_reason,
        "time_of_closest_approach_s": res.time_of_closest_approach_s,
        "max_achieved_accel_g": float(acc.max() / G0),
        "max_total_incidence_deg": float(np.degrees(alpha_t.max())),
        "max_fin_deflection_deg": float(np.degrees(np.abs(res.states[:, S.FIN:S.FIN + 4]).max())),
        "damage_model": res.model.value,
        "wing_damage": res.fins.wing_damage,
        "rudder_effectiveness": res.fins.rudder_effectiveness,
        "fin_remaining": dict(zip(FinDamage.NAMES, map(float, res.fins.remaining))),
        "airframe": res.airframe,
        "damaged_loop_poles": [[float(p.real), float(p.imag)] for p in res.damaged_loop_poles],
        "autopilot": {"k_a_s_per_m": ap.three_loop.k_a, "omega_i_radps": ap.three_loop.omega_i,
                      "k_r_s": ap.three_loop.k_r, "k_dc": ap.three_loop.k_dc,
                      "k_phi": ap.k_phi, "k_p_s": ap.k_p, "design_alpha_deg": math.degrees(ap.design_alpha_rad),
                      "airframe_omega_radps": _finite(ap.linear.omega_af), "airframe_zeta": _finite(ap.linear.zeta_af),
                      **{k: _finite(v) for k, v in ap.margins.items()}},
        "steps": res.steps,
        "dt_s": res.dt_s,
        "dt_crit_s": res.dt_crit_s,
        "ns_per_step": 1e9 * res.kernel_wall_s / max(res.steps, 1),
    }


def run_flight(flight: FlightConfig, altitude_m: float, stage_dir: Path, log: logging.Logger,
               shell_dir: Path | None = None, missile: MissileConfig | None = None) -> dict:
    """The flight stage: nominal engagement (history.csv, plots) and, if ``flight.sweep`` is set,
    the sweep (sweep.csv, miss-vs-damage plot). Returns the ``flight`` section of summary.json.

    ``missile``: the case's ``[missile]`` (airframe geometry and mass; radar preset if None).
    With ``flight.damage_from_shell``, ``shell_dir`` (the shell stage's output folder, next to the
    run's summary.json) sets each fin's remaining share (flexnet_fe.flight.damage)."""
    from flexnet_fe.flight import plots

    t0 = time.perf_counter()
    stage_dir = Path(stage_dir)
    fins, link = None, None
    if flight.damage_from_shell:
        if shell_dir is None:
            raise FlexnetError("flight.damage_from_shell = true needs the shell stage's results")
        mcfg = missile or MissileConfig(preset="radar")
        fins, link = damage_from_shell(shell_dir, flight.damage_law, mcfg.material)
        log.info("flight: damage from the shell stage (%s, allowable %s Pa): remaining %s",
                 flight.damage_law.law.value, link["allowable_pa"], link["remaining"])
    res = simulate_flight(flight, altitude_m, missile, fins=fins)
    summary = flight_summary(res, flight)
    warnings = []
    if link is not None:
        summary["damage_from_shell"] = link
    log.info("flight: dt = %.3g s (dt_crit %.3g s), %d steps, %.0f ns/step", res.dt_s, res.dt_crit_s,
             res.steps, summary["ns_per_step"])
    log.info("flight: miss %.3f m at t = %.3f s (%s, lethal radius %.1f m), max accel %.1f g, max incidence %.1f deg",
             res.miss_distance_m, res.time_of_closest_approach_s, "hit" if summary["hit"] else "miss",
             flight.lethal_radius, summary["max_achieved_accel_g"], summary["max_total_incidence_deg"])
    if not res.closest_approach_found:
        warnings.append(f"flight: no closest approach: {res.end_reason}; miss_distance_m is the smallest range flown")
        log.warning(warnings[-1])
    if summary["max_total_incidence_deg"] > 30.0:
        warnings.append(f"flight: total incidence reached {summary['max_total_incidence_deg']:.0f} deg, beyond the "
                        "linear aerodynamics' range; the trajectory after that is qualitative")
        log.warning(warnings[-1])
    cols = history_columns(res, flight)
    write_history_csv(stage_dir / HISTORY, cols)
    plots.plot_engagement(cols, flight, stage_dir)
    if flight.sweep is not None:
        summary["sweep"] = run_flight_sweep(flight, altitude_m, stage_dir, log, missile)
    if warnings:
        summary["warnings"] = warnings
    summary["wall_s"] = time.perf_counter() - t0
    return summary


def first_miss_value(values, misses, radius: float):
    """The first swept value (listed from undamaged to damaged) whose miss exceeds ``radius``
    [m] (∞ = diverged counts as a miss), or None if every point hits."""
    return next((v for v, mm in zip(values, misses) if not mm <= radius), None)


def run_flight_sweep(flight: FlightConfig, altitude_m: float, stage_dir: Path, log: logging.Logger,
                     missile: MissileConfig | None = None) -> dict:
    """Miss distance vs ``flight.sweep`` values for every damage model (geometry and the paper's
    two coefficient readings); writes sweep.csv, sweep.json and flight_miss_vs_damage.png. The
    threshold is the first swept value (values are listed from undamaged to damaged) whose miss
    exceeds the lethal radius (also given for 1, 5, 10 m). A point whose integration fails
    (NumericalError, e.g. the damaged missile slows below the aero model's Mach range) is logged
    as a warning and counted as a miss (∞ in sweep.csv)."""
    from flexnet_fe.flight import plots

    sw = flight.sweep
    if sw is None:
        raise ValueError("flight.sweep is not set")
    cols: dict[str, list[float]] = {"value": list(sw.values)}
    out: dict = {"parameter": sw.parameter.value, "values": list(sw.values), "lethal_radius_m": flight.lethal_radius}
    for model in DamageModel:
        misses = []
        for v in sw.values:
            dmg = flight.damage.model_copy(update={"model": model, sw.parameter.value: v})
            try:
                r = simulate_flight(flight, altitude_m, missile, dmg)
                miss = r.miss_distance_m if r.closest_approach_found else math.inf
            except NumericalError as err:  # a diverging damaged missile is a miss; say so in the log
                log.warning("sweep %s=%g (%s): %s", sw.parameter.value, v, model.value, err)
                miss = math.inf
            misses.append(miss)
        suffix = f"_{model.value}"
        cols[f"miss_m{suffix}"] = misses
        out[f"miss_m{suffix}"] = [mm if math.isfinite(mm) else None for mm in misses]
        out[f"threshold{suffix}"] = first_miss_value(sw.values, misses, flight.lethal_radius)
        out[f"threshold_by_radius{suffix}"] = {
            f"{r:g}": first_miss_value(sw.values, misses, r) for r in REPORT_RADII_M}
        log.info("sweep %s (%s): misses %s m; first miss at %s", sw.parameter.value, model.value,
                 ", ".join(f"{m:.2f}" for m in misses), out[f"threshold{suffix}"])
    write_history_csv(stage_dir / SWEEP_TABLE, {k: np.asarray(v, dtype=float) for k, v in cols.items()})
    plots.plot_sweep(cols, sw.parameter.value, flight.lethal_radius, stage_dir)
    atomic_write_json(stage_dir / "sweep.json", out)
    return out
