//! Every kind of light against closed forms, by shadow rays (`--direct sample`) and by photons alone
//! (`--direct photons`): a point light over a plane (I cos / d^2), a spot's falloff across its cone, the sun
//! on a plane (E cos), a plane and a white sphere under a constant sky (rho L, and L: the furnace), an
//! environment map with one bright pixel against the directional light it amounts to, and a glowing
//! analytic sphere against a tessellated one. The GPU kernels against the CPU twin are in
//! tests/kernels.rs; the Mitsuba references in tests/reference_render.rs.

mod common;

use common::*;
use glam::{Mat3, Vec3};
use ppm_vk_engine::scene::{Emitter, EnvMap, Environment, Mesh, Scene};
use ppm_vk_engine::{DirectLight, Mode, RgbImage, Settings};

const RHO: f32 = 0.5;

/// A 4 x 4 m floor at y = 0 (albedo RHO) seen straight from above, `w` pixels square, with the lights
/// given; the floor fills the image. `extra`: TOML appended (more materials and shapes).
fn floor_scene(w: u32, emitters: Vec<Emitter>, extra: &str) -> Scene {
    let text = format!(
        r#"name = "lights-test"
[camera]
eye = [0.0, 4.0, 0.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
vfov = 40.0
resolution = [{w}, {w}]
[materials.floor]
diffuse = [{RHO}, {RHO}, {RHO}]
[materials.placeholder]
emission = [1.0, 1.0, 1.0]
[[quad]]
origin = [-2.0, 0.0, -2.0]
edge_u = [0.0, 0.0, 4.0]
edge_v = [4.0, 0.0, 0.0]
material = "floor"
{extra}
# A light for the parser (every scene needs one), removed below: the emitters replace it.
[[quad]]
origin = [100.0, 100.0, 100.0]
edge_u = [0.1, 0.0, 0.0]
edge_v = [0.0, 0.0, 0.1]
material = "placeholder"
"#
    );
    let mut scene = Scene::parse(&text, "lights-test.toml").unwrap_or_else(|e| panic!("{e:#}"));
    scene.quads.pop();
    let check = !emitters.is_empty(); // else the caller adds its light and checks
    scene.emitters = emitters;
    if check {
        scene.validate().unwrap_or_else(|e| panic!("{e:#}"));
    }
    scene
}

/// Where the point (px + jx, py + jy) of the image of `scene`'s camera meets the plane y = 0 (ray.comp's
/// camera_ray).
fn floor_point(scene: &Scene, px: f32, py: f32) -> Vec3 {
    let c = &scene.camera;
    let forward = (c.look_at - c.eye).normalize();
    let right = forward.cross(c.up).normalize();
    let up = right.cross(forward);
    let t = (c.vfov_deg.to_radians() * 0.5).tan();
    let aspect = c.width as f32 / c.height as f32;
    let sx = (2.0 * px / c.width as f32 - 1.0) * aspect * t;
    let sy = (1.0 - 2.0 * py / c.height as f32) * t;
    let d = (forward + sx * right + sy * up).normalize();
    c.eye + d * (-c.eye.y / d.y)
}

fn settings(direct: DirectLight, photons: u32) -> Settings {
    Settings {
        mode: Mode::Sppm,
        photons_per_pass: photons,
        direct,
        ..Settings::default()
    }
}

/// The image's value (channel 0) averaged over the b x b block of pixels at block (bx, by).
fn block(image: &RgbImage, b: u32, bx: u32, by: u32) -> f64 {
    let mut sum = 0f64;
    for y in by * b..(by + 1) * b {
        for x in bx * b..(bx + 1) * b {
            sum += image.get(x, y)[0] as f64;
        }
    }
    sum / (b * b) as f64
}

/// The closed form averaged over the same block, as the pixels' box filter averages it (8 x 8 points a
/// pixel).
fn block_expected(scene: &Scene, b: u32, bx: u32, by: u32, f: &dyn Fn(Vec3) -> f64) -> f64 {
    const K: u32 = 8;
    let mut sum = 0f64;
    for y in by * b * K..(by + 1) * b * K {
        for x in bx * b * K..(bx + 1) * b * K {
            let (px, py) = ((x as f32 + 0.5) / K as f32, (y as f32 + 0.5) / K as f32);
            sum += f(floor_point(scene, px, py));
        }
    }
    sum / (b * b * K * K) as f64
}

/// Compares every b x b block of the image with the closed form: relative error within `rel` where the
/// expected value is at least a tenth of the largest, absolute within rel * largest elsewhere (and
/// everywhere with `of_peak`: the photons' kernel blurs an edge by its radius). A block where `f` is NaN
/// anywhere is not checked.
fn check_blocks(name: &str, image: &RgbImage, scene: &Scene, b: u32, rel: f64, of_peak: bool, f: &dyn Fn(Vec3) -> f64) {
    let n = scene.camera.width / b;
    let mut worst = 0f64;
    let mut most = 0f64;
    for by in 0..n {
        for bx in 0..n {
            most = most.max(block_expected(scene, b, bx, by, f));
        }
    }
    for by in 0..n {
        for bx in 0..n {
            let (got, want) = (block(image, b, bx, by), block_expected(scene, b, bx, by, f));
            if want.is_nan() {
                continue;
            }
            let err = if want > 0.1 * most && !of_peak {
                (got / want - 1.0).abs()
            } else {
                (got - want).abs() / most
            };
            worst = worst.max(err);
            assert!(
                err <= rel,
                "{name}: block ({bx}, {by}) is {got:.5}, the closed form {want:.5} ({:.2}% off)",
                100.0 * err
            );
        }
    }
    println!("{name}: worst block {:.2}% off", 100.0 * worst);
}

/// A point light 1 m over the floor: L = (rho / pi) I cos / d^2 at every point, by shadow rays to within
/// the noise of the pixels' box filter and by photons alone to within their kernel's blur over 4 x 4 blocks
/// (5%).
#[test]
fn a_point_light_over_a_plane_gives_i_cos_over_d_squared() {
    let ctx = ctx();
    let (pos, i) = (Vec3::new(0.3, 1.0, -0.2), 2.0f32);
    let scene = floor_scene(
        32,
        vec![Emitter::Point {
            position: pos,
            intensity: Vec3::splat(i),
        }],
        "",
    );
    let f = |x: Vec3| {
        let d = pos - x;
        let d2 = d.length_squared() as f64;
        RHO as f64 / std::f64::consts::PI * i as f64 * (d.y as f64 / d2.sqrt()) / d2
    };
    // Each pixel's value is a mean over random points of it (the box filter), noisy by the closed form's
    // change across a pixel: 2 x 2 blocks after 16 passes are within 1.5% (measured: 0.9% at most).
    let sampled = render(&ctx, &scene, settings(DirectLight::Sample, 20_000), 16);
    check_blocks("point, shadow rays", &sampled, &scene, 2, 0.015, false, &f);
    let photons = render(&ctx, &scene, settings(DirectLight::Photons, 200_000), 16);
    check_blocks("point, photons", &photons, &scene, 4, 0.05, false, &f);
    assert_clean(&ctx);
}

/// A spot 1 m over the floor pointing straight down, cutoff 30 degrees and beam 20: its profile across the
/// cone (full in the beam, the linear ramp in angle, nothing outside) times cos / d^2.
#[test]
fn a_spot_falls_off_across_its_cone_as_mitsubas() {
    let ctx = ctx();
    let (pos, i) = (Vec3::new(0.0, 1.0, 0.0), 3.0f32);
    let (cutoff, beam) = (30f32.to_radians(), 20f32.to_radians());
    let scene = floor_scene(
        32,
        vec![Emitter::Spot {
            position: pos,
            direction: -Vec3::Y,
            intensity: Vec3::splat(i),
            cutoff,
            beam,
        }],
        "",
    );
    let f = |x: Vec3| {
        let d = pos - x;
        let d2 = d.length_squared() as f64;
        let cos = d.y as f64 / d2.sqrt();
        let angle = cos.acos();
        let falloff = if angle >= cutoff as f64 {
            0.0
        } else if angle <= beam as f64 {
            1.0
        } else {
            (cutoff as f64 - angle) / (cutoff - beam) as f64
        };
        RHO as f64 / std::f64::consts::PI * i as f64 * falloff * cos / d2
    };
    // The falloff's ramp and the cone's edge cross pixels, whose box filter draws random points of them:
    // 4 x 4 blocks after 16 passes.
    let sampled = render(&ctx, &scene, settings(DirectLight::Sample, 20_000), 16);
    check_blocks("spot, shadow rays", &sampled, &scene, 4, 0.03, false, &f);
    // All photons land in the cone: 50k a pass keeps the lookups inside lavapipe's loop budget (issue 39).
    let photons = render(&ctx, &scene, settings(DirectLight::Photons, 50_000), 48);
    check_blocks("spot, photons", &photons, &scene, 4, 0.04, true, &f);
    assert_clean(&ctx);
}

/// The sun 35 degrees from the zenith: L = (rho / pi) E cos 35 everywhere on the floor.
#[test]
fn the_sun_on_a_plane_gives_e_cos() {
    let ctx = ctx();
    let e = 4.0f32;
    let theta = 35f32.to_radians();
    let direction = Vec3::new(theta.sin(), -theta.cos(), 0.0);
    let scene = floor_scene(
        16,
        vec![Emitter::Directional {
            direction,
            irradiance: Vec3::splat(e),
        }],
        "",
    );
    let want = RHO as f64 / std::f64::consts::PI * e as f64 * (theta.cos() as f64);
    for (direct, photons, passes, tol) in [
        (DirectLight::Sample, 10_000, 2, 1e-4),
        (DirectLight::Photons, 200_000, 16, 0.02),
    ] {
        let image = render(&ctx, &scene, settings(direct, photons), passes);
        let mean = image.mean()[0];
        println!("sun, {direct:?}: mean {mean:.5}, closed form {want:.5}");
        assert!((mean / want - 1.0).abs() < tol, "{direct:?}: {mean} against {want}");
    }
    assert_clean(&ctx);
}

/// A constant sky of radiance L: the floor (which sees the whole upper hemisphere and nothing else)
/// reflects rho L; and the furnace, a white sphere (albedo 1) alone in the sky, reflects exactly L and
/// vanishes against it (every pixel L).
#[test]
fn a_constant_sky_lights_a_plane_by_rho_l_and_a_white_sphere_vanishes() {
    let ctx = ctx();
    let l = 1.5f32;
    let sky = || {
        vec![Emitter::Environment(Environment {
            scale: Vec3::splat(l),
            map: None,
            to_world: Mat3::IDENTITY,
        })]
    };
    let scene = floor_scene(16, sky(), "");
    let want = (RHO * l) as f64;
    for (direct, photons, passes, tol) in [
        (DirectLight::Sample, 10_000, 8, 0.01),
        (DirectLight::Photons, 200_000, 16, 0.03),
    ] {
        let image = render(&ctx, &scene, settings(direct, photons), passes);
        let mean = image.mean()[0];
        println!("sky over a plane, {direct:?}: mean {mean:.5}, closed form {want:.5}");
        assert!((mean / want - 1.0).abs() < tol, "{direct:?}: {mean} against {want}");
    }
    // The furnace: the floor replaced by a white sphere in the middle of the view, sky all around.
    let mut furnace = floor_scene(
        16,
        sky(),
        "[materials.white]\ndiffuse = [1.0, 1.0, 1.0]\n[[sphere]]\ncenter = [0.0, 1.0, 0.0]\nradius = 0.8\nmaterial = \"white\"\n",
    );
    furnace.quads.remove(0);
    for (direct, photons, passes, tol) in [
        (DirectLight::Sample, 10_000, 8, 0.01),
        (DirectLight::Photons, 200_000, 16, 0.03),
    ] {
        let image = render(&ctx, &furnace, settings(direct, photons), passes);
        let mean = image.mean()[0];
        println!("white furnace, {direct:?}: mean {mean:.5}, sky {l}");
        assert!((mean / l as f64 - 1.0).abs() < tol, "{direct:?}: {mean} against {l}");
    }
    assert_clean(&ctx);
}

/// An environment map black but for one bright pixel is, to the floor, the directional light from that
/// pixel's direction with the irradiance the pixel's bilinear patch gives (its integral over the sphere:
/// L du dv 2 pi^2 sin theta over one pixel's spacing, the hat's area), times the cosine.
#[test]
fn an_environment_map_with_one_bright_pixel_is_a_sun() {
    let ctx = ctx();
    let (w, h) = (64u32, 33u32);
    let (row, col) = (8u32, 40u32); // theta = pi * 8 / 32 = 45 degrees
    let radiance = 500.0f32;
    let mut pixels = vec![Vec3::ZERO; (w * h) as usize];
    pixels[(row * w + col) as usize] = Vec3::splat(radiance);
    let map = EnvMap {
        name: "one-pixel".into(),
        width: w,
        height: h,
        pixels,
    };
    let scene = floor_scene(
        16,
        vec![Emitter::Environment(Environment {
            scale: Vec3::ONE,
            map: Some(map),
            to_world: Mat3::IDENTITY,
        })],
        "",
    );
    let (u, v) = ((col as f32 + 0.5) / w as f32, row as f32 / (h - 1) as f32);
    let towards = ppm_vk_engine::scene::emitter::envmap_direction(u, v);
    let theta = std::f64::consts::PI * v as f64;
    // The hat's integral over the sphere: L (1 / w) (1 / (h - 1)) 2 pi^2 sin theta (sin theta varies by
    // 1e-3 over the hat at 45 degrees).
    let e = radiance as f64 * 2.0 * std::f64::consts::PI.powi(2) * theta.sin() / (w as f64 * (h - 1) as f64);
    let want = RHO as f64 / std::f64::consts::PI * e * towards.y as f64;
    let sun = floor_scene(
        16,
        vec![Emitter::Directional {
            direction: -towards,
            irradiance: Vec3::splat(e as f32),
        }],
        "",
    );
    for (direct, photons, passes, tol) in [
        (DirectLight::Sample, 10_000, 8, 0.02),
        (DirectLight::Photons, 200_000, 16, 0.03),
    ] {
        let image = render(&ctx, &scene, settings(direct, photons), passes);
        let sun_image = render(&ctx, &sun, settings(direct, photons), passes);
        let (mean, sun_mean) = (image.mean()[0], sun_image.mean()[0]);
        println!("one-pixel map, {direct:?}: mean {mean:.5}, its sun {sun_mean:.5}, closed form {want:.5}");
        assert!((mean / want - 1.0).abs() < tol, "{direct:?}: {mean} against {want}");
        assert!(
            (sun_mean / want - 1.0).abs() < tol,
            "{direct:?}: the sun {sun_mean} against {want}"
        );
    }
    assert_clean(&ctx);
}

/// A UV sphere of `n` x 2n quads (two triangles each) about `centre`, vertices on the sphere of radius r.
fn uv_sphere(centre: Vec3, r: f32, n: u32, material: u32) -> Mesh {
    let mut positions = Vec::new();
    for i in 0..=n {
        let theta = std::f32::consts::PI * i as f32 / n as f32;
        for j in 0..2 * n {
            let phi = std::f32::consts::PI * j as f32 / n as f32;
            positions.push(centre + r * Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin()));
        }
    }
    let at = |i: u32, j: u32| i * 2 * n + j % (2 * n);
    let mut indices = Vec::new();
    for i in 0..n {
        for j in 0..2 * n {
            // Wound so that the front (the winding's normal) faces out.
            let (a, b, c, d) = (at(i, j), at(i, j + 1), at(i + 1, j), at(i + 1, j + 1));
            if i > 0 {
                indices.push([a, b, c]);
            }
            if i + 1 < n {
                indices.push([b, d, c]);
            }
        }
    }
    let count = indices.len();
    Mesh {
        name: "uv-sphere".into(),
        positions,
        normals: None,
        uvs: None,
        indices,
        materials: vec![material; count],
    }
}

