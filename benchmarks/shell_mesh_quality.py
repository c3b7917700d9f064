"""Fin mesh quality and the shell stage's explicit step (issue 10): the refined fin meshes of a
finished run, per Gmsh recombination scheme (``flexnet_fe.missile.mesh.REFINED_SCHEMES``), side
by side in one run.

Mesh table (cheap, every fin of the run): the fin re-meshed exactly as the shell stage does it
(``shell.local_mesh_size`` within r_ex + 2 local sizes of the fin's contact points), then
  - element edge lengths inside that refined zone (cells whose centre lies within it):
    5th percentile / median / 95th percentile against the requested size;
  - h_min (shortest edge of the fin, what the stage logs) and the smallest characteristic length
    L = √2 A / √(d1² + d2²) (= h for a square of side h; A area, d1, d2 diagonals);
  - DOFs (5 per node), dt_crit by the stage's Lanczos estimate, c_p dt_crit (the "length" the
    step sees: c_p dt_crit = h on a square mesh of side h, measured here on a 40 × 40 plate),
    DOF-steps per simulated ms at dt = safety_factor × dt_crit (the stage's cost measure).

Accuracy table (``--solve wing_1,rudder_2``, optionally at other ``--solve-sizes``): the shell
stage on those fins, each in its own window (``shell.window = "fin"``, as the case), with each
scheme (``shell.local_mesh_scheme``): peak von Mises (the structural peak of the report), its ZZ
error estimate, steps, DOFs, DOF-steps and wall time.

    PYTHONPATH=$PWD .venv/bin/python benchmarks/shell_mesh_quality.py /tmp/lead4_def \\
        --solve wing_1,rudder_2 --solve-sizes 0.0025,0.00125 --json /tmp/mesh_quality.json
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_shell import _run_stage  # noqa: E402

from flexnet_fe.missile.build import build_missile  # noqa: E402
from flexnet_fe.missile.config import MissileConfig  # noqa: E402
from flexnet_fe.missile.mesh import (REFINED_SCHEMES, fin_outline_from_msh,  # noqa: E402
                                     write_meshes, write_refined_fin_mesh)
from flexnet_fe.msh import read_msh_nodes_and_cells  # noqa: E402
from flexnet_fe.shell import hotspot  # noqa: E402
from flexnet_fe.shell.config import ShellConfig  # noqa: E402
from flexnet_fe.shell.explicit import critical_step, max_eigenvalue  # noqa: E402
from flexnet_fe.shell.forms import NDOF_NODE, ShellMaterial  # noqa: E402
from flexnet_fe.shell.meshio import load_fin_mesh, write_plate_msh  # noqa: E402
from flexnet_fe.shell.model import build_model  # noqa: E402


def quad_measures(x: np.ndarray, quads: np.ndarray):
    """(edge lengths (nc, 4) [m], characteristic lengths √2 A/√(d1² + d2²) (nc,) [m], cell
    centres (nc, 3) [m]) of quadrilaterals ``quads`` (nc, 4) on nodes ``x`` (n, 3) [m]."""
    edges = np.linalg.norm(x[quads] - x[np.roll(quads, -1, axis=1)], axis=2)
    d1, d2 = x[quads[:, 2]] - x[quads[:, 0]], x[quads[:, 3]] - x[quads[:, 1]]
    area = 0.5 * np.linalg.norm(np.cross(d1, d2), axis=1)
    char = math.sqrt(2.0) * area / np.sqrt((d1 ** 2).sum(1) + (d2 ** 2).sum(1))
    return edges, char, x[quads].mean(axis=1)


def lanczos_dt(path: Path, mat: ShellMaterial, lanczos_steps: int) -> tuple[float, int]:
    """(dt_crit [s] by the stage's Lanczos estimate, DOFs) of the clamped-root fin mesh."""
    model = build_model(load_fin_mesh(path), mat, "auto")
    lam, _ = max_eigenvalue(model.op, steps=lanczos_steps)
    return critical_step(lam), model.V.dofmap.index_map.size_global * NDOF_NODE


def limiting_node(path: Path, mat: ShellMaterial) -> dict:
    """Where the step is set: the largest eigenpair of M^-1/2 K M^-1/2 (scipy ``eigsh``, serial)
    — its node of largest amplitude, the DOF kind (0-2 translations, 3-4 rotations), the share
    of the mode's squared amplitude on that node and on the four largest, the node's position
    [m] and the edges [m] of the cells around it."""
    from scipy import sparse
    from scipy.sparse.linalg import eigsh

    model = build_model(load_fin_mesh(path), mat, "auto")
    ai, aj, av = model.op.K.convert("aij").getValuesCSR()
    d = sparse.diags(np.sqrt(model.op.minv))
    lam, vec = eigsh(d @ sparse.csr_matrix((av, aj, ai)) @ d, k=1, which="LA")
    amp = vec[:, 0].reshape(-1, NDOF_NODE) ** 2
    per_node = amp.sum(axis=1)
    order = np.argsort(per_node)[::-1]
    node = int(order[0])
    x = model.V.tabulate_dof_coordinates()
    cells = model.V.dofmap.list.array.reshape(-1, 4)[:, [0, 1, 3, 2]]  # dolfinx → cyclic
    around = cells[(cells == node).any(axis=1)]
    edges, _, _ = quad_measures(x, around)
    return dict(cp_dt_crit_m=math.sqrt(mat.plane_stress_modulus / mat.density) * 2.0
                / math.sqrt(lam[0]), node_m=x[node].tolist(), dof=int(np.argmax(amp[node])),
                share_1=float(per_node[node] / per_node.sum()),
                share_4=float(per_node[order[:4]].sum() / per_node.sum()),
                cells_around=len(around), edges_around_m=edges.round(6).tolist())


def mesh_rows(run_dir: Path, fins: list[str], schemes: list[str], work: Path,
              where: bool = False) -> list[dict]:
    """One row per (fin, scheme): refined-zone edge statistics, h_min, DOFs, dt_crit, cost."""
    case = json.loads((run_dir / "resolved.json").read_text())["case"]
    shell = ShellConfig.model_validate(case.get("shell") or {})
    mcfg = MissileConfig.model_validate(case["missile"])
    coarse = write_meshes(mcfg, work / "meshes")
    specs = {f.name: f for f in build_missile(mcfg).fins}
    with np.load(run_dir / "collide" / "fin_contacts.npz") as z:
        names, fin, point, width = (list(z["fin_names"]), z["fin"], z["point"], z["width"])
    hl = shell.local_mesh_size
    rows = []
    for name in fins:
        f = specs[name]
        mat = ShellMaterial(thickness=f.thickness, youngs_modulus=f.material.youngs_modulus,
                            poisson_ratio=f.material.poisson_ratio, density=f.material.density)
        c_p = math.sqrt(mat.plane_stress_modulus / mat.density)
        sel = fin == names.index(name)
        r_ex = float(hotspot.exclusion_radius(f.thickness, width[sel],
                                              max(shell.stvenant_radius_factor, 1.0)).max())
        zone = r_ex + 2.0 * hl  # as shell.stage._fin_mesh_path
        corners, h = fin_outline_from_msh(coarse[name])
        for scheme in schemes:
            path = work / f"{name}_{scheme}.msh"
            t0 = time.perf_counter()
            write_refined_fin_mesh(corners, max(h, hl), point[sel], hl, zone, path,
                                   scheme=scheme)
            t_mesh = time.perf_counter() - t0
            x, cells = read_msh_nodes_and_cells(path)
            edges, char, centre = quad_measures(x, next(iter(cells.values())))
            inz = cKDTree(point[sel]).query(centre)[0] < zone
            ez = edges[inz].ravel()
            dt_crit, dofs = lanczos_dt(path, mat, shell.lanczos_steps)
            dt = shell.safety_factor * dt_crit
            rows.append(dict(fin=name, scheme=scheme, requested_m=hl, zone_cells=int(inz.sum()),
                             zone_edge_p5_m=float(np.percentile(ez, 5)),
                             zone_edge_median_m=float(np.median(ez)),
                             zone_edge_p95_m=float(np.percentile(ez, 95)),
                             h_min_m=float(edges.min()), char_min_m=float(char.min()),
                             dofs=dofs, dt_crit_s=dt_crit, cp_dt_crit_m=c_p * dt_crit,
                             dof_steps_per_ms=dofs * 1e-3 / dt, mesh_s=t_mesh))
            print(_fmt_mesh(rows[-1]), flush=True)
            if where:
                rows[-1]["limiting"] = limiting_node(path, mat)
                print("    step set at", rows[-1]["limiting"], flush=True)
    return rows


def square_reference(mat: ShellMaterial, size: float, lanczos_steps: int, work: Path) -> float:
    """c_p dt_crit / h of a structured 40 × 40 plate of square cells of side ``size``."""
    path = write_plate_msh(work / "square.msh", 40, 40, 40 * size, 40 * size)
    dt_crit, _ = lanczos_dt(path, mat, lanczos_steps)
    return math.sqrt(mat.plane_stress_modulus / mat.density) * dt_crit / size


def _fmt_mesh(r: dict) -> str:
    mm = 1e3
    return (f"{r['fin']:9s} {r['scheme']:9s} zone edge p5/median/p95 "
            f"{r['zone_edge_p5_m'] * mm:.3f}/{r['zone_edge_median_m'] * mm:.3f}/"
            f"{r['zone_edge_p95_m'] * mm:.3f} mm (requested {r['requested_m'] * mm:.3f}), "
            f"h_min {r['h_min_m'] * mm:.3f} mm, L_min {r['char_min_m'] * mm:.3f} mm, "
            f"{r['dofs']} DOFs, dt_crit {r['dt_crit_s']:.4e} s (c_p dt {r['cp_dt_crit_m'] * mm:.3f}"
            f" mm), {r['dof_steps_per_ms']:.3e} DOF-steps/ms, mesh {r['mesh_s']:.1f} s")


def solve_rows(run_dir: Path, fins: list[str], schemes: list[str],
               sizes: list[float | None]) -> list[dict]:
    """The shell stage on each fin alone (its own window, as the case) with each scheme, at each
    ``local_mesh_size`` of ``sizes`` (None: the case's)."""
    case = json.loads((run_dir / "resolved.json").read_text())["case"]
    rows = []
    for name in fins:
        for size in sizes:
            for scheme in schemes:
                rows.append(_solve_one(run_dir, case, name, scheme, size))
    return rows


def _solve_one(run_dir: Path, case: dict, name: str, scheme: str, size: float | None) -> dict:
    shell_set = {"workers": 1, "local_mesh_scheme": scheme}
    if size is not None:
        shell_set["local_mesh_size"] = size
    with tempfile.TemporaryDirectory() as td:
        t0 = time.perf_counter()
        s = _run_stage(run_dir, case["missile"]["mesh_size"], [name], Path(td), None, shell_set)
        wall = time.perf_counter() - t0
    f = s[name]
    r = dict(fin=name, scheme=scheme, local_mesh_size_m=f["local_mesh_size_m"],
             peak_von_mises_pa=f["peak_von_mises_pa"],
             peak_time_s=f["peak_time_s"], peak_error_estimate_rel=f["peak_error_estimate_rel"],
             dofs=f["dofs"], steps=f["steps"], dt_s=f["dt_s"], dof_steps=f["dofs"] * f["steps"],
             h_min_m=f["h_min_m"], loops_wall_s=s["loops_wall_s"], wall_s=wall)
    print(f"{name:9s} {scheme:9s} {1e3 * r['local_mesh_size_m']:.4g} mm: peak "
          f"{r['peak_von_mises_pa'] / 1e6:.1f} MPa at {r['peak_time_s'] * 1e3:.4f} ms (ZZ "
          f"{100 * r['peak_error_estimate_rel']:.2f} %), {r['dofs']} DOFs x {r['steps']} steps = "
          f"{r['dof_steps']:.3e} DOF-steps (dt {r['dt_s']:.4e} s), loops "
          f"{r['loops_wall_s']:.1f} s, stage {r['wall_s']:.1f} s", flush=True)
    return r


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("run_dir", help="a finished run (collide/fin_contacts.npz, resolved.json)")
    ap.add_argument("--fins", default="", help="mesh table fins (default: every loaded fin)")
    ap.add_argument("--schemes", default=",".join(REFINED_SCHEMES))
    ap.add_argument("--solve", default="", help="fins to run the shell stage on, per scheme")
    ap.add_argument("--solve-sizes", default="",
                    help="local_mesh_size values [m] for --solve (default: the case's)")
    ap.add_argument("--where", action="store_true",
                    help="also locate each mesh's limiting mode (scipy eigsh; slower)")
    ap.add_argument("--json", default="")
    a = ap.parse_args(argv)
    run_dir = Path(a.run_dir)
    schemes = a.schemes.split(",")
    with np.load(run_dir / "collide" / "fin_contacts.npz") as z:
        loaded = [str(z["fin_names"][i]) for i in np.unique(z["fin"])]
    fins = a.fins.split(",") if a.fins else loaded
    out: dict = {}
    with tempfile.TemporaryDirectory() as td:
        mat = ShellMaterial(thickness=0.004, youngs_modulus=71.7e9, poisson_ratio=0.33,
                            density=2810.0)
        out["square_cp_dt_over_h"] = square_reference(mat, 1.25e-3, 40, Path(td))
        print(f"structured square cells (40 x 40, 1.25 mm): c_p dt_crit / h = "
              f"{out['square_cp_dt_over_h']:.3f}", flush=True)
        out["mesh"] = mesh_rows(run_dir, fins, schemes, Path(td), a.where)
    if a.solve:
        sizes = [float(x) for x in a.solve_sizes.split(",")] if a.solve_sizes else [None]
        out["solve"] = solve_rows(run_dir, a.solve.split(","), schemes, sizes)
    if a.json:
        Path(a.json).write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
