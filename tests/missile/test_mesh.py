"""Gmsh meshes against the geometry and the contact shapes; quality; dolfinx loading."""

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from flexnet_fe.machine import launcher_env
from flexnet_fe.missile.config import MissileConfig
from flexnet_fe.missile.geometry import EDGE_NAMES
from flexnet_fe.missile.build import build_missile
from flexnet_fe.missile.mesh import BODY_TAGS, PHYSICAL_TAGS, write_meshes
from flexnet_fe.msh import gmsh_model, read_msh_nodes_and_cells
from flexnet_fe.missile.shapes import (PART_BODY, PART_NOSE, body_closest_point, closest_points,
                                       pack_shapes)

ROUND = 1e-12  # [m] gmsh places nodes on the exact lines/arcs: only round-off separates them

CASES = {
    "radar": dict(preset="radar"),
    "infrared": dict(preset="infrared"),
    "cone_fine": dict(preset="radar", name="cone_fine", nose_shape="cone", nose_length=0.5,
                      mesh_size=0.01),
}


@pytest.fixture(scope="module", params=list(CASES))
def built(request, tmp_path_factory):
    cfg = MissileConfig(**CASES[request.param])
    paths = write_meshes(cfg, tmp_path_factory.mktemp(request.param))
    return cfg, build_missile(cfg), paths


def _physical_groups(path):
    """{name: (dim, node coordinates [m] (k, 3), elements (e, nodes per element) 0-based)}."""
    with gmsh_model("read_groups") as gmsh:
        gmsh.merge(str(path))
        tags, x, _ = gmsh.model.mesh.getNodes()
        pos = {int(t): i for i, t in enumerate(tags)}
        x = np.asarray(x).reshape(-1, 3)
        out = {}
        for dim, tag in gmsh.model.getPhysicalGroups():
            name = gmsh.model.getPhysicalName(dim, tag)
            ntags, nx = gmsh.model.mesh.getNodesForPhysicalGroup(dim, tag)
            elems = []
            for ent in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
                for t, c in zip(*gmsh.model.mesh.getElements(dim, ent)[::2]):
                    nn = gmsh.model.mesh.getElementProperties(t)[3]
                    elems.append(np.array([pos[int(k)] for k in c]).reshape(-1, nn))
            out[name] = (dim, tag, np.asarray(nx).reshape(-1, 3), np.vstack(elems), x)
        return out


def test_written_files(built):
    _, missile, paths = built
    assert set(paths) == {f.name for f in missile.fins} | {"body"}
    assert all(p.stat().st_size > 0 for p in paths.values())


