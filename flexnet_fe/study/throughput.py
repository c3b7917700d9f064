"""Throughput and scaling (issue 15 §4): the net kernel against the plain-numpy second model
(``study.net_numpy``); the shell step's effective bandwidth (bytes counted from the kernel's
arrays) beside a STREAM triad; shell ns per DOF-step and the log-log slope of cost against size
per stage (from the accuracy records); the default case end to end, by stage and by part
(kernel, plots, area, snapshots, XDMF, meshing, assembly, load transfer, report); 1 against 2
MPI ranks of its shell stage. Measurements: thread CPU time for one-core kernels, wall time for
stages (the pipeline's own unit), one run, side by side."""

from __future__ import annotations

import importlib
import logging
import math
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from numba import njit

from flexnet_fe.study.common import Context, loglog_slope

LOG = logging.getLogger("flexnet.study.throughput")

SIZE_KNOBS = {"deploy": ("net.subdivisions",),
              "collide": ("net.subdivisions", "collide.crop", "collide.crop_wave_speed_factor"),
              "shell": ("missile.mesh_size",), "flight": ("flight.dt",)}
"""The knobs whose variants change each stage's problem size (deploy nodes, collide active
segments, shell DOFs, flight steps)."""


def net_kernel(ctx: Context) -> list[dict]:
    try:
        mod = importlib.import_module("flexnet_fe.study.net_numpy")
    except ImportError as err:
        ctx.note("throughput", f"net kernel vs numpy: flexnet_fe.study.net_numpy not on this branch ({err}) "
                               "— skipped")
        return []
    n_side, steps = (41, 50) if ctx.quick else (101, 400)
    out = []
    for air in (False, True):
        r = mod.net_kernel_throughput(n_side, air, steps)
        out.append({"kind": "net_kernel", "air": air, "n_side": n_side, **r})
    return out


def shell_rate(stage_rows: list[dict]) -> list[dict]:
    out = []
    for r in stage_rows:
        if r["stage"] == "shell" and r["status"] == "ok" and r.get("steps"):
            out.append({"kind": "shell_dof_step", "knob": r["knob"], "value": r["value"], "dofs": r["size"],
                        "steps": r["steps"], "ns_per_dof_step": 1e9 * r["cpu_s"] / (r["size"] * r["steps"])})
    return out


def slopes(stage_rows: list[dict]) -> list[dict]:
    """Per stage: slope of log(CPU) and of log(CPU per step) against log(size) over the default
    and its size-knob variants (size: deploy nodes, collide active segments, shell DOFs, flight steps)."""
    out = []
    for stage, knobs in SIZE_KNOBS.items():
        pts = [r for r in stage_rows if r["stage"] == stage and r["status"] == "ok"
               and (r["is_default"] or r["knob"] in knobs) and r.get("size")]
        if len(pts) < 2:
            continue
        size = [r["size"] for r in pts]
        used = sorted({r["knob"] for r in pts if not r["is_default"]})
        out.append({"kind": "scaling", "stage": stage, "size_knob": ", ".join(used), "points": len(pts),
                    "size_min": min(size), "size_max": max(size),
                    "slope_cpu": loglog_slope(size, [r["cpu_s"] for r in pts]),
                    "slope_cpu_per_step": loglog_slope(size, [r["cpu_s"] / r["steps"] for r in pts])})
    return out


def end_to_end(run_dir: Path) -> list[dict]:
    """Per stage wall time of an existing run of the default case, from its status.json."""
    from flexnet_fe.io import read_json
    from flexnet_fe.runs import STATUS

    status = read_json(Path(run_dir) / STATUS)["stages"]
    out = [{"kind": "end_to_end", "stage": name, "wall_s": rec.get("wall_s", math.nan)}
           for name, rec in status.items() if rec.get("state") == "done"]
    if out:
        out.append({"kind": "end_to_end", "stage": "total", "wall_s": sum(r["wall_s"] for r in out),
                    "target_s": 15.0})
    return out


# --- memory bandwidth: STREAM triad against the shell step (issue 15 §4) ---------------------

@njit(cache=True)
def _triad(a, b, c, s):
    """STREAM triad a = b + s c (McCalpin): 2 reads + 1 write of 8 bytes per element."""
    for i in range(a.size):
        a[i] = b[i] + s * c[i]


