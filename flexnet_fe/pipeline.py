"""Run a case's stages into a run directory (DESIGN.md §3) and keep ``status.json`` honest.

The files and states are those of :mod:`flexnet_fe.runs`. What this module guarantees:

- **One writer**: the run holds ``run.lock`` (flock) from start to end; a second run into the same
  folder is refused with one line; a lock left by a killed run is taken over with a note.
- **No half-replaced stage**: a stage writes into ``.<stage>.partial/``, renamed to ``<stage>/``
  when it ends (done, failed or interrupted).
- **Signals**: SIGINT / SIGTERM during a stage record ``interrupted`` (time, signal, last output
  time) and end with one line and exit 130 / 143. Heavy libraries are imported *before* the
  handlers are installed: importing gmsh resets SIGINT to the default (process killed at once).
- **I/O errors** (disk full, read-only, permission) record ``failed`` with the path and errno.
- **Dependencies**: each stage's record holds the hash of its inputs (its case tables and its
  upstream stages' hashes); a done stage whose inputs changed, or whose upstream stage is not
  done, becomes ``stale``. ``flexnet run`` without ``--stages`` skips stages that are done and
  up to date (so a re-run after an interrupt resumes) unless ``force``.
- **MPI** (``mpirun -n N flexnet run``): rank 0 owns the run directory (lock, status, summary,
  renames, every stage that is not distributed); the shell stage runs on every rank, the other
  ranks writing only the solver's collective XDMF/HDF5 output inside the stage folder rank 0
  created.
"""

from __future__ import annotations

import errno
import hashlib
import json
import logging
import os
import platform
import shutil
import signal
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from flexnet_fe import __version__
from flexnet_fe.config import Case, case_hash, resolved_dict
from flexnet_fe.errors import CaseError, FlexnetError, RunIOError, StageInterrupted
from flexnet_fe.io import atomic_write_json, read_json
from flexnet_fe.machine import launched_by_mpirun
from flexnet_fe.runs import (RESOLVED, STAGE_LOG, STATUS, SUMMARY, RunLock, StageContext, check_run_dir,
                             last_output_time, me, now, partial_dir, process_alive, publish_stage,
                             interrupt_handled, signal_handlers, signals_deferred, stage_dir)
from flexnet_fe.stages import REGISTRY, STAGE_ORDER, Stage, pipeline_order_error

LOG = logging.getLogger("flexnet")

IO_ERRNOS = {errno.ENOSPC, errno.EROFS, errno.EACCES, errno.EPERM, errno.EDQUOT, errno.EIO, errno.EFBIG}
"""Operating-system errors reported as one line with path and errno (not a traceback)."""

HEAVY_MODULES = ("numba", "scipy", "pydantic", "dolfinx", "gmsh")
"""Imported (for their versions) before the signal handlers are installed."""


def _versions() -> dict[str, str]:
    import numpy
    out = {"flexnet_fe": __version__, "python": platform.python_version(), "numpy": numpy.__version__}
    for mod in HEAVY_MODULES:
        try:
            out[mod] = str(__import__(mod).__version__)
        except Exception:  # not installed or not importable: record that, don't fail the run
            out[mod] = "unavailable"
    return out


def stage_hashes(case: Case) -> dict[Stage, str]:
    """SHA-256 of each stage's inputs: the case tables it reads and its upstream stages' hashes
    (so a change upstream changes every hash downstream). Stages the case cannot run are absent."""
    data, out = resolved_dict(case), {}
    for stage in STAGE_ORDER:
        spec = REGISTRY[stage]
        if any(getattr(case, t) is None for t in spec.needs):
            continue
        tables = (*spec.reads, *spec.reads_also(case))
        blob = {"stage": stage.value, "version": __version__, "tables": {t: data.get(t) for t in tables},
                "upstream": {u.value: out.get(u) for u in spec.upstream(case)}}
        out[stage] = hashlib.sha256(json.dumps(blob, sort_keys=True).encode()).hexdigest()
    return out


