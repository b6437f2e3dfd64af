#!/bin/bash
# satmesh synth --initial-dsm noisy|sharp: the initial DSM's errors as a noisy pipeline's
# (blur and per-cell noise: ~0.3 cell of noise at one cell) or as a sharp one's (the
# Pléiades triplet's s2p DSM: 0.05 m at 0.5 m cells), both with fattened walls; satmesh
# refine measures and logs that noise (DsmCellNoise) and, with sharp_dsm_noise_cells,
# meshes a DSM under the bound at its own cells. Bad values are refused naming the option.
# usage: synth_initial_dsm_test.sh SATMESH
set -euo pipefail
satmesh=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
noise_of() {  # the "height noise at one cell N m" of a refine log
  grep -o 'height noise at one cell [0-9.]* m' "$1" | head -1 | awk '{print $6}'
}
for dsm in noisy sharp; do
  "$satmesh" synth --preset small --views stereo --gsd 0.5 --seed 1 --initial-dsm $dsm \
    --out "$work/$dsm" --no-preview > "$work/synth_$dsm.log" 2>&1
  "$satmesh" refine "$work/$dsm/job.json" --out "$work/r_$dsm" > "$work/r_$dsm.log" 2>&1 \
    || { echo "FAIL: refine $dsm"; tail "$work/r_$dsm.log"; exit 1; }
  echo "$dsm: $(grep -o 'initial DSM: .*' "$work/r_$dsm.log" | head -1)"
done
python3 -c "import sys; n, s = map(float, sys.argv[1:]); assert n > 0.12 and 0.04 <= s <= 0.08, (n, s)" \
  "$(noise_of "$work/r_noisy.log")" "$(noise_of "$work/r_sharp.log")" \
  || { echo "FAIL: noise noisy $(noise_of "$work/r_noisy.log") m, sharp $(noise_of "$work/r_sharp.log") m"; exit 1; }
grep -q 'block-averaged to 1.00 m' "$work/r_sharp.log" \
  || { echo "FAIL: by default a sharp DSM is block-averaged"; exit 1; }
"$satmesh" refine "$work/sharp/job.json" --out "$work/r_sharp_cells" --set sharp_dsm_noise_cells=0.2 \
  > "$work/r_sharp_cells.log" 2>&1 || { echo "FAIL: refine sharp_dsm_noise_cells=0.2"; exit 1; }
grep -q 'sharp, meshed at its 0.50 m cells' "$work/r_sharp_cells.log" \
  || { echo "FAIL: sharp_dsm_noise_cells=0.2: $(grep 'initial DSM' "$work/r_sharp_cells.log")"; exit 1; }
if "$satmesh" synth --preset small --initial-dsm smooth --out "$work/bad" --no-preview > "$work/bad.log" 2>&1; then
  echo "FAIL: --initial-dsm smooth accepted"; exit 1
fi
grep -q "option --initial-dsm: expected noisy or sharp, got 'smooth'" "$work/bad.log" \
  || { echo "FAIL: message: $(cat "$work/bad.log")"; exit 1; }
echo "PASS"
