//! The GLSL BVH traversal (`shaders/common/bvh.glsl`, through the test kernel `bvh_trace.comp`) against its
//! CPU twin `ppm_vk_reference::bvh` on the very same nodes, and the loop budget that keeps
//! lavapipe from cutting a traversal short without a word.

mod common;

use common::*;
use glam::Vec3;
use ppm_vk_engine::bvh::{self, Bvh, BvhOptions, BvhTracer, DeviceBvh, TriangleInput, MAX_DEPTH, STACK};
use ppm_vk_engine::layout::{BvhNode, Triangle};
use ppm_vk_kernels::bvh_trace::{TraceHit, TraceRay, MAX_BUDGET, NO_HIT};
use ppm_vk_reference::bvh::{brute_force, intersect, normal, Traversal};
use ppm_vk_reference::meshes;
use ppm_vk_reference::rng::Rng;

fn ray(o: Vec3, d: Vec3) -> TraceRay {
    TraceRay {
        origin: o.to_array(),
        tmin: 0.0,
        dir: d.to_array(),
        tmax: f32::INFINITY,
    }
}

fn cpu(b: &Bvh, r: &TraceRay, budget: u32) -> Traversal {
    intersect(
        &b.wide,
        &b.triangles,
        Vec3::from(r.origin),
        Vec3::from(r.dir),
        r.tmin,
        r.tmax,
        budget,
    )
}

fn built(input: &[TriangleInput]) -> Bvh {
    let b = bvh::build(input, &BvhOptions::default()).unwrap();
    b.validate(bvh::MAX_LEAF, MAX_DEPTH).unwrap();
    b
}

/// Panics unless every GPU hit is the CPU's: the same triangle and step count, t within 1e-6 relative.
/// Returns (hits, hits with a bit-identical t).
fn assert_gpu_matches_cpu(b: &Bvh, rays: &[TraceRay], gpu: &[TraceHit], budget: u32, what: &str) -> (usize, usize) {
    assert_eq!(gpu.len(), rays.len());
    let (mut hits, mut identical) = (0, 0);
    for (i, (r, g)) in rays.iter().zip(gpu).enumerate() {
        let c = cpu(b, r, budget);
        let ctx = format!("{what}, ray {i} {r:?}: GPU {g:?}, CPU {c:?}");
        assert_eq!(g.cut != 0, c.cut, "{ctx}");
        assert_eq!(g.root_child, b.wide[0].child[0], "{ctx}");
        assert_eq!(g.steps, c.steps, "{ctx}");
        match c.hit {
            None => assert_eq!(g.triangle, NO_HIT, "{ctx}"),
            Some(h) => {
                assert_eq!(g.triangle, h.triangle, "{ctx}");
                assert!((g.t - h.t).abs() <= 1e-6 * h.t.abs(), "{ctx}");
                assert!(
                    (Vec3::from(g.normal) - normal(&b.triangles[h.triangle as usize])).length() <= 1e-6,
                    "{ctx}"
                );
                assert!((glam::Vec2::from(g.bary) - h.bary).abs().max_element() <= 1e-5, "{ctx}");
                hits += 1;
                identical += (g.t == h.t) as usize;
            }
        }
    }
    (hits, identical)
}

/// bvh_subgroup_cost is what lavapipe's loop counter takes for the call: the most steps of any lane of the
/// subgroup (consecutive invocations) plus the loop's exit.
fn assert_subgroup_cost(gpu: &[TraceHit], what: &str) {
    let size = gpu[0].subgroup_size as usize;
    assert!(size > 0 && gpu.iter().all(|h| h.subgroup_size as usize == size));
    for (k, group) in gpu.chunks(size).enumerate() {
        let most = group.iter().map(|h| h.steps).max().unwrap();
        assert!(
            group.iter().all(|h| h.subgroup_cost == most + 1),
            "{what}: subgroup {k}: {group:?}"
        );
    }
}

fn random_unit(rng: &mut Rng) -> Vec3 {
    loop {
        let v = Vec3::new(rng.float(), rng.float(), rng.float()) * 2.0 - 1.0;
        if v.length_squared() > 1e-4 && v.length_squared() <= 1.0 {
            return v.normalize();
        }
    }
}