class Status:
    """``status.json``: one record per stage, rewritten atomically on every change."""

    def __init__(self, path: Path, case: Case, hashes: dict[Stage, str]):
        self.path, self.case, self.hashes = path, case, hashes
        old = read_json(path) if path.is_file() else {}
        records = old.get("stages", {}) if isinstance(old.get("stages"), dict) else {}
        self.data = {"case": case.case.name, "case_hash": case_hash(case),
                     "stages": {s.value: records.get(s.value, {"state": "pending"}) for s in STAGE_ORDER}}
        for s in STAGE_ORDER:  # we hold the lock: a record saying "running" is a dead writer's
            rec = self.record(s)
            if rec.get("state") == "running":
                self.data["stages"][s.value] = {**rec, "state": "interrupted", "interrupted_at": None, "error": (
                    f"process {rec.get('pid', '?')} on {rec.get('host', '?')} ended while running this stage "
                    f"(found by the next run)")}
        self.save()

    def record(self, stage: Stage) -> dict:
        return self.data["stages"][stage.value]

    def state(self, stage: Stage) -> str:
        return self.record(stage).get("state", "pending")

    def set(self, stage: Stage, **fields) -> None:
        self.data["stages"][stage.value] = fields
        self.save()

    def stale_reason(self, stage: Stage) -> str | None:
        """Why a ``done`` stage's results no longer follow from the case, or None."""
        rec = self.record(stage)
        if stage not in self.hashes:
            return "the case no longer has this stage's tables"
        if rec.get("input_hash") != self.hashes[stage]:
            return "its inputs changed since it ran"
        for up in REGISTRY[stage].upstream(self.case):
            if self.state(up) != "done":
                return f"upstream stage '{up.value}' is {self.state(up)}"
        return None

    def save(self) -> None:
        for s in STAGE_ORDER:  # done → stale where the inputs moved on (in pipeline order);
            rec = self.record(s)  # a stale stage stays stale (its reason updated) until re-run
            if rec.get("state") in ("done", "stale"):
                reason = self.stale_reason(s)
                if reason:
                    self.data["stages"][s.value] = {**rec, "state": "stale", "stale_reason": reason}
        atomic_write_json(self.path, self.data)


def plan_stages(case: Case, stages: list[Stage] | None) -> list[Stage]:
    """The stages to run: ``stages`` as given (distinct, in pipeline order) or the case's own."""
    wanted = list(stages or case.case.stages)
    reason = pipeline_order_error(wanted)
    if reason:
        raise CaseError("--stages", ",".join(s.value for s in wanted), reason)
    for stage in wanted:
        missing = [t for t in REGISTRY[stage].needs if getattr(case, t) is None]
        if missing:
            raise CaseError("--stages", stage.value, f"the case has no [{missing[0]}] table, which this stage needs")
    return wanted


def _check_upstream(case: Case, wanted: list[Stage], status: Status, run_dir: Path) -> None:
    for stage in wanted:
        for up in REGISTRY[stage].upstream(case):
            if up not in wanted and status.state(up) != "done":
                raise FlexnetError(f"stage '{stage.value}' needs the results of stage '{up.value}', which is "
                                   f"{status.state(up)} in {run_dir}: run with --stages {up.value},{stage.value}")


def _stage_logger(folder: Path, stage: Stage) -> tuple[logging.Logger, logging.Handler]:
    log = logging.getLogger(f"flexnet.{stage.value}")
    with signals_deferred():  # not a half-made handler (runs.signals_deferred)
        handler = logging.FileHandler(folder / STAGE_LOG, mode="w")
    handler.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(message)s"))
    log.addHandler(handler)
    return log, handler


def _mpi_world():
    """MPI.COMM_WORLD when launched by mpirun with more than one rank, else None (no import)."""
    if not launched_by_mpirun():
        return None
    from mpi4py import MPI

    return MPI.COMM_WORLD if MPI.COMM_WORLD.size > 1 else None


def _petsc_on_self():
    """Under mpirun but running a case alone (a sweep worker): initialise PETSc on COMM_SELF
    before dolfinx is imported (its default, COMM_WORLD, is collective over all the workers).
    Returns MPI.COMM_SELF then, else None."""
    if not launched_by_mpirun():
        return None
    from mpi4py import MPI

    if "petsc4py.PETSc" not in sys.modules:
        import petsc4py

        petsc4py.init(comm=MPI.COMM_SELF)
    return MPI.COMM_SELF


def is_root() -> bool:
    """True on rank 0 of an MPI run, and in a serial run."""
    comm = _mpi_world()
    return comm is None or comm.rank == 0


