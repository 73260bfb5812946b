//! The BVH builder (crates/engine/src/bvh/) against brute force through the CPU twin's traversal: the
//! same nearest hits on soups, closed meshes that are watertight from inside, degenerate and identical
//! triangles, the depth and step bounds, determinism across threads. Moved from the builder's unit tests
//! when the twin became a crate of its own.

use glam::Vec3;

use ppm_vk_engine::bvh::*;
use ppm_vk_reference::bvh::{brute_force, intersect, triangle_test, BvhRay};
use ppm_vk_reference::meshes::*;
use ppm_vk_reference::rng::Rng;
use ppm_vk_reference::trace::v3;

const NO_BUDGET: u32 = u32::MAX;

fn built(input: &[TriangleInput]) -> Bvh {
    let bvh = build(input, &BvhOptions::default()).unwrap();
    bvh.validate(MAX_LEAF, MAX_DEPTH).unwrap();
    bvh.validate_wide().unwrap();
    bvh
}

fn random_unit(rng: &mut Rng) -> Vec3 {
    loop {
        let v = Vec3::new(rng.float(), rng.float(), rng.float()) * 2.0 - 1.0;
        if v.length_squared() > 1e-4 && v.length_squared() <= 1.0 {
            return v.normalize();
        }
    }
}

/// Traces (o, d) through the BVH and by brute force; panics unless both find the same nearest hit.
/// Returns the hit and whether its t is bit-identical to brute force's.
///
/// Where several triangles meet the ray at one point (a shared vertex or edge), each one's t is that
/// distance rounded its own way, a few ulps apart, and a box is culled by a distance that rounded the
/// way of none of them; so there the BVH may report one of them a few ulps farther than the nearest of
/// the rounded values. Never nearer: brute force tests everything.
fn same_as_brute_force(bvh: &Bvh, o: Vec3, d: Vec3, what: &str) -> Option<(reference::bvh::BvhHit, bool)> {
    let got = intersect(&bvh.wide, &bvh.triangles, o, d, 0.0, f32::INFINITY, NO_BUDGET);
    assert!(!got.cut);
    let want = brute_force(&bvh.triangles, o, d, 0.0, f32::INFINITY);
    match (got.hit, want) {
        (None, None) => None,
        (Some(g), Some(w)) => {
            let r = BvhRay::new(o, d);
            let test = |i: u32| {
                let t = &bvh.triangles[i as usize];
                triangle_test(&r, v3(t.v0), v3(t.v1), v3(t.v2), 0.0, f32::INFINITY).map(|h| h.0)
            };
            let exact = g.t == w.t;
            assert!(
                g.t >= w.t && g.t - w.t <= 2e-6 * g.t,
                "{what}: ray {o} {d}: BVH t {} (triangle {}), brute force {} ({})",
                g.t,
                g.triangle,
                w.t,
                w.triangle
            );
            assert_eq!(
                test(g.triangle),
                Some(g.t),
                "{what}: the BVH's hit is not its triangle's"
            );
            // Independent of the test's arithmetic: the barycentric point is the ray's point.
            let t = &bvh.triangles[g.triangle as usize];
            let p = (1.0 - g.bary.x - g.bary.y) * v3(t.v0) + g.bary.x * v3(t.v1) + g.bary.y * v3(t.v2);
            let q = o + g.t * d;
            let scale = o.abs().max_element().max(q.abs().max_element()).max(1.0);
            assert!(
                (p - q).length() <= 1e-4 * scale,
                "{what}: barycentric point {p} is not the ray's {q}"
            );
            assert!(
                g.bary.min_element() >= -1e-5 && g.bary.x + g.bary.y <= 1.0 + 1e-5,
                "{what}: bary {}",
                g.bary
            );
            Some((g, exact))
        }
        (g, w) => panic!("{what}: ray {o} {d}: BVH {g:?}, brute force {w:?}"),
    }
}

use ppm_vk_reference as reference;

