"""Gmsh meshes of the missile: one all-quadrilateral shell mesh per fin, a body surface mesh.

Fin meshes: the fin's mid-plane trapezoid placed in 3-D where it sits on the missile (body frame
B, :mod:`flexnet_fe.missile.geometry`), meshed as a transfinite (structured) grid and recombined
into quadrilaterals only — dolfinx 0.5.2 cannot load mixed triangle/quadrilateral meshes. Root and
tip get ``n_chord`` divisions, leading and trailing edge ``n_span`` divisions:
``n_chord = ceil(mean chord / h_e)``, ``n_span = ceil(longer of LE, TE / h_e)`` with the element
size h_e = ``cfg.mesh_size``. Physical groups (names and fixed tags in :data:`PHYSICAL_TAGS`):
``surface`` (2-D), ``root``, ``leading_edge``, ``tip``, ``trailing_edge`` (1-D).

Body mesh (pictures only, triangles): the body profile revolved about the x_b axis; physical
surfaces ``nose``, ``body`` (cylinder), ``base``.

Gmsh 4.8.4 (Debian) crashes with ``Mesh.Algorithm = 8`` (re-checked for issue 10: a segmentation
fault on a refined fin with the Threshold size field); it is not used here. dolfinx 0.5.2's
``gmshio.read_from_msh`` is broken (undefined names), so ``flexnet_fe.shell.meshio.load_fin_mesh`` opens the file with
gmsh on rank 0 and calls ``gmshio.model_to_mesh(..., gdim=3)`` itself. gmsh is initialised once per
process and never finalised here (see :func:`gmsh_model`).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from flexnet_fe.missile.config import MissileConfig
from flexnet_fe.missile.geometry import EDGE_NAMES, Fin, Missile, PrimKind
from flexnet_fe.missile.build import build_missile
from flexnet_fe.msh import gmsh_model, read_msh_nodes_and_cells
from flexnet_fe.runs import BODY_MSH

PHYSICAL_TAGS: dict[str, int] = {"surface": 1, "root": 11, "leading_edge": 12, "tip": 13,
                                 "trailing_edge": 14}
"""Physical-group tags of every fin mesh (cell tags: ``surface``; facet tags: the four edges)."""

BODY_TAGS: dict[str, int] = {"body": 1, "nose": 2, "base": 3}
"""Physical-group tags of the body surface mesh."""


def fin_divisions(fin: Fin, mesh_size: float) -> tuple[int, int]:
    """(n_chord, n_span): element counts along root/tip and along leading/trailing edge."""
    n_chord = max(1, math.ceil(0.5 * (fin.root_chord + fin.tip_chord) / mesh_size))
    n_span = max(1, math.ceil(max(fin.edge_length(1), fin.edge_length(3)) / mesh_size))
    return n_chord, n_span


def build_fin_model(gmsh, fin: Fin, mesh_size: float) -> None:
    """Add the fin's all-quadrilateral mesh with its physical groups to the current gmsh model."""
    geo = gmsh.model.geo
    pts = [geo.addPoint(*map(float, c)) for c in fin.corners]  # root TE, root LE, tip LE, tip TE
    lines = [geo.addLine(pts[k], pts[(k + 1) % 4]) for k in range(4)]  # EDGE_NAMES order
    loop = geo.addCurveLoop(lines)
    surf = geo.addPlaneSurface([loop])
    n_chord, n_span = fin_divisions(fin, mesh_size)
    for k, line in enumerate(lines):
        geo.mesh.setTransfiniteCurve(line, (n_chord if k in (0, 2) else n_span) + 1)
    geo.mesh.setTransfiniteSurface(surf, "Left", pts)
    geo.mesh.setRecombine(2, surf)
    geo.synchronize()
    _tag_and_generate(gmsh, surf, lines)


def _tag_and_generate(gmsh, surf: int, lines) -> None:
    """Name the fin surface and its four edges (:data:`PHYSICAL_TAGS`) and mesh it in 2-D."""
    gmsh.model.addPhysicalGroup(2, [surf], PHYSICAL_TAGS["surface"])
    gmsh.model.setPhysicalName(2, PHYSICAL_TAGS["surface"], "surface")
    for k, name in enumerate(EDGE_NAMES):
        gmsh.model.addPhysicalGroup(1, [lines[k]], PHYSICAL_TAGS[name])
        gmsh.model.setPhysicalName(1, PHYSICAL_TAGS[name], name)
    gmsh.model.mesh.generate(2)


