"""The shell stage end to end: outputs, XDMF readable by PyVista, a blow-up keeps earlier
output, and 2 MPI processes give the same stress history as one."""

from __future__ import annotations

import logging
import os
import subprocess
import textwrap
from pathlib import Path

import numpy as np
import pytest

from flexnet_fe.config import load_case
from flexnet_fe.errors import CaseError, NumericalError
from flexnet_fe.io import read_history_csv, write_history_csv
from flexnet_fe.shell import stage as stage_mod
from flexnet_fe.shell.config import FinSpec, ShellConfig
from flexnet_fe.machine import launcher_env
from flexnet_fe.shell.meshio import write_plate_msh
from flexnet_fe.shell.stage import run_shell
from flexnet_fe.shell.stage import CELL_NAMES, NODAL_NAMES

ROOT = Path(__file__).resolve().parents[2]
PY = ROOT / ".venv" / "bin" / "python"


def make_inputs(d: Path) -> list[FinSpec]:
    """A wing in the x_b–y_b plane (root on the body at y_b = 0.1 m) and a rudder at 90° roll
    that gets no contact; a rope load moving over the wing for 1 ms; a body deceleration."""
    write_plate_msh(d / "wing.msh", 12, 6, 0.3, 0.15, origin=(-1.2, 0.1, 0.0), a1=(1, 0, 0),
                    a2=(0, 1, 0))
    write_plate_msh(d / "rudder.msh", 6, 4, 0.2, 0.1, origin=(-2.0, 0.0, 0.1), a1=(1, 0, 0),
                    a2=(0, 0, 1))
    t = np.linspace(0.0, 1e-3, 21)
    per = np.array([0] + [2] * 19 + [0])
    rs = np.concatenate([[0], np.cumsum(per)]).astype(np.int64)
    k = np.repeat(np.arange(21), per)
    # rope crossing the wing: one point on the face, one on the leading edge (y = 0.25)
    pts = np.column_stack([-1.0 - 0.1 * t[k] / 1e-3, np.where(np.arange(rs[-1]) % 2, 0.25, 0.18),
                           np.zeros(rs[-1])])
    amp = np.sin(np.pi * t[k] / 1e-3)
    force = np.column_stack([-200.0 * amp, np.zeros_like(amp), 1500.0 * amp])
    np.savez(d / "fin_contacts.npz", fin_names=np.array(["wing", "rudder"]), t=t, row_start=rs,
             fin=np.zeros(rs[-1], np.int32), point=pts, force=force,
             width=np.full(rs[-1], 5e-3))
    write_history_csv(d / "history.csv", {
        "t_s": t, "accel_body_x_mps2": -2e4 * np.sin(np.pi * t / 1e-3),
        "accel_body_y_mps2": 0 * t, "accel_body_z_mps2": 3e3 * np.sin(np.pi * t / 1e-3)})
    return [FinSpec(name, d / f"{name}.msh", 4e-3, 71.7e9, 0.33, 2810.0, 503e6)
            for name in ("wing", "rudder")]


def _log():
    log = logging.getLogger("flexnet.test.shell")
    log.setLevel(logging.INFO)
    return log


CFG = ShellConfig(end_margin=1e-3, history_interval=1e-5, field_interval=2.5e-4, bearing_rope_modulus=1e11)


