#!/usr/bin/env bash
# The hardening build (RELIABILITY.md): clang 14 with AddressSanitizer + UndefinedBehavior-
# Sanitizer and libFuzzer instrumentation into ./build-asan, then
#  1. the sanitized unit tests: the suites that parse or check outside input and serve it
#     (rpc, mesh, the server with its job parsing and path checks, against its stub engine);
#     the refinement's numerics are left to the normal build (minutes under ASan)
#  2. every fuzz target of tests/fuzz over its committed corpus (seeds + regressions: a
#     crash found once stays fixed), then FUZZ_S seconds of new fuzzing each
#     (default 60, the issue's CI run; 0 = corpus only), P targets at a time (default 2,
#     CI's two cores; 1 on a machine shared with others)
#   scripts/sanitize.sh [--fuzz-seconds N] [--fuzz-parallel P] [--seeds] [--no-tests]
# --seeds rewrites the seed corpora from our writers (tests/fuzz/corpus/<target>/).
# Needs clang-14, libfuzzer-14-dev, libomp-14-dev (docker/deps-debian12-test.txt).
# Fuzzing finds are written to build-asan/fuzz-findings/<target>/; a find fails the run.
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
fuzz_s=60 fuzz_parallel=2 seeds=0 tests=1
while [ $# -gt 0 ]; do
  case "$1" in
    --fuzz-seconds) fuzz_s="$2"; shift 2 ;;
    --fuzz-parallel) fuzz_parallel="$2"; shift 2 ;;
    --seeds) seeds=1; shift ;;
    --no-tests) tests=0; shift ;;
    *) echo "usage: scripts/sanitize.sh [--fuzz-seconds N] [--fuzz-parallel P] [--seeds] [--no-tests]" >&2; exit 2 ;;
  esac
done
build="$here/build-asan"
targets_fuzz=(fuzz_ply fuzz_obj fuzz_drc fuzz_glb fuzz_rpc_text fuzz_geotiff fuzz_job_json fuzz_http)
# Not tiling_test: it needs the synthetic scene generator (a fifth of the build) for its
# fixtures; its input checks run in the normal build.
targets_test=(rpc_test mesh_test server_test)
t0=$SECONDS
cmake -S "$here" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Sanitize \
  -DCMAKE_CXX_COMPILER=clang++-14 -DCMAKE_CXX_FLAGS_SANITIZE="-O1 -gline-tables-only" \
  -DSATMESH_FUZZ=ON >/dev/null
cmake --build "$build" -j "$(nproc)" --target "${targets_fuzz[@]}" $([ "$seeds" = 1 ] && echo fuzz_seeds) \
  $([ "$tests" = 1 ] && echo "${targets_test[@]}")
echo "sanitize: build $((SECONDS - t0)) s"

export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:allocator_may_return_null=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
export LSAN_OPTIONS="suppressions=$here/tests/fuzz/lsan.supp"
corpus="$here/tests/fuzz/corpus"
if [ "$seeds" = 1 ]; then "$build/tests/fuzz/fuzz_seeds" "$corpus"; fi

if [ "$tests" = 1 ]; then
  t1=$SECONDS
  # TiledJob/EndToEnd refine scenes: the normal build runs them.
  ctest --test-dir "$build" --output-on-failure -j "$(nproc)" \
    -R '^(RpcModel|ReadRpc|FitRpc|RpcFitOptions|GdalRpcTransformer|ReadMesh|FuzzRegression|MalformedPly|WriteGlb|WriteMesh|MeshWriteOptions|ValidateMesh|TriangleMesh|ProblemFromException|ResolveHrefs|JobStore|ServerOptions|Api|Malformed|Load|Process)\.'
  echo "sanitize: tests $((SECONDS - t1)) s"
fi

t2=$SECONDS
findings="$build/fuzz-findings"
rm -rf "$findings"
run_one() {
  local target="$1" dir="$corpus/${1#fuzz_}" work="$build/fuzz-work/${1#fuzz_}" out="$findings/$1"
  mkdir -p "$work" "$out"
  # The committed corpus (seeds, regressions) first: every input must pass.
  "$build/tests/fuzz/$target" -rss_limit_mb=2048 -timeout=10 "$dir" -runs=0 >"$out/corpus.log" 2>&1 \
    || { echo "sanitize: $target FAILS on its committed corpus (log: $out/corpus.log)"; return 1; }
  local seconds="$fuzz_s"
  if [ "$seconds" -gt 0 ]; then
    "$build/tests/fuzz/$target" -rss_limit_mb=2048 -timeout=10 -max_total_time="$seconds" -print_final_stats=1 \
      -artifact_prefix="$out/" "$work" "$dir" >"$out/fuzz.log" 2>&1 \
      || { echo "sanitize: $target found a crash: $(ls "$out" | grep -v log | head -1) (log: $out/fuzz.log)"; return 1; }
    echo "sanitize: $target: $(grep -E '^stat::number_of_executed_units' "$out/fuzz.log" | awk '{print $2}') runs in ${seconds} s, $(grep -oE 'cov: [0-9]+' "$out/fuzz.log" | tail -1)"
  fi
}
export -f run_one
export build corpus findings fuzz_s
printf '%s\n' "${targets_fuzz[@]}" | xargs -P "$fuzz_parallel" -I{} bash -c 'run_one {}'
echo "sanitize: fuzz $((SECONDS - t2)) s ($fuzz_parallel at a time); total $((SECONDS - t0)) s"
