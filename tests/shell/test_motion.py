"""Sampling a fin's normal displacement for the collision kernel (``shell.motion``): the grid, the
interpolation, the time resampling and the sampler against closed forms, and end to end against the
shell stage's own displacement field. (The interpolation and end-to-end tests after a helper's
branch ``finmotion``, 2026-11-28.)"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pytest

from flexnet_fe.config import load_case
from flexnet_fe.io import write_history_csv

from flexnet_fe.missile.build import build_missile
from flexnet_fe.missile.config import MissileConfig
from flexnet_fe.missile.shapes import pack_shapes
from flexnet_fe.shell.forms import NDOF_NODE
from flexnet_fe.shell.motion import _Sampler, fin_motion, grid_interpolation, grid_of, grid_points, resample

CASE = Path(__file__).resolve().parents[2] / "cases" / "radar_traction"
COARSE = ["missile.mesh_size=0.04", "shell.end_margin=3e-4", "shell.workers=1", "shell.local_mesh_size=0.02"]


@pytest.fixture(scope="module")
def case():
    return load_case(CASE, COARSE)[0]


def test_the_grid_covers_every_fins_contact_polygon():
    # Reference: the contact polygons of the radar missile (root extension included,
    # missile.shapes.pack_shapes): every corner lies within the grid, and the grid's extreme points
    # are the polygon's bounding box (to round-off).
    for poly in pack_shapes(build_missile(MissileConfig(preset="radar"))).fin_poly:
        g = grid_of(poly, 41, 31)
        pts = grid_points(g, 41, 31)
        assert pts.shape == (41 * 31, 2)
        np.testing.assert_allclose(pts.min(axis=0), poly.min(axis=0), atol=1e-15)
        np.testing.assert_allclose(pts.max(axis=0), poly.max(axis=0), atol=1e-12)
        assert np.all(poly >= pts.min(axis=0) - 1e-15) and np.all(poly <= pts.max(axis=0) + 1e-12)
        np.testing.assert_array_equal(pts[1 * 31 + 2], [g[0] + g[1], g[2] + 2 * g[3]])  # row i·nv + j


def _fin_geometry(case, tmp_path, name):
    """(fin, FinGeometry) of one fin of ``case``'s missile on its uniform mesh."""
    from mpi4py import MPI

    from flexnet_fe.missile.mesh import write_meshes
    from flexnet_fe.shell.forms import shell_space
    from flexnet_fe.shell.meshio import load_fin_mesh
    from flexnet_fe.shell.transfer import FinGeometry

    fin = next(f for f in build_missile(case.missile).fins if f.name == name)
    fm = load_fin_mesh(write_meshes(case.missile, tmp_path)[name], MPI.COMM_SELF)
    pl = fm.plane
    return fin, FinGeometry(mesh=fm.mesh, V=shell_space(fm.mesh), origin=pl.origin, e1=pl.e1, e2=pl.e2, n=pl.n)


def _points(fin, poly, nu, nv):
    uv = grid_points(grid_of(poly, nu, nv), nu, nv)
    return fin.origin + uv[:, :1] * np.asarray(fin.e1) + uv[:, 1:] * np.asarray(fin.e2)


def test_interpolation_reproduces_a_linear_field_and_takes_the_nearest_node_outside(case, tmp_path):
    # Reference: closed form. Bilinear (isoparametric) cells reproduce w = a + b u + c v exactly
    # (Σ N_i = 1, Σ N_i x_i = x), so inside the mesh the grid equals the closed form to round-off
    # (1e-12 of |w| ~ 1: the pull-back converges to 1e-14). Outside it a grid point takes the value of
    # the node nearest in the plane, found here by brute force; every grid point more than 1 µm inside
    # the trapezoid fin.uv must be inside the mesh (the mesh is that trapezoid).
    fin, fg = _fin_geometry(case, tmp_path, "rudder_2")
    pts = _points(fin, pack_shapes(build_missile(case.missile)).fin_poly[5], 23, 17)
    P = grid_interpolation(fg, pts)
    xn = fg.V.tabulate_dof_coordinates()
    un, vn = (xn - fin.origin) @ fin.e1, (xn - fin.origin) @ fin.e2
    ug, vg = (pts - fin.origin) @ fin.e1, (pts - fin.origin) @ fin.e2
    f = 0.3 - 2.0 * un + 5.0 * vn
    w = P @ f
    near = np.argmin((ug[:, None] - un) ** 2 + (vg[:, None] - vn) ** 2, axis=1)
    inside = np.abs(w - (0.3 - 2.0 * ug + 5.0 * vg)) < 1e-12
    np.testing.assert_array_equal(w[~inside], f[near[~inside]])
    uv = fin.uv
    edges = [(uv[k], uv[(k + 1) % 4]) for k in range(4)]  # counter-clockwise: inside on the left
    depth = np.min([((p1 - p0)[0] * (vg - p0[1]) - (p1 - p0)[1] * (ug - p0[0])) / np.linalg.norm(p1 - p0)
                    for p0, p1 in edges], axis=0)
    assert np.all(inside[depth > 1e-6]) and np.any(depth < 0) and np.any(inside)


