"""Collide kernel cost, old vs new, side by side (issue 9 speed target; not a test).

ns per spring-step of the collide kernel of whichever ``flexnet_fe`` is first on the path, on the
cropped radar × traction scene of that tree's own case file: deploy once into DEPLOY_DIR (reused
if present), then simulate REPS times (rep 0 may include numba compilation).

    git archive fb2b29c | tar -x -C /tmp/oldtree        # the pre-issue-9 kernel, not committed
    PYTHONPATH=/tmp/oldtree python benchmarks/collide_kernel_speed.py /tmp/oldtree old /tmp/dep_old 2
    PYTHONPATH=$PWD         python benchmarks/collide_kernel_speed.py $PWD        new /tmp/dep_new 2

Alternate old and new invocations and compare medians (docs/performance.md).
"""
import logging
import sys
from pathlib import Path

from flexnet_fe.atmosphere import isa
from flexnet_fe.collide.scene import held_net
from flexnet_fe.collide.simulate import simulate
from flexnet_fe.config import load_case
from flexnet_fe.missile.build import build_missile
from flexnet_fe.net.deploy import run_deploy


def main() -> None:
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
        s = simulate(net, missile, case.collide, air.gravity, log, air_density=air.density, n_snapshots=2).summary
        ns = s["wall_s"] / (s["steps"] * s["active_segments"]) * 1e9
        load = Path("/proc/loadavg").read_text().split()[0]
        print(f"{label} rep {rep}: steps {s['steps']} active {s['active_segments']} wall {s['wall_s']:.2f} s "
              f"ns/spring-step {ns:.1f} load {load}", flush=True)


if __name__ == "__main__":
    main()