def stream_triad(n: int, repeats: int = 10) -> dict:
    """Triad bandwidth on one core [GB/s] over three float64 arrays of ``n`` elements: the best
    and the median of ``repeats`` timed passes after one untimed pass (STREAM reports the best;
    bytes counted as STREAM does, 24 per element: write-allocate traffic not counted). Times are
    the thread's CPU time (the machine is shared: wall time would count the time the thread
    waits for a core), here and in :func:`shell_bandwidth`."""
    rng = np.random.default_rng(0)
    a, b, c = np.zeros(n), rng.random(n), rng.random(n)
    _triad(a, b, c, 3.0)
    times = []
    for _ in range(repeats):
        t0 = time.thread_time()
        _triad(a, b, c, 3.0)
        times.append(time.thread_time() - t0)
    nbytes = 24.0 * n
    return {"kind": "stream_triad", "elements": n, "bytes": nbytes,
            "gbps_best": nbytes / min(times) / 1e9, "gbps_median": nbytes / float(np.median(times)) / 1e9}


def shell_step_bytes(D, St) -> int:
    """Bytes the compiled shell step (``shell.kernel._fused_step`` with the per-step load and
    frame-acceleration lookups of ``advance_steps``) must move per step at least, counted from
    the arrays it touches once per step: read — K's row pointer, column indices, 2 × 2 membrane
    and 3 × 3 bending blocks, M⁻¹, the translational mass, the w-fixed flags, the load scratch;
    read and written — u, v and the product scratch y. (``mass`` is read at sample steps only;
    the loaded DOFs' few entries are not counted.) Neighbour reads of u and y are assumed to hit
    cache (each entry counted once): this is the compulsory traffic, as STREAM counts it."""
    K = D.K
    read = (K.indptr.nbytes + K.indices.nbytes + K.mem.nbytes + K.bend.nbytes + D.minv.nbytes
            + D.mass_t.nbytes + D.wfix.nbytes + St.fext.nbytes)
    return int(read + 2 * (St.u.nbytes + St.v.nbytes + St.y.nbytes))


def _plate_kernel(n_nodes: int):
    """A clamped square Al plate (6 mm, 0.3 m) with about ``n_nodes`` nodes, under a uniform
    pressure pulse: (model, step data, recovery data, dt [s]) of the compiled shell kernel."""
    from flexnet_fe.shell import api
    from flexnet_fe.shell.explicit import critical_step, max_eigenvalue
    from flexnet_fe.shell.forms import ShellMaterial, Support
    from flexnet_fe.shell.solve import LocalFrame, recovery_for, step_data

    nx = max(2, round(math.sqrt(n_nodes)) - 1)
    mat = ShellMaterial(thickness=6e-3, youngs_modulus=71.7e9, poisson_ratio=0.33, density=2810.0)
    model = api.plate(nx, nx, 0.3, 0.3, mat, supports={"root": Support.CLAMPED})
    loads = api.pressure(model, times=[0.0, 1e-4, 2e-4], values=[0.0, 1e5, 0.0])
    D = step_data(model, loads, LocalFrame(model.fin.plane))
    R = recovery_for(model)._replace(e1=np.array([1.0, 0.0, 0.0]), e2=np.array([0.0, 1.0, 0.0]))
    dt = 0.9 * critical_step(max_eigenvalue(model.op)[0])
    return model, D, R, dt


