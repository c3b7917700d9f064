"""``[collide] resolution_check``: the headlines' moves when the rope pieces at the fins are halved."""

from __future__ import annotations

import logging
import multiprocessing
import os
import signal

import pytest
from pydantic import ValidationError

from flexnet_fe.atmosphere import isa
from flexnet_fe.collide.config import CollideConfig
from flexnet_fe.collide.resolution import resolution_moves
from flexnet_fe.collide.scene import held_net
from flexnet_fe.collide.simulate import simulate
from flexnet_fe.errors import NumericalError
from flexnet_fe.collide import check
from flexnet_fe.collide.stage import run_collide
from flexnet_fe.missile.build import build_missile
from flexnet_fe.missile.config import MissileConfig
from flexnet_fe.net.config import TractionNet

LOG = logging.getLogger("test_resolution")


def _summary(dv, peak, imp, dur, fins):
    return {"dv_over_v": dv, "peak_accel_mps2": peak, "impulse_ns": imp, "duration_s": dur, "fin_impulse_ns": fins}


def test_moves_are_relative_to_the_finer_run_and_flag_beyond_the_tolerance():
    # Reference: the definition, (fine − coarse) / fine, by hand. Δv 0.93 → 1.00 moves +7 % (flagged
    # at 2 %), the peak 14.0 → 14.1 +0.71 % (not), rudder_2 1.0 → 1.5 +33 %; wing_9 carries 1 % of
    # the fin impulse (< SHARE_MIN) and is not checked however far it moves.
    coarse = _summary(0.93, 14.0, 10.0, 0.0104, {"wing_1": 4.0, "rudder_2": 1.0, "wing_9": 0.01})
    fine = _summary(1.00, 14.1, 10.0, 0.0104, {"wing_1": 4.0, "rudder_2": 1.5, "wing_9": 0.06})
    section, warnings = resolution_moves(coarse, fine, 0.35e-3, 0.02)
    assert section["dv_over_v_move_rel"] == pytest.approx(0.07)
    assert section["peak_accel_move_rel"] == pytest.approx(0.1 / 14.1)
    assert section["impulse_move_rel"] == 0.0 and section["duration_move_rel"] == 0.0
    assert section["fin_impulse_move_rel"] == {"wing_1": 0.0, "rudder_2": pytest.approx(1 / 3)}
    assert section["flagged"] == ["Δv/v", "rudder_2 impulse"] and len(warnings) == 2
    assert "+7.0 %" in warnings[0] and "0.7 → 0.35 mm" in warnings[0]
    # a headline the finer run does not have at all (no contact left): −100 %, finite for strict JSON
    gone, gone_w = resolution_moves(coarse, {**fine, "duration_s": 0.0}, 0.35e-3, 0.02, 0.7e-3)
    assert gone["duration_move_rel"] == -1.0 and "contact duration" in gone["flagged"]
    assert "0.7 → 0.35 mm, chords 1.4 → 0.7 mm" in gone_w[0]  # the chord of collide.adapt, halved too


def test_check_needs_a_piece_length_to_halve():
    with pytest.raises(ValidationError, match="resolution_check needs fin_piece_length"):
        CollideConfig(resolution_check=True)


@pytest.mark.parametrize("beside", [True, False])
def test_stage_reports_the_moves_of_the_two_runs(tmp_path, monkeypatch, beside):
    # Reference: a second model, the same impact run by hand at half the pieces — both the pieces
    # cut at the start and the chord they are cut to where they press (simulate is deterministic):
    # the stage's moves are exactly those of the two summaries, whether the check's impact ran in a
    # second process beside the run's (two cores) or after it in this one.
    monkeypatch.setattr(check, "check_beside", lambda: beside)
    net_cfg = TractionNet(edge_length=1.0, mesh_size=0.05, rope_diameter=4.5e-3, corner_mass=1e-3,
                          transverse_modulus=1e11)
    cfg = CollideConfig(net_source="flat_taut", duration=4e-3, aim_point=(0.025, 0.025), snapshots=2,
                        fin_piece_length=4e-3, fin_piece_chord=8e-3, resolution_check=True)
    air = isa(8000.0)
    s = run_collide(net_cfg, None, MissileConfig(preset="radar"), cfg, air, None, tmp_path, LOG)
    missile = build_missile(MissileConfig(preset="radar"))
    fine = simulate(held_net(net_cfg, cfg.net_source, None), missile,
                    cfg.model_copy(update={"fin_piece_length": 2e-3, "fin_piece_chord": 4e-3, "resolution_check": False}),
                    air.gravity, LOG,
                    air_density=air.density, n_snapshots=2).summary
    expected, warnings = resolution_moves(s, fine, 2e-3, cfg.resolution_tolerance, 4e-3)
    got = dict(s["resolution_check"])
    assert got.pop("wall_s") > 0.0 and got.pop("fin_piece_chord_m") == 4e-3
    assert s["cut_segments"] > 0 and fine["cut_segments"] > 0  # the chord rule was at work in both
    assert got == expected and got["fin_impulse_move_rel"]  # fins were hit and checked
    assert all(w in s["warnings"] for w in warnings)


