//! CPU twin of shaders/common/texture.glsl: a texture's value at texture coordinates, from the same
//! texels the kernels read (`GpuScene::textures`), and a material with its texture applied.

use glam::{IVec2, Vec2, Vec3};
use ppm_vk_kernels::layout::{
    Material, FILTER_NEAREST, SURFACE_PLASTIC, TEXTURE_CHECKERBOARD, WRAP_CLAMP, WRAP_MIRROR,
};
use ppm_vk_materials::math::v3;

use ppm_vk_engine::lower::GpuScene;

pub(crate) fn texel_rgb(t: [u32; 4]) -> Vec3 {
    Vec3::new(f32::from_bits(t[0]), f32::from_bits(t[1]), f32::from_bits(t[2]))
}

/// texture.glsl's `wrap_pixel`.
fn wrap_pixel(i: i32, n: i32, wrap: u32) -> i32 {
    if wrap == WRAP_CLAMP {
        return i.clamp(0, n - 1);
    }
    let k = (i as f32 / n as f32).floor() as i32;
    let m = i - n * k;
    if wrap == WRAP_MIRROR && k & 1 != 0 {
        n - 1 - m
    } else {
        m
    }
}

pub(crate) fn pixel(texels: &[[u32; 4]], first: u32, size: IVec2, p: IVec2, wrap: u32) -> Vec3 {
    let x = wrap_pixel(p.x, size.x, wrap);
    let y = wrap_pixel(p.y, size.y, wrap);
    texel_rgb(texels[(first as i32 + y * size.x + x) as usize])
}

/// texture.glsl's `texture_value`: the texture whose header is texel `at`, at `uv`.
pub fn value(texels: &[[u32; 4]], at: u32, uv: Vec2) -> Vec3 {
    let head = texels[at as usize];
    let r0 = texel_rgb(texels[at as usize + 1]);
    let r1 = texel_rgb(texels[at as usize + 2]);
    let st = Vec2::new(r0.x * uv.x + r0.y * uv.y + r0.z, r1.x * uv.x + r1.y * uv.y + r1.z);
    if head[0] & 15 == TEXTURE_CHECKERBOARD {
        let f = st - st.floor();
        let upper = (f.x > 0.5, f.y > 0.5);
        return texel_rgb(texels[at as usize + if upper.0 == upper.1 { 3 } else { 4 }]);
    }
    let (filter, wrap) = ((head[0] >> 4) & 15, (head[0] >> 8) & 15);
    let size = IVec2::new(head[1] as i32, head[2] as i32);
    let p = st * size.as_vec2();
    if filter == FILTER_NEAREST {
        return pixel(texels, head[3], size, p.floor().as_ivec2(), wrap);
    }
    let p = p - Vec2::splat(0.5);
    let i = p.floor().as_ivec2();
    let w = p - i.as_vec2();
    let c = |dx: i32, dy: i32| pixel(texels, head[3], size, i + IVec2::new(dx, dy), wrap);
    (1.0 - w.y) * ((1.0 - w.x) * c(0, 0) + w.x * c(1, 0)) + w.y * ((1.0 - w.x) * c(0, 1) + w.x * c(1, 1))
}

/// texture.glsl's `apply_parameter_textures`: specular_reflectance's texture becomes the colour, alpha's
/// luminance (floored at Mitsuba's 1e-4) both alphas.
fn apply_parameter_textures(g: &GpuScene, m: &Material, uv: Vec2) -> Material {
    let mut out = *m;
    if m.specular_texture != 0 {
        out.color = value(&g.textures, m.specular_texture - 1, uv).to_array();
    }
    if m.alpha_texture != 0 {
        let y = Vec3::new(0.212671, 0.715160, 0.072169); // Mitsuba's luminance
        out.alpha_u = value(&g.textures, m.alpha_texture - 1, uv).dot(y).max(1e-4);
        out.alpha_v = out.alpha_u;
    }
    out
}

