//! BVH build speed and memory on a generated 1M-triangle mesh (a closed UV sphere, 1000 x 501) and a
//! 1M-triangle random soup: best of `--runs` builds per thread count.
//!
//! cargo run --release -p ppm-vk-engine --example bvh_build [-- --triangles 1000000 --runs 5]

use anyhow::{bail, Context as _, Result};
use glam::Vec3;
use ppm_vk_engine::bvh::{self, meshes, BvhOptions, TriangleInput};

fn main() -> Result<()> {
    let mut triangles = 1_000_000usize;
    let mut runs = 5usize;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let value = args.next().with_context(|| format!("{a} needs a value"))?;
        match a.as_str() {
            "--triangles" => triangles = value.parse().with_context(|| format!("--triangles {value}"))?,
            "--runs" => runs = value.parse().with_context(|| format!("--runs {value}"))?,
            _ => bail!("unknown argument {a} (--triangles N, --runs N)"),
        }
    }
    // 2 segments (rings - 1) triangles with segments = 2 (rings - 1).
    let half = ((triangles as f64 / 4.0).sqrt().round() as u32).max(2);
    let sphere = meshes::uv_sphere(Vec3::ZERO, 1.0, half + 1, 2 * half, 0);
    let soup = meshes::random_soup(1, sphere.len(), 100.0, 0.5);
    let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    println!("{} logical cores", cores);
    for (name, mesh) in [("sphere", &sphere), ("soup", &soup)] {
        for threads in [1, cores] {
            measure(name, mesh, threads, runs)?;
        }
    }
    Ok(())
}

fn measure(name: &str, mesh: &[TriangleInput], threads: usize, runs: usize) -> Result<()> {
    let opts = BvhOptions { threads, ..BvhOptions::default() };
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
    Ok(())
}
