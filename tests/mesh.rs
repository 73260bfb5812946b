//! Triangle meshes rendered: against the analytic scenes they replace, a closed-form furnace, triangle
//! lights against the quad they tile, and a BVH too degenerate for the loop budget.

mod common;

use std::path::Path;

use common::*;
use glam::Vec3;
use ppm_vk_engine::metrics::{compare, Reference};
use ppm_vk_engine::scene::{Mesh, Surface};
use ppm_vk_engine::{Mode, Renderer, RgbImage, Scene, Settings};
use ppm_vk_scene_gen as demo;

fn scene(name: &str) -> Scene {
    demo::ensure(&demo::default_dir()).expect("writing the demo meshes");
    load(&format!("{}/scenes/{name}", env!("CARGO_MANIFEST_DIR")))
}

fn render(scene: &Scene, settings: Settings, passes: u32) -> RgbImage {
    let ctx = ctx();
    let eye_paths_per_pass = scene.camera.width as u64
        * scene.camera.height as u64
        * (settings.slots(scene) + settings.emission_samples) as u64;
    let mut r = Renderer::new(&ctx, scene, settings).unwrap();
    let mut last = None;
    for _ in 0..passes {
        last = Some(r.pass().unwrap());
    }
    // A path caught by total internal reflection in a glass sphere may reach a depth backstop or use up
    // its thread's BVH budget (rounding can leave a ray that entered at grazing incidence just past the
    // critical angle inside, and a sphere keeps that angle): counted, and rare. Measured: 3e-5 of all
    // photon and eye paths in cornell-spheres, 7e-5 with its glass sphere in 20480 facets.
    let s = last.unwrap();
    let paths = s.emitted_total + eye_paths_per_pass * passes as u64;
    println!(
        "paths cut: {} photon, {} eye, of {paths}",
        s.photon_paths_cut, s.eye_paths_cut
    );
    assert!(
        (s.photon_paths_cut + s.eye_paths_cut) * 5_000 <= paths,
        "{} photon and {} eye paths cut",
        s.photon_paths_cut,
        s.eye_paths_cut
    );
    let image = r.image().unwrap();
    assert_eq!(image.count_non_finite(), 0);
    drop(r);
    assert_clean(&ctx);
    image
}

fn sppm(photons: u32) -> Settings {
    Settings {
        mode: Mode::Sppm,
        photons_per_pass: photons,
        ..Settings::default()
    }
}

/// The furnace on a tessellated sphere (1280 triangles facing in, albedo 0.5, Le 1): L = 2 everywhere,
/// within 1%, and so with albedo 0.95 (L = 20 Le): the triangles' light sampling (uniform on each,
/// chosen by power), their front sides and the BVH's watertightness all enter.
#[test]
fn mesh_furnace_converges_to_le_over_one_minus_rho() {
    let mut s = scene("furnace-mesh.toml").with_resolution(24, 24);
    for (rho, le) in [(0.5f32, 1.0f32), (0.95, 0.05)] {
        for m in &mut s.materials {
            m.surface = Surface::Diffuse {
                albedo: Vec3::splat(rho),
            };
            m.emission = Vec3::splat(le);
        }
        let want = le as f64 / (1.0 - rho as f64);
        let image = render(&s, sppm(50_000), 8);
        let m = image.mean();
        println!("mesh furnace rho {rho}: mean {m:?}, want {want}");
        for c in 0..3 {
            assert!((m[c] / want - 1.0).abs() < 0.01, "rho {rho}: mean {m:?} vs {want}");
        }
    }
}

