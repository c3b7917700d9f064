"""Collide kernel cost, old vs new, side by side (issue 9 speed target; not a test).

Whole run (the original mode): ns per spring-step of the collide kernel of whichever
``flexnet_fe`` is first on the path, on the cropped radar × traction scene of that tree's own case
file: deploy once into DEPLOY_DIR (reused if present), then simulate REPS times (rep 0 may
include numba compilation). Run the script by its path from outside the trees (a ``python -c`` or a
script in the tree's root puts that directory first on ``sys.path``, ahead of PYTHONPATH):

    git archive fb2b29c | tar -x -C /tmp/oldtree        # the pre-issue-9 kernel, not committed
    PYTHONPATH=/tmp/oldtree python benchmarks/collide_kernel_speed.py /tmp/oldtree old /tmp/dep_old 2
    PYTHONPATH=$PWD         python benchmarks/collide_kernel_speed.py $PWD        new /tmp/dep_new 2

Window (issue 9, fine rope resolution): one process times the kernel of git commit OLD
(``collide/kernel.py`` and ``missile/shapes.py`` of that commit, loaded as separate modules) and
this tree's kernel, interleaved (old, new, new, old, ...), on the same state: CASE with
``[collide] rope_split`` K, advanced by this tree's kernel to T0 [ms] from the deploy state in
DEPLOY_DIR (``run_deploy`` there if missing; the state is cached in STATE_FILE), then STEPS steps
per rep, in calls of one output interval. Prints ns per spring-step per rep with the load average,
the medians, their ratio and whether the two final states are bit-identical (the per-call
accumulators included: both run the same calls).

    python benchmarks/collide_kernel_speed.py window radar_traction 32 4 DEPLOY_DIR STATE_FILE \\
        [--old 49c5162] [--steps 3000] [--reps 6]
"""
import argparse
import importlib.util
import logging
import math
import pickle
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from flexnet_fe.atmosphere import isa
from flexnet_fe.collide import kernel as kernel_new
from flexnet_fe.collide import model as M
from flexnet_fe.collide import simulate as S
from flexnet_fe.collide.refine import split_near_path
from flexnet_fe.collide.scene import held_net
from flexnet_fe.config import load_case
from flexnet_fe.missile.build import build_missile
from flexnet_fe.net.deploy import run_deploy

ROOT = Path(__file__).resolve().parents[1]


def whole_run() -> None:
    root, label, dep = Path(sys.argv[1]), sys.argv[2], Path(sys.argv[3])
    reps = int(sys.argv[4]) if len(sys.argv) > 4 else 2
    log = logging.getLogger("collide_kernel_speed")
    logging.basicConfig(level=logging.WARNING)
    case, _ = load_case(root / "cases" / "radar_traction")
    air = isa(case.atmosphere.altitude)
    if not (dep / "net_state.npz").is_file():
        run_deploy(case.net, case.deploy, air, dep, log)
    net = held_net(case.net, case.collide.net_source, dep)
    missile = build_missile(case.missile)
    for rep in range(reps):
        s = S.simulate(net, missile, case.collide, air.gravity, log, air_density=air.density, n_snapshots=2).summary
        ns = s["wall_s"] / (s["steps"] * s["active_segments"]) * 1e9
        load = Path("/proc/loadavg").read_text().split()[0]
        print(f"{label} rep {rep}: steps {s['steps']} active {s['active_segments']} wall {s['wall_s']:.2f} s "
              f"ns/spring-step {ns:.1f} load {load}", flush=True)


