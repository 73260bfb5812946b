//! Textures (Mitsuba's `bitmap` and `checkerboard`): a reflectance that varies over a surface with its
//! texture coordinates. A material with a texture takes its diffuse reflectance (a diffuse surface's
//! albedo, a plastic's diffuse_reflectance) from it at each point; shaders/common/texture.glsl evaluates
//! it, crates/engine/src/reference/texture.rs is its CPU twin. Texture coordinates follow Mitsuba: (0, 0)
//! is the top-left corner of an image, v grows downwards; a rectangle's are its local (x, y) mapped from
//! [-1, 1] to [0, 1], a sphere's its longitude and colatitude, a mesh's its vertices'.

use std::path::Path;

use glam::Vec3;

/// Largest accepted image side. A larger one is almost certainly a mistake and would not fit a device's
/// texel buffer (`Limit` errors say so for the sum of a scene's textures).
pub const MAX_TEXTURE_SIDE: u32 = 16384;

/// How coordinates outside [0, 1] wrap (Mitsuba's `wrap_mode`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Wrap {
    Repeat,
    Mirror,
    Clamp,
}

/// How an image is read between its pixels' centres (Mitsuba's `filter_type`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Filter {
    Bilinear,
    Nearest,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Pattern {
    /// Linear RGB pixels, row by row from the image's top row.
    Bitmap { width: u32, height: u32, pixels: Vec<Vec3> },
    /// Mitsuba's checkerboard: color0 where floor(2u) + floor(2v) is even (of the uv after `to_uv`), else
    /// color1.
    Checkerboard { color0: Vec3, color1: Vec3 },
}

#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Where it came from (the image file as given, or "checkerboard"), for messages.
    pub name: String,
    pub pattern: Pattern,
    pub filter: Filter,
    pub wrap: Wrap,
    /// Mitsuba's `to_uv`, an affine map of the surface's coordinates: (m[0] u + m[1] v + m[2],
    /// m[3] u + m[4] v + m[5]).
    pub to_uv: [f32; 6],
}

/// The identity `to_uv`.
pub const IDENTITY_UV: [f32; 6] = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0];

impl Texture {
    /// The largest value of each channel anywhere on the texture.
    pub fn max(&self) -> Vec3 {
        match &self.pattern {
            Pattern::Bitmap { pixels, .. } => pixels.iter().fold(Vec3::ZERO, |a, p| a.max(*p)),
            Pattern::Checkerboard { color0, color1 } => color0.max(*color1),
        }
    }

    /// The smallest.
    pub fn min(&self) -> Vec3 {
        match &self.pattern {
            Pattern::Bitmap { pixels, .. } => pixels.iter().fold(Vec3::INFINITY, |a, p| a.min(*p)),
            Pattern::Checkerboard { color0, color1 } => color0.min(*color1),
        }
    }

    /// Pixels it holds (0 for a checkerboard).
    pub fn pixel_count(&self) -> u64 {
        match &self.pattern {
            Pattern::Bitmap { width, height, .. } => *width as u64 * *height as u64,
            Pattern::Checkerboard { .. } => 0,
        }
    }
}

/// sRGB's transfer function inverted: an encoded value in [0, 1] to linear.
pub fn srgb_to_linear(x: f32) -> f32 {
    if x <= 0.04045 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

/// Reads an image file (PNG, JPEG, EXR) as linear RGB, its top row first: 8- and 16-bit images are taken
/// as sRGB-encoded and decoded unless `raw` (Mitsuba's rule; alpha is dropped), floating-point ones
/// (EXR) as linear already. The error says what is wrong with the file, without its name (the caller's
/// message names it with the scene line).
pub fn read_image(path: &Path, raw: bool) -> Result<(u32, u32, Vec<Vec3>), String> {
    let open = || {
        image::ImageReader::open(path)
            .map_err(|e| format!("cannot open the image: {e}"))?
            .with_guessed_format()
            .map_err(|e| format!("cannot read the image: {e}"))
    };
    // The size first, from the header: an absurd one is refused before anything is decoded.
    let (width, height) = open()?
        .into_dimensions()
        .map_err(|e| format!("not a readable PNG, JPEG or EXR image: {e}"))?;
    if width == 0 || height == 0 || width > MAX_TEXTURE_SIDE || height > MAX_TEXTURE_SIDE {
        return Err(format!(
            "image of {width} x {height} pixels: each side must be in 1..={MAX_TEXTURE_SIDE}"
        ));
    }
    let image = open()?
        .decode()
        .map_err(|e| format!("not a readable PNG, JPEG or EXR image: {e}"))?;
    let linear = raw || matches!(image.color(), image::ColorType::Rgb32F | image::ColorType::Rgba32F);
    let rgb = image.to_rgb32f();
    let pixels = rgb
        .pixels()
        .map(|p| {
            let v = Vec3::from_array(p.0);
            if linear {
                v
            } else {
                Vec3::new(srgb_to_linear(v.x), srgb_to_linear(v.y), srgb_to_linear(v.z))
            }
        })
        .collect();
    Ok((width, height, pixels))
}