/// texture.glsl's `apply_texture`: material `m` at texture coordinates `uv`.
/// An emitter's radiance texture gives its emission there.
pub fn apply(g: &GpuScene, m: &Material, uv: Vec2) -> Material {
    let mut m = apply_parameter_textures(g, m, uv);
    if v3(m.emission).max_element() > 0.0 && m.emission_texture != 0 {
        m.emission = value(&g.textures, m.emission_texture - 1, uv).to_array();
    }
    if m.texture == 0 {
        return m;
    }
    let mut value = value(&g.textures, m.texture - 1, uv);
    if m.surface == SURFACE_PLASTIC {
        let b = v3(m.lobe_b);
        let inner = if b.z != 0.0 {
            Vec3::ONE - value * b.y
        } else {
            Vec3::splat(1.0 - b.y)
        };
        value = value / inner / (m.ior * m.ior);
    }
    Material {
        color: value.to_array(),
        ..m
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ppm_vk_engine::lower::texture_texels;
    use ppm_vk_engine::scene::texture::{read_image, Filter, Pattern, Texture, Wrap};

    const REFERENCES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/references");

    use ppm_vk_materials::testing::json_rgb as rgb;

    /// Mitsuba's bitmap and checkerboard evaluated at 30-34 texture coordinates each (inside, on pixel
    /// centres and between them, outside [0, 1] both ways) in 25 cases: three images (8-bit sRGB RGB, a
    /// float EXR, an 8-bit grayscale PNG), both filters, the three wrap modes, raw on and off, to_uv maps
    /// with a scale, an offset and a rotation (scenes/references/textures.py wrote textures.json). Ours,
    /// reading the images through scene::texture and the texels the kernels read, must agree; a point
    /// Mitsuba's script marks as on an edge (where nearest filtering or the checkerboard jumps, so an ulp
    /// of the coordinate decides) may take either side.
    #[test]
    fn textures_match_mitsubas() {
        let text = std::fs::read_to_string(format!("{REFERENCES}/textures.json")).unwrap();
        let json: serde_json::Value = serde_json::from_str(&text).unwrap();
        let (mut worst, mut points, mut edges) = (0f32, 0, 0);
        for case in json["cases"].as_array().unwrap() {
            let p = &case["params"];
            let m: Vec<f32> = case["to_uv"]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap() as f32)
                .collect();
            let pattern = match p["type"].as_str().unwrap() {
                "checkerboard" => Pattern::Checkerboard {
                    color0: p.get("color0").map_or(Vec3::splat(0.4), rgb),
                    color1: p.get("color1").map_or(Vec3::splat(0.2), rgb),
                },
                _ => {
                    let path = format!("{REFERENCES}/{}", p["filename"].as_str().unwrap());
                    let raw = p.get("raw").is_some_and(|r| r.as_bool().unwrap());
                    let (width, height, pixels) = read_image(std::path::Path::new(&path), raw).unwrap();
                    Pattern::Bitmap { width, height, pixels }
                }
            };
            let texture = Texture {
                name: "t".into(),
                pattern,
                filter: match p.get("filter_type").and_then(|f| f.as_str()) {
                    Some("nearest") => Filter::Nearest,
                    _ => Filter::Bilinear,
                },
                wrap: match p.get("wrap_mode").and_then(|f| f.as_str()) {
                    Some("mirror") => Wrap::Mirror,
                    Some("clamp") => Wrap::Clamp,
                    _ => Wrap::Repeat,
                },
                to_uv: [m[0], m[1], m[2], m[3], m[4], m[5]],
            };
            let (texels, at) = texture_texels(&[texture]);
            for s in case["samples"].as_array().unwrap() {
                let uv = s["uv"].as_array().unwrap();
                let uv = Vec2::new(uv[0].as_f64().unwrap() as f32, uv[1].as_f64().unwrap() as f32);
                let (got, want) = (value(&texels, at[0], uv), rgb(&s["value"]));
                let e = (got - want).abs().max_element();
                if s.get("edge").is_some_and(|e| e.as_bool().unwrap()) {
                    edges += 1;
                    continue;
                }
                points += 1;
                worst = worst.max(e);
                assert!(e < 2e-5, "{p} to_uv {m:?} at {uv}: {got} against Mitsuba's {want}");
            }
        }
        println!("{points} points (and {edges} on edges): largest difference {worst:.2e}");
    }
}
