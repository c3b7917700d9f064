"""Run directories: the contract between stages, reports, sweeps and tests (DESIGN.md §3).

Every file name the run machinery writes or reads is named here once::

    <run>/resolved.json         the validated case actually used, versions, case hash
    <run>/status.json           per stage: state, input hash, times, PID and host (atomic writes)
    <run>/summary.json          headline numbers, one section per *done* stage
    <run>/run.lock              the writer's lock (PID, host, start time; flock-held)
    <run>/<stage>/              a finished (or interrupted/failed) stage's files
    <run>/.<stage>.partial/     where a running stage writes; renamed to <stage>/ when it ends
    <run>/<stage>/history.csv   one row per output time (every stage)
    <run>/deploy/net_state.npz  the net at maximum area (read by collide); net.pvd snapshots
    <run>/collide/fin_contacts.npz  contact forces on the fins (read by shell); net.pvd and
                                missile.pvd snapshots (read by the report)
    <run>/shell/<fin>/fields.xdmf, envelope.xdmf  stress frames; peak envelope (read by flight
                                damage and the report)
    <run>/shell/meshes/<fin>.msh, body.msh  the Gmsh meshes of the case's missile (read by the
                                report)
    <run>/report.html           the report

Stages and readers import these names (``HISTORY``, ``NET_STATE``, ``FIN_CONTACTS``,
``ENVELOPE_XDMF`` ...) instead of writing the literals.

A stage is a function ``run(ctx: StageContext) -> dict`` that writes its files into
``ctx.stage_dir`` and returns its section of ``summary.json`` (SI units, JSON-able values).

States of a stage in ``status.json``: ``pending`` (never run), ``running`` (with ``pid`` and
``host``; a ``running`` whose process is gone is *stale*), ``done``, ``failed`` (+ ``error``),
``interrupted`` (+ ``outputs_up_to_s``), ``stale`` (its results were computed from inputs that
have changed since, or its upstream stage is not ``done``: re-run, never reported as done).
"""

from __future__ import annotations

import errno
import fcntl
import json
import logging
import os
import shutil
import signal
import socket
import sys
import threading
import time
from contextlib import contextmanager
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

RESOLVED = "resolved.json"
STATUS = "status.json"
SUMMARY = "summary.json"
LOCK = "run.lock"
HISTORY = "history.csv"
STAGE_LOG = "log.txt"
REPORT = "report.html"
NET_STATE = "net_state.npz"
"""deploy/: the net at maximum area, read by collide (``net.deploy.write_net_state``)."""
NET_PVD = "net.pvd"
MISSILE_PVD = "missile.pvd"
"""collide/: the missile body at each snapshot (beside net.pvd), read by the report's pictures."""
FIN_CONTACTS = "fin_contacts.npz"
"""collide/: contact forces on the fins, read by shell (fields in DESIGN.md §3)."""
FIELDS_XDMF = "fields.xdmf"
"""shell/<fin>/: recovered stress frames."""
ENVELOPE_XDMF = "envelope.xdmf"
"""shell/<fin>/: peak-over-time stresses, read by flight damage and the report."""
SHELL_MESHES = "meshes"
"""shell/: the Gmsh meshes the stage solved on (``missile.mesh.write_meshes``: ``<fin>.msh``, body.msh)."""
BODY_MSH = "body.msh"
"""shell/meshes/: the missile body's surface mesh, read by the report's ParaView file."""
SWEEP_TABLE = "sweep.csv"
"""a sweep folder's table (``flexnet sweep``), and flight/: the flight stage's own ``[flight].sweep`` table."""
BATCH_TABLE = "batch.csv"
MAP_TABLE = "map.csv"
"""the engagement map's table (``flexnet_fe.engagement_map``; its picture has the same stem, .png)."""
ENSEMBLE_TABLE = "ensemble.csv"
"""an ensemble folder's member table (``flexnet_fe.ensemble``; its picture has the same stem, .png)."""
ENSEMBLE_STATS = "ensemble.json"
"""an ensemble folder's statistics (``flexnet_fe.ensemble.summarise``)."""

STATES = ("pending", "running", "done", "failed", "interrupted", "stale")

MAX_NAME = 100
"""Longest case, run or sweep-variant name [characters] (a path component must stay < 255 bytes
with the suffixes added to it)."""