def test_stage_outputs(tmp_path):
    fins = make_inputs(tmp_path)
    out = tmp_path / "shell"
    s = run_shell(CFG, fins, tmp_path / "fin_contacts.npz", tmp_path / "history.csv", out, _log())
    assert set(s) >= {"wing", "dt_s", "dt_crit_s", "dofs", "steps", "wall_s"}
    assert "rudder" not in s  # fins = "loaded": the rudder has no contact event
    w = s["wing"]
    assert 0 < s["dt_s"] <= 0.9 * s["dt_crit_s"] * (1 + 1e-12)
    h = read_history_csv(out / "wing" / "history.csv")
    assert h["t_s"][-1] == pytest.approx(2e-3, abs=s["dt_s"])
    # the summary's peak is the history's maximum (same samples); the peak row carries the
    # located value (the recovered field's maximum in the cells around the peak node, so at
    # least the nodal value) and its location, within a cell diagonal of the node
    i = int(np.argmax(h["max_von_mises_pa"]))
    assert w["peak_von_mises_pa"] == h["max_von_mises_pa"][i]
    assert w["peak_time_s"] == h["t_s"][i]
    assert w["peak_von_mises_pa"] >= w["peak_nodal_von_mises_pa"] * (1 - 1e-12)
    np.testing.assert_allclose(w["peak_location_m"], [h[f"max_von_mises_{c}_m"][i] for c in "xyz"])
    # (the magnitude of a stage peak is checked against the Navier series in
    # test_shell_load_option_runs_a_pressure_history_on_a_fin)
    assert w["peak_max_principal_pa"] > 0
    assert w["allowable_pa"] == 503e6 and 0 < w["peak_error_estimate_rel"] < 1
    # the free vibration after the last load (the half-sine ends at 1 ms): the largest history row
    # after it, at most the peak (which is the largest row of all)
    after = h["t_s"] > 1e-3
    assert w["after_last_load_max_von_mises_pa"] == h["max_von_mises_pa"][after].max()
    assert 0 < w["after_last_load_over_peak"] == w["after_last_load_max_von_mises_pa"] / w["peak_von_mises_pa"] <= 1
    assert isinstance(s["warnings"], list)
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
    pv = pytest.importorskip("pyvista")
    r = pv.XdmfReader(str(out / "wing" / "fields.xdmf"))
    # t = 0, 0.25 ms, ..., 2 ms (field_interval), plus the running peak's instants (at most one
    # per interval), one of which is the final peak time
    times = np.asarray(r.time_values)
    assert 9 <= len(times) <= 17 and np.all(np.diff(times) > 0)
    assert np.min(np.abs(times - w["peak_time_s"])) < 1e-6 * w["peak_time_s"]
    r.set_active_time_value(r.time_values[-1])
    blocks = r.read()
    names = [blocks.get_block_name(k) for k in range(blocks.n_blocks)]
    assert set(NODAL_NAMES) | set(CELL_NAMES) | {"displacement_m"} <= set(names)
    vm = blocks[names.index(NODAL_NAMES[0])].point_data[NODAL_NAMES[0]]
    assert vm.shape == (13 * 7,) and np.all(np.isfinite(vm))
    cm = blocks[names.index("von_mises_top_pa")].cell_data["von_mises_top_pa"]
    assert cm.shape == (72,) and np.all(np.isfinite(cm))
    env = pv.XdmfReader(str(out / "wing" / "envelope.xdmf")).read()
    en = [env.get_block_name(k) for k in range(env.n_blocks)]
    peak_env = env[en.index("peak_von_mises_pa")].cell_data["peak_von_mises_pa"].max()
    # the envelope is the maximum over the same samples; the XDMF reader returns float32
    assert peak_env == pytest.approx(w["peak_von_mises_pa"], rel=1e-6)


def test_blow_up_is_caught_and_keeps_earlier_output(tmp_path, monkeypatch):
    fins = make_inputs(tmp_path)
    # pretend the stability limit were 2.2× larger: the step is then ~2 × the true limit
    real = stage_mod.critical_step
    monkeypatch.setattr(stage_mod, "critical_step", lambda *a: 2.2 * real(*a))
    with pytest.raises(NumericalError, match=r"dt = .* dt_crit = "):
        run_shell(CFG.model_copy(update={"history_interval": 2e-6}), fins,
                  tmp_path / "fin_contacts.npz", tmp_path / "history.csv", tmp_path / "s", _log())
    h = read_history_csv(tmp_path / "s" / "wing" / "history.csv")
    assert len(h["t_s"]) >= 2 and np.all(np.isfinite(h["max_von_mises_pa"]))
    pv = pytest.importorskip("pyvista")
    assert pv.XdmfReader(str(tmp_path / "s" / "wing" / "fields.xdmf")).number_time_points >= 1