def old_kernel(commit: str):
    """The collide kernel of git ``commit`` as a module (its own copy of ``missile/shapes.py``)."""
    tmp = Path(tempfile.mkdtemp(prefix="old_kernel_"))
    for src, name in (("flexnet_fe/collide/kernel.py", "kernel_old.py"), ("flexnet_fe/missile/shapes.py",
                                                                           "shapes_old.py")):
        text = subprocess.run(["git", "-C", str(ROOT), "show", f"{commit}:{src}"], check=True, capture_output=True,
                              text=True).stdout
        (tmp / name).write_text(text.replace("from flexnet_fe.missile.shapes import", "from shapes_old import"))
    sys.path.insert(0, str(tmp))
    spec = importlib.util.spec_from_file_location("kernel_old", tmp / "kernel_old.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def window_state(case_name: str, k: int, t0_ms: float, dep: Path, state_file: Path):
    """(model, state, dt, steps per output interval) at t0 of CASE with rope_split k (cached)."""
    if state_file.is_file():
        d = pickle.loads(state_file.read_bytes())
        return d["model"], d["state"], d["dt"], d["n_sub"]
    log = logging.getLogger("collide_kernel_speed")
    case, _ = load_case(ROOT / "cases" / case_name)
    cfg = case.collide.model_copy(update={"rope_split": k})
    air = isa(case.atmosphere.altitude)
    if not (dep / "net_state.npz").is_file():
        run_deploy(case.net, case.deploy, air, dep, log)
    missile = build_missile(case.missile)
    net = split_near_path(held_net(case.net, cfg.net_source, dep), missile, cfg)
    setup = S.build(net, missile, cfg, air.gravity, log, cfg.crop, air.density if cfg.air else 0.0)
    km, start = setup.model, setup.start
    n_sub = max(1, math.ceil(cfg.output_interval / setup.step.dt))
    dt = cfg.output_interval / n_sub
    st = M.new_state(net.x[setup.used], km.seg.shape[0], km.fin_half.shape[0], start.x_cg, start.v_cg, start.q)
    for _ in range(round(t0_ms * 1e-3 / cfg.output_interval)):
        if kernel_new.advance(km, st, n_sub, dt) != M.OK:
            raise SystemExit("collide_kernel_speed: the run stopped before t0")
        S._take_fin_events(km, st)
    state_file.write_bytes(pickle.dumps({"model": km, "state": st, "dt": dt, "n_sub": n_sub}))
    return km, st, dt, n_sub


def window(argv) -> None:
    ap = argparse.ArgumentParser(prog="collide_kernel_speed.py window")
    for name, typ in (("case", str), ("rope_split", int), ("t0_ms", float), ("deploy", Path), ("state", Path)):
        ap.add_argument(name, type=typ)
    ap.add_argument("--old", default="49c5162", help="git commit of the old kernel")
    ap.add_argument("--steps", type=int, default=3000)
    ap.add_argument("--reps", type=int, default=6)
    a = ap.parse_args(argv)
    km, st0, dt, chunk = window_state(a.case, a.rope_split, a.t0_ms, a.deploy, a.state)
    kernels = {"old": old_kernel(a.old), "new": kernel_new}
    fresh = lambda: st0._replace(**{f: getattr(st0, f).copy() for f in st0._fields})  # noqa: E731
    for mod in kernels.values():
        mod.advance(km, fresh(), 1, dt)  # compile / load the cache
    ns_seg = km.seg.shape[0]
    times, final = {k: [] for k in kernels}, {}
    print(f"{a.case}, rope_split {a.rope_split}, t0 {a.t0_ms} ms: {ns_seg} segments, dt {dt:.4g} s, "
          f"{a.steps} steps per rep in calls of {chunk}", flush=True)
    for rep in range(a.reps):
        for label in (("old", "new") if rep % 2 == 0 else ("new", "old")):
            s, done = fresh(), 0
            t = time.perf_counter()
            while done < a.steps:
                n = min(chunk, a.steps - done)
                if kernels[label].advance(km, s, n, dt) != M.OK:
                    raise SystemExit(f"collide_kernel_speed: {label} kernel stopped")
                done += n
            times[label].append((time.perf_counter() - t) / (a.steps * ns_seg) * 1e9)
            final[label] = s
            load = Path("/proc/loadavg").read_text().split()[0]
            print(f"  {label} rep {rep}: {times[label][-1]:.1f} ns per spring-step, load {load}", flush=True)
    med = {k: float(np.median(v)) for k, v in times.items()}
    same = all(np.array_equal(getattr(final["old"], f), getattr(final["new"], f)) for f in st0._fields)
    print(f"median ns per spring-step: old {med['old']:.1f}, new {med['new']:.1f}; "
          f"old/new {med['old'] / med['new']:.2f}; final states bit-identical: {same}", flush=True)


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "window":
        window(sys.argv[2:])
    else:
        whole_run()
