//! Mitsuba's `blendbsdf` (src/bsdfs/blendbsdf.cpp): two nested bsdfs and a `weight` (a float or a texture,
//! default 0.5), f = (1 - w) f_0 + w f_1. Each component becomes a scene material of its own and the
//! blend a `Surface::Blend` of the two (bsdf.rs's `material`).

use std::rc::Rc;

use anyhow::Result;

use super::bsdf::{Blend, Bsdf, Perturbation};
use super::elem::Elem;
use super::properties::Props;
use super::Builder;
use crate::{Surface, MAX_BLEND_DEPTH};

impl Bsdf {
    /// The plain bsdfs it is made of: itself, or a blend's components' (in order).
    pub(super) fn leaves(&self) -> Vec<&Bsdf> {
        match &self.blend {
            Some(b) => [b.first.leaves(), b.second.leaves()].concat(),
            None => vec![self],
        }
    }

    /// How many blends deep it is (0: not a blend).
    pub(super) fn blend_depth(&self) -> u32 {
        self.blend
            .as_ref()
            .map_or(0, |b| 1 + b.first.blend_depth().max(b.second.blend_depth()))
    }

    /// Whether anything in it reads texture coordinates: a texture, a bump or normal map, a blend's weight,
    /// a mask's opacity.
    pub(super) fn textured(&self) -> bool {
        let mask = matches!(self.opacity, Some(super::bsdf::Opacity::Texture(_)));
        mask || match &self.blend {
            Some(b) => b.texture.is_some() || b.first.textured() || b.second.textured(),
            None => {
                self.texture.is_some() || self.normal_map.is_some() || self.specular.is_some() || self.alpha.is_some()
            }
        }
    }

    /// `self` with bump or normal map `p`: a blend's components each get it. A bump map around a blend
    /// is the blend of the components bumped alike, exactly: both read the same perturbed frame, and the
    /// shadowing term multiplies each. Fails where a component has a map of its own.
    pub(super) fn perturbed(self, p: &Perturbation) -> Option<Bsdf> {
        if self.normal_map.is_some() {
            return None;
        }
        let Some(b) = self.blend else {
            return Some(Bsdf {
                normal_map: Some(p.clone()),
                ..self
            });
        };
        let Blend {
            weight,
            texture,
            first,
            second,
        } = Rc::try_unwrap(b).unwrap_or_else(|b| Blend {
            weight: b.weight,
            texture: b.texture.clone(),
            first: b.first.clone(),
            second: b.second.clone(),
        });
        Some(Bsdf {
            blend: Some(Rc::new(Blend {
                weight,
                texture,
                first: first.perturbed(p)?,
                second: second.perturbed(p)?,
            })),
            ..self
        })
    }
}

