"""One writer per run directory, stale locks and stale ``running`` records, dependencies
(``stale`` downstream), disk errors (issue 11, items 1, 3, 4). Stages are stubbed where the test
is about the machinery, not the physics."""

from __future__ import annotations

import errno
import json
import logging
import os
import subprocess
import sys
import uuid

import pytest

from flexnet_fe.cli import main
from flexnet_fe.config import load_case
from flexnet_fe.errors import RunDirError, RunIOError, StageInterrupted
from flexnet_fe.pipeline import run_case
from flexnet_fe.runs import RunLock
from flexnet_fe.stages import Stage

from conftest import ROOT, TINY_DEPLOY, one_error_line, run_cli, status

RADAR = ROOT / "cases/radar_traction"


def _case(*overrides):
    return load_case(RADAR, list(overrides))


def stub(name, calls):
    def run(ctx):
        calls.append(name)
        (ctx.stage_dir / "history.csv").write_text("t_s,x\n0,1\n0.5,2\n")
        assert ctx.stage_dir.name == f".{name}.partial"  # writes go to the temporary folder
        token = f"{name}-{uuid.uuid4().hex}"
        assert not (ctx.run_dir / name / f"{token}.txt").exists()  # a reader never sees it mid-stage
        (ctx.stage_dir / f"{token}.txt").write_text(token)
        return {"value": 1.0}
    return run


def stubs(calls, **override):
    funcs = {s: stub(s.value, calls) for s in Stage}
    funcs.update({Stage(k): v for k, v in override.items()})
    return funcs


def test_second_writer_is_refused(tmp_path):
    run = tmp_path / "run"
    run.mkdir()
    (run / "status.json").write_text('{"stages": {}}')
    with RunLock(run):
        r = run_cli("run", ROOT / "cases/traction_deploy", "--out", run, *TINY_DEPLOY)
    assert r.returncode == 2
    line = one_error_line(r.stderr)
    assert f"{run}: in use by another run (PID {os.getpid()}" in line
    assert json.loads((run / "status.json").read_text()) == {"stages": {}}  # untouched


class _Collect(logging.Handler):
    def __init__(self):
        super().__init__()
        self.lines = []

    def emit(self, record):
        self.lines.append(record.getMessage())


def test_stale_lock_and_stale_running_are_taken_over(tmp_path):
    """A writer killed with SIGKILL leaves its lock file (not locked) and status 'running'."""
    case, case_dir = _case()
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True,
                          text=True).stdout.strip()
    run = tmp_path / "run"
    run.mkdir()
    (run / "run.lock").write_text(json.dumps({"pid": int(dead), "host": "vm", "started": "then"}))
    (run / "status.json").write_text(json.dumps({"stages": {"deploy": {
        "state": "running", "pid": int(dead), "host": os.uname().nodename}}}))
    # `flexnet status` (no lock taken) recognises the dead writer
    assert main(["status", str(run)]) == 0
    calls = []
    notes = _Collect()
    logging.getLogger("flexnet").addHandler(notes)
    try:
        run_case(case, case_dir, run, [Stage.deploy], stage_funcs=stubs(calls))
    finally:
        logging.getLogger("flexnet").removeHandler(notes)
    assert any(f"took over the stale lock of PID {dead}" in ln for ln in notes.lines), notes.lines
    assert status(run)["deploy"]["state"] == "done" and calls == ["deploy"]
    assert (run / "run.lock").read_text() == ""  # released


def test_status_command_names_a_dead_running_stage(tmp_path, capsys):
    run = tmp_path / "run"
    run.mkdir()
    (run / "status.json").write_text(json.dumps({"stages": {"deploy": {
        "state": "running", "pid": 2 ** 22 + 7, "host": os.uname().nodename}}}))
    assert main(["status", str(run)]) == 0
    assert "deploy   running (stale): process" in capsys.readouterr().out


def test_interrupted_upstream_makes_downstream_stale(tmp_path):
    """collide re-run interrupted → shell and flight must not stay 'done' (issue 11 "Why")."""
    case, case_dir = _case()
    calls = []
    run_case(case, case_dir, tmp_path, stage_funcs=stubs(calls))
    assert [status(tmp_path)[s]["state"] for s in ("deploy", "collide", "shell", "flight")] == ["done"] * 4

    def interrupted(ctx):
        (ctx.stage_dir / "history.csv").write_text("t_s,x\n0,1\n0.25,2\n")
        raise KeyboardInterrupt

    with pytest.raises(StageInterrupted, match=r"interrupted during collide; outputs up to t = 0.25 s kept"):
        run_case(case, case_dir, tmp_path, [Stage.collide], stage_funcs=stubs(calls, collide=interrupted))
    st = status(tmp_path)
    assert st["deploy"]["state"] == "done" and st["collide"]["state"] == "interrupted"
    assert st["shell"]["state"] == "stale" and "upstream stage 'collide' is interrupted" in st["shell"]["stale_reason"]
    assert st["flight"]["state"] == "stale"
    assert set(json.loads((tmp_path / "summary.json").read_text())) == {"deploy"}
    # the default re-run resumes: deploy is skipped, collide, shell and flight run again
    calls.clear()
    run_case(case, case_dir, tmp_path, stage_funcs=stubs(calls))
    assert calls == ["collide", "shell", "flight"]
    assert all(status(tmp_path)[s]["state"] == "done" for s in ("deploy", "collide", "shell", "flight"))


