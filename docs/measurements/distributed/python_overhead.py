"""What merging costs from Python, and what Ray adds, against rendering the parts (docs/distributed.md).

    target/python/bin/python docs/measurements/distributed/python_overhead.py [RES] [WORKERS] [PASSES]

Renders WORKERS parts of PASSES passes of cornell-spheres at RES x RES (20k photons a pass) one after
another with ppm_vk.render_part, then times: a part's to_bytes and its pickle round trip (what a Ray task's
return costs to encode), ppm_vk.merge of the parts, and the same render as ppm_vk.distributed.render on a
local Ray cluster of WORKERS CPUs (ray.init timed apart). Prints one JSON line.
"""

import json
import pathlib
import pickle
import sys
import time

import ray

import ppm_vk
import ppm_vk.distributed

REPO = pathlib.Path(__file__).resolve().parents[3]
SCENE = REPO / "scenes" / "cornell-spheres.toml"


def timed(f):
    t = time.perf_counter()
    out = f()
    return out, time.perf_counter() - t


def main():
    res, workers, passes = (int(a) for a in (sys.argv[1:] + ["128", "2", "2"][len(sys.argv) - 1:]))
    settings = dict(resolution=(res, res), photons_per_pass=20_000, seed=1)
    parts, render_s = timed(lambda: [ppm_vk.render_part(SCENE, k, workers, passes, **settings)
                                     for k in range(workers)])
    data, to_bytes_s = timed(lambda: parts[0].to_bytes())
    _, pickle_s = timed(lambda: pickle.loads(pickle.dumps(parts[0])))
    image, merge_s = timed(lambda: ppm_vk.merge(parts))
    _, init_s = timed(lambda: ray.init(num_cpus=workers, include_dashboard=False, log_to_driver=False))
    try:
        ray_image, ray_s = timed(lambda: ppm_vk.distributed.render(SCENE, workers, passes, **settings))
    finally:
        ray.shutdown()
    assert ray_image.tobytes() == image.tobytes()
    print(json.dumps({
        "res": res, "workers": workers, "passes_per_worker": passes, "part_bytes": len(data),
        "render_parts_sequential_s": round(render_s, 3), "to_bytes_s": round(to_bytes_s, 4),
        "pickle_round_trip_s": round(pickle_s, 4), "merge_s": round(merge_s, 4),
        "merge_per_render": round(merge_s / render_s, 5), "ray_init_s": round(init_s, 2),
        "ray_render_s": round(ray_s, 2),
    }))


if __name__ == "__main__":
    main()