#[test]
fn bvh_matches_brute_force_on_random_soups() {
    for (seed, n, size) in [
        (1, 1, 0.3),
        (2, 2, 0.3),
        (3, 7, 0.2),
        (4, 100, 0.1),
        (5, 3000, 0.05),
        (6, 3000, 0.5),
    ] {
        let input = random_soup(seed, n, 1.0, size);
        let bvh = built(&input);
        assert_eq!(bvh.stats.triangles, n);
        let mut rng = Rng::new(seed, 99);
        let (mut hits, mut inexact) = (0, 0);
        let rays = 2000;
        for k in 0..rays {
            let o = Vec3::new(rng.float(), rng.float(), rng.float()) * 1.6 - 0.3;
            let mut d = random_unit(&mut rng);
            match k % 10 {
                // Axis-parallel rays: direction components exactly 0 (the slab test's reciprocal).
                0 => d = Vec3::new(0.0, 0.0, d.z.signum()),
                1 => d = Vec3::new(d.x, 0.0, -0.0).normalize(),
                // Not unit: t is in units of |d|.
                2 => d *= 7.5,
                // Aimed at a vertex or an edge point of a random triangle.
                3 | 4 => {
                    let t = &input[rng.next_u32() as usize % n];
                    let target = if k % 10 == 3 {
                        t.v[0]
                    } else {
                        t.v[1].lerp(t.v[2], rng.float())
                    };
                    d = target - o;
                }
                _ => {}
            }
            if let Some((_, exact)) = same_as_brute_force(&bvh, o, d, &format!("soup {seed}, ray {k}")) {
                hits += 1;
                inexact += !exact as usize;
            }
        }
        println!(
            "soup {seed}: {n} triangles, {} nodes, depth {}, SAH {:.2}: {hits} of {rays} rays hit, {inexact} a few ulps off",
            bvh.stats.nodes, bvh.stats.depth, bvh.stats.sah_cost
        );
        // Only rays aimed at a vertex or an edge point can meet several triangles at one point.
        assert!(inexact * 50 <= rays, "soup {seed}: {inexact} hits not bit-identical");
        assert!(hits > rays / 10, "soup {seed}: only {hits} hits: the rays test little");
    }
}

/// From inside a closed mesh every ray hits, including those exactly through vertices and shared
/// edges, and the hit is the brute-force one.
fn watertight_from_inside(mesh: &[TriangleInput], inside: &[Vec3], what: &str) -> (usize, usize) {
    let bvh = built(mesh);
    let (mut rays, mut inexact) = (0, 0);
    let mut rng = Rng::new(7, 7);
    for &o in inside {
        for t in mesh {
            // Through each vertex, the middle of each edge and a random point on it.
            let targets = [
                t.v[0],
                t.v[1],
                t.v[2],
                (t.v[0] + t.v[1]) * 0.5,
                (t.v[1] + t.v[2]) * 0.5,
                (t.v[2] + t.v[0]) * 0.5,
                t.v[0].lerp(t.v[1], rng.float()),
                t.v[1].lerp(t.v[2], rng.float()),
            ];
            for target in targets {
                let d = target - o;
                let hit = same_as_brute_force(&bvh, o, d, what);
                let (_, exact) =
                    hit.unwrap_or_else(|| panic!("{what}: ray from {o} through {target} left the closed mesh"));
                rays += 1;
                inexact += !exact as usize;
            }
        }
    }
    (rays, inexact)
}

#[test]
fn bvh_closed_sphere_is_watertight() {
    let mesh = uv_sphere(Vec3::ZERO, 1.0, 24, 32, 0);
    assert_eq!(mesh.len(), 2 * 32 * 23);
    // The centre makes the ray through a vertex exactly the vertex's own coordinates.
    let inside = [
        Vec3::ZERO,
        Vec3::new(0.3, -0.2, 0.1),
        Vec3::new(0.0, 0.0, 0.9),
        Vec3::new(-0.5, 0.5, -0.6),
    ];
    let (rays, inexact) = watertight_from_inside(&mesh, &inside, "sphere");
    println!(
        "sphere: {rays} rays through vertices and edges, none missed; {inexact} hits a few ulps off brute force's"
    );
}

