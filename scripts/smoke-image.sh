#!/usr/bin/env bash
# Smoke test of the satmesh image (scripts/build-image.sh) without a container engine:
# buildah runs satmesh-server from the image (chroot isolation, host loopback) with a data
# dir and an input root; checks /health and /processes, submits the small synthetic job
# with the image's own CLI, downloads its results, checks the job viewer (page, CesiumJS,
# live tileset), then stops the server. Exits non-zero
# on the first failure. Run as root.
#
#   scripts/smoke-image.sh [--tag localhost/satmesh:latest] [--port 18080] [--no-job]
#                          [--iterations 5] [--keep]
set -euo pipefail

tag="localhost/satmesh:latest"  # image to test
port=18080                      # loopback port of the server
job=1                           # 1: submit the small synthetic job and fetch its results
iterations=5                    # refinement iterations per level of that job (speed)
keep=0                          # 1: keep the work folder (data dir, inputs, logs)

usage() { sed -n '2,9p' "$0" | sed 's/^# \{0,1\}//'; exit 2; }
while [ $# -gt 0 ]; do
  case "$1" in
    --tag) tag="$2"; shift 2 ;;
    --port) port="$2"; shift 2 ;;
    --no-job) job=0; shift ;;
    --iterations) iterations="$2"; shift 2 ;;
    --keep) keep=1; shift ;;
    -h|--help) usage ;;
    *) echo "smoke-image: unknown argument '$1'" >&2; usage ;;
  esac
done
[ "$(id -u)" -eq 0 ] || { echo "smoke-image: run as root (buildah)" >&2; exit 2; }

url="http://127.0.0.1:$port"
work="$(mktemp -d /tmp/satmesh-smoke.XXXXXX)"
mkdir "$work/data" "$work/inputs"
chown 10001 "$work/data" "$work/inputs"  # the image's non-root user
srv="" cli="" server_pid=""

fail() { echo "smoke-image: FAIL: $*" >&2; [ -f "$work/server.log" ] && tail -20 "$work/server.log" >&2; exit 1; }
# body_has URL PATTERN: GET URL succeeds and its body contains PATTERN. The body is read
# whole first: `curl | grep -q` fails under pipefail when grep leaves before curl has
# written everything (curl: (23) Failed writing body; CI, the viewer page).
body_has() { local body; body=$(curl -fsS "$1") && grep -qF -- "$2" <<<"$body"; }

# `buildah run` does not take its container's processes with it when killed: they live
# on as orphans, and the server keeps the port. So the server runs in a process group of
# its own (setsid), and stopping it ends the whole group, whatever state it is in.
server_process() {  # the satmesh-server process of that group, if any
  local p
  for p in $(pgrep -g "$server_pid" || true); do
    [ "$(cat /proc/"$p"/comm 2>/dev/null)" = "satmesh-server" ] && { echo "$p"; return 0; }
  done
  return 0
}

group_alive() { pgrep -g "$server_pid" >/dev/null 2>&1; }

stop_server() {
  [ -n "$server_pid" ] || return 0
  local p; p="$(server_process)"
  # SIGTERM to the server (its graceful stop), then up to 10 s for the group to end.
  if [ -n "$p" ]; then kill -TERM "$p" 2>/dev/null || true; else kill -TERM -- -"$server_pid" 2>/dev/null || true; fi
  for _ in $(seq 50); do group_alive || break; sleep 0.2; done
  if group_alive; then
    echo "smoke-image: the server did not stop in 10 s on SIGTERM; killing its process group" >&2
    kill -KILL -- -"$server_pid" 2>/dev/null || true
    for _ in $(seq 25); do group_alive || break; sleep 0.2; done
  fi
  wait "$server_pid" 2>/dev/null || true
  group_alive && { echo "smoke-image: ERROR: processes of the server's group $server_pid survive: $(pgrep -g "$server_pid" | tr '\n' ' ')" >&2; return 1; }
  server_pid=""
}

# Runs on every exit (success, fail, set -e, SIGINT/SIGTERM): stops the server, removes
# the containers, and fails loudly if the port still answers afterwards. set +e and the
# explicit `return 0`s matter: in a function called from an EXIT trap a bare `return`
# returns the status the script exits with, so after `fail` (exit 1) the old stop_server
# died under set -e at `p="$(server_process ...)"` and left the server running.
cleanup() {
  local rc=$? stopped=0
  set +e
  trap - EXIT INT TERM
  stop_server && stopped=1
  for c in $srv $cli; do buildah rm "$c" >/dev/null 2>&1 || true; done
  if [ "$keep" -eq 1 ]; then echo "smoke-image: kept $work"; else rm -rf "$work"; fi
  if [ "$stopped" -ne 1 ] || { [ "$started" -eq 1 ] && curl -s -o /dev/null --max-time 2 "$url/health"; }; then
    echo "smoke-image: ERROR: the server from the image still runs or port $port still answers after cleanup" >&2
    [ "$rc" -ne 0 ] || rc=1
  fi
  exit "$rc"
}
started=0  # 1 once this run started a server (the port was free before)
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

