#!/usr/bin/env python3
"""The realism table (README "Cameras and rig errors"): one row per bench folder of
`pbnbv bench --camera C --rig-errors E` (pbnbv, arm, hemisphere, 10 views), from each run's
coverage.json (coverage, cloud and mesh metrics at 5 mm, the hand-eye check) and a second
evaluation of its mesh and cloud at 2 mm (`pbnbv evaluate --threshold 0.002`).

    make_table.py PBNBV_BINARY BENCH_DIR... > table.md

Figures are means over the objects of each run's figure (medians and p95s included)."""
import json
import os
import statistics
import subprocess
import sys


def evaluate_2mm(pbnbv, run):
    out = os.path.join(run, "metrics-2mm.json")
    if not os.path.exists(out):
        subprocess.run([pbnbv, "evaluate", run, "--threshold", "0.002", "--json", out], check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(out) as f:
        return json.load(f)


def row(pbnbv, bench):
    with open(os.path.join(bench, "bench.json")) as f:
        spec = json.load(f)
    runs = sorted(os.path.join(bench, "pbnbv", r) for r in os.listdir(os.path.join(bench, "pbnbv")))
    cov, acc_med, acc_p95, comp_med, f5m, p5m, f2m, f5c, hand = [], [], [], [], [], [], [], [], []
    for run in runs:
        path = os.path.join(run, "coverage.json")
        if not os.path.exists(path):
            continue
        with open(path) as f:
            c = json.load(f)
        sm = c["surface_metrics"]
        if "cloud" not in sm or "mesh" not in sm or "f_score" not in sm["mesh"]:
            continue
        cov.append(c["coverage_by_view"][-1])
        acc_med.append(sm["cloud"]["accuracy"]["median_mm"])
        acc_p95.append(sm["cloud"]["accuracy"]["p95_mm"])
        comp_med.append(sm["cloud"]["completeness"]["median_mm"])
        f5c.append(sm["cloud"]["f_score"])
        f5m.append(sm["mesh"]["f_score"])
        p5m.append(sm["mesh"]["precision"])
        two = evaluate_2mm(pbnbv, run)
        mesh2 = [x for x in two["models"] if x["model"] == "mesh"]
        f2m.append(mesh2[0]["f_score"] if mesh2 else float("nan"))
        if c.get("hand_eye"):
            hand.append((c["hand_eye"]["error_mm"], c["hand_eye"]["error_deg"]))
    m = statistics.mean
    he = "" if not hand else "%.2f mm / %.3f deg (worst %.2f / %.3f)" % (
        m(h[0] for h in hand), m(h[1] for h in hand), max(h[0] for h in hand), max(h[1] for h in hand))
    return "| %s | %s | %d | %.1f | %.3f / %.3f | %.2f | %.3f | %.3f | %.3f | %.3f | %s |" % (
        spec["camera"], spec["rig_errors"], len(cov), m(cov), m(acc_med), m(acc_p95), m(comp_med), m(f5c),
        m(f5m), m(f2m), m(p5m), he)


def main():
    pbnbv, benches = sys.argv[1], sys.argv[2:]
    print("| camera | rig errors | objects | coverage after view 10 (%) | cloud accuracy median / p95 (mm) "
          "| cloud completeness median (mm) | cloud F at 5 mm | mesh F at 5 mm | mesh F at 2 mm "
          "| mesh precision at 5 mm | hand-eye estimate from the truth (mean) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for b in benches:
        print(row(pbnbv, b))


if __name__ == "__main__":
    main()
