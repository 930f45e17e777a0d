#!/usr/bin/env bash
# Optional end-to-end check (CTest runs it as Export.BlenderPlaysClip where Debian's blender and
# python3-numpy are installed, and reports it skipped, exit 77, where they are not): exports
# a clip with `hmsm export --gltf`, imports it into Blender headless and compares the skinned
# mesh at several key frames with `hmsm simulate --backend cpu64 --dump-vertices` after the same
# number of steps (frame k = round(k / (fps dt)) steps).
# Usage: tools/gltf/blender_check.sh [PRESET] [SECONDS]   (default paper-1, 2; 24 fps, dt 1/120)
set -euo pipefail
if ! command -v blender >/dev/null 2>&1 ||
   ! blender -b --factory-startup --python-exit-code 1 --python-expr "import numpy" >/dev/null 2>&1; then
  echo "blender_check: skipped (needs blender and python3-numpy)" >&2
  exit 77
fi
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
hmsm="${HMSM_BUILD_DIR:-$root/build}/hmsm"
preset="${1:-paper-1}"; seconds="${2:-2}"; fps=24
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
wind=(--wind y2 --wind-strength 4 --wind-frequency 0.5)
"$hmsm" generate --preset "$preset" --out "$work/tree.json"
height="$(python3 -c "import json,sys; y=[n['position'][1] for n in json.load(open(sys.argv[1]))['nodes']]; print(max(y)-min(y))" "$work/tree.json")"
"$hmsm" export --tree "$work/tree.json" --gltf "$work/tree.glb" --seconds "$seconds" --fps "$fps" "${wind[@]}"
last=$(python3 -c "import math; print(math.floor($seconds * $fps + 1e-9))")
checks=()
for k in 0 1 $((last / 2 + 1)) "$last"; do
  steps=$(python3 -c "import math; print(math.floor($k / ($fps / 120) + 0.5 + 1e-9))")
  "$hmsm" simulate --tree "$work/tree.json" --backend cpu64 --steps "$steps" "${wind[@]}" \
    --dump-vertices "$work/v$k.bin" 2>/dev/null
  checks+=("$k:$work/v$k.bin")
done
blender -b --factory-startup --python-exit-code 1 --python "$root/tools/gltf/blender_check.py" -- \
  "$work/tree.glb" "$height" "${checks[@]}" 2>&1 | grep -E '^blender_check|Error|Traceback'
exit "${PIPESTATUS[0]}"