/// Rays from `origins` through every vertex, edge middle and a random edge point of `mesh`, plus random
/// rays (some axis-parallel, some not unit).
fn rays_at(mesh: &[TriangleInput], origins: &[Vec3], random: usize, seed: u64) -> Vec<TraceRay> {
    let mut rng = Rng::new(seed, 3);
    let mut rays = Vec::new();
    for &o in origins {
        for t in mesh {
            for target in [
                t.v[0],
                t.v[1],
                t.v[2],
                (t.v[0] + t.v[1]) * 0.5,
                t.v[1].lerp(t.v[2], rng.float()),
            ] {
                rays.push(ray(o, target - o));
            }
        }
    }
    for k in 0..random {
        let o = origins[k % origins.len()] + (Vec3::new(rng.float(), rng.float(), rng.float()) - 0.5) * 0.1;
        let d = match k % 8 {
            0 => Vec3::new(0.0, -1.0, 0.0),
            1 => Vec3::new(0.6, 0.0, -0.8),
            2 => random_unit(&mut rng) * 3.0,
            _ => random_unit(&mut rng),
        };
        rays.push(ray(o, d));
    }
    rays
}

#[test]
fn bvh_gpu_traversal_matches_cpu_reference() {
    let ctx = ctx();
    let tracer = BvhTracer::new(&ctx).unwrap();
    // Inside even after the random rays' jitter of up to 0.05 per axis.
    let sphere_origins = [Vec3::ZERO, Vec3::new(0.3, -0.2, 0.1), Vec3::new(-0.4, 0.4, -0.5)];
    let box_origins = [Vec3::ZERO, Vec3::new(0.25, -0.125, 0.5)];
    let soup_origins = [Vec3::splat(0.5), Vec3::new(-0.5, 0.2, 0.4), Vec3::new(1.5, 1.5, 1.5)];
    let cases: [(&str, Vec<TriangleInput>, &[Vec3], bool); 4] = [
        (
            "sphere",
            meshes::uv_sphere(Vec3::ZERO, 1.0, 24, 32, 0),
            &sphere_origins,
            true,
        ),
        (
            "box",
            meshes::box_grid(Vec3::splat(-1.0), Vec3::splat(1.0), 8, 0),
            &box_origins,
            true,
        ),
        (
            "sparse soup",
            meshes::random_soup(21, 300, 1.0, 0.05),
            &soup_origins,
            false,
        ),
        (
            "dense soup",
            meshes::random_soup(22, 3000, 1.0, 0.3),
            &soup_origins,
            false,
        ),
    ];
    for (name, mesh, origins, closed) in cases {
        let b = built(&mesh);
        let dev = DeviceBvh::new(&ctx, &b).unwrap();
        let rays = rays_at(&mesh, origins, 4000, 5);
        let gpu = tracer.trace(&ctx, &dev, &rays, MAX_BUDGET).unwrap();
        let (hits, identical) = assert_gpu_matches_cpu(&b, &rays, &gpu, MAX_BUDGET, name);
        println!(
            "{name}: {} triangles, {} rays, {hits} hits, {identical} with a bit-identical t",
            mesh.len(),
            rays.len()
        );
        assert!(hits * 4 >= rays.len(), "{name}: only {hits} of {} rays hit", rays.len());
        assert_subgroup_cost(&gpu, name);
        if closed {
            // Every origin is inside: watertight on the GPU too.
            let missed: Vec<_> = rays
                .iter()
                .zip(&gpu)
                .filter(|(_, h)| h.triangle == NO_HIT)
                .map(|(r, _)| *r)
                .collect();
            assert!(
                missed.is_empty(),
                "{name}: rays left the closed mesh on the GPU: {missed:?}"
            );
        }
    }
    assert_clean(&ctx);
}

/// `n` copies of one triangle, and rays from above through `count` points of it.
fn stack(n: usize, jitter: f32) -> (Vec<TriangleInput>, Vec<TraceRay>) {
    let mut rng = Rng::new(n as u64, 9);
    let mut j = || (Vec3::new(rng.float(), rng.float(), rng.float()) - 0.5) * jitter;
    let mesh = (0..n)
        .map(|_| TriangleInput {
            v: [Vec3::ZERO + j(), Vec3::X + j(), Vec3::Y + j()],
            material: 0,
        })
        .collect();
    let rays = (0..64)
        .map(|k| {
            let p = Vec3::new(0.1 + 0.3 * (k % 8) as f32 / 8.0, 0.1 + 0.3 * (k / 8) as f32 / 8.0, 1.0);
            ray(p, -Vec3::Z)
        })
        .collect();
    (mesh, rays)
}

