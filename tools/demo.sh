#!/usr/bin/env bash
# The README's first command: installs what is missing, builds, generates the paper-1 tree,
# simulates 10 s of Y1 wind on the best available backend, compares the backends this machine
# has (a Table 1-style table), and renders the swaying tree: out/paper-1.gif and a strip of four
# frames, out/paper-1-strip.png, then a gust and a blast through a small forest driven by a
# schedule file (out/forest-gust.gif); then exports the paper-1 animation as a skinned glTF
# clip, out/paper-1.glb (docs/export.md), and checks it with the Khronos glTF validator. Sized
# for a 2-core machine without a GPU (Vulkan on lavapipe).
#
# Environment: HMSM_BUILD_DIR (default build), HMSM_DEMO_OUT (default out), HMSM_DEMO_PRESET
# (default paper-1), HMSM_DEMO_FRAMES (48), HMSM_DEMO_FPS (12), HMSM_DEMO_SIZE (320x240).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/tools/install_deps.sh"
"$root/tools/build.sh"
build="${HMSM_BUILD_DIR:-$root/build}"
out="${HMSM_DEMO_OUT:-$root/out}"
preset="${HMSM_DEMO_PRESET:-paper-1}"
frames="${HMSM_DEMO_FRAMES:-48}"
fps="${HMSM_DEMO_FPS:-12}"
size="${HMSM_DEMO_SIZE:-320x240}"
hmsm="$build/hmsm"
mkdir -p "$out"
start=$SECONDS

section() { printf '\n== %s\n' "$*"; }

section "the tree: $preset"
"$hmsm" generate --preset "$preset" --out "$out/$preset.json"
"$hmsm" info --tree "$out/$preset.json"

section "10 s of Y1 wind (1200 steps of 1/120 s) on the best available backend"
"$hmsm" simulate --tree "$out/$preset.json" --backend auto --steps 1200 --wind y1 \
  --dump-nodes "$out/nodes.csv" --dump-vertices "$out/vertices.bin" --report "$out/report.json"

# A value out of a report written by `hmsm simulate --report` (one key per line).
json_value() {
  sed -n -e "s/^ *\"$2\": *\"\(.*\)\",\{0,1\}$/\1/p" \
         -e "s/^ *\"$2\": *\([^\"{[][^,]*\),\{0,1\}$/\1/p" "$1" | head -n 1
}

section "backends on this machine (the paper's Table 1: steps per second, speed-up over cpu)"
if "$hmsm" bench --quick --presets "$preset" --instances none --no-progress \
     --json "$out/bench.json" >"$out/bench.md" 2>"$out/bench.log"; then
  # The Table 1 section; per-pass times and the rest are in out/bench.md.
  awk '/^### Steps per second/ { show = 1 } /^### / && !/Steps per second/ { show = 0 } show' "$out/bench.md"
  echo "(per-pass device times, pointer jumping vs level by level, copy bandwidth: $out/bench.md)"
else
  # Without a working `hmsm bench`: time 120 steps per backend with `hmsm simulate --report`.
  echo "(hmsm bench unavailable: $(tail -n 1 "$out/bench.log"); timing hmsm simulate instead)"
  printf '%-6s  %-44s  %9s  %9s  %8s\n' backend device "ms/step" "steps/s" speed-up
  cpu_rate=""
  for backend in cpu cpu64 vulkan cuda; do
    report="$out/report-$backend.json"
    if ! "$hmsm" simulate --tree "$out/$preset.json" --backend "$backend" --steps 120 \
         --report "$report" 2>/dev/null; then
      printf '%-6s  %s\n' "$backend" "(not available here)"
      continue
    fi
    rate="$(json_value "$report" steps_per_second)"
    device="$(json_value "$report" device)"
    [ "$backend" = cpu ] && cpu_rate="$rate"
    awk -v b="$backend" -v d="$device" -v r="$rate" -v c="${cpu_rate:-0}" 'BEGIN {
      printf "%-6s  %-44.44s  %9.3f  %9.1f  %7.2fx\n", b, d, 1000 / r, r, (c > 0 ? r / c : 0) }'
  done
fi

section "rendering $frames frames at $fps fps, ${size} (Vulkan offscreen)"
"$hmsm" render --tree "$out/$preset.json" --backend auto --wind y1 \
  --frames "$frames" --fps "$fps" --width "${size%x*}" --height "${size#*x}" \
  --out "$out/frames" --gif "$out/$preset.gif" --strip "$out/$preset-strip.png"

# Live control from a file: a gust (a strength ramp to 14 m/s and back) and then a radial blast
# sweep through a grove of five paper-5 trees in turbulent wind (examples/forest). The wind gain
# is given explicitly so the picture does not depend on the default.
forest="$root/examples/forest/grove.json"
schedule="$root/examples/forest/gust_and_blast.json"
live=(--wind turbulent --wind-speed 4 --turbulence 0.4 --front-speed 4 --wind-gain 1.5)
section "a gust and a blast through a small forest ($frames frames, --wind-schedule)"
printf '{"format": "hmsm-schedule", "version": 1, "events": [{"step": 1, "wind": {"speed": 4}}]}\n' \
  >"$out/probe-schedule.json"
if "$hmsm" simulate --forest "$forest" --backend cpu --steps 1 --wind-schedule "$out/probe-schedule.json" \
     2>"$out/probe.log"; then
  "$hmsm" render --forest "$forest" --backend auto "${live[@]}" --wind-schedule "$schedule" \
    --frames "$frames" --fps "$fps" --width "${size%x*}" --height "${size#*x}" \
    --out "$out/forest-frames" --gif "$out/forest-gust.gif" --strip "$out/forest-gust-strip.png"
else
  echo "(live control is not available in this build: $(tail -n 1 "$out/probe.log"); the grove without the schedule)"
  "$hmsm" render --forest "$forest" --backend auto "${live[@]}" \
    --frames "$frames" --fps "$fps" --width "${size%x*}" --height "${size#*x}" \
    --out "$out/forest-frames" --gif "$out/forest-gust.gif" --strip "$out/forest-gust-strip.png"
fi

section "exporting 10 s at 24 fps as a skinned glTF 2.0 clip (docs/export.md)"
"$hmsm" export --tree "$out/$preset.json" --gltf "$out/$preset.glb" --seconds 10 --fps 24 --wind y1
if command -v node >/dev/null 2>&1 && [ -d "$root/tools/gltf/node_modules/gltf-validator" ]; then
  node "$root/tools/gltf/validate.mjs" "$out/$preset.glb"
fi

section "done in $((SECONDS - start)) s (after the build); outputs in $out"
ls -l "$out"
