#!/usr/bin/env bash
# scripts/bench-pair on two hand-made bench folders whose figures can be checked by hand:
#   before: a  rig 2 4 6 8 10 s,        observable 50 80 91 96 97 %  (90 % at view 3, 6 s; 95 % at view 4, 8 s)
#           b  rig 3 6 9 12 15 s,       observable 40 70 90 95 96 %  (90 % at view 3, 9 s; 95 % at view 4, 12 s)
#   after:  a  rig 1 2 3 4 5 s,         the same observable           (90 % at 3 s, 95 % at 4 s)
#           b  rig 1.5 3 4.5 6 7.5 s,   observable 40 70 90 94 95 %   (90 % at 4.5 s, 95 % at view 5, 7.5 s)
#           c  only in after (not paired); d incomplete in both (not paired)
# Rig time 12.5 -> 6.25 s a run (-50 %); coverage 96.5 -> 95.5 % (-1 point); to 90 % 7.5 -> 3.75 s
# (-50 %); to 95 % 10 -> 5.75 s (-42.5 %), views 4 -> 4.5, 20 / 8 = 2.5 -> 11.5 / 9 = 1.28 s a view.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
run() {  # object rig... / observable...
  printf '{"planner": "pbnbv", "object": "%s", "first_view": 1, "complete": %s, "rig_time_by_view": [%s], "observable_by_view": [%s], "coverage_by_view": [%s]}' "$@"
}
mkdir -p "$dir/before/evaluation/x" "$dir/after/evaluation/x"
cat > "$dir/before/evaluation/x/evaluation.json" <<JSON
{"runs": [$(run a true "2,4,6,8,10" "50,80,91,96,97" "50,80,91,96,97"), $(run b true "3,6,9,12,15" "40,70,90,95,96" "40,70,90,95,96"),
          $(run d false "1,2,3,4,5" "1,2,3,4,5" "1,2,3,4,5")]}
JSON
cat > "$dir/after/evaluation/x/evaluation.json" <<JSON
{"runs": [$(run a true "1,2,3,4,5" "50,80,91,96,97" "50,80,91,96,96"), $(run b true "1.5,3,4.5,6,7.5" "40,70,90,94,95" "40,70,90,94,95"),
          $(run c true "1,2,3,4,5" "99,99,99,99,99" "99,99,99,99,99"), $(run d false "1,2,3,4,5" "1,2,3,4,5" "1,2,3,4,5")]}
JSON
out=$("$root/scripts/bench-pair" --samples 200 "$dir/before" "$dir/after")
echo "$out"
expect() {
  if ! grep -qF -- "$1" <<<"$out"; then
    echo "bench_pair_test: expected a line with: $1" >&2
    exit 1
  fi
}
expect "2 runs paired (pbnbv)"
expect "rig time to the last view: 12.50 -> 6.25 s"
expect "rig time change: -50.00 %"
expect "coverage after the last view: 96.50 -> 95.50 %"
expect "coverage change: -1.00 points"
expect "to 90 %: 7.50 -> 3.75 s over 2 runs reaching it in both (0 only before, 0 only after); views 3.00 -> 3.00, 2.50 -> 1.25 s a view"
expect "to 95 %: 10.00 -> 5.75 s over 2 runs reaching it in both (0 only before, 0 only after); views 4.00 -> 4.50, 2.50 -> 1.28 s a view"
expect "to 95 % change: -42.50 %"
# Pooling a folder with itself changes nothing.
out=$("$root/scripts/bench-pair" --samples 200 "$dir/before,$dir/before" "$dir/after,$dir/after")
expect "to 95 % change: -42.50 %"
# The same runs read from a summary.json alone (what docs/benchmark keeps of a bench run).
mkdir -p "$dir/summary"
python3 - "$dir/after/evaluation/x/evaluation.json" "$dir/summary/summary.json" <<'PY'
import json, sys
runs = json.load(open(sys.argv[1]))["runs"]
out = {"pbnbv": {"runs": {r["object"]: {"object": r["object"], "first_view": 1, "complete": r["complete"],
                                        "coverage_by_view": r["coverage_by_view"],
                                        "observable_coverage_by_view": r["observable_by_view"],
                                        "rig_time_s_by_view": r["rig_time_by_view"]} for r in runs}}}
json.dump(out, open(sys.argv[2], "w"))
PY
out=$("$root/scripts/bench-pair" --samples 200 "$dir/before" "$dir/summary")
expect "to 95 %: 10.00 -> 5.75 s over 2 runs reaching it in both"
# What is not a bench folder, or a bad option, is refused by name.
if msg=$("$root/scripts/bench-pair" "$dir/before" "$dir/none" 2>&1); then echo "bench_pair_test: a folder with no evaluation was taken" >&2; exit 1; fi
grep -qF "$dir/none holds neither evaluation" <<<"$msg" || { echo "bench_pair_test: $msg" >&2; exit 1; }
if msg=$("$root/scripts/bench-pair" --samples 5 "$dir/before" "$dir/after" 2>&1); then echo "bench_pair_test: --samples 5 was taken" >&2; exit 1; fi
grep -qF -- "--samples 5 is out of 100-100000" <<<"$msg" || { echo "bench_pair_test: $msg" >&2; exit 1; }
echo "bench_pair_test: passed"