@pytest.mark.mpi
def test_two_processes_give_the_same_history(tmp_path):
    fins = make_inputs(tmp_path)
    # zones of 20 max(t, d) = 0.1 m (the loads are 80 mm from the root): while the rope load
    # acts, the sampled maxima leave out nodes (checked against a run without zones), and both
    # paths must leave out the same ones (the masked PETSc path is exercised)
    # mass scaling on (every cell here is at the smallest step, so all nodes gain ×2.25): the
    # ghost nodes must take the same factor on both processes (MAX update)
    cfg = CFG.model_copy(update={"stvenant_radius_factor": 20.0, "mass_scaling": 1.5})
    ser = run_shell(cfg, fins, tmp_path / "fin_contacts.npz", tmp_path / "history.csv",
                    tmp_path / "serial", _log())
    # the added inertia is said in the summary (the report lists the warnings)
    assert ser["wing"]["mass_added_rel"] == pytest.approx(1.25, rel=1e-9)
    assert any("selective mass scaling" in w and "wing" in w for w in ser["warnings"])
    run_shell(cfg.model_copy(update={"stvenant_radius_factor": 0.0}), fins,
              tmp_path / "fin_contacts.npz", tmp_path / "history.csv", tmp_path / "nozone", _log())
    h0 = read_history_csv(tmp_path / "nozone" / "wing" / "history.csv")["max_von_mises_pa"]
    h1 = read_history_csv(tmp_path / "serial" / "wing" / "history.csv")["max_von_mises_pa"]
    assert np.all(h1 <= h0 * (1 + 1e-12)) and np.any(h1 < 0.9 * h0)
    script = tmp_path / "par.py"
    script.write_text(textwrap.dedent(f"""
        import logging, sys
        from pathlib import Path
        sys.path.insert(0, {str(ROOT)!r})
        from flexnet_fe.shell.config import FinSpec, ShellConfig
        from flexnet_fe.shell.stage import run_shell
        d = Path({str(tmp_path)!r})
        fins = [FinSpec(n, d / f"{{n}}.msh", 4e-3, 71.7e9, 0.33, 2810.0, 503e6)
                for n in ("wing", "rudder")]
        cfg = ShellConfig.model_validate_json({cfg.model_dump_json()!r})
        s = run_shell(cfg, fins, d / "fin_contacts.npz", d / "history.csv", d / "parallel",
                      logging.getLogger("par"))
        import json
        if __import__("mpi4py").MPI.COMM_WORLD.rank == 0:
            (d / "par.json").write_text(json.dumps(s["wing"]))
    """))
    res = subprocess.run(["mpirun", "--oversubscribe", "--allow-run-as-root", "-n", "2", str(PY),
                          str(script)], capture_output=True, text=True, timeout=600,
                         env={**launcher_env(dict(os.environ)), "FLEXNET_NO_PROGRESS": "1"})
    assert res.returncode == 0, res.stderr[-3000:]
    a = read_history_csv(tmp_path / "serial" / "wing" / "history.csv")
    b = read_history_csv(tmp_path / "parallel" / "wing" / "history.csv")
    for k in a:
        # Reference: the serial run (compiled kernel). The 2-process run steps with PETSc
        # (Mat.mult per step) and completes the stress recovery by a reverse scatter: only the
        # summation order differs, so histories agree to round-off; bound 1e-10 (issue 10).
        scale = np.nanmax(np.abs(a[k])) or 1.0
        np.testing.assert_allclose(b[k], a[k], rtol=0, atol=1e-10 * scale, err_msg=k)
    # the located peak (gathered to rank 0 under MPI) and its ZZ estimate are the serial ones
    import json
    par = json.loads((tmp_path / "par.json").read_text())
    w = ser["wing"]
    np.testing.assert_allclose(par["peak_location_m"], w["peak_location_m"], rtol=0, atol=1e-12)
    assert par["peak_error_estimate_rel"] == pytest.approx(w["peak_error_estimate_rel"], rel=1e-8)
    assert par["peak_bearing_pa"] == pytest.approx(w["peak_bearing_pa"], rel=1e-12)


