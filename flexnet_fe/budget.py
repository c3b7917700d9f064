"""What a case will cost, known before any big allocation: nodes, DOFs, steps, memory and disk
per stage, from the case alone (no physics is run), and the checks that refuse a case which
cannot work (inconsistent geometry, non-finite derived values) or would exhaust the machine.

The estimates are our own order-of-magnitude formulas, documented next to each one (they follow
the stage code's array sizes: ``net/deploy.py``, ``collide/simulate.py``, ``flight/simulate.py``,
the shell's sparse matrices). They are deliberately simple: they must be cheap (``validate``
imports no dolfinx or gmsh and compiles nothing; the rope checks import ``net.topology`` for the
builders' own rope area and EA/l0, which loads numba, ≈ 0.5 s) and are meant to catch the orders of magnitude that turn a
typo into a MemoryError, a std::bad_alloc or a run of a year — not to predict a wall time.

Budget (docs/validation.md "Run machinery"): memory ≤ the machine's available memory
(``MemAvailable``, or ``FLEXNET_MEMORY_BUDGET`` bytes when set), steps ≤ :data:`MAX_STEPS` per stage, disk ≤ the free space of the output
folder. ``--force`` runs anyway.
"""

from __future__ import annotations

import math
import os
import shutil
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from flexnet_fe.errors import CaseError
from flexnet_fe.shell.strikes import STRIKE_OFFSETS

MAX_STEPS = 1e9
"""Largest number of time steps one stage may take [-] (≈ hours at the fastest kernels' ~1 µs
per step on a tiny model; days on a real one)."""

F8 = 8
"""bytes per float64"""

SHELL_STEP_FACTOR = 0.25
"""dt / (safety × h / c_p) of the shell stage on the paper fins [-]: measured 0.25 on the 20 mm
structured fin meshes (their narrowest quads near the tip are ≈ 0.4 h; the Mindlin shear and
rotary-inertia modes lower it further) and 0.45–0.54 at local sizes 5 / 2.5 / 1.25 mm
(radar × traction, 2026-11-23, /tmp/lead/shell_conv.log): 0.25 keeps the estimate an upper
bound on the steps within ≈ 2×."""

BASE_PROCESS = 0.45e9
"""Memory of a flexnet process before any stage allocates [bytes]: Python with numpy, numba,
dolfinx/PETSc and gmsh imported (measured: 419 MB maximum resident set of a 121-node deploy)."""


@dataclass
class StageCost:
    """Estimated size of one stage. ``drivers`` names, for each quantity, the case field that
    sets it (used in the refusal line)."""

    stage: str
    nodes: float = 0.0
    dofs: float = 0.0
    steps: float = 0.0
    memory_bytes: float = 0.0
    disk_bytes: float = 0.0
    drivers: dict[str, str] = field(default_factory=dict)
    detail: str = ""

    def line(self) -> str:
        return (f"{self.stage}: {self.nodes:.3g} nodes, {self.dofs:.3g} DOFs, {self.steps:.3g} steps, "
                f"memory {_size(self.memory_bytes)}, disk {_size(self.disk_bytes)}")


def _size(n: float) -> str:
    if not math.isfinite(n):
        return "∞"
    for unit in ("B", "kB", "MB", "GB", "TB", "PB"):
        if n < 1000 or unit == "PB":
            return f"{n:.3g} {unit}"
        n /= 1000.0


def _finite(file, field_path: str, what: str, value: float) -> float:
    if not math.isfinite(value) or value <= 0.0:
        raise CaseError(file, field_path, f"the derived {what} = {value:.4g} is not a finite positive number")
    return value


def net_counts(net) -> tuple[float, float, float]:
    """(nodes, segments, rope segment rest length l0 [m]) of the net, as the builders make them
    (``net/topology.py``: traction knots round(L/h)+1 per side, rotary round(R/h) rings)."""
    s = net.subdivisions
    if net.kind == "traction":
        m = round(net.edge_length / net.mesh_size)
        bars = 2.0 * m * (m + 1)
        return (m + 1.0) * (m + 1.0) + bars * (s - 1), bars * s, net.mesh_size / s
    rings = round(net.warp_length / net.mesh_size)
    bars = 2.0 * net.warps * rings  # warp bars + weft chords
    return 1 + net.warps * rings + bars * (s - 1), bars * s, net.mesh_size / s


