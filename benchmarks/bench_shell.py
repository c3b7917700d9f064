"""Shell solver benchmark (issue 10): step speed against a STREAM triad measured in the same run,
set-up time, accuracy versus CPU on the plate-pulse problem, and the paper fins' peak stress
under mesh refinement (reproducible on any collision run directory).

    .venv/bin/python benchmarks/bench_shell.py kernel            # ns per DOF-step, % of triad
    .venv/bin/python benchmarks/bench_shell.py plate             # accuracy vs CPU (+ PNG chart)
    .venv/bin/python benchmarks/bench_shell.py paper RUN_DIR [--fins wing_1,wing_3]
                                [--sizes 0.02,0.01,0.005] [--end-time S]
        # RUN_DIR: a run directory with collide/ done (e.g. `flexnet run cases/radar_traction
        # --stages deploy,collide --out RUN_DIR`); re-meshes the fins at each size and runs the
        # shell stage on the recorded collision loads
    .venv/bin/python benchmarks/bench_shell.py case RUN_DIR     # the stage as the case runs it
    .venv/bin/python benchmarks/bench_shell.py zone RUN_DIR FIN --time S [--part inplane|normal]
                                [--local 0.005,0.0025,0.00125,0.000625]
        # the static response to the largest contact event of FIN at time S, at each local
        # mesh size: the structural peak outside its St-Venant zone and the largest von Mises on
        # rings of radius 9–24 mm around it (is the zone-boundary peak converging?)

Ratios are measured side by side in one run (the machine is shared: absolute times vary 2–3×);
each timing is the best of several repeats.
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
import time
from pathlib import Path

import numpy as np
from numba import njit

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
logging.getLogger("UFL").setLevel(logging.ERROR)
logging.getLogger("FFCX").setLevel(logging.ERROR)
logging.getLogger().setLevel(logging.WARNING)

from flexnet_fe.shell import api, kernel as kn, navier  # noqa: E402
from flexnet_fe.shell.explicit import (central_difference, critical_step,  # noqa: E402
                                       max_eigenvalue, no_loads)
from flexnet_fe.shell.forms import NDOF_NODE, ShellMaterial, Support  # noqa: E402
from flexnet_fe.shell.mass import auto_rotary_scale  # noqa: E402
from flexnet_fe.shell.model import ShellModel  # noqa: E402
from flexnet_fe.shell.recovery import locate_peak, von_mises  # noqa: E402
from flexnet_fe.shell.solve import LocalFrame, recovery_for, run, step_data  # noqa: E402

AL7075 = ShellMaterial(thickness=6e-3, youngs_modulus=71.7e9, poisson_ratio=0.33, density=2810.0,
                       yield_strength=503e6)


@njit(cache=True)
def _triad(a, b, c, s):
    for i in range(a.size):
        a[i] = b[i] + s * c[i]


def stream_triad(n=20_000_000, repeat=5) -> float:
    """Best STREAM-triad bandwidth a = b + s c [B/s] (3 × 8 bytes per element, 1 thread)."""
    a, b, c = np.zeros(n), np.ones(n), np.full(n, 2.0)
    _triad(a, b, c, 3.0)
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        _triad(a, b, c, 3.0)
        best = min(best, time.perf_counter() - t0)
    return 24.0 * n / best


def step_bytes(D: kn.StepData) -> float:
    """Bytes one fused step must stream: 13 matrix values + one 4-byte index per stored block,
    row pointers, and per DOF: u, v read and written, M⁻¹, m_t, f_ext read (y stays in cache:
    it is touched only a few rows ahead of the sweep; m is read on sample steps only)."""
    nnzb = len(D.K.indices)
    n = len(D.minv)
    return nnzb * (13 * 8 + 4) + 8 * (n // NDOF_NODE) + n * 8 * 7


def time_kernel(model: ShellModel, steps: int = 40, repeat: int = 7) -> dict:
    """Best time per step of the compiled kernel (no sampling) and of the PETSc step."""
    op = model.op
    lam, _ = max_eigenvalue(op)
    dt = 0.9 * critical_step(lam)
    lf = LocalFrame(model.fin.plane)
    D = step_data(model, no_loads(op), lf)
    R = recovery_for(model)._replace(e1=np.array([1.0, 0, 0]), e2=np.array([0, 1.0, 0]))
    P = kn.StepParams(dt=dt, alpha=0.0, beta=0.0, growth_limit=1e300, sample_every=10 ** 9)
    u0 = np.zeros(op.n_owned)
    u0[2::NDOF_NODE] = 1e-7 * np.sin(op.x_nodes[:, 0] * 20.0)
    St = kn.new_state(op.n_owned, u0 * (op.minv > 0))
    H = kn.new_history(4, op.n_owned // NDOF_NODE)
    kn.advance(D, P, R, St, H, 2)
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        kn.advance(D, P, R, St, H, steps)
        best = min(best, (time.perf_counter() - t0) / steps)
    # sampling cost: one nodal recovery
    nodal = np.zeros((op.n_owned // NDOF_NODE, 4))
    from flexnet_fe.shell.recovery import sample_nodes
    sample_nodes(R, St.u, nodal)
    ts = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        sample_nodes(R, St.u, nodal)
        ts = min(ts, time.perf_counter() - t0)
    tp = np.inf
    for _ in range(3):
        t0 = time.perf_counter()
        for _s in central_difference(op, no_loads(op), dt, 10, 11, dt_crit=dt, u0=u0):
            pass
        tp = min(tp, (time.perf_counter() - t0) / 10)
    n = op.n_owned
    return {"dofs": n, "step_s": best, "ns_per_dof_step": best / n * 1e9,
            "bytes_per_step": step_bytes(D), "bandwidth_Bps": step_bytes(D) / best,
            "sample_ns_per_dof": ts / n * 1e9, "petsc_step_s": tp,
            "speedup_vs_petsc": tp / best}


def setup_time(n_side: int) -> dict:
    """Wall time of everything before the first step on an n_side² plate (mesh, forms, K, M,
    block storage, Lanczos dt_crit, recovery data, step data)."""
    t0 = time.perf_counter()
    m = api.plate(n_side, n_side, 0.5, 0.5, AL7075, supports={"root": Support.CLAMPED})
    t1 = time.perf_counter()
    lam, _ = max_eigenvalue(m.op)
    t2 = time.perf_counter()
    recovery_for(m)
    step_data(m, no_loads(m.op), LocalFrame(m.fin.plane))
    t3 = time.perf_counter()
    return {"dofs": m.op.n_owned, "setup_s": t3 - t0, "model_s": t1 - t0, "lanczos_s": t2 - t1,
            "kernel_data_s": t3 - t2}


def paper_fin_model(mesh_size: float) -> ShellModel:
    """The radar missile's wing_1 (Al 7075, 6 mm) meshed at ``mesh_size`` [m], clamped root."""
    import tempfile
    from flexnet_fe.missile.config import MissileConfig
    from flexnet_fe.missile.mesh import write_meshes

    with tempfile.TemporaryDirectory() as td:
        paths = write_meshes(MissileConfig(preset="radar", mesh_size=mesh_size), Path(td))
        return api.fin(paths["wing_1"], AL7075)