def test_runs_on_the_missile_meshers_fin(tmp_path):
    """Integration (wiring) with the missile model: its fin mesh and material, a rope load at
    the leading edge; the run is finite and the reported peak lies on the fin."""
    build = pytest.importorskip("flexnet_fe.missile.build")
    mesh_mod = pytest.importorskip("flexnet_fe.missile.mesh")
    from flexnet_fe.missile.config import MissileConfig
    from flexnet_fe.shell.stage import fin_specs

    cfg = MissileConfig(preset="radar", mesh_size=0.05)
    paths = mesh_mod.write_meshes(cfg, tmp_path / "meshes")
    fin = build.build_missile(cfg).fins[0]
    t = np.linspace(0.0, 2e-4, 11)
    le_mid = 0.5 * (fin.corners[1] + fin.corners[2])
    np.savez(tmp_path / "c.npz", fin_names=np.array([fin.name]), t=t,
             row_start=np.arange(12, dtype=np.int64), fin=np.zeros(11, np.int32),
             point=np.tile(le_mid, (11, 1)), force=np.outer(np.sin(np.pi * t / 2e-4), 5e3 * fin.n),
             width=np.full(11, 5e-3))
    with pytest.raises(CaseError, match="bearing_rope_modulus"):  # contact loads, no rope modulus: refused
        run_shell(ShellConfig(end_time=5e-4), fin_specs([fin], paths), tmp_path / "c.npz", None, tmp_path / "shell",
                  _log())
    s = run_shell(ShellConfig(end_time=5e-4, bearing_rope_modulus=1e11), fin_specs([fin], paths), tmp_path / "c.npz", None,
                  tmp_path / "shell", _log())
    r = s[fin.name]
    assert np.isfinite(r["peak_von_mises_pa"]) and r["peak_von_mises_pa"] > 1e6
    p = np.asarray(r["peak_location_m"])
    assert abs((p - fin.origin) @ fin.n) < 1e-9  # on the fin plane
    uv = np.array([(p - fin.origin) @ fin.e1, (p - fin.origin) @ fin.e2])
    lo, hi = fin.uv.min(axis=0), fin.uv.max(axis=0)
    assert np.all(uv >= lo - 1e-9) and np.all(uv <= hi + 1e-9)  # inside the fin's bounding box


