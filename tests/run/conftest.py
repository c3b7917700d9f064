"""Shared helpers for the run-machinery tests: the CLI as a subprocess or in-process, small cases."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from flexnet_fe.machine import launcher_env

ROOT = Path(__file__).resolve().parents[2]
PY = sys.executable
CLI = [PY, "-m", "flexnet_fe.cli"]

TINY_DEPLOY = ["--set", "net.edge_length=1.0", "--set", "net.mesh_size=0.1"]
"""traction_deploy on a 1 m net of 10 cm cells: 121 nodes; ≈ 1 s of wall time per simulated second."""


def env() -> dict:
    return dict(launcher_env(dict(os.environ)), FLEXNET_NO_PROGRESS="1", PYTHONPATH=str(ROOT))


def run_cli(*args, timeout=600, extra_env=None):
    return subprocess.run([*CLI, *map(str, args)], capture_output=True, text=True, cwd=ROOT,
                          env={**env(), **(extra_env or {})}, timeout=timeout)


def start_cli(*args) -> subprocess.Popen:
    return subprocess.Popen([*CLI, *map(str, args)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            cwd=ROOT, env=env())


def status(run_dir: Path) -> dict:
    return json.loads((Path(run_dir) / "status.json").read_text())["stages"]


def wait_for_state(run_dir: Path, stage: str, state: str, proc: subprocess.Popen, timeout=120.0) -> None:
    """Poll status.json until ``stage`` is in ``state`` (fails if the process ends first)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        try:
            if status(run_dir)[stage]["state"] == state:
                return
        except (OSError, ValueError, KeyError):
            pass
        if proc.poll() is not None:
            pytest.fail(f"process ended (rc {proc.returncode}) before {stage} was {state}: {proc.stderr.read()[-2000:]}")
        time.sleep(0.05)
    pytest.fail(f"{stage} never reached {state}")


def interrupt(proc: subprocess.Popen, sig: int) -> tuple[int, str]:
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=120)
    return proc.returncode, err


def one_error_line(stderr: str) -> str:
    """The stderr of a refused command: exactly one line that is not an INFO/WARNING log line."""
    lines = [ln for ln in stderr.strip().splitlines() if not ln.startswith(("INFO ", "WARNING ", "DEBUG "))]
    assert "Traceback" not in stderr, stderr
    assert len(lines) == 1, stderr
    return lines[0]


SIGNALS = {"SIGINT": (signal.SIGINT, 130), "SIGTERM": (signal.SIGTERM, 143)}