buildah inspect --type image "$tag" >/dev/null 2>&1 || fail "no image $tag (run scripts/build-image.sh)"
srv=$(buildah from --pull=never "$tag")
cli=$(buildah from --pull=never "$tag")
in_client() { buildah run --isolation chroot -v "$work/inputs:/inputs" "$cli" -- "$@"; }

echo "smoke-image: user $(buildah run --isolation chroot "$srv" -- id -un), $(in_client satmesh-server --help | head -1)"
curl -s -o /dev/null "$url/health" && fail "port $port is already in use"

setsid buildah run --isolation chroot -v "$work/data:/data" -v "$work/inputs:/inputs:ro" "$srv" -- \
  satmesh-server --host 127.0.0.1 --port "$port" --data-dir /data --data-root /inputs \
  --proto-dir /usr/local/share/satmesh/proto --workers 2 >"$work/server.log" 2>&1 &
server_pid=$!
started=1
if kill -0 "$server_pid" 2>/dev/null && [ "$(ps -o pgid= -p "$server_pid" | tr -d ' ')" != "$server_pid" ]; then
  fail "setsid did not give the server a process group of its own (pid $server_pid)"
fi
for _ in $(seq 100); do
  curl -fsS -o /dev/null "$url/health" 2>/dev/null && break
  kill -0 "$server_pid" 2>/dev/null || fail "the server exited"
  sleep 0.3
done
health=$(curl -fsS "$url/health") || fail "GET /health"
echo "smoke-image: GET /health -> $health"
body_has "$url/processes" '"refine-mesh"' || fail "GET /processes does not list refine-mesh"
echo "smoke-image: GET /processes lists refine-mesh"

if [ "$job" -eq 1 ]; then
  # Scene at the input root: the job's relative hrefs resolve against the server's data root.
  in_client satmesh synth --preset small --out /inputs >"$work/synth.log" 2>&1 || fail "satmesh synth"
  [ -f "$work/inputs/job.json" ] || fail "synth wrote no job.json"
  id=$(in_client satmesh submit /inputs/job.json --server "$url" --wait --quiet \
       --set "options.iterations_per_level=$iterations" 2>"$work/submit.log") \
    || { cat "$work/submit.log" >&2; fail "job did not succeed"; }
  echo "smoke-image: job $id: $(tail -1 "$work/submit.log")"
  in_client satmesh results "$id" --server "$url" --out /inputs/result >"$work/results.log" 2>&1 \
    || { cat "$work/results.log" >&2; fail "satmesh results"; }
  for f in tileset.json metrics.json preview.png convergence.png viewer.html; do
    [ -s "$work/inputs/result/$f" ] || fail "results: no $f"
  done
  ls "$work/inputs/result/tiles/"*.glb >/dev/null 2>&1 || fail "results: no tiles/*.glb"
  [ "$(stat -c %u "$work/data/jobs" 2>/dev/null || stat -c %u "$work/data")" = 10001 ] \
    || fail "the server did not write its data as uid 10001"
  echo "smoke-image: results: $(ls "$work/inputs/result" | tr '\n' ' ')"
  # The job viewer: its page, the CesiumJS the image carries, the live tileset.
  body_has "$url/jobs/$id/viewer" 'Cesium.js' || fail "GET /jobs/$id/viewer"
  cesium_bytes=$(curl -fsS "$url/viewer/Cesium/Cesium.js" | wc -c) || fail "GET /viewer/Cesium/Cesium.js"
  [ "$cesium_bytes" -gt 1000000 ] || fail "/viewer/Cesium/Cesium.js has $cesium_bytes bytes"
  body_has "$url/jobs/$id/tileset.json" '"tiles_done"' || fail "GET /jobs/$id/tileset.json"
  echo "smoke-image: viewer page, CesiumJS ($cesium_bytes bytes) and live tileset served"
fi

stop_server || fail "cannot stop the server"
curl -s -o /dev/null --max-time 2 "$url/health" && fail "port $port still answers after the server stopped"
echo "smoke-image: OK ($tag)"