def test_shell_load_option_runs_a_pressure_history_on_a_fin(tmp_path):
    """[shell.load] + [shell.supports] (no collision stage needed): the stage gives the same
    peak as the API on the same mesh and supports (wiring), and a bad support name is a one-line
    config error naming the field."""
    from pydantic import ValidationError
    from flexnet_fe.shell import api
    from flexnet_fe.shell.forms import ShellMaterial

    write_plate_msh(tmp_path / "plate.msh", 12, 12, 0.2, 0.2)
    spec = FinSpec("plate", tmp_path / "plate.msh", 2e-3, 70e9, 0.3, 2700.0, 300e6)
    sup = {g: "simply_supported_hard" for g in ("root", "tip", "leading_edge", "trailing_edge")}
    load = {"times": [0.0, 2.5e-4, 5e-4], "pressure": [0.0, 1e4, 0.0]}
    cfg = ShellConfig(supports=sup, load=load, end_time=6e-4, history_interval=1e-9,
                      rotary_inertia_scale=4.0)
    s = run_shell(cfg, [spec], tmp_path / "none.npz", None, tmp_path / "out", _log())
    mat = ShellMaterial(thickness=2e-3, youngs_modulus=70e9, poisson_ratio=0.3, density=2700.0)
    m = api.plate(12, 12, 0.2, 0.2, mat, supports="simply_supported_hard", rotary_scale=4.0)
    ref = api.solve(m, api.pressure(m, load["times"], load["pressure"]), 6e-4)
    assert s["plate"]["peak_von_mises_pa"] == pytest.approx(ref.peak.value, rel=1e-9)
    assert s["plate"]["peak_time_s"] == pytest.approx(ref.run.peak_t, rel=1e-12)
    # Independent reference: the Navier series of the same simply supported plate (hard support,
    # κ = 5/6, rotary inertia ×4), exact for the piecewise-linear pulse: peak surface von Mises
    # over the stage's sample times and an 11 × 11 grid of a quarter plate (the peak is central).
    # The plate-series study (docs/validation.md) measured −7.4 % at 12² with O(h²)
    # convergence; the ZZ estimate is validated there as an upper bound of that error.
    # Measured here: −6.1 %, ZZ estimate 9.2 %.
    from flexnet_fe.shell import navier
    from flexnet_fe.shell.recovery import von_mises
    t_s = read_history_csv(tmp_path / "out" / "plate" / "history.csv")["t_s"]
    plate = navier.PlateData(0.2, 0.2, 2e-3, 70e9, 0.3, 2700.0, rotary_scale=4.0)
    amps = navier.transient_amplitudes(plate, 61, t_s, load["times"], load["pressure"])
    g = np.linspace(0.0, 0.1, 11)
    X, Y = (v.ravel() for v in np.meshgrid(g, g))
    vm_ref = von_mises(navier.fields(plate, amps, X, Y)[1]).max()
    err = s["plate"]["peak_von_mises_pa"] / vm_ref - 1.0
    assert abs(err) < 0.10 and abs(err) <= s["plate"]["peak_error_estimate_rel"], (err, vm_ref)
    with pytest.raises(ValidationError, match="supports"):
        ShellConfig(supports={"root": "glued"})


def test_bearing_modulus_is_the_nets_unless_given():
    # One quantity, one value: a case that leaves shell.bearing_rope_modulus out takes the modulus
    # the collision's contact stiffness uses (net.transverse_modulus, else net.youngs_modulus).
    case, _ = load_case(ROOT / "cases" / "radar_traction", ["net.transverse_modulus=3e9"])
    assert case.shell.bearing_rope_modulus == 3e9 == case.net.contact_modulus
    case, _ = load_case(ROOT / "cases" / "radar_traction", ["shell.bearing_rope_modulus=2e9"])
    assert case.shell.bearing_rope_modulus == 2e9 and case.net.contact_modulus != 2e9


@pytest.mark.parametrize("scheme", ["full_quad", "blossom"])
def test_local_mesh_scheme_reaches_the_mesher(tmp_path, scheme):
    """Wiring of ``shell.local_mesh_scheme``: the stage's refined fin mesh is the one
    ``write_refined_fin_mesh`` writes with that scheme for the same inputs (reference: the
    mesher called directly; equal node count and coordinates)."""
    from flexnet_fe.missile.build import build_missile
    from flexnet_fe.missile.config import MissileConfig
    from flexnet_fe.missile.mesh import (fin_outline_from_msh, write_meshes,
                                         write_refined_fin_mesh)
    from flexnet_fe.msh import read_msh_nodes_and_cells
    from flexnet_fe.shell.stage import FinContacts, fin_specs
    from mpi4py import MPI

    cfg = MissileConfig(preset="radar", mesh_size=0.05)
    fin = build_missile(cfg).fins[4]
    spec = fin_specs([fin], write_meshes(cfg, tmp_path / "meshes"))[0]
    pts = fin.corners[1] + np.linspace(0.2, 0.6, 3)[:, None] * (fin.corners[2] - fin.corners[1])
    contacts = FinContacts(fin_names=(fin.name,), t=np.array([0.0]), sample=np.zeros(3, np.int64),
                           fin=np.zeros(3, np.int64), point=pts, force=np.zeros((3, 3)),
                           width=np.full(3, 4.5e-3))
    shell = ShellConfig(local_mesh_size=0.005, local_mesh_scheme=scheme)
    got = stage_mod._fin_mesh_path(shell, spec, contacts, 0, tmp_path / "shell", MPI.COMM_SELF)
    corners, h = fin_outline_from_msh(spec.mesh_path)
    radius = 2.0 * max(fin.thickness, 4.5e-3) + 2.0 * 0.005
    ref = write_refined_fin_mesh(corners, max(h, 0.005), pts, 0.005, radius,
                                 tmp_path / "ref.msh", scheme=scheme)
    x_got, x_ref = read_msh_nodes_and_cells(got)[0], read_msh_nodes_and_cells(ref)[0]
    assert x_got.shape == x_ref.shape and np.array_equal(x_got, x_ref)


