"""Per scene, the photon stage, the eye pass and the whole pass (ms, median of a bench run's passes) of
each build in each round of run.sh, and after / before round by round (usage: python3 summary.py [DIR],
DIR holding bench-{before,after}-{1,2}.json; default: this script's folder)."""
import json
import os
import sys

here = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
runs = {}
for b in ("before", "after"):
    for r in (1, 2):
        d = json.load(open(os.path.join(here, f"bench-{b}-{r}.json")))
        runs[(b, r)] = {c["scene"].split("/")[-1]: c for c in d["cases"]}
print("| scene | stage | before (rounds 1, 2) | after | after / before |")
print("|---|---|---|---|---|")
for s in runs[("before", 1)]:
    for label, get in (("photon stage", lambda c: c["stage_ms_median"]["photon"]),
                       ("eye pass", lambda c: c["stage_ms_median"]["ray"]),
                       ("whole pass", lambda c: c["pass_wall_ms_median"])):
        bv = [get(runs[("before", r)][s]) for r in (1, 2)]
        av = [get(runs[("after", r)][s]) for r in (1, 2)]
        ratio = ", ".join(f"{a / b:.2f}" for a, b in zip(av, bv))
        print(f"| {s} | {label} | {bv[0]:.0f}, {bv[1]:.0f} | {av[0]:.0f}, {av[1]:.0f} | {ratio} |")