def check_net(net, file) -> tuple[float, float, float, float]:
    """Geometry consistency and finite derived rope values; returns (nodes, segments, l0 [m],
    wave speed c [m/s])."""
    span_field, span = (("net.edge_length", net.edge_length) if net.kind == "traction"
                        else ("net.warp_length", net.warp_length))
    if net.mesh_size > span:
        raise CaseError(file, "net.mesh_size", f"{net.mesh_size:g} m is larger than {span_field} = {span:g} m "
                        "(the net would have no mesh cell)")
    # the net builders' and the collide crop's own formulas (their one home): the numbers the run will use
    from flexnet_fe.collide.crop import wave_speed
    from flexnet_fe.net.topology import rope_area, segment_stiffness

    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):  # an overflow is reported below
        d = np.float64(net.rope_diameter)  # numpy floats overflow to inf (a Python float's ** raises)
        area = _finite(file, "net.rope_diameter", "rope cross-section π d²/4 [m²]", float(rope_area(d)))
        _finite(file, "net.density", "rope mass per length ρA [kg/m]", net.density * area)
        ea = _finite(file, "net.youngs_modulus", "rope axial stiffness EA [N]", float(np.float64(net.youngs_modulus) * area))
        c = _finite(file, "net.youngs_modulus", "rope wave speed √(E/ρ) [m/s]",
                    wave_speed(net.youngs_modulus, net.density))
        nodes, segs, l0 = net_counts(net)
        _finite(file, "net.mesh_size", "segment stiffness EA/l0 [N/m]", float(segment_stiffness(np.float64(ea), l0)))
    return nodes, segs, l0, c


def deploy_cost(case, file) -> StageCost:
    """Steps: the spring limit of an interior knot of 4 segments (mass 2ρAl0, ω² = 4E/(ρl0²)) is
    dt = l0/c; with the safety factor dt = safety·l0/c (the drag limit, which depends on the
    state, can only make it smaller, so this is a lower bound on the steps). Memory: the process
    itself (:data:`BASE_PROCESS`), the model and its work arrays (≈ 100 floats per node and per
    segment: measured 574 MB above the base for 2.5e5 nodes + 5.0e5 segments, i.e. 95 floats)
    plus ≈ 16 history columns per output row; disk: one
    .vtu snapshot of ≈ 60 B per node and per segment every snapshot_interval."""
    d, net = case.deploy, case.net
    nodes, segs, l0, c = check_net(net, file)
    # Every rope–rope segment of a uniform net has ω² = 4E/(ρ l0²) (the lumped masses are half
    # segments, net/timestep.spring_limit), and ω dt_crit = 2(√(1+ζ²) − ζ): dt_crit = (√(1+ζ²) − ζ) l0/c.
    # Corner masses and the hub only lower ω_max… or raise it (hub links): the run re-checks exactly.
    zeta = net.damping_ratio
    limit = (math.sqrt(1 + zeta * zeta) - zeta) * l0 / c
    if d.time_step is not None and d.time_step > limit:
        raise CaseError(file, "deploy.time_step", f"forced dt = {d.time_step:.4g} s exceeds the rope springs' "
                        f"stability limit {limit:.4g} s = (√(1+ζ²) − ζ) l0/c (l0 = {l0:.4g} m, c = {c:.4g} m/s)")
    dt = d.time_step or d.safety_factor * limit
    rows = d.duration / d.output_interval
    snaps = d.duration / min(d.snapshot_interval, d.duration)
    mem = BASE_PROCESS + 100 * F8 * (nodes + segs) + 16 * F8 * rows
    cost = StageCost("deploy", nodes, 3 * nodes, d.duration / dt, mem, 60 * (nodes + segs) * snaps + 16 * 25 * rows,
                     {"nodes": "net.mesh_size", "steps": "deploy.duration", "memory": _mem_driver(
                         100 * F8 * (nodes + segs), 16 * F8 * rows, "net.mesh_size", "deploy.output_interval"),
                      "disk": "deploy.snapshot_interval"})
    cost.detail = (f"{rows:.3g} history rows = deploy.duration / deploy.output_interval, "
                   f"{snaps:.3g} snapshots, dt ≈ {dt:.3g} s")
    return cost