def test_fin_meshes_match_geometry(built):
    cfg, missile, paths = built
    shapes = pack_shapes(missile)
    for fin in missile.fins:
        groups = _physical_groups(paths[fin.name])
        assert {k: v[:2] for k, v in groups.items()} == \
            {"surface": (2, PHYSICAL_TAGS["surface"]),
             **{n: (1, PHYSICAL_TAGS[n]) for n in EDGE_NAMES}}
        _, _, _, quads, x = groups["surface"]
        assert quads.shape[1] == 4  # all-quadrilateral (dolfinx 0.5.2 needs one cell type)
        # every node on the fin's mid-plane and inside (or on) the real trapezoid
        uvw = fin.to_plane(x)
        assert np.abs(uvw[:, 2]).max() < ROUND
        for k in range(4):
            c0, c1 = fin.uv[k], fin.uv[(k + 1) % 4]
            t = (c1 - c0) / np.linalg.norm(c1 - c0)
            outward = np.cross(t, uvw[:, :2] - c0)  # > 0 left of a CCW edge = inside
            assert outward.min() > -ROUND
        # area: planar quads with straight edges: exact sum of two triangles each,
        # reference = trapezoid (c_r + c_t) b / 2
        p0, p1, p2, p3 = (x[quads[:, i]] for i in range(4))
        area = 0.5 * (np.linalg.norm(np.cross(p1 - p0, p2 - p0), axis=1)
                      + np.linalg.norm(np.cross(p2 - p0, p3 - p0), axis=1)).sum()
        np.testing.assert_allclose(area, fin.area, rtol=1e-12)
        # each edge group: its nodes on its edge line, its segments add up to the edge length
        for k, name in enumerate(EDGE_NAMES):
            _, _, xe, lines, _ = groups[name]
            a, b = fin.corners[k], fin.corners[(k + 1) % 4]
            t = (b - a) / np.linalg.norm(b - a)
            off = (xe - a) - np.outer((xe - a) @ t, t)
            assert np.linalg.norm(off, axis=1).max() < ROUND
            length = np.linalg.norm(x[lines[:, 1]] - x[lines[:, 0]], axis=1).sum()
            np.testing.assert_allclose(length, fin.edge_length(k), rtol=1e-12)
        np.testing.assert_allclose(fin.edge_length(0), fin.root_chord, rtol=1e-14)
        # the root nodes lie on the body surface: the contact body's zero level
        for p in groups["root"][2]:
            d, _, _, part = body_closest_point(p, shapes.prof_kind, shapes.prof_data,
                                               shapes.prof_part)
            assert abs(d) < ROUND and part == PART_BODY
        # the mid-surface nodes are inside the contact plate, at most h/2 deep
        d, _, _, _ = closest_points(x, shapes)
        assert d.max() < ROUND and d.min() > -0.5 * fin.thickness - ROUND


def test_body_mesh_on_zero_level(built):
    _, missile, paths = built
    groups = _physical_groups(paths["body"])
    assert {k: v[:2] for k, v in groups.items()} == {n: (2, t) for n, t in BODY_TAGS.items()}
    shapes = pack_shapes(missile)
    for name, part in (("nose", PART_NOSE), ("body", PART_BODY), ("base", PART_BODY)):
        xs = groups[name][2]
        d = np.array([body_closest_point(p, shapes.prof_kind, shapes.prof_data,
                                         shapes.prof_part)[0] for p in xs])
        # nodes are placed on the exact circles/arcs of the revolved profile: round-off only
        assert np.abs(d).max() < 1e-9, name


def _quad_quality(x, quads):
    """Minimum interior angle [deg] and maximum edge-length ratio of each quad."""
    p = [x[quads[:, i]] for i in range(4)]
    angles, lengths = [], []
    for i in range(4):
        a, b, c = p[i - 1], p[i], p[(i + 1) % 4]
        u, v = a - b, c - b
        cosang = (u * v).sum(1) / np.linalg.norm(u, axis=1) / np.linalg.norm(v, axis=1)
        angles.append(np.degrees(np.arccos(np.clip(cosang, -1, 1))))
        lengths.append(np.linalg.norm(c - b, axis=1))
    lengths = np.array(lengths)
    return np.min(angles, axis=0), lengths.max(0) / lengths.min(0)


@pytest.mark.parametrize("refine", [1.0, 0.5])
def test_fin_mesh_quality(tmp_path, refine):
    cfg = MissileConfig(preset="radar")
    cfg = cfg.model_copy(update={"mesh_size": cfg.mesh_size * refine})
    missile = build_missile(cfg)
    paths = write_meshes(cfg, tmp_path)
    for fin in missile.fins:
        x, cells = read_msh_nodes_and_cells(paths[fin.name])
        assert set(cells) == {"Quadrilateral 4"}
        min_angle, ratio = _quad_quality(x, cells["Quadrilateral 4"])
        # a structured grid on a trapezoid: the smallest angle is set by the geometry, between
        # the leading edge and the chord lines, 90° - Λ_LE = 35° for the wings; bound 30°.
        # Edge ratio: n_chord from the mean chord keeps root/tip spacing within
        # c_r/c_mean = 1.6 and c_t/c_mean = 0.4 of the size; bound 3.
        assert min_angle.min() >= min(30.0, 90.0 - np.degrees(fin.leading_edge_sweep) - 1e-9)
        assert ratio.max() <= 3.0
        # element size honoured: the longest element edge is not much above the target size
        x_q = x[cells["Quadrilateral 4"]]
        longest = np.linalg.norm(np.roll(x_q, -1, axis=1) - x_q, axis=2).max()
        assert longest <= 1.7 * cfg.mesh_size