def cmd_kernel(args) -> dict:
    bw = stream_triad()
    print(f"STREAM triad (numba, 1 thread, 3 × 160 MB): {bw / 1e9:.2f} GB/s")
    rows = []
    for label, model in (("radar wing_1, 20 mm mesh", paper_fin_model(0.02)),
                         ("radar wing_1, 10 mm mesh", paper_fin_model(0.01)),
                         ("plate 141², 1e5 DOFs", api.plate(141, 141, 0.5, 0.5, AL7075,
                                                            supports={"root": "clamped"}))):
        r = time_kernel(model)
        r["triad_Bps"] = stream_triad(repeat=3)
        r["label"] = label
        rows.append(r)
        print(f"{label:26s} {r['dofs']:>7d} DOFs: {r['ns_per_dof_step']:6.2f} ns/DOF-step "
              f"({r['step_s'] * 1e6:8.1f} µs/step), {r['bandwidth_Bps'] / 1e9:5.2f} GB/s = "
              f"{r['bandwidth_Bps'] / r['triad_Bps']:5.1%} of the triad ({r['triad_Bps'] / 1e9:.1f}"
              f" GB/s); one stress sample {r['sample_ns_per_dof']:.1f} ns/DOF; PETSc step "
              f"{r['petsc_step_s'] * 1e6:.1f} µs ({r['speedup_vs_petsc']:.1f}× slower)")
    su = setup_time(141)
    print(f"set-up at {su['dofs']} DOFs: {su['setup_s']:.2f} s (model {su['model_s']:.2f}, "
          f"Lanczos {su['lanczos_s']:.2f}, kernel/recovery data {su['kernel_data_s']:.2f})")
    return {"triad_Bps": bw, "kernel": rows, "setup": su}