def test_peak_check_is_the_first_part_of_a_run_at_half_the_size(tmp_path):
    """Reference: the stage run at half the local mesh size (the second model). shell.peak_check
    runs each fin on that run's mesh from the same start to its peak + 0.1 ms, so its peak is that
    run's peak to the bit when that peak comes before the check's end (here it does: a 0.2 ms
    strike); the error estimate is then 2 |move| (Richardson at order 1), the ZZ one kept apart."""
    from flexnet_fe.missile.build import build_missile
    from flexnet_fe.missile.config import MissileConfig
    from flexnet_fe.missile.mesh import write_meshes
    from flexnet_fe.shell.stage import PEAK_CHECK_AFTER_S, fin_specs

    cfg = MissileConfig(preset="radar", mesh_size=0.05)
    paths = write_meshes(cfg, tmp_path / "meshes")
    fin = build_missile(cfg).fins[0]
    t = np.linspace(0.0, 2e-4, 11)
    le = fin.corners[1] + 0.4 * (fin.corners[2] - fin.corners[1])
    np.savez(tmp_path / "c.npz", fin_names=np.array([fin.name]), t=t,
             row_start=np.arange(12, dtype=np.int64), fin=np.zeros(11, np.int32),
             point=np.tile(le, (11, 1)), force=np.outer(np.sin(np.pi * t / 2e-4), 5e3 * fin.n),
             width=np.full(11, 5e-3))
    # a body deceleration too, so that a second fin without contact loads has a peak: it keeps its
    # mesh at any local size, so it keeps its ZZ estimate (nothing to halve)
    write_history_csv(tmp_path / "h.csv", {"t_s": t, "accel_body_x_mps2": 0 * t, "accel_body_y_mps2": 0 * t,
                                           "accel_body_z_mps2": 2e3 * np.sin(np.pi * t / 2e-4)})
    other = build_missile(cfg).fins[4]
    base = ShellConfig(end_time=6e-4, bearing_rope_modulus=1e11, history_interval=1e-5, fins="named",
                       fin_names=(fin.name, other.name))
    specs = fin_specs([fin, other], paths)
    s = run_shell(base.model_copy(update={"local_mesh_size": 0.02, "peak_check": True}), specs,
                  tmp_path / "c.npz", tmp_path / "h.csv", tmp_path / "a", _log())
    half = run_shell(base.model_copy(update={"local_mesh_size": 0.01}), specs, tmp_path / "c.npz", tmp_path / "h.csv",
                     tmp_path / "b", _log())[fin.name]
    assert s[other.name]["peak_von_mises_pa"] > 0 and s[other.name]["peak_error_estimate_kind"] == "zz"
    assert "peak_check" not in s[other.name]
    r, c = s[fin.name], s[fin.name]["peak_check"]
    assert half["peak_time_s"] <= c["end_time_s"] == pytest.approx(r["peak_time_s"] + PEAK_CHECK_AFTER_S)
    assert c["peak_von_mises_pa"] == half["peak_von_mises_pa"] and c["dofs"] == half["dofs"]
    assert c["move_rel"] == c["peak_von_mises_pa"] / r["peak_von_mises_pa"] - 1.0
    assert r["peak_error_estimate_kind"] == "mesh_halving"
    assert r["peak_error_estimate_rel"] == 2.0 * abs(c["move_rel"]) and r["peak_zz_estimate_rel"] > 0
    assert c["steps"] < half["steps"]  # (cheaper: it stops after the peak)
    assert (tmp_path / "a" / "peak_check" / fin.name / "history.csv").exists()


