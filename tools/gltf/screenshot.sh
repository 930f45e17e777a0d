#!/usr/bin/env bash
# Renders an exported GLB with the three.js viewer (tools/gltf/viewer.html) in headless Chromium
# at a chosen clip time. Usage: tools/gltf/screenshot.sh FILE.glb OUT.png [TIME_S] [WxH]
# Serves the repository root on 127.0.0.1 for the page; needs chromium and tools/install_deps.sh's
# npm packages.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
glb="$(realpath "$1")"; png="$(realpath -m "$2")"; time="${3:-5}"; size="${4:-800x600}"
case "$glb" in "$root"/*) ;; *) echo "screenshot.sh: $1 must lie inside $root (served over HTTP)" >&2; exit 2;; esac
port=$((20000 + RANDOM % 20000))
python3 -m http.server -b 127.0.0.1 "$port" -d "$root" >/dev/null 2>&1 &
server=$!
trap 'kill "$server" 2>/dev/null' EXIT
for _ in $(seq 50); do
  python3 -c "import socket; socket.create_connection(('127.0.0.1', $port), 1)" 2>/dev/null && break
  sleep 0.1
done
url="http://127.0.0.1:$port/tools/gltf/viewer.html?file=/${glb#"$root"/}&t=$time&w=${size%x*}&h=${size#*x}"
chromium --headless --no-sandbox --disable-gpu-sandbox --use-gl=angle --use-angle=swiftshader \
  --enable-unsafe-swiftshader --hide-scrollbars --window-size="${size/x/,}" \
  --virtual-time-budget=20000 --screenshot="$png" "$url" 2>/dev/null
echo "$png"