def plate_case(n: int):
    """The plate-pulse problem of tests/shell/test_plate_series.py on n × n: returns (CPU set-up
    [s], CPU solve [s], RMS centre-deflection error, peak von Mises error, ZZ estimate)."""
    mat = ShellMaterial(thickness=2e-3, youngs_modulus=70e9, poisson_ratio=0.3, density=2700.0)
    a, end = 0.2, 1e-3
    kt, kg = [0.0, 2.5e-4, 5e-4], [0.0, 1e4, 0.0]
    s = auto_rotary_scale(a / 32, mat)
    plate = navier.PlateData(a, a, 2e-3, 70e9, 0.3, 2700.0, rotary_scale=s)
    c0 = time.process_time()
    m = api.plate(n, n, a, a, mat, supports=Support.SIMPLY_SUPPORTED_HARD, rotary_scale=s)
    loads = api.pressure(m, kt, kg)
    lam, _ = max_eigenvalue(m.op)
    dt = 0.9 * critical_step(lam)
    R = recovery_for(m)
    c1 = time.process_time()
    centre = int(np.argmin(np.linalg.norm(m.op.x_nodes - [a / 2, a / 2, 0.0], axis=1)))
    tw = []
    every = max(1, round(1e-6 / dt))
    res = run(m, loads, R, dt=dt, n_steps=int(np.ceil(end / dt)), sample_every=every,
              frame_every=5 * every, frame=lambda t, u: tw.append((t, u[5 * centre + 2])))
    pk = locate_peak(R, res.u_peak, res.peak_node, m.V.tabulate_dof_coordinates(),
                     m.fin.plane.origin)
    c2 = time.process_time()
    t, w = np.array(tw).T
    keep = np.concatenate([[True], np.diff(t) > 0])
    t, w = t[keep], w[keep]
    wr = navier.fields(plate, navier.transient_amplitudes(plate, 61, t, kt, kg),
                       np.array([a / 2]), np.array([a / 2]))[0][:, 0]
    g = np.linspace(0.0, a / 2, 11)
    X, Y = (v.ravel() for v in np.meshgrid(g, g))
    vm_ref = von_mises(navier.fields(plate, navier.transient_amplitudes(plate, 61, res.t, kt, kg),
                                     X, Y)[1]).max()
    return (c1 - c0, c2 - c1, float(np.sqrt(np.mean((w - wr) ** 2)) / np.abs(wr).max()),
            float(pk.value / vm_ref - 1), float(pk.error_estimate_rel), m.op.n_owned, res.steps)


def cmd_plate(args) -> dict:
    rows = []
    for n in (8, 12, 16, 24, 32, 48, 64):
        su, so, ew, es, est, dofs, steps = plate_case(n)
        rows.append(dict(n=n, dofs=dofs, steps=steps, cpu_setup_s=su, cpu_solve_s=so,
                         rms_deflection_err=ew, peak_vm_err=es, zz_estimate=est))
        print(f"{n:3d}² ({dofs:6d} DOFs, {steps:5d} steps): CPU set-up {su:5.2f} s, solve "
              f"{so:6.2f} s; RMS deflection error {100 * ew:.3f} %, peak von Mises error "
              f"{100 * es:+.3f} % (ZZ estimate {100 * est:.3f} %)")
    _plate_chart(rows, ROOT / "docs" / "img" / "shell_plate_accuracy_cpu.png")
    return {"plate": rows}


