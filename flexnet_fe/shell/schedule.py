"""When each fin is simulated, and on how many threads the fins run.

Time window. A fin at rest under zero load stays exactly at rest (u = v = 0 solves the
undamped or damped equations of motion with f = 0), so a fin needs simulating only from just
before its first contact load to its last contact load plus ``shell.end_margin``. The contact
loads are linear between samples (:mod:`flexnet_fe.shell.kernel`), so the load of a fin whose
first event is at sample j is zero up to t_{j−1}: the window starts one history interval before
that, on the history grid of a run from t = 0 (same step numbers and times, hence the same
numbers: ``tests/shell/test_schedule.py``). It ends at the sample after the fin's last event
(where its interpolated load returns to zero) plus ``end_margin``.

Departure: the body (frame) acceleration of ``collide/history.csv`` loads every fin with
−m a(t) during the whole collision, including outside the fin's contact window. The window
leaves it out there. Its size is reported per fin, before and after the window
(``window_accel_before_mps2`` / ``_after_``: the largest |a| at the acceleration samples
outside the window; ``window_force_ratio_before`` / ``_after``: fin mass × that over the fin's
largest contact force), and so is what it can do: by superposition the peak moves by at most the
left-out load's own peak stress, which the stage solves on the fin's unrefined mesh
(``shell.stage.omitted_stress``, ×2 for that mesh; ``window_before_stress_bound_pa`` /
``window_after_stress_bound_pa``): a warning when either exceeds ``shell.peak_error_tolerance`` of
the peak. Before the window it changes the state the window starts from; after it, it loads the
fin on to the stage's end. (The former criteria were force ratios: above that tolerance before
the window, which fired on every fin of infrared × traction at ratios of 12–77 % while the bound
is 0.3–0.8 % of the peaks and the full window moved wing_1 by 0.08 %; above 0.5 after it.) On
radar × traction the windowed peaks equal the full-window ones to 7e-5 (largest ratios 0.95 %
before, 6.8 % after; docs/performance.md). ``shell.window = "full"`` simulates every fin from
t = 0 to the stage's end as before. The window's end also cuts off the fin's undamped free
vibration after its last load: the summary gives its largest stress within ``end_margin`` over
the peak (``after_last_load_over_peak``), a warning above FREE_VIBRATION_LIMIT.

Threads. After their operators are assembled (dolfinx, serial), the fins are independent: their
compiled time loops (:func:`flexnet_fe.shell.kernel.advance`, ``nogil``) run in a thread pool of
``shell.workers`` threads, each as soon as its fin is set up, while this thread sets up the next
(``run_as_ready``: the set-ups, ~45 % of radar × traction's stage, no longer wait for one
another and the loops for all of them). dolfinx 0.5.2's bindings never release the GIL (no
``gil_scoped_release`` in python/dolfinx/wrappers at v0.5.2), so its calls from the set-up and
from the fins' XDMF frames cannot run at once; only the compiled loops run beside them. Each fin's
numbers do not depend on the thread count (no shared state; each kernel call is the serial
code), so the results are those of one worker.
"""

from __future__ import annotations

import math
import threading
from concurrent.futures import ThreadPoolExecutor
from typing import Callable, Iterable, NamedTuple, TypeVar

import numpy as np


class FinWindow(NamedTuple):
    """The simulated interval of one fin [s] and what it leaves out."""

    load_start_s: float
    """the last instant at which the fin's contact load is still zero [s]"""
    end_s: float
    """the end of the simulation [s]"""
    accel_before_mps2: float = 0.0
    """largest |body acceleration| at samples before load_start_s (left out) [m/s²]"""
    accel_after_mps2: float = 0.0
    """largest |body acceleration| at samples after end_s (left out) [m/s²]"""
    last_load_s: float = math.nan
    """the first instant at which the fin's contact load is zero again for good [s] (nan: no load)"""
    stage_end_s: float = math.nan
    """the end of the stage (of every fin's simulation) [s] (nan: end_s)"""


