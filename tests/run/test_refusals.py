"""Every refusal listed in issue 11 "Why": one line naming the file (or option), the field and the
reason, exit code 2, no traceback, and no run folder left behind. Run in-process through
``flexnet_fe.cli.main`` (the same code path as the command, without a Python start per case),
plus one subprocess check that the command itself prints no traceback."""

from __future__ import annotations

import pytest

from flexnet_fe.cli import main

from conftest import ROOT, one_error_line, run_cli

RADAR = ROOT / "cases/radar_traction"
DEPLOY = ROOT / "cases/traction_deploy"
FLIGHT = ROOT / "cases/flight_baseline"
LONG = "a" * 10000

# (case, extra arguments, the file or option named, the field named, words of the reason)
REFUSALS = [
    (DEPLOY, ["--set", 'case.name=".."'], "case.toml", "case.name", "must not start with '.'"),
    (DEPLOY, ["--set", 'case.name="."'], "case.toml", "case.name", "must not start with '.'"),
    (DEPLOY, ["--set", f'case.name="{LONG}"'], "case.toml", "case.name", "at most 100 characters"),
    (DEPLOY, ["--set", 'case.name="../escape"'], "case.toml", "case.name", "must not start with '.'"),
    (DEPLOY, ["--set", 'case.name="a/b"'], "case.toml", "case.name", "only letters"),
    (RADAR, ["--set", 'case.stages=["collide", "deploy"]'], "case.toml", "case.stages", "pipeline order: deploy, collide"),
    (RADAR, ["--stages", "shell,collide"], "--stages", "--stages", "pipeline order: collide, shell"),
    (RADAR, ["--stages", "deploy,deploy"], "--stages", "--stages", "listed twice"),
    (DEPLOY, ["--set", "net.mesh_size=0.1\nnet.edge_length=9"], "--set", "net.mesh_size", "single TOML value"),
    (DEPLOY, ["--set", "net.mesh_size=0.1 0.2"], "--set", "net.mesh_size", "not a single TOML value"),
    (DEPLOY, ["--set", "net.edge_length=true"], "case.toml", "net.edge_length", "got a boolean"),
    (DEPLOY, ["--set", "net.edge_length=0.01"], "case.toml", "net.mesh_size", "larger than net.edge_length"),
    (DEPLOY, ["--set", "net.rope_diameter=1e308"], "case.toml", "net.rope_diameter", "not a finite positive number"),
    (RADAR, ["--set", "collide.impact_speed=1e308"], "case.toml", "collide.impact_speed", "not a finite positive number"),
    (DEPLOY, ["--set", "net.mesh_size=1e-6"], "case.toml", "net.mesh_size", "of memory"),
    (DEPLOY, ["--set", "deploy.duration=1e6"], "case.toml", "deploy.output_interval", "deploy.duration / deploy.output_interval"),
    (DEPLOY, ["--set", "deploy.output_interval=1e-12"], "case.toml", "deploy.output_interval", "of memory"),
    (FLIGHT, ["--set", "flight.t_end=1e6"], "case.toml", "flight.output_dt", "of memory"),
    (DEPLOY, ["--set", "net.mesh_size=1e-3"], "case.toml", "net.mesh_size", "of memory"),
    (RADAR, ["--set", "missile.mesh_size=1e-5"], "case.toml", "missile.mesh_size", "of memory"),
    (DEPLOY, ["--set", "deploy.time_step=0.01"], "case.toml", "deploy.time_step", "stability limit"),
    (DEPLOY, ["--set", "net.rope_diamter=1e-3"], "case.toml", "net.rope_diamter", "did you mean rope_diameter"),
    (RADAR, ["--set", "shell.yield_strength=1e8"], "case.toml", "shell.yield_strength", "belongs in [missile.material]"),
]


@pytest.mark.parametrize("case, extra, where, field, words", REFUSALS,
                         ids=[f"{r[3]}:{r[4][:24]}" for r in REFUSALS])
def test_refusal_is_one_line(case, extra, where, field, words, tmp_path, capsys, monkeypatch):
    # A fixed memory budget (4 GB) so the refusals do not depend on the machine's free memory.
    monkeypatch.setenv("FLEXNET_MEMORY_BUDGET", "4e9")
    out = tmp_path / "run"
    assert main(["run", str(case), "--out", str(out), *extra]) == 2
    line = one_error_line(capsys.readouterr().err)
    assert f"{where}: " in line and (field == where or f": {field}: " in line) and words in line, line
    assert not out.exists()


def test_force_skips_the_budget(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("FLEXNET_MEMORY_BUDGET", "1e6")  # 1 MB: every case is above it
    assert main(["validate", str(DEPLOY)]) == 2
    assert "of memory" in capsys.readouterr().err
    assert main(["validate", str(DEPLOY), "--force"]) == 0
    out = capsys.readouterr().out
    assert "deploy: 1.02e+04 nodes" in out and "steps" in out


def test_refuses_a_folder_that_is_not_a_run_directory(tmp_path, capsys):
    """Without this, `--out .` (or case name "..") would replace someone's deploy/ folder."""
    (tmp_path / "deploy").mkdir()
    (tmp_path / "deploy" / "precious.txt").write_text("keep me")
    assert main(["run", str(DEPLOY), "--out", str(tmp_path)]) == 2
    assert "not a run directory" in one_error_line(capsys.readouterr().err)
    assert (tmp_path / "deploy" / "precious.txt").read_text() == "keep me"


def test_command_prints_no_traceback(tmp_path):
    out = tmp_path / "run"
    r = run_cli("run", DEPLOY, "--out", out, "--set", 'case.name=".."')
    assert r.returncode == 2 and "case.name" in one_error_line(r.stderr)
    assert not out.exists()
