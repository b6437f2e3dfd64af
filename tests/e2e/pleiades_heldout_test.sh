#!/bin/bash
# Real imagery, held-out views (issue 16): the Pléiades triplet of ../shared/data (three
# views, an s2p DSM). The RPC biases are estimated once over the three views (`satmesh
# bias`) and then kept fixed; each 2-view subset is refined from the s2p DSM (defaults,
# estimate_bias off, so the three runs share one block), and `satmesh zncc` measures every
# pair's ZNCC, the held-out view's two pairs included, through the DSM (holes filled, as
# the refinement meshes it) and through each result. The checks compare the surfaces over
# the windows every one of them counts (`satmesh zncc`'s second table): a surface's own
# mean averages the windows it makes valid, another support for each surface.
#
# usage: pleiades_heldout_test.sh SATMESH [DATA_DIR] [--keep DIR] [--max-fall F]
#                                 [--max-mean-fall F] [--set k=v ...]
#   DATA_DIR    the triplet (default: ../shared/data/pleiades_marseille_triplet beside the
#               repository); absent: skipped (exit 77)
#   --keep DIR  keep the jobs, results and logs in DIR
#   --max-fall  largest fall of a held-out pair's ZNCC that passes (default 0.002, issue 16)
#   --max-mean-fall  largest fall of a held-out view's mean over its pairs that passes
#               (default 0: the mean must rise, issue 16)
#   --set       refinement options for the three runs (as `satmesh refine --set`)
# Checks: each held-out view's mean ZNCC over its two pairs rises (falls by at most
# --max-mean-fall), and no held-out pair falls by more than --max-fall. Prints the table
# either way. ctest runs it as a regression guard with today's margins (tests/e2e/
# CMakeLists.txt); run it without them to see issue 16's bars.
set -euo pipefail
satmesh=$1
shift
here="$(cd "$(dirname "$0")" && pwd)"
data="$here/../../../shared/data/pleiades_marseille_triplet"
if [ $# -gt 0 ] && [ "${1#--}" = "$1" ]; then data=$1; shift; fi
keep="" max_fall=0.002 max_mean_fall=0 sets=()
while [ $# -gt 0 ]; do
  case "$1" in
    --keep) keep=$2; shift 2 ;;
    --max-fall) max_fall=$2; shift 2 ;;
    --max-mean-fall) max_mean_fall=$2; shift 2 ;;
    --set) sets+=(--set "$2"); shift 2 ;;
    *) echo "unknown argument: $1" >&2; exit 2 ;;
  esac
done
for f in img_01.tif img_02.tif img_03.tif s2p_dsm.tif; do
  [ -f "$data/$f" ] || { echo "SKIP: no $data/$f (the shared Pléiades triplet)"; exit 77; }
done
data="$(cd "$data" && pwd)"
if [ -n "$keep" ]; then work=$keep; mkdir -p "$work"; else work=$(mktemp -d); trap 'rm -rf "$work"' EXIT; fi

cat > "$work/job_123.json" <<EOF
{"images": [{"href": "$data/img_01.tif"}, {"href": "$data/img_02.tif"}, {"href": "$data/img_03.tif"}],
 "initial": {"dsm": "$data/s2p_dsm.tif"}}
EOF
"$satmesh" bias --job "$work/job_123.json" --write-job "$work/job_123_b.json" > "$work/bias.log" 2>&1 \
  || { cat "$work/bias.log"; echo "FAIL: satmesh bias"; exit 1; }
python3 - "$work" <<'PY'
import json, sys
work = sys.argv[1]
job = json.load(open(f"{work}/job_123_b.json"))
for name, keep in (("01_02", (0, 1)), ("01_03", (0, 2)), ("02_03", (1, 2))):
    sub = dict(job, images=[job["images"][i] for i in keep], options={"estimate_bias": False})
    json.dump(sub, open(f"{work}/job_{name}.json", "w"), indent=1)
PY
for name in 01_02 01_03 02_03; do
  /usr/bin/time -f "%e s, peak %M KB" "$satmesh" refine "$work/job_$name.json" --out "$work/r_$name" \
    "${sets[@]}" > "$work/r_$name.log" 2>&1 || { tail -20 "$work/r_$name.log"; echo "FAIL: refine $name"; exit 1; }
  echo "refined with img_${name%_*} + img_${name#*_}: $(tail -1 "$work/r_$name.log")"
done
"$satmesh" zncc --job "$work/job_123_b.json" --mesh initial-filled --mesh "$work/r_01_02" \
  --mesh "$work/r_01_03" --mesh "$work/r_02_03" --pairs 0-2,1-2,0-1 > "$work/zncc.log" 2>&1 \
  || { cat "$work/zncc.log"; echo "FAIL: satmesh zncc"; exit 1; }
python3 - "$work/zncc.log" "$max_fall" "$max_mean_fall" <<'PY'
import re, sys
log, max_fall, max_mean_fall = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
own, common = {}, {}
for line in open(log):
    m = re.match(r"(\S+) \(\d+ faces\), level 0(, common windows)?:\s+(.*)\s+all", line)
    if m:
        name = m.group(1).rstrip("/").split("/")[-1]
        table = common if m.group(2) else own
        table[name] = {p: float(v) for p, v in re.findall(r"(\d-\d) ([0-9.]+)", m.group(3))}
assert len(own) == 4 and len(common) == 4, f"could not read the ZNCC tables from {log}"
def held_out_rows(table, title):
    """Prints the table's held-out rows; yields (held, pairs, before, after) of each."""
    print(title)
    print("held out | its pairs | s2p DSM (holes filled) | refined with the other two | change")
    for held, result in ((2, "r_01_02"), (1, "r_01_03"), (0, "r_02_03")):
        pairs = [p for p in ("0-2", "1-2", "0-1") if str(held) in p]
        before = [table["initial-filled"][p] for p in pairs]
        after = [table[result][p] for p in pairs]
        print(f"img_0{held + 1} | {' / '.join(pairs)} | {' / '.join(f'{b:.4f}' for b in before)} | "
              f"{' / '.join(f'{a:.4f}' for a in after)} | "
              f"{' / '.join(f'{a - b:+.4f}' for a, b in zip(after, before))}")
        yield held, pairs, before, after
for _ in held_out_rows(own, "Each surface over its own windows (not one support; not checked):"):
    pass
failures = []
for held, pairs, before, after in held_out_rows(common, "Over the windows every surface counts (checked):"):
    change = [a - b for a, b in zip(after, before)]
    mean_change = (sum(after) - sum(before)) / 2
    if not (mean_change > 0 if max_mean_fall == 0 else mean_change >= -max_mean_fall):
        failures.append(f"held out img_0{held + 1}: the mean of its pairs "
                        f"{'does not rise' if max_mean_fall == 0 else f'falls by more than {max_mean_fall}'} "
                        f"({sum(before) / 2:.5f} -> {sum(after) / 2:.5f})")
    for p, c in zip(pairs, change):
        if c < -max_fall:
            failures.append(f"held out img_0{held + 1}: pair {p} falls by {-c:.4f} (> {max_fall})")
if failures:
    print("FAIL:\n  " + "\n  ".join(failures))
    sys.exit(1)
print("PASS: " + ("every held-out view's mean rises" if max_mean_fall == 0 else
                  f"no held-out view's mean falls by more than {max_mean_fall}") +
      f", no held-out pair falls by more than {max_fall}")
PY
