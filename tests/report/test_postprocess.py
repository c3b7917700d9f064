"""The postprocess scripts, run as a user runs them (child processes, offscreen EGL)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np

from flexnet_fe.io import pvd_entries

from .synthetic import ENVELOPE_VM_PA, make_run

ROOT = Path(__file__).resolve().parents[2]
ENV = dict(os.environ, VTK_DEFAULT_OPENGL_WINDOW="vtkEGLRenderWindow", PYVISTA_OFF_SCREEN="true")


def _run(script: str, *args) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(ROOT / "postprocess" / script), *map(str, args)],
                          env=ENV, capture_output=True, text=True, timeout=120)


def test_show_stress_envelope(tmp_path):
    run = make_run(tmp_path / "run")
    p = _run("show_stress.py", run)
    assert p.returncode == 0, p.stderr
    png = run / "postprocess" / "wing_1_peak_von_mises.png"
    assert png.is_file()
    # the printed maximum is the largest cell value written into envelope.xdmf
    assert f"max {ENVELOPE_VM_PA.max() / 1e6:.6g} MPa" in p.stdout


def test_show_stress_missing_files_is_an_error(tmp_path):
    run = make_run(tmp_path / "run", xdmf=False)
    p = _run("show_stress.py", run)
    assert p.returncode == 2 and "no fin folders" in p.stderr     # fin folders hold XDMF files
    p = _run("show_stress.py", run, "--fin", "wing_1")
    assert p.returncode == 1 and "no such file" in p.stderr


def test_show_net_from_pvd(tmp_path):
    from flexnet_fe.net.snapshots import write_pvd, write_vtu

    stage = tmp_path / "run" / "deploy"
    (stage / "snapshots").mkdir(parents=True)
    springs = np.array([[0, 1], [1, 2], [2, 3], [3, 0]])
    entries = []
    for k, t in enumerate((0.0, 0.1, 0.2, 0.3)):
        s = 1.0 + k
        x = np.array([[-s, -s, 0.0], [s, -s, 0.0], [s, s, 0.0], [-s, s, 0.0]])
        write_vtu(stage / "snapshots" / f"net_{k:05d}.vtu", x, np.zeros_like(x), springs, np.full(4, 10.0 * k))
        entries.append((t, f"snapshots/net_{k:05d}.vtu"))
    write_pvd(stage / "net.pvd", entries)
    assert [t for t, _ in pvd_entries(stage / "net.pvd")] == [0.0, 0.1, 0.2, 0.3]
    p = _run("show_net.py", tmp_path / "run", "--count", 3)
    assert p.returncode == 0, p.stderr
    assert (tmp_path / "run" / "postprocess" / "deploy_net.png").is_file()
    # 3 snapshots evenly spread over 4: indices 0, 2 (1.5 rounds to even), 3
    assert "3 snapshots, t = 0, 0.2, 0.3 s" in p.stdout


def test_show_net_follows_a_net_that_flies_away(tmp_path):
    """The traction net flies ≈ 370 m along z while it opens; every panel must show it (a
    shared camera drew blank panels). Reference: the panel layout (3 columns × 1 row)."""
    from PIL import Image

    from .synthetic import grid_net, write_lines_pvd

    stage = tmp_path / "run" / "deploy"
    frames = []
    for t, z, half in ((0.0, 0.0, 1.0), (0.1, 120.0, 2.0), (0.2, 370.0, 3.0)):
        x, lines = grid_net(z, half=half)
        frames.append((t, x + np.array([0.0, 0.3 * z, 0.0]), lines))   # drifts sideways too
    write_lines_pvd(stage, "net", frames, tension=True)
    png = tmp_path / "net.png"
    p = _run("show_net.py", tmp_path / "run", "--count", 3, "--out", png)
    assert p.returncode == 0, p.stderr
    img = np.asarray(Image.open(png).convert("L"), dtype=float)
    h, w = img.shape
    for k in range(3):                                   # the middle of each panel holds net lines
        panel = img[h // 4: 3 * h // 4, k * w // 3 + w // 12: (k + 1) * w // 3 - w // 12]
        assert (panel < 200).mean() > 0.01, f"panel {k} is blank"
