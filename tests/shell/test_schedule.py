"""Per-fin time windows and fins run on several threads (flexnet_fe/shell/schedule.py).

References: the full-window run (every fin from t = 0) and the one-thread run. A fin at rest
under zero load stays exactly at rest (u = v = 0, K·0 = 0, a = M⁻¹(0 − 0) = 0 in floating
point too), and the windowed run keeps the absolute step numbers and times of the full run, so
both compute the same floating-point operations from the window's start on: the comparisons are
bitwise. The threads run the same serial kernel on separate data: bitwise as well.
"""

from __future__ import annotations

import logging
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from flexnet_fe.io import read_history_csv
from flexnet_fe.shell import kernel as kn
from flexnet_fe.shell.config import FinSpec, ShellConfig
from flexnet_fe.shell.meshio import write_plate_msh
from flexnet_fe.shell.schedule import FinWindow, fin_window, run_as_ready, window_steps
from flexnet_fe.shell.stage import WINDOW_BOUND_FACTOR, run_shell

LOG = logging.getLogger("flexnet.test.schedule")
CFG = ShellConfig(end_margin=3e-4, history_interval=1e-5, field_interval=2.5e-4, bearing_rope_modulus=1e11)


def make_inputs(d: Path) -> list[FinSpec]:
    """A wing (x–y plane) loaded from 0.4 to 0.9 ms and a rudder (x–z plane) from 0.65 to
    1.0 ms, contact samples every 50 µs from 0 to 1 ms; no body acceleration."""
    write_plate_msh(d / "wing.msh", 10, 5, 0.3, 0.15, origin=(-1.2, 0.1, 0.0), a1=(1, 0, 0),
                    a2=(0, 1, 0))
    write_plate_msh(d / "rudder.msh", 6, 4, 0.2, 0.1, origin=(-2.0, 0.0, 0.1), a1=(1, 0, 0),
                    a2=(0, 0, 1))
    t = np.arange(21) * 5e-5
    j = np.arange(21)
    wing = ((j >= 8) & (j <= 18)).astype(int)  # 0.4–0.9 ms
    rudder = ((j >= 13) & (j <= 20)).astype(int)  # 0.65–1 ms
    per = wing + rudder
    k = np.repeat(np.arange(len(t)), per)
    fin = np.concatenate([[0] * w + [1] * r for w, r in zip(wing, rudder)]).astype(np.int32)
    pts = np.where((fin == 0)[:, None], [-1.05, 0.18, 0.0], [-1.9, 0.0, 0.15])
    amp = np.sin(np.pi * (t[k] - np.where(fin == 0, 4e-4, 6.5e-4)) / 6e-4) + 0.2
    force = np.where((fin == 0)[:, None], [0.0, 0.0, 1500.0], [0.0, 800.0, 0.0]) * amp[:, None]
    np.savez(d / "fin_contacts.npz", fin_names=np.array(["wing", "rudder"]), t=t,
             row_start=np.concatenate([[0], np.cumsum(per)]).astype(np.int64), fin=fin,
             point=pts, force=force, width=np.full(len(fin), 5e-3))
    return [FinSpec(name, d / f"{name}.msh", 4e-3, 71.7e9, 0.33, 2810.0, 503e6)
            for name in ("wing", "rudder")]


def _run(d: Path, out: str, **cfg) -> dict:
    return run_shell(CFG.model_copy(update=cfg), make_inputs(d), d / "fin_contacts.npz", None,
                     d / out, LOG)


def test_windowed_fin_gives_the_full_window_peak_bitwise(tmp_path):
    # the same end (shell.end_time) for both: what is compared is the start of the window (the
    # end is shell.end_margin after the fin's last load, a modelling choice checked below)
    full = _run(tmp_path, "full", window="full", workers=1, end_time=1.3e-3)
    win = _run(tmp_path, "win", window="fin", workers=1, end_time=1.3e-3)
    for name, first in (("wing", 4e-4), ("rudder", 6.5e-4)):
        f, w = full[name], win[name]
        # the window starts on a history row (10 µs) before the sample before the first load
        # (there the interpolated load is still zero)
        assert first - 5e-5 - 3e-5 < w["start_time_s"] <= first - 5e-5 - 1e-5 + 1e-12
        assert w["steps"] < 0.8 * f["steps"] and f["start_time_s"] == 0.0
        assert w["end_time_s"] == f["end_time_s"]
        for key in ("peak_von_mises_pa", "peak_time_s", "peak_location_m",
                    "peak_max_principal_pa", "peak_error_estimate_rel", "max_abs_u_m"):
            assert w[key] == f[key], (name, key)
        hf = read_history_csv(tmp_path / "full" / name / "history.csv")
        hw = read_history_csv(tmp_path / "win" / name / "history.csv")
        assert hw["t_s"][0] == pytest.approx(w["start_time_s"], rel=1e-12)
        i0 = int(np.searchsorted(hf["t_s"], hw["t_s"][0] * (1 - 1e-9)))
        assert len(hf["t_s"]) == i0 + len(hw["t_s"])
        for col in hw:  # same rows, same bits (the full run is at rest before the window)
            np.testing.assert_array_equal(hw[col], hf[col][i0:], err_msg=col)
        assert np.all(hf["max_abs_u_m"][:i0 + 1] == 0.0)
        assert np.all(hf["kinetic_energy_j"][:i0 + 1] == 0.0)
    assert all("time window" not in m for m in win["warnings"])


