//! The BVH traversal alone on a scene's meshes: rays traced through the test kernel bvh_trace.comp (the
//! traversal of shaders/common/bvh.glsl), best of three dispatches, in two sets: camera rays through
//! every pixel (coherent, as the eye pass traces them) and rays leaving random points of the triangles
//! in cosine-distributed directions (incoherent, as photons bounce).
//!
//! cargo run --release -p ppm-vk-engine --example bvh_trace -- scenes/glass-on-table.toml [--rays 1000000]

use anyhow::{bail, Context as _, Result};
use ppm_vk_engine::bvh::{self, BvhOptions, DeviceBvh, TriangleInput};
use ppm_vk_engine::{Context, ContextOptions, Scene};
use ppm_vk_kernels::bvh_trace::{self, TraceHit, TracePush, TraceRay};
use ppm_vk_reference::rng::Rng;

fn main() -> Result<()> {
    let mut path = None;
    let mut n = 1_000_000usize;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--rays" => {
                let v = args.next().context("--rays needs a value")?;
                n = v.parse().with_context(|| format!("--rays {v}"))?;
            }
            _ if path.is_none() => path = Some(a),
            _ => bail!("unknown argument {a} (SCENE [--rays N])"),
        }
    }
    let path = path.context("usage: bvh_trace SCENE [--rays N]")?;
    let scene = Scene::load(&path)?;
    let input = TriangleInput::of_scene(&scene);
    if input.is_empty() {
        bail!("{path}: no triangles");
    }
    let b = bvh::build(&input, &BvhOptions::default())?;
    println!(
        "{path}: {} triangles, {} binary nodes (depth {}), {} wide nodes, stack bound {}",
        b.stats.triangles, b.stats.nodes, b.stats.depth, b.stats.wide_nodes, b.stats.stack_bound
    );
    let ctx = Context::new(&ContextOptions::default()).context("opening the Vulkan device")?;
    let dev = DeviceBvh::new(&ctx, &b)?;
    let kernel = ppm_vk_kernels::pipeline(&ctx, &ppm_vk_kernels::reflected::BVH_TRACE)?;

    // Camera rays, row by row, over as many frames as make n.
    let cam = &scene.camera;
    let forward = (cam.look_at - cam.eye).normalize();
    let right = forward.cross(cam.up).normalize();
    let up = right.cross(forward);
    let tan = (cam.vfov_deg.to_radians() * 0.5).tan();
    let aspect = cam.width as f32 / cam.height as f32;
    let pixels = (cam.width * cam.height) as usize;
    let camera: Vec<TraceRay> = (0..n)
        .map(|i| {
            let p = i % pixels;
            let (px, py) = ((p as u32 % cam.width) as f32 + 0.5, (p as u32 / cam.width) as f32 + 0.5);
            let sx = (2.0 * px / cam.width as f32 - 1.0) * aspect * tan;
            let sy = (1.0 - 2.0 * py / cam.height as f32) * tan;
            TraceRay {
                origin: cam.eye.to_array(),
                tmin: 0.0,
                dir: (forward + sx * right + sy * up).normalize().to_array(),
                tmax: f32::INFINITY,
            }
        })
        .collect();
    // Bounce rays: a random point of a random triangle, off its front side, cosine-distributed.
    let mut rng = Rng::new(7, 1);
    let (lo, hi) = scene.bounds();
    let eps = 1e-4 * (hi - lo).max_element();
    let bounce: Vec<TraceRay> = (0..n)
        .map(|_| {
            let t = &input[(rng.float() * input.len() as f32) as usize % input.len()];
            let (mut a, mut c) = (rng.float(), rng.float());
            if a + c > 1.0 {
                (a, c) = (1.0 - a, 1.0 - c);
            }
            let p = t.v[0] + a * (t.v[1] - t.v[0]) + c * (t.v[2] - t.v[0]);
            let nrm = (t.v[1] - t.v[0]).cross(t.v[2] - t.v[0]).normalize();
            let d = ppm_vk_reference::trace::cosine_direction(nrm, rng.float(), rng.float());
            TraceRay {
                origin: (p + eps * nrm).to_array(),
                tmin: 0.0,
                dir: d.to_array(),
                tmax: f32::INFINITY,
            }
        })
        .collect();
    let budget: u32 = std::env::var("BUDGET")
        .ok()
        .and_then(|b| b.parse().ok())
        .unwrap_or(bvh_trace::MAX_BUDGET);
    for (name, rays) in [("camera", &camera), ("bounce", &bounce)] {
        let ray_buf = ctx.buffer_from("rays", rays)?;
        let hit_buf = ctx.buffer_from("hits", &vec![TraceHit::default(); n])?;
        let push = TracePush {
            count: n as u32,
            budget,
            any_hit: 0,
        };
        let mut best = f64::INFINITY;
        for _ in 0..3 {
            // The first dispatch also compiles the kernel: best of three.
            let start = std::time::Instant::now();
            ctx.run(|cmd| bvh_trace::record(&kernel, cmd, &dev.nodes, &dev.triangles, &ray_buf, &hit_buf, &push))?;
            best = best.min(start.elapsed().as_secs_f64());
        }
        let hits: Vec<TraceHit> = ctx.download(&hit_buf)?;
        let hit = hits.iter().filter(|h| h.triangle != bvh_trace::NO_HIT).count();
        let steps = hits.iter().map(|h| h.steps as f64).sum::<f64>() / n as f64;
        let group = hits.iter().map(|h| h.subgroup_cost as f64).sum::<f64>() / n as f64;
        println!(
            "{name:6}: {n} rays in {:.1} ms = {:.2} M rays/s; {steps:.1} steps per ray, {group:.1} per subgroup; {:.1}% hit",
            best * 1e3,
            n as f64 / best / 1e6,
            100.0 * hit as f64 / n as f64
        );
    }
    Ok(())
}