/// A glowing analytic sphere (sampled by the solid angle of its cap) and a tessellated one of the same
/// radiance (sampled by area) light the floor alike: the mesh's area is short of the sphere's by its
/// tessellation (0.4% at 48 x 96), which the comparison allows.
#[test]
fn a_glowing_sphere_matches_a_tessellated_one() {
    let ctx = ctx();
    let extra = "[materials.glow]\nemission = [6.0, 6.0, 6.0]\n";
    let (centre, r) = (Vec3::new(0.2, 0.8, 0.1), 0.3);
    let mut analytic = floor_scene(16, vec![], extra);
    let glow = analytic.materials.iter().position(|m| m.name == "glow").unwrap() as u32;
    analytic.spheres.push(ppm_vk_engine::scene::Sphere {
        center: centre,
        radius: r,
        material: glow,
    });
    analytic.validate().unwrap();
    let mut mesh = floor_scene(16, vec![], extra);
    let m = uv_sphere(centre, r, 48, glow);
    let area: f32 = m
        .indices
        .iter()
        .map(|t| {
            let p = t.map(|i| m.positions[i as usize]);
            0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length()
        })
        .sum();
    let deficit = 1.0 - area / (4.0 * std::f32::consts::PI * r * r);
    mesh.meshes.push(m);
    mesh.validate().unwrap();
    for (direct, photons, passes, tol) in [
        (DirectLight::Sample, 10_000, 16, 0.01),
        (DirectLight::Photons, 200_000, 16, 0.02),
    ] {
        let a = render(&ctx, &analytic, settings(direct, photons), passes);
        let b = render(&ctx, &mesh, settings(direct, photons), passes);
        // The floor only: the spheres themselves (radiance 6) are in view, their silhouettes differ.
        let floor = |i: &RgbImage| {
            let lit: Vec<f64> = (0..i.pixels.len())
                .filter(|&k| a.pixels[k][0] < 3.0 && b.pixels[k][0] < 3.0)
                .map(|k| i.pixels[k][0] as f64)
                .collect();
            lit.iter().sum::<f64>() / lit.len() as f64
        };
        let (ma, mb) = (floor(&a), floor(&b));
        println!(
            "glowing sphere, {direct:?}: analytic {ma:.5}, mesh {mb:.5}, mesh area short by {:.2}%",
            100.0 * deficit
        );
        assert!(
            (mb / ma - 1.0).abs() < tol + deficit as f64,
            "{direct:?}: analytic {ma} against the mesh's {mb}"
        );
    }
    assert_clean(&ctx);
}

