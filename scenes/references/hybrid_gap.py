#!/usr/bin/env python3
"""Estimates what make_reference.py's hybrid integrator leaves out (README-lights.md): light that leaves a
point or spot light through smooth surfaces before its first diffuse or glossy bounce and is then seen
through smooth surfaces (L S+ D ... S+ E).

    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so \
        python3 scenes/references/hybrid_gap.py spot-caustic [--radius 0.1] [--spp 1024] [--chunks 4]

The scene's one `point` or `spot` emitter (scenes/NAME.xml) is replaced by a sphere light of radius
`--radius` at its position with radiance I / (pi r^2): the same intensity I in every direction (for a spot,
right for the directions inside its full beam, which is where the smooth object lies in these scenes). A
path tracer with BSDF sampling only then counts the paths whose first vertex from the camera and whose
last vertex before the light are both smooth (delta), with a diffuse or glossy vertex between. Prints the
image mean of that part and its standard error. The proxy's size blurs what it lights, not how much light
it carries: the estimate hardly depends on the radius (spot-caustic: 5.4e-4 +- 0.2e-4 at 0.1 m, 4.8e-4 +-
1.0e-4 at 0.05 m).
"""

import argparse
import os
import re
import tempfile
import time

import numpy as np

import drjit as dr
import mitsuba as mi

mi.set_variant("llvm_ad_rgb")

HERE = os.path.dirname(os.path.abspath(__file__))


class SmoothBothEnds(mi.SamplingIntegrator):
    """BSDF-sampled paths that hit an emitter right after a smooth vertex, whose first camera vertex is
    smooth and which have a non-smooth vertex between."""

    def __init__(self, props):
        super().__init__(props)

    @dr.syntax
    def sample(self, scene, sampler, ray, medium=None, active=True):
        ray = mi.Ray3f(ray)
        L = mi.Spectrum(0.0)
        beta = mi.Spectrum(1.0)
        active = mi.Bool(active)
        depth = mi.UInt32(0)
        first_delta = mi.Bool(False)
        seen_non_delta = mi.Bool(False)
        prev_delta = mi.Bool(False)
        ctx = mi.BSDFContext()
        while active:
            si = scene.ray_intersect(ray, active)
            valid = active & si.is_valid()
            hit_emitter = valid & si.shape.is_emitter()
            count = hit_emitter & first_delta & seen_non_delta & prev_delta
            L += dr.select(count, beta * si.emitter(scene, count).eval(si, count), 0.0)
            active = valid & ~hit_emitter
            bs, w = si.bsdf(ray).sample(ctx, si, sampler.next_1d(active), sampler.next_2d(active), active)
            is_delta = mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta)
            first_delta = dr.select(depth == 0, is_delta, first_delta)
            seen_non_delta |= active & ~is_delta
            prev_delta = is_delta
            beta *= w
            ray = si.spawn_ray(si.to_world(bs.wo))
            depth += 1
            active &= (depth < 40) & (dr.max(beta) > 0) & first_delta
            q = dr.minimum(dr.max(beta), 0.95)
            u = sampler.next_1d(active)
            rr = active & (depth > 5)
            active &= ~rr | (u < q)
            beta = dr.select(rr, beta / q, beta)
        return L, mi.Bool(True), []

    def aov_names(self):
        return []


def proxy_xml(text, radius):
    """The scene with its point or spot emitter replaced by a sphere light of the same intensity."""
    m = re.search(r'<emitter type="(point|spot)">.*?</emitter>', text, re.S)
    block = m.group(0)
    pos = re.search(r'<point name="position" x="([^"]+)" y="([^"]+)" z="([^"]+)"', block) or re.search(
        r'<lookat origin="([^,"]+),\s*([^,"]+),\s*([^,"]+)"', block)
    intensity = np.array([float(v) for v in re.search(r'name="intensity" value="([^"]+)"', block).group(1).split(",")])
    radiance = ", ".join(f"{v:.6g}" for v in intensity / (np.pi * radius**2) * np.ones(3))
    sphere = (f'<shape type="sphere"><point name="center" x="{pos.group(1)}" y="{pos.group(2)}" z="{pos.group(3)}"/>'
              f'<float name="radius" value="{radius}"/><bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>'
              f'<emitter type="area"><rgb name="radiance" value="{radiance}"/></emitter></shape>')
    return text.replace(block, sphere)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("name", help="scenes/NAME.xml")
    p.add_argument("--radius", type=float, default=0.1)
    p.add_argument("--spp", type=int, default=1024)
    p.add_argument("--chunks", type=int, default=4)
    p.add_argument("--res", type=int, default=128)
    a = p.parse_args()
    src = os.path.join(HERE, "..", a.name + ".xml")
    text = proxy_xml(open(src).read(), a.radius)
    # beside the original, so that its relative paths still resolve
    with tempfile.NamedTemporaryFile("w", suffix=".xml", dir=os.path.dirname(src), delete=False) as f:
        f.write(text)
    try:
        scene = mi.load_file(f.name, res=a.res)
    finally:
        os.unlink(f.name)
    mi.register_integrator("smooth_both_ends", lambda props: SmoothBothEnds(props))
    integrator = mi.load_dict({"type": "smooth_both_ends"})
    start = time.perf_counter()
    means = np.array([
        np.array(mi.render(scene, integrator=integrator, spp=a.spp, seed=2000 + k), dtype=np.float64)
        .reshape(-1, 3).mean(axis=0)
        for k in range(a.chunks)
    ])
    print(f"{a.name}: L S+ D ... S+ E by a sphere light of radius {a.radius} at {a.res}x{a.res}, "
          f"{a.chunks} chunks of {a.spp} spp, {time.perf_counter() - start:.0f} s: image mean {means.mean(axis=0)} "
          f"+- {means.std(axis=0, ddof=1) / np.sqrt(a.chunks)}")


if __name__ == "__main__":
    main()
