//! Where photons are aimed (photon.comp's `aimed_direction`, shaders/photon/targets.glsl): a bounding
//! sphere around the surfaces of each material that casts caustics, the surfaces a photon leaves by a
//! mirror, glass or a lobe the eye paths sample through (never a record there). A narrow caustic is the
//! light of the few photons that happen to leave the light towards such an object (2% of glass-on-table's
//! photons reach its torus); `Settings::caustic_photons` of every area light's photons are drawn inside the
//! cones these spheres subtend instead, each weighted by the density of the mixture (Jensen's projection
//! maps, as a continuous density: no direction is left out, so no light is).

use glam::Vec3;
use ppm_vk_kernels::layout::{
    Material, Quad, Sphere, Triangle, MAX_TARGETS, SURFACE_BLEND, SURFACE_CONDUCTOR, SURFACE_GLASS, SURFACE_MIRROR,
    SURFACE_ROUGH_CONDUCTOR, SURFACE_ROUGH_GLASS, SURFACE_THIN,
};

/// Whether material `i` is one a photon leaves without a record, by a mirror, glass or a lobe sampled
/// through (rough conductors below `glossy_alpha`, whose surfaces hold no hit points); a blend if either
/// of its components is.
fn casts(materials: &[Material], i: usize, glossy_alpha: f32, depth: u32) -> bool {
    let m = &materials[i];
    match m.surface {
        SURFACE_MIRROR | SURFACE_GLASS | SURFACE_CONDUCTOR | SURFACE_THIN | SURFACE_ROUGH_GLASS => true,
        SURFACE_ROUGH_CONDUCTOR => m.alpha_u < glossy_alpha,
        SURFACE_BLEND if depth < 8 => [m.lobe_a[0], m.lobe_a[1]]
            .iter()
            .any(|c| casts(materials, c.to_bits() as usize, glossy_alpha, depth + 1)),
        _ => false,
    }
}

/// The aim spheres, (centre, radius) each: one around the primitives of every material that casts, by its
/// bounding box; where more than [`MAX_TARGETS`] materials cast, one around them all. Empty where none does.
pub fn targets(
    materials: &[Material],
    spheres: &[Sphere],
    quads: &[Quad],
    triangles: &[Triangle],
    glossy_alpha: f32,
) -> Vec<[f32; 4]> {
    let mut boxes: Vec<Option<(Vec3, Vec3)>> = vec![None; materials.len()];
    let mut add = |material: u32, points: &[Vec3]| {
        let i = material as usize;
        if i >= materials.len() || !casts(materials, i, glossy_alpha, 0) {
            return;
        }
        for &p in points {
            let b = boxes[i].get_or_insert((p, p));
            *b = (b.0.min(p), b.1.max(p));
        }
    };
    for s in spheres {
        let (c, r) = (Vec3::from(s.center), Vec3::splat(s.radius));
        add(s.material, &[c - r, c + r]);
    }
    for q in quads {
        // A disk is the ellipse inscribed in its parallelogram: the corners bound it.
        let (o, u, v) = (Vec3::from(q.origin), Vec3::from(q.edge_u), Vec3::from(q.edge_v));
        add(q.material, &[o, o + u, o + v, o + u + v]);
    }
    for t in triangles {
        add(t.material, &[t.v0.into(), t.v1.into(), t.v2.into()]);
    }
    let boxes: Vec<(Vec3, Vec3)> = boxes.into_iter().flatten().collect();
    let sphere = |(lo, hi): (Vec3, Vec3)| {
        let c = 0.5 * (lo + hi);
        [c.x, c.y, c.z, 0.5 * (hi - lo).length()]
    };
    if boxes.len() > MAX_TARGETS {
        let all = boxes
            .iter()
            .copied()
            .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)))
            .expect("more than MAX_TARGETS boxes");
        return vec![sphere(all)];
    }
    boxes.into_iter().map(sphere).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn material(surface: u32) -> Material {
        Material {
            surface,
            ..Default::default()
        }
    }

    #[test]
    fn one_sphere_per_casting_material_and_none_for_diffuse() {
        let materials = [material(0), material(SURFACE_GLASS), material(SURFACE_MIRROR)];
        let sphere = |center: [f32; 3], radius: f32, material: u32| Sphere {
            center,
            radius,
            material,
            ..Default::default()
        };
        let spheres = [
            sphere([0.0; 3], 5.0, 0),
            sphere([1.0, 0.0, 0.0], 0.5, 1),
            sphere([-1.0, 0.0, 0.0], 0.25, 2),
        ];
        let t = targets(&materials, &spheres, &[], &[], f32::MAX);
        assert_eq!(t.len(), 2);
        // A sphere's box is a cube: the bounding sphere of the cube, sqrt(3) r.
        assert!((t[0][0] - 1.0).abs() < 1e-6 && (t[0][3] - 0.5 * 3f32.sqrt()).abs() < 1e-6);
        assert!((t[1][0] + 1.0).abs() < 1e-6 && (t[1][3] - 0.25 * 3f32.sqrt()).abs() < 1e-6);
        // Rough metal that holds hit points (alpha at least glossy_alpha) is not a target.
        let rough = [Material {
            alpha_u: 0.3,
            ..material(SURFACE_ROUGH_CONDUCTOR)
        }];
        let one = [sphere([0.0; 3], 1.0, 0)];
        assert!(targets(&rough, &one, &[], &[], 0.15).is_empty());
        assert_eq!(targets(&rough, &one, &[], &[], 0.5).len(), 1);
    }

    #[test]
    fn more_casting_materials_than_targets_share_one_sphere() {
        let materials: Vec<Material> = (0..=MAX_TARGETS).map(|_| material(SURFACE_GLASS)).collect();
        let spheres: Vec<Sphere> = (0..materials.len())
            .map(|i| Sphere {
                center: [i as f32, 0.0, 0.0],
                radius: 0.1,
                material: i as u32,
                ..Default::default()
            })
            .collect();
        let t = targets(&materials, &spheres, &[], &[], f32::MAX);
        assert_eq!(t.len(), 1);
        let n = MAX_TARGETS as f32;
        assert!((t[0][0] - 0.5 * n).abs() < 1e-5, "centre {:?}", t[0]);
        assert!(t[0][3] >= 0.5 * n + 0.1, "radius {}", t[0][3]);
    }
}