def _plate_chart(rows, png: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cpu = np.array([r["cpu_setup_s"] + r["cpu_solve_s"] for r in rows])
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    ax.loglog(cpu, [100 * r["rms_deflection_err"] for r in rows], "o-",
              label="centre deflection, RMS over time")
    ax.loglog(cpu, [100 * abs(r["peak_vm_err"]) for r in rows], "s-",
              label="peak surface von Mises (recovered)")
    ax.loglog(cpu, [100 * r["zz_estimate"] for r in rows], "s:", color="C1", alpha=0.6,
              label="its ZZ error estimate")
    for r, c in zip(rows, cpu):
        ax.annotate(f"{r['n']}²", (c, 100 * r["rms_deflection_err"]), fontsize=7,
                    textcoords="offset points", xytext=(3, -9))
    ax.axhline(0.1, color="grey", lw=0.6, ls="--")
    ax.set_xlabel("CPU time, set-up + solve [s]")
    ax.set_ylabel("error vs Navier series [%]")
    ax.set_title("SS Reissner–Mindlin plate, uniform pressure pulse", fontsize=10)
    ax.grid(True, which="both", lw=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    png.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(png, dpi=120)
    print(f"chart: {png}")


def _run_stage(run_dir: Path, mesh_size: float, fins, out: Path, end_time=None,
               shell_set: dict | None = None) -> dict:
    from flexnet_fe.missile.config import MissileConfig
    from flexnet_fe.missile.build import build_missile
    from flexnet_fe.missile.mesh import write_meshes
    from flexnet_fe.shell.config import ShellConfig
    from flexnet_fe.shell.stage import fin_specs, run_shell

    resolved = json.loads((run_dir / "resolved.json").read_text())
    case = resolved.get("case", resolved)
    mcfg = MissileConfig.model_validate({**case["missile"], "mesh_size": mesh_size})
    shell = ShellConfig.model_validate({**(case.get("shell") or {}),
                                        **({"fins": "named", "fin_names": list(fins)} if fins
                                           else {}),
                                        **({"end_time": end_time} if end_time else {}),
                                        **(shell_set or {})})
    paths = write_meshes(mcfg, out / "meshes")
    specs = fin_specs(build_missile(mcfg).fins, paths)
    log = logging.getLogger("bench_shell")
    t0 = time.perf_counter()
    s = run_shell(shell, specs, run_dir / "collide" / "fin_contacts.npz",
                  run_dir / "collide" / "history.csv", out / "shell", log)
    s["bench_wall_s"] = time.perf_counter() - t0
    return s


def cmd_paper(args) -> dict:
    run_dir = Path(args.run_dir)
    sizes = [float(x) for x in args.sizes.split(",")]
    fins = [f for f in args.fins.split(",") if f] if args.fins else None
    import tempfile
    rows = []
    shell_set = {"stvenant_radius_factor": args.factor}
    if args.peak_interval:
        shell_set["peak_interval"] = args.peak_interval
    local = [float(x) for x in args.local.split(",")] if args.local else []
    runs = [(h, None) for h in sizes] + [(sizes[-1] if sizes else 0.02, hl) for hl in local]
    for h, hl in runs:
        with tempfile.TemporaryDirectory() as td:
            s = _run_stage(run_dir, h, fins, Path(td), args.end_time,
                           {**shell_set, "local_mesh_size": hl})
        if hl is not None:
            h = hl
        for name, r in s.items():
            if isinstance(r, dict) and "peak_von_mises_pa" in r:
                rows.append(dict(mesh_size=h, fin=name, factor=args.factor,
                                 peak=r["peak_von_mises_pa"], t=r["peak_time_s"],
                                 loc=r["peak_location_m"], est=r["peak_error_estimate_rel"],
                                 raw=r["peak_von_mises_with_load_zones_pa"],
                                 p1=r["peak_max_principal_pa"], bearing=r["peak_bearing_pa"],
                                 bearing_kind=r["peak_bearing_kind"],
                                 radius=r["stvenant_radius_m"], dofs=r["dofs"],
                                 steps=r["steps"], wall=s["bench_wall_s"], local=hl,
                                 h_min=r["h_min_m"]))
                print(f"h = {1e3 * h:5.2f} mm {name:9s} {r['dofs']:7d} DOFs {r['steps']:7d} steps:"
                      f" structural peak {r['peak_von_mises_pa'] / 1e6:9.2f} MPa at "
                      f"{1e3 * r['peak_time_s']:.4f} ms {r['peak_location_m']}, ZZ estimate "
                      f"{100 * r['peak_error_estimate_rel']:.2f} % (r_ex "
                      f"{1e3 * r['stvenant_radius_m']:.1f} mm; with the load zones "
                      f"{r['peak_von_mises_with_load_zones_pa'] / 1e6:.1f} MPa; bearing "
                      f"{r['peak_bearing_pa'] / 1e6:.1f} MPa {r['peak_bearing_kind']})", flush=True)
        print(f"h = {1e3 * h:5.2f} mm: stage wall {s['bench_wall_s']:.1f} s", flush=True)
    for name in sorted({r["fin"] for r in rows}):
        _orders([(r["mesh_size"], r["peak"]) for r in rows if r["fin"] == name], name)
    return {"paper": rows}


def cmd_case(args) -> dict:
    import tempfile
    run_dir = Path(args.run_dir)
    resolved = json.loads((run_dir / "resolved.json").read_text())
    case = resolved.get("case", resolved)
    h = case["missile"].get("mesh_size", 0.02)
    walls = []
    for _ in range(2):  # first run warms the caches
        with tempfile.TemporaryDirectory() as td:
            s = _run_stage(run_dir, h, None, Path(td))
        walls.append(s["bench_wall_s"])
    print(f"shell stage at the case's mesh ({1e3 * h:.1f} mm): {walls[-1]:.2f} s warm "
          f"(cold {walls[0]:.2f} s), {s['dofs']} DOFs, {s['steps']} steps")
    return {"case": {"mesh_size": h, "wall_warm_s": walls[-1], "wall_cold_s": walls[0],
                     "dofs": s["dofs"], "steps": s["steps"]}}


def _static_event(run_dir: Path, fin: str, h_local: float, time_s: float, part: str,
                  work: Path) -> dict:
    """Static response of ``fin`` (mesh refined to ``h_local`` [m] at its loads) to the largest
    contact event of the sample nearest ``time_s`` [s] (``part``: all, in-plane or normal
    component): structural peak outside its zone, and ring maxima of the recovered von Mises."""
    from mpi4py import MPI
    from flexnet_fe.missile.build import build_missile
    from flexnet_fe.missile.config import MissileConfig
    from flexnet_fe.missile.mesh import write_meshes
    from flexnet_fe.shell import hotspot, stage as stg
    from flexnet_fe.shell.config import ShellConfig
    from flexnet_fe.shell.meshio import load_fin_mesh
    from flexnet_fe.shell.model import build_model
    from flexnet_fe.shell.recovery import nodal_strains, shape_q1, stress_tensors
    from flexnet_fe.shell.transfer import FinGeometry, contact_transfer

    case = json.loads((run_dir / "resolved.json").read_text())
    case = case.get("case", case)
    mcfg = MissileConfig.model_validate({**case["missile"], "mesh_size": 0.02})
    shell = ShellConfig.model_validate({**(case.get("shell") or {}), "local_mesh_size": h_local})
    spec = {s.name: s for s in stg.fin_specs(build_missile(mcfg).fins,
                                             write_meshes(mcfg, work / "meshes"))}[fin]
    con = stg.read_fin_contacts(run_dir / "collide" / "fin_contacts.npz")
    idx = con.fin_names.index(fin)
    fm = load_fin_mesh(stg._fin_mesh_path(shell, spec, con, idx, work, MPI.COMM_WORLD),
                       MPI.COMM_WORLD)
    mat = ShellMaterial(thickness=spec.thickness, youngs_modulus=spec.youngs_modulus,
                        poisson_ratio=spec.poisson_ratio, density=spec.density,
                        yield_strength=spec.yield_strength)
    model = build_model(fm, mat, supports=dict(shell.supports))
    pl = model.fin.plane
    k = int(np.argmin(np.abs(con.t - time_s)))
    sel = np.flatnonzero((con.fin == idx) & (con.sample == k))
    e = sel[np.argmax(np.linalg.norm(con.force[sel], axis=1))]
    F = con.force[e] - (con.force[e] @ pl.n) * pl.n if part == "inplane" else (
        (con.force[e] @ pl.n) * pl.n if part == "normal" else con.force[e])
    fg = FinGeometry(mesh=model.V.mesh, V=model.V, origin=pl.origin, e1=pl.e1, e2=pl.e2, n=pl.n)
    G = contact_transfer(fg, con.point[[e]], con.width[[e]], plane_tol=2 * mat.thickness)
    u = api.static(model, np.asarray(G @ F).ravel())
    R = recovery_for(model)
    x = model.V.tabulate_dof_coordinates()
    p0 = con.point[e] - ((con.point[e] - pl.origin) @ pl.n) * pl.n
    rex = float(hotspot.exclusion_radius(mat.thickness, con.width[[e]],
                                         shell.stvenant_radius_factor)[0])
    s6 = nodal_strains(R, u)
    t = mat.thickness

    def vm(s):
        return np.maximum(von_mises(stress_tensors(s, R, 0.5 * t)),
                          von_mises(stress_tensors(s, R, -0.5 * t)))

    near = np.flatnonzero(np.linalg.norm(x[R.cells].mean(axis=1) - p0, axis=1) < 0.045)
    g = np.linspace(0.0, 1.0, 21)
    N = shape_q1(np.repeat(g, 21), np.tile(g, 21))
    r = np.linalg.norm(np.einsum("mk,ckd->cmd", N, x[R.cells[near]]).reshape(-1, 3) - p0, axis=1)
    vq = vm(np.einsum("mk,ckd->cmd", N, s6[R.cells[near]]).reshape(-1, 6))
    vn = np.where(np.linalg.norm(x - p0, axis=1) < rex, 0.0, vm(s6))
    node = int(np.argmax(vn))
    pk = locate_peak(R, u, node, x, pl.origin, exclude=(p0[None], np.array([rex])))
    rings = {f"ring_{int(round(rr * 1e3))}mm_pa": float(vq[(r >= rr) & (r < rr + 1e-4)].max())
             for rr in (9e-3, 12e-3, 15e-3, 18e-3, 24e-3)}
    return dict(fin=fin, local=h_local, part=part, force_n=[float(v) for v in F],
                dofs=int(len(u)), r_ex=rex, peak_pa=pk.value,
                peak_r_m=float(np.linalg.norm(pk.location - p0)), zz=pk.error_estimate_rel,
                **rings)


def cmd_zone(args) -> dict:
    import tempfile
    rows = []
    for h in (float(v) for v in args.local.split(",")):
        with tempfile.TemporaryDirectory() as td:
            r = _static_event(Path(args.run_dir), args.fin, h, args.time, args.part, Path(td))
        rows.append(r)
        rings = ", ".join(f"{k[5:-3]} {v / 1e6:.1f}" for k, v in r.items() if k.startswith("ring"))
        print(f"{args.fin} {args.part} static, {1e3 * h:.3f} mm at the loads, {r['dofs']} DOFs: "
              f"structural peak {r['peak_pa'] / 1e6:.2f} MPa at r = {1e3 * r['peak_r_m']:.2f} mm "
              f"(r_ex {1e3 * r['r_ex']:.1f} mm, ZZ {100 * r['zz']:.1f} %); ring maxima [MPa]: "
              f"{rings}", flush=True)
    _orders([(r["local"], r["peak_pa"]) for r in rows], args.fin)
    return {"zone": rows}


def _orders(pk, name: str) -> None:
    """Observed order and Richardson limit from the last three (h, value) pairs."""
    if len(pk) < 3:
        return
    (h1, s1), (h2, s2), (h3, s3) = pk[-3:]
    if (s2 - s1) * (s3 - s2) > 0 and abs(s3 - s2) < abs(s2 - s1):
        p = np.log(abs((s2 - s1) / (s3 - s2))) / np.log(h1 / h2)
        ext = s3 + (s3 - s2) / ((h2 / h3) ** p - 1)
        print(f"{name}: observed order {p:.2f}, Richardson limit {ext / 1e6:.2f} MPa, "
              f"finest mesh {100 * (s3 / ext - 1):+.2f} %")
    else:
        print(f"{name}: peaks {[f'{v / 1e6:.1f}' for _, v in pk]} MPa — not monotone, no order")


def reference_run(K, minv, wfix, normal, loads, dt: float, n_steps: int, alpha: float,
                  beta: float, checkpoints, dtype=np.longdouble) -> dict:
    """The explicit scheme (explicit.central_difference: lumped M, w-fixed projection) re-done
    in numpy at ``dtype`` (x87 80-bit extended: eps 1.1e-19) on given double-precision data:
    K a scipy CSR matrix, minv (n,), wfix (n_nodes,), normal (3,), loads a LoadHistory — a
    reference whose own round-off is 2 000× smaller. Returns {step: u (float64)}."""
    K = K.tocsr()
    rows = np.repeat(np.arange(K.shape[0]), np.diff(K.indptr))
    aj, av = K.indices, K.data.astype(dtype)
    minv = np.asarray(minv, dtype=dtype)
    nrm = np.asarray(normal, dtype=dtype)
    wf = np.asarray(wfix) != 0
    n = K.shape[0]
    u, v = np.zeros(n, dtype), np.zeros(n, dtype)
    free3 = minv.reshape(-1, NDOF_NODE)[:, :3] > 0
    out = {}

    def interp(times, t):
        k = min(int(np.searchsorted(times, t, side="right")) - 1, len(times) - 2)
        return k, (dtype(t) - dtype(times[k])) / (dtype(times[k + 1]) - dtype(times[k]))

    for step in range(1, n_steps + 1):
        t = (step - 1) * dt
        x = u + dtype(beta) * v if beta else u
        y = np.zeros(n, dtype)
        np.add.at(y, rows, av * x[aj])
        fe = np.zeros(n, dtype)
        P = loads.nodal
        if len(loads.times) and loads.times[0] <= t <= loads.times[-1]:
            k, sfr = interp(loads.times, t)
            for j, wgt in ((k, 1 - sfr), (k + 1, sfr)):
                lo, hi = P.indptr[j], P.indptr[j + 1]
                np.add.at(fe, P.indices[lo:hi], wgt * P.data[lo:hi].astype(dtype))
        at = loads.accel_times
        if len(at) and at[0] <= t <= at[-1]:
            k, sfr = interp(at, t)
            acc = (1 - sfr) * loads.accel[k].astype(dtype) + sfr * loads.accel[k + 1].astype(dtype)
            for c in range(3):
                fe -= acc[c] * loads.mass_c[c].astype(dtype)
        h = dtype(0.5 * dt if step == 1 else dt)
        v += h * (minv * (fe - y) - dtype(alpha) * v)
        vb = v.reshape(-1, NDOF_NODE)
        vb[wf, :3] -= (vb[wf, :3] @ nrm)[:, None] * nrm[None, :]
        vb[:, :3] *= free3
        u += dtype(dt) * v
        ub = u.reshape(-1, NDOF_NODE)
        ub[wf, :3] -= (ub[wf, :3] @ nrm)[:, None] * nrm[None, :]
        if step in checkpoints:
            out[step] = u.astype(np.float64)
    return out


def split_to_csr(K: kn.SplitUpper):
    """The compiled kernel's matrix (fin frame, membrane/bending blocks, upper triangle) as a
    full scipy CSR matrix with the same double values."""
    from scipy import sparse
    r, c, v = [], [], []
    nrow = np.repeat(np.arange(len(K.indptr) - 1), np.diff(K.indptr))
    for p, (i, j) in enumerate(zip(nrow, K.indices)):
        for a in range(2):
            for b in range(2):
                r.append(5 * i + a), c.append(5 * j + b), v.append(K.mem[p, 2 * a + b])
                if i != j:
                    r.append(5 * j + b), c.append(5 * i + a), v.append(K.mem[p, 2 * a + b])
        for a in range(3):
            for b in range(3):
                r.append(5 * i + 2 + a), c.append(5 * j + 2 + b), v.append(K.bend[p, 3 * a + b])
                if i != j:
                    r.append(5 * j + 2 + b), c.append(5 * i + 2 + a), v.append(K.bend[p, 3 * a + b])
    n = 5 * (len(K.indptr) - 1)
    return sparse.csr_matrix((v, (r, c)), shape=(n, n))


def cmd_agreement(args) -> dict:
    """Compiled vs PETSc step over 1 000 steps (the problem of tests/shell/test_kernel.py), both
    against the extended-precision reference: is their 3–6e-12 difference round-off growth?"""
    from flexnet_fe.shell.explicit import Backend
    from flexnet_fe.shell.forms import Support as Sup
    sys.path.insert(0, str(ROOT))
    from tests.shell.conftest import A1, A2, ORIGIN
    from tests.shell.test_kernel import MAT, _loads
    rows = []
    for tilted in (True, False):
        kw = dict(origin=ORIGIN, a1=A1, a2=A2) if tilted else {}
        m = api.plate(10, 6, 0.3, 0.15, MAT, supports={"root": Sup.CLAMPED,
                                                      "tip": Sup.SIMPLY_SUPPORTED}, **kw)
        loads = _loads(m)
        lam, _ = max_eigenvalue(m.op)
        dt = 0.9 * critical_step(lam, 50.0, 1e-7)
        R = recovery_for(m)
        marks = (10, 100, 1000)
        from scipy import sparse
        from tests.shell.conftest import scipy_matrix
        from flexnet_fe.shell.explicit import LoadHistory
        ref = reference_run(scipy_matrix(m.op), m.op.minv, m.op.wfix, m.op.normal, loads, dt,
                            1000, 50.0, 1e-7, marks)
        # the compiled kernel's own data (fin frame: rotated and split K, rotated loads)
        lf = LocalFrame(m.fin.plane)
        D = step_data(m, loads, lf)
        mc = np.zeros((3, len(D.mass_t)))
        for c in range(3):
            mc[c, c::NDOF_NODE] = D.mass_t[c::NDOF_NODE]
        loc_loads = LoadHistory(times=D.times, nodal=sparse.csc_matrix(
            (D.vals, D.rows, D.colptr), shape=(len(D.minv), len(D.times))),
            accel_times=D.acc_times, accel=D.acc, mass_c=mc)
        ref_loc = reference_run(split_to_csr(D.K), D.minv, D.wfix, np.array([0.0, 0.0, 1.0]),
                                loc_loads, dt, 1000, 50.0, 1e-7, marks)
        ref_loc = {k: lf.to_body(v) for k, v in ref_loc.items()}
        for n in marks:
            u = {be: run(m, loads, R, dt=dt, n_steps=n, sample_every=10, frame_every=10 * n,
                         alpha=50.0, beta=1e-7, backend=be).u
                 for be in (Backend.COMPILED, Backend.PETSC)}
            nr = np.linalg.norm(ref[n])
            r = dict(tilted=tilted, steps=n,
                     compiled_vs_petsc=np.linalg.norm(u[Backend.COMPILED] - u[Backend.PETSC]) / nr,
                     compiled_vs_ref=np.linalg.norm(u[Backend.COMPILED] - ref[n]) / nr,
                     petsc_vs_ref=np.linalg.norm(u[Backend.PETSC] - ref[n]) / nr,
                     compiled_vs_own_ref=np.linalg.norm(u[Backend.COMPILED] - ref_loc[n]) / nr,
                     ref_vs_own_ref=np.linalg.norm(ref[n] - ref_loc[n]) / nr)
            rows.append(r)
            print(f"{'tilted' if tilted else 'flat  '} {n:5d} steps: compiled−PETSc "
                  f"{r['compiled_vs_petsc']:.2e}, compiled−ref {r['compiled_vs_ref']:.2e}, "
                  f"PETSc−ref {r['petsc_vs_ref']:.2e}; compiled − ref on its own data "
                  f"{r['compiled_vs_own_ref']:.2e}, ref(frame B K) − ref(fin-frame split K) "
                  f"{r['ref_vs_own_ref']:.2e} (‖·‖₂ / ‖u_ref‖)", flush=True)
    return {"agreement": rows}


def main() -> None:
    ap = argparse.ArgumentParser()
    sub = ap.add_subparsers(dest="cmd", required=True)
    sub.add_parser("kernel")
    sub.add_parser("plate")
    p = sub.add_parser("paper")
    p.add_argument("run_dir")
    p.add_argument("--fins", default="")
    p.add_argument("--sizes", default="0.02,0.01,0.005")
    p.add_argument("--end-time", type=float, default=None)
    p.add_argument("--local", default="",
                   help="local element sizes around the contacts [m] (on the last --sizes mesh)")
    p.add_argument("--factor", type=float, default=2.0,
                   help="shell.stvenant_radius_factor (0: peaks at the loads included)")
    p.add_argument("--peak-interval", type=float, default=None,
                   help="shell.peak_interval [s] (default: the case's)")
    z = sub.add_parser("zone")
    z.add_argument("run_dir")
    z.add_argument("fin")
    z.add_argument("--time", type=float, required=True)
    z.add_argument("--part", default="all", choices=("all", "inplane", "normal"))
    z.add_argument("--local", default="0.005,0.0025,0.00125,0.000625")
    sub.add_parser("agreement")
    c = sub.add_parser("case")
    c.add_argument("run_dir")
    args = ap.parse_args()
    out = {"kernel": cmd_kernel, "plate": cmd_plate, "paper": cmd_paper, "case": cmd_case,
           "agreement": cmd_agreement, "zone": cmd_zone}[
        args.cmd](args)
    print(json.dumps(out, default=float))


if __name__ == "__main__":
    main()
