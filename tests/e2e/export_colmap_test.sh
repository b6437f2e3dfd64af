#!/bin/bash
# satmesh export-colmap on the small synthetic scene: the COLMAP model and images are
# written, every pinhole is within 0.1 px of its RPC, and the exported initial.ply mapped
# back by `satmesh eval --frame` scores as the initial DSM does (the frame's round trip).
# Also the OpenMVS side-by-side benchmark's skip path (CI has no OpenMVS).
# usage: export_colmap_test.sh SATMESH REPO_ROOT
set -euo pipefail
satmesh=$1
repo=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

"$satmesh" synth --preset small --seed 3 --out "$work/scene" --no-preview > "$work/synth.log" 2>&1
"$satmesh" export-colmap "$work/scene/job.json" --out "$work/colmap" > "$work/export.log" 2>&1
for f in sparse/cameras.txt sparse/images.txt sparse/points3D.txt images/img_00.png \
         images/img_02.png initial.ply frame.json; do
  [ -s "$work/colmap/$f" ] || { echo "FAIL: no $f"; exit 1; }
done
[ "$(grep -c PINHOLE "$work/colmap/sparse/cameras.txt")" = 3 ] || { echo "FAIL: cameras.txt"; exit 1; }
"$satmesh" eval --scene "$work/scene" --result "$work/colmap/initial.ply" \
  --frame "$work/colmap/frame.json" --json "$work/eval.json" > "$work/eval.log" 2>&1
python3 - "$work" <<'EOF'
import json, sys
w = sys.argv[1]
frame = json.load(open(f"{w}/colmap/frame.json"))
worst = max(i["pinhole_max_px"] for i in frame["images"])
assert worst < 0.1, f"pinhole {worst} px from its RPC"
e = json.load(open(f"{w}/eval.json"))
a = e["initial"]["dsm"]["roof_mask"]["raw"]["nmad_m"]
b = e["result"]["dsm"]["roof_mask"]["raw"]["nmad_m"]
assert abs(b - a) < 0.05 * a, f"initial.ply roofs NMAD {b} vs initial DSM {a}"
ma = e["initial"]["dsm"]["roof_mask"]["raw"]["median_m"]
mb = e["result"]["dsm"]["roof_mask"]["raw"]["median_m"]
assert abs(mb - ma) < 0.05, f"initial.ply roofs median {mb} m vs the DSM's {ma} m: the frame is off"
print(f"pinholes within {worst:.4f} px; initial.ply roofs NMAD {b:.3f} m (DSM {a:.3f} m)")
EOF
out=$(env -u OPENMVS_BIN "$repo/tests/bench/openmvs_side_by_side.sh" "$work/scene")
[ "$out" = "skipped: no OpenMVS build (set OPENMVS_BIN)" ] || { echo "FAIL: skip path: $out"; exit 1; }
echo "PASS"