LOAD_SCRIPT = textwrap.dedent("""
    import sys
    from mpi4py import MPI
    import ufl
    from dolfinx import fem
    from flexnet_fe.missile.mesh import PHYSICAL_TAGS
    from flexnet_fe.shell.meshio import load_fin_mesh  # the loader the shell stage uses
    for path in sys.argv[1:]:
        fin = load_fin_mesh(path, MPI.COMM_WORLD)
        mesh, ft = fin.mesh, fin.facet_tags
        assert fin.edge_tags == {n: PHYSICAL_TAGS[n] for n in fin.edge_tags} and len(fin.edge_tags) == 4
        assert mesh.geometry.dim == 3 and mesh.topology.cell_name() == "quadrilateral"
        ds = ufl.Measure("ds", domain=mesh, subdomain_data=ft)
        vals = [fem.assemble_scalar(fem.form(1.0 * ufl.dx(domain=mesh)))]
        vals += [fem.assemble_scalar(fem.form(1.0 * ds(PHYSICAL_TAGS[n])))
                 for n in ("root", "leading_edge", "tip", "trailing_edge")]
        vals = [mesh.comm.allreduce(v, op=MPI.SUM) for v in vals]
        if mesh.comm.rank == 0:
            print(path, *map(repr, vals))
""")


def _run_loader(tmp_path, paths, nproc):
    script = tmp_path / "load.py"
    script.write_text(LOAD_SCRIPT)
    cmd = [sys.executable, str(script), *map(str, paths)]
    if nproc > 1:
        cmd = ["mpirun", "--oversubscribe", "--allow-run-as-root", "-n", str(nproc)] + cmd
    env = {**launcher_env(dict(os.environ)), "OMPI_MCA_rmaps_base_oversubscribe": "1"}
    out = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=tmp_path,
                         timeout=300)
    assert out.returncode == 0, out.stderr[-3000:]
    res = {}
    for line in out.stdout.splitlines():
        path, *vals = line.split()
        res[Path(path).stem] = np.array([float(v) for v in vals])
    return res


@pytest.fixture(scope="module")
def radar_meshes(tmp_path_factory):
    cfg = MissileConfig(preset="radar")
    paths = write_meshes(cfg, tmp_path_factory.mktemp("radar_load"))
    return build_missile(cfg), [paths[f.name] for f in build_missile(cfg).fins]


def _expected(fin):
    # dolfinx integrals of 1 over the bilinear quads: exact for planar straight-edged quads;
    # reference: trapezoid area and the four edge lengths
    return np.array([fin.area, *(fin.edge_length(k) for k in range(4))])


def test_fin_meshes_load_in_dolfinx_serial(tmp_path, radar_meshes):
    missile, paths = radar_meshes
    res = _run_loader(tmp_path, paths, 1)
    for fin in missile.fins:
        np.testing.assert_allclose(res[fin.name], _expected(fin), rtol=1e-12)


@pytest.mark.mpi
def test_fin_meshes_load_in_dolfinx_mpi(tmp_path, radar_meshes):
    missile, paths = radar_meshes
    serial = _run_loader(tmp_path, paths, 1)
    parallel = _run_loader(tmp_path, paths, 2)
    for fin in missile.fins:
        # same mesh split over 2 ranks: sums differ by summation order only
        np.testing.assert_allclose(parallel[fin.name], serial[fin.name], rtol=1e-12)
        np.testing.assert_allclose(parallel[fin.name], _expected(fin), rtol=1e-12)
