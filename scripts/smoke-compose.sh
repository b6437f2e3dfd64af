#!/usr/bin/env bash
# Smoke test of docker/compose.yaml with podman-compose: brings the stack up on a loopback
# port from the image built by scripts/build-image.sh (--no-build: building would pull
# debian:12-slim from a registry), writes the small synthetic scene into its inputs folder
# with the image's CLI, submits it to the stack with the image's CLI, downloads and checks
# the results, and takes the stack down with its volume on every exit. Run as root.
#
#   scripts/smoke-compose.sh [--tag localhost/satmesh:latest] [--port 18081] [--iterations 5]
#
# Podman settings this machine needs go in a file named by CONTAINERS_CONF (see
# docker/README.md: a sandbox without CAP_SYS_RESOURCE and with hybrid cgroups).
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
# shellcheck source=lib/compose-smoke.sh
source "$here/scripts/lib/compose-smoke.sh"

tag="localhost/satmesh:latest"  # image to run (compose.yaml names it satmesh:latest)
port=18081                      # loopback port of the stack
iterations=5                    # refinement iterations per level of the job (speed)

usage() { sed -n '2,8p' "$0" | sed 's/^# \{0,1\}//'; exit 2; }
while [ $# -gt 0 ]; do
  case "$1" in
    --tag) tag="$2"; shift 2 ;;
    --port) port="$2"; shift 2 ;;
    --iterations) iterations="$2"; shift 2 ;;
    -h|--help) usage ;;
    *) echo "smoke-compose: unknown argument '$1'" >&2; usage ;;
  esac
done
[ "$(id -u)" -eq 0 ] || { echo "smoke-compose: run as root (podman)" >&2; exit 2; }
# Absolute: podman-compose runs podman from the compose file's folder (a relative
# CONTAINERS_CONF, as docker/README.md writes it, was not found there).
if [ -n "${CONTAINERS_CONF:-}" ]; then CONTAINERS_CONF="$(realpath "$CONTAINERS_CONF")"; export CONTAINERS_CONF; fi
for t in podman podman-compose curl; do
  command -v "$t" >/dev/null || { echo "smoke-compose: $t is not installed (apt-get install podman podman-compose curl)" >&2; exit 2; }
done

url="http://127.0.0.1:$port"
project="satmesh-smoke-$port"
work="$(mktemp -d /tmp/satmesh-compose.XXXXXX)"
mkdir "$work/inputs"
chown 10001 "$work/inputs"  # the image's non-root user writes the scene there
# A token for the stack (compose.yaml passes SATMESH_TOKEN through), used by the CLI below.
SATMESH_TOKEN="smoke-$(od -An -N8 -tx8 /dev/urandom | tr -d ' ')"
export SATMESH_INPUTS="$work/inputs" SATMESH_PORT="$port" SATMESH_TOKEN
compose() { podman-compose -p "$project" -f "$here/docker/compose.yaml" "$@"; }
up=0

fail() {
  echo "smoke-compose: FAIL: $*" >&2
  [ "$up" -eq 1 ] && compose logs 2>/dev/null | tail -20 >&2
  exit 1
}
cleanup() {
  local rc=$?
  set +e
  trap - EXIT INT TERM
  if [ "$up" -eq 1 ]; then
    compose down -v >"$work/down.log" 2>&1 || { cat "$work/down.log" >&2; rc=1; }
    podman network rm -f "${project}_default" >/dev/null 2>&1  # podman-compose 1.0.3 leaves it
    if curl -s -o /dev/null --max-time 2 "$url/health"; then
      echo "smoke-compose: ERROR: port $port still answers after 'podman-compose down'" >&2
      rc=1
    fi
  fi
  rm -rf "$work"
  exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

podman image exists "$tag" || fail "no image $tag (run scripts/build-image.sh)"
# compose.yaml names the image satmesh:latest; podman resolves it to localhost/satmesh:latest.
[ "$tag" = localhost/satmesh:latest ] || podman tag "$tag" localhost/satmesh:latest
compose_smoke_preflight

compose_smoke_up_with_small_scene
echo "smoke-compose: GET /health -> $health"
code=$(curl -s -o /dev/null -w '%{http_code}' "$url/processes")
[ "$code" = 401 ] || fail "GET /processes without the token answered $code, not 401: the token did not reach the server"
echo "smoke-compose: GET /processes without the token -> 401"
id=$(cli submit /inputs/job.json --server "$url" --wait --quiet \
       --set "options.iterations_per_level=$iterations" 2>"$work/submit.log") \
  || { cat "$work/submit.log" >&2; fail "the job did not succeed"; }
echo "smoke-compose: job $id: $(tail -1 "$work/submit.log")"
cli results "$id" --server "$url" --out /inputs/result >"$work/results.log" 2>&1 \
  || { cat "$work/results.log" >&2; fail "satmesh results"; }
for f in tileset.json metrics.json; do
  [ -s "$work/inputs/result/$f" ] || fail "results: no $f"
done
ls "$work/inputs/result/tiles/"*.glb >/dev/null 2>&1 || fail "results: no tiles/*.glb"
echo "smoke-compose: results: $(ls "$work/inputs/result" | tr '\n' ' ')"
echo "smoke-compose: OK ($tag, compose project $project)"