def _mem_driver(a: float, b: float, field_a: str, field_b: str) -> str:
    return field_a if a >= b else field_b


def collide_cost(case, file) -> StageCost:
    """Steps: the stage's own step rule (``collide.timestep.choose_step``: rope springs, contact,
    travel per step) evaluated at the lightest node the missile can reach before the run knows the
    held net: with ``rope_split`` k > 1 a node between two pieces of rest length l0/k (mass ρA l0/k,
    the split's re-lumping, ``collide/refine.py``), with ``fin_piece_length`` p shorter than that a
    node between two pieces of length p (the cut at the fins makes pieces of p/2 … p, and the
    held net's rest lengths are shorter than its chords: the estimate may be up to ≈ 2^0.4 × too
    few steps there), else an interior knot (2ρA l0); the most
    segments at a node 4 (a rotary net's hub: its warps). Memory: the process, the held net and
    its work arrays (≈ 100 floats per node and per segment, as deploy; not measured separately)
    and ≈ 40 history columns per output row; disk: snapshots (60 B per node) × snapshots. With
    ``resolution_check`` the steps add the second impact's, at half the pieces, and the memory is
    counted twice (it runs in a second process beside the first on two cores or more:
    ``collide.check.check_beside``). With ``fin_coupling = "staggered"`` the steps add the rigid
    impact's (``shell.coupling``) and the memory the fins' sampled motion, every fin moving over
    ``duration`` (41 × 41 floats per µs per fin: an upper bound, the fins' windows are shorter)."""
    cc, net = case.collide, case.net
    nodes, segs, l0, c = check_net(net, file)
    energy = 0.5 * _missile_mass(case.missile) * cc.impact_speed * cc.impact_speed
    _finite(file, "collide.impact_speed", "missile kinetic energy ½mv² [J]", energy)
    dt = _collide_step(case, l0)
    steps = cc.end_time / dt
    if cc.resolution_check:  # the check's second impact, at half the pieces (collide.resolution)
        half = cc.model_copy(update={"fin_piece_length": 0.5 * cc.fin_piece_length})
        steps += cc.end_time / _collide_step(case.model_copy(update={"collide": half}), l0)
    staggered = cc.fin_coupling.value == "staggered"
    if staggered:  # the impact with rigid fins first (shell.coupling)
        steps += cc.end_time / dt
    rows = cc.end_time / cc.output_interval  # up to the cap: the run goes on while the contact does
    mem = (BASE_PROCESS + 100 * F8 * (nodes + segs) + 40 * F8 * rows) * (2 if cc.resolution_check else 1)
    if staggered:
        mem += 8 * cc.duration / 1e-6 * 41 * 41 * F8  # 8 fins (as shell_cost), shell.coupling.MOTION_INTERVAL
    cost = StageCost("collide", nodes, 3 * nodes + 6, steps, mem,
                     60 * (nodes + segs) * cc.snapshots + 40 * 25 * rows,
                     {"nodes": "net.mesh_size", "steps": "collide.impact_speed",
                      "memory": _mem_driver(100 * F8 * (nodes + segs), 40 * F8 * rows, "net.mesh_size",
                                            "collide.output_interval"), "disk": "collide.output_interval"})
    cost.detail = (f"{rows:.3g} history rows at most = collide.max_duration (or duration) / collide.output_interval, "
                   f"dt ≈ {dt:.3g} s (collide step rule, rope_split {cc.rope_split}, fin_piece_length {cc.fin_piece_length})"
                   + ("; steps include the resolution check's impact at half the pieces" if cc.resolution_check else "")
                   + ("; steps include the staggered fin coupling's rigid impact, memory its fins' motion" if staggered
                      else ""))
    return cost


