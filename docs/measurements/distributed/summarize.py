#!/usr/bin/env python3
"""Markdown table of run.sh's results.jsonl: per scene, method and worker count, the mean over seeds of the
merged image's errors, and the ratio of its relMSE to the one-machine render of as many passes, SPPM's
(`independent` with one worker is the ordinary SPPM render)."""
import collections
import json
import sys

rows = [json.loads(line) for line in open(sys.argv[1])]
by = collections.defaultdict(list)
for r in rows:
    by[(r["scene"], r["method"], r["workers"])].append(r)
seeds = sorted({r["seed"] for r in rows})
print(f"seeds {seeds}; each cell the mean over them (min-max in brackets)\n")
print("| scene | method | workers x passes | relMSE | / SPPM 1 x 32 | RMSE | caustic RMSE | bias |")
print("|---|---|---|---|---|---|---|---|")


def stat(values):
    m = sum(values) / len(values)
    return m, min(values), max(values)


for (scene, method, n), rs in sorted(by.items(), key=lambda kv: (kv[0][0], kv[0][1] != "probabilistic", kv[0][2])):
    base = {r["seed"]: r for r in by[(scene, "independent", 1)]}
    rs = [r for r in rs if r["seed"] in base]
    if not rs:
        continue
    rel = stat([r["error"]["rel_mse"] for r in rs])
    ratio = stat([r["error"]["rel_mse"] / base[r["seed"]]["error"]["rel_mse"] for r in rs])
    rmse = stat([r["error"]["rmse"] for r in rs])
    bias = stat([r["error"]["mean_bias"] for r in rs])
    caustic = [r["region_errors"]["caustic"]["rmse"] for r in rs if "caustic" in r["region_errors"]]
    c = "%.4f" % stat(caustic)[0] if caustic else "-"
    print(
        f"| {scene} | {method} | {n} x {rs[0]['passes_per_worker']} | {rel[0]:.5f} [{rel[1]:.5f}-{rel[2]:.5f}] "
        f"| {ratio[0]:.3f} [{ratio[1]:.3f}-{ratio[2]:.3f}] | {rmse[0]:.4f} | {c} | {bias[0]:+.4f} |"
    )
