#!/bin/bash
# satmesh refine vs OpenMVS RefineMesh, both with default options, on one synthetic scene,
# evaluated the same way (issue 18). A manual benchmark: not part of ctest, CI has no
# OpenMVS. See tests/bench/README.md.
#
# usage: tests/bench/openmvs_side_by_side.sh SCENE_DIR
#        tests/bench/openmvs_side_by_side.sh PRESET VIEWS GSD SEED   (satmesh synth if needed)
# env:   OPENMVS_BIN  folder holding InterfaceCOLMAP and RefineMesh (required; else skipped)
#        SATMESH      the satmesh binary (default: build/client/satmesh of this checkout)
#        WORK         working folder (default /tmp/satmesh-openmvs); results in
#                     WORK/<scene name>/{satmesh,colmap,*.time,*.eval.json,*.log}
#        BENCH_LOCK   lock file taken around every timed run (default /tmp/satmesh-bench.lock)
#        SATMESH_SET  extra `--set key=value` arguments for satmesh refine (default none)
#        OPENMVS_INITIAL  dsm (default: the initial DSM as a full-resolution grid mesh) or
#                     coarse (the coarse mesh satmesh starts from), export-colmap --initial
#        OPENMVS_BIAS 1: give OpenMVS the RPC biases satmesh estimates (satmesh bias
#                     --write-job, untimed); default 0: the job's RPCs as they are
set -euo pipefail

repo=$(cd "$(dirname "$0")/../.." && pwd)
if [ -z "${OPENMVS_BIN:-}" ] || [ ! -x "$OPENMVS_BIN/RefineMesh" ] || [ ! -x "$OPENMVS_BIN/InterfaceCOLMAP" ]; then
  echo "skipped: no OpenMVS build (set OPENMVS_BIN)"
  exit 0
fi
SATMESH=${SATMESH:-$repo/build/client/satmesh}
WORK=${WORK:-/tmp/satmesh-openmvs}
BENCH_LOCK=${BENCH_LOCK:-/tmp/satmesh-bench.lock}
[ -x "$SATMESH" ] || { echo "no satmesh binary at $SATMESH (build it, or set SATMESH)" >&2; exit 1; }

