"""The engagement: missile 6-DOF + fin actuators + autopilot + seeker + PN vs a turning aircraft.

Model and state are data (``FlightModel``, a NamedTuple of NamedTuples numba reads; the state a
flat vector with the named offsets below); the right-hand side :func:`derivative` is pure and is
the composition of separate blocks — target, seeker/guidance, air data, aerodynamics
(``flexnet_fe.flight.aero.loads``), autopilot, actuators, rigid body. Diagnostics are a separate
pure function (:func:`diagnostics`) whose values are named by :data:`DIAG_COLUMNS`. One numba
kernel (:func:`advance`) integrates with classical RK4 (all blocks are continuous-time, as in
Zarchan's simulations) until the first closest approach (range rate changes sign) or ``n_steps``.
Frames: ``flexnet_fe.flight``.

State vector s, shape (N_STATE,):
    POS 0:3 missile position in F [m]           VEL 3:6 velocity in F [m/s]
    QUAT 6:10 attitude quaternion B→F (w,x,y,z)  RATE 10:13 body rates p, q, r [rad/s]
    FIN 13:17 deflections of rudder_1..4 [rad]   FIN_RATE 17:21 their rates [rad/s]
    INTEG 21:23 three-loop integrators (pitch, yaw) [rad]   LOS 23:26 seeker LOS rate Ω_f in F [rad/s]

Fin actuators: δ̈ = ω_a² (sat(δ_c) − δ) − 2 ζ_a ω_a δ̇ with the rate held at ±rate limit and the
deflection at ±position limit (mechanical stops: after each step the states are put back on the
stop). These are the physical limits of the actuator, not numerical clamps.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from flexnet_fe.flight.aero import CoefficientScale, loads, supersonic_beta
from flexnet_fe.flight.airframe import Airframe
from flexnet_fe.flight.eom import euler_rates, quat_rate
from flexnet_fe.flight.guidance import closing_speed, first_order_lag_rate, los_rate, pn_command
from flexnet_fe.flight.target import level_turn
from flexnet_fe.frames import quat_to_matrix

POS, VEL, QUAT, RATE, FIN, FIN_RATE, INTEG, LOS = 0, 3, 6, 10, 13, 17, 21, 23
N_STATE = 26

DIAG_COLUMNS = (
    "target_x_m", "target_y_m", "target_z_m",
    "accel_cmd_y_mps2", "accel_cmd_z_mps2", "accel_y_mps2", "accel_z_mps2",
    "alpha_rad", "alpha_yaw_rad", "mach", "range_m", "closing_speed_mps",
    "fin_cmd_pitch_rad", "fin_cmd_yaw_rad", "fin_cmd_roll_rad", "roll_angle_rad",
)
"""Names (with units) of the values :func:`diagnostics` returns, in its order."""
N_DIAG = len(DIAG_COLUMNS)

STATUS_CLOSEST = 0
STATUS_T_END = 1
STATUS_NONFINITE = 2
STATUS_SUBSONIC = 3
STATUS_OUT_OF_AIR_TABLE = 4


class Guidance(NamedTuple):
    nav: float
    """navigation constant N [-]"""
    tau_s: float
    """seeker time constant [s]"""
    a_max: float
    """acceleration command limit [m/s²]"""
    gravity_comp: bool
    """add +g (up) to the command"""
    gravity: float
    """[m/s²]"""


class Gains(NamedTuple):
    """Fixed autopilot gains (three-loop pitch/yaw, PD roll), see flexnet_fe.flight.autopilot."""

    k_a: float
    omega_i: float
    k_r: float
    k_dc: float
    k_phi: float
    k_p: float


class Actuator(NamedTuple):
    omega: float
    """[rad/s]"""
    zeta: float
    max_deflection: float
    """[rad]"""
    max_rate: float
    """[rad/s]"""


class Target(NamedTuple):
    """Level-turning aircraft (flexnet_fe.flight.target), vectors in F, shape (3,)."""

    p0: np.ndarray
    forward: np.ndarray
    centre: np.ndarray
    speed: float
    omega: float
    t_start: float


class AirTable(NamedTuple):
    """ISA density [kg/m³] and speed of sound [m/s] at altitudes alt0 + k dalt [m]."""

    alt0: float
    dalt: float
    rho: np.ndarray
    sound: np.ndarray


class FlightModel(NamedTuple):
    airframe: Airframe
    scale: CoefficientScale
    guidance: Guidance
    gains: Gains
    actuator: Actuator
    target: Target
    air: AirTable
    alt0: float
    """altitude of y_F = 0 [m]"""


@njit(cache=True)
def _mat_vec(m, v):
    """m @ v for (3, 3) and (3,) without BLAS call overhead."""
    return np.array([m[0, 0] * v[0] + m[0, 1] * v[1] + m[0, 2] * v[2],
                     m[1, 0] * v[0] + m[1, 1] * v[1] + m[1, 2] * v[2],
                     m[2, 0] * v[0] + m[2, 1] * v[1] + m[2, 2] * v[2]])


@njit(cache=True)
def _mat_t_vec(m, v):
    """m.T @ v for (3, 3) and (3,)."""
    return np.array([m[0, 0] * v[0] + m[1, 0] * v[1] + m[2, 0] * v[2],
                     m[0, 1] * v[0] + m[1, 1] * v[1] + m[2, 1] * v[2],
                     m[0, 2] * v[0] + m[1, 2] * v[1] + m[2, 2] * v[2]])


@njit(cache=True)
def air_at(alt, air):
    """(ρ [kg/m³], a [m/s]) at altitude ``alt`` [m] by linear interpolation in the table (the
    kernel stops the run when the missile leaves it)."""
    n = air.rho.shape[0]
    x = (alt - air.alt0) / air.dalt
    i = min(max(int(math.floor(x)), 0), n - 2)
    f = x - i
    return air.rho[i] * (1 - f) + air.rho[i + 1] * f, air.sound[i] * (1 - f) + air.sound[i + 1] * f


@njit(cache=True)
def target_state(t, tg):
    """Aircraft position [m], velocity [m/s] in F at time t [s]."""
    p, v, _a = level_turn(t, tg.p0, tg.forward, tg.centre, tg.speed, tg.omega, tg.t_start)
    return p, v


@njit(cache=True)
def guidance_command(s, rot, pt, vt, gd):
    """(body normal command (y_b, z_b) [m/s²] limited to a_max, seeker rate dΩ_f/dt (3,), V_c [m/s]):
    true PN on the seeker-filtered LOS rate, + g up if compensated, rotated into body axes."""
    r = pt - s[POS:POS + 3]
    v = vt - s[VEL:VEL + 3]
    d_los = first_order_lag_rate(s[LOS:LOS + 3], los_rate(r, v), gd.tau_s)
    vc = closing_speed(r, v)
    a_cmd = pn_command(gd.nav, vc, s[LOS:LOS + 3], r)
    if gd.gravity_comp:
        a_cmd[1] += gd.gravity
    f_cmd = _mat_t_vec(rot, a_cmd)
    cy, cz = f_cmd[1], f_cmd[2]
    cmag = math.sqrt(cy * cy + cz * cz)
    if cmag > gd.a_max:
        cy *= gd.a_max / cmag
        cz *= gd.a_max / cmag
    return cy, cz, d_los, vc


@njit(cache=True)
def roll_angle(rot):
    """Roll φ [rad] of R = R_y(ψ) R_z(θ) R_x(φ) (flexnet_fe.flight)."""
    return math.atan2(-rot[1, 2], rot[1, 1])


@njit(cache=True)
def autopilot(accel_b, cmd_y, cmd_z, omega, integ, phi, g):
    """Three-loop pitch (rate ω_z) and yaw (rate −ω_y) and PD roll hold (Zarchan ch. 23).

    accel_b: aerodynamic specific force in body axes [m/s²] (3,) (accelerometer at the CG);
    cmd_y, cmd_z: commands [m/s²]; omega: body rates (3,); integ: integrators (2,); phi: roll [rad].
    Returns (d integ/dt (2,), fin commands of rudder_1..4 (4,), (pitch, yaw, roll) commands [rad])."""
    rate_p, rate_y = omega[2], -omega[1]
    d_integ = np.array([g.omega_i * (rate_p + g.k_a * (accel_b[1] - g.k_dc * cmd_y)),
                        g.omega_i * (rate_y + g.k_a * (accel_b[2] - g.k_dc * cmd_z))])
    dc_p = g.k_r * (integ[0] + rate_p)
    dc_y = g.k_r * (integ[1] + rate_y)
    dc_r = -(g.k_phi * phi + g.k_p * omega[0])
    # mixing (fins 0 top, 1 right, 2 bottom, 3 left; frame doc in flexnet_fe.flight)
    cmd = np.array([-dc_y + dc_r, dc_p + dc_r, dc_y + dc_r, -dc_p + dc_r])
    return d_integ, cmd, (dc_p, dc_y, dc_r)


@njit(cache=True)
def actuator_rates(delta, rate, cmd, act):
    """(dδ/dt, dδ̇/dt), each (4,): 2nd-order actuators against their rate and position stops."""
    d_delta, d_rate = np.empty(4), np.empty(4)
    for i in range(4):
        c = min(max(cmd[i], -act.max_deflection), act.max_deflection)
        acc = act.omega * act.omega * (c - delta[i]) - 2.0 * act.zeta * act.omega * rate[i]
        if (rate[i] >= act.max_rate and acc > 0) or (rate[i] <= -act.max_rate and acc < 0):
            acc = 0.0
        pos_rate = rate[i]
        if (delta[i] >= act.max_deflection and pos_rate > 0) or (delta[i] <= -act.max_deflection and pos_rate < 0):
            pos_rate = 0.0
        d_delta[i] = pos_rate
        d_rate[i] = acc
    return d_delta, d_rate


@njit(cache=True)
def air_data(s, rot, m):
    """(body velocity (3,) [m/s], q̄ [Pa], Mach, β_M) at the missile (β_M from max(M, M_min))."""
    rho, a_sound = air_at(m.alt0 + s[POS + 1], m.air)
    v_b = _mat_t_vec(rot, s[VEL:VEL + 3])
    speed = math.sqrt(v_b[0] * v_b[0] + v_b[1] * v_b[1] + v_b[2] * v_b[2])
    mach = speed / a_sound
    return v_b, 0.5 * rho * speed * speed, mach, supersonic_beta(max(mach, m.airframe.mach_min))


@njit(cache=True)
def derivative(t, s, m):
    """ṡ (N_STATE,) at time t [s] for model m (``FlightModel``); pure."""
    af = m.airframe
    q = s[QUAT:QUAT + 4] / math.sqrt(np.dot(s[QUAT:QUAT + 4], s[QUAT:QUAT + 4]))
    rot = quat_to_matrix(q)
    pt, vt = target_state(t, m.target)
    cy, cz, d_los, _vc = guidance_command(s, rot, pt, vt, m.guidance)
    v_b, qbar, _mach, beta_m = air_data(s, rot, m)
    omega = s[RATE:RATE + 3]
    force, moment = loads(af, m.scale, v_b, omega, s[FIN:FIN + 4], qbar, beta_m)
    accel_b = force / af.mass
    d_integ, cmd, _dc = autopilot(accel_b, cy, cz, omega, s[INTEG:INTEG + 2], roll_angle(rot), m.gains)
    d_delta, d_rate = actuator_rates(s[FIN:FIN + 4], s[FIN_RATE:FIN_RATE + 4], cmd, m.actuator)
    ds = np.empty(N_STATE)
    ds[POS:POS + 3] = s[VEL:VEL + 3]                                   # rigid body (flexnet_fe.flight.eom)
    ds[VEL:VEL + 3] = _mat_vec(rot, accel_b)
    ds[VEL + 1] -= m.guidance.gravity
    ds[QUAT:QUAT + 4] = quat_rate(s[QUAT:QUAT + 4], omega)
    ds[RATE:RATE + 3] = euler_rates(omega, af.inertia, moment)
    ds[FIN:FIN + 4] = d_delta
    ds[FIN_RATE:FIN_RATE + 4] = d_rate
    ds[INTEG:INTEG + 2] = d_integ
    ds[LOS:LOS + 3] = d_los
    return ds


@njit(cache=True)
def diagnostics(t, s, m):
    """The values named by :data:`DIAG_COLUMNS` at (t, s), shape (N_DIAG,); pure."""
    q = s[QUAT:QUAT + 4] / math.sqrt(np.dot(s[QUAT:QUAT + 4], s[QUAT:QUAT + 4]))
    rot = quat_to_matrix(q)
    pt, vt = target_state(t, m.target)
    cy, cz, _d, vc = guidance_command(s, rot, pt, vt, m.guidance)
    v_b, qbar, mach, beta_m = air_data(s, rot, m)
    force, _mom = loads(m.airframe, m.scale, v_b, s[RATE:RATE + 3], s[FIN:FIN + 4], qbar, beta_m)
    accel_b = force / m.airframe.mass
    phi = roll_angle(rot)
    _di, _cmd, dc = autopilot(accel_b, cy, cz, s[RATE:RATE + 3], s[INTEG:INTEG + 2], phi, m.gains)
    r = pt - s[POS:POS + 3]
    return np.array([pt[0], pt[1], pt[2], cy, cz, accel_b[1], accel_b[2],
                     math.atan2(-v_b[1], v_b[0]), math.atan2(-v_b[2], v_b[0]), mach,
                     math.sqrt(np.dot(r, r)), vc, dc[0], dc[1], dc[2], phi])


@njit(cache=True)
def _apply_stops(s, act):
    for i in range(4):
        if s[FIN + i] > act.max_deflection:
            s[FIN + i] = act.max_deflection
            s[FIN_RATE + i] = min(s[FIN_RATE + i], 0.0)
        elif s[FIN + i] < -act.max_deflection:
            s[FIN + i] = -act.max_deflection
            s[FIN_RATE + i] = max(s[FIN_RATE + i], 0.0)
        s[FIN_RATE + i] = min(max(s[FIN_RATE + i], -act.max_rate), act.max_rate)


@njit(cache=True)
def range_rate_sign(t, s, m):
    """r · ṙ of the aircraft relative to the missile [m²/s] (negative while closing)."""
    pt, vt = target_state(t, m.target)
    return np.dot(pt - s[POS:POS + 3], vt - s[VEL:VEL + 3])


@njit(cache=True)
def rk4_step(t, s, dt, m):
    """One classical RK4 step of :func:`derivative`, then the actuator stops."""
    k1 = derivative(t, s, m)
    k2 = derivative(t + 0.5 * dt, s + 0.5 * dt * k1, m)
    k3 = derivative(t + 0.5 * dt, s + 0.5 * dt * k2, m)
    k4 = derivative(t + dt, s + dt * k3, m)
    out = s + dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    _apply_stops(out, m.actuator)
    return out


@njit(cache=True)
def _status(t, s, m):
    if not np.all(np.isfinite(s)):
        return STATUS_NONFINITE
    alt = m.alt0 + s[POS + 1]
    if alt < m.air.alt0 or alt > m.air.alt0 + m.air.dalt * (m.air.rho.shape[0] - 1):
        return STATUS_OUT_OF_AIR_TABLE
    if math.sqrt(np.dot(s[VEL:VEL + 3], s[VEL:VEL + 3])) < m.airframe.mach_min * air_at(alt, m.air)[1]:
        return STATUS_SUBSONIC
    return STATUS_T_END


@njit(cache=True)
def advance(m, s0, dt, n_steps, every):
    """Advance from s0 (t = 0) with RK4 step dt [s] for at most n_steps, recording every
    ``every`` steps. Returns (times (k,), states (k, N_STATE), diags (k, N_DIAG), status, t_prev,
    s_prev, t_last, s_last); the last two steps bracket the closest approach when
    status == STATUS_CLOSEST. Stops with STATUS_SUBSONIC below the airframe's supersonic-edge Mach."""
    n_rec = n_steps // every + 2
    times, states, diags = np.empty(n_rec), np.empty((n_rec, N_STATE)), np.empty((n_rec, N_DIAG))
    s, s_prev, t, t_prev = s0.copy(), s0.copy(), 0.0, 0.0
    times[0], states[0], diags[0] = t, s, diagnostics(t, s, m)
    k = 1
    status = STATUS_T_END
    rdot_prev = range_rate_sign(t, s, m)
    for step in range(1, n_steps + 1):
        s_prev, t_prev = s, t
        s = rk4_step(t, s, dt, m)
        t = step * dt
        status = _status(t, s, m)
        if status == STATUS_NONFINITE or status == STATUS_OUT_OF_AIR_TABLE:
            break
        rdot = range_rate_sign(t, s, m)
        done = rdot_prev < 0.0 and rdot >= 0.0
        if done:
            status = STATUS_CLOSEST
        if step % every == 0 or done or status == STATUS_SUBSONIC:
            times[k], states[k], diags[k] = t, s, diagnostics(t, s, m)
            k += 1
        if done or status == STATUS_SUBSONIC:
            break
        rdot_prev = rdot
    return times[:k], states[:k], diags[:k], status, t_prev, s_prev, t, s