/// A disk light (an emitting quad with `disk`: the ellipse inscribed in it, Mitsuba's `disk`), sampled
/// as one light uniformly in its area: a horizontal disk of radius R at height h lights the floor by the
/// closed form of a parallel disk's form factor, L = rho Le F with
/// F = 1/2 [1 - (a^2 + h^2 - R^2) / sqrt((a^2 + h^2 + R^2)^2 - 4 R^2 a^2)] at distance a from its axis;
/// a tilted ellipse (unequal edges) by quadrature over its area. Both by shadow rays and by photons alone.
#[test]
fn a_disk_light_gives_its_form_factor_and_an_ellipse_its_quadrature() {
    let ctx = ctx();
    let le = 4.0f64;
    let (c, r, h) = (Vec3::new(0.2, 0.0, -0.1), 0.3f32, 0.8f32);
    let quad = |origin: Vec3, u: Vec3, v: Vec3| {
        format!(
            "[materials.glow]\nemission = [{le}, {le}, {le}]\n[[quad]]\norigin = {:?}\nedge_u = {:?}\n\
             edge_v = {:?}\nmaterial = \"glow\"\ndisk = true\n",
            origin.to_array(),
            u.to_array(),
            v.to_array()
        )
    };
    // Facing down: x cross z = -y.
    let circle = floor_scene(
        32,
        vec![],
        &quad(
            c + Vec3::new(-r, h, -r),
            Vec3::new(2.0 * r, 0.0, 0.0),
            Vec3::new(0.0, 0.0, 2.0 * r),
        ),
    );
    circle.validate().unwrap();
    assert!(circle.quads[1].disk);
    let form_factor = |x: Vec3| {
        let a2 = ((x.x - c.x).powi(2) + (x.z - c.z).powi(2)) as f64;
        let (h2, r2) = ((h * h) as f64, (r * r) as f64);
        0.5 * (1.0 - (a2 + h2 - r2) / ((a2 + h2 + r2).powi(2) - 4.0 * r2 * a2).sqrt())
    };
    let f = |x: Vec3| RHO as f64 * le * form_factor(x);
    // A tilted ellipse (semi-axes 0.4 and 0.14, its normal 20 degrees from straight down, its plane's
    // horizon off the image, where the photons' blur of the kink would bias them), lighting the
    // floor by the integral of Le cos_x cos_y / (pi d^2) over its area: 48 x 96 polar midpoints.
    let (o, u, v) = (
        Vec3::new(-0.6, 1.0, 0.3),
        Vec3::new(0.8, 0.0, 0.0),
        Vec3::new(0.0, 0.1, 0.27),
    );
    let ellipse = floor_scene(32, vec![], &quad(o, u, v));
    ellipse.validate().unwrap();
    let n = u.cross(v).normalize();
    assert!(n.y < 0.0, "facing down");
    let quadrature = |x: Vec3| {
        let (nr, nphi) = (48, 96);
        let area = f64::from(u.cross(v).length()) * std::f64::consts::FRAC_PI_4;
        let mut sum = 0f64;
        for i in 0..nr {
            let rr = ((i as f32 + 0.5) / nr as f32).sqrt() * 0.5;
            for j in 0..nphi {
                let phi = std::f32::consts::TAU * (j as f32 + 0.5) / nphi as f32;
                let y = o + (0.5 + rr * phi.cos()) * u + (0.5 + rr * phi.sin()) * v;
                let d = y - x;
                let d2 = d.length_squared();
                let (cos_x, cos_y) = (d.y / d2.sqrt(), -n.dot(d) / d2.sqrt());
                sum += f64::from(cos_x.max(0.0) * cos_y.max(0.0) / d2);
            }
        }
        RHO as f64 / std::f64::consts::PI * le * sum * area / (nr * nphi) as f64
    };
    // The camera above sees the disk's back where it hides the floor: NaN there, and check_blocks skips
    // the blocks it touches (their pixels' box filter mixes the back and the floor).
    let hidden = |x: Vec3, o: Vec3, u: Vec3, v: Vec3| {
        let eye = Vec3::new(0.0, 4.0, 0.0);
        let (d, n) = (x - eye, u.cross(v));
        let t = n.dot(o - eye) / n.dot(d);
        let rel = eye + t * d - o;
        let w = n / n.dot(n);
        let (a, b) = (w.dot(rel.cross(v)), w.dot(u.cross(rel)));
        (0.0..1.0).contains(&t) && (2.0 * a - 1.0).powi(2) + (2.0 * b - 1.0).powi(2) <= 1.0
    };
    let (co, cu, cv) = (
        c + Vec3::new(-r, h, -r),
        Vec3::new(2.0 * r, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 2.0 * r),
    );
    let seen_disk = |x: Vec3| if hidden(x, co, cu, cv) { f64::NAN } else { f(x) };
    let seen_ellipse = |x: Vec3| if hidden(x, o, u, v) { f64::NAN } else { quadrature(x) };
    for (name, scene, closed) in [
        ("disk", &circle, &seen_disk as &dyn Fn(Vec3) -> f64),
        ("ellipse", &ellipse, &seen_ellipse),
    ] {
        // A point on an area light per shadow ray is noisier than a point light's: 4 x 4 blocks after 32
        // passes (measured: 2 x 2 blocks after 16 passes spread by up to 6%, with no trend); the photons'
        // blur over 4 x 4 as the point light's.
        let sampled = render(&ctx, scene, settings(DirectLight::Sample, 20_000), 32);
        check_blocks(&format!("{name}, shadow rays"), &sampled, scene, 4, 0.03, false, closed);
        let photons = render(&ctx, scene, settings(DirectLight::Photons, 200_000), 16);
        check_blocks(&format!("{name}, photons"), &photons, scene, 4, 0.05, false, closed);
    }
    assert_clean(&ctx);
}

