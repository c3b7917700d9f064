"""The deploy stage: open a traction or rotary net in the air (paper §III, §V-B).

``run_deploy`` builds the net, chooses the time step from physics, advances the compiled
kernel one output interval per call, and writes into ``stage_dir``:

- ``history.csv``: one row per output time (float64, units in the column names);
- ``snapshots/net_*.vtu`` + ``net.pvd``: the net as a line mesh (ParaView / PyVista);
- ``deploy.png``: plots like the paper's Fig. 7 (traction) or Fig. 9 (rotary) above the net at
  eight instants, like its Fig. 6 / Fig. 8 (one figure: ``net.plots``);
- ``net_state.npz`` (allow_pickle=False): the state at maximum area (``t``, ``x``, ``v``,
  ``hub``, ``wrap``) plus the topology arrays, for the collision stage.
"""

from __future__ import annotations

import logging
import math
import time
from pathlib import Path

import numpy as np

from flexnet_fe.atmosphere import Air
from flexnet_fe.errors import NumericalError
from flexnet_fe.io import write_history_csv
from flexnet_fe.net.area import loop_area, raster_area
from flexnet_fe.net.config import DeployConfig, RotaryNet, TractionNet
from flexnet_fe.net.plots import plot_deployment
from flexnet_fe.net.snapshots import write_pvd, write_vtu
from flexnet_fe.net.state import (Environment, NetState, energies, evaluate_tensions, initial_state,
                                  step_many)
from flexnet_fe.net.timestep import choose_time_step, drag_limit
from flexnet_fe.net.topology import NetModel, build_net
from flexnet_fe.progress import progress_bar
from flexnet_fe.runs import HISTORY, NET_PVD, NET_STATE


def net_area(model: NetModel, x: np.ndarray, pixel: float) -> float:
    """Net area [m^2] (``flexnet_fe.net.area``): union of the cells projected on x–y."""
    return float(raster_area(np.ascontiguousarray(x[:, :2]), model.cells, pixel))