def test_strike_envelope_is_the_run_with_the_loads_moved_along_the_edge(tmp_path):
    """Reference: the stage run on loads moved by hand (closed form: a leading-edge point at
    fraction λ of the edge moves to λ + δ/span) with the envelope run's end time (the second
    model): shell.strike_envelope's peak for that move equals it to the bit, and the envelope is the
    largest of the moved peaks and the fin's own."""
    from flexnet_fe.missile.build import build_missile
    from flexnet_fe.missile.config import MissileConfig
    from flexnet_fe.missile.mesh import write_meshes
    from flexnet_fe.shell.stage import PEAK_CHECK_AFTER_S, fin_specs
    from flexnet_fe.shell.strikes import STRIKE_OFFSETS

    cfg = MissileConfig(preset="radar", mesh_size=0.05)
    paths = write_meshes(cfg, tmp_path / "meshes")
    fin = build_missile(cfg).fins[0]
    c0, c1, c2 = fin.corners[:3]  # root trailing edge; root and tip of the leading edge
    root = (c1 - c0) / np.linalg.norm(c1 - c0)
    span = float(np.linalg.norm((c2 - c1) - ((c2 - c1) @ root) * root))
    t = np.linspace(0.0, 2e-4, 11)
    width = 5e-3

    def contacts(path, lam):
        np.savez(path, fin_names=np.array([fin.name]), t=t, row_start=np.arange(12, dtype=np.int64),
                 fin=np.zeros(11, np.int32), point=np.tile(c1 + lam * (c2 - c1), (11, 1)),
                 force=np.outer(np.sin(np.pi * t / 2e-4), 5e3 * fin.n), width=np.full(11, width))

    contacts(tmp_path / "c.npz", 0.1)
    base = ShellConfig(end_time=6e-4, bearing_rope_modulus=1e11, history_interval=1e-5, fins="named",
                       fin_names=(fin.name,))
    specs = fin_specs([fin], paths)
    r = run_shell(base.model_copy(update={"strike_envelope": True}), specs, tmp_path / "c.npz", None,
                  tmp_path / "a", _log())[fin.name]
    e = r["strike_envelope"]
    assert e["offsets_m"] == pytest.approx([f * width for f in STRIKE_OFFSETS], rel=1e-12)
    assert e["end_time_s"] == pytest.approx(r["peak_time_s"] + PEAK_CHECK_AFTER_S)
    k = len(STRIKE_OFFSETS) - 1  # the largest move out
    contacts(tmp_path / "m.npz", 0.1 + e["offsets_m"][k] / span)
    ref = run_shell(base.model_copy(update={"end_time": e["end_time_s"]}), specs, tmp_path / "m.npz", None,
                    tmp_path / "b", _log())[fin.name]
    assert e["peaks_pa"][k] == ref["peak_von_mises_pa"]
    assert r["strike_envelope_von_mises_pa"] == max(e["peaks_pa"] + [r["peak_von_mises_pa"]])
    assert len(set(e["peaks_pa"])) == len(STRIKE_OFFSETS)  # each move is its own run
    assert (tmp_path / "a" / "strike_envelope" / "+1d" / fin.name / "history.csv").exists()