#[test]
fn bvh_closed_box_is_watertight() {
    // Coordinates on a 1/4 grid and origins on a 1/8 one: the rays pass exactly through the vertices and
    // the points of the shared (and diagonal) edges they aim at.
    let mesh = box_grid(Vec3::splat(-1.0), Vec3::splat(1.0), 8, 0);
    assert_eq!(mesh.len(), 12 * 64);
    let inside = [
        Vec3::ZERO,
        Vec3::new(0.25, -0.125, 0.5),
        Vec3::new(0.875, 0.875, -0.875),
    ];
    let (rays, inexact) = watertight_from_inside(&mesh, &inside, "box");
    println!("box: {rays} rays through vertices and edges, none missed; {inexact} hits a few ulps off brute force's");
    // Along an edge of the box from outside: in the planes of two faces (no hit there), through the
    // corner vertex of the third: the hit is that corner.
    let bvh = built(&mesh);
    for (o, d, corner) in [
        (Vec3::new(-3.0, -1.0, -1.0), Vec3::X, Vec3::new(-1.0, -1.0, -1.0)),
        (Vec3::new(1.0, 5.0, -1.0), -Vec3::Y, Vec3::new(1.0, 1.0, -1.0)),
        (Vec3::new(1.0, 1.0, 2.0), -Vec3::Z, Vec3::new(1.0, 1.0, 1.0)),
        // Along a shared edge inside the face z = 1, onto the edge between two faces.
        (Vec3::new(-3.0, 0.25, 1.0), Vec3::X, Vec3::new(-1.0, 0.25, 1.0)),
    ] {
        let (hit, _) =
            same_as_brute_force(&bvh, o, d, "along an edge").expect("a ray along an edge hits the face it runs into");
        assert_eq!(o + hit.t * d, corner, "ray {o} {d}");
    }
    // From outside, aimed at every vertex and edge middle of the face x = 1 off its outline (a ray
    // through the silhouette may pass outside): a hit at that very point (the box is convex).
    let o = Vec3::new(3.0, -2.5, 1.75);
    let mut aimed = 0;
    for t in &mesh {
        for (a, b) in [(t.v[0], t.v[1]), (t.v[1], t.v[2]), (t.v[2], t.v[0])] {
            for target in [a, (a + b) * 0.5] {
                if target.x != 1.0 || target.y.abs() == 1.0 || target.z.abs() == 1.0 {
                    continue;
                }
                let (hit, _) =
                    same_as_brute_force(&bvh, o, target - o, "from outside").expect("ray at a vertex missed");
                assert!((hit.t - 1.0).abs() <= 1e-6, "ray at {target} hit at t {}", hit.t);
                aimed += 1;
            }
        }
    }
    assert!(aimed > 100);
}

#[test]
fn bvh_drops_and_counts_degenerate_triangles() {
    let good = random_soup(11, 20, 1.0, 0.2);
    let p = Vec3::new(0.5, 0.5, 0.5);
    let mut input = good.clone();
    let bad = [
        [p, p, p],
        [p, p, Vec3::ONE],
        [Vec3::ZERO, Vec3::ONE, Vec3::splat(2.0)],
        [Vec3::new(f32::NAN, 0.0, 0.0), Vec3::X, Vec3::Y],
        [Vec3::new(0.0, f32::INFINITY, 0.0), Vec3::X, Vec3::Y],
    ];
    let mut bad_at = Vec::new();
    for (k, v) in bad.iter().enumerate() {
        let at = 3 * k + 1;
        input.insert(at, TriangleInput { v: *v, material: 0 });
        bad_at.push(at as u32);
    }
    // A tiny triangle is not degenerate: its f32 cross product would underflow, its area is not 0.
    let q = Vec3::new(0.0, 0.0, 0.5);
    let tiny = TriangleInput {
        v: [q, q + Vec3::X * 1e-25, q + Vec3::Y * 1e-25],
        material: 0,
    };
    input.push(tiny);
    let bvh = built(&input);
    assert_eq!(bvh.dropped, bad_at);
    assert_eq!(bvh.stats.dropped, bad.len());
    assert_eq!(bvh.stats.input, input.len());
    assert_eq!(bvh.stats.triangles, good.len() + 1);
    // Every kept triangle is its input, by `source`.
    for t in &bvh.triangles {
        let src = &input[t.source as usize];
        assert_eq!([t.v0, t.v1, t.v2], src.v.map(|v| v.to_array()));
        assert_eq!(t.material, src.material);
    }
}

