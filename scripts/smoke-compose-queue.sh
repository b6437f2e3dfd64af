#!/usr/bin/env bash
# Smoke test of docker/compose-redis.yaml with podman-compose (issue 22): brings up Redis
# (Debian's redis-server from localhost/satmesh-redis, AOF on), one API node and two
# workers from the images scripts/build-image.sh made (--no-build: nothing is pulled),
# writes the small synthetic scene into the inputs folder with the image's CLI, submits
# it cut into tiles, waits for success, downloads and checks the results, checks that
# both workers refined tiles, and takes the stack down (containers, volumes, network) on
# every exit. Exits non-zero on the first failure. Run as root.
#
#   scripts/smoke-compose-queue.sh [--tag localhost/satmesh:latest]
#       [--redis-tag localhost/satmesh-redis:latest] [--port 18083] [--iterations 3]
#       [--tile-size-m 20] [--timeout-s 120] [--keep-logs DIR]
#
# The services find each other by name (redis, api): podman needs its netavark network
# backend with aardvark-dns (installed here when missing; CNI has no DNS on Debian 12).
# Podman settings go in the file CONTAINERS_CONF names; default docker/podman-sandbox.conf
# (netavark, runc, lower rlimits: docker/README.md).
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
# shellcheck source=lib/compose-smoke.sh
source "$here/scripts/lib/compose-smoke.sh"

tag="localhost/satmesh:latest"              # the satmesh image (API node and workers)
redis_tag="localhost/satmesh-redis:latest"  # the Redis image (docker/redis.Dockerfile)
port=18083                                  # loopback port of the API node
iterations=3                                # refinement iterations per level (speed)
tile_size_m=20                              # tile size: the small scene in 16 tiles
timeout_s=120                               # the job must end within this, s
keep_logs=""                                # folder to copy the containers' logs to

usage() { sed -n '2,12p' "$0" | sed 's/^# \{0,1\}//'; exit 2; }
while [ $# -gt 0 ]; do
  case "$1" in
    --tag) tag="$2"; shift 2 ;;
    --redis-tag) redis_tag="$2"; shift 2 ;;
    --port) port="$2"; shift 2 ;;
    --iterations) iterations="$2"; shift 2 ;;
    --tile-size-m) tile_size_m="$2"; shift 2 ;;
    --timeout-s) timeout_s="$2"; shift 2 ;;
    --keep-logs) keep_logs="$2"; shift 2 ;;
    -h|--help) usage ;;
    *) echo "smoke-compose-queue: unknown argument '$1'" >&2; usage ;;
  esac
done
[ "$(id -u)" -eq 0 ] || { echo "smoke-compose-queue: run as root (podman)" >&2; exit 2; }
# Absolute: podman-compose runs podman from the compose file's folder.
CONTAINERS_CONF="$(realpath "${CONTAINERS_CONF:-$here/docker/podman-sandbox.conf}")"
export CONTAINERS_CONF

# Host tools (not project dependencies), installed when missing, as build-image.sh does.
missing=""
for p in podman podman-compose runc netavark aardvark-dns curl python3; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
if [ -n "$missing" ]; then
  echo "smoke-compose-queue: installing host tools:$missing"
  export DEBIAN_FRONTEND=noninteractive
  { apt-get install -y -qq --no-install-recommends $missing >/dev/null 2>&1 \
    || { apt-get update -qq && apt-get install -y -qq --no-install-recommends $missing >/dev/null; }; } \
    || { echo "smoke-compose-queue: cannot install$missing" >&2; exit 2; }
fi
backend=$(podman info --format '{{.Host.NetworkBackend}}' 2>/dev/null || true)
[ "$backend" = netavark ] || {
  echo "smoke-compose-queue: podman's network backend is '$backend', not netavark: the services" \
       "could not find each other by name. Set network_backend = \"netavark\" in $CONTAINERS_CONF" >&2
  exit 2
}

t0=$SECONDS
url="http://127.0.0.1:$port"
project="satmesh-queue-$port"
work="$(mktemp -d /tmp/satmesh-compose-queue.XXXXXX)"
mkdir "$work/inputs"
chown 10001 "$work/inputs"  # the image's non-root user writes the scene there
SATMESH_TOKEN="smoke-$(od -An -N8 -tx8 /dev/urandom | tr -d ' ')"
export SATMESH_INPUTS="$work/inputs" SATMESH_PORT="$port" SATMESH_TOKEN
export SATMESH_IMAGE="$tag" SATMESH_REDIS_IMAGE="$redis_tag"
compose() { podman-compose -p "$project" -f "$here/docker/compose-redis.yaml" "$@"; }
containers() { podman ps -a --filter "label=io.podman.compose.project=$project" --format '{{.Names}}'; }
up=0

