//! The bsdfs that let light through a surface unchanged: Mitsuba's `mask` (its nested bsdf with probability
//! `opacity`, else straight through: src/bsdfs/mask.cpp) and `null` (always straight through:
//! src/bsdfs/null.cpp), read as an opacity on the material (shaders/materials/mask.glsl decides per ray).

use anyhow::Result;
use glam::Vec3;

use super::bsdf::{Bsdf, Opacity};
use super::elem::Elem;
use super::properties::{color, Props};
use super::Builder;
use crate::Surface;

impl Builder {
    /// Mitsuba's `mask`: one nested bsdf (an element or a `ref`) and `opacity` (a float, a colour or a
    /// texture; default 0.5).
    pub(super) fn mask(&mut self, e: &Elem, props: &Props, objects: &[&Elem]) -> Result<Bsdf> {
        let mut inner = None;
        for &o in objects {
            let b = match o.tag.as_str() {
                "bsdf" => self.bsdf(o)?,
                "ref" => Bsdf {
                    id: None,
                    ..self.bsdf_ref(o)?
                },
                _ => return Err(o.err(format!("not expected inside {}", e.what()))),
            };
            if inner.replace(b).is_some() {
                return Err(o.err("a second bsdf: a mask wraps one (as in Mitsuba)"));
            }
        }
        let inner = inner.ok_or_else(|| e.err("needs one nested bsdf (Mitsuba: \"Child BSDF not specified\")"))?;
        if inner.opacity.is_some() {
            return Err(e.err("a mask or null bsdf inside a mask is not supported (one opacity per surface)"));
        }
        let opacity = match props.get("opacity") {
            None => Opacity::Value(0.5),
            Some(p) if p.tag == "texture" || p.tag == "ref" => Opacity::Texture(self.texture_or_ref(p)?),
            Some(p) => {
                // A constant: Mitsuba's eval_1 of it, the luminance of a colour (a float's own value).
                let c: Vec3 = color(p)?;
                let v = ppm_vk_materials::mask::luminance(c);
                if !(0.0..=1.0).contains(&v) {
                    self.warn(
                        p,
                        format!(
                            "opacity {v} outside [0, 1]: clamped to {} (as Mitsuba)",
                            v.clamp(0.0, 1.0)
                        ),
                    );
                }
                Opacity::Value(v.clamp(0.0, 1.0))
            }
        };
        Ok(Bsdf {
            opacity: Some(opacity),
            ..inner
        })
    }

    /// Mitsuba's `null`: no surface for any ray (opacity 0). Only as the bsdf of an invisible shape here:
    /// ppm-vk has no media for it to bound, and a light on it is refused (shape.rs).
    pub(super) fn null(&self) -> Bsdf {
        Bsdf {
            surface: Surface::Diffuse { albedo: Vec3::ZERO },
            two_sided: false,
            id: None,
            texture: None,
            normal_map: None,
            blend: None,
            opacity: Some(Opacity::Value(0.0)),
            specular: None,
            alpha: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{error, load_body, load_in, write_texture};
    use crate::texture::Pattern;
    use crate::{Surface, TempDir};
    use glam::Vec3;

    /// A mask's opacity, a float, a texture or a `ref`, becomes the material's opacity texture (a constant
    /// a checkerboard of one value); the nested bsdf (also through a `ref`) is the material's surface; a
    /// null is opacity 0 on a black surface; twosided wraps a mask and a mask a twosided.
    #[test]
    fn mask_and_null_become_an_opacity() {
        let dir = TempDir::new("mitsuba-mask");
        write_texture(&dir, "leaf.png");
        let s = load_in(
            &dir,
            r#"<texture type="bitmap" id="leafy"><string name="filename" value="leaf.png"/></texture>
               <bsdf type="diffuse" id="green"><rgb name="reflectance" value="0.1, 0.6, 0.2"/></bsdf>
               <shape type="rectangle"><bsdf type="mask"><float name="opacity" value="0.25"/>
                 <bsdf type="twosided"><bsdf type="diffuse"/></bsdf></bsdf></shape>
               <shape type="rectangle"><bsdf type="twosided"><bsdf type="mask"><ref name="opacity" id="leafy"/>
                 <ref id="green"/></bsdf></bsdf></shape>
               <shape type="sphere"><bsdf type="mask"><bsdf type="conductor"/></bsdf></shape>
               <shape type="rectangle"><bsdf type="null"/></shape>"#,
            &[],
        )
        .unwrap_or_else(|e| panic!("{e:#}"));
        // quads[0] is the lamp of the tests' scene head.
        let opacity = |i: usize| {
            let m = &s.materials[s.quads[i + 1].material as usize];
            &s.textures[m.opacity.expect("masked") as usize]
        };
        let constant = |t: &crate::texture::Texture| match t.pattern {
            Pattern::Checkerboard { color0, color1 } if color0 == color1 => Some(color0.x),
            _ => None,
        };
        assert_eq!(constant(opacity(0)), Some(0.25));
        assert!(matches!(opacity(1).pattern, Pattern::Bitmap { .. }));
        assert_eq!(
            s.materials[s.quads[2].material as usize].surface,
            Surface::Diffuse {
                albedo: Vec3::new(0.1, 0.6, 0.2)
            }
        );
        let sphere = &s.materials[s.spheres[0].material as usize];
        assert_eq!(
            constant(&s.textures[sphere.opacity.unwrap() as usize]),
            Some(0.5),
            "Mitsuba's default"
        );
        let null = &s.materials[s.quads[3].material as usize];
        assert_eq!(null.surface, Surface::Diffuse { albedo: Vec3::ZERO });
        assert_eq!(constant(&s.textures[null.opacity.unwrap() as usize]), Some(0.0));
    }

    /// What is refused, each naming the element.
    #[test]
    fn malformed_masks_are_refused_by_name() {
        for (body, want) in [
            (
                r#"<shape type="sphere"><bsdf type="mask"/></shape>"#,
                "needs one nested bsdf",
            ),
            (
                r#"<shape type="sphere"><bsdf type="mask"><bsdf type="diffuse"/><bsdf type="diffuse"/></bsdf></shape>"#,
                "a second bsdf",
            ),
            (
                r#"<shape type="sphere"><bsdf type="mask"><bsdf type="mask"><bsdf type="diffuse"/></bsdf></bsdf></shape>"#,
                "inside a mask",
            ),
            (
                r#"<shape type="rectangle"><bsdf type="mask"><bsdf type="diffuse"/></bsdf><emitter type="area"/></shape>"#,
                "area emitter on a mask or null",
            ),
            (
                r#"<shape type="rectangle"><bsdf type="null"/><emitter type="area"/></shape>"#,
                "area emitter on a mask or null",
            ),
            (
                r#"<shape type="sphere"><bsdf type="mask"><float name="opacity" value="nan"/><bsdf type="diffuse"/></bsdf></shape>"#,
                "not",
            ),
            (
                r#"<shape type="sphere"><bsdf type="null"><float name="opacity" value="1"/></bsdf></shape>"#,
                "opacity",
            ),
        ] {
            let e = error(body);
            assert!(e.contains(want) && e.contains("scene.xml:"), "{body}: {e}");
        }
        // An opacity outside [0, 1] is clamped, as Mitsuba's eval_opacity does, with a warning.
        let s = load_body(
            r#"<shape type="sphere"><bsdf type="mask"><float name="opacity" value="1.5"/><bsdf type="diffuse"/></bsdf></shape>"#,
        )
        .unwrap();
        assert!(s.warnings.iter().any(|w| w.contains("clamped")), "{:?}", s.warnings);
    }
}