def _local_maxima(x: np.ndarray) -> list[int]:
    """Interior local maxima of x as ``scipy.signal.find_peaks`` finds them: a strict rise,
    then a flat top (possibly one sample), then a strict fall; the index is the middle of the
    top (rounded down)."""
    peaks, i, n = [], 1, len(x)
    while i < n - 1:
        if x[i - 1] < x[i]:
            ahead = i + 1
            while ahead < n - 1 and x[ahead] == x[i]:
                ahead += 1
            if x[ahead] < x[i]:
                peaks.append((i + ahead - 1) // 2)
                i = ahead
        i += 1
    return peaks


def _prominence(x: np.ndarray, p: int) -> float:
    """Topographic prominence of the peak at p (``scipy.signal.peak_prominences``, no window):
    x[p] minus the higher of the lowest values on each side before a higher sample."""
    left = right = x[p]
    i = p
    while i >= 0 and x[i] <= x[p]:
        left = min(left, x[i])
        i -= 1
    i = p
    while i < len(x) and x[i] <= x[p]:
        right = min(right, x[i])
        i += 1
    return float(x[p] - max(left, right))


def area_peaks(area: np.ndarray) -> np.ndarray:
    """Indices of the maxima of the area history whose prominence is at least 5 % of its range
    (``scipy.signal.find_peaks(area, prominence=0.05 * range)``, written out: importing
    scipy.signal costs 0.5–1.7 s, several times the deploy kernel; tests/net checks the two agree)."""
    rng = float(area.max() - area.min())
    if rng <= 0.0:
        return np.zeros(0, dtype=int)
    x = np.asarray(area, dtype=float)
    return np.array([p for p in _local_maxima(x) if _prominence(x, p) >= 0.05 * rng], dtype=np.int64)


def find_period(t: np.ndarray, area: np.ndarray) -> float | None:
    """Open/contract period [s]: time between the first two maxima of the area whose
    prominence exceeds 5 % of the area's range; None if fewer than two are simulated."""
    peaks = area_peaks(area)
    return float(t[peaks[1]] - t[peaks[0]]) if len(peaks) >= 2 else None


def hub_nodes_inside(model: NetModel, state: NetState) -> np.ndarray:
    """Warps whose first node is inside the hub cylinder (projected within the rim and within
    H/2 of the hub plane), shape (k,) int. Net–hub contact is not modelled: such a node passes
    through the hub, and its link keeps its wound angle while inside (``hub.wrap_geometry``)."""
    j = model.springs[model.hub_link, 1]
    d = state.x[j] - state.x[model.hub_node]
    inside = (np.hypot(d[:, 0], d[:, 1]) <= model.hub_radius) & (np.abs(d[:, 2]) <= 0.5 * model.hub_length)
    return np.flatnonzero(inside)


HISTORY_COLUMNS = (
    "t_s", "area_m2", "area_loop_m2", "mass_speed_rel_mps", "mass_speed_mps", "max_tension_n",
    "mass_rope_tension_n", "peak_tension_interval_n", "hub_spin_radps", "hub_wrap_max_rad", "com_speed_z_mps",
    "kinetic_energy_rel_j", "elastic_energy_j", "dissipated_rope_j", "air_work_rel_j", "dt_s", "dt_drag_limit_s",
    "drag_number")
"""Columns of the deploy ``history.csv`` (units in the names)."""


class _Recorder:
    """One history row per output time, the VTU snapshots, the shapes for ``deploy.png`` and
    the state at maximum area."""

    def __init__(self, model: NetModel, env: Environment, deploy: DeployConfig, snap_dir: Path, n_out: int):
        self.model, self.env, self.deploy, self.snap_dir = model, env, deploy, snap_dir
        self.cols = {k: np.zeros(n_out + 1) for k in HISTORY_COLUMNS}
        self.snaps: list[tuple[float, str]] = []
        self.shapes: list[tuple[float, np.ndarray]] = []
        self.best = {"area": -1.0}
        self.snap_every = max(1, int(round(deploy.snapshot_interval / deploy.output_interval)))
        self.shape_ks = set(np.linspace(0, n_out, 8).round().astype(int).tolist())
        # segments that end on a corner / tip mass (the ropes pulling the masses back)
        self.at_mass = np.isin(model.springs, model.mass_nodes).any(axis=1)
        self.clock = {"kernel": 0.0, "area": 0.0, "snapshots": 0.0, "record_other": 0.0}  # wall [s]

    def record(self, k: int, state: NetState, peak: float) -> None:
        """Row ``k`` from ``state``; ``peak`` [N] the largest tension of the interval ending here."""
        model, cols = self.model, self.cols
        w0 = time.perf_counter()
        evaluate_tensions(model, state, self.env)  # at this row's state (the kernel's are a step old)
        x, v = state.x, state.v
        mtot = model.mass.sum()
        vcom = (model.mass[:, None] * v).sum(axis=0) / mtot
        mv = v[model.mass_nodes]
        cols["t_s"][k] = state.t
        w1 = time.perf_counter()
        area = net_area(model, x, self.deploy.area_pixel)
        w2 = time.perf_counter()
        cols["area_m2"][k] = area
        cols["area_loop_m2"][k] = loop_area(x[:, :2], model.boundary_loop)
        cols["mass_speed_rel_mps"][k] = float(np.linalg.norm(mv - vcom, axis=1).mean())
        cols["mass_speed_mps"][k] = float(np.linalg.norm(mv, axis=1).mean())
        cols["max_tension_n"][k] = float(state.tension.max())
        cols["mass_rope_tension_n"][k] = float(state.tension[self.at_mass].mean())
        cols["peak_tension_interval_n"][k] = peak
        cols["hub_spin_radps"][k] = state.hub[1] if model.hub_node >= 0 else 0.0
        cols["hub_wrap_max_rad"][k] = float(np.abs(state.wrap).max())
        cols["com_speed_z_mps"][k] = vcom[2]
        e = energies(model, state)
        cols["kinetic_energy_rel_j"][k] = e["kinetic"] - 0.5 * mtot * float(vcom @ vcom)  # about the CoM
        cols["elastic_energy_j"][k] = e["elastic"]
        cols["dissipated_rope_j"][k] = state.losses[0]  # since t = 0 (net.kernels.advance)
        cols["air_work_rel_j"][k] = state.losses[1]
        cols["dt_drag_limit_s"][k] = drag_limit(model, x, v, self.env.rho)
        if k in self.shape_ks:
            self.shapes.append((state.t, x[:, :2].copy()))
        if area > self.best["area"]:
            self.best.update(area=area, t=state.t, x=x.copy(), v=v.copy(), hub=state.hub.copy(),
                             wrap=state.wrap.copy())
        w3 = time.perf_counter()
        if k % self.snap_every == 0:
            name = f"net_{k // self.snap_every:05d}.vtu"
            write_vtu(self.snap_dir / name, x, v, model.springs, state.tension)
            self.snaps.append((state.t, f"snapshots/{name}"))
        clock = self.clock
        clock["area"] += w2 - w1
        clock["snapshots"] += time.perf_counter() - w3
        clock["record_other"] += (w1 - w0) + (w3 - w2)


def _setup(net: TractionNet | RotaryNet, deploy: DeployConfig, air: Air, log: logging.Logger):
    """The model, its t = 0 state, the loads and the time-step choice; logs them.
    Returns (model, state, env, ts, flight speed [m/s])."""
    model = build_net(net)
    speed = deploy.mach * air.speed_of_sound
    state = initial_state(model, (0.0, 0.0, speed))
    rho = air.density if deploy.air else 0.0
    env = Environment(gravity=np.array([0.0, -air.gravity if deploy.gravity else 0.0, 0.0]),
                      rho=rho, wind=np.zeros(3), air=deploy.air)
    ts = choose_time_step(model, state.x, state.v, rho, deploy.safety_factor, deploy.time_step)
    log.info("net %s: %d nodes, %d segments, net mass %.4g kg", model.kind, model.n_nodes,
             model.n_springs, float(model.mass.sum()))
    log.info("air %s (rho = %.4g kg/m^3 at %.0f m), gravity %s, flight speed %.1f m/s (Mach %.2f)",
             "on" if deploy.air else "off", air.density, air.altitude, "on" if deploy.gravity else "off",
             speed, deploy.mach)
    log.info("time step at t = 0: %.4g s (%s; spring limit %.4g s, drag limit %.4g s, safety %.2f); "
             "re-derived from the drag limit of the current state every output interval %.4g s",
             ts.dt, "forced" if ts.forced else "from physics", ts.spring_limit, ts.drag_limit,
             deploy.safety_factor, deploy.output_interval)
    return model, state, env, ts, speed


def _substeps(ts, deploy: DeployConfig, drag_lim: float, t: float) -> tuple[int, float]:
    """(steps in the next output interval, stability limit [s]): the spring limit is fixed
    (linear ropes), the drag limit ``drag_lim`` [s] follows the state at ``t`` [s]. A forced
    step above the limit raises."""
    lim = min(ts.spring_limit, drag_lim)
    if ts.forced:
        if ts.dt > lim:
            raise NumericalError(
                f"forced time step dt = {ts.dt:.4g} s exceeds the stability limit "
                f"{lim:.4g} s at t = {t:.4g} s (springs {ts.spring_limit:.4g} s, drag "
                f"{drag_lim:.4g} s)")
        return int(math.ceil(deploy.output_interval / ts.dt - 1e-9)), lim
    return int(math.ceil(deploy.output_interval / (deploy.safety_factor * lim))), lim


def _march(model: NetModel, state: NetState, ts, deploy: DeployConfig, rec: _Recorder,
           log: logging.Logger) -> int:
    """Advance through every output interval, recording each; returns the number of steps."""
    n_out = len(rec.cols["t_s"]) - 1
    cols = rec.cols
    cols["dt_s"][0] = ts.dt
    rec.record(0, state, 0.0)
    steps = 0
    warned_inside = False
    with progress_bar(n_out, f"deploy {model.kind}") as bar:
        for k in range(1, n_out + 1):
            sub, lim = _substeps(ts, deploy, cols["dt_drag_limit_s"][k - 1], state.t)
            dt = deploy.output_interval / sub  # outputs fall on steps; dt <= safety × limit
            w0 = time.perf_counter()
            peak, drag_number = step_many(model, state, rec.env, dt, sub, lim)
            rec.clock["kernel"] += time.perf_counter() - w0
            steps += sub
            state.t = k * deploy.output_interval  # remove round-off drift of the summed steps
            if drag_number > 2.0:
                raise NumericalError(
                    f"drag time scale fell below the time step during t <= {state.t:.4g} s: "
                    f"λ·dt = {drag_number:.3g} > 2 with dt = {dt:.4g} s (lower safety_factor)")
            if model.hub_node >= 0 and not warned_inside:
                inside = hub_nodes_inside(model, state)
                if len(inside):
                    warned_inside = True
                    log.warning("t = %.4g s: the first node of warp(s) %s is inside the hub (net-hub "
                                "contact is not modelled; reported once)", state.t, inside.tolist())
            cols["dt_s"][k] = dt
            cols["drag_number"][k] = drag_number
            rec.record(k, state, peak)
            bar.update(1)
    return steps


def write_net_state(path: Path, model: NetModel, best: dict) -> None:
    """``net_state.npz`` (allow_pickle=False): the state ``best`` (t, x, v, hub, wrap) plus the
    topology arrays, for the collision stage."""
    np.savez(path, kind=np.array(model.kind), t=best["t"], x=best["x"],
             v=best["v"], hub=best["hub"], wrap=best["wrap"], mass=model.mass, springs=model.springs,
             rest_length=model.rest_length, stiffness_ea=model.stiffness_ea,
             damping=model.damping, slack_offset=model.slack_offset, diameter=model.diameter,
             drag_free=model.drag_free, mass_nodes=model.mass_nodes, cells=model.cells,
             hub_link=model.hub_link, anchor_angle=model.anchor_angle,
             hub_node=model.hub_node, hub_radius=model.hub_radius, hub_length=model.hub_length,
             hub_inertia=model.hub_inertia)


def _summary(cols: dict, model: NetModel, ts, deploy: DeployConfig, air: Air, speed: float, steps: int) -> dict:
    """The ``deploy`` summary section from the history columns (SI units)."""
    i_max = int(np.argmax(cols["area_m2"]))
    peaks = area_peaks(cols["area_m2"])
    i_first = int(peaks[0]) if len(peaks) else i_max
    return {
        "max_area_m2": float(cols["area_m2"][i_max]),
        "time_to_max_area_s": float(cols["t_s"][i_max]),
        "first_max_area_m2": float(cols["area_m2"][i_first]),
        "time_to_first_max_area_s": float(cols["t_s"][i_first]),
        "initial_area_m2": float(cols["area_m2"][0]),
        "period_s": find_period(cols["t_s"], cols["area_m2"]),
        "max_tension_n": float(cols["peak_tension_interval_n"].max()),
        "steps": steps,
        "dt_s": float(cols["dt_s"][1:].min()),
        "dt_max_s": float(cols["dt_s"][1:].max()),
        "dt_spring_limit_s": ts.spring_limit,
        "dt_drag_limit_min_s": (float(cols["dt_drag_limit_s"].min()) if deploy.air else None),
        "nodes": model.n_nodes,
        "segments": model.n_springs,
        "net_mass_kg": float(model.mass.sum()),
        "area_pixel_m": deploy.area_pixel,
        "air": {"on": deploy.air, "altitude_m": air.altitude, "density_kgpm3": air.density,
                "speed_of_sound_mps": air.speed_of_sound, "flight_speed_mps": speed,
                "gravity_mps2": air.gravity if deploy.gravity else 0.0},
        "snapshots": NET_PVD,
        "state_at_max_area": NET_STATE,
    }


def run_deploy(net: TractionNet | RotaryNet, deploy: DeployConfig, air: Air, stage_dir: Path,
               log: logging.Logger, plots: bool = True) -> dict:
    """Simulate the deployment and write its outputs (``deploy.png`` only if ``plots``: the
    accuracy-vs-cost study times the simulation without the figure); returns the ``deploy`` summary section
    (SI units): max_area_m2, time_to_max_area_s, initial_area_m2, period_s, max_tension_n,
    steps, dt_s, wall_s (and its split ``wall_breakdown_s``: kernel, area, snapshots, record_other,
    plots, rest [s]), plus the first opening's maximum (``first_max_area_m2`` at
    ``time_to_first_max_area_s``), dt limits, snapshot and state file names, air state.
    ``max_area_m2`` is the largest area over the whole simulated time; ``net_state.npz`` holds
    the state at that instant."""
    wall0 = time.perf_counter()
    stage_dir = Path(stage_dir)
    snap_dir = stage_dir / "snapshots"
    snap_dir.mkdir(parents=True, exist_ok=True)
    for old in snap_dir.glob("net_*.vtu"):  # a re-run replaces the previous series
        old.unlink()

    model, state, env, ts, speed = _setup(net, deploy, air, log)
    rec = _Recorder(model, env, deploy, snap_dir, int(round(deploy.duration / deploy.output_interval)))
    steps = _march(model, state, ts, deploy, rec, log)

    write_history_csv(stage_dir / HISTORY, rec.cols)
    write_pvd(stage_dir / NET_PVD, rec.snaps)
    write_net_state(stage_dir / NET_STATE, model, rec.best)
    title = (f"{model.kind} net deployment — air {'on' if deploy.air else 'off'}, "
             f"Mach {deploy.mach:g} at {air.altitude:.0f} m, d = {net.rope_diameter * 1e3:g} mm (world frame W)")
    w0 = time.perf_counter()
    if plots:
        plot_deployment(stage_dir / "deploy.png", rec.cols, rec.shapes, model.springs, model.kind, title)
    rec.clock["plots"] = time.perf_counter() - w0

    summary = _summary(rec.cols, model, ts, deploy, air, speed, steps)
    summary["wall_s"] = time.perf_counter() - wall0
    rec.clock["rest"] = summary["wall_s"] - sum(rec.clock.values())
    summary["wall_breakdown_s"] = dict(rec.clock)
    log.info("max area %.2f m^2 at t = %.3f s (initial %.2f m^2), period %s s, max tension %.4g N, %.1f s wall",
             summary["max_area_m2"], summary["time_to_max_area_s"], summary["initial_area_m2"],
             summary["period_s"], summary["max_tension_n"], summary["wall_s"])
    return summary