def _time_steps(D, R, P, n_nodes: int, n_dofs: int, steps: int, repeats: int) -> list[float]:
    from flexnet_fe.shell import kernel as kn

    out = []
    for _ in range(repeats):
        St = kn.new_state(n_dofs)
        H = kn.new_history(steps // P.sample_every + 2, n_nodes)
        t0 = time.thread_time()
        failed = kn.advance(D, P, R, St, H, steps)
        out.append(time.thread_time() - t0)
        if failed:
            raise RuntimeError(f"shell bandwidth benchmark: the plate run failed at step {failed}")
    return out


def shell_bandwidth(n_nodes: int, steps: int, repeats: int = 5, sample_every: int = 0) -> dict:
    """Effective bandwidth of the compiled shell step (``shell.kernel.advance``, one core) on a
    plate of about ``n_nodes`` nodes: :func:`shell_step_bytes` per step over the best time per
    step of ``repeats`` runs of ``steps`` steps (after a 10-step warm-up). ``sample_every`` > 0
    also times the same run with the stress sampling every that many steps (the stage samples
    every history_interval / dt steps) and reports the sampling's share."""
    from flexnet_fe.shell import kernel as kn

    model, D, R, dt = _plate_kernel(n_nodes)
    n_dofs, nn = model.op.n_owned, model.op.n_owned // 5
    P = kn.StepParams(dt=dt, alpha=0.0, beta=0.0, growth_limit=10.0, sample_every=steps + 1)
    _time_steps(D, R, P, nn, n_dofs, 10, 1)
    best = min(_time_steps(D, R, P, nn, n_dofs, steps, repeats)) / steps
    nbytes = shell_step_bytes(D, kn.new_state(n_dofs))
    row = {"kind": "shell_bandwidth", "nodes": nn, "dofs": n_dofs, "blocks": int(D.K.indices.size),
           "bytes_per_step": nbytes, "bytes_per_dof_step": nbytes / n_dofs, "steps": steps,
           "ns_per_dof_step": 1e9 * best / n_dofs, "gbps": nbytes / best / 1e9}
    if sample_every > 0:
        Ps = P._replace(sample_every=sample_every)
        _time_steps(D, R, Ps, nn, n_dofs, 2 * sample_every, 1)
        sampled = min(_time_steps(D, R, Ps, nn, n_dofs, steps, repeats)) / steps
        row.update(sample_every=sample_every, ns_per_dof_step_sampled=1e9 * sampled / n_dofs,
                   sampling_share=1.0 - best / sampled)
    return row


def bandwidth(ctx: Context) -> list[dict]:
    """The shell step at ~1e4 and ~1e5 DOFs, each beside a STREAM triad moving the same bytes
    per pass (same cache level), and one triad ≫ the 32 MiB L3 (memory); each shell row gets
    its fraction of both."""
    sizes = (400, 2000) if ctx.quick else (2000, 20000)
    steps = (200, 50) if ctx.quick else (4000, 400)
    big = (1 << 21) if ctx.quick else (1 << 24)
    out = [dict(stream_triad(big, repeats=3 if ctx.quick else 10), sized_like=f"{24 * big / 2**20:.0f} MiB")]
    for n, st in zip(sizes, steps):
        sh = shell_bandwidth(n, st, repeats=3 if ctx.quick else 5, sample_every=25)
        tr = dict(stream_triad(int(sh["bytes_per_step"] // 24), repeats=5 if ctx.quick else 20),
                  sized_like=f"shell step at {sh['dofs']} DOFs")
        sh["fraction_of_triad_same_bytes"] = sh["gbps"] / tr["gbps_best"]
        sh["fraction_of_triad_memory"] = sh["gbps"] / out[0]["gbps_best"]
        out += [tr, sh]
    return out


# --- the default case end to end, by stage and inside each stage (issue 15 §4) ----------------

ENTRIES = (
    ("kernel", "flexnet_fe.net.deploy", "step_many"), ("kernel", "flexnet_fe.collide.kernel", "advance"),
    ("kernel", "flexnet_fe.shell.kernel", "advance"), ("kernel", "flexnet_fe.flight.simulate", "advance"),
    ("area rasterising", "flexnet_fe.net.deploy", "net_area"),
    ("snapshots (vtu/pvd)", "flexnet_fe.net.deploy", "write_vtu"),
    ("snapshots (vtu/pvd)", "flexnet_fe.net.deploy", "write_pvd"),
    ("snapshots (vtu/pvd)", "flexnet_fe.collide.stage", "write_outputs"),
    ("per-output tensions and energies", "flexnet_fe.net.deploy", "evaluate_tensions"),
    ("per-output tensions and energies", "flexnet_fe.net.deploy", "energies"),
    ("plots", "flexnet_fe.net.deploy", "plot_deployment"), ("plots", "flexnet_fe.collide.plots", "plot_all"),
    ("plots", "flexnet_fe.flight.plots", "plot_engagement"),
    ("XDMF", "dolfinx.io.XDMFFile", "write_mesh"), ("XDMF", "dolfinx.io.XDMFFile", "write_function"),
    ("fin mesh (gmsh)", "flexnet_fe.missile.mesh", "write_refined_fin_mesh"),
    ("fin mesh (gmsh)", "flexnet_fe.shell.stage", "load_fin_mesh"),
    ("assembly K, M (dolfinx)", "flexnet_fe.shell.stage", "build_model"),
    ("dt_crit (Lanczos)", "flexnet_fe.shell.stage", "max_eigenvalue"),
    ("contact load transfer", "flexnet_fe.shell.stage", "contact_transfer"),
    ("stress recovery after the run", "flexnet_fe.shell.stage", "build_recovery"),
    ("stress recovery after the run", "flexnet_fe.shell.stage", "locate_peak"),
    ("history csv", "flexnet_fe.net.deploy", "write_history_csv"),
    ("history csv", "flexnet_fe.shell.stage", "write_history_csv"),
    ("history csv", "flexnet_fe.flight.stage", "write_history_csv"),
)
"""(category, module or class, attribute): the functions whose time is charged to each part of a
stage, wrapped in timers for the profiled run where the stage code looks them up (its own
module's name, or the module it imports at call time). A call inside another timed call counts
for the outer one only. The shell kernel's stress sampling runs inside the kernel (see
:func:`shell_bandwidth`'s sampling share)."""


class _Timers:
    """Context manager: the :data:`ENTRIES` wrapped in timers; ``seconds`` per category."""

    def __enter__(self):
        self.saved, self.seconds, self.depth = [], {}, 0
        for cat, owner, attr in ENTRIES:
            mod_name, _, cls = owner.rpartition(".") if owner.endswith("XDMFFile") else (owner, "", "")
            obj = getattr(importlib.import_module(mod_name), cls) if cls else importlib.import_module(mod_name)
            f = getattr(obj, attr)
            self.saved.append((obj, attr, f))
            setattr(obj, attr, self._timed(f, cat))
        return self

    def _timed(self, f, cat):
        def timed(*a, **k):
            if self.depth:
                return f(*a, **k)
            self.depth += 1
            t0 = time.perf_counter()
            try:
                return f(*a, **k)
            finally:
                self.seconds[cat] = self.seconds.get(cat, 0.0) + time.perf_counter() - t0
                self.depth -= 1
        return timed

    def __exit__(self, *exc):
        for obj, attr, f in reversed(self.saved):
            setattr(obj, attr, f)


def profile_case(case_dir: Path, run_dir: Path, log=LOG) -> list[dict]:
    """Run ``case_dir`` stage by stage into ``run_dir`` with its functions timed by part
    (:data:`ENTRIES`), then ``flexnet report`` on it; per stage the wall time, the seconds of each part
    (``s_<part>``), the remainder (``s_other``) and the kernel's share of the stage."""
    from flexnet_fe.config import load_case
    from flexnet_fe.pipeline import run_case

    case, case_dir = load_case(case_dir, [])
    out = []
    jobs = [(s.value, lambda s=s: run_case(case, case_dir, run_dir, [s], force=True)) for s in case.case.stages]
    # the report as users make it, `flexnet report RUN` (a process of its own: the run layer does
    # not import the report package); its row is the whole command, interpreter start included
    root = Path(__file__).resolve().parents[2]
    jobs.append(("report (flexnet report, own process)", lambda: subprocess.run(
        [sys.executable, "-m", "flexnet_fe.cli", "report", str(run_dir)], check=True, cwd=root,
        capture_output=True, env=dict(os.environ, PYTHONPATH=str(root)))))
    for name, job in jobs:
        with _Timers() as tm:
            t0 = time.perf_counter()
            job()
            wall = time.perf_counter() - t0
        row = {"kind": "end_to_end", "stage": name, "wall_s": wall, **{f"s_{k}": v for k, v in tm.seconds.items()}}
        row["s_other"] = wall - sum(tm.seconds.values())
        row["kernel_share"] = tm.seconds.get("kernel", 0.0) / wall
        log.info("end to end %s: %.1f s wall (%s)", name, wall,
                 ", ".join(f"{k} {v:.2f}" for k, v in tm.seconds.items()))
        out.append(row)
    out.append({"kind": "end_to_end", "stage": "total", "wall_s": sum(r["wall_s"] for r in out),
                "target_s": 15.0})
    return out


# --- 1 against 2 MPI ranks for the shell stage (issue 15 §4) -----------------------------------

def _shell_run(src: Path, dst: Path, sets: tuple[str, ...], ranks: int, timeout: float = 3600.0) -> dict:
    """``flexnet run CASE --stages shell`` on a copy ``dst`` of the run directory ``src`` (its
    collide stage done), with ``ranks`` MPI processes (``mpirun -n`` when > 1, as
    tests/run/test_mpi_run.py does); the stage's wall time from status.json and the process's
    elapsed time [s]."""
    from flexnet_fe.io import read_json
    from flexnet_fe.runs import STATUS
    from flexnet_fe.study.scenes import CASE

    if dst.exists():
        shutil.rmtree(dst)
    shutil.copytree(src, dst)
    cmd = [sys.executable, "-m", "flexnet_fe.cli", "run", str(CASE), "--out", str(dst), "--stages", "shell",
           "--force", *[a for s in sets for a in ("--set", s)]]
    if ranks > 1:
        cmd = ["mpirun", "--oversubscribe", "--allow-run-as-root", "-n", str(ranks), *cmd]
    root = Path(__file__).resolve().parents[2]
    env = dict(os.environ, FLEXNET_NO_PROGRESS="1", PYTHONPATH=str(root), OMP_NUM_THREADS="1")
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True, cwd=root, env=env, timeout=timeout)
    elapsed = time.perf_counter() - t0
    if p.returncode != 0:
        raise RuntimeError(f"shell run with {ranks} rank(s) failed: {p.stderr[-2000:]}")
    rec = read_json(dst / STATUS)["stages"]["shell"]
    return {"stage_wall_s": rec.get("wall_s", math.nan), "process_wall_s": elapsed}


def mpi_scaling(ctx: Context, run_dir: Path, end_time: float = 2e-3) -> list[dict]:
    """Shell stage of the default case on 1 rank (compiled kernel, the default backend; and the
    PETSc backend, the one MPI runs use) and on 2 ranks (PETSc), from the collide output in
    ``run_dir``, simulating ``end_time`` [s] (the shipped run simulates 14 ms: setup — mesh,
    assembly, Lanczos — weighs more here than in it). Speed-up = 1-rank wall / 2-rank wall."""
    if shutil.which("mpirun") is None:
        ctx.note("throughput", "1 vs 2 MPI ranks: no mpirun on this machine — skipped")
        return []
    sets = (f"shell.end_time={end_time}",)
    runs = [("compiled", 1, sets), ("petsc", 1, sets + ('shell.backend="petsc"',)),
            ("petsc", 2, sets + ('shell.backend="petsc"',))]
    out = []
    for backend, ranks, s in runs:
        r = _shell_run(Path(run_dir), ctx.scratch("mpi") / f"{backend}_{ranks}", s, ranks)
        out.append({"kind": "mpi", "backend": backend, "ranks": ranks, "end_time_s": end_time, **r})
    for r in out:
        r["speedup_vs_1_compiled"] = out[0]["stage_wall_s"] / r["stage_wall_s"]
        r["speedup_vs_1_petsc"] = out[1]["stage_wall_s"] / r["stage_wall_s"]
    return out


def rows(ctx: Context, stage_rows: list[dict], run_dir: Path | None = None) -> list[dict]:
    """Net kernel against numpy, triad against the shell step, shell ns per DOF-step and the
    log-log slopes from the accuracy studies' rows; full study (or ``run_dir``): the default
    case end to end by stage (profiled, full study) and 1 vs 2 MPI ranks of its shell stage."""
    from flexnet_fe.study.scenes import CASE

    out = net_kernel(ctx) + bandwidth(ctx) + shell_rate(stage_rows) + slopes(stage_rows)
    if run_dir is not None:
        return out + end_to_end(run_dir)
    if ctx.quick:
        ctx.note("throughput", "end to end by stage and 1 vs 2 MPI ranks: full study only (or --run-dir DIR)")
        return out
    rd = ctx.scratch("end_to_end")
    ctx.note("throughput", "end to end: cases/radar_traction run stage by stage in one process with the parts' "
                           "entry functions timed (throughput.ENTRIES; numba's on-disk caches filled, imports and "
                           "cache loading counted in the first stage that needs them), then `flexnet report` on it")
    out += profile_case(CASE, rd)
    return out + mpi_scaling(ctx, rd)