def _collide_step(case, l0: float) -> float:
    """dt [s] of ``collide.timestep.choose_step`` for the case (``collide_cost``); l0 [m] the
    deployed net's segment rest length."""
    from flexnet_fe.collide.config import ContactLaw
    from flexnet_fe.collide.timestep import choose_step, contact_stiffness, line_stiffnesses
    from flexnet_fe.net.forces import rope_material
    from flexnet_fe.net.topology import rope_area

    cc, net, m = case.collide, case.net, case.missile
    rope = rope_material(net)
    k = int(cc.rope_split)
    mu = rope.density * float(rope_area(rope.diameter))  # rope mass per length [kg/m]
    piece = l0 / k
    if cc.fin_piece_length is not None and cc.fin_piece_length < piece:
        piece = float(cc.fin_piece_length)
    m_min = mu * piece if piece < l0 else 2.0 * mu * l0
    n_seg = 4 if net.kind == "traction" else max(4, int(net.warps))
    fin_half = 0.5 * min(m.wings.thickness, m.rudders.thickness)
    k_body, k_fin = contact_stiffness(cc, rope.radius, rope.transverse_modulus, rope.poisson_ratio, fin_half,
                                      0.5 * m.body_diameter)
    ea = np.array([rope.youngs_modulus * float(rope_area(rope.diameter)) / piece])
    mass = np.array([mu * piece])
    line = None
    if cc.contact_law is ContactLaw.line:  # the unstretched rope's mass per length
        kl_body, kl_fin = line_stiffnesses(cc, rope.radius, rope.transverse_modulus, rope.poisson_ratio,
                                           np.array([fin_half]), 0.5 * m.body_diameter)
        line = (max(kl_body, float(kl_fin.max())), mu)
    dt = choose_step(cc, ea, mass, mass, m_min, n_seg, rope.radius, fin_half, max(k_body, k_fin), line).dt
    return cc.load_dt / math.ceil(cc.load_dt / dt)  # a whole number of steps per fin-load interval (simulate)


def _missile_mass(missile) -> float:
    """Rough missile mass [kg] for the energy check: the given mass, else a uniform cylinder."""
    if missile.mass is not None:
        return missile.mass
    return missile.body_density * math.pi * missile.body_diameter * missile.body_diameter / 4 * missile.body_length


def shell_cost(case, file) -> StageCost:
    """Fin mesh: quadrilaterals of size h = missile.mesh_size on the 4 wings and 4 rudders
    (trapezoid area (c_r + c_t)/2 · b each); 6 DOFs per node. Gmsh needs ≈ 1 kB per element and
    the explicit solver ≈ 2 kB per DOF (the 54-wide stiffness rows in BAIJ plus lumped mass,
    state and stress work vectors). Steps: dt ≈ safety × β h_min / c_p with c_p = √(E/(ρ(1−ν²))),
    h_min = the smaller of missile.mesh_size and shell.local_mesh_size (the refined zones set the
    step of the whole fin) and β = :data:`SHELL_STEP_FACTOR`; end time = collide duration + end_margin unless given. Disk: 8 stress and
    displacement fields per output, 40 outputs per fin by default. Steps are per fin, from t = 0 to
    the end: an upper bound — before the collision no one knows each fin's load window
    (``shell.window = "fin"`` simulates about half of it on radar_traction) or how many fins
    share the ``shell.workers`` threads. ``shell.peak_check`` reruns each fin at half the local
    size up to its peak (``shell.stage.check_peaks``): at most the same span at half the step,
    so the bound's steps +2×; ``shell.strike_envelope`` reruns each fin at the same size up to its
    peak once per move (``shell.strikes.STRIKE_OFFSETS``): +1× per move. The check's memory is that of a mesh with ≈ 4× the nodes of the refined zones,
    which are not counted here (measured on the paper cases: docs/performance.md)."""
    m, sh = case.missile, case.shell
    h = m.mesh_size
    h_min = min(h, sh.local_mesh_size or h)
    area = sum(4 * 0.5 * (f.root_chord + f.tip_chord) * f.span for f in (m.wings, m.rudders))
    elements = _finite(file, "missile.mesh_size", "fin element count", area / (h * h))
    nodes = elements * 1.1
    mat = m.material
    cp = math.sqrt(mat.youngs_modulus / (mat.density * (1 - mat.poisson_ratio * mat.poisson_ratio)))
    end = sh.end_time or (case.collide.duration + sh.end_margin)
    dt = sh.safety_factor * SHELL_STEP_FACTOR * h_min / cp
    outputs = end / sh.field_interval if sh.field_interval else 40
    mem = BASE_PROCESS + max(1e3 * elements, 2e3 * 6 * nodes)
    steps = end / dt * (1 + (2 if sh.peak_check else 0) + (len(STRIKE_OFFSETS) if sh.strike_envelope else 0))
    cost = StageCost("shell", nodes, 6 * nodes, steps, mem, 8 * F8 * elements * outputs,
                     {"nodes": "missile.mesh_size", "steps": "shell.local_mesh_size" if h_min < h else "missile.mesh_size",
                      "memory": "missile.mesh_size",
                      "disk": "shell.field_interval"})
    cost.detail = (f"{elements:.3g} fin elements of size missile.mesh_size (refined zones not counted), "
                   f"dt ≈ {dt:.3g} s from the smallest element size {h_min:.3g} m, end {end:.3g} s"
                   + (", the peak check's rerun at half the local size counted" if sh.peak_check else "")
                   + (", the strike envelope's reruns counted" if sh.strike_envelope else ""))
    return cost