def build_body_model(gmsh, missile: Missile, mesh_size: float) -> None:
    """Add the body surface (profile revolved about x_b in four quarter turns) to the model."""
    geo = gmsh.model.geo
    R = missile.radius
    nose, cyl, base = missile.profile
    apex = geo.addPoint(0.0, 0.0, 0.0, mesh_size)
    p_nose = geo.addPoint(-missile.nose_length, R, 0.0, mesh_size)
    p_base = geo.addPoint(-missile.length, R, 0.0, mesh_size)
    p_axis = geo.addPoint(-missile.length, 0.0, 0.0, mesh_size)
    if nose.kind is PrimKind.SEGMENT:
        c_nose = geo.addLine(apex, p_nose)
    else:
        sc, rc = nose.data[0], nose.data[1]
        centre = geo.addPoint(-sc, rc, 0.0, mesh_size)
        c_nose = geo.addCircleArc(apex, centre, p_nose)
    curves = {"nose": c_nose, "body": geo.addLine(p_nose, p_base),
              "base": geo.addLine(p_base, p_axis)}
    surfaces: dict[str, list[int]] = {k: [] for k in curves}
    for name, c in curves.items():
        dimtags = [(1, c)]
        for _ in range(4):
            out = geo.revolve(dimtags, 0, 0, 0, 1, 0, 0, math.pi / 2)
            surfaces[name] += [t for d, t in out if d == 2]
            dimtags = [out[0]]
    geo.synchronize()
    for name, tags in surfaces.items():
        gmsh.model.addPhysicalGroup(2, tags, BODY_TAGS[name])
        gmsh.model.setPhysicalName(2, BODY_TAGS[name], name)
    gmsh.option.setNumber("Mesh.MeshSizeMax", mesh_size)
    gmsh.model.mesh.generate(2)


