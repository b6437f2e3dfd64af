#!/usr/bin/env bash
# Smoke test of the image in its distributed roles (issue 22), without a container
# engine: a redis-server on the host's loopback (Debian's, as the tests use; AOF on),
# satmesh-server from the image as an API node (--queue) and two satmesh-worker
# processes from the image (buildah, chroot isolation, host loopback) sharing one data
# dir. The small synthetic job, cut into tiles, is submitted with the image's own CLI;
# it must succeed with every tile done by the workers, and its results download. Exits
# non-zero on the first failure. Run as root.
#
#   scripts/smoke-image-queue.sh [--tag localhost/satmesh:latest] [--port 18082] [--keep]
set -euo pipefail

tag="localhost/satmesh:latest"  # image to test
port=18082                      # loopback port of the API node
keep=0                          # 1: keep the work folder (data dir, inputs, logs)
while [ $# -gt 0 ]; do
  case "$1" in
    --tag) tag="$2"; shift 2 ;;
    --port) port="$2"; shift 2 ;;
    --keep) keep=1; shift ;;
    -h|--help) sed -n '2,9p' "$0" | sed 's/^# \{0,1\}//'; exit 2 ;;
    *) echo "smoke-image-queue: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
[ "$(id -u)" -eq 0 ] || { echo "smoke-image-queue: run as root (buildah)" >&2; exit 2; }
command -v redis-server >/dev/null || { echo "smoke-image-queue: redis-server is not installed (scripts/install-deps.sh installs it)" >&2; exit 2; }

url="http://127.0.0.1:$port"
work="$(mktemp -d /tmp/satmesh-smoke-queue.XXXXXX)"
mkdir "$work/data" "$work/inputs" "$work/redis"
chown 10001 "$work/data" "$work/inputs"  # the image's non-root user
groups=()      # process groups started here (setsid): each ends with its whole group
containers=()

fail() {
  echo "smoke-image-queue: FAIL: $*" >&2
  for log in "$work"/*.log; do [ -f "$log" ] && { echo "--- $log" >&2; tail -8 "$log" >&2; }; done
  exit 1
}

# start NAME CMD...: CMD in a process group of its own, output in $work/NAME.log.
start() {
  local name="$1"; shift
  setsid "$@" >"$work/$name.log" 2>&1 &
  groups+=("$!")
}

cleanup() {
  local rc=$?
  set +e
  trap - EXIT INT TERM
  for g in "${groups[@]}"; do kill -TERM -- -"$g" 2>/dev/null; done
  for g in "${groups[@]}"; do
    for _ in $(seq 50); do pgrep -g "$g" >/dev/null 2>&1 || break; sleep 0.2; done
    kill -KILL -- -"$g" 2>/dev/null
    wait "$g" 2>/dev/null
  done
  for c in "${containers[@]}"; do buildah rm "$c" >/dev/null 2>&1; done
  if [ "$keep" -eq 1 ]; then echo "smoke-image-queue: kept $work"; else rm -rf "$work"; fi
  if curl -s -o /dev/null --max-time 2 "$url/health"; then
    echo "smoke-image-queue: ERROR: port $port still answers after cleanup" >&2
    [ "$rc" -ne 0 ] || rc=1
  fi
  exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

buildah inspect --type image "$tag" >/dev/null 2>&1 || fail "no image $tag (run scripts/build-image.sh)"
curl -s -o /dev/null "$url/health" && fail "port $port is already in use"
redis_port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
queue="redis://127.0.0.1:$redis_port"
start redis redis-server --bind 127.0.0.1 --port "$redis_port" --dir "$work/redis" \
  --save '' --appendonly yes
for _ in $(seq 50); do redis-cli -p "$redis_port" ping >/dev/null 2>&1 && break; sleep 0.1; done
redis-cli -p "$redis_port" ping >/dev/null 2>&1 || fail "redis-server did not start"

container() { local c; c=$(buildah from --pull=never "$tag"); containers+=("$c"); echo "$c"; }
mounts=(-v "$work/data:/data" -v "$work/inputs:/inputs")
api=$(container); w1=$(container); w2=$(container); cli=$(container)
in_client() { buildah run --isolation chroot -v "$work/inputs:/inputs" "$cli" -- "$@"; }

start api buildah run --isolation chroot "${mounts[@]}" "$api" -- \
  satmesh-server --host 127.0.0.1 --port "$port" --data-dir /data --data-root /inputs \
  --proto-dir /usr/local/share/satmesh/proto --queue "$queue"
start worker1 buildah run --isolation chroot "${mounts[@]}" "$w1" -- \
  satmesh-worker --queue "$queue" --data-dir /data --name smoke-w1
start worker2 buildah run --isolation chroot "${mounts[@]}" "$w2" -- \
  satmesh-worker --queue "$queue" --data-dir /data --name smoke-w2
for _ in $(seq 100); do curl -fsS -o /dev/null "$url/health" 2>/dev/null && break; sleep 0.3; done
health=$(curl -fsS "$url/health") || fail "GET /health of the API node"
echo "smoke-image-queue: API node up: $health"

in_client satmesh synth --preset small --out /inputs >"$work/synth.log" 2>&1 || fail "satmesh synth"
id=$(in_client satmesh submit /inputs/job.json --server "$url" --wait --quiet \
     --set options.iterations_per_level=3 --set tiling.size_m=20 2>"$work/submit.log") \
  || fail "the job did not succeed through the queue"
echo "smoke-image-queue: job $id: $(tail -1 "$work/submit.log")"
tiles=$(curl -fsS "$url/jobs/$id/tiles") || fail "GET /jobs/$id/tiles"
read -r total done_ <<<"$(python3 -c 'import json,sys; t=json.load(sys.stdin)["tiles"]; print(len(t), sum(x.get("status")=="done" for x in t))' <<<"$tiles")"
[ "$total" -ge 2 ] && [ "$total" = "$done_" ] || fail "tiles: $done_ of $total done (want >= 2, all done): $tiles"
in_client satmesh results "$id" --server "$url" --out /inputs/result >"$work/results.log" 2>&1 || fail "satmesh results"
for f in tileset.json metrics.json mesh.ply; do [ -s "$work/inputs/result/$f" ] || fail "results: no $f"; done
n1=$(grep -c "done" "$work/worker1.log" || true); n2=$(grep -c "done" "$work/worker2.log" || true)
echo "smoke-image-queue: $total tiles done; worker log lines with 'done': w1 $n1, w2 $n2"
echo "smoke-image-queue: OK ($tag)"