@dataclass(frozen=True)
class StageContext:
    """What a stage gets.

    case      the validated case (``flexnet_fe.config.Case``)
    case_dir  folder of the case file; files named in the case resolve against it
    run_dir   the run directory (``runs/<name>/``); earlier stages' outputs are in its sub-folders
    stage_dir where this stage writes (a temporary folder, renamed to ``run_dir/<stage>`` when the
              stage ends), created empty for it
    log       a named logger that writes to ``stage_dir / "log.txt"`` (and the console)
    """

    case: Any
    case_dir: Path
    run_dir: Path
    stage_dir: Path
    log: logging.Logger
    comm: Any = None
    """MPI communicator of a distributed stage; None = ``MPI.COMM_WORLD`` (COMM_SELF is passed
    when one rank of an MPI job runs a whole case alone, e.g. an mpi4py.futures sweep worker)."""

    def stage_output(self, stage: str) -> Path:
        """Folder of an earlier stage's outputs (it must have completed)."""
        return stage_dir(self.run_dir, stage)


def now() -> str:
    """UTC time stamp, ISO 8601, seconds."""
    return datetime.now(timezone.utc).isoformat(timespec="seconds")


def stage_dir(run_dir: Path, stage: str) -> Path:
    return Path(run_dir) / stage


def partial_dir(run_dir: Path, stage: str) -> Path:
    return Path(run_dir) / f".{stage}.partial"


def old_dir(run_dir: Path, stage: str) -> Path:
    return Path(run_dir) / f".{stage}.old"


def is_run_dir(path: Path) -> bool:
    """A folder written by ``flexnet run`` (has status.json or resolved.json)."""
    path = Path(path)
    return (path / STATUS).is_file() or (path / RESOLVED).is_file()


