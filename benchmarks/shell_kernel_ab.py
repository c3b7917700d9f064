"""Shell step A/B: this tree's compiled step (``shell.kernel.advance``, its stress sampling
``shell.recovery.sample_nodes``) against another version of the two modules, side by side in one
process (thread CPU time, interleaved repetitions, alternating order).

    git show <rev>:flexnet_fe/shell/kernel.py > /tmp/shell_kernel_other.py
    git show <rev>:flexnet_fe/shell/recovery.py > /tmp/shell_recovery_other.py
    PYTHONPATH=. .venv/bin/python benchmarks/shell_kernel_ab.py /tmp/shell_kernel_other.py \
        /tmp/shell_recovery_other.py [--repeats 9]

Problems: the radar missile's wing_1 (Al 7075, 6 mm, clamped root) meshed at 20 and 10 mm
(cache-resident) and a 141 × 141 plate (1e5 DOFs), each from the same smooth initial deflection
at 0.9 dt_crit. Two cadences: the bare step (no stress sampling) and the shell stage's (the
stresses for the running peak every 3 steps — ``shell.peak_interval`` 0.25 µs over a step of
≈ 0.09 µs at the cases' 1.25 mm — and a history row every 21). Each repetition times one call of
each version; reported: the median ns per DOF-step of each and the median, min and max of the
per-repetition ratio other / this (paired: both saw the same machine load). The end states (u, v,
the history rows, the envelope, the peaks) must be equal to the bit, else the script says so and
exits 1.
"""

from __future__ import annotations

import argparse
import importlib.util
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_shell import AL7075, paper_fin_model  # noqa: E402
from flexnet_fe.shell import api, kernel as kn  # noqa: E402
from flexnet_fe.shell.explicit import critical_step, max_eigenvalue, no_loads  # noqa: E402
from flexnet_fe.shell.forms import NDOF_NODE  # noqa: E402
from flexnet_fe.shell.solve import LocalFrame, recovery_for, step_data  # noqa: E402


def _load(name: str, path: str):
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod  # numba's cache pickles references to the module by name
    spec.loader.exec_module(mod)
    return mod


def load_other(kernel_path: str, recovery_path: str):
    """The other kernel module, its stress sampling taken from the other recovery module (bound
    before the first call, so numba compiles the other kernel against it)."""
    rec = _load("shell_recovery_other", recovery_path)
    ker = _load("shell_kernel_other", kernel_path)
    ker.sample_nodes = rec.sample_nodes
    return ker


def problem(model):
    """(StepData, RecoveryData in the local frame, u0, dt, n_nodes) of ``model`` with no loads."""
    op = model.op
    lam, _ = max_eigenvalue(op)
    dt = 0.9 * critical_step(lam)
    D = step_data(model, no_loads(op), LocalFrame(model.fin.plane))
    R = recovery_for(model)._replace(e1=np.array([1.0, 0, 0]), e2=np.array([0, 1.0, 0]))
    u0 = np.zeros(op.n_owned)
    u0[2::NDOF_NODE] = 1e-7 * np.sin(op.x_nodes[:, 0] * 20.0)
    return D, R, u0 * (op.minv > 0), dt, op.n_owned // NDOF_NODE


def run(mod, prob, steps: int, peak_every: int, sample_every: int):
    """One call of ``mod.advance`` over ``steps`` steps from the problem's start: (thread CPU s,
    state, history)."""
    D, R, u0, dt, nn = prob
    P = mod.StepParams(dt=dt, alpha=0.0, beta=0.0, growth_limit=1e300, sample_every=sample_every,
                       peak_every=peak_every)
    St = mod.new_state(len(u0), u0)
    H = mod.new_history(steps // sample_every + 2, nn)
    t0 = time.thread_time()
    failed = mod.advance(D, P, R, St, H, steps)
    cpu = time.thread_time() - t0
    if failed:
        raise SystemExit(f"energy guard tripped at step {failed}")
    return cpu, St, H


def same(a, b) -> bool:
    (_, sa, ha), (_, sb, hb) = a, b
    pairs = [(sa.u, sb.u), (sa.v, sb.v), (sa.scal, sb.scal), (sa.u_peak, sb.u_peak)]
    pairs += [(getattr(ha, f), getattr(hb, f)) for f in ("t", "vm", "node", "p1", "umax", "ke", "se", "work", "env")]
    return all(np.array_equal(x, y) for x, y in pairs)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("kernel_other")
    ap.add_argument("recovery_other")
    ap.add_argument("--repeats", type=int, default=9)
    args = ap.parse_args()
    other = load_other(args.kernel_other, args.recovery_other)
    problems = [("radar wing_1, 20 mm", paper_fin_model(0.02)), ("radar wing_1, 10 mm", paper_fin_model(0.01)),
                ("plate 141², 1e5 DOFs", api.plate(141, 141, 0.5, 0.5, AL7075, supports={"root": "clamped"}))]
    ok = True
    print("| problem | DOFs | cadence | other [ns/DOF-step] | this | other / this: median [min, max] |")
    print("|---|---|---|---|---|---|")
    for label, model in problems:
        prob = problem(model)
        n = len(prob[2])
        steps = max(63, 63 * round(1.5e7 / n / 63))
        for cadence, pe, se in (("bare step", 0, 10 ** 9), ("stage: peak every 3, row every 21", 3, 21)):
            for mod in (other, kn):  # compile and warm
                run(mod, prob, 21, pe, se)
            t = {"other": [], "this": []}
            last = {}
            for r in range(args.repeats):
                order = (("other", other), ("this", kn)) if r % 2 else (("this", kn), ("other", other))
                for name, mod in order:
                    last[name] = run(mod, prob, steps, pe, se)
                    t[name].append(last[name][0] / steps / n * 1e9)
            if not same(last["other"], last["this"]):
                ok = False
                print(f"**{label}, {cadence}: the end states differ**")
            ratios = [a / b for a, b in zip(t["other"], t["this"])]
            print(f"| {label} | {n} | {cadence} | {statistics.median(t['other']):.2f} | "
                  f"{statistics.median(t['this']):.2f} | **{statistics.median(ratios):.2f}** "
                  f"[{min(ratios):.2f}, {max(ratios):.2f}] |")
    print("end states equal to the bit" if ok else "END STATES DIFFER")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