logs() {  # every container's log into $work/logs/NAME.log
  mkdir -p "$work/logs"
  local c
  for c in $(containers); do podman logs "$c" >"$work/logs/$c.log" 2>&1 || true; done
}
fail() {
  echo "smoke-compose-queue: FAIL: $*" >&2
  if [ "$up" -eq 1 ]; then
    logs
    for f in "$work"/logs/*.log; do echo "--- $(basename "$f")" >&2; tail -8 "$f" >&2; done
  fi
  exit 1
}
cleanup() {
  local rc=$?
  set +e
  trap - EXIT INT TERM
  if [ "$up" -eq 1 ]; then
    [ -z "$keep_logs" ] || { logs; mkdir -p "$keep_logs" && cp "$work"/logs/*.log "$keep_logs"/; }
    compose down -v -t 5 >"$work/down.log" 2>&1 || { cat "$work/down.log" >&2; rc=1; }
    # podman-compose 1.0.3 leaves the project's network behind.
    podman network rm -f "${project}_default" >/dev/null 2>&1
    if [ -n "$(containers)" ]; then
      echo "smoke-compose-queue: ERROR: containers left after 'podman-compose down': $(containers | tr '\n' ' ')" >&2
      rc=1
    fi
    if curl -s -o /dev/null --max-time 2 "$url/health"; then
      echo "smoke-compose-queue: ERROR: port $port still answers after 'podman-compose down'" >&2
      rc=1
    fi
  fi
  rm -rf "$work"
  echo "smoke-compose-queue: $([ "$rc" -eq 0 ] && echo OK || echo FAILED) in $((SECONDS - t0)) s"
  exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

for image in "$tag" "$redis_tag"; do
  podman image exists "$image" || fail "no image $image (run scripts/build-image.sh)"
done
compose_smoke_preflight
[ -z "$(containers)" ] || fail "compose project $project has containers already: $(containers | tr '\n' ' ')"

compose_smoke_up_with_small_scene
echo "smoke-compose-queue: up in $((SECONDS - t0)) s: $(containers | tr '\n' ' '); GET /health -> $health"
aof=$(podman exec "${project}_redis_1" redis-cli config get appendonly | tail -1)
[ "$aof" = yes ] || fail "redis: appendonly is '$aof', not yes"

t_job=$SECONDS
id=$(timeout "$timeout_s" podman run --rm --no-healthcheck --network host -e SATMESH_TOKEN \
       -v "$work/inputs:/inputs" --entrypoint satmesh "$tag" \
       submit /inputs/job.json --server "$url" --wait --quiet \
       --set "options.iterations_per_level=$iterations" --set "tiling.size_m=$tile_size_m" \
       2>"$work/submit.log") \
  || { cat "$work/submit.log" >&2; fail "the job did not succeed through the queue within $timeout_s s"; }
echo "smoke-compose-queue: job $id in $((SECONDS - t_job)) s: $(tail -1 "$work/submit.log")"
tiles=$(curl -fsS -H "Authorization: Bearer $SATMESH_TOKEN" "$url/jobs/$id/tiles") || fail "GET /jobs/$id/tiles"
read -r total done_ <<<"$(python3 -c 'import json,sys; t=json.load(sys.stdin)["tiles"]; print(len(t), sum(x.get("status")=="done" for x in t))' <<<"$tiles")"
[ "$total" -ge 4 ] && [ "$total" = "$done_" ] || fail "tiles: $done_ of $total done (want >= 4, all done)"
cli results "$id" --server "$url" --out /inputs/result >"$work/results.log" 2>&1 \
  || { cat "$work/results.log" >&2; fail "satmesh results"; }
for f in tileset.json metrics.json mesh.ply; do
  [ -s "$work/inputs/result/$f" ] || fail "results: no $f"
done
ls "$work/inputs/result/tiles/"*.glb >/dev/null 2>&1 || fail "results: no tiles/*.glb"

# Both workers refined tiles: their logs name each tile they finished ("job ID tile X done").
per_worker=""
for w in "${project}_worker_1" "${project}_worker_2"; do
  n=$(podman logs "$w" 2>&1 | grep -c "job $id tile .* done" || true)
  [ "$n" -ge 1 ] || fail "worker $w refined no tile of job $id"
  per_worker="$per_worker $w: $n"
done
# Acknowledged tiles leave the stream (the last XACK follows the job's end by a moment).
for _ in $(seq 50); do
  stream=$(podman exec "${project}_redis_1" redis-cli xlen satmesh:tiles)
  [ "$stream" = 0 ] && break
  sleep 0.1
done
[ "$stream" = 0 ] || fail "the stream satmesh:tiles holds $stream entries after the job (want 0: trimmed)"
echo "smoke-compose-queue: $done_/$total tiles done; tiles per worker:$per_worker; stream length after: $stream"
echo "smoke-compose-queue: results: $(ls "$work/inputs/result" | tr '\n' ' ')"
