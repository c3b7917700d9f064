#!/bin/bash
# Side by side (issue 9 speed, docs/performance.md "Collide: the far net in windows ..."): each paper
# case's collide stage at its shipped resolution, main at OLD (default a66e223: single rate, no nose
# cones) and this tree, one after the other, in one job. Needs each case's deploy in
# runs/dep_<case>/deploy (`flexnet run cases/<case> --stages deploy --out runs/dep_<case>`).
#   bash benchmarks/collide_far_net_sbs.sh [OLD] [OUT_DIR]
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
old="${1:-a66e223}"
out="${2:-$here/runs}"
tree="$(mktemp -d)"
git -C "$here" archive "$old" | tar -x -C "$tree"
for c in radar_traction infrared_traction radar_rotary; do
  (cd "$tree" && PYTHONPATH="$tree" "$here/.venv/bin/python" benchmarks/collide_rope_resolution.py run \
     "cases/$c" "$here/runs/dep_$c/deploy" "$out/sbs_old.jsonl" --pieces 0.7e-3)
  (cd "$here" && PYTHONPATH="$here" "$here/.venv/bin/python" benchmarks/collide_rope_resolution.py run \
     "cases/$c" "runs/dep_$c/deploy" "$out/sbs_new.jsonl" --pieces 0.7e-3)
done
rm -rf "$tree"