def test_changed_inputs_make_a_stage_and_its_downstream_stale(tmp_path):
    case, case_dir = _case()
    calls = []
    run_case(case, case_dir, tmp_path, stage_funcs=stubs(calls))
    changed, _ = _case("collide.restitution=0.3")   # collide's table: deploy stays valid
    calls.clear()
    run_case(changed, case_dir, tmp_path, stage_funcs=stubs(calls))
    assert calls == ["collide", "shell", "flight"]
    calls.clear()
    run_case(changed, case_dir, tmp_path, stage_funcs=stubs(calls), force=True)
    assert calls == ["deploy", "collide", "shell", "flight"]
    # --stages deploy alone with new net inputs: the others become stale, never "done"
    net_changed, _ = _case("collide.restitution=0.3", "net.damping_ratio=0.1")
    run_case(net_changed, case_dir, tmp_path, [Stage.deploy], stage_funcs=stubs(calls))
    st = status(tmp_path)
    assert [st[s]["state"] for s in ("deploy", "collide", "shell", "flight")] == ["done", "stale", "stale", "stale"]
    assert "inputs changed" in st["collide"]["stale_reason"]


def test_downstream_alone_refused_when_upstream_is_not_done(tmp_path):
    case, case_dir = _case()
    with pytest.raises(Exception, match=r"needs the results of stage 'collide'.*--stages collide,shell"):
        run_case(case, case_dir, tmp_path, [Stage.shell], stage_funcs=stubs([]))


def test_disk_full_in_a_stage_is_one_line_and_failed(tmp_path, capsys, monkeypatch):
    """Simulated ENOSPC from inside a stage (the tmpfs test below does it for real)."""
    import dataclasses

    from flexnet_fe import stages as stages_mod

    def full(ctx):
        raise OSError(errno.ENOSPC, "No space left on device", str(ctx.stage_dir / "history.csv"))

    def ok(ctx):
        (ctx.stage_dir / "history.csv").write_text("t_s\n0\n")
        return {"value": 2.0}

    reg = dict(stages_mod.REGISTRY)
    reg[Stage.deploy] = dataclasses.replace(reg[Stage.deploy], run=ok)
    reg[Stage.flight] = dataclasses.replace(reg[Stage.flight], run=full)
    monkeypatch.setattr(stages_mod, "REGISTRY", reg)
    monkeypatch.setattr("flexnet_fe.pipeline.REGISTRY", reg)
    run = tmp_path / "run"
    rc = main(["run", str(ROOT / "cases/traction_deploy"), "--out", str(run), *TINY_DEPLOY,
               "--set", 'case.stages=["deploy", "flight"]', "--set", "flight.lethal_radius=5.0", "--set", 'missile.preset="radar"'])
    assert rc == RunIOError.exit_code == 74
    line = one_error_line(capsys.readouterr().err)
    assert "history.csv: No space left on device (ENOSPC)" in line and "stage flight" in line
    st = status(run)
    assert st["flight"]["state"] == "failed" and "ENOSPC" in st["flight"]["error"]
    assert st["deploy"]["state"] == "done" and (run / "deploy" / "history.csv").is_file()
    assert json.loads((run / "summary.json").read_text()) == {"deploy": {"value": 2.0}}


def _mount_tmpfs(path, size="300k") -> bool:
    path.mkdir()
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(path)], capture_output=True)
    return r.returncode == 0


@pytest.mark.slow
def test_real_full_disk(tmp_path):
    """A 300 kB tmpfs as --out: deploy fits, flight's history does not. The budget refuses the
    case up front; with --force the real ENOSPC is one line, status failed, deploy intact."""
    mnt = tmp_path / "mnt"
    if not _mount_tmpfs(mnt):
        pytest.skip("cannot mount a tmpfs here (the patched-writer test covers ENOSPC)")
    try:
        run = mnt / "run"
        args = ["run", ROOT / "cases/traction_deploy", "--out", run, "--set", "net.edge_length=1.0",
                "--set", "net.mesh_size=0.25", "--set", "deploy.duration=0.05", "--set",
                "deploy.snapshot_interval=0.05", "--set", 'case.stages=["deploy", "flight"]',
                "--set", "flight.lethal_radius=5.0", "--set", "flight.t_end=6.0",
                "--set", 'missile.preset="radar"']
        r = run_cli(*args)
        assert r.returncode == 2 and "free in" in one_error_line(r.stderr) and not run.exists()
        r = run_cli(*args, "--force")
        assert r.returncode == 74, r.stderr
        line = one_error_line(r.stderr)
        assert "No space left on device (ENOSPC)" in line, line
        st = status(run)
        assert st["flight"]["state"] == "failed" and st["deploy"]["state"] == "done"
        assert (run / "deploy" / "history.csv").is_file()
    finally:
        subprocess.run(["umount", str(mnt)])


def test_lock_refuses_the_same_process_twice(tmp_path):
    with RunLock(tmp_path):
        with pytest.raises(RunDirError, match="in use by another run"):
            RunLock(tmp_path).acquire()
    RunLock(tmp_path).acquire().release()


def test_read_only_output_folder(tmp_path):
    """A read-only --out: one line with the path and EROFS, exit 74, no traceback."""
    mnt = tmp_path / "ro"
    mnt.mkdir()
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", "ro,size=100k", "tmpfs", str(mnt)], capture_output=True)
    if r.returncode != 0:
        pytest.skip("cannot mount a read-only tmpfs here")
    try:
        r = run_cli("run", ROOT / "cases/traction_deploy", "--out", mnt / "run", *TINY_DEPLOY, "--force")
        assert r.returncode == 74
        assert one_error_line(r.stderr).endswith(f"{mnt / 'run'}: Read-only file system (EROFS) while creating "
                                                 "the run directory")
    finally:
        subprocess.run(["umount", str(mnt)])
