"""Sweeps in parallel that resume (issue 11, item 6): a 2 × 2 sweep with -j 2, killed after its
first variant, resumed → four variant folders and four rows; done variants are not run again."""

from __future__ import annotations

import csv
import json
import signal
import time

import pytest

from flexnet_fe.sweep import safe_name, sweep_variants, parse_axis, without_builtin_sweep

from conftest import ROOT, TINY_DEPLOY, run_cli, start_cli

DEPLOY = ROOT / "cases/traction_deploy"


def rows(table):
    with open(table, newline="") as f:
        return list(csv.DictReader(f))


def finished_at(run_dir):
    return json.loads((run_dir / "status.json").read_text())["stages"]["deploy"].get("finished")


@pytest.mark.slow
def test_killed_sweep_resumes(tmp_path):
    out = tmp_path / "sweep"
    args = ["sweep", DEPLOY, *TINY_DEPLOY, "--vary", "deploy.duration=0.05,4.0",
            "--vary", "net.rope_diameter=4e-3,5e-3", "-j", "2", "--out", out]
    proc = start_cli(*args)
    table = out / "sweep.csv"
    end = time.monotonic() + 300
    while not (table.is_file() and rows(table)) and time.monotonic() < end and proc.poll() is None:
        time.sleep(0.05)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 143, err
    first = rows(table)
    assert 1 <= len(first) < 4, first  # the 4 s variants cannot have finished
    assert all(r["error"] == "" for r in first)
    done_before = {r["label"]: finished_at(out / r["label"]) for r in first}

    r = run_cli(*args)
    assert r.returncode == 0, r.stderr
    final = rows(table)
    assert len(final) == 4 and all(x["error"] == "" for x in final), final
    assert [x["label"] for x in final] == ["duration-0.05_rope_diameter-4e-3", "duration-0.05_rope_diameter-5e-3",
                                            "duration-4.0_rope_diameter-4e-3", "duration-4.0_rope_diameter-5e-3"]
    for label, stamp in done_before.items():  # reused, not re-run
        assert finished_at(out / label) == stamp
        assert f"{label}: done earlier with the same inputs, reused" in r.stderr
    assert {float(x["deploy.duration"]) for x in final} == {0.05, 4.0}


def test_variant_names_are_safe_and_unique():
    axes = [parse_axis("net.rope_diameter=4e-3,5e-3"), parse_axis('missile.name="../x","a b"')]
    labels = [v.label for v in sweep_variants(DEPLOY, [], axes)]
    assert labels[0] == "rope_diameter-4e-3_name-..-x" and len(set(labels)) == 4
    assert all(not lab.startswith(".") and "/" not in lab for lab in labels)
    assert safe_name("..") == "v.." and len(safe_name("x" * 1000)) == 100
    assert safe_name("x" * 1000) != safe_name("x" * 999)


def test_builtin_sweep_does_not_run_in_a_sweep_point():
    from flexnet_fe.config import load_case

    case, _ = load_case(ROOT / "cases/flight_wing_sweep")
    assert case.flight.sweep is not None
    assert without_builtin_sweep(case).flight.sweep is None
    assert without_builtin_sweep(case).flight.damage == case.flight.damage


@pytest.mark.mpi
def test_sweep_through_mpi4py_futures(tmp_path):
    """The cluster engine: ``mpiexec -n 3 python -m mpi4py.futures -m flexnet_fe.cli sweep …
    --executor mpi`` (one manager, two workers; each variant runs alone on COMM_SELF)."""
    import shutil
    import subprocess

    from conftest import CLI, env

    if shutil.which("mpiexec") is None:
        pytest.skip("no mpiexec")
    out = tmp_path / "sweep"
    cmd = ["mpiexec", "--oversubscribe", "--allow-run-as-root", "-n", "3", CLI[0], "-m", "mpi4py.futures",
           "-m", "flexnet_fe.cli", "sweep", str(ROOT / "cases/flight_baseline"), "--set", "flight.t_end=1.0",
           "--vary", "flight.navigation_constant=3,4", "--executor", "mpi", "--out", str(out)]
    r = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, env=env(), timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    got = rows(out / "sweep.csv")
    assert [x["label"] for x in got] == ["navigation_constant-3", "navigation_constant-4"]
    assert all(x["error"] == "" and float(x["flight.miss_distance_m"]) > 0 for x in got)
    # the same variants serially give the same numbers (reference: the local engine)
    ref = tmp_path / "ref"
    assert run_cli("sweep", ROOT / "cases/flight_baseline", "--set", "flight.t_end=1.0",
                   "--vary", "flight.navigation_constant=3,4", "--out", ref).returncode == 0
    assert [x["flight.miss_distance_m"] for x in rows(ref / "sweep.csv")] == [x["flight.miss_distance_m"] for x in got]