if [ $# -eq 1 ]; then
  scene=$(cd "$1" && pwd)
elif [ $# -eq 4 ]; then
  scene=$WORK/scenes/$1_$2_$3_$4
  if [ ! -f "$scene/job.json" ]; then
    mkdir -p "$WORK/scenes"
    echo "== satmesh synth --preset $1 --views $2 --gsd $3 --seed $4"
    "$SATMESH" synth --preset "$1" --views "$2" --gsd "$3" --seed "$4" --out "$scene" --no-preview \
      > "$scene.synth.log" 2>&1
  fi
else
  sed -n '6,7p' "$0" >&2
  exit 2
fi
[ -f "$scene/job.json" ] || { echo "no job.json in $scene" >&2; exit 1; }
out=$WORK/$(basename "$scene")
rm -rf "$out"
mkdir -p "$out"

# timed NAME CMD...: CMD under the bench lock; wall, user, sys, peak RSS to $out/NAME.time.
timed() {
  local name=$1
  shift
  echo "== $name: $*"
  flock "$BENCH_LOCK" /usr/bin/time -f "%e %U %S %M" -o "$out/$name.time" "$@" > "$out/$name.log" 2>&1 ||
    { echo "$name failed (rc $?), log: $out/$name.log" >&2; tail -5 "$out/$name.log" >&2; exit 1; }
}

# 1. satmesh, defaults.
timed satmesh "$SATMESH" refine "$scene/job.json" --out "$out/satmesh" ${SATMESH_SET:-}

# 2. OpenMVS: pinholes fitted to the RPCs, 8-bit images, the initial DSM as a grid mesh.
export_job=$scene/job.json
if [ "${OPENMVS_BIAS:-0}" = 1 ]; then
  echo "== satmesh bias --job $scene/job.json --write-job $out/job_with_bias.json"
  "$SATMESH" bias --job "$scene/job.json" --write-job "$out/job_with_bias.json" > "$out/bias.log" 2>&1
  export_job=$out/job_with_bias.json
fi
timed export "$SATMESH" export-colmap "$export_job" --out "$out/colmap" \
  --initial "${OPENMVS_INITIAL:-dsm}"
timed interface "$OPENMVS_BIN/InterfaceCOLMAP" -w "$out/colmap" -i "$out/colmap" \
  -o "$out/colmap/scene.mvs" --image-folder "$out/colmap/images/"
timed refinemesh "$OPENMVS_BIN/RefineMesh" -w "$out/colmap" -i "$out/colmap/scene.mvs" \
  -m "$out/colmap/initial.ply" -o "$out/colmap/scene_refine.mvs"

# 3. One evaluation for all: the exported initial mesh (a check of the frame's round trip:
# it must score as the initial DSM does), OpenMVS's mesh, satmesh's.
echo "== eval"
frame=$out/colmap/frame.json
"$SATMESH" eval --scene "$scene" --result "$out/colmap/initial.ply" --frame "$frame" \
  --json "$out/initial.eval.json" > "$out/initial.eval.txt" 2>&1
"$SATMESH" eval --scene "$scene" --result "$out/colmap/scene_refine.ply" --frame "$frame" \
  --json "$out/openmvs.eval.json" > "$out/openmvs.eval.txt" 2>&1
"$SATMESH" eval --scene "$scene" --result "$out/satmesh" \
  --json "$out/satmesh.eval.json" > "$out/satmesh.eval.txt" 2>&1

python3 - "$out" "$scene" <<'EOF'
import json, os, re, sys
out, scene = sys.argv[1], sys.argv[2]

def metrics(name, which="result"):
    e = json.load(open(f"{out}/{name}.eval.json"))[which]
    roof = e["dsm"]["roof_mask"]["raw"]
    m3 = e["mesh3d"]
    return [f"{roof['nmad_m']:.3f}", f"{roof['perc68_m']:.3f}",
            f"{100 * m3['facade']['completeness']['0.5m']:.0f}%",
            f"{100 * m3['under_overhang']['completeness']['0.5m']:.1f}%",
            f"{100 * m3['all']['fscore']['0.5m']:.1f}",
            f"{m3['facade_offset']['median_m']:+.2f}"]

def timing(*names):
    wall = cpu = 0.0
    rss = 0
    for n in names:
        w, u, s, m = open(f"{out}/{n}.time").read().split()[-4:]
        wall, cpu, rss = wall + float(w), cpu + float(u) + float(s), max(rss, int(m))
    return [f"{wall:.1f}", f"{cpu:.1f}", f"{rss / 1024:.0f}"]

def faces_openmvs():
    log = open(f"{out}/refinemesh.log").read()
    m = re.findall(r"Mesh refinement completed: (\d+) vertices, (\d+) faces", log)
    return f"{int(m[-1][1]):,}" if m else "?"

def faces_satmesh():
    try:
        return f"{json.load(open(f'{out}/satmesh/metrics.json'))['totals']['faces']:,}"
    except Exception:
        return "?"

load = open("/proc/loadavg").read().split()[:3]
print(f"\nOpenMVS input: {os.environ.get('OPENMVS_INITIAL', 'dsm')} mesh, "
      f"{'biases estimated by satmesh' if os.environ.get('OPENMVS_BIAS') == '1' else 'the job RPCs'}")
print(f"scene {scene}  (load average now {' '.join(load)}, {os.cpu_count()} CPUs)")
print("| | roofs NMAD m | roofs perc-68 m | facades @0.5 | under overhangs @0.5 | F @0.5 "
      "| walls' offset m | wall s | CPU s | peak MB | faces |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
print("| initial DSM | " + " | ".join(metrics("satmesh", "initial")) + " | | | | |")
print("| initial.ply via --frame (OpenMVS input) | " + " | ".join(metrics("initial")) + " | | | | |")
print("| OpenMVS RefineMesh | " + " | ".join(metrics("openmvs") + timing("refinemesh")) +
      f" | {faces_openmvs()} |")
print("| satmesh refine | " + " | ".join(metrics("satmesh") + timing("satmesh")) +
      f" | {faces_satmesh()} |")
print("OpenMVS inputs (not in its row): export-colmap " + ", ".join(timing("export")) +
      " (wall s, CPU s, peak MB); InterfaceCOLMAP " + ", ".join(timing("interface")))
fr = json.load(open(f"{out}/colmap/frame.json"))
print("pinhole fit, worst view: max %.3f px, rms %.3f px" %
      (max(i["pinhole_max_px"] for i in fr["images"]), max(i["pinhole_rms_px"] for i in fr["images"])))
EOF