def test_resample_is_linear_in_time_onto_the_regular_grid():
    # Reference: a field linear in time, sampled at irregular times, is reproduced at the regular
    # times t0 + j dt up to the last sample.
    t = np.array([1.0e-3, 1.0007e-3, 1.0021e-3, 1.0030e-3, 1.00305e-3, 1.0042e-3])
    w = np.outer(t - 1e-3, [1.0, -2.0])
    out = resample(t, w, 1e-6)
    tj = 1e-3 + 1e-6 * np.arange(5)  # up to 1.004e-3 ≤ t[-1]
    assert out.shape == (5, 2)
    np.testing.assert_allclose(out, np.outer(tj - 1e-3, [1.0, -2.0]), atol=1e-18)


def test_the_sampler_takes_the_normal_component_and_skips_a_repeated_instant():
    # Reference: closed form. Nodes with displacement (1, 2, 3) mm × k and normal (0, 0.6, 0.8)
    # have u·n = 3.6 mm × k; a frame at a time already taken (a running peak's) is not kept.
    n = 3
    u = np.zeros(n * NDOF_NODE)
    u.reshape(-1, NDOF_NODE)[:, :3] = np.outer(np.arange(1, n + 1), [1e-3, 2e-3, 3e-3])
    from scipy import sparse

    s = _Sampler(sparse.csr_matrix(np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])), np.array([0.0, 0.6, 0.8]))
    s.write(1e-6, u)
    s.write(1e-6, 2 * u)
    s.write(2e-6, 2 * u)
    assert s.t == [1e-6, 2e-6]
    np.testing.assert_allclose(s.w[0], [3.6e-3, 3 * 3.6e-3], rtol=1e-14)
    np.testing.assert_allclose(s.w[1], [7.2e-3, 6 * 3.6e-3], rtol=1e-14)


def _collision(d: Path, fins, loaded: int) -> None:
    """A hand-made collision record: a half-sine pull of 2 × 1 kN along the normal of fin ``loaded``
    (a rudder; 0.1–0.4 ms, two points), a body deceleration; no load on the other fins."""
    fin = fins[loaded]
    t = np.linspace(0.0, 5e-4, 26)
    amp = np.where((t > 1e-4) & (t < 4e-4), np.sin(np.pi * (t - 1e-4) / 3e-4), 0.0)
    per = np.where(amp > 0, 2, 0)
    rs = np.concatenate([[0], np.cumsum(per)]).astype(np.int64)
    k = np.repeat(np.arange(len(t)), per)
    uv = np.tile([[0.2, 0.25], [0.12, 0.3]], (len(t), 1))[: rs[-1]]  # (u, v) [m] on a rudder
    point = fin.origin + uv[:, :1] * fin.e1 + uv[:, 1:] * fin.e2
    np.savez(d / "fin_contacts.npz", fin_names=np.array([f.name for f in fins]), t=t, row_start=rs,
             fin=np.full(rs[-1], loaded, np.int32), point=point, force=1e3 * amp[k, None] * fin.n,
             width=np.full(rs[-1], 4.5e-3))
    write_history_csv(d / "history.csv", {"t_s": t, "accel_body_x_mps2": -3e4 * amp,
                                          "accel_body_y_mps2": 0 * t, "accel_body_z_mps2": 0 * t})