def test_two_workers_give_the_one_worker_results_bitwise(tmp_path):
    one = _run(tmp_path, "one", workers=1)
    two = _run(tmp_path, "two", workers=2)
    assert one["workers"] == 1 and two["workers"] == 2
    # default window: each fin ends end_margin after the sample where its load returns to zero
    # (the wing's last load sample is at 0.9 ms, the rudder's at the last sample, 1 ms)
    for name, end in (("wing", 0.95e-3 + 3e-4), ("rudder", 1e-3 + 3e-4)):
        assert end <= one[name]["end_time_s"] < end + 1e-5 + 1e-12
    for name in ("wing", "rudder"):
        assert {k: v for k, v in two[name].items()} == one[name], name
        a = read_history_csv(tmp_path / "one" / name / "history.csv")
        b = read_history_csv(tmp_path / "two" / name / "history.csv")
        for col in a:
            np.testing.assert_array_equal(b[col], a[col], err_msg=col)


def test_window_arithmetic():
    t = np.arange(10) * 1e-5
    w = fin_window(t, np.array([3, 5, 4]), 1.0, 2e-5, np.array([0.0, 5e-5, 1e-4]),
                   np.array([[3.0, 4.0, 0.0], [1.0, 0, 0], [0, 0, 7.0]]), fixed_end=False)
    # zero load up to the sample before the first event; load until the sample after the last
    assert w == FinWindow(2e-5, 6e-5 + 2e-5, 5.0, 7.0, t[6], 1.0)  # |a| = 5 at t = 0 (before), 7 after
    assert fin_window(t, np.array([0]), 1.0, 0.0, t[:0], np.zeros((0, 3)),
                      fixed_end=True) == FinWindow(0.0, 1.0, 0.0, 0.0, 1e-5, 1.0)
    start, n = window_steps(FinWindow(2e-5, 8e-5), 1e-6, 3)
    assert start % 3 == 0 and start * 1e-6 <= 2e-5 - 3e-6 and start * 1e-6 > 2e-5 - 6e-6 - 1e-12
    assert (start + n) % 3 == 0 and 8e-5 <= (start + n) * 1e-6 < 8e-5 + 3e-6
    assert window_steps(FinWindow(0.0, 1e-5), 1e-6, 4) == (0, 12)


def test_run_as_ready_keeps_order_and_raises_after_all_jobs():
    done = []

    def fn(j):
        done.append(j)
        if j == 1:
            raise ValueError("job 1")
        return 10 * j

    assert run_as_ready([0, 2, 3], fn, 2) == [0, 20, 30]
    with pytest.raises(ValueError, match="job 1"):
        run_as_ready([0, 1, 2, 3], fn, 2)
    assert sorted(done[3:]) == [0, 1, 2, 3]


def test_run_as_ready_starts_each_job_while_the_next_is_made():
    # Reference: the order of events. Job 0's run must start before job 1 is made (it is handed to
    # a thread at once and waits for nothing); while jobs are still being made, at most workers − 1
    # run at once (the making has a core), afterwards workers; a failure in making a job is raised
    # only after the jobs already handed out have ended, which keep their results.
    events, started = [], threading.Event()

    def jobs():
        yield 0
        assert started.wait(5.0)  # job 0 runs while this (the set-up) is still going
        events.append("made 1")
        yield 1
        raise RuntimeError("set-up of job 2")

    def fn(j):
        if j == 0:
            started.set()
        time.sleep(0.05)
        events.append(f"ran {j}")
        return j

    with pytest.raises(RuntimeError, match="set-up of job 2"):
        run_as_ready(jobs(), fn, 2)
    assert sorted(events) == ["made 1", "ran 0", "ran 1"]
    assert run_as_ready(iter([5, 6]), fn, 1) == [5, 6]  # one worker: in this thread, in order

    lock, now, most, making = threading.Lock(), [0], {True: 0, False: 0}, [True]

    def counted(j):
        with lock:
            now[0] += 1
            most[making[0]] = max(most[making[0]], now[0])
        time.sleep(0.1)
        with lock:
            now[0] -= 1
        return j

    def made():
        yield from range(6)  # more jobs than threads at once, then a long making of nothing more
        time.sleep(0.15)
        making[0] = False

    assert run_as_ready(made(), counted, 3) == list(range(6))
    assert most[True] == 2 and most[False] == 3  # 3 workers: 2 while making, then 3