/// Scale invariance with every kind of light: the floor scene with a point, a spot, the sun and a sky,
/// scaled by 1e-3 and 1e3 (a point's and a spot's intensity by s^2, Scene::scaled), renders the same image
/// mean: nothing in the lights' sampling depends on the scene's units.
#[test]
fn every_light_is_scale_free() {
    let ctx = ctx();
    let scene = floor_scene(
        16,
        vec![
            Emitter::Point {
                position: Vec3::new(0.3, 1.0, -0.2),
                intensity: Vec3::splat(2.0),
            },
            Emitter::Spot {
                position: Vec3::new(-0.5, 1.5, 0.5),
                direction: Vec3::new(0.2, -1.0, 0.1).normalize(),
                intensity: Vec3::splat(5.0),
                cutoff: 0.6,
                beam: 0.4,
            },
            Emitter::Directional {
                direction: Vec3::new(0.3, -1.0, 0.2).normalize(),
                irradiance: Vec3::splat(1.0),
            },
            Emitter::Environment(Environment {
                scale: Vec3::splat(0.2),
                map: None,
                to_world: Mat3::IDENTITY,
            }),
        ],
        "[materials.white]\ndiffuse = [0.8, 0.8, 0.8]\n[materials.glow]\nemission = [3.0, 3.0, 3.0]\n\
         [[sphere]]\ncenter = [0.4, 0.3, 0.3]\nradius = 0.3\nmaterial = \"white\"\n\
         [[sphere]]\ncenter = [-0.6, 0.8, -0.4]\nradius = 0.1\nmaterial = \"glow\"\n",
    );
    let mean = |s: &Scene| render(&ctx, s, settings(DirectLight::Sample, 50_000), 8).mean()[0];
    let base = mean(&scene);
    for k in [1e-3f32, 1e3] {
        let m = mean(&scene.scaled(k));
        println!("scaled by {k}: mean {m:.5} against {base:.5}");
        assert!((m / base - 1.0).abs() < 0.01, "scaled by {k}: {m} against {base}");
    }
    assert_clean(&ctx);
}
