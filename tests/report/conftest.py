"""Fixtures of the report tests: synthetic run directories in tmp_path (see synthetic.py)."""

from __future__ import annotations

from pathlib import Path

import pytest

from .synthetic import make_run


@pytest.fixture
def run_dir(tmp_path) -> Path:
    """A synthetic run: deploy, collide, shell done (one fin with an envelope XDMF); flight failed."""
    return make_run(tmp_path / "run")