def flight_cost(case, file) -> StageCost:
    """``flight/simulate.run_engagement`` allocates (t_end/output_dt + 2) records of 26 states
    and ≈ 30 diagnostics (float64) up front; RK4 steps = t_end / dt (per sweep value, twice for
    a wing-damage sweep)."""
    f = case.flight
    runs = 1 + (2 * len(f.sweep.values) if f.sweep is not None else 0)
    rec = f.t_end / max(f.output_dt, f.dt) + 2
    mem = BASE_PROCESS + rec * (1 + 26 + 30) * F8
    cost = StageCost("flight", 1, 26, runs * f.t_end / f.dt, mem, rec * 40 * 25,
                     {"nodes": "flight", "steps": "flight.t_end", "memory": "flight.output_dt", "disk": "flight.output_dt"})
    cost.detail = f"{rec:.3g} records = flight.t_end / flight.output_dt, {runs} engagement(s) of t_end / dt steps"
    return cost


COSTS = {"deploy": deploy_cost, "collide": collide_cost, "shell": shell_cost, "flight": flight_cost}


def estimate(case, file, stages=None) -> list[StageCost]:
    """The cost of each stage to run (default: the case's own stages). Raises CaseError for an
    inconsistent case (geometry, non-finite derived values)."""
    names = [getattr(s, "value", s) for s in (stages or case.case.stages)]
    return [COSTS[n](case, file) for n in names]


def available_memory() -> float:
    """The memory budget [bytes]: ``FLEXNET_MEMORY_BUDGET`` (bytes) if set, else
    ``MemAvailable`` of /proc/meminfo (inf where it cannot be read)."""
    if os.environ.get("FLEXNET_MEMORY_BUDGET"):
        return float(os.environ["FLEXNET_MEMORY_BUDGET"])
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return float(line.split()[1]) * 1024.0
    except OSError:
        pass
    return math.inf


def free_disk(path: Path) -> float:
    """Free bytes on the filesystem that holds ``path`` (or its nearest existing parent)."""
    path = Path(path).absolute()
    while not path.exists() and path != path.parent:
        path = path.parent
    try:
        return float(shutil.disk_usage(path).free)
    except OSError:
        return math.inf


def check_budget(costs: list[StageCost], file, out_dir: Path | None = None,
                 memory: float | None = None, max_steps: float = MAX_STEPS) -> None:
    """Refuse (CaseError naming the driving field and the estimate) a stage above the budget."""
    memory = available_memory() if memory is None else memory
    disk = free_disk(out_dir) if out_dir is not None else math.inf
    total_disk = 0.0
    for c in costs:
        if not c.memory_bytes <= memory:
            raise CaseError(file, c.drivers["memory"], f"{c.stage} needs ≈ {_size(c.memory_bytes)} of memory "
                            f"({c.detail}), above the {_size(memory)} available; "
                            "change the field or run with --force")
        if not c.steps <= max_steps:
            raise CaseError(file, c.drivers["steps"], f"{c.stage} needs ≈ {c.steps:.3g} time steps ({c.detail}), above the "
                            f"limit of {max_steps:.3g}; change the field or run with --force")
        total_disk += c.disk_bytes
        if not total_disk <= disk:
            raise CaseError(file, c.drivers["disk"], f"the run would write ≈ {_size(total_disk)} by the end of "
                            f"{c.stage}, above the {_size(disk)} free in {out_dir}; change the field, free space, "
                            "or run with --force")


def describe(costs: list[StageCost]) -> str:
    return "\n".join("  " + c.line() for c in costs)

