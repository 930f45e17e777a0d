#!/usr/bin/env bash
# Regenerates the validation table of docs/real-trees.md: `hmsm analyze --whole-tree` on the
# presets paper-1..paper-5 (coupled with the held and the articulated exchange, in leaf and
# leaf-off, and paper) and on the example scans of tests/data/import (imported with a broadleaf
# species, coupled with either exchange in leaf and leaf-off), compared
# with the published relations the page cites. Prints the Markdown table on stdout and keeps the
# JSON reports in OUT (default validation/).
#
#   tools/validate_real_trees.sh [OUT]        (HMSM=path/to/hmsm, default build/hmsm; needs jq)
#
# The runs are short (pull 15 s, release 40 s, sway at 10 m/s for 60 s after 10 s) so the whole
# table takes minutes; lengthen them with ANALYZE_FLAGS="--sway-seconds 300 ..." for smoother slopes.
set -euo pipefail
cd "$(dirname "$0")/.."
HMSM=${HMSM:-build/hmsm}
OUT=${1:-validation}
mkdir -p "$OUT"
FLAGS="--whole-tree --json --no-progress --pull-seconds 15 --release-seconds 40 --settle-seconds 10 \
--sway-seconds 60 --sway-speeds 10 ${ANALYZE_FLAGS:-}"

run() {  # name, source flags, dynamics flags
  local name=$1 source=$2 dynamics=$3
  # shellcheck disable=SC2086
  "$HMSM" analyze $source $dynamics $FLAGS >"$OUT/$name.json"
}

for p in paper-1 paper-2 paper-3 paper-4 paper-5; do
  run "$p-coupled-on" "--preset $p" "--dynamics coupled"
  run "$p-coupled-off" "--preset $p" "--dynamics coupled --leaf-off"
  run "$p-articulated-on" "--preset $p" "--dynamics coupled --exchange articulated"
  run "$p-articulated-off" "--preset $p" "--dynamics coupled --exchange articulated --leaf-off"
  run "$p-paper" "--preset $p" "--dynamics paper"
done
for scan in scan_treeqsm scan_treeqsm_v23; do
  "$HMSM" import --treeqsm "tests/data/import/$scan.txt" --out "$OUT/$scan.tree.json" --species sugar-maple \
    --leaves 2000 >/dev/null
  run "$scan-coupled-on" "--tree $OUT/$scan.tree.json" "--dynamics coupled"
  run "$scan-coupled-off" "--tree $OUT/$scan.tree.json" "--dynamics coupled --leaf-off"
  run "$scan-articulated-on" "--tree $OUT/$scan.tree.json" "--dynamics coupled --exchange articulated"
  run "$scan-articulated-off" "--tree $OUT/$scan.tree.json" "--dynamics coupled --exchange articulated --leaf-off"
done
"$HMSM" import --simpleforest tests/data/import/scan_simpleforest.csv --out "$OUT/scan_simpleforest.tree.json" \
  --species sugar-maple --leaves 2000 >/dev/null
run "scan_simpleforest-coupled-on" "--tree $OUT/scan_simpleforest.tree.json" "--dynamics coupled"
run "scan_simpleforest-coupled-off" "--tree $OUT/scan_simpleforest.tree.json" "--dynamics coupled --leaf-off"
run "scan_simpleforest-articulated-on" "--tree $OUT/scan_simpleforest.tree.json" \
  "--dynamics coupled --exchange articulated"
run "scan_simpleforest-articulated-off" "--tree $OUT/scan_simpleforest.tree.json" \
  "--dynamics coupled --exchange articulated --leaf-off"

echo "| tree | dynamics | H (m) | DBH (m) | f0 (Hz) | 1.15·H^-0.56 | 0.068 + 319·DBH/H² | ζ | slope at 10 m/s | cross/along | lean (°) | top/H |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
for f in "$OUT"/*-coupled-on.json "$OUT"/*-coupled-off.json "$OUT"/*-articulated-on.json \
  "$OUT"/*-articulated-off.json "$OUT"/*-paper.json; do
  name=$(basename "$f" .json)
  jq -r --arg name "${name%-*}" '.models[0] | . as $m | .sway[0] as $s |
    "| \($name | sub("-(coupled|articulated)$"; "")) | \(.dynamics)\(if .exchange == "articulated" then " articulated" else "" end)\(if .dynamics == "coupled" then (if .leaves_on then ", leaf-on" else ", leaf-off" end) else "" end) | \(.height_m*10|round/10) | \(.dbh_m*100|round/100) | \(.release.frequency_hz*1000|round/1000) | \((1.15 * pow(.height_m; -0.56))*1000|round/1000) | \((0.068 + 319 * .dbh_m / (.height_m*.height_m))*1000|round/1000) | \(.release.damping_ratio*1000|round/1000) | \($s.slope*100|round/100) | \($s.cross_ratio*100|round/100) | \($s.mean_lean_deg*1000|round/1000) | \($s.mean_top_over_height*10000|round/10000) |"' "$f"
done