#[test]
fn bvh_empty_and_single() {
    let empty = built(&[]);
    assert_eq!((empty.stats.nodes, empty.stats.triangles, empty.stats.depth), (1, 0, 0));
    let miss = intersect(
        &empty.wide,
        &empty.triangles,
        Vec3::ZERO,
        Vec3::X,
        0.0,
        f32::INFINITY,
        NO_BUDGET,
    );
    assert_eq!((miss.hit, miss.steps, miss.cut), (None, 1, false));
    let one = [TriangleInput {
        v: [Vec3::X, Vec3::Y, Vec3::Z],
        material: 3,
    }];
    let bvh = built(&one);
    assert_eq!((bvh.stats.nodes, bvh.stats.leaves, bvh.stats.depth), (1, 1, 0));
    let (hit, _) = same_as_brute_force(&bvh, Vec3::ZERO, Vec3::ONE, "single").unwrap();
    assert!((hit.t - 1.0 / 3.0).abs() < 1e-7);
}

/// The depth limit holds exactly where SAH alone would go deeper, and the tree is still right. (SAH
/// itself never nears MAX_DEPTH in f32: it takes sizes shrinking by about the triangle count at each
/// level. The GPU's stack at MAX_DEPTH is tested on a tree made by hand, tests/bvh.rs.)
#[test]
fn bvh_depth_limit_at_the_bound() {
    let chain = growing_chain(150, 1.25);
    let free = built(&chain);
    let limit = 12;
    assert!(free.stats.depth > limit, "SAH alone: depth {}", free.stats.depth);
    let opts = BvhOptions {
        max_depth: limit,
        ..BvhOptions::default()
    };
    let bvh = build(&chain, &opts).unwrap();
    bvh.validate(MAX_LEAF, limit).unwrap();
    println!(
        "chain of {}: depth {} by SAH, {} with the limit ({} median splits)",
        chain.len(),
        free.stats.depth,
        bvh.stats.depth,
        bvh.stats.median_splits
    );
    assert_eq!(bvh.stats.depth, limit);
    assert!(bvh.stats.median_splits > 0);
    // Rays onto every triangle, the deepest leaves included.
    for t in &chain {
        let target = (t.v[0] + t.v[1] + t.v[2]) / 3.0;
        let o = target + Vec3::new(0.1, -1.0, 0.3) * (t.v[1].x - t.v[0].x);
        assert!(same_as_brute_force(&bvh, o, target - o, "chain").is_some());
    }
    // The tightest limit: 4000 triangles in leaves of 4 need 10 levels.
    let soup = random_soup(3, 4000, 1.0, 0.05);
    let opts = BvhOptions {
        max_depth: 10,
        ..BvhOptions::default()
    };
    let bvh = build(&soup, &opts).unwrap();
    bvh.validate(MAX_LEAF, 10).unwrap();
    assert_eq!(bvh.stats.depth, 10);
    let err = build(&soup, &BvhOptions { max_depth: 9, ..opts }).unwrap_err();
    assert!(err.to_string().contains("10 levels deep"), "{err}");
    assert!(build(
        &soup,
        &BvhOptions {
            max_depth: MAX_DEPTH + 1,
            ..opts
        }
    )
    .is_err());
}