def process_alive(pid: int | None, host: str | None) -> bool | None:
    """True/False for a process on this host; None when it cannot be told (another host)."""
    if not pid or host != socket.gethostname():
        return None
    try:
        os.kill(int(pid), 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def me() -> dict[str, Any]:
    """This process: ``{"pid", "host"}``."""
    return {"pid": os.getpid(), "host": socket.gethostname()}


def publish_stage(run_dir: Path, stage: str) -> Path:
    """Move ``.<stage>.partial/`` into place as ``<stage>/`` (the old one, if any, is removed).

    Two renames: a reader sees the old complete folder or the new one, never a half-written one
    (between the renames ``<stage>/`` is briefly absent)."""
    src, dst, old = partial_dir(run_dir, stage), stage_dir(run_dir, stage), old_dir(run_dir, stage)
    if not src.exists():  # already published (an interrupt arrived just after the rename)
        return dst
    if old.exists():
        shutil.rmtree(old)
    if dst.exists():
        os.rename(dst, old)
    os.rename(src, dst)
    shutil.rmtree(old, ignore_errors=True)
    return dst


def last_output_time(folder: Path) -> float | None:
    """Largest ``t_s`` on the last row of ``history.csv`` in ``folder`` or its sub-folders [s]
    (None when no history was written)."""
    best = None
    for path in [Path(folder) / HISTORY, *Path(folder).glob(f"*/{HISTORY}")]:
        try:
            lines = path.read_text().splitlines()
            names = lines[0].split(",")
            t = float(lines[-1].split(",")[names.index("t_s")]) if len(lines) > 1 else None
        except (OSError, ValueError, IndexError):
            continue
        if t is not None and (best is None or t > best):
            best = t
    return best


class _SignalState:
    """The interrupt in progress: ``pending`` signal number, ``handled`` once the code that
    caught :class:`Interrupted` has started its clean-up, ``depth`` of nested handler blocks."""

    pending: int | None = None
    handled: bool = False
    redeliver: threading.Thread | None = None
    depth: int = 0
    deferring: int = 0
    deferred: int | None = None


_SIG = _SignalState()

REDELIVER_S = 0.25
"""If an Interrupted raised by the handler is swallowed (Python ignores exceptions raised inside
``__del__`` and weakref callbacks, where a signal can land — seen in an import's module-lock
callback), the signal is delivered again after this many seconds [s], until some code reports it
handled — acted on only while no Interrupted is on its way out (``_propagating``): one passing
through a slow clean-up is not cut short by a second (CI, 2026-11-27: the collide stage's check
process being joined; a later one landing in the stage's handler before it could record the
interrupt left the stage 'running' and ended the process by the bare signal). Short, so that the
stage the user interrupted is still the one running (at 2 s a 1.3 s deploy finished first and the
interrupt came only after it: CI, 2026-11-27)."""


def _on_signal(signum, frame):
    from flexnet_fe.errors import Interrupted

    if _SIG.handled:
        return  # the clean-up is running (a few renames and writes): let it finish
    if _SIG.deferring:
        _SIG.deferred = signum  # raised when the signals_deferred block ends
        return
    if _propagating():
        return  # the last Interrupted is still on its way out (through slow clean-ups: a process
        #         joined): a second one would cut them short, or land in the handler itself
    _SIG.pending = signum
    if _SIG.redeliver is None:
        _SIG.redeliver = threading.Thread(target=_redeliver, daemon=True)
        _SIG.redeliver.start()
    raise Interrupted(signum)


def _propagating() -> bool:
    """True when an :class:`Interrupted` is on its way out through the code the signal interrupted:
    it is the exception being handled there (an ``except``, ``finally`` or ``__exit__`` it passes
    through) or the context of one. Asked of the exception state, not of the Interrupted object's
    life: one swallowed and then kept alive (by an extension, a reference cycle) would otherwise
    block every re-delivery, and the stage would run to its end and the process end with the bare
    signal — CI's ``test_sigterm_in_collide``, exit −15, 2026-11-28. (Signals traced at the
    collide stage's start land in imports, one in scipy's Cython module initialisation, which
    swallowed it; what kept CI's alive was not observed.)"""
    from flexnet_fe.errors import Interrupted

    err, seen = sys.exc_info()[1], set()
    while err is not None and id(err) not in seen:
        if isinstance(err, Interrupted):
            return True
        seen.add(id(err))
        err = err.__context__
    return False


def _quiet_unraisable(hook):
    """``sys.unraisablehook`` that drops an :class:`Interrupted` Python swallowed where the signal
    landed (a weakref callback or ``__del__``, REDELIVER_S) — it is delivered again, so its
    "Exception ignored … Traceback" on stderr would only alarm the user (CI, 2026-11-28: SIGINT in
    an import's module-lock callback during the deploy stage) — and passes anything else to
    ``hook``."""
    def quiet(unraisable):
        from flexnet_fe.errors import Interrupted

        if not isinstance(unraisable.exc_value, Interrupted):
            hook(unraisable)
    return quiet


def _redeliver() -> None:
    while True:
        time.sleep(REDELIVER_S)
        if _SIG.pending is None or _SIG.handled:
            return
        os.kill(os.getpid(), _SIG.pending)


def interrupt_handled() -> None:
    """Called by the code that caught :class:`Interrupted`: no re-delivery, and further
    SIGINT/SIGTERM are ignored until the outermost :func:`signal_handlers` block ends."""
    _SIG.handled = True


@contextmanager
def signals_deferred():
    """A signal arriving inside the block raises its :class:`Interrupted` when the block ends, not
    in the middle: for a few lines that must not be cut in half. A ``logging.FileHandler`` is
    registered for flushing at exit before its stream is set; interrupted between the two, it
    is flushed at exit and prints "Exception ignored in atexit callback … AttributeError" after the
    interrupt's one line (CI's test_signal_in_deploy[SIGINT], 2026-11-29). (Blocking the signal with
    ``pthread_sigmask`` would not do: the kernel hands a process-directed signal to any thread that
    does not block it — numba's, the re-delivery thread — and Python runs the handler in the main
    thread all the same.)"""
    _SIG.deferring += 1
    try:
        yield
    finally:
        _SIG.deferring -= 1
    if _SIG.deferring == 0 and _SIG.deferred is not None:
        signum, _SIG.deferred = _SIG.deferred, None
        _on_signal(signum, None)


@contextmanager
def signal_handlers():
    """SIGINT and SIGTERM raise :class:`Interrupted` inside the block (main thread only)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    for s in old:
        signal.signal(s, _on_signal)
    old_hook = sys.unraisablehook
    sys.unraisablehook = _quiet_unraisable(old_hook)
    _SIG.depth += 1
    try:
        yield
    finally:
        _SIG.depth -= 1
        sys.unraisablehook = old_hook
        for s, h in old.items():
            signal.signal(s, h if h is not None else signal.SIG_DFL)
        if _SIG.depth == 0:  # an Interrupted leaving the block is not lost: the caller's except handles it
            leaving = isinstance(sys.exc_info()[1], KeyboardInterrupt)
            lost = _SIG.pending if not (_SIG.handled or leaving) else None
            _SIG.pending, _SIG.handled, _SIG.redeliver = None, False, None
            if lost is not None:  # the Interrupted was swallowed and the block ended: not lost
                print(f"flexnet: signal {signal.Signals(lost).name} arrived where it could not be handled; "
                      "ending with it", file=sys.stderr, flush=True)
                os.kill(os.getpid(), lost)


class RunLock:
    """One writer per run directory: ``run.lock`` held with ``flock`` and holding the writer's
    PID, host and start time.

    The kernel releases an flock when its process dies, however it dies: a lock file that still
    names a writer but is not locked is *stale* (its writer was killed) and is taken over with a
    note. A lock held by a live process refuses the second run with one line.
    """

    def __init__(self, run_dir: Path):
        self.path = Path(run_dir) / LOCK
        self.fd: int | None = None
        self.note = ""

    def acquire(self) -> "RunLock":
        from flexnet_fe.errors import RunDirError

        fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as err:
            os.close(fd)
            if err.errno not in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                raise
            holder = _read_lock(self.path)
            raise RunDirError(f"{self.path.parent}: in use by another run (PID {holder.get('pid', '?')} on "
                              f"{holder.get('host', '?')} since {holder.get('started', '?')}); wait for it "
                              f"to finish or choose another --out") from None
        old = _read_fd(fd)
        if old:
            self.note = (f"took over the stale lock of PID {old.get('pid', '?')} on {old.get('host', '?')} "
                         f"(started {old.get('started', '?')}), which ended without releasing it")
        os.ftruncate(fd, 0)
        os.pwrite(fd, (json.dumps({**me(), "started": now()}) + "\n").encode(), 0)
        os.fsync(fd)
        self.fd = fd
        return self

    def release(self) -> None:
        """Empty the lock file (an empty lock file names no writer) and unlock it. The file is
        kept: unlinking a locked file lets a third process lock a fresh inode concurrently."""
        if self.fd is None:
            return
        try:
            os.ftruncate(self.fd, 0)
        except OSError:
            pass
        os.close(self.fd)
        self.fd = None

    def __enter__(self) -> "RunLock":
        return self.acquire()

    def __exit__(self, *exc) -> None:
        self.release()


def _read_fd(fd: int) -> dict:
    try:
        text = os.pread(fd, 4096, 0).decode(errors="replace").strip()
        return json.loads(text) if text else {}
    except (OSError, ValueError):
        return {"pid": "?", "host": "?", "started": "?"}


def _read_lock(path: Path) -> dict:
    try:
        text = Path(path).read_text().strip()
        return json.loads(text) if text else {}
    except (OSError, ValueError):
        return {}


def check_run_dir(path: Path) -> None:
    """Refuse an output folder that exists, is not empty and is not a run directory: the run would
    replace sub-folders named like stages (``deploy/`` ...) that belong to someone else."""
    from flexnet_fe.errors import RunDirError

    path = Path(path)
    if path.exists() and not path.is_dir():
        raise RunDirError(f"{path}: exists and is not a folder")
    # a run killed between taking its lock and writing its status leaves only run.lock: ours
    own = {p.name for p in path.iterdir()} <= {LOCK} if path.is_dir() else True
    if path.is_dir() and not own and not is_run_dir(path):
        raise RunDirError(f"{path}: folder is not empty and is not a run directory (no {STATUS}); "
                          f"choose an empty or new --out")


FIN_PEAK, FIN_STRIKE_ENVELOPE = "peak_von_mises_pa", "strike_envelope_von_mises_pa"
"""The shell summary's keys of a fin's peak von Mises and its strike envelope [Pa]."""


def governing_peak(fin_summary: dict) -> float | None:
    """The von Mises stress a fin is held to [Pa], from its shell-summary entry: its strike
    envelope where the shell stage computed one (``shell.strike_envelope``), else its peak; None
    without either."""
    v = fin_summary.get(FIN_STRIKE_ENVELOPE)
    return v if v is not None else fin_summary.get(FIN_PEAK)
