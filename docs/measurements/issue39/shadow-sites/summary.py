"""Issue 39's shadow-ray sites: per scene, the eye pass (`ray` ms) and the whole pass of each build in each
round, and after / before (usage: python3 summary.py [NAME], NAME as run.sh's)."""
import json
import sys

name = sys.argv[1] if len(sys.argv) > 1 else "bench"
runs = {}
for b in ("before", "after"):
    for r in (1, 2):
        d = json.load(open(f"{name}-{b}-{r}.json"))
        runs[(b, r)] = {c["scene"].split("/")[-1]: c for c in d["cases"]}
scenes = list(runs[("before", 1)].keys())
print("| scene | eye pass ms, before (rounds 1, 2) | after | after / before | photon stage ms, before | after | pass ms, before | after |")
print("|---|---|---|---|---|---|---|---|")
ratios = {}
for s in scenes:
    def col(b, key):
        return [runs[(b, r)][s]["stage_ms_median"][key] for r in (1, 2)]

    def wall(b):
        return [runs[(b, r)][s]["pass_wall_ms_median"] for r in (1, 2)]
    rb, ra = col("before", "ray"), col("after", "ray")
    pb, pa = col("before", "photon"), col("after", "photon")
    wb, wa = wall("before"), wall("after")
    ratio = [a / b for a, b in zip(ra, rb)]
    f = lambda v: ", ".join(f"{x:.0f}" for x in v)
    print(f"| {s} | {f(rb)} | {f(ra)} | {', '.join(f'{x:.2f}' for x in ratio)} | {f(pb)} | {f(pa)} | {f(wb)} | {f(wa)} |")
    ratios[s] = [(runs[(b, r)][s]["vs_first_scene"] or {"eye_pass_per_hit_point": 1.0})["eye_pass_per_hit_point"]
                 for b in ("before", "after") for r in (1, 2)]
print()
print("| scene | eye pass per hit point / cornell-spheres', before (rounds 1, 2) | after |")
print("|---|---|---|")
for s, v in ratios.items():
    print(f"| {s} | {v[0]:.2f}x, {v[1]:.2f}x | {v[2]:.2f}x, {v[3]:.2f}x |")