/// cornell-spheres with its walls and light as triangles renders the analytic scene's image: the same
/// mean and, against the Mitsuba reference, the same error in every region (within the noise: the two
/// trace different photons, the light being sampled per triangle).
#[test]
fn cornell_in_triangles_renders_the_analytic_image() {
    let reference = Reference::load(Path::new(CORNELL_REFERENCE)).unwrap();
    let analytic = render(&cornell(64, 64), sppm(100_000), 20);
    let mesh = render(&scene("cornell-mesh.toml").with_resolution(64, 64), sppm(100_000), 20);
    let (ma, mm) = (analytic.mean(), mesh.mean());
    println!("mean: analytic {ma:?}, mesh {mm:?}");
    for c in 0..3 {
        assert!((mm[c] / ma[c] - 1.0).abs() < 0.01, "means differ: {mm:?} vs {ma:?}");
    }
    for region in cornell_regions() {
        let ea = compare(&analytic, &reference, Some(&region), true).unwrap();
        let em = compare(&mesh, &reference, Some(&region), true).unwrap();
        println!(
            "{}: relMSE analytic {:.5}, mesh {:.5}; bias {:+.4} / {:+.4}",
            region.name, ea.rel_mse, em.rel_mse, ea.mean_bias, em.mean_bias
        );
        // Independent noise of equal variance: the ratio of two such errors stays within 1.5x at these
        // pixel counts (measured 0.8-1.2); a missing wall, a flipped light or leaking edges is far more.
        assert!(
            em.rel_mse < 1.5 * ea.rel_mse + 1e-4,
            "{}: mesh relMSE {} vs analytic {}",
            region.name,
            em.rel_mse,
            ea.rel_mse
        );
    }
}

/// The glass sphere as 20480 triangles casts the analytic sphere's caustic: the caustic region's error
/// against the reference is the analytic render's, within the noise. (Flat facets bend light a little
/// differently from the sphere; at 20k facets that is below the noise of this render.)
#[test]
fn a_tessellated_glass_sphere_casts_the_analytic_caustic() {
    let reference = Reference::load(Path::new(CORNELL_REFERENCE)).unwrap();
    let settings = Settings {
        mode: Mode::Ppm,
        ..sppm(200_000)
    };
    let analytic = render(&cornell(128, 128), settings.clone(), 12);
    let mesh = render(
        &scene("cornell-glass-mesh.toml").with_resolution(128, 128),
        settings,
        12,
    );
    let caustic = cornell_regions().into_iter().find(|r| r.name == "caustic").unwrap();
    let ea = compare(&analytic, &reference, Some(&caustic), true).unwrap();
    let em = compare(&mesh, &reference, Some(&caustic), true).unwrap();
    println!(
        "caustic relMSE: analytic {:.5}, mesh {:.5}; mean bias {:+.4} / {:+.4}",
        ea.rel_mse, em.rel_mse, ea.mean_bias, em.mean_bias
    );
    assert!(
        em.rel_mse < 1.5 * ea.rel_mse + 1e-4,
        "mesh caustic relMSE {} vs analytic {}",
        em.rel_mse,
        ea.rel_mse
    );
}

/// A square light tiled into 100k emitting triangles lights the scene as the one quad it replaces:
/// lights are chosen by power from an f32 table with 100k entries and sampled uniformly on each triangle.
#[test]
fn a_hundred_thousand_emitting_triangles_light_like_their_quad() {
    let quad_lit = cornell(32, 32);
    let mut tri_lit = quad_lit.clone();
    let li = tri_lit.lights()[0] as usize;
    let light = tri_lit.quads.remove(li);
    let n = 224u32; // 224 x 224 cells, two triangles each: 100352 triangles
    let mut mesh = Mesh {
        name: "tiled light".into(),
        positions: Vec::new(),
        normals: None,
        uvs: None,
        indices: Vec::new(),
        materials: Vec::new(),
    };
    for j in 0..=n {
        for i in 0..=n {
            mesh.positions
                .push(light.origin + light.edge_u * (i as f32 / n as f32) + light.edge_v * (j as f32 / n as f32));
        }
    }
    let at = |i: u32, j: u32| j * (n + 1) + i;
    for j in 0..n {
        for i in 0..n {
            // Counter-clockwise in (edge_u, edge_v): the quad's front side.
            mesh.indices.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            mesh.indices.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            mesh.materials.extend([light.material, light.material]);
        }
    }
    tri_lit.meshes.push(mesh);
    tri_lit.validate().unwrap();
    assert!(tri_lit.emitting_triangles().len() >= 100_000);
    // 20k photons a pass: at 32 x 32 eq. 8's radius is 17 cm, and more photons crowd a lookup past
    // lavapipe's loop budget (the gather says so).
    let settings = Settings {
        seed: 3,
        ..sppm(20_000)
    };
    let (a, b) = (render(&quad_lit, settings.clone(), 30), render(&tri_lit, settings, 30));
    let (ma, mb) = (a.mean(), b.mean());
    println!("mean: quad light {ma:?}, 100k triangles {mb:?}");
    for c in 0..3 {
        assert!((mb[c] / ma[c] - 1.0).abs() < 0.02, "{mb:?} vs {ma:?}");
    }
}

