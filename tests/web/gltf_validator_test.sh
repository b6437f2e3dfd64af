#!/usr/bin/env bash
# The glb tiles of a refined multi-tile job through Khronos glTF-Validator (npm
# gltf-validator, installed into web/node_modules by scripts/install-deps.sh): 0 errors and
# 0 warnings on every tile as written (Draco-compressed) and on a decoded copy of each
# (Draco's own decoder, written uncompressed: the validator then checks the decoded normals'
# lengths, the accessors' bounds and counts). Also asserts that the tiles carry NORMAL and
# the viewer's _HEIGHT and _CHANGE attributes.
#   gltf_validator_test.sh SATMESH GLB_DECODE_COPY WEB_DIR
set -euo pipefail
satmesh="$1" decode="$2" web="$3"
if ! command -v node >/dev/null || [ ! -d "$web/node_modules/gltf-validator" ]; then
  echo "SKIP: node or $web/node_modules/gltf-validator missing (run scripts/install-deps.sh)"
  exit 77
fi
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
"$satmesh" synth --preset small --out "$work/scene" >/dev/null
# 72 m scene in 40 m tiles: 2 x 2 tiles.
"$satmesh" refine "$work/scene/job.json" --out "$work/out" --set tiling.size_m=40 --set tiling.overlap_m=8 \
  --set iterations_per_level=4 | tail -1
tiles=("$work"/out/tiles/*.glb)
[ "${#tiles[@]}" -ge 4 ] || { echo "FAIL: expected >= 4 tiles, got ${#tiles[@]}"; exit 1; }
decoded=()
for t in "${tiles[@]}"; do
  d="$work/$(basename "$t" .glb).decoded.glb"
  "$decode" "$t" "$d"
  decoded+=("$d")
done
node "$web/tools/validate-gltf.mjs" "${tiles[@]}" "${decoded[@]}"
# The attributes, read from the JSON chunk of every tile.
node -e '
const fs = require("fs");
for (const f of process.argv.slice(1)) {
  const b = fs.readFileSync(f), n = b.readUInt32LE(12);
  const gltf = JSON.parse(b.subarray(20, 20 + n).toString());
  for (const m of gltf.meshes) for (const p of m.primitives)
    for (const a of ["POSITION", "NORMAL", "_HEIGHT", "_CHANGE"])
      if (!(a in p.attributes) || !(a in p.extensions.KHR_draco_mesh_compression.attributes)) {
        console.log(`FAIL: ${f}: no Draco-compressed ${a}`); process.exit(1);
      }
}
console.log(`${process.argv.length - 1} tiles carry POSITION, NORMAL, _HEIGHT, _CHANGE (Draco)`);
' "${tiles[@]}"