def write_meshes(cfg: MissileConfig, out_dir: Path) -> dict[str, Path]:
    """Write ``<fin name>.msh`` for every fin and ``body.msh`` into ``out_dir``.

    Returns {fin name or "body": path}. The meshes follow ``cfg`` (element size ``cfg.mesh_size``).
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    missile = build_missile(cfg)
    paths: dict[str, Path] = {}
    for fin in missile.fins:
        path = out_dir / f"{fin.name}.msh"
        with gmsh_model(fin.name) as gmsh:
            build_fin_model(gmsh, fin, cfg.mesh_size)
            gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
            gmsh.write(str(path))
        paths[fin.name] = path
    path = out_dir / BODY_MSH
    with gmsh_model("body") as gmsh:
        build_body_model(gmsh, missile, cfg.mesh_size)
        gmsh.write(str(path))
    paths["body"] = path
    return paths


def fin_outline_from_msh(path: Path) -> tuple[np.ndarray, float]:
    """The four corners of a fin mesh written by :func:`write_meshes` (root TE, root LE, tip LE,
    tip TE: :data:`EDGE_NAMES` order of the edges between them), shape (4, 3) [m], and its median
    element edge length [m]."""
    with gmsh_model("outline") as gmsh:
        gmsh.merge(str(path))
        ends = []
        for name in EDGE_NAMES:
            tags, x = gmsh.model.mesh.getNodesForPhysicalGroup(1, PHYSICAL_TAGS[name])
            ends.append(np.asarray(x).reshape(-1, 3))
    x, cells = read_msh_nodes_and_cells(path)
    quads = next(iter(cells.values()))
    edge = np.linalg.norm(x[quads] - x[np.roll(quads, -1, axis=1)], axis=2)
    corners = []
    for k in range(4):  # corner k joins edge k − 1 and edge k
        a, b = ends[k - 1], ends[k]
        d = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=2)
        i, _ = np.unravel_index(np.argmin(d), d.shape)
        corners.append(a[i])
    return np.array(corners), float(np.median(edge))


REFINED_SCHEMES: dict[str, dict[str, float]] = {
    "blossom": {"Mesh.Algorithm": 6, "Mesh.RecombinationAlgorithm": 1},
    "full_quad": {"Mesh.Algorithm": 6, "Mesh.RecombinationAlgorithm": 3},
}
"""Gmsh recombination of the refined fin mesh (:func:`write_refined_fin_mesh`). Both mesh the
size field with frontal-Delaunay triangles (``Mesh.Algorithm`` 6). ``blossom`` pairs the
triangles into quadrilaterals by a minimum-cost perfect matching (Gmsh makes every boundary
curve's segment count even for it, as a perfect matching needs; a left-over triangle would
raise — none on the eight paper fins nor the tests' contact set);
``full_quad`` (the default) meshes at twice the size, recombines, and splits every quad
into 4 and every left-over triangle into 3 quadrilaterals (the median element is the requested
size as well: it does NOT halve the size), but each split triangle leaves kite-shaped quads with
two edges of ≈ 0.58 of it. Measured on the eight radar × traction fins at 1.25 mm
(benchmarks/shell_mesh_quality.py; docs/performance.md, "Fin mesh quality and the shell step"):
median edge in the refined zone 1.19–1.23 mm (blossom) and 1.20–1.26 mm (full_quad); the
explicit step c_p·dt_crit 0.65–0.92 mm against 0.64–0.78 mm, 1.01–1.36× the step per fin and
1.14× fewer DOF-steps for the stage, peaks within the recovery's error estimate of each other,
2–3× the meshing time: not the default (the gain is not material; ``[shell] local_mesh_scheme``).
Both stay well below square cells (c_p·dt_crit = h): the step is set by a few cells (valence-3
nodes, a wing's 35° root/leading-edge corner)."""


def write_refined_fin_mesh(corners: np.ndarray, mesh_size: float, points: np.ndarray,
                           fine_size: float, radius: float, path: Path, *,
                           scheme: str = "full_quad") -> Path:
    """An all-quadrilateral fin mesh refined around ``points`` (m, 3) [m] (contact points):
    element size ``fine_size`` within ``radius`` [m] of a point, growing linearly to
    ``mesh_size`` over the next 2 × mesh_size (Gmsh Distance + Threshold size fields, frontal
    Delaunay triangles recombined into quads as :data:`REFINED_SCHEMES` ``[scheme]`` says).
    Corners (4, 3) and physical groups as :func:`build_fin_model`. Written to ``path``
    (msh 4.1). Raises RuntimeError if Gmsh leaves a non-quadrilateral element."""
    if scheme not in REFINED_SCHEMES:
        raise ValueError(f"scheme must be one of {sorted(REFINED_SCHEMES)}, got {scheme!r}")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    corners = np.asarray(corners, float)
    n = np.cross(corners[1] - corners[0], corners[3] - corners[0])
    n /= np.linalg.norm(n)
    pts = np.asarray(points, float).reshape(-1, 3)
    pts = pts - ((pts - corners[0]) @ n)[:, None] * n  # onto the fin plane
    if len(pts):  # one point per cell of fine_size/2: the field cost stays bounded
        _, first = np.unique(np.floor(pts / (0.5 * fine_size)).astype(np.int64), axis=0,
                             return_index=True)
        pts = pts[np.sort(first)]
    with gmsh_model("refined_fin") as gmsh:
        geo = gmsh.model.geo
        P = [geo.addPoint(*map(float, c)) for c in corners]
        lines = [geo.addLine(P[k], P[(k + 1) % 4]) for k in range(4)]
        surf = geo.addPlaneSurface([geo.addCurveLoop(lines)])
        field_pts = [geo.addPoint(*map(float, p)) for p in pts]
        geo.synchronize()
        f = gmsh.model.mesh.field
        size = mesh_size
        if field_pts:
            d = f.add("Distance")
            f.setNumbers(d, "PointsList", field_pts)
            th = f.add("Threshold")
            f.setNumber(th, "InField", d)
            f.setNumber(th, "SizeMin", fine_size)
            f.setNumber(th, "SizeMax", mesh_size)
            f.setNumber(th, "DistMin", radius)
            f.setNumber(th, "DistMax", radius + 2.0 * mesh_size)
            f.setAsBackgroundMesh(th)
            size = fine_size
        opts = {"Mesh.MeshSizeExtendFromBoundary": 0, "Mesh.MeshSizeFromPoints": 0,
                "Mesh.MeshSizeFromCurvature": 0, "Mesh.RecombineAll": 1,
                **REFINED_SCHEMES[scheme], "Mesh.Smoothing": 10,
                "Mesh.MeshSizeMin": 0.5 * size, "Mesh.MeshSizeMax": mesh_size,
                "Mesh.MshFileVersion": 4.1}
        saved = {k: gmsh.option.getNumber(k) for k in opts}
        try:
            for k, v in opts.items():
                gmsh.option.setNumber(k, v)
            _tag_and_generate(gmsh, surf, lines)
            types, _, _ = gmsh.model.mesh.getElements(2)
            if any(gmsh.model.mesh.getElementProperties(t)[3] != 4 for t in types):
                raise RuntimeError("refined fin mesh is not all-quadrilateral")
            gmsh.write(str(path))
        finally:
            for k, v in saved.items():
                gmsh.option.setNumber(k, v)
    return path