def test_advance_releases_the_gil():
    # the thread pool gains only if the kernel runs without the GIL
    assert kn.advance.targetoptions.get("nogil") is True


def test_body_acceleration_left_out_before_the_window_is_reported(tmp_path):
    from flexnet_fe.io import write_history_csv
    fins = make_inputs(tmp_path)
    # 2 000 m/s² for 0.2 ms, before either fin's first load: the wing (≈ 0.5 kg) gets about
    # 1 kN of inertial load, comparable with its 1.8 kN rope load — the window must say so
    t = np.linspace(0.0, 1e-3, 101)
    write_history_csv(tmp_path / "acc.csv", {
        "t_s": t, "accel_body_x_mps2": 0 * t, "accel_body_y_mps2": 0 * t,
        "accel_body_z_mps2": np.where(t <= 2e-4, 2e3, 0.0)})
    s = run_shell(CFG, fins, tmp_path / "fin_contacts.npz", tmp_path / "acc.csv",
                  tmp_path / "out", LOG)
    w = s["wing"]
    mass = 0.3 * 0.15 * 4e-3 * 2810.0  # minus the clamped root nodes' share
    assert w["window_accel_before_mps2"] == 2e3 and w["window_accel_after_mps2"] == 0.0
    assert 0.9 * mass * 2e3 / 1800.0 < w["window_force_ratio_before"] < mass * 2e3 / 1800.0
    assert any("wing: the time window" in m and "before it" in m for m in s["warnings"])
    full = run_shell(CFG.model_copy(update={"window": "full"}), fins,
                     tmp_path / "fin_contacts.npz", tmp_path / "acc.csv", tmp_path / "full", LOG)
    assert full["wing"]["window_force_ratio_before"] == 0.0
    assert full["wing"]["window_before_stress_bound_pa"] == 0.0
    assert not any("time window" in m for m in full["warnings"])
    # Reference: superposition (stage.omitted_stress). The run from t = 0 is the window's
    # run plus the response to the left-out load, so the two peaks differ by at most that
    # response's own peak — solved on the same mesh here (no local refinement), so the bound
    # before its safety factor holds, up to the two runs' different steps (1 %). And it is not
    # vacuous: the left-out load is what moves the peak, by a fair share of the bound.
    diff = abs(full["wing"]["peak_von_mises_pa"] - w["peak_von_mises_pa"])
    raw = w["window_before_stress_bound_pa"] / WINDOW_BOUND_FACTOR
    assert 0.1 * raw < diff <= 1.01 * raw  # measured: 3.15 against 9.22 MPa


def test_body_acceleration_left_out_after_the_window_is_bounded(tmp_path):
    from flexnet_fe.io import write_history_csv
    fins = make_inputs(tmp_path)
    # the wing's rope load ends at 1 ms, its window at 2 ms (end_margin); the stage runs to 4 ms
    # (the acceleration's last sample, 3 ms, + end_margin). 2 000 m/s² from 2.2 to 2.6 ms: after
    # the window (about 1 kN of inertial load on the ≈ 0.5 kg wing, against its 1.8 kN rope load)
    t = np.linspace(0.0, 3e-3, 301)
    ramp = np.where((t >= 2.2e-3) & (t <= 2.6e-3), 2e3, 0.0)
    for name, a in (("with.csv", ramp), ("without.csv", 0 * t)):
        write_history_csv(tmp_path / name, {"t_s": t, "accel_body_x_mps2": 0 * t, "accel_body_y_mps2": 0 * t,
                                            "accel_body_z_mps2": a})
    s = run_shell(CFG, fins, tmp_path / "fin_contacts.npz", tmp_path / "with.csv", tmp_path / "win", LOG)
    w = s["wing"]
    assert w["window_accel_after_mps2"] == 2e3 and w["window_after_stress_bound_pa"] > 0.0
    assert w["window_before_stress_bound_pa"] == 0.0
    assert any("wing: the time window" in m and "after it" in m for m in s["warnings"])
    # Reference: superposition (stage.omitted_stress). Two runs to the stage's end, 'full' window
    # (no part left out), with and without the left-out acceleration, differ by the response to it
    # from rest at the window's end: at every point and instant by at most its von Mises, so their
    # largest von Mises at each instant after 2 ms (history rows) differ by at most its peak —
    # solved on the same (unrefined) mesh here, so the bound before its safety factor holds, up to
    # the runs' steps (1 %). Not vacuous: the acceleration moves them by a fair share of it.
    full = CFG.model_copy(update={"window": "full"})
    rows = []
    for name in ("with", "without"):
        r = run_shell(full, fins, tmp_path / "fin_contacts.npz", tmp_path / f"{name}.csv", tmp_path / f"f_{name}", LOG)
        assert r["wing"]["window_after_stress_bound_pa"] == 0.0
        h = read_history_csv(tmp_path / f"f_{name}" / "wing" / "history.csv")
        rows.append(h["max_von_mises_pa"][h["t_s"] >= w["end_time_s"]])
    raw = w["window_after_stress_bound_pa"] / WINDOW_BOUND_FACTOR
    moved = np.abs(rows[0] - rows[1]).max()
    assert 0.1 * raw < moved <= 1.01 * raw, (moved, raw)


