"""The collide stage's resolution check (``[collide] resolution_check``) as a job: the impact again
with the rope pieces at the fins halved, run in a second process beside the stage's own impact when
the machine allows it (``check_beside``), else after it in this process; its summary's moves
(``collide.resolution``) go into the stage's summary. ``start_check`` before the run's impact,
``finish_check`` after it, ``_Check.stop`` always (it ends or terminates the process)."""

from __future__ import annotations

import logging
import os
from dataclasses import dataclass

from flexnet_fe.atmosphere import Air
from flexnet_fe.collide.config import CollideConfig
from flexnet_fe.collide.resolution import resolution_moves
from flexnet_fe.collide.simulate import simulate
from flexnet_fe.errors import FlexnetError, NumericalError
from flexnet_fe.machine import cpu_count, launched_by_mpirun
from flexnet_fe.missile.geometry import Missile


def check_config(cfg: CollideConfig) -> CollideConfig:
    """The resolution check's impact (``[collide] resolution_check``): the rope pieces at the fins
    halved (``fin_piece_length`` and, when set, ``fin_piece_chord``; ``collide.resolution``), its
    fin loads sampled at the output interval (its headlines — Δv, the CFC peak, the fin impulses —
    do not depend on how finely the fin loads are sampled)."""
    return cfg.model_copy(update={"fin_piece_length": 0.5 * cfg.fin_piece_length,
                                  "fin_piece_chord": None if cfg.fin_piece_chord is None else 0.5 * cfg.fin_piece_chord,
                                  "resolution_check": False, "load_interval": None})


def check_beside() -> bool:
    """Run the resolution check's impact in a second process beside the run's own: when this
    process may use two cores or more, is not a rank of an mpirun job (whose cores the launcher
    has shared out; a plain run that initialised MPI for itself, as importing dolfinx does, may
    start a process), is not a daemonic process (a ``flexnet sweep -j N`` worker: it may not
    start processes, and the sweep has shared the cores out already) and its main module is safe to
    import again (``_main_reimport_safe``). Otherwise it runs after the run's impact, in this
    process. Both ways give the same summary (the impacts are deterministic and share nothing;
    tests/collide/test_resolution.py)."""
    import multiprocessing

    return (cpu_count() >= 2 and not launched_by_mpirun() and not multiprocessing.current_process().daemon
            and _main_reimport_safe())


def _main_reimport_safe() -> bool:
    """A spawned process imports the parent's ``__main__`` again: a module run with ``-m`` (pytest,
    ``python -m flexnet_fe.cli``) by name, a script by path, running its top level. The ``flexnet``
    entry point guards its call; a user's script may not (``cli.main([...])`` at its top level would
    run the case again in the child). So: a main module with a name, or the ``flexnet`` script."""
    import sys
    from pathlib import Path

    main = sys.modules.get("__main__")
    if main is None or getattr(main, "__spec__", None) is not None:
        return True
    path = getattr(main, "__file__", None)
    return path is None or Path(path).name == "flexnet"


class _LogLines(logging.Handler):
    """Keeps the formatted records (the check's log, sent back to the stage's)."""

    def __init__(self, lines: list[str]):
        super().__init__(logging.INFO)
        self.lines = lines

    def emit(self, record: logging.LogRecord) -> None:
        self.lines.append(record.getMessage())


PARENT_POLL_S = 0.5
"""How often the check's process looks whether the stage's process is still there [s]."""


def _exit_with(parent: int) -> None:
    """End this process once ``parent`` (the stage's process) is gone: a parent killed outright
    (SIGKILL, or a signal it could not handle) runs no clean-up, and the check would run on for
    minutes, holding a core and the parent's stderr (a caller reading it to its end would wait)."""
    import time

    while os.getppid() == parent:
        time.sleep(PARENT_POLL_S)
    os._exit(1)


