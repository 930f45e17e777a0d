#!/usr/bin/env bash
# Turns an `hmsm bench --json` result into a dated pair under docs/benchmarks/:
#   <date>-<device>-<commit>.json (the result as is) and .md (its tables, rendered by
#   `hmsm bench --render`, under a header, with an Analysis section to write by hand).
# usage: tools/bench_doc.sh RESULT.json [DEVICE-SLUG]
#   DEVICE-SLUG defaults to the first GPU device in the result (else the host CPU), e.g. nvidia-h100.
#   HMSM=path/to/hmsm picks the binary (default: build-bench/hmsm, then build/hmsm).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
[[ $# -ge 1 && -f $1 ]] || { echo "usage: $0 RESULT.json [DEVICE-SLUG]" >&2; exit 2; }
result=$1
hmsm=${HMSM:-}
for candidate in "$root/build-bench/hmsm" "$root/build/hmsm"; do
    [[ -z $hmsm && -x $candidate ]] && hmsm=$candidate
done
[[ -n $hmsm ]] || { echo "$0: no hmsm binary; set HMSM=..." >&2; exit 2; }

read -r date commit device < <(python3 - "$result" "${2:-}" <<'PY'
import json, re, sys
d = json.load(open(sys.argv[1]))
assert d.get("format") == "hmsm-bench", "not an hmsm-bench result"
slug = sys.argv[2]
if not slug:
    devices = [b.get("device", "") for b in d.get("backends", [])
               if b.get("available") and b.get("backend") not in ("cpu", "cpu64")]
    devices = [x for x in devices if x] or [d.get("host", {}).get("cpu", "host")]
    slug = devices[0]
    slug = re.sub(r"\(.*?\)", "", slug)
slug = re.sub(r"[^a-z0-9]+", "-", slug.lower()).strip("-")[:40]
print(d.get("date", "unknown")[:10], d.get("commit", "unknown"), slug)
PY
)
base="$root/docs/benchmarks/$date-$device-$commit"
cp "$result" "$base.json"
{
    echo "# hmsm bench: $device, $date, commit $commit"
    echo
    echo "Raw result: [$(basename "$base.json")]($(basename "$base.json")). Tables rendered by"
    echo "\`hmsm bench --render\`; the model behind bytes and % of copy is in [README.md](README.md)."
    echo
    "$hmsm" bench --render "$result" | sed '1s/^## /## Run: /'
    echo
    echo "## Analysis"
    echo
    echo "_Where each step's time goes (per-pass table), how far each case is from the roofline"
    echo "(% of copy), and the next optimisations that would close the gap._"
} > "$base.md"
echo "$base.md"
echo "$base.json"