def run_case(case: Case, case_dir: Path, run_dir: Path, stages: list[Stage] | None = None,
             stage_funcs: dict[Stage, Callable[[StageContext], dict]] | None = None,
             force: bool = False, mpi: bool = True) -> dict:
    """Run ``stages`` (default: the case's own list, skipping stages that are done and up to
    date unless ``force``) in pipeline order into ``run_dir``. Returns the summary dict (empty on
    ranks > 0 of an MPI run). ``mpi=False``: run serially even under mpirun (sweep workers).

    Raises :class:`StageInterrupted` on SIGINT/SIGTERM, :class:`RunIOError` on a disk error,
    :class:`RunDirError` when another run holds the folder, else the stage's own error — each
    after recording it in status.json.
    """
    funcs = stage_funcs or {s: spec.run for s, spec in REGISTRY.items()}
    wanted = plan_stages(case, stages)
    comm = _mpi_world() if mpi else None
    self_comm = None if mpi else _petsc_on_self()
    # Heavy imports first, on every rank: gmsh resets SIGINT when imported, and PETSc's
    # initialisation (imported with dolfinx) is collective, so all ranks must do it together.
    versions = _versions()
    if comm is not None and comm.rank != 0:
        return _follow(comm, case, case_dir, Path(run_dir), funcs)
    run_dir = Path(run_dir)
    try:
        check_run_dir(run_dir)
        try:
            run_dir.mkdir(parents=True, exist_ok=True)
            lock = RunLock(run_dir).acquire()
        except OSError as err:
            raise RunIOError(err, "creating the run directory") from None
        try:
            if lock.note:
                LOG.warning("%s: %s", run_dir, lock.note)
            with signal_handlers():
                summary = _run_locked(case, case_dir, run_dir, wanted, funcs, versions, comm or self_comm,
                                      skip_done=stages is None and not force)
        finally:
            lock.release()
    finally:
        if comm is not None:
            _send(comm, _END)
    return summary


@dataclass(frozen=True)
class _Run:
    """One locked run on rank 0: the case, its folders, status.json, the summary being written
    (``summary`` is updated in place), the stages' input hashes and the communicator (or None)."""

    case: Case
    case_dir: Path
    run_dir: Path
    status: Status
    summary: dict
    hashes: dict
    comm: object | None


def _run_locked(case, case_dir, run_dir, wanted, funcs, versions, comm, skip_done: bool) -> dict:
    hashes = stage_hashes(case)
    atomic_write_json(run_dir / RESOLVED, {
        "case": resolved_dict(case), "case_dir": str(case_dir), "case_hash": case_hash(case),
        "stage_hashes": {s.value: h for s, h in hashes.items()}, "versions": versions, "written": now()})
    status = Status(run_dir / STATUS, case, hashes)
    summary_path = run_dir / SUMMARY
    summary = read_json(summary_path) if summary_path.is_file() else {}
    summary = {k: v for k, v in summary.items() if status.data["stages"].get(k, {}).get("state") == "done"}
    _check_upstream(case, wanted, status, run_dir)
    run = _Run(case, case_dir, run_dir, status, summary, hashes, comm)
    for stage in wanted:
        if skip_done and status.state(stage) == "done":
            LOG.info("stage %s: up to date (done %s), skipped; --force re-runs it", stage.value,
                     status.record(stage).get("finished", "earlier"))
            continue
        _run_stage(run, stage, funcs[stage])
    return run.summary


def _run_stage(run: _Run, stage: Stage, func: Callable[[StageContext], dict]) -> dict:
    status, summary, comm = run.status, run.summary, run.comm
    distributed = comm is not None and comm.size > 1 and REGISTRY[stage].distributed
    part = partial_dir(run.run_dir, stage.value)
    if part.exists():
        shutil.rmtree(part)
    part.mkdir()
    summary.pop(stage.value, None)
    started, t0, log, handler = now(), time.perf_counter(), None, None
    try:  # from here on, any end (signal included) is recorded
        status.set(stage, state="running", started=started, input_hash=run.hashes[stage], **me())
        _prune_summary(run)
        log, handler = _stage_logger(part, stage)
        LOG.info("stage %s: running → %s", stage.value, stage_dir(run.run_dir, stage.value))
        if distributed:
            _send(comm, STAGE_ORDER.index(stage))
        section = func(StageContext(run.case, run.case_dir, run.run_dir, part, log, comm))
        with signals_deferred():
            log.removeHandler(handler)
            handler.close()
            handler = None
        publish_stage(run.run_dir, stage.value)
        summary[stage.value] = section
        atomic_write_json(run.run_dir / SUMMARY, summary)
        wall = time.perf_counter() - t0
        status.set(stage, state="done", started=started, finished=now(), input_hash=run.hashes[stage], wall_s=wall,
                   **me())
    except BaseException as err:
        if isinstance(err, KeyboardInterrupt):
            interrupt_handled()
        summary.pop(stage.value, None)
        if handler is not None:
            log.removeHandler(handler)
            handler.close()
        _record_end(run, stage, err, started, time.perf_counter() - t0)
        _prune_summary(run)
        if distributed:
            comm.Abort(getattr(err, "exit_code", 1))  # the other ranks may sit in a collective
        shown = _translate(run, stage, err)
        if shown is err:
            raise
        raise shown from None
    LOG.info("stage %s: done in %.1f s", stage.value, wall)
    return section