/// Thousands of triangles stacked on one another make a BVH whose traversal visits them all: more steps
/// than lavapipe's loop budget leaves. The render must stop with an error naming the cause, never draw
/// an image with rays that silently missed.
#[test]
fn a_degenerate_bvh_stops_the_render_instead_of_losing_hits() {
    let mut s = cornell(16, 16);
    let floor = s.quads.iter().position(|q| q.normal().y > 0.9).unwrap();
    let q = s.quads[floor];
    let mut mesh = Mesh {
        name: "stack".into(),
        positions: Vec::new(),
        normals: None,
        uvs: None,
        indices: Vec::new(),
        materials: Vec::new(),
    };
    let lift = Vec3::Y * 1e-3;
    for _ in 0..70_000u32 {
        let base = mesh.positions.len() as u32;
        mesh.positions
            .extend([q.origin + lift, q.origin + q.edge_u + lift, q.origin + q.edge_v + lift]);
        mesh.indices.push([base, base + 1, base + 2]);
        mesh.materials.push(q.material);
    }
    s.meshes.push(mesh);
    let ctx = ctx();
    let result = Renderer::new(&ctx, &s, sppm(20_000)).and_then(|mut r| r.pass().map(|_| ()));
    match (ctx.info().loop_budget, result) {
        (Some(_), Err(e)) => {
            let msg = format!("{e:#}");
            println!("{msg}");
            assert!(
                msg.contains("BVH") && msg.contains("loop iterations"),
                "unexpected error: {msg}"
            );
        }
        (Some(_), Ok(())) => {
            panic!("70000 stacked triangles traced within the loop budget: the test needs a harder case")
        }
        (None, r) => r.unwrap(), // no loop budget: the traversal simply finishes
    }
    assert_clean(&ctx);
}

