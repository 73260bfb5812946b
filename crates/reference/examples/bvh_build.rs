//! BVH build speed and memory on a generated 1M-triangle mesh (a closed UV sphere, 1000 x 501) and a
//! 1M-triangle random soup: best of `--runs` builds per thread count. `--trace N` also traces N rays from
//! inside the sphere through its BVH on the Vulkan device (the test kernel bvh_trace.comp).
//!
//! cargo run --release -p ppm-vk-engine --example bvh_build [-- --triangles 1000000 --runs 5 --trace 1000000]

use anyhow::{bail, Context as _, Result};
use glam::Vec3;
use ppm_vk_engine::bvh::{self, Bvh, BvhOptions, DeviceBvh, TriangleInput};
use ppm_vk_engine::{Context, ContextOptions};
use ppm_vk_kernels::bvh_trace::{self, TraceHit, TracePush, TraceRay};
use ppm_vk_reference::meshes;
use ppm_vk_reference::rng::Rng;

fn main() -> Result<()> {
    let mut triangles = 1_000_000usize;
    let mut runs = 5usize;
    let mut trace = 0usize;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let value = args.next().with_context(|| format!("{a} needs a value"))?;
        match a.as_str() {
            "--triangles" => triangles = value.parse().with_context(|| format!("--triangles {value}"))?,
            "--runs" => runs = value.parse().with_context(|| format!("--runs {value}"))?,
            "--trace" => trace = value.parse().with_context(|| format!("--trace {value}"))?,
            _ => bail!("unknown argument {a} (--triangles N, --runs N, --trace N)"),
        }
    }
    // 2 segments (rings - 1) triangles with segments = 2 (rings - 1).
    let half = ((triangles as f64 / 4.0).sqrt().round() as u32).max(2);
    let sphere = meshes::uv_sphere(Vec3::ZERO, 1.0, half + 1, 2 * half, 0);
    let soup = meshes::random_soup(1, sphere.len(), 100.0, 0.5);
    let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    println!("{} logical cores", cores);
    let mut sphere_bvh = None;
    for (name, mesh) in [("sphere", &sphere), ("soup", &soup)] {
        for threads in [1, cores] {
            let b = measure(name, mesh, threads, runs)?;
            if name == "sphere" {
                sphere_bvh = Some(b);
            }
        }
    }
    if trace > 0 {
        trace_rays(&sphere_bvh.expect("built above"), trace)?;
    }
    Ok(())
}

/// Rays from random points inside the unit sphere in random directions, traced on the device; every one
/// must hit (the mesh is closed).
fn trace_rays(b: &Bvh, n: usize) -> Result<()> {
    let ctx = Context::new(&ContextOptions::default()).context("opening the Vulkan device")?;
    let dev = DeviceBvh::new(&ctx, b)?;
    let mut rng = Rng::new(3, 4);
    let mut point = || loop {
        let v = Vec3::new(rng.float(), rng.float(), rng.float()) * 2.0 - 1.0;
        if v.length_squared() < 0.8 && v.length_squared() > 1e-4 {
            return v;
        }
    };
    let rays: Vec<TraceRay> = (0..n)
        .map(|_| TraceRay {
            origin: (0.5 * point()).to_array(),
            tmin: 0.0,
            dir: point().normalize().to_array(),
            tmax: f32::INFINITY,
        })
        .collect();
    let ray_buf = ctx.buffer_from("rays", &rays)?;
    let hit_buf = ctx.buffer_from("hits", &vec![TraceHit::default(); n])?;
    let kernel = ppm_vk_kernels::pipeline(&ctx, &ppm_vk_kernels::reflected::BVH_TRACE)?;
    let push = TracePush {
        count: n as u32,
        budget: bvh_trace::MAX_BUDGET,
        any_hit: 0,
    };
    let mut best = f64::INFINITY;
    for _ in 0..3 {
        // The first dispatch also compiles the kernel (lavapipe compiles at first use): best of three.
        let start = std::time::Instant::now();
        ctx.run(|cmd| bvh_trace::record(&kernel, cmd, &dev.nodes, &dev.triangles, &ray_buf, &hit_buf, &push))?;
        best = best.min(start.elapsed().as_secs_f64());
    }
    let hits: Vec<TraceHit> = ctx.download(&hit_buf)?;
    let missed = hits.iter().filter(|h| h.triangle == bvh_trace::NO_HIT).count();
    let cut = hits.iter().filter(|h| h.cut != 0).count();
    let steps: f64 = hits.iter().map(|h| h.steps as f64).sum::<f64>() / n as f64;
    println!(
        "trace on {}: {n} rays from inside the sphere in {:.1} ms = {:.2} M rays/s, {steps:.1} steps per ray, {missed} missed, {cut} cut",
        ctx.info().name,
        best * 1e3,
        n as f64 / best / 1e6
    );
    if missed + cut > 0 {
        bail!("{missed} rays missed and {cut} were cut inside a closed mesh");
    }
    Ok(())
}

fn measure(name: &str, mesh: &[TriangleInput], threads: usize, runs: usize) -> Result<Bvh> {
    let opts = BvhOptions {
        threads,
        ..BvhOptions::default()
    };
    let mut best = f64::INFINITY;
    let mut last = None;
    for _ in 0..runs.max(1) {
        let b = bvh::build(mesh, &opts).with_context(|| format!("building over the {name}"))?;
        best = best.min(b.stats.build_seconds);
        last = Some(b);
    }
    let b = last.expect("at least one run");
    let s = &b.stats;
    let bytes = b.node_bytes() + b.triangle_bytes();
    println!(
        "{name:6} {} triangles, {threads} thread(s): best of {runs} {:.1} ms = {:.2} M triangles/s; {} nodes ({} leaves, \
         depth {}, SAH cost {:.1}, {} median splits, {} dropped); nodes {:.1} MB + triangles {:.1} MB = {:.1} bytes/triangle",
        s.triangles,
        best * 1e3,
        s.input as f64 / best / 1e6,
        s.nodes,
        s.leaves,
        s.depth,
        s.sah_cost,
        s.median_splits,
        s.dropped,
        b.node_bytes() as f64 / 1e6,
        b.triangle_bytes() as f64 / 1e6,
        bytes as f64 / s.triangles as f64
    );
    Ok(b)
}
