#!/usr/bin/env bash
# End-to-end run as an unprivileged user from an unwritable current directory (issue 17),
# as the container image, a systemd service or `cd / && satmesh refine ...` run it:
#  1. `satmesh synth --preset small`, then `satmesh refine job.json --out DIR`;
#  2. satmesh-server on a loopback port, the job submitted with `satmesh submit --wait`,
#     its results fetched with `satmesh results`.
# Both run as nobody:nogroup with `cd /`, on the synthetic initial DSM, which has NaN
# holes: each run must log that it filled them (the GDALFillNodata path), succeed, and
# write nothing outside its work folder. Needs root to drop privileges (setpriv); exits
# 77 (ctest SKIP_RETURN_CODE) with the reason when not root.
#
#   unprivileged_run_test.sh SATMESH SATMESH_SERVER PROTO_DIR
set -euo pipefail

[ $# -eq 3 ] || { echo "usage: $0 SATMESH SATMESH_SERVER PROTO_DIR" >&2; exit 2; }
satmesh_bin="$1" server_bin="$2" proto_dir="$3"
iterations=3  # refinement iterations per level: a short run still goes through every stage

skip() { echo "unprivileged_run_test: SKIPPED: $*" >&2; exit 77; }
fail() { echo "unprivileged_run_test: FAIL: $*" >&2; exit 1; }

[ "$(id -u)" -eq 0 ] || skip "not root (uid $(id -u)): cannot drop privileges to nobody"
command -v setpriv >/dev/null || skip "setpriv (util-linux) is not installed"
id nobody >/dev/null 2>&1 && getent group nogroup >/dev/null || skip "no user nobody / group nogroup"
for f in "$satmesh_bin" "$server_bin"; do [ -x "$f" ] || fail "no executable $f"; done
[ -f "$proto_dir/openapi.json" ] || fail "no $proto_dir/openapi.json"

# Everything the run may write lives in $work, owned by nobody. The binaries and proto/
# are copied there: the build tree may sit under a folder nobody cannot enter (/root).
work="$(mktemp -d /tmp/satmesh-unpriv.XXXXXX)"
server_pid=""
cleanup() {
  local rc=$?
  set +e  # under set -e a failing command would end the handler before the server stops
  if [ -n "$server_pid" ]; then
    kill -TERM "$server_pid" 2>/dev/null || true
    for _ in $(seq 50); do kill -0 "$server_pid" 2>/dev/null || break; sleep 0.1; done
    kill -KILL "$server_pid" 2>/dev/null || true
    wait "$server_pid" 2>/dev/null || true
  fi
  rm -rf "$work"
  exit "$rc"
}
trap cleanup EXIT
mkdir "$work/bin" "$work/scene" "$work/data"
cp "$satmesh_bin" "$server_bin" "$work/bin/"
cp -r "$proto_dir" "$work/proto"
chmod -R a+rX "$work"
chown nobody:nogroup "$work/scene" "$work/data"
chmod 755 "$work"  # nobody reads it but cannot write in it
satmesh="$work/bin/$(basename "$satmesh_bin")"
server="$work/bin/$(basename "$server_bin")"
touch "$work/start"

# Runs "$@" as nobody:nogroup with / as its current directory and a minimal environment.
nobody_cmd=(setpriv --reuid=nobody --regid=nogroup --clear-groups --
            env -i PATH=/usr/bin:/bin HOME=/nonexistent LANG=C.UTF-8)
as_nobody() { (cd / && exec "${nobody_cmd[@]}" "$@"); }
as_nobody sh -c 'test "$(id -un)" = nobody' || fail "setpriv did not switch to nobody"
if as_nobody sh -c ': > ./satmesh-unpriv-probe' 2>/dev/null; then
  rm -f /satmesh-unpriv-probe
  fail "/ is writable by nobody here: the test would not exercise an unwritable cwd"
fi

# Exits with the log's tail unless the log shows the DSM's holes were filled.
expect_filled() {
  grep -qE 'empty DSM cells \([0-9.]+%\) filled' "$1" \
    || { tail -20 "$1" >&2; fail "$2: no 'empty DSM cells ... filled' in its log: the hole filling did not run"; }
}

echo "unprivileged_run_test: as nobody from /, work folder $work"
t0=$SECONDS
as_nobody "$satmesh" synth --preset small --out "$work/scene" >"$work/synth.log" 2>&1 \
  || { tail -20 "$work/synth.log" >&2; fail "satmesh synth"; }
[ -f "$work/scene/job.json" ] || fail "synth wrote no job.json"

# 1. The CLI.
as_nobody "$satmesh" refine "$work/scene/job.json" --out "$work/scene/cli-out" \
  --set "iterations_per_level=$iterations" >"$work/refine.log" 2>&1 \
  || { tail -20 "$work/refine.log" >&2; fail "satmesh refine as nobody from /"; }
expect_filled "$work/refine.log" "satmesh refine"
for f in tileset.json metrics.json; do
  [ -s "$work/scene/cli-out/$f" ] || fail "satmesh refine wrote no $f"
done
ls "$work/scene/cli-out/tiles/"*.glb >/dev/null 2>&1 || fail "satmesh refine wrote no tiles/*.glb"
echo "unprivileged_run_test: CLI refine OK ($((SECONDS - t0)) s)"

# 2. The server, on a free loopback port below the kernel's ephemeral range: a port in that
# range can be taken between the probe and the server's bind by the local end of another
# test's connection (ctest -j2; CI once failed "cannot listen on 127.0.0.1:38904").
port=""
ephemeral_low=$(cut -f1 /proc/sys/net/ipv4/ip_local_port_range 2>/dev/null || echo 32768)
[ "$ephemeral_low" -gt 21000 ] 2>/dev/null || ephemeral_low=32768  # an unusual range: Linux's default
for p in $(shuf -i 20000-$((ephemeral_low - 1)) -n 20); do
  (exec 3<>"/dev/tcp/127.0.0.1/$p") 2>/dev/null || { port=$p; break; }
done
[ -n "$port" ] || fail "no free loopback port found"
url="http://127.0.0.1:$port"
# One subshell that execs (setpriv and env exec too): $! is the server's own pid, so that
# cleanup stops the server (a function run with & would fork twice, and the kill would
# reach a shell, leaving the server running).
(cd / && exec "${nobody_cmd[@]}" "$server" --host 127.0.0.1 --port "$port" --data-dir "$work/data" \
  --data-root "$work/scene" --proto-dir "$work/proto" --workers 1) >"$work/server.log" 2>&1 &
server_pid=$!
ready=0
for _ in $(seq 100); do
  kill -0 "$server_pid" 2>/dev/null || { cat "$work/server.log" >&2; fail "satmesh-server exited"; }
  (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null && { ready=1; break; }
  sleep 0.1
done
[ "$ready" -eq 1 ] || fail "satmesh-server does not listen on $url after 10 s"
[ "$(readlink /proc/"$server_pid"/exe)" = "$server" ] \
  || fail "pid $server_pid is not the server ($(readlink /proc/"$server_pid"/exe)): cleanup would not stop it"

id=$(as_nobody "$satmesh" submit "$work/scene/job.json" --server "$url" --wait --quiet \
       --set "options.iterations_per_level=$iterations" 2>"$work/submit.log") \
  || { cat "$work/submit.log" >&2; tail -20 "$work/server.log" >&2; fail "the job did not succeed on the server"; }
expect_filled "$work/server.log" "satmesh-server"
as_nobody "$satmesh" results "$id" --server "$url" --out "$work/scene/server-out" >"$work/results.log" 2>&1 \
  || { cat "$work/results.log" >&2; fail "satmesh results $id"; }
for f in tileset.json metrics.json; do
  [ -s "$work/scene/server-out/$f" ] || fail "satmesh results wrote no $f"
done
ls "$work/scene/server-out/tiles/"*.glb >/dev/null 2>&1 || fail "satmesh results wrote no tiles/*.glb"
echo "unprivileged_run_test: server job $id OK ($((SECONDS - t0)) s)"

# Nothing written as nobody outside the work folder (the temp dir included). Checked
# before the server stops, so it covers the server's lifetime up to here.
# find exits non-zero when files vanish under it (tests running in parallel remove their
# temp dirs): that is not a finding, so only its output counts (pipefail would end the
# script here). Other runs of this test on the machine (another checkout's ctest) write
# as nobody into their own /tmp/satmesh-unpriv.* folders: not ours, not a finding.
stray=$( { find /tmp /var/tmp /dev/shm -xdev -user nobody -newer "$work/start" \
             -not -path "$work" -not -path "$work/*" \
             -not -path "/tmp/satmesh-unpriv.*" 2>/dev/null || true; } | head -5)
[ -z "$stray" ] || fail "files written as nobody outside $work: $stray"
echo "unprivileged_run_test: OK"
