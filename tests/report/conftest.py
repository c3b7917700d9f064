"""Fixtures of the report tests: synthetic run directories in tmp_path (see synthetic.py)."""

from __future__ import annotations

from pathlib import Path

import pytest

from .synthetic import make_run, parse_html


@pytest.fixture
def run_dir(tmp_path) -> Path:
    """A synthetic run: deploy, collide, shell done (two fins with fields and envelope XDMF,
    a body mesh, collide snapshots); flight failed."""
    return make_run(tmp_path / "run")


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """(run_dir, html text, parsed tree) of one report built once per test module (read only)."""
    from flexnet_fe.report import build_report

    run = make_run(tmp_path_factory.mktemp("built") / "run")
    html = build_report(run).read_text()
    return run, html, parse_html(html)