def _check_process(conn, parent: int, net, missile: Missile, cfg: CollideConfig, gravity: float,
                   density: float, fin_motion) -> None:
    """The check's impact in a spawned process of ``parent``: sends ("ok", summary, None, log
    lines), ("error", numerical?, message, lines) for a FlexnetError, or ("crash", traceback, None,
    lines); ends itself when ``parent`` is gone (``_exit_with``)."""
    import signal
    import threading
    import traceback

    from tqdm import tqdm

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C: the stage stops this process itself
    threading.Thread(target=_exit_with, args=(parent,), daemon=True, name="exit-with-parent").start()
    os.environ["FLEXNET_NO_PROGRESS"] = "1"  # one progress bar: the run's
    tqdm.set_lock(threading.RLock())  # (tqdm's default lock is a process semaphore, left behind
    #                                    by a terminated process: a warning at the run's exit)
    lines: list[str] = []
    log = logging.getLogger("flexnet.collide.check")
    log.propagate = False
    log.setLevel(logging.INFO)
    log.addHandler(_LogLines(lines))
    try:
        summary = simulate(net, missile, cfg, gravity, log, air_density=density, n_snapshots=2,
                           fin_motion=fin_motion).summary
        conn.send(("ok", summary, None, lines))
    except FlexnetError as err:
        conn.send(("error", isinstance(err, NumericalError), str(err), lines))
    except BaseException:  # a bug: its traceback goes to the stage, which raises it
        conn.send(("crash", traceback.format_exc(), None, lines))
    finally:
        conn.close()


STOP_WAIT_S = 30.0
"""How long the stage waits for the check's process to exit by itself once its result is in [s]."""


@dataclass
class _Check:
    """The resolution check's impact: started beside the run's (``proc``, ``conn``) or deferred
    (``args``: run by ``_finish_check`` in this process)."""

    args: tuple
    piece: float
    chord: float | None
    proc: object = None
    conn: object = None
    done: bool = False

    def stop(self) -> None:
        """End the check's process: after its result it ends by itself (waited for), when the stage
        fails or is interrupted it is terminated."""
        if self.proc is not None:
            if self.done:
                self.proc.join(timeout=STOP_WAIT_S)
            if self.proc.is_alive():
                self.proc.terminate()
            self.proc.join()
            self.conn.close()
            self.proc = None


def start_check(net, missile: Missile, cfg: CollideConfig, air: Air, log: logging.Logger, fin_motion=None) -> _Check:
    """Start the check's impact beside the run's (``check_beside``), or prepare it to run after; the
    fins moving as ``fin_motion`` (``collide.model.FinMotion``) in it too, if given."""
    fine = check_config(cfg)
    args = (net, missile, fine, air.gravity, air.density, fin_motion)
    check = _Check(args, fine.fin_piece_length, fine.fin_piece_chord)
    beside = check_beside()
    where = "beside the impact (a second process)" if beside else "after the impact"
    log.info("collide: resolution check: the impact again with rope pieces of %.3g mm at the fins%s, %s",
             1e3 * check.piece, "" if check.chord is None else f", cut to chords of {1e3 * check.chord:.3g} mm "
             "where they press", where)
    if beside:
        import multiprocessing

        ctx = multiprocessing.get_context("spawn")
        check.conn, send = ctx.Pipe(duplex=False)
        check.proc = ctx.Process(target=_check_process, args=(send, os.getpid(), *args), daemon=True,
                                 name="flexnet-resolution-check")
        check.proc.start()
        send.close()
    return check


def finish_check(summary: dict, check: _Check, cfg: CollideConfig, log: logging.Logger) -> None:
    """Wait for (or run) the check's impact; add ``summary['resolution_check']`` and its warnings."""
    if check.proc is None:
        net, missile, fine_cfg, gravity, density, motion = check.args
        fine = simulate(net, missile, fine_cfg, gravity, log, air_density=density, n_snapshots=2,
                        fin_motion=motion).summary
    else:
        try:
            kind, a, b, lines = check.conn.recv()
            check.done = True
        except EOFError:
            check.proc.join()
            raise NumericalError(f"collide: the resolution check's process ended without a result (exit code "
                                 f"{check.proc.exitcode}; out of memory?); collide.resolution_check = false skips "
                                 "the check") from None
        for line in lines:
            log.info("collide (resolution check): %s", line.removeprefix("collide: "))
        if kind == "error":
            raise (NumericalError if a else FlexnetError)(f"collide: in the resolution check's impact (rope pieces "
                                                          f"halved at the fins): {b.removeprefix('collide: ')}")
        if kind == "crash":
            raise RuntimeError(f"the resolution check's process failed:\n{a}")
        fine = a
    section, warnings = resolution_moves(summary, fine, check.piece, cfg.resolution_tolerance, check.chord)
    section["fin_piece_chord_m"] = check.chord
    section["wall_s"] = fine["wall_s"]
    summary["resolution_check"] = section
    summary["warnings"].extend(warnings)
    log.info("collide: resolution check (%.3g mm): Δv/v %+.2f %%, CFC peak %+.2f %%, impulse %+.2f %%; flagged: %s",
             1e3 * check.piece, 100 * section["dv_over_v_move_rel"], 100 * section["peak_accel_move_rel"],
             100 * section["impulse_move_rel"], ", ".join(section["flagged"]) or "none")