def _prune_summary(run: _Run) -> None:
    """summary.json keeps the sections of done stages only (a stale section is removed)."""
    summary = run.summary
    for name in [k for k in summary if run.status.data["stages"].get(k, {}).get("state") != "done"]:
        del summary[name]
    atomic_write_json(run.run_dir / SUMMARY, summary)


def _record_end(run: _Run, stage: Stage, err: BaseException, started: str, wall: float) -> None:
    """Record a stage that ended with ``err`` in status.json and put its partial files in place."""
    run_dir, status = run.run_dir, run.status
    base = {"started": started, "finished": now(), "input_hash": run.hashes[stage], "wall_s": wall, **me()}
    if isinstance(err, OSError) and err.errno in IO_ERRNOS:
        # Free what the stage wrote (a full disk must have room for status.json).
        shutil.rmtree(partial_dir(run_dir, stage.value), ignore_errors=True)
        status.set(stage, state="failed", error=str(RunIOError(err, where=str(stage_dir(run_dir, stage.value)))),
                   **base)
        return
    publish_stage(run_dir, stage.value)
    if isinstance(err, KeyboardInterrupt):
        signum = getattr(err, "signum", signal.SIGINT)
        status.set(stage, state="interrupted", interrupted_at=now(), signal=signal.Signals(signum).name,
                   outputs_up_to_s=last_output_time(stage_dir(run_dir, stage.value)), **base)
        return
    status.set(stage, state="failed", error=str(err) or type(err).__name__, **base)


def _translate(run: _Run, stage: Stage, err: BaseException) -> BaseException:
    """The exception the caller sees for a stage that ended with ``err``."""
    run_dir, status = run.run_dir, run.status
    if isinstance(err, OSError) and err.errno in IO_ERRNOS:
        return RunIOError(err, f"running stage {stage.value}", str(stage_dir(run_dir, stage.value)))
    if isinstance(err, KeyboardInterrupt):
        return StageInterrupted(stage.value, getattr(err, "signum", signal.SIGINT),
                                status.record(stage).get("outputs_up_to_s"), str(run_dir))
    return err


_END = -1
"""Command from rank 0: the run is over (else the index of a distributed stage to run)."""


def _send(comm, command: int) -> None:
    import numpy as np

    comm.Ibcast(np.array([command], dtype=np.int64), root=0).Wait()


def _receive(comm) -> int:
    """Wait for rank 0's next command without busy-polling a core (a blocking MPI broadcast
    spins at 100 % CPU while rank 0 runs deploy and collide alone)."""
    import numpy as np

    buf = np.empty(1, dtype=np.int64)
    req = comm.Ibcast(buf, root=0)
    while not req.Test():
        time.sleep(0.02)
    return int(buf[0])


def _follow(comm, case, case_dir, run_dir: Path, funcs) -> dict:
    """Ranks > 0: wait for rank 0 to start a distributed stage, run it in the folder rank 0
    created, repeat until the end. They never create, lock, rename or delete anything in the
    run directory."""
    while True:
        command = _receive(comm)
        if command == _END:
            return {}
        stage = STAGE_ORDER[command]
        log = logging.getLogger(f"flexnet.{stage.value}")
        try:
            funcs[stage](StageContext(case, case_dir, run_dir, partial_dir(run_dir, stage.value), log, comm))
        except BaseException as err:  # one line, then end every rank (they may sit in a collective)
            print(f"flexnet: error: rank {comm.rank}, stage {stage.value}: {err or type(err).__name__}",
                  file=sys.stderr)
            comm.Abort(getattr(err, "exit_code", 1))


def stale_running(run_dir: Path) -> list[str]:
    """Stages that status.json says are ``running`` although their process is gone."""
    path = Path(run_dir) / STATUS
    if not path.is_file():
        return []
    stages = read_json(path).get("stages", {})
    return [name for name, rec in stages.items()
            if rec.get("state") == "running" and process_alive(rec.get("pid"), rec.get("host")) is False]