/// Thousands of overlapping triangles: every box along the ray holds the hit, so the traversal visits
/// them all. The GPU's hit is then the exact nearest one, or the traversal was cut and `trace` fails;
/// never a silent miss.
#[test]
fn bvh_gpu_overlapping_triangles_hit_exactly_or_fail() {
    let ctx = ctx();
    let tracer = BvhTracer::new(&ctx).unwrap();
    let (mut exact, mut failed) = (0, 0);
    for (n, jitter) in [
        (1000, 0.0),
        (10_000, 0.0),
        (10_000, 1e-3),
        (30_000, 1e-4),
        (60_000, 0.0),
        (60_000, 1e-3),
        (80_000, 0.0),
    ] {
        let (mesh, rays) = stack(n, jitter);
        let b = built(&mesh);
        let dev = DeviceBvh::new(&ctx, &b).unwrap();
        let need = rays.iter().map(|r| cpu(&b, r, u32::MAX).steps).max().unwrap();
        match tracer.trace(&ctx, &dev, &rays, MAX_BUDGET) {
            Ok(hits) => {
                assert!(need <= MAX_BUDGET, "{n}: {need} steps needed, yet not cut");
                for (r, h) in rays.iter().zip(&hits) {
                    let want = brute_force(
                        &b.triangles,
                        Vec3::from(r.origin),
                        Vec3::from(r.dir),
                        0.0,
                        f32::INFINITY,
                    )
                    .unwrap();
                    assert_eq!(h.t, want.t, "{n} triangles: ray {r:?}");
                }
                assert_gpu_matches_cpu(&b, &rays, &hits, MAX_BUDGET, "stack");
                exact += 1;
            }
            Err(e) => {
                assert!(need > MAX_BUDGET, "{n}: cut though {need} steps suffice");
                assert!(format!("{e:#}").contains("cut at the budget"), "{e:#}");
                // The records say which rays: each cut exactly at the budget.
                let raw = tracer.trace_unchecked(&ctx, &dev, &rays, MAX_BUDGET).unwrap();
                assert!(raw.iter().any(|h| h.cut != 0 && h.steps == MAX_BUDGET));
                failed += 1;
            }
        }
        println!(
            "{n} overlapping triangles (jitter {jitter}): depth {}, up to {need} steps per ray",
            b.stats.depth
        );
    }
    assert!(
        exact > 0 && failed > 0,
        "both outcomes should occur: {exact} exact, {failed} failed"
    );
    assert_clean(&ctx);
}

