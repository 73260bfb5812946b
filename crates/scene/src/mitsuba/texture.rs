//! The `<texture>` element (Mitsuba's `bitmap` and `checkerboard`), nested in a bsdf or at the top level.

use std::rc::Rc;

use anyhow::Result;
use glam::Vec3;

use super::elem::Elem;
use super::properties::Props;
use super::Builder;
use crate::texture::{self, Filter, Pattern, Texture, Wrap};

/// A texture with the element it was read from (to locate what a later check finds wrong with it).
#[derive(Debug)]
pub(super) struct Tex {
    pub(super) texture: Texture,
    pub(super) at: Elem,
}

/// Whether two bsdfs read the same texture (or neither reads one).
pub(super) fn same_texture(a: &Option<Rc<Tex>>, b: &Option<Rc<Tex>>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => Rc::ptr_eq(a, b) || a.texture == b.texture,
        _ => false,
    }
}

impl Builder {
    /// A `<texture>`: Mitsuba's `bitmap` (its image read here, relative to the scene file) or
    /// `checkerboard`.
    pub(super) fn texture(&self, e: &Elem) -> Result<Tex> {
        let (props, objects) = Props::of(e);
        if let Some(o) = objects.first() {
            return Err(o.err(format!("not expected inside {}", e.what())));
        }
        let to_uv = texture::uv_map_from_affine(&props.transform("to_uv")?);
        let choice = |name: &str, default: &str, known: &[&str]| -> Result<String> {
            let v = props.string(name)?.unwrap_or(default);
            if known.contains(&v) {
                Ok(v.to_string())
            } else {
                Err(props
                    .get(name)
                    .unwrap()
                    .err(format!("\"{v}\": expected {}", known.join(", "))))
            }
        };
        let texture = match e.kind() {
            "bitmap" => {
                let path = self.file(e, &props)?;
                let filter = match choice("filter_type", "bilinear", &["bilinear", "nearest"])?.as_str() {
                    "nearest" => Filter::Nearest,
                    _ => Filter::Bilinear,
                };
                let wrap = match choice("wrap_mode", "repeat", &["repeat", "mirror", "clamp"])?.as_str() {
                    "mirror" => Wrap::Mirror,
                    "clamp" => Wrap::Clamp,
                    _ => Wrap::Repeat,
                };
                let raw = props.boolean("raw")?;
                // How Mitsuba stores the pixels (half or single precision) and whether it uses the GPU's
                // texture units: not what the image holds.
                choice("format", "auto", &["auto", "variant", "fp16"])?;
                props.ignore(&["accel"]);
                props.finish()?;
                let shown = path.display().to_string();
                Texture::bitmap(&path, &shown, raw, filter, wrap, to_uv).map_err(|m| e.err(format!("{shown}: {m}")))?
            }
            "checkerboard" => {
                let color0 = props.color("color0")?.unwrap_or(Vec3::splat(0.4));
                let color1 = props.color("color1")?.unwrap_or(Vec3::splat(0.2));
                props.finish()?;
                Texture {
                    name: "checkerboard".into(),
                    pattern: Pattern::Checkerboard { color0, color1 },
                    filter: Filter::Bilinear,
                    wrap: Wrap::Repeat,
                    to_uv,
                }
            }
            _ => return Err(e.err("unsupported texture (read: bitmap, checkerboard)")),
        };
        Ok(Tex { texture, at: e.clone() })
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{load_in, write_texture};
    use super::*;
    use crate::{Material, Microfacet, Scene, Surface, TempDir};

    fn material_of_quad(s: &Scene, quad: usize) -> &Material {
        &s.materials[s.quads[quad].material as usize]
    }

    #[test]
    fn bitmap_and_checkerboard_textures_on_diffuse_and_plastic() {
        let dir = TempDir::new("mitsuba-tex");
        std::fs::create_dir_all(dir.0.join("tex")).unwrap();
        write_texture(&dir, "tex/rgbw.png");
        let s = load_in(
            &dir,
            r#"<shape type="rectangle"><bsdf type="diffuse"><texture type="bitmap" name="reflectance">
                 <string name="filename" value="tex/rgbw.png"/></texture></bsdf></shape>
               <shape type="rectangle"><bsdf type="twosided"><bsdf type="diffuse"><texture type="bitmap" name="reflectance">
                 <string name="filename" value="tex/rgbw.png"/><string name="filter_type" value="nearest"/>
                 <string name="wrap_mode" value="clamp"/><boolean name="raw" value="true"/>
                 <string name="format" value="fp16"/><boolean name="accel" value="false"/>
                 <transform name="to_uv"><scale x="2" y="3"/><translate x="0.5"/></transform></texture></bsdf></bsdf></shape>
               <shape type="sphere"><bsdf type="plastic"><texture type="checkerboard" name="diffuse_reflectance">
                 <rgb name="color0" value="0.1, 0.2, 0.3"/></texture></bsdf></shape>
               <shape type="sphere"><transform name="to_world"><scale value="2"/><translate x="3"/></transform>
                 <bsdf type="diffuse"><texture type="checkerboard" name="reflectance"/></bsdf></shape>"#,
            &[],
        )
        .unwrap_or_else(|e| panic!("{e:#}"));
        // One texture for each distinct (image, parameters): three, the checkerboards differing in colour.
        assert_eq!(
            s.textures.len(),
            4,
            "{:?}",
            s.textures.iter().map(|t| &t.name).collect::<Vec<_>>()
        );
        let m = material_of_quad(&s, 1);
        let t = &s.textures[m.texture.unwrap() as usize];
        assert!(t.name.ends_with("tex/rgbw.png"), "{}", t.name);
        assert_eq!(
            (t.filter, t.wrap, t.to_uv),
            (Filter::Bilinear, Wrap::Repeat, texture::IDENTITY_UV)
        );
        assert_eq!(
            t.pattern,
            Pattern::Bitmap {
                width: 2,
                height: 2,
                pixels: vec![Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE]
            },
            "top row first"
        );
        // The constant is the texture's largest value in each channel.
        assert_eq!(m.surface, Surface::Diffuse { albedo: Vec3::ONE });
        let t2 = &s.textures[material_of_quad(&s, 2).texture.unwrap() as usize];
        assert_eq!((t2.filter, t2.wrap), (Filter::Nearest, Wrap::Clamp));
        assert_eq!(t2.to_uv, [2.0, 0.0, 0.5, 0.0, 3.0, 0.0]);
        assert_ne!(
            material_of_quad(&s, 1),
            material_of_quad(&s, 2),
            "different textures, different materials"
        );
        let plastic = &s.materials[s.spheres[0].material as usize];
        let board = &s.textures[plastic.texture.unwrap() as usize];
        assert_eq!(
            board.pattern,
            Pattern::Checkerboard {
                color0: Vec3::new(0.1, 0.2, 0.3),
                color1: Vec3::splat(0.2)
            }
        );
        assert!(matches!(plastic.surface, Surface::Plastic { diffuse, .. } if diffuse == Vec3::new(0.2, 0.2, 0.3)));
        // Mitsuba's defaults, on a sphere scaled and moved (not rotated).
        let grey = &s.materials[s.spheres[1].material as usize];
        assert_eq!(
            s.textures[grey.texture.unwrap() as usize].pattern,
            Pattern::Checkerboard {
                color0: Vec3::splat(0.4),
                color1: Vec3::splat(0.2)
            }
        );
        assert_eq!(
            grey.surface,
            Surface::Diffuse {
                albedo: Vec3::splat(0.4)
            }
        );
        s.validate().unwrap();

        // A top-level texture, referenced twice: one texture, one material; a plastic above the photons'
        // bound is lowered per pixel, with a warning, in a copy of its own.
        let s = load_in(
            &dir,
            r#"<texture type="bitmap" id="wood"><string name="filename" value="tex/rgbw.png"/></texture>
               <bsdf type="diffuse" id="a"><ref name="reflectance" id="wood"/></bsdf>
               <shape type="rectangle"><ref id="a"/></shape>
               <shape type="rectangle"><bsdf type="diffuse" id="a2"><ref id="wood" name="reflectance"/></bsdf></shape>
               <shape type="rectangle"><bsdf type="twosided"><bsdf type="roughplastic"><ref name="diffuse_reflectance" id="wood"/></bsdf></bsdf></shape>"#,
            &[],
        )
        .unwrap_or_else(|e| panic!("{e:#}"));
        let (a, a2, p) = (
            material_of_quad(&s, 1),
            material_of_quad(&s, 2),
            material_of_quad(&s, 3),
        );
        assert_eq!(a.texture, a2.texture);
        assert_ne!(p.texture, a.texture);
        assert_eq!(s.textures.len(), 2);
        let ior = (1.49f64 / 1.000277) as f32;
        let coat = crate::plastic::coat(ior, Some(Microfacet::isotropic(false, 0.1)));
        let most = crate::plastic::max_diffuse_reflectance(ior, false, &coat);
        assert_eq!(s.textures[p.texture.unwrap() as usize].max(), Vec3::splat(most));
        assert!(matches!(p.surface, Surface::Plastic { diffuse, .. } if diffuse == Vec3::splat(most)));
        assert!(
            s.warnings
                .iter()
                .any(|w| w.contains("rgbw.png\": 4 pixels lowered to at most 0.9")),
            "{:?}",
            s.warnings
        );
        s.validate().unwrap();
    }

    #[test]
    fn texture_errors_name_the_file_and_line() {
        let dir = TempDir::new("mitsuba-tex-err");
        write_texture(&dir, "t.png");
        dir.write("corrupt.png", "\u{89}PNG\r\n\u{1a}\nthis is not a PNG");
        // A valid PNG header (signature, IHDR) claiming 100000 x 1 pixels, then an empty IDAT and IEND.
        let chunk = |kind: &[u8], data: &[u8]| -> Vec<u8> {
            let mut c = (data.len() as u32).to_be_bytes().to_vec();
            c.extend_from_slice(kind);
            c.extend_from_slice(data);
            // CRC-32 of the chunk's type and data.
            let mut crc = !0u32;
            for &b in &c[4..] {
                crc ^= u32::from(b);
                for _ in 0..8 {
                    crc = if crc & 1 != 0 {
                        0xEDB8_8320 ^ (crc >> 1)
                    } else {
                        crc >> 1
                    };
                }
            }
            c.extend_from_slice(&(!crc).to_be_bytes());
            c
        };
        let claiming = |w: u32, h: u32| {
            let mut ihdr = w.to_be_bytes().to_vec();
            ihdr.extend_from_slice(&h.to_be_bytes());
            ihdr.extend_from_slice(&[8, 2, 0, 0, 0]);
            let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
            png.extend(chunk(b"IHDR", &ihdr));
            png.extend(chunk(b"IDAT", &[]));
            png.extend(chunk(b"IEND", &[]));
            png
        };
        std::fs::write(dir.0.join("huge.png"), claiming(100_000, 1)).unwrap();
        // Sides within bounds, but 2^28 pixels: refused before anything is decoded.
        std::fs::write(dir.0.join("vast.png"), claiming(16384, 16384)).unwrap();
        // An EXR with a value above 1.
        image::Rgb32FImage::from_raw(1, 1, vec![1.5, 0.5, 0.5])
            .unwrap()
            .save(dir.0.join("bright.exr"))
            .unwrap();
        let bitmap = |file: &str| {
            format!(
                r#"<shape type="rectangle"><bsdf type="diffuse">
<texture type="bitmap" name="reflectance"><string name="filename" value="{file}"/></texture></bsdf></shape>"#
            )
        };
        let diffuse =
            |texture: &str| format!(r#"<shape type="rectangle"><bsdf type="diffuse">{texture}</bsdf></shape>"#);
        let tex = r#"<texture type="bitmap" name="reflectance"><string name="filename" value="t.png"/></texture>"#;
        // (body, the element named, its line, what is said)
        let cases: Vec<(String, &str, usize, &str)> = vec![
            (bitmap("missing.png"), r#"<texture type="bitmap" name="reflectance">"#, 13, "missing.png: cannot read the image"),
            (bitmap("corrupt.png"), r#"<texture type="bitmap" name="reflectance">"#, 13, "corrupt.png: not a readable PNG"),
            (bitmap("huge.png"), r#"<texture type="bitmap" name="reflectance">"#, 13, "huge.png: image of 100000 x 1 pixels"),
            (bitmap("vast.png"), r#"<texture type="bitmap" name="reflectance">"#, 13, "vast.png: image of 16384 x 16384 pixels: at most"),
            (
                bitmap("bright.exr"),
                r#"<texture type="bitmap" name="reflectance">"#,
                13,
                "bright.exr: pixel (0, 0) (column, row from the top) is [1.5, 0.5, 0.5]: a reflectance texture's values must be in [0, 1]",
            ),
            (
                diffuse(r#"<texture type="mesh_attribute" name="reflectance"/>"#),
                r#"<texture type="mesh_attribute" name="reflectance">"#,
                12,
                "unsupported texture (read: bitmap, checkerboard)",
            ),
            (
                diffuse(r#"<texture type="bitmap" name="reflectance"><string name="filename" value="t.png"/><string name="filter_type" value="cubic"/></texture>"#),
                r#"<string name="filter_type">"#,
                12,
                "\"cubic\": expected bilinear, nearest",
            ),
            (
                diffuse(r#"<texture type="bitmap" name="reflectance"><string name="filename" value="t.png"/><float name="gamma" value="2.2"/></texture>"#),
                r#"<float name="gamma">"#,
                12,
                "parameter not read by ppm-vk for <texture type=\"bitmap\" name=\"reflectance\">",
            ),
            (
                diffuse(r#"<texture type="checkerboard" name="reflectance"><texture type="checkerboard" name="color0"/></texture>"#),
                r#"<texture type="checkerboard" name="color0">"#,
                12,
                "a texture on color0 is not supported",
            ),
            (diffuse(r#"<ref name="reflectance" id="nothing"/>"#), r#"<ref id="nothing" name="reflectance">"#, 12, "no texture with id \"nothing\""),
            (
                format!(r#"<shape type="rectangle"><bsdf type="conductor">{}</bsdf></shape>"#, tex.replace("reflectance", "eta")),
                r#"<texture type="bitmap" name="eta">"#,
                12,
                "a texture on eta is not supported: read on diffuse reflectances",
            ),
            (
                format!(r#"<shape type="rectangle"><bsdf type="plastic">{}</bsdf></shape>"#, tex.replace("reflectance", "specular_reflectance")),
                r#"<texture type="bitmap" name="specular_reflectance">"#,
                12,
                "a texture on plastic's specular_reflectance is not supported",
            ),
            (
                format!(r#"<shape type="sphere"><emitter type="area">{}</emitter></shape>"#, tex.replace("reflectance", "radiance")),
                r#"<texture type="bitmap" name="radiance">"#,
                12,
                "a texture on an area emitter's radiance on a sphere is not supported yet",
            ),
            (
                format!(r#"<shape type="sphere"><transform name="to_world"><rotate x="1" angle="30"/></transform><bsdf type="diffuse">{tex}</bsdf></shape>"#),
                r#"<shape type="sphere">"#,
                12,
                "a textured sphere whose to_world rotates or mirrors it",
            ),
            (
                format!(r#"<shape type="sphere"><transform name="to_world"><scale value="-1"/></transform><bsdf type="diffuse">{tex}</bsdf></shape>"#),
                r#"<shape type="sphere">"#,
                12,
                "rotates or mirrors",
            ),
            (
                r#"<texture type="bitmap" id="a"><string name="filename" value="t.png"/></texture><bsdf type="diffuse" id="a"/>"#.to_string(),
                r#"<bsdf type="diffuse" id="a">"#,
                12,
                "the id \"a\" is already taken",
            ),
        ];
        for (body, element, line, says) in &cases {
            let e = match load_in(&dir, body, &[]) {
                Ok(_) => panic!("expected an error for {body}"),
                Err(e) => format!("{e:#}"),
            };
            assert!(
                e.contains(&format!("scene.xml:{line}:")),
                "{e} should be at line {line}"
            );
            assert!(e.contains(element), "{e} should name {element}");
            assert!(e.contains(says), "{e} should say {says}");
        }
    }
}
