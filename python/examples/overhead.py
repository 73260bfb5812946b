"""The Python layer's cost per pass: Renderer.pass_() timed from Python against the engine's own wall time of
the same pass (PassStats.wall_ms, submission to completion), pass by pass in one run. What is left is the
layer: the lock, releasing and retaking the GIL, the statistics dict and dataclass.

    target/python/bin/python python/examples/overhead.py [SCENE] [--resolution W H] [--photons N] [--passes P]

Prints a table and one JSON line."""

import argparse
import json
import statistics
import time

import ppm_vk

parser = argparse.ArgumentParser()
parser.add_argument("scene", nargs="?", default="scenes/cornell-spheres.toml")
parser.add_argument("--resolution", type=int, nargs=2, default=None)
parser.add_argument("--photons", type=int, default=None)
parser.add_argument("--passes", type=int, default=20)
parser.add_argument("--warm-up", type=int, default=2)
args = parser.parse_args()

settings = {}
if args.resolution:
    settings["resolution"] = tuple(args.resolution)
if args.photons:
    settings["photons_per_pass"] = args.photons
renderer = ppm_vk.Renderer(args.scene, **settings)
for _ in range(args.warm_up):
    renderer.pass_()
python_ms, engine_ms = [], []
for _ in range(args.passes):
    start = time.perf_counter()
    stats = renderer.pass_()
    python_ms.append((time.perf_counter() - start) * 1e3)
    engine_ms.append(stats.wall_ms)
overhead = [p - e for p, e in zip(python_ms, engine_ms)]
result = {
    "scene": args.scene,
    "device": renderer.device,
    "resolution": [renderer.camera["width"], renderer.camera["height"]],
    "photons_per_pass": renderer.settings["photons_per_pass"],
    "passes": args.passes,
    "engine_ms_median": statistics.median(engine_ms),
    "python_ms_median": statistics.median(python_ms),
    "overhead_ms_median": statistics.median(overhead),
    "overhead_ms_max": max(overhead),
    "overhead_share_median": statistics.median(o / e for o, e in zip(overhead, engine_ms)),
}
print(f"{'pass':>5} {'engine ms':>10} {'python ms':>10} {'overhead ms':>12}")
for i, (p, e) in enumerate(zip(python_ms, engine_ms)):
    print(f"{i + 1 + args.warm_up:>5} {e:>10.3f} {p:>10.3f} {p - e:>12.4f}")
print(json.dumps(result))