def fin_window(times: np.ndarray, samples: np.ndarray, end_time: float, end_margin: float,
               accel_t: np.ndarray, accel: np.ndarray, *, fixed_end: bool) -> FinWindow:
    """Window of a fin whose contact events are at the sample indices ``samples`` (ne,) of the
    contact sample times ``times`` (nt,) [s]. ``end_time``: the stage's end [s] (the window never
    goes beyond it); ``fixed_end``: the user gave ``shell.end_time`` (kept as the fin's end).
    ``accel_t`` (na,) [s], ``accel`` (na, 3) [m/s²]: the body acceleration, to report what the
    window leaves out before and after. A fin without events: the whole interval [0, end_time]."""
    if not len(samples):
        return FinWindow(0.0, end_time, stage_end_s=end_time)
    j0, j1 = int(samples.min()), int(samples.max())
    start = float(times[j0 - 1]) if j0 > 0 else float(times[0])
    last = float(times[min(j1 + 1, len(times) - 1)])
    end = end_time if fixed_end else min(end_time, last + end_margin)
    mag = np.linalg.norm(np.asarray(accel, float).reshape(-1, 3), axis=1)
    return FinWindow(start, end, float(mag[accel_t < start].max(initial=0.0)),
                     float(mag[accel_t > end].max(initial=0.0)), last, end_time)


def window_steps(window: FinWindow, dt: float, every: int) -> tuple[int, int]:
    """(start step, number of steps) of a window on the grid of a run from t = 0 with step
    ``dt`` [s] and history rows every ``every`` steps: the start is a row at least one row
    interval before ``load_start_s`` (so the load is zero there and at the first step), the end
    the first row at or after ``end_s``."""
    row = dt * every
    start = every * max(0, math.floor(window.load_start_s / row) - 1)
    end = every * max(1, math.ceil(window.end_s / row))
    return start, max(end - start, every)


J = TypeVar("J")
R = TypeVar("R")


def run_as_ready(jobs: Iterable[J], fn: Callable[[J], R], workers: int) -> list[R]:
    """[fn(job) for job in jobs], each job handed to a thread as soon as the iterable yields it, so
    making the next job (in this thread) overlaps the threads' work on the earlier ones. ``workers``
    jobs run at once, ``workers`` − 1 while jobs are still being made (the making takes a core;
    1 worker: make, run, make, run… in this thread). The results come back in the order of
    ``jobs``; the first exception — of making a job, then of the jobs in order — is raised after
    every job handed out has ended (the others keep their outputs)."""
    if workers <= 1:
        return [fn(j) for j in jobs]
    slots = threading.Semaphore(workers)
    slots.acquire()  # the making's core, given back when every job is made

    def run(job: J) -> R:
        with slots:
            return fn(job)

    made_err = None
    with ThreadPoolExecutor(max_workers=workers, thread_name_prefix="shell-fin") as pool:
        futures = []
        try:
            for j in jobs:
                futures.append(pool.submit(run, j))
        except BaseException as err:  # (Ctrl-C too: the threads' loops end, then it is raised)
            made_err = err
        finally:
            slots.release()
        errors = [f.exception() for f in futures]
    for err in [made_err, *errors]:
        if err is not None:
            raise err
    return [f.result() for f in futures]


FREE_VIBRATION_LIMIT = 0.75
"""warn when a fin's free vibration after its last contact load (undamped: it does not decay) reaches
more than this fraction of its peak within ``shell.end_margin``. The margin (2 ms) is a tenth of the
paper fins' fundamental period (23–26 ms), so the vibration's later maxima are not seen: run on over
a whole period after the last load, the four fins measured grew ×1.08–1.22 over their margins'
largest stress (radar × traction's wing_1 and rudder_1: 42 → 51 and 32 → 36 % of their peaks;
radar × rotary's rudders 1 and 4: 59 → 64 and 62 → 74 %) and no peak moved. Below this limit a later,
larger peak needs ×1.33 (docs/validation.md, "After the window")."""

IO_LOCK = threading.Lock()
"""Held around every dolfinx/XDMF call and progress update made from a fin's thread (dolfinx
and HDF5 are not made to be called from several threads at once)."""
