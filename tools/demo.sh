#!/usr/bin/env bash
# The README's first command: installs what is missing, builds, and runs the main job on the best
# available backend: 10 s of Y1 wind on a tree, with a report of where the time went.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/tools/install_deps.sh"
"$root/tools/build.sh"
build="${HMSM_BUILD_DIR:-$root/build}"
out="${HMSM_DEMO_OUT:-$root/out}"
mkdir -p "$out"
hmsm="$build/hmsm"
preset="${HMSM_DEMO_PRESET:-paper-1}"
"$hmsm" generate --preset "$preset" --out "$out/$preset.json"
"$hmsm" info --tree "$out/$preset.json"
"$hmsm" simulate --tree "$out/$preset.json" --backend auto --steps 1200 --wind y1 \
  --dump-nodes "$out/nodes.csv" --dump-vertices "$out/vertices.bin" --report "$out/report.json"
echo "demo outputs in $out:"
ls -l "$out"
