#!/usr/bin/env bash
# The job viewer in Debian's headless Chromium (web/tools/viewer-check.mjs, puppeteer-core):
#  1. satmesh-server on loopback (with a bearer token) runs a small synthetic job in 2 x 2
#     tiles; its /jobs/{id}/viewer#token=T page, opened while the job runs, must load every
#     tile with no console error and no request off the server, and show shaded relief
#     (luminance spread of the city lit vs unlit);
#  2. the same page as `satmesh refine` writes it (DIR/viewer.html + DIR/Cesium), served by
#     a plain static file server (python3 -m http.server).
# Skipped (exit 77) only where chromium or web/node_modules is absent.
#   viewer_test.sh SATMESH SATMESH_SERVER WEB_DIR
# SATMESH_VIEWER_SCREENSHOTS=DIR keeps the screenshots (server.png, static.png).
set -euo pipefail
satmesh="$1" server="$2" web="$3"
chromium="${CHROMIUM:-$(command -v chromium || true)}"
if [ -z "$chromium" ]; then
  echo "SKIP: no chromium on this machine (Debian package chromium; scripts/install-deps.sh installs it)"
  exit 77
fi
if ! command -v node >/dev/null || [ ! -d "$web/node_modules/puppeteer-core" ]; then
  echo "SKIP: node or $web/node_modules/puppeteer-core missing (run scripts/install-deps.sh)"
  exit 77
fi
export CHROMIUM="$chromium"
work="$(mktemp -d)"
shots="${SATMESH_VIEWER_SCREENSHOTS:-$work}"
mkdir -p "$shots"
server_pid="" http_pid=""
cleanup() {
  local rc=$?
  for pid in $server_pid $http_pid; do kill "$pid" 2>/dev/null || true; wait "$pid" 2>/dev/null || true; done
  rm -rf "$work"
  exit "$rc"
}
trap cleanup EXIT

"$satmesh" synth --preset small --out "$work/scene" >/dev/null
tiling=(--set tiling.size_m=40 --set tiling.overlap_m=8 --set iterations_per_level=4)

# 1. The server's page, on a server with a token (the page sends it: #token=).
export SATMESH_TOKEN="viewer-test-token"
"$server" --port 0 --data-dir "$work/data" --data-root "$work/scene" --workers 1 >"$work/server.out" 2>"$work/server.log" &
server_pid=$!
for _ in $(seq 100); do grep -q "listening on port" "$work/server.out" 2>/dev/null && break; sleep 0.1; done
port=$(sed -n 's/^listening on port \([0-9]*\)$/\1/p' "$work/server.out")
[ -n "$port" ] || { cat "$work/server.log"; echo "FAIL: the server did not start"; exit 1; }
# The page opened while the job runs (one worker, 20 iterations a level: some seconds a
# tile): tiles appear as they finish; the states it went through are printed.
id=$("$satmesh" submit "$work/scene/job.json" --server "http://127.0.0.1:$port" --set tiling.size_m=40 \
     --set tiling.overlap_m=8)
echo "job $id submitted on port $port"
node "$web/tools/viewer-check.mjs" "http://127.0.0.1:$port/jobs/$id/viewer#token=$SATMESH_TOKEN" 4 "$shots/server.png" | tee "$work/check.json"
grep -qE '"[0-9.]+s running [123]/4"' "$work/check.json" && echo "tiles appeared while the job ran" \
  || echo "note: the job finished before the page showed a partial state"

# 2. The page `satmesh refine` writes, through a static file server.
"$satmesh" refine "$work/scene/job.json" --out "$work/out" "${tiling[@]}" >/dev/null 2>&1
[ -f "$work/out/viewer.html" ] && [ -f "$work/out/Cesium/Cesium.js" ] || { echo "FAIL: refine wrote no viewer"; exit 1; }
for png in preview convergence; do
  [ "$(head -c 4 "$work/out/$png.png" | tail -c 3)" = PNG ] || { echo "FAIL: refine wrote no $png.png"; exit 1; }
done
if ! command -v python3 >/dev/null; then
  echo "note: no python3 for a static file server: the static page is not checked"
  exit 0
fi
# A port below the kernel's ephemeral range, which the local ends of other tests'
# connections take from (ctest -j2): as e2e_unprivileged_run picks its server's.
ephemeral_low=$(cut -f1 /proc/sys/net/ipv4/ip_local_port_range 2>/dev/null || echo 32768)
[ "$ephemeral_low" -gt 21000 ] 2>/dev/null || ephemeral_low=32768  # an unusual range: Linux's default
http_port=$(( 20000 + RANDOM % (ephemeral_low - 20000) ))
python3 -m http.server "$http_port" --bind 127.0.0.1 --directory "$work/out" >"$work/http.log" 2>&1 &
http_pid=$!
for _ in $(seq 50); do python3 -c "import urllib.request as u; u.urlopen('http://127.0.0.1:$http_port/tileset.json')" 2>/dev/null && break; sleep 0.1; done
node "$web/tools/viewer-check.mjs" "http://127.0.0.1:$http_port/viewer.html" 4 "$shots/static.png"
