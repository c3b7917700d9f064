"""``mpirun -n 2 flexnet run`` (issue 11, item 5): rank 0 owns the run directory, the shell stage
runs distributed, the result equals the serial run.

Reference: the same shell stage run serially through the same command on a copy of the same run
directory. Only the summation order of the distributed sparse products and reductions differs,
so the stress histories agree to round-off: |Δ| ≤ 1e-10 × the column's largest value."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

from flexnet_fe.config import load_case
from flexnet_fe.io import read_history_csv, write_history_csv
from flexnet_fe.pipeline import run_case
from flexnet_fe.stages import Stage

from conftest import CLI, ROOT, env, run_cli, status

RADAR = ROOT / "cases/radar_traction"
SMALL = ["missile.mesh_size=0.05", "shell.end_time=3e-4", "shell.history_interval=1e-5",
         'collide.net_source="flat_taut"', "shell.local_mesh_size=0.0025"]


def fake_collide(ctx):
    """A rope load at the leading edge of the first wing: a half sine of 5 kN over 0.2 ms."""
    from flexnet_fe.missile.build import build_missile

    fin = build_missile(ctx.case.missile).fins[0]
    t = np.linspace(0.0, 2e-4, 11)
    le_mid = 0.5 * (fin.corners[1] + fin.corners[2])
    np.savez(ctx.stage_dir / "fin_contacts.npz", fin_names=np.array([fin.name]), t=t,
             row_start=np.arange(12, dtype=np.int64), fin=np.zeros(11, np.int32),
             point=np.tile(le_mid, (11, 1)), force=np.outer(np.sin(np.pi * t / 2e-4), 5e3 * fin.n),
             width=np.full(11, 5e-3))
    write_history_csv(ctx.stage_dir / "history.csv", {"t_s": t, **{
        f"accel_body_{a}_mps2": np.zeros_like(t) for a in "xyz"}})
    return {"fin": fin.name}


@pytest.mark.mpi
def test_mpirun_two_ranks_equals_serial(tmp_path):
    if shutil.which("mpirun") is None:
        pytest.skip("no mpirun")
    case, case_dir = load_case(RADAR, SMALL)
    serial, par = tmp_path / "serial", tmp_path / "par"
    run_case(case, case_dir, serial, [Stage.collide], stage_funcs={Stage.collide: fake_collide})
    shutil.copytree(serial, par)
    sets = [a for s in SMALL for a in ("--set", s)]
    r = run_cli("run", RADAR, "--out", serial, "--stages", "shell", *sets)
    assert r.returncode == 0, r.stderr[-3000:]
    p = subprocess.run(["mpirun", "--oversubscribe", "--allow-run-as-root", "-n", "2", *CLI, "run", str(RADAR),
                        "--out", str(par), "--stages", "shell", *sets], capture_output=True, text=True,
                       cwd=ROOT, env=env(), timeout=600)
    assert p.returncode == 0, p.stderr[-3000:]
    assert p.stdout.count("radar_traction: done") == 1  # rank 0 alone reports
    st = status(par)["shell"]
    assert st["state"] == "done" and st["pid"] != 0
    fin = json.loads((serial / "summary.json").read_text())["collide"]["fin"]
    a = read_history_csv(serial / "shell" / fin / "history.csv")
    b = read_history_csv(par / "shell" / fin / "history.csv")
    assert len(a["t_s"]) > 10
    # The peak row's location is the shell's *located* peak: under MPI the peak state is gathered
    # and located on the whole fin (every cell around the peak node), as in the serial run, so
    # every value, location included, must equal the serial run.
    for k in a:
        scale = np.nanmax(np.abs(a[k])) or 1.0
        np.testing.assert_allclose(b[k], a[k], rtol=0, atol=1e-10 * scale, err_msg=k)
    sa, sb = (json.loads((d / "summary.json").read_text())["shell"][fin] for d in (serial, par))
    assert sb["peak_von_mises_pa"] == pytest.approx(sa["peak_von_mises_pa"], rel=1e-10)
    # other ranks never touched the folder: no stray partial folders, one lock, released
    assert sorted(x.name for x in par.iterdir() if x.name.startswith(".")) == []
    assert (par / "run.lock").read_text() == ""


def test_a_singletons_child_is_not_an_mpirun_rank(monkeypatch):
    # Reference: Open MPI's environment, as measured on this machine (2026-11-28): a plain process
    # that initialises MPI (importing dolfinx) becomes a singleton and setenv()s OMPI_MCA_ess=singleton,
    # PMIX_RANK=0 and ~25 more OMPI_*/ORTE_*/PMIX_* variables; a process it starts inherits them
    # (pytest-xdist's workers under `pytest -n 2 tests/shell`: its conftest imports dolfinx in the
    # main process). Such a child is no rank of an mpirun job (it must still run the collision's
    # check beside it), and an mpirun started with that environment exits 1 without a word.
    from flexnet_fe import machine

    singleton = {"OMPI_MCA_ess": "singleton", "PMIX_RANK": "0", "OMPI_MCA_orte_launch": "1",
                 "ORTE_SCHIZO_DETECTION": "ORTE", "PMIX_NAMESPACE": "x", "OMPI_MCA_btl": "self", "PATH": "/bin"}
    for k in machine.MPI_LAUNCH_VARS + tuple(singleton):
        monkeypatch.delenv(k, raising=False)
    assert not machine.launched_by_mpirun()
    for k, v in singleton.items():
        monkeypatch.setenv(k, v)
    assert not machine.launched_by_mpirun()
    monkeypatch.setenv("OMPI_COMM_WORLD_SIZE", "2")  # a real rank has this too
    assert machine.launched_by_mpirun()
    monkeypatch.delenv("OMPI_COMM_WORLD_SIZE")
    monkeypatch.delenv("OMPI_MCA_ess")  # PMIX_RANK without a singleton: a PMIx launcher's rank
    assert machine.launched_by_mpirun()
    assert machine.launcher_env(singleton) == {"PATH": "/bin"}
    assert machine.launcher_env({"OMPI_MCA_btl": "self", "PATH": "/bin"}) == {"OMPI_MCA_btl": "self", "PATH": "/bin"}
    # and mpirun, started from this (now singleton-like) environment through launcher_env, runs
    if shutil.which("mpirun") is None:
        pytest.skip("no mpirun")
    monkeypatch.setenv("OMPI_MCA_ess", "singleton")
    cmd = ["mpirun", "--oversubscribe", "--allow-run-as-root", "-n", "2", sys.executable, "-c",
           "from mpi4py import MPI; print(MPI.COMM_WORLD.size)"]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=120, env=machine.launcher_env(dict(os.environ)))
    assert p.returncode == 0 and "".join(p.stdout.split()) == "22", p.stderr[-2000:]  # (two ranks' lines may interleave)