def test_a_failing_check_stops_the_stage_with_its_reason(tmp_path):
    # Reference: the check's own error. A contact far too soft for the impact (K = 1 N/m^1.5, given)
    # lets the rope's centre line reach a fin's core in both impacts; the run's impact stops first
    # or the check's does — either way the stage raises the one-line tunnelling error (the check's
    # is labelled as the check's), the check's process is gone, and nothing is written.
    net_cfg = TractionNet(edge_length=1.0, mesh_size=0.05, rope_diameter=4.5e-3, corner_mass=1e-3)
    cfg = CollideConfig(net_source="flat_taut", duration=4e-3, aim_point=(0.025, 0.025), snapshots=2,
                        fin_piece_length=4e-3, resolution_check=True, stiffness_rule="given", contact_stiffness=1.0)
    with pytest.raises(NumericalError, match="tunnelling"):
        run_collide(net_cfg, None, MissileConfig(preset="radar"), cfg, isa(8000.0), None, tmp_path, LOG)
    assert not (tmp_path / "history.csv").exists()
    assert not [p for p in multiprocessing.active_children() if p.name == "flexnet-resolution-check"]


def test_the_check_process_error_reaches_the_stage_as_one_line(monkeypatch):
    # Reference: the check's own error, raised by simulate in the check's process function run here
    # (in this process, so its message can be read): it is sent back as an error, not a crash, and
    # the stage raises it as the check's NumericalError, one line, its log lines passed on.
    net_cfg = TractionNet(edge_length=1.0, mesh_size=0.05, rope_diameter=4.5e-3, corner_mass=1e-3)
    cfg = CollideConfig(net_source="flat_taut", duration=4e-3, aim_point=(0.025, 0.025), snapshots=2,
                        fin_piece_length=4e-3, stiffness_rule="given", contact_stiffness=1.0)
    air = isa(8000.0)
    monkeypatch.setattr(signal, "signal", lambda *a: None)  # (the process function ignores Ctrl-C: not here)
    monkeypatch.setenv("FLEXNET_NO_PROGRESS", "1")  # (it sets it: restored after the test)
    monkeypatch.setattr(logging.getLogger("flexnet.collide.check"), "handlers", [])  # (it adds one)
    monkeypatch.setattr(check, "_exit_with", lambda parent: None)  # (it watches its parent: this process's)
    recv, send = multiprocessing.Pipe(duplex=False)
    check._check_process(send, os.getppid(), held_net(net_cfg, cfg.net_source, None),
                         build_missile(MissileConfig(preset="radar")), cfg, air.gravity, air.density, None)
    kind, numerical, message, lines = recv.recv()
    assert (kind, numerical) == ("error", True) and "tunnelling" in message and "\n" not in message
    assert any("dt =" in line for line in lines)  # the check's log came back with it
    recv2, send2 = multiprocessing.Pipe(duplex=False)
    send2.send((kind, numerical, message, lines))
    job = check._Check((), 2e-3, None, proc=object(), conn=recv2)
    with pytest.raises(NumericalError, match="in the resolution check's impact .*tunnelling"):
        check.finish_check({}, job, cfg, LOG)


