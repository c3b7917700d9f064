"""Discoverable inputs (issue 12, item 7): `flexnet schema`, the README's generated case
reference, `--version`, `--help` without internal comments."""

from __future__ import annotations

import subprocess
import sys

from flexnet_fe import __version__
from flexnet_fe.cli import build_parser, main
from flexnet_fe.config import field_paths
from flexnet_fe.schema_doc import schema_text

from conftest import ROOT


def test_schema_lists_every_field_with_unit_and_default():
    text = schema_text()
    for name, paths in field_paths().items():  # a leaf field line, or a sub-table heading
        assert f"  {name} = " in text or any(f"[{p}" in text for p in paths), name
    assert "  rope_diameter = 0.0045   float (> 0)  [m]" in text
    assert "[missile.material]" in text and "  yield_strength = 503000000.0" in text


def test_schema_of_one_table_and_an_unknown_table(capsys):
    assert main(["schema", "collide"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("[collide]") and "impact_speed = 500.0" in out and "[net" not in out
    assert main(["schema", "colide"]) == 2
    assert "no such table; tables: atmosphere, case, collide" in capsys.readouterr().err


def test_readme_case_reference_is_current():
    r = subprocess.run([sys.executable, str(ROOT / "scripts/case_reference.py"), "--check"], cwd=ROOT)
    assert r.returncode == 0, "README.md's case reference is stale: run scripts/case_reference.py"


def test_version_and_help(capsys):
    try:
        main(["--version"])
    except SystemExit as e:
        assert e.code == 0
    assert capsys.readouterr().out.strip() == f"flexnet_fe {__version__}"
    help_text = build_parser().format_help()
    assert "No physics here" not in help_text and "exit codes:" in help_text
    assert "schema" in help_text and "status" in help_text