def _stage_reference(shell, missile_cfg, d: Path, pts, fin, monkeypatch) -> tuple[float, list]:
    """Second path: the shell stage itself (``run_shell`` with ``shell``) on the same record; at each
    of its XDMF frames the CG1 displacement it writes, evaluated by dolfinx at the grid points (its
    own point location) and dotted with fin.n. Returns (the stage's sample interval [s], [(t, inside
    mask, w)])."""
    from dolfinx import geometry

    from flexnet_fe.missile.mesh import write_meshes
    from flexnet_fe.shell import stage as stage_mod

    frames = []
    write = stage_mod._FieldWriter.write

    def spy(self, t, u_owned):
        write(self, t, u_owned)
        mesh = self.disp.function_space.mesh
        tree = geometry.BoundingBoxTree(mesh, mesh.topology.dim)
        hit = geometry.compute_colliding_cells(mesh, geometry.compute_collisions(tree, pts), pts)
        ok = np.array([len(hit.links(i)) > 0 for i in range(len(pts))])
        cells = np.array([hit.links(i)[0] for i in np.flatnonzero(ok)], np.int32)
        frames.append((t, ok, self.disp.eval(pts[ok], cells) @ fin.n))

    monkeypatch.setattr(stage_mod._FieldWriter, "write", spy)
    specs = stage_mod.fin_specs(build_missile(missile_cfg).fins, write_meshes(missile_cfg, d / "meshes"))
    s = stage_mod.run_shell(shell, specs, d / "fin_contacts.npz", d / "history.csv", d / "stage",
                            logging.getLogger("flexnet.test.fin_motion"))
    monkeypatch.undo()
    return s[fin.name]["sample_interval_s"], frames


def test_end_to_end_equals_the_stage_displacement_at_its_frames(case, tmp_path, monkeypatch):
    # Reference: the shell stage's own output path (the displacement its fields.xdmf frames hold,
    # evaluated at the grid points by dolfinx's bounding-box tree and Function.eval, not by the load
    # transfer's pull-back fin_motion uses). Same model, loads and steps (interval = the stage's sample
    # interval, so fin_motion's frames are the stage's samples), so at every stage frame on the sample
    # grid the two agree to round-off: 1e-9 of the largest |w|. Unloaded fins: nt = 0; the root
    # extension (u < 0, nearest node on the clamped root) stays 0.
    missile = build_missile(case.missile)
    fins = missile.fins
    loaded = 4  # rudder_1: the smaller fin, the shorter run
    _collision(tmp_path, fins, loaded)
    nu, nv = 11, 9
    fin, poly = fins[loaded], pack_shapes(missile).fin_poly[loaded]
    pts = _points(fin, poly, nu, nv)
    shell = case.shell.model_copy(update={"peak_check": False, "strike_envelope": False})
    ref = tmp_path / "ref"
    ref.mkdir()
    _collision(ref, fins, loaded)
    interval, frames = _stage_reference(shell, case.missile, ref, pts, fin, monkeypatch)
    m, summaries = fin_motion(case.missile, shell.model_copy(update={"history_interval": interval}), tmp_path,
                              tmp_path / "fm", interval=interval, nu=nu, nv=nv)
    assert m.w.shape == (m.offset[-1], nu, nv) and m.dt == interval
    assert [int(n) for n in m.nt] == [0] * loaded + [m.offset[-1]] + [0] * (len(fins) - loaded - 1)
    assert set(summaries) == {fin.name}
    w = m.w[m.offset[loaded]:m.offset[loaded + 1]].reshape(m.nt[loaded], -1)
    scale = np.abs(w).max()
    assert scale > 1e-6  # the fin moved (2 kN on a 4 mm rudder: tenths of a mm)
    on_grid = 0
    for t, ok, w_ref in frames:
        k = int(round((t - m.t0[loaded]) / interval))
        if abs(m.t0[loaded] + k * interval - t) > 1e-9 * interval or k >= m.nt[loaded]:
            continue  # a running-peak frame between the samples
        np.testing.assert_allclose(w[k][ok], w_ref, rtol=0, atol=1e-9 * scale)
        on_grid += 1
    assert on_grid >= 5
    u = m.grid[loaded, 0] + np.arange(nu) * m.grid[loaded, 1]
    assert np.all(m.w[:, u < 0, :] == 0.0)