/// The budget at lavapipe's limit: a traversal of exactly MAX_BUDGET steps (the loop's 65535th iteration
/// is its exit) finishes with the right hit, one step more is cut and reported, never cut silently.
#[test]
fn bvh_gpu_loop_budget_at_the_bound() {
    let ctx = ctx();
    let tracer = BvhTracer::new(&ctx).unwrap();
    let steps_for = |n: usize| {
        let (mesh, rays) = stack(n, 0.0);
        let b = built(&mesh);
        let s = cpu(&b, &rays[0], u32::MAX).steps;
        (b, rays, s)
    };
    // The most identical triangles whose traversal fits the budget (steps grow with the count).
    let (mut lo, mut hi) = (1000usize, 80_000usize);
    assert!(steps_for(lo).2 <= MAX_BUDGET && steps_for(hi).2 > MAX_BUDGET);
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if steps_for(mid).2 <= MAX_BUDGET {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let (b, rays, s) = steps_for(lo);
    println!(
        "{lo} identical triangles: {s} steps per ray (budget {MAX_BUDGET}); {} triangles: {}",
        hi,
        steps_for(hi).2
    );
    assert!(s + 3 > MAX_BUDGET, "{s} steps: not at the bound");
    let dev = DeviceBvh::new(&ctx, &b).unwrap();
    let hits = tracer.trace(&ctx, &dev, &rays, MAX_BUDGET).unwrap();
    assert_gpu_matches_cpu(&b, &rays, &hits, MAX_BUDGET, "at the bound");
    assert!(hits.iter().all(|h| h.triangle != NO_HIT && h.steps <= s));
    // One step short: cut, on every lane that needed them all.
    let short = tracer.trace_unchecked(&ctx, &dev, &rays, s - 1).unwrap();
    assert_gpu_matches_cpu(&b, &rays, &short, s - 1, "one step short");
    assert!(short[0].cut == 1 && tracer.trace(&ctx, &dev, &rays, s - 1).is_err());
    // One triangle more needs more than the budget: an error, not lavapipe's silent cut.
    let (b, rays, _) = steps_for(hi);
    let dev = DeviceBvh::new(&ctx, &b).unwrap();
    assert!(tracer.trace(&ctx, &dev, &rays, MAX_BUDGET).is_err());
    // A budget past the limit is refused.
    assert!(tracer.trace_unchecked(&ctx, &dev, &rays, MAX_BUDGET + 1).is_err());
    assert_clean(&ctx);
}

/// A 4-wide tree whose traversal fills the stack exactly: a spine of `depth` nodes, each with the next
/// spine node as its nearest child along +x and three leaves of one triangle each behind it; the last
/// node has four leaves. Going down the spine pushes three leaves a level. Made by hand: a built tree of
/// MAX_DEPTH binary levels needs far fewer entries (bvh_depth_limit_at_the_bound).
fn spine(depth: u32) -> Bvh {
    let end = 4.0 * depth as f32 + 4.0;
    let across = |x: f32| ([x, -1.0, -1.0], [x, 2.0, 2.0]);
    let mut wide = Vec::new();
    let mut triangles = Vec::new();
    for k in 0..depth {
        let mut children = Vec::new();
        let base = 4.0 * k as f32;
        if k + 1 == depth {
            let x = base + 0.75;
            children.push((across(x).0, across(x).1, BvhNode::leaf(triangles.len() as u32, 1)));
            triangles.push(x);
        } else {
            children.push(([base + 0.5, -1.0, -1.0], [end, 2.0, 2.0], k + 1));
        }
        for slot in 1..4 {
            let x = base + slot as f32;
            children.push((across(x).0, across(x).1, BvhNode::leaf(triangles.len() as u32, 1)));
            triangles.push(x);
        }
        wide.push(BvhNode::new(&children));
    }
    let triangles = triangles
        .iter()
        .enumerate()
        .map(|(i, &x)| Triangle {
            v0: [x, -1.0, -1.0],
            v1: [x, 2.0, -1.0],
            v2: [x, -1.0, 2.0],
            source: i as u32,
            ..Default::default()
        })
        .collect();
    Bvh {
        wide,
        triangles,
        ..Bvh::default()
    }
}

#[test]
fn bvh_gpu_stack_at_its_bound() {
    let ctx = ctx();
    let tracer = BvhTracer::new(&ctx).unwrap();
    let depth = STACK / 3;
    let b = spine(depth);
    b.validate_wide().unwrap();
    assert_eq!(
        bvh::stack_bound(&b.wide),
        STACK,
        "the spine should need exactly the whole stack"
    );
    let dev = DeviceBvh::new(&ctx, &b).unwrap();
    let rays = vec![
        ray(Vec3::new(-1.0, 0.25, 0.25), Vec3::X),
        ray(Vec3::new(1000.0, 0.5, 0.1), -Vec3::X),
    ];
    let hits = tracer.trace(&ctx, &dev, &rays, MAX_BUDGET).unwrap();
    assert_gpu_matches_cpu(&b, &rays, &hits, MAX_BUDGET, "spine");
    let x = |h: &TraceHit| b.triangles[h.triangle as usize].v0[0];
    assert_eq!(x(&hits[0]), 1.0, "the nearest triangle along +x is the first");
    assert_eq!(
        x(&hits[1]),
        4.0 * (depth - 1) as f32 + 3.0,
        "the nearest along -x is the last"
    );
    // Along +x the stack is full at the bottom of the spine.
    assert_eq!(cpu(&b, &rays[0], MAX_BUDGET).stack_peak, STACK);
    // One level more than the stack holds is refused before it reaches the GPU.
    let err = DeviceBvh::new(&ctx, &spine(depth + 1))
        .err()
        .expect("a tree deeper than the stack");
    assert!(format!("{err:#}").contains("stack entries"), "{err:#}");
    // What makes STACK enough for every built tree: the wide tree's stack needs at most three entries per
    // binary level, and build() keeps to MAX_DEPTH levels. A deep chain (39 levels) shows the bound.
    let b = built(&meshes::growing_chain(100, 2.0));
    println!("chain of 100: {:?}", b.stats);
    assert!(
        b.stats.depth > 32 && b.stats.stack_bound <= 3 * b.stats.depth,
        "{:?}",
        b.stats
    );
    assert_clean(&ctx);
}
