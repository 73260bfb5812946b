//! The bsdfs that wrap another and change where its shading normal points: Mitsuba's `bumpmap` (a height
//! texture) and `normalmap` (a tangent-space normal texture), both with their shadowing term (Mitsuba 3's
//! src/bsdfs/bumpmap.cpp, normalmap.cpp, normalmap_helpers.h).

use std::rc::Rc;

use anyhow::Result;

use super::bsdf::{Bsdf, Perturbation};
use super::elem::Elem;
use super::properties::Props;
use super::texture::Tex;
use super::Builder;

/// What a modifier nests: bsdfs (an element, or one a `ref` names) and textures.
enum Nested<'a> {
    Bsdf(&'a Elem),
    BsdfRef(Bsdf),
    Texture(&'a Elem),
}

impl Builder {
    /// Mitsuba's `bumpmap`: one nested bsdf and one texture (nested, named anything, or a `ref` to a
    /// top-level one), and `scale` (default 1).
    pub(super) fn bumpmap(&mut self, e: &Elem, props: &Props, objects: &[&Elem]) -> Result<Bsdf> {
        let nested = self.nested(e, props, objects, None)?;
        let textures: Vec<&Elem> = nested
            .iter()
            .filter_map(|n| match n {
                Nested::Texture(t) => Some(*t),
                _ => None,
            })
            .collect();
        let texture = match textures[..] {
            [one] => self.texture_or_ref(one)?,
            [] => return Err(e.err("needs one nested texture (the height map)")),
            [_, second, ..] => return Err(second.err("a second texture: a bumpmap has one (as in Mitsuba)")),
        };
        // Mitsuba's checkerboard has no gradient (Texture::eval_1_grad throws).
        if matches!(texture.texture.pattern, crate::texture::Pattern::Checkerboard { .. }) {
            return Err(texture
                .at
                .err("a checkerboard as a height map: Mitsuba gives it no gradient (use a bitmap)"));
        }
        let scale = props.float("scale")?.unwrap_or(1.0);
        if !(scale as f32).is_finite() {
            return Err(props
                .get("scale")
                .unwrap()
                .err(format!("must be a finite 32-bit float, got {scale}")));
        }
        self.wrap(e, props, nested, texture, Some(scale as f32))
    }

    /// Mitsuba's `normalmap`: one nested bsdf and the texture `normalmap`.
    pub(super) fn normalmap(&mut self, e: &Elem, props: &Props, objects: &[&Elem]) -> Result<Bsdf> {
        let nested = self.nested(e, props, objects, Some("normalmap"))?;
        let Some(t) = props.get("normalmap") else {
            return Err(e.err("needs the texture \"normalmap\""));
        };
        let texture = self.texture_or_ref(t)?;
        self.wrap(e, props, nested, texture, None)
    }

    /// The objects nested in modifier `e`, with its named textures (all of them, or only `only`).
    fn nested<'a>(
        &self,
        e: &'a Elem,
        props: &Props,
        objects: &[&'a Elem],
        only: Option<&str>,
    ) -> Result<Vec<Nested<'a>>> {
        let mut out = Vec::new();
        for &o in objects {
            out.push(match o.tag.as_str() {
                "bsdf" => Nested::Bsdf(o),
                "texture" => Nested::Texture(o),
                "ref" => {
                    let id = o.required("id")?;
                    match (self.bsdfs.get(id), self.textures.contains_key(id)) {
                        (Some(b), _) => Nested::BsdfRef(b.clone()),
                        (None, true) => Nested::Texture(o),
                        (None, false) => {
                            return Err(o.err(format!("no bsdf or texture with id \"{id}\" defined before it")))
                        }
                    }
                }
                _ => return Err(o.err(format!("not expected inside {}", e.what()))),
            });
        }
        if only.is_none() {
            for c in &e.children {
                if let (true, Some(name)) = (c.tag == "texture" || c.tag == "ref", c.attr("name")) {
                    props.get(name); // read here
                    out.push(Nested::Texture(c));
                }
            }
        }
        Ok(out)
    }

    /// The nested bsdf with the perturbation; Mitsuba's options that ppm-vk does not follow are warned.
    fn wrap(
        &mut self,
        e: &Elem,
        props: &Props,
        nested: Vec<Nested>,
        texture: Rc<Tex>,
        bump_scale: Option<f32>,
    ) -> Result<Bsdf> {
        let mut bsdfs = nested.into_iter().filter(|n| !matches!(n, Nested::Texture(_)));
        let inner = match (bsdfs.next(), bsdfs.next()) {
            (Some(Nested::Bsdf(b)), None) => self.bsdf(b)?,
            (Some(Nested::BsdfRef(b)), None) => Bsdf { id: None, ..b },
            (None, _) => return Err(e.err("needs one nested bsdf")),
            _ => return Err(e.err("holds a second bsdf: it wraps one (as in Mitsuba)")),
        };
        if inner.normal_map.is_some() {
            return Err(e.err("a bump or normal map inside another is not supported (one perturbation per surface)"));
        }
        let given = |name: &str| props.get(name).is_some();
        if given("use_shadowing_function") && !props.boolean("use_shadowing_function")? {
            return Err(props
                .get("use_shadowing_function")
                .unwrap()
                .err("only the default, true, is supported (the shadowing term is always applied)"));
        }
        if !given("flip_invalid_normals") || props.boolean("flip_invalid_normals")? {
            self.warn(
                e,
                "flip_invalid_normals (Mitsuba's default): ppm-vk does not mirror a perturbed normal that \
                 faces away from the eye; such a path ends there, as at any shading normal (docs/mitsuba.md)",
            );
        }
        Ok(Bsdf {
            normal_map: Some(Perturbation { texture, bump_scale }),
            ..inner
        })
    }

    /// A `<texture>` element, or a `<ref>` to a top-level one.
    pub(super) fn texture_or_ref(&self, t: &Elem) -> Result<Rc<Tex>> {
        if t.tag != "ref" {
            return Ok(Rc::new(self.texture(t)?));
        }
        let id = t.required("id")?;
        self.textures
            .get(id)
            .cloned()
            .ok_or_else(|| t.err(format!("no texture with id \"{id}\" defined before it")))
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{error, load_body, load_in, write_texture};
    use crate::{NormalMap, Surface, TempDir};

    /// A bumpmap (its texture nested, named anything) and a normalmap around diffuse and twosided
    /// plastic bsdfs become the materials' normal maps, the textures interned once each; Mitsuba's
    /// default flip_invalid_normals is warned about.
    #[test]
    fn bumpmap_and_normalmap_wrap_their_bsdf() {
        let dir = TempDir::new("mitsuba-bump");
        write_texture(&dir, "h.png");
        let s = load_in(
            &dir,
            r#"<shape type="rectangle"><bsdf type="bumpmap"><float name="scale" value="0.25"/>
                 <texture type="bitmap" name="arbitrary"><string name="filename" value="h.png"/><boolean name="raw" value="true"/></texture>
                 <bsdf type="diffuse"><rgb name="reflectance" value="0.3"/></bsdf></bsdf></shape>
               <shape type="sphere"><bsdf type="normalmap"><boolean name="flip_invalid_normals" value="false"/>
                 <texture type="bitmap" name="normalmap"><string name="filename" value="h.png"/><boolean name="raw" value="true"/></texture>
                 <bsdf type="twosided"><bsdf type="plastic"/></bsdf></bsdf></shape>"#,
            &[],
        )
        .unwrap_or_else(|e| panic!("{e:#}"));
        assert_eq!(s.textures.len(), 1, "one image, one texture");
        let quad = &s.materials[s.quads[1].material as usize];
        assert_eq!(
            quad.surface,
            Surface::Diffuse {
                albedo: glam::Vec3::splat(0.3)
            }
        );
        assert_eq!(
            quad.normal_map,
            Some(NormalMap::Bump {
                texture: 0,
                scale: 0.25
            })
        );
        let sphere = &s.materials[s.spheres[0].material as usize];
        assert!(
            matches!(sphere.surface, Surface::Plastic { .. }),
            "{:?}",
            sphere.surface
        );
        assert_eq!(sphere.normal_map, Some(NormalMap::Normal { texture: 0 }));
        let warned: Vec<&String> = s
            .warnings
            .iter()
            .filter(|w| w.contains("flip_invalid_normals"))
            .collect();
        assert_eq!(
            warned.len(),
            1,
            "only the bumpmap keeps Mitsuba's default: {:?}",
            s.warnings
        );
        assert!(warned[0].contains("<bsdf type=\"bumpmap\">"), "{}", warned[0]);
    }

    /// What is refused, by element.
    #[test]
    fn malformed_modifiers_are_refused_by_element() {
        let cases: &[(&str, &str)] = &[
            (
                r#"<shape type="cube"><bsdf type="bumpmap"><bsdf type="diffuse"/></bsdf></shape>"#,
                "needs one nested texture",
            ),
            (
                r#"<shape type="cube"><bsdf type="bumpmap"><texture type="checkerboard"/></bsdf></shape>"#,
                "a checkerboard as a height map",
            ),
            (
                r#"<shape type="cube"><bsdf type="normalmap"><bsdf type="diffuse"/></bsdf></shape>"#,
                "needs the texture \"normalmap\"",
            ),
            (
                r#"<shape type="rectangle"><bsdf type="normalmap"><texture type="checkerboard" name="normalmap"/></bsdf></shape>"#,
                "needs one nested bsdf",
            ),
            (
                r#"<shape type="rectangle"><bsdf type="normalmap"><texture type="checkerboard" name="normalmap"/>
                   <bsdf type="normalmap"><texture type="checkerboard" name="normalmap"/><bsdf type="diffuse"/></bsdf></bsdf></shape>"#,
                "a bump or normal map inside another",
            ),
            (
                r#"<shape type="rectangle"><bsdf type="normalmap"><boolean name="use_shadowing_function" value="false"/>
                   <texture type="checkerboard" name="normalmap"/><bsdf type="diffuse"/></bsdf></shape>"#,
                "only the default, true, is supported",
            ),
            (
                r#"<shape type="rectangle"><boolean name="flip_normals" value="true"/><bsdf type="normalmap">
                   <texture type="checkerboard" name="normalmap"/><bsdf type="diffuse"/></bsdf></shape>"#,
                "on a rectangle turned by flip_normals",
            ),
        ];
        // A cube has Mitsuba's texture coordinates (a mesh of its own once textured or mapped): read.
        let cube = load_body(
            r#"<shape type="cube"><bsdf type="normalmap"><texture type="checkerboard" name="normalmap"/><bsdf type="diffuse"/></bsdf></shape>"#,
        )
        .unwrap();
        assert!(
            cube.meshes.iter().any(|m| m.uvs.is_some()),
            "the mapped cube is a mesh with uvs"
        );
        for (body, want) in cases {
            let e = error(body);
            assert!(e.contains(want), "{body}: {e}");
            assert!(
                e.contains("scene.xml:12:") || e.contains("scene.xml:13:"),
                "located: {e}"
            );
            assert!(e.contains(": <"), "names the element: {e}");
        }
    }
}