/// A small mesh is written into the tracing kernels and tested by the triangles' planes, two at a time
/// where they make a parallelogram (geometry.glsl's inline_pair_test and inline_triangle_test), not by the
/// BVH's watertight test: it must trace what the BVH traces, to rounding. cornell-mesh (14 triangles,
/// three spheres) both ways: the eye pass's hit points in the same places and the photon records matched
/// one to one, and both paths' records matched by the CPU reference's.
#[test]
fn a_small_mesh_written_into_the_kernels_traces_what_the_bvh_traces() {
    let ctx = ctx();
    let s = scene("cornell-mesh.toml").with_resolution(32, 32);
    let photons = 20_000;
    let tol = 1e-4 * (s.bounds().1 - s.bounds().0).max_element();
    let run = |max_inline_triangles: u32| {
        let settings = Settings {
            max_inline_triangles,
            ..sppm(photons)
        };
        let mut r = Renderer::new(&ctx, &s, settings).unwrap();
        let inline = r.gpu_scene().triangles_inline;
        let paired = (r.gpu_scene().inline_pairs.len(), r.gpu_scene().inline_singles.len());
        assert_eq!(
            paired,
            if inline { (7, 0) } else { (0, 0) },
            "the box's 7 quads are 14 triangles"
        );
        let hits = r.read_hit_points().unwrap();
        let records = r.trace_and_gather(0, photons).unwrap();
        let cpu = ppm_vk_reference::photon_pass(r.gpu_scene(), 0, photons, ppm_vk_kernels::photon::SALT_PHOTON);
        let matched = match_records(&records, &cpu, tol);
        (inline, hits, records, (cpu.len(), matched))
    };
    let (inline, hits_inline, records_inline, (cpu_inline, matched_inline)) = run(64);
    let (bvh, hits_bvh, records_bvh, (cpu_bvh, matched_bvh)) = run(0);
    assert!(
        inline && !bvh,
        "cornell-mesh should be written out with the default, traversed with 0"
    );
    // The same slots filled, at the same places: an eye path that a last bit sends the other way at glass
    // would differ, and none does at this size.
    assert_eq!(hits_inline.len(), hits_bvh.len());
    let far = hits_inline
        .iter()
        .zip(&hits_bvh)
        .filter(|(a, b)| {
            a.pixel != b.pixel
                || a.brdf != b.brdf
                || (glam::Vec3::from_array(a.pos) - glam::Vec3::from_array(b.pos))
                    .abs()
                    .max_element()
                    > tol
                || (0..3).any(|c| !close(a.weight[c] as f64, b.weight[c] as f64, 1e-4, 1e-9))
        })
        .count();
    let filled = hits_bvh.iter().filter(|h| h.pixel != u32::MAX).count();
    assert!(filled > 900, "only {filled} hit points");
    assert_eq!(
        far,
        0,
        "{far} of {} hit points differ beyond rounding",
        hits_inline.len()
    );
    // The photons: one to one within rounding, but for paths a last bit sends the other way (a threshold
    // met exactly, as tests/kernels.rs allows between the GPU and its twin).
    let between = match_records(&records_inline, &records_bvh, tol);
    println!(
        "records: {} written out, {} through the BVH, {between} matched; CPU {matched_inline} of \
         {cpu_inline} and {matched_bvh} of {cpu_bvh} matched",
        records_inline.len(),
        records_bvh.len(),
    );
    let (n_in, n_bvh) = (records_inline.len(), records_bvh.len());
    assert!(n_in.abs_diff(n_bvh) * 200 <= n_bvh, "{n_in} records against {n_bvh}");
    assert!(
        between * 1000 >= n_bvh * 995,
        "only {between} of {n_bvh} records of the BVH's have a twin from the written-out triangles"
    );
    // Each path's CPU twin (reference::trace tests the written-out triangles by their planes too).
    for (what, matched, cpu) in [
        ("written out", matched_inline, cpu_inline),
        ("BVH", matched_bvh, cpu_bvh),
    ] {
        assert!(
            matched * 1000 >= cpu * 995,
            "{what}: only {matched} of {cpu} CPU records have a GPU twin"
        );
    }
    assert_clean(&ctx);
}

/// In a BVH scene a photon thread takes photons while its loop budget lasts; a photon whose traversal
/// runs out is suspended, and it and the photons no thread took are traced in the resume round. With a
/// first-round budget so small that most photons go that way, the batch's records are exactly those of
/// the ordinary run: nothing lost, nothing traced twice.
#[test]
fn photons_suspended_or_left_over_finish_in_the_resume_round() {
    let ctx = ctx();
    let s = scene("cornell-glass-mesh.toml").with_resolution(32, 32);
    let photons = 20_000;
    let mut r = Renderer::new(&ctx, &s, sppm(photons)).unwrap();
    assert!(r.gpu_scene().traverses_bvh());
    let ordinary = sorted_records(r.trace_and_gather(0, photons).unwrap());
    let work = r.read_photon_work().unwrap();
    println!("ordinary: {} records, {work:?}", ordinary.len());
    // 200 loop iterations in the first round and none started below 100: a thread gets through a photon
    // or two, and many traversals (the glass sphere's 20480 facets) run out.
    r.set_photon_round(200, 100);
    let forced = sorted_records(r.trace_and_gather(0, photons).unwrap());
    let work = r.read_photon_work().unwrap();
    println!("forced: {} records, {work:?}", forced.len());
    assert!(
        work.suspended > 100,
        "too few photons suspended to test the resume round: {work:?}"
    );
    assert!(
        work.started < photons,
        "every photon started in the first round: {work:?}"
    );
    assert_eq!(forced.len(), ordinary.len());
    assert!(forced == ordinary, "the resume round traced other records");
    let counters = r.path_counters().unwrap();
    assert_eq!(counters.traversal_cut, 0, "{counters:?}");
    assert_clean(&ctx);
}
