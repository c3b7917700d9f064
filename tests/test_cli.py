"""The `flexnet` command: bad input gives one clear line (file, dotted field, reason), exit code 2,
no traceback and no run directory; --help does not import the heavy libraries."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FLEXNET = [sys.executable, "-m", "flexnet_fe.cli"]


def run_cli(*args, cwd=None):
    env = dict(os.environ, FLEXNET_NO_PROGRESS="1")
    return subprocess.run([*FLEXNET, *map(str, args)], capture_output=True, text=True, cwd=cwd or ROOT,
                          env=env, timeout=600)


def test_help_is_light():
    # --help must not import numba, dolfinx, gmsh, pyvista, matplotlib (they take seconds).
    code = ("import sys; from flexnet_fe.cli import build_parser; build_parser().format_help();"
            "import flexnet_fe.config;"
            "heavy=[m for m in ('numba','dolfinx','gmsh','pyvista','matplotlib','scipy') if m in sys.modules];"
            "print(','.join(heavy))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True)
    assert out.stdout.strip() == "", f"heavy modules imported by the CLI/config: {out.stdout}"


BAD_CASES = [
    # (override, expected dotted field, expected words in the reason)
    ("net.rope_diameter=-1e-3", "net.rope_diameter", "greater than 0"),
    ("net.rope_diameter=nan", "net.rope_diameter", "finite"),
    ("net.colour=3", "net.colour", "unknown key"),
    ("atmosphere.altitude='high'", "atmosphere.altitude", "number"),
    ("case.stages=['deploy', 'paint']", "case.stages[1]", "deploy"),
]


@pytest.mark.parametrize("override, field, words", BAD_CASES)
def test_bad_field_is_one_line(tmp_path, override, field, words):
    out_dir = tmp_path / "run"
    r = run_cli("run", ROOT / "cases/traction_deploy", "--out", out_dir, "--set", override)
    assert r.returncode == 2, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in r.stderr, r.stderr
    assert "case.toml" in lines[0] and f": {field}: " in lines[0] and words in lines[0], lines[0]
    assert not out_dir.exists()


def test_bad_toml_names_file(tmp_path):
    bad = tmp_path / "case.toml"
    bad.write_text("[case]\nname = 'x'\nstages = [\n")
    r = run_cli("validate", bad)
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1
    assert str(bad) in r.stderr and "not valid TOML" in r.stderr


def test_missing_case_file(tmp_path):
    r = run_cli("validate", tmp_path / "nope")
    assert r.returncode == 2 and "no such case file" in r.stderr


def test_validate_all_cases():
    for case in sorted((ROOT / "cases").glob("*/case.toml")):
        r = run_cli("validate", case)
        assert r.returncode == 0, r.stderr


def test_failed_stage_is_recorded(tmp_path):
    """A stage that fails leaves status.json saying which and why; earlier summary sections stay."""
    from flexnet_fe.config import Stage, load_case
    from flexnet_fe.pipeline import run_case

    # The traction case plus a default [flight] table, so two stages can run (both stubbed here).
    case, case_dir = load_case(ROOT / "cases/traction_deploy", ["flight.lethal_radius=5.0", 'missile.preset="radar"'])
    calls = []

    def ok(ctx):
        calls.append(ctx.stage_dir.name)
        (ctx.stage_dir / "history.csv").write_text("t_s\n0\n")
        return {"value": 1.0}

    def boom(ctx):
        raise RuntimeError("synthetic failure")

    funcs = {Stage.deploy: ok, Stage.flight: boom}
    with pytest.raises(RuntimeError):
        run_case(case, case_dir, tmp_path, [Stage.deploy, Stage.flight], stage_funcs=funcs)
    status = json.loads((tmp_path / "status.json").read_text())
    assert status["stages"]["deploy"]["state"] == "done"
    assert status["stages"]["flight"] == {**status["stages"]["flight"], "state": "failed",
                                          "error": "synthetic failure"}
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary == {"deploy": {"value": 1.0}}
    assert (tmp_path / "deploy" / "history.csv").is_file()
    # A re-run replaces the stage folder cleanly and the failure is gone.
    (tmp_path / "deploy" / "stale.txt").write_text("old")
    run_case(case, case_dir, tmp_path, [Stage.deploy], stage_funcs=funcs)
    assert not (tmp_path / "deploy" / "stale.txt").exists()
    assert json.loads((tmp_path / "status.json").read_text())["stages"]["flight"]["state"] == "failed"


def test_stage_without_its_table_is_refused(tmp_path):
    r = run_cli("run", ROOT / "cases/traction_deploy", "--out", tmp_path / "r", "--stages", "deploy,collide")
    assert r.returncode == 2 and "--stages" in r.stderr and "[missile]" in r.stderr, r.stderr
    assert not (tmp_path / "r").exists()


def test_report_on_a_sweep_folder_routes_to_the_sweep_report(tmp_path, monkeypatch, capsys):
    """`flexnet report <sweep dir>` just works (issue 12 §5): the folder's sweep.csv is used."""
    import flexnet_fe.report as report
    from flexnet_fe.cli import main

    (tmp_path / "sweep.csv").write_text("label,error\na,\n")
    seen = []
    monkeypatch.setattr(report, "build_sweep_report", lambda table, params: seen.append(table) or table)
    assert main(["report", str(tmp_path)]) == 0
    assert seen == [tmp_path / "sweep.csv"]