impl Builder {
    /// Mitsuba's `blendbsdf`: two nested bsdfs (elements or `ref`s, in the order written) and `weight`.
    pub(super) fn blendbsdf(&mut self, e: &Elem, props: &Props, objects: &[&Elem]) -> Result<Bsdf> {
        let mut parts = Vec::new();
        for &o in objects {
            parts.push(match o.tag.as_str() {
                "bsdf" => (self.bsdf(o)?, o),
                "ref" => (self.bsdf_ref(o)?, o),
                _ => return Err(o.err(format!("not expected inside {}", e.what()))),
            });
        }
        // The traversal reads a mask from the material a ray meets, before the blend chooses: a mask
        // around a blend is read, one inside it is not.
        if let Some((_, o)) = parts.iter().find(|(b, _)| b.opacity.is_some()) {
            return Err(
                o.err("a mask or null bsdf inside a blendbsdf is not supported (put the mask around the blend)")
            );
        }
        let (first, second) = match <[(Bsdf, &Elem); 2]>::try_from(parts) {
            Ok([(a, _), (b, _)]) => (a, b),
            Err(parts) => {
                return Err(match parts.get(2) {
                    Some((_, third)) => third.err("a third bsdf: a blendbsdf blends two (as in Mitsuba)"),
                    None => e.err(format!("needs two nested bsdfs (as in Mitsuba), has {}", parts.len())),
                })
            }
        };
        let (weight, texture) = match props.get("weight") {
            Some(t) if t.tag == "texture" || t.tag == "ref" => {
                let t = match t.tag.as_str() {
                    "texture" => Rc::new(self.texture(t)?),
                    _ => {
                        let id = t.required("id")?;
                        self.textures
                            .get(id)
                            .cloned()
                            .ok_or_else(|| t.err(format!("no texture with id \"{id}\" defined before it")))?
                    }
                };
                if let Some(bad) = t.texture.out_of_range() {
                    return Err(t.at.err(format!(
                        "{}: {bad}: a blend weight texture's values must be in [0, 1] (Mitsuba would clip \
                         them)",
                        t.texture.name
                    )));
                }
                // Unread: the texture gives the weight.
                (0.5, Some(t))
            }
            _ => {
                let w = props.float("weight")?.unwrap_or(0.5);
                if !(0.0..=1.0).contains(&w) {
                    return Err(props
                        .get("weight")
                        .unwrap()
                        .err(format!("must be in [0, 1], got {w} (Mitsuba would clip it)")));
                }
                (w as f32, None)
            }
        };
        let blend = Blend {
            weight,
            texture,
            first,
            second,
        };
        let depth = 1 + blend.first.blend_depth().max(blend.second.blend_depth());
        if depth > MAX_BLEND_DEPTH {
            return Err(e.err(format!(
                "blendbsdfs nested {depth} deep, more than MAX_BLEND_DEPTH = {MAX_BLEND_DEPTH}"
            )));
        }
        let two_sided = blend.first.two_sided && blend.second.two_sided;
        Ok(Bsdf {
            // The components' materials are made with the blend's (bsdf.rs's `material`).
            surface: Surface::Blend {
                weight,
                first: 0,
                second: 0,
            },
            two_sided,
            id: None,
            texture: None,
            normal_map: None,
            blend: Some(Rc::new(blend)),
            opacity: None,
            specular: None,
            alpha: None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{error, load_body, load_in, write_texture};
    use crate::{Material, NormalMap, Scene, Surface, TempDir, MAX_BLEND_DEPTH};
    use glam::Vec3;

    fn material(s: &Scene, i: u32) -> &Material {
        &s.materials[i as usize]
    }

    /// A blend's components become materials of their own (named by id, else after the blend), in the
    /// order written; a textured weight is the blend's texture; twosided around a blend of one-sided
    /// bsdfs (Blender's export) and blends of twosided ones both read.
    #[test]
    fn blends_become_materials_of_their_components() {
        let dir = TempDir::new("mitsuba-blend");
        write_texture(&dir, "w.png");
        let s = load_in(
            &dir,
            r#"<bsdf type="roughconductor" id="metal"/>
               <shape type="rectangle"><bsdf type="twosided"><bsdf type="blendbsdf"><float name="weight" value="0.25"/>
                 <bsdf type="diffuse"><rgb name="reflectance" value="0.3"/></bsdf><ref id="metal"/></bsdf></bsdf></shape>
               <shape type="sphere"><bsdf type="blendbsdf" id="b">
                 <texture type="bitmap" name="weight"><string name="filename" value="w.png"/></texture>
                 <bsdf type="twosided"><bsdf type="diffuse"/></bsdf><bsdf type="twosided"><bsdf type="plastic"/></bsdf></bsdf></shape>"#,
            &[],
        )
        .unwrap_or_else(|e| panic!("{e:#}"));
        let quad = material(&s, s.quads[1].material);
        let Surface::Blend { weight, first, second } = quad.surface else {
            panic!("{:?}", quad.surface)
        };
        assert_eq!(weight, 0.25);
        assert_eq!(
            material(&s, first).surface,
            Surface::Diffuse {
                albedo: Vec3::splat(0.3)
            }
        );
        assert_eq!(material(&s, second).name, "metal");
        assert!(matches!(material(&s, second).surface, Surface::RoughConductor { .. }));
        let sphere = material(&s, s.spheres[0].material);
        assert_eq!(sphere.name, "b");
        let Surface::Blend { first, second, .. } = sphere.surface else {
            panic!("{:?}", sphere.surface)
        };
        assert_eq!(sphere.texture, Some(0), "the weight's texture");
        assert_eq!(
            (material(&s, first).name.as_str(), material(&s, second).name.as_str()),
            ("b.0", "b.1")
        );
        assert!(matches!(material(&s, second).surface, Surface::Plastic { .. }));
        assert!(
            !s.warnings.iter().any(|w| w.contains("one-sided")),
            "two-sided both: {:?}",
            s.warnings
        );
    }

    /// A bump map around a blend goes to each component (the same map); one inside a blend stays its
    /// component's; 0.6's two-weight mixturebsdf reads as the blend it is.
    #[test]
    fn maps_around_blends_go_to_their_components_and_mixtures_read() {
        let dir = TempDir::new("mitsuba-blend-maps");
        write_texture(&dir, "h.png");
        let s = load_in(
            &dir,
            r#"<shape type="rectangle"><bsdf type="bumpmap"><texture type="bitmap"><string name="filename" value="h.png"/></texture>
                 <bsdf type="blendbsdf"><bsdf type="diffuse"/><bsdf type="conductor"/></bsdf></bsdf></shape>
               <shape type="sphere"><bsdf type="blendbsdf"><bsdf type="normalmap">
                 <texture type="bitmap" name="normalmap"><string name="filename" value="h.png"/><boolean name="raw" value="true"/></texture>
                 <bsdf type="diffuse"/></bsdf><bsdf type="diffuse"/></bsdf></shape>"#,
            &[],
        )
        .unwrap_or_else(|e| panic!("{e:#}"));
        let quad = material(&s, s.quads[1].material);
        let Surface::Blend { first, second, .. } = quad.surface else {
            panic!("{:?}", quad.surface)
        };
        assert_eq!(quad.normal_map, None);
        let bump = Some(NormalMap::Bump { texture: 0, scale: 1.0 });
        assert_eq!(
            (material(&s, first).normal_map, material(&s, second).normal_map),
            (bump, bump)
        );
        let sphere = material(&s, s.spheres[0].material);
        let Surface::Blend { first, second, .. } = sphere.surface else {
            panic!("{:?}", sphere.surface)
        };
        // The same image, read raw or not (pure 0 and 255), is one texture.
        assert_eq!(material(&s, first).normal_map, Some(NormalMap::Normal { texture: 0 }));
        assert_eq!(material(&s, second).normal_map, None);

        let path = dir.write(
            "old.xml",
            r#"<scene version="0.6.0"><sensor type="perspective"><transform name="toWorld"><lookAt origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform></sensor>
               <shape type="rectangle"><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>
               <shape type="sphere"><bsdf type="mixturebsdf"><string name="weights" value="0.3, 0.7"/>
                 <bsdf type="diffuse"/><bsdf type="conductor"/></bsdf></shape></scene>"#,
        );
        let s = crate::mitsuba::load(&path, &[]).unwrap_or_else(|e| panic!("{e:#}"));
        let m = material(&s, s.spheres[0].material);
        let Surface::Blend { weight, first, second } = m.surface else {
            panic!("{:?}", m.surface)
        };
        assert!((weight - 0.7).abs() < 1e-7, "{weight}");
        assert!(matches!(material(&s, first).surface, Surface::Diffuse { .. }));
        assert!(matches!(material(&s, second).surface, Surface::Mirror { .. }));
    }

    /// What is refused, by element.
    #[test]
    fn what_blends_cannot_be_is_refused_by_element() {
        let cases: &[(&str, &str)] = &[
            (
                r#"<shape type="rectangle"><bsdf type="blendbsdf"><bsdf type="diffuse"/><bsdf type="diffuse"/></bsdf>
                   <emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>"#,
                "an area emitter on a blendbsdf surface",
            ),
            (
                r#"<shape type="rectangle"><bsdf type="twosided"><bsdf type="blendbsdf"><bsdf type="diffuse"/>
                   <bsdf type="dielectric"/></bsdf></bsdf></shape>"#,
                "wraps a blendbsdf with a two-sided or transmitting component",
            ),
            (
                r#"<shape type="rectangle"><bsdf type="normalmap"><texture type="checkerboard" name="normalmap"/>
                   <bsdf type="blendbsdf"><bsdf type="normalmap"><texture type="checkerboard" name="normalmap"/>
                   <bsdf type="diffuse"/></bsdf><bsdf type="diffuse"/></bsdf></bsdf></shape>"#,
                "a bump or normal map inside another",
            ),
            (
                r#"<shape type="rectangle"><bsdf type="blendbsdf"><texture type="checkerboard" name="weight"/>
                   <bsdf type="diffuse"/><bsdf type="diffuse"/></bsdf><boolean name="flip_normals" value="true"/></shape>"#,
                "a blendbsdf with a texture or anisotropic roughness on a rectangle turned",
            ),
            (
                r#"<shape type="rectangle"><bsdf type="blendbsdf"><rgb name="color" value="1"/>
                   <bsdf type="diffuse"/><bsdf type="diffuse"/></bsdf></shape>"#,
                "color",
            ),
        ];
        for (body, want) in cases {
            let e = error(body);
            assert!(e.contains(want), "{body}: {e}");
            assert!(
                e.contains("scene.xml:12:") || e.contains("scene.xml:13:"),
                "located: {e}"
            );
        }
        // A checkerboard weight on a cube: a mesh with texture coordinates.
        let cube = load_body(
            r#"<shape type="cube"><bsdf type="blendbsdf"><texture type="checkerboard" name="weight"/>
               <bsdf type="diffuse"/><bsdf type="diffuse"/></bsdf></shape>"#,
        )
        .unwrap();
        assert!(cube.meshes.iter().any(|m| m.uvs.is_some()), "the textured cube has uvs");
    }

    /// Scene::validate on blends built in code: indices in range, no cycle, at most MAX_BLEND_DEPTH deep
    /// (at the bound accepted), no map of their own, a weight in [0, 1].
    #[test]
    fn validate_checks_blends() {
        let base = load_body(r#"<shape type="sphere"><bsdf type="diffuse"/></shape>"#).unwrap();
        let sphere = base.spheres[0].material;
        // `n` blends, each of the next and the sphere's diffuse, the sphere on the first.
        let chain = |n: u32| {
            let mut s = base.clone();
            let start = s.materials.len() as u32;
            for k in 0..n {
                let next = if k + 1 < n { start + k + 1 } else { sphere };
                s.materials.push(Material {
                    name: format!("blend{k}"),
                    surface: Surface::Blend {
                        weight: 0.5,
                        first: next,
                        second: sphere,
                    },
                    ..s.materials[sphere as usize].clone()
                });
            }
            s.spheres[0].material = start;
            s
        };
        chain(MAX_BLEND_DEPTH).validate().unwrap();
        let e = format!("{:#}", chain(MAX_BLEND_DEPTH + 1).validate().unwrap_err());
        assert!(
            e.contains("materials.blend4.blend") && e.contains("MAX_BLEND_DEPTH = 4"),
            "{e}"
        );
        let with = |f: &dyn Fn(&mut Scene)| {
            let mut s = chain(2);
            f(&mut s);
            format!("{:#}", s.validate().unwrap_err())
        };
        let last = base.materials.len();
        let e = with(&|s| {
            s.materials[last + 1].surface = Surface::Blend {
                weight: 0.5,
                first: 99,
                second: 0,
            }
        });
        assert!(
            e.contains("materials.blend1.blend") && e.contains("index 99 out of range"),
            "{e}"
        );
        let e = with(&|s| {
            s.materials[last + 1].surface = Surface::Blend {
                weight: 0.5,
                first: last as u32,
                second: 0,
            }
        });
        assert!(e.contains("contains itself"), "{e}");
        let e = with(&|s| {
            s.materials[last].surface = Surface::Blend {
                weight: -0.1,
                first: 0,
                second: 0,
            }
        });
        assert!(
            e.contains("materials.blend0.blend.weight") && e.contains("[0, 1]"),
            "{e}"
        );
        let e = with(&|s| s.materials[last].normal_map = Some(NormalMap::Normal { texture: 0 }));
        assert!(e.contains("normal_map"), "{e}");
        let e = with(&|s| s.materials[last].emission = Vec3::ONE);
        assert!(e.contains("materials.blend0.emission"), "{e}");
    }
}
