#!/usr/bin/env python3
"""The realism table (README "Cameras and rig errors"): one row per bench folder of
`pbnbv bench --camera C --rig-errors E` (pbnbv, arm, hemisphere, 10 views), from each run's
coverage.json (coverage, cloud and mesh metrics at 5 mm, the hand-eye check) and a second
evaluation of its mesh and cloud at 2 mm (`pbnbv evaluate --threshold 0.002`).

    make_table.py [--remesh] PBNBV_BINARY BENCH_DIR... > table.md

Figures are means over the objects of each run's figure (medians and p95s included). --remesh
builds each run's mesh again with this binary first (`pbnbv mesh RUN`: the same frames and poses,
today's surface code) and takes the mesh's figures at 5 mm from a fresh evaluation too, so rows
run before a change of the mesher compare with rows run after it."""
import json
import os
import statistics
import subprocess
import sys


REMESH = False


def evaluate(pbnbv, run, threshold_mm):
    out = os.path.join(run, "metrics-%dmm.json" % threshold_mm)
    if not os.path.exists(out):
        subprocess.run([pbnbv, "evaluate", run, "--threshold", "%g" % (threshold_mm / 1000.0), "--json", out],
                       check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(out) as f:
        return json.load(f)


def mesh_figures(two):
    mesh = [x for x in two["models"] if x["model"] == "mesh"]
    return mesh[0] if mesh else None


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
        if REMESH:
            subprocess.run([pbnbv, "mesh", run], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            for t in (2, 5):
                if os.path.exists(os.path.join(run, "metrics-%dmm.json" % t)):
                    os.remove(os.path.join(run, "metrics-%dmm.json" % t))
            five = mesh_figures(evaluate(pbnbv, run, 5))
            sm = dict(sm, mesh={"f_score": five["f_score"], "precision": five["precision"]})
        cov.append(c["coverage_by_view"][-1])
        acc_med.append(sm["cloud"]["accuracy"]["median_mm"])
        acc_p95.append(sm["cloud"]["accuracy"]["p95_mm"])
        comp_med.append(sm["cloud"]["completeness"]["median_mm"])
        f5c.append(sm["cloud"]["f_score"])
        f5m.append(sm["mesh"]["f_score"])
        p5m.append(sm["mesh"]["precision"])
        mesh2 = mesh_figures(evaluate(pbnbv, run, 2))
        f2m.append(mesh2["f_score"] if mesh2 else float("nan"))
        if c.get("hand_eye"):
            hand.append((c["hand_eye"]["error_mm"], c["hand_eye"]["error_deg"]))
    m = statistics.mean
    he = "" if not hand else "%.2f mm / %.3f deg (worst %.2f / %.3f)" % (
        m(h[0] for h in hand), m(h[1] for h in hand), max(h[0] for h in hand), max(h[1] for h in hand))
    return "| %s | %s | %d | %.1f | %.3f / %.3f | %.2f | %.3f | %.3f | %.3f | %.3f | %s |" % (
        spec["camera"], spec["rig_errors"], len(cov), m(cov), m(acc_med), m(acc_p95), m(comp_med), m(f5c),
        m(f5m), m(f2m), m(p5m), he)


def main():
    global REMESH
    args = sys.argv[1:]
    if args and args[0] == "--remesh":
        REMESH, args = True, args[1:]
    pbnbv, benches = args[0], args[1:]
    print("| camera | rig errors | objects | coverage after view 10 (%) | cloud accuracy median / p95 (mm) "
          "| cloud completeness median (mm) | cloud F at 5 mm | mesh F at 5 mm | mesh F at 2 mm "
          "| mesh precision at 5 mm | hand-eye estimate from the truth (mean) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for b in benches:
        print(row(pbnbv, b))


if __name__ == "__main__":
    main()