def test_petsc_backend_runs_the_same_window(tmp_path):
    # Reference: the compiled kernel over the same window. The PETSc step (Mat.mult per step,
    # frame B) differs from it by the summation order only: histories agree to round-off,
    # bound 1e-10 of each column's scale as the MPI test (issue 10's backend agreement).
    a = _run(tmp_path, "compiled", workers=1, end_time=1.3e-3)
    b = _run(tmp_path, "petsc", workers=1, end_time=1.3e-3, backend="petsc")
    for name in ("wing", "rudder"):
        assert a[name]["start_time_s"] > 0 and b[name]["steps"] == a[name]["steps"]
        assert b[name]["start_time_s"] == a[name]["start_time_s"]
        ha = read_history_csv(tmp_path / "compiled" / name / "history.csv")
        hb = read_history_csv(tmp_path / "petsc" / name / "history.csv")
        for col in ha:
            scale = np.nanmax(np.abs(ha[col])) or 1.0
            np.testing.assert_allclose(hb[col], ha[col], rtol=0, atol=1e-10 * scale,
                                       err_msg=f"{name} {col}")
        assert b[name]["peak_von_mises_pa"] == pytest.approx(a[name]["peak_von_mises_pa"],
                                                             rel=1e-10)


def test_every_run_says_what_the_load_sampling_does_to_its_peaks():
    # Reference: docs/validation.md, "The fin loads' time sampling" — radar_traction's peaks,
    # one collision sampled at 0.078 µs and coarsened: ×4–11 higher at ≤ 0.3125 µs than at 10 µs,
    # then ≤ 7 % on the rudders from 0.3125 to 0.156 µs, but +31/+51 % on rudders 2/4 with the
    # rope's chords halved. A run coarser than LOAD_SAMPLING_RESOLVED_S is told its peaks are
    # under-estimated; a finer one that they still follow the rope; no contact loads, nothing.
    from flexnet_fe.shell.stage import (FinContacts, LOAD_SAMPLING_RESOLVED_S, load_sampling_resolved,
                                        load_sampling_warning)

    def contacts(dt):
        t = np.arange(5) * dt
        return FinContacts(fin_names=("wing_1",), t=t, sample=np.array([2]), fin=np.array([0]),
                           point=np.zeros((1, 3)), force=np.ones((1, 3)), width=np.full(1, 4.5e-3))
    coarse, fine = contacts(1e-5), contacts(3.125e-7)
    assert 3.125e-7 <= LOAD_SAMPLING_RESOLVED_S < 6.25e-7
    text = load_sampling_warning(coarse)
    assert load_sampling_resolved(coarse) is False
    assert "10 µs" in text and "50 kHz" in text and "UNDER-ESTIMATED" in text and "load_interval" in text
    text = load_sampling_warning(fine)
    assert load_sampling_resolved(fine) is True
    assert "0.312 µs" in text and "not converged in the rope" in text and "UNDER" not in text
    empty = coarse.__class__(fin_names=(), t=coarse.t, sample=np.zeros(0, np.int64), fin=np.zeros(0, np.int64),
                             point=np.zeros((0, 3)), force=np.zeros((0, 3)), width=np.zeros(0))
    assert load_sampling_warning(empty) == "" and load_sampling_resolved(empty) is None


def test_after_last_load_reads_the_rows_after_it():
    # Reference: the definition (shell.stage.after_last_load): the largest row strictly after the
    # last load, over the peak; no last load (nan: window 'full' or a given pressure) or no row
    # after it gives None, never NaN (summary.json is strict JSON).
    from flexnet_fe.shell.stage import after_last_load

    t = np.array([0.0, 1.0, 2.0, 3.0])
    vm = np.array([1.0, 8.0, 3.0, 2.0])
    assert after_last_load(t, vm, 1.0, 8.0) == {"after_last_load_max_von_mises_pa": 3.0,
                                                "after_last_load_over_peak": 3.0 / 8.0}
    none = {"after_last_load_max_von_mises_pa": None, "after_last_load_over_peak": None}
    assert after_last_load(t, vm, float("nan"), 8.0) == none
    assert after_last_load(t, vm, 3.0, 8.0) == none