/// Thousands of identical triangles: no plane separates them; median splits, and every one is tested.
#[test]
fn bvh_identical_triangles() {
    let t = TriangleInput {
        v: [Vec3::ZERO, Vec3::X, Vec3::Y],
        material: 0,
    };
    let bvh = built(&vec![t; 5000]);
    assert_eq!(bvh.stats.depth, levels_needed(5000, MAX_LEAF as usize));
    assert!(bvh.stats.median_splits > 0);
    let o = Vec3::new(0.25, 0.25, 1.0);
    let (hit, _) = same_as_brute_force(&bvh, o, -Vec3::Z, "stack").unwrap();
    assert_eq!(hit.t, 1.0);
    // Every box holds the hit point, so every triangle is tested, one a step, the node visits beside
    // them in the same steps or in steps of their own.
    let r = intersect(&bvh.wide, &bvh.triangles, o, -Vec3::Z, 0.0, f32::INFINITY, NO_BUDGET);
    assert!(
        (5000..=5000 + bvh.wide.len()).contains(&(r.steps as usize)),
        "{} steps, {} wide nodes",
        r.steps,
        bvh.wide.len()
    );
}

/// A traversal that needs S steps finishes with a budget of S and is cut with S - 1.
#[test]
fn bvh_step_budget_at_the_bound() {
    let bvh = built(&uv_sphere(Vec3::ZERO, 1.0, 16, 16, 0));
    let mut rng = Rng::new(5, 5);
    for _ in 0..200 {
        let o = Vec3::new(rng.float(), rng.float(), rng.float()) * 0.5;
        let d = random_unit(&mut rng);
        let full = intersect(&bvh.wide, &bvh.triangles, o, d, 0.0, f32::INFINITY, NO_BUDGET);
        assert!(full.hit.is_some() && !full.cut);
        let exact = intersect(&bvh.wide, &bvh.triangles, o, d, 0.0, f32::INFINITY, full.steps);
        assert_eq!(exact, full);
        let short = intersect(&bvh.wide, &bvh.triangles, o, d, 0.0, f32::INFINITY, full.steps - 1);
        assert!(short.cut && short.steps == full.steps - 1);
    }
}

/// The parallel build makes the very tree the single-threaded one does.
#[test]
fn bvh_build_is_deterministic_across_threads() {
    let soup = random_soup(8, 50_000, 10.0, 0.1);
    let one = build(
        &soup,
        &BvhOptions {
            threads: 1,
            ..BvhOptions::default()
        },
    )
    .unwrap();
    let many = build(
        &soup,
        &BvhOptions {
            threads: 4,
            ..BvhOptions::default()
        },
    )
    .unwrap();
    many.validate(MAX_LEAF, MAX_DEPTH).unwrap();
    assert_eq!(one.nodes, many.nodes);
    assert_eq!(one.triangles, many.triangles);
    assert_eq!(one.stats.sah_cost, many.stats.sah_cost);
}

#[test]
fn bvh_stats_of_a_sphere() {
    let mesh = uv_sphere(Vec3::ZERO, 1.0, 101, 100, 0);
    let bvh = built(&mesh);
    let s = &bvh.stats;
    println!("{s:?}");
    assert_eq!((s.input, s.triangles, s.dropped), (mesh.len(), mesh.len(), 0));
    assert_eq!(s.nodes, 2 * s.leaves - 1);
    assert!(s.leaves >= mesh.len().div_ceil(MAX_LEAF as usize));
    // A ray that meets the root tests a handful of nodes and triangles, not 20000: the SAH cost of a
    // good tree over a closed surface is a few tens (one leaf of everything would cost 20000).
    assert!(s.sah_cost > 1.0 && s.sah_cost < 100.0, "SAH cost {}", s.sah_cost);
    assert!(
        s.depth >= levels_needed(mesh.len(), MAX_LEAF as usize) && s.depth < 40,
        "depth {}",
        s.depth
    );
    // The 4-wide nodes: 64 bytes each, about a third as many as the binary tree's (at most 4 children
    // where the binary has 2): fewer node bytes per triangle than the binary tree's 32-byte nodes.
    assert_eq!(bvh.node_bytes(), 64 * s.wide_nodes);
    assert!(
        s.wide_nodes * 3 <= s.nodes + 3 && bvh.node_bytes() < 32 * s.nodes,
        "{s:?}"
    );
    assert_eq!(bvh.triangle_bytes(), 48 * s.triangles);
}