def test_a_sweep_worker_runs_the_check_in_its_own_process():
    # Reference: multiprocessing's rule — a daemonic process (a pool worker of ``flexnet sweep -j N``)
    # may not start processes (Process.start asserts it). In such a worker the check must run after
    # the impact, in the worker; in this (non-daemonic) process on two cores it may run beside.
    with multiprocessing.get_context("spawn").Pool(1) as pool:
        assert pool.apply(check.check_beside) is False
    assert check.check_beside() is (check.cpu_count() >= 2 and not check.launched_by_mpirun())


def test_the_check_stays_in_a_script_whose_top_level_would_run_again(monkeypatch):
    # Reference: multiprocessing's spawn rule — the child imports the parent's __main__ again, by name
    # when it was run with -m, else by path, running a script's top level. A user's script that calls
    # cli.main at its top level would run the case again in the child: the check runs after the impact
    # there. The flexnet entry point (a guarded script) and -m modules may start the process.
    import sys
    import types

    script = types.ModuleType("__main__")
    script.__spec__, script.__file__ = None, "/home/user/my_study.py"
    monkeypatch.setitem(sys.modules, "__main__", script)
    assert check._main_reimport_safe() is False and check.check_beside() is False
    script.__file__ = "/work/venv/bin/flexnet"
    assert check._main_reimport_safe() is True
    script.__spec__ = types.SimpleNamespace(name="pytest")
    script.__file__ = "/home/user/my_study.py"
    assert check._main_reimport_safe() is True


_KILLED_PARENT = """
import logging, os, signal, time
from flexnet_fe.atmosphere import isa
from flexnet_fe.collide import check
from flexnet_fe.collide.config import CollideConfig
from flexnet_fe.collide.scene import held_net
from flexnet_fe.missile.build import build_missile
from flexnet_fe.missile.config import MissileConfig
from flexnet_fe.net.config import TractionNet

check.check_beside = lambda: True
net_cfg = TractionNet(edge_length=1.0, mesh_size=0.05, rope_diameter=4.5e-3, corner_mass=1e-3)
cfg = CollideConfig(net_source="flat_taut", duration=0.5, aim_point=(0.025, 0.025), snapshots=2,
                    fin_piece_length=4e-3, resolution_check=True, impact_speed=5.0)
job = check.start_check(held_net(net_cfg, cfg.net_source, None), build_missile(MissileConfig(preset="radar")),
                        cfg, isa(8000.0), logging.getLogger("test"))
print(job.proc.pid, flush=True)
time.sleep(float(os.environ["KILL_AFTER_S"]))
os.kill(os.getpid(), signal.SIGKILL)
"""


def _gone(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/status") as f:
            return any(line.startswith("State:") and "Z" in line for line in f)
    except FileNotFoundError:
        return True


@pytest.mark.parametrize("kill_after_s", [0.0, 4.0])
def test_the_check_process_ends_when_the_stage_process_is_killed(kill_after_s):
    # Reference: the kernel's rule that an orphan is re-parented (its getppid changes). A stage's
    # process killed outright (SIGKILL: no clean-up runs) while its check's impact is starting up
    # (0 s) or running (4 s): the check's process ends within a few of its parent polls instead of
    # running its impact on (this slow 5 m/s impact runs well past the 15 s waited: without the
    # watch both cases failed; at 20 m/s it ran 10–30 s).
    import subprocess
    import sys
    import time
    from pathlib import Path

    # (the child holds the parent's stdout and stderr: read the one line, then wait for the parent)
    proc = subprocess.Popen([sys.executable, "-c", _KILLED_PARENT], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                            text=True, cwd=Path(__file__).resolve().parents[2],
                            env=dict(os.environ, KILL_AFTER_S=str(kill_after_s), FLEXNET_NO_PROGRESS="1"))
    child = int(proc.stdout.readline())
    assert proc.wait(timeout=120) == -signal.SIGKILL
    proc.stdout.close()
    end = time.monotonic() + 15.0  # its imports (≈ 2 s, more under load), then a poll of 0.5 s
    while not _gone(child) and time.monotonic() < end:
        time.sleep(0.1)
    gone = _gone(child)
    if not gone:
        os.kill(child, signal.SIGKILL)
    assert gone
