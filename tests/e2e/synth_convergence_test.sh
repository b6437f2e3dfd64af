#!/bin/bash
# satmesh synth --convergence-deg: a one-pass collection's convergence is drawn from the
# requested range (real pairs: Pléiades 7-28 deg, WorldView in-track 25-45 deg;
# ../shared/ACQUISITIONS.md), for stereo and for tri-stereo's outer views; bad values and
# collections without a pass geometry are refused with a message naming the option.
# usage: synth_convergence_test.sh SATMESH
set -euo pipefail
satmesh=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
angles() {  # the "convergence (deg):0-1 7.5,0-2 ..." line as "0-1 7.5 0-2 ..."
  grep '^convergence (deg):' "$1" | sed 's/^convergence (deg)://; s/,/ /g'
}
for seed in 1 2 3; do
  "$satmesh" synth --preset small --views stereo --convergence-deg 38,44 --seed $seed \
    --out "$work/st$seed" --no-preview > "$work/st$seed.log" 2>&1
  set -- $(angles "$work/st$seed.log")
  python3 -c "import sys; a = float(sys.argv[1]); assert 37.5 <= a <= 44.5, a" "$2" \
    || { echo "FAIL: stereo seed $seed converges at $2 deg, not in 38-44"; exit 1; }
  echo "stereo seed $seed: $*"
  "$satmesh" synth --preset small --views tristereo --convergence-deg 7,9 --seed $seed \
    --out "$work/ts$seed" --no-preview > "$work/ts$seed.log" 2>&1
  # pairs 0-1 and 1-2 are the outer views with the middle one
  set -- $(angles "$work/ts$seed.log")
  python3 -c "import sys; a = [float(x) for x in sys.argv[1:]]; assert all(6.5 <= x <= 9.5 for x in a), a" "$2" "$6" \
    || { echo "FAIL: tri-stereo seed $seed: $*"; exit 1; }
  echo "tri-stereo seed $seed: $*"
done
bad() {  # bad ARGS... EXPECTED_MESSAGE
  local expected=${*: -1}
  if "$satmesh" synth --preset small --out "$work/bad" --no-preview "${@:1:$#-1}" > "$work/bad.log" 2>&1; then
    echo "FAIL: accepted: ${*:1:$#-1}"; exit 1
  fi
  grep -q -- "$expected" "$work/bad.log" || { echo "FAIL: message for ${*:1:$#-1}: $(cat "$work/bad.log")"; exit 1; }
}
bad --views stereo --convergence-deg 7 "expected MIN,MAX in degrees, got '7'"
bad --views stereo --convergence-deg 9,7 "stereo_min_convergence_deg <= stereo_max_convergence_deg"
bad --views multidate --convergence-deg 7,9 "applies to one pass"
echo "PASS"
