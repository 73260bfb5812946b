//! Textures (Mitsuba's `bitmap` and `checkerboard`): a reflectance that varies over a surface with its
//! texture coordinates. A material with a texture takes its diffuse reflectance (a diffuse surface's
//! albedo, a plastic's diffuse_reflectance) from it at each point; shaders/common/texture.glsl evaluates
//! it, crates/reference/src/texture.rs is its CPU twin. Texture coordinates follow Mitsuba: (0, 0)
//! is the top-left corner of an image, v grows downwards; a rectangle's are its local (x, y) mapped from
//! [-1, 1] to [0, 1], a sphere's its longitude and colatitude, a mesh's its vertices'.

use std::path::Path;

use glam::Vec3;

/// Largest accepted image side. A larger one is almost certainly a mistake and would not fit a device's
/// texel buffer (`Limit` errors say so for the sum of a scene's textures).
pub const MAX_TEXTURE_SIDE: u32 = 16384;

/// Most pixels one image may have: 2^26 (8192 x 8192). Decoding takes 12 bytes a pixel twice over on the
/// host (the decoder's and ours) and the kernels 16 on the device: this keeps one image near 1.5 GiB of host
/// memory at most, whatever size its header claims.
pub const MAX_TEXTURE_PIXELS: u64 = 1 << 26;

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
    /// Mitsuba's checkerboard: color0 where the fractional parts of u and v (after `to_uv`) are on the same
    /// side of 1/2 (both above it, or neither), else color1.
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

/// Most bytes the decoder may allocate for one image: its pixels as four 32-bit floats (the widest
/// format read, EXR) and as much again for the decoder's own buffers. The default of the image crate
/// (512 MiB) refused EXRs inside [`MAX_TEXTURE_PIXELS`].
const MAX_DECODE_BYTES: u64 = MAX_TEXTURE_PIXELS * 16 * 2;

/// The image crate's error as a sentence, without its debug dumps (a PNG's bad chunk came out as
/// `ChunkType { type: IDA«, .. }`).
fn image_error(e: &image::ImageError) -> String {
    use image::ImageError as E;
    // The codec's own words where they are one plain line; else only what kind of error it is.
    let plain = |s: String| {
        let s = s.lines().next().unwrap_or("").trim().trim_end_matches('.').to_string();
        let clean = !s.is_empty() && !s.contains(['{', '}']) && s.chars().all(|c| c.is_ascii() && !c.is_control());
        clean.then(|| format!(" ({})", crate::error::truncated(&s, 100)))
    };
    match e {
        E::Decoding(d) => format!(
            "not a readable PNG, JPEG or EXR image: its data is damaged or cut short{}",
            plain(d.to_string()).unwrap_or_default()
        ),
        E::IoError(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => {
            "not a readable PNG, JPEG or EXR image: the file ends early (truncated)".into()
        }
        E::IoError(io) => format!("cannot read the image: {io}"),
        E::Limits(_) => format!(
            "decoding it would take more than {} MiB, the most one image may (MAX_TEXTURE_PIXELS of four \
             32-bit floats, twice)",
            MAX_DECODE_BYTES >> 20
        ),
        E::Unsupported(u) => format!(
            "not a readable PNG, JPEG or EXR image: an unsupported format or feature{}",
            plain(u.to_string()).unwrap_or_default()
        ),
        E::Parameter(p) => format!("not a readable image{}", plain(p.to_string()).unwrap_or_default()),
        E::Encoding(_) => "not a readable image".into(),
    }
}

/// Whether a JPEG's data ends with its end-of-image marker after its last scan: a file cut inside a
/// scan decodes without a word (the decoder is lenient and fills the rest grey), so it is checked here,
/// as a truncated PNG is refused by its decoder. In a scan a 0xFF byte is always followed by 0x00 or a
/// restart marker, so an FF D9 after the last start-of-scan (FF DA) is the real end.
fn jpeg_is_complete(bytes: &[u8]) -> bool {
    let last_scan = bytes.windows(2).rposition(|w| w == [0xFF, 0xDA]);
    last_scan.is_some_and(|at| bytes[at..].windows(2).any(|w| w == [0xFF, 0xD9]))
}

/// Reads an image file (PNG, JPEG, EXR, Radiance HDR, TGA, BMP, PPM/PGM: those of Mitsuba's Bitmap formats
/// that the image crate decodes; PFM: pfm.rs) as linear RGB, its top row first: 8- and 16-bit images are taken as
/// sRGB-encoded and decoded unless `raw` (Mitsuba's rule; alpha is dropped), floating-point ones (EXR,
/// HDR) as linear already. Only a regular file of at most [`MAX_IMAGE_BYTES`](crate::MAX_IMAGE_BYTES)
/// is opened. The error says what is wrong with the file, without its name (the caller's message
/// names it with the scene line).
pub fn read_image(path: &Path, raw: bool) -> Result<(u32, u32, Vec<Vec3>), String> {
    use std::io::{BufReader, Cursor, Read as _, Seek as _};
    let (file, _) =
        crate::files::open_bounded(path, crate::files::MAX_IMAGE_BYTES, "the image").map_err(|e| match e {
            crate::Error::Io { error, .. } => error.to_string(),
            e => e.to_string(),
        })?;
    let mut reader = BufReader::new(file);
    // A PFM (which the image crate does not read): by its first bytes, read whole (the file's bound).
    use std::io::BufRead as _;
    let head = reader.fill_buf().map_err(|e| format!("cannot read the image: {e}"))?;
    if crate::pfm::is_pfm(head) {
        return crate::pfm::read(&mut reader, MAX_TEXTURE_SIDE, MAX_TEXTURE_PIXELS);
    }
    // By its first bytes; a TGA has no signature, so by its extension then.
    let format = image::ImageReader::new(&mut reader)
        .with_guessed_format()
        .map_err(|e| format!("cannot read the image: {e}"))?
        .format()
        .or_else(|| {
            image::ImageFormat::from_path(path)
                .ok()
                .filter(|f| *f == image::ImageFormat::Tga)
        });
    reader.rewind().map_err(|e| format!("cannot read the image: {e}"))?;
    // A JPEG is read whole to check its end (JPEGs are small: the bound is the file's).
    let mut jpeg = Vec::new();
    if format == Some(image::ImageFormat::Jpeg) {
        reader
            .read_to_end(&mut jpeg)
            .map_err(|e| format!("cannot read the image: {e}"))?;
        if !jpeg_is_complete(&jpeg) {
            return Err(
                "not a readable JPEG image: its data ends before the end-of-image marker (the file is \
                        cut short)"
                    .into(),
            );
        }
    }
    let image = match format {
        None => return Err("not a readable PNG, JPEG or EXR image: its first bytes are none of theirs".into()),
        Some(image::ImageFormat::Jpeg) => decode(Cursor::new(&jpeg[..]), image::ImageFormat::Jpeg)?,
        Some(f) => decode(reader, f)?,
    };
    let (width, height) = (image.width(), image.height());
    let linear = raw || matches!(image.color(), image::ColorType::Rgb32F | image::ColorType::Rgba32F);
    // One float copy of the pixels at a time: an image at MAX_TEXTURE_PIXELS is 768 MiB of them.
    let rgb = image.into_rgb32f().into_raw();
    let pixels = rgb
        .chunks_exact(3)
        .map(|p| {
            let v = Vec3::new(p[0], p[1], p[2]);
            if linear {
                v
            } else {
                Vec3::new(srgb_to_linear(v.x), srgb_to_linear(v.y), srgb_to_linear(v.z))
            }
        })
        .collect();
    Ok((width, height, pixels))
}

/// Decodes the image `source` holds in `format`, its size first, from the header: an absurd one is
/// refused before anything is decoded.
fn decode<R: std::io::BufRead + std::io::Seek>(
    mut source: R,
    format: image::ImageFormat,
) -> Result<image::DynamicImage, String> {
    let reader = |source: R| {
        let mut r = image::ImageReader::with_format(source, format);
        let mut limits = image::Limits::default();
        limits.max_alloc = Some(MAX_DECODE_BYTES);
        r.limits(limits);
        r
    };
    let mut header = image::ImageReader::with_format(&mut source, format);
    header.no_limits();
    let (width, height) = header.into_dimensions().map_err(|e| image_error(&e))?;
    if width == 0 || height == 0 || width > MAX_TEXTURE_SIDE || height > MAX_TEXTURE_SIDE {
        return Err(format!(
            "image of {width} x {height} pixels: each side must be in 1..={MAX_TEXTURE_SIDE}"
        ));
    }
    if width as u64 * height as u64 > MAX_TEXTURE_PIXELS {
        return Err(format!(
            "image of {width} x {height} pixels: at most {MAX_TEXTURE_PIXELS} pixels (8192 x 8192)"
        ));
    }
    source.rewind().map_err(|e| format!("cannot read the image: {e}"))?;
    reader(source).decode().map_err(|e| image_error(&e))
}

/// Mitsuba's `to_uv` from the 4x4 affine transform its XML gives: Mitsuba applies it to the point
/// (u, v, 0), so the z column drops out and the translation's x and y are the offsets.
pub fn uv_map_from_affine(m: &glam::DAffine3) -> [f32; 6] {
    let (x, y, t) = (m.matrix3.x_axis, m.matrix3.y_axis, m.translation);
    [x.x, y.x, t.x, x.y, y.y, t.y].map(|c| c as f32)
}

/// Two affine uv maps (as `to_uv`) one after the other: the map of `outer(inner(uv))`.
pub fn compose_uv(outer: [f32; 6], inner: [f32; 6]) -> [f32; 6] {
    let [a, b, c, d, e, f] = outer;
    let [p, q, r, s, t, u] = inner;
    [
        a * p + b * s,
        a * q + b * t,
        a * r + b * u + c,
        d * p + e * s,
        d * q + e * t,
        d * r + e * u + f,
    ]
}

/// Mitsuba's texture coordinates of a sphere at `offset` from its centre (any length; in the sphere's
/// object axes, which are the world's for a sphere without rotation): u the longitude from +x towards
/// +y over 2 pi, v the angle from +z over pi.
pub fn sphere_uv(offset: Vec3) -> glam::Vec2 {
    let d = offset.normalize_or_zero();
    let phi = d.y.atan2(d.x);
    let phi = if phi < 0.0 { phi + std::f32::consts::TAU } else { phi };
    glam::Vec2::new(
        phi / std::f32::consts::TAU,
        d.z.clamp(-1.0, 1.0).acos() / std::f32::consts::PI,
    )
}

impl Texture {
    /// An image file as a texture (its pixels by [`read_image`]); `name` is how messages name it.
    pub fn bitmap(
        path: &Path,
        name: impl Into<String>,
        raw: bool,
        filter: Filter,
        wrap: Wrap,
        to_uv: [f32; 6],
    ) -> Result<Texture, String> {
        let (width, height, pixels) = read_image(path, raw)?;
        Ok(Texture {
            name: name.into(),
            pattern: Pattern::Bitmap { width, height, pixels },
            filter,
            wrap,
            to_uv,
        })
    }

    /// The first value that is not a reflectance (finite and in [0, 1] in every channel), described
    /// (`pixel (3, 7) (column, row from the top) is [1.5, 0, 0]`); `None` when all are.
    pub fn out_of_range(&self) -> Option<String> {
        let bad = |v: &Vec3| !(v.is_finite() && v.cmpge(Vec3::ZERO).all() && v.cmple(Vec3::ONE).all());
        match &self.pattern {
            Pattern::Bitmap { width, pixels, .. } => pixels.iter().position(bad).map(|k| {
                let w = (*width).max(1) as usize;
                let (x, y) = (k % w, k / w);
                format!(
                    "pixel ({x}, {y}) (column, row from the top) is {}",
                    crate::error::fmt_vec(pixels[k].to_array())
                )
            }),
            Pattern::Checkerboard { color0, color1 } => [("color0", color0), ("color1", color1)]
                .into_iter()
                .find(|(_, c)| bad(c))
                .map(|(n, c)| format!("{n} is {}", crate::error::fmt_vec(c.to_array()))),
        }
    }

    /// Checks what a renderer relies on: a bitmap's size within [`MAX_TEXTURE_SIDE`] and its pixel count,
    /// every value a reflectance (finite, in [0, 1]), a finite `to_uv`.
    pub fn check(&self) -> Result<(), String> {
        self.check_as(false)
    }

    /// [`Texture::check`] for a texture of radiances (an area light's `radiance`, as Mitsuba reads it:
    /// unbounded): every value finite and at least 0 instead of a reflectance.
    pub fn check_radiance(&self) -> Result<(), String> {
        self.check_as(true)
    }

    fn check_as(&self, radiance: bool) -> Result<(), String> {
        if let Pattern::Bitmap { width, height, pixels } = &self.pattern {
            if !(1..=MAX_TEXTURE_SIDE).contains(width) || !(1..=MAX_TEXTURE_SIDE).contains(height) {
                return Err(format!(
                    "image of {width} x {height} pixels: each side must be in 1..={MAX_TEXTURE_SIDE}"
                ));
            }
            if pixels.len() as u64 != *width as u64 * *height as u64 {
                return Err(format!("{} pixels for {width} x {height}", pixels.len()));
            }
        }
        if radiance {
            let bad = |v: &Vec3| !(v.is_finite() && v.cmpge(Vec3::ZERO).all());
            let found = match &self.pattern {
                Pattern::Bitmap { pixels, .. } => pixels.iter().find(|p| bad(p)).copied(),
                Pattern::Checkerboard { color0, color1 } => [*color0, *color1].into_iter().find(bad),
            };
            if let Some(v) = found {
                return Err(format!(
                    "a value of {}: a radiance must be finite and at least 0",
                    crate::error::fmt_vec(v.to_array())
                ));
            }
        } else if let Some(bad) = self.out_of_range() {
            return Err(format!("{bad}: a reflectance must be finite and in [0, 1]"));
        }
        if !self.to_uv.iter().all(|x| x.is_finite()) {
            return Err(format!("to_uv {:?} is not finite", self.to_uv));
        }
        Ok(())
    }

    /// The texture with every channel above `most` lowered to it, and how many pixels (or colours)
    /// changed; `None` when none is above.
    pub fn lowered(&self, most: f32) -> Option<(Texture, usize)> {
        let cap = Vec3::splat(most);
        let mut out = self.clone();
        let changed = match &mut out.pattern {
            Pattern::Bitmap { pixels, .. } => pixels
                .iter_mut()
                .filter(|p| p.cmpgt(cap).any())
                .map(|p| *p = p.min(cap))
                .count(),
            Pattern::Checkerboard { color0, color1 } => [color0, color1]
                .into_iter()
                .filter(|c| c.cmpgt(cap).any())
                .map(|c| *c = c.min(cap))
                .count(),
        };
        (changed > 0).then_some((out, changed))
    }
}

/// The index of `texture` in `textures`, added when no equal one is there (the same image read twice,
/// for two materials, is stored once).
pub fn intern(textures: &mut Vec<Texture>, texture: std::borrow::Cow<'_, Texture>) -> u32 {
    let i = match textures.iter().position(|t| *t == *texture) {
        Some(i) => i,
        None => {
            textures.push(texture.into_owned());
            textures.len() - 1
        }
    };
    i as u32
}

/// Writes an 8-bit RGB PNG of `width` x `height` pixels (`rgb`: 3 bytes a pixel, top row first).
#[cfg(test)]
pub(crate) fn write_png(path: &Path, width: u32, height: u32, rgb: &[u8]) {
    image::RgbImage::from_raw(width, height, rgb.to_vec())
        .expect("3 bytes a pixel")
        .save(path)
        .expect("writing a test PNG");
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DAffine3, DMat3, DVec3, Vec2};

    #[test]
    fn to_uv_is_the_affine_map_of_u_v_0() {
        // Mitsuba: scale 2 then translate 0.5 in u: u' = 2 u + 0.5; the z column (here a shear into
        // z) drops out.
        let m = DAffine3::from_translation(DVec3::new(0.5, 0.25, 9.0))
            * DAffine3::from_mat3(DMat3::from_cols(
                DVec3::new(2.0, 0.0, 0.0),
                DVec3::new(0.0, 3.0, 0.0),
                DVec3::new(7.0, 8.0, 1.0),
            ));
        assert_eq!(uv_map_from_affine(&m), [2.0, 0.0, 0.5, 0.0, 3.0, 0.25]);
        // A quarter turn about z: (u, v) -> (-v, u).
        let r = DAffine3::from_rotation_z(std::f64::consts::FRAC_PI_2);
        let q = uv_map_from_affine(&r);
        let want = [0.0, -1.0, 0.0, 1.0, 0.0, 0.0];
        assert!(q.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-7), "{q:?}");
        // Composition: outer after inner.
        let flip_u = [-1.0, 0.0, 1.0, 0.0, 1.0, 0.0];
        let scale = [2.0, 0.0, 0.5, 0.0, 3.0, 0.25];
        assert_eq!(compose_uv(scale, flip_u), [-2.0, 0.0, 2.5, 0.0, 3.0, 0.25]);
        assert_eq!(compose_uv(IDENTITY_UV, scale), scale);
    }

    #[test]
    fn sphere_uv_matches_mitsuba() {
        // Mitsuba 3.9.1 (scalar_rgb), a ray hitting the unit sphere: the hit point and its si.uv.
        for (p, uv) in [
            (Vec3::X, Vec2::new(0.0, 0.5)),
            (Vec3::Y, Vec2::new(0.25, 0.5)),
            (Vec3::NEG_X, Vec2::new(0.5, 0.5)),
            (Vec3::NEG_Y, Vec2::new(0.75, 0.5)),
            (Vec3::new(0.3, 0.1, 0.948683), Vec2::new(0.0512, 0.1024)),
        ] {
            let got = sphere_uv(p * 2.5);
            assert!(got.distance(uv) < 1e-4, "{p}: {got} against Mitsuba's {uv}");
        }
    }

    #[test]
    fn values_are_checked_and_lowered() {
        let mut t = Texture {
            name: "t".into(),
            pattern: Pattern::Bitmap {
                width: 2,
                height: 2,
                pixels: vec![
                    Vec3::splat(0.1),
                    Vec3::splat(0.99),
                    Vec3::new(0.5, 0.96, 0.2),
                    Vec3::ZERO,
                ],
            },
            filter: Filter::Bilinear,
            wrap: Wrap::Repeat,
            to_uv: IDENTITY_UV,
        };
        assert_eq!(t.check(), Ok(()));
        assert_eq!((t.max(), t.min()), (Vec3::splat(0.99), Vec3::ZERO));
        let (low, n) = t.lowered(0.95).expect("two pixels above");
        assert_eq!((n, low.max()), (2, Vec3::splat(0.95)));
        assert!(t.lowered(0.99).is_none());
        if let Pattern::Bitmap { pixels, .. } = &mut t.pattern {
            pixels[3] = Vec3::new(0.0, f32::NAN, 0.0);
        }
        let e = t.check().unwrap_err();
        assert!(
            e.starts_with("pixel (1, 1) (column, row from the top) is [0, NaN, 0]"),
            "{e}"
        );
        if let Pattern::Bitmap { pixels, .. } = &mut t.pattern {
            pixels.pop();
        }
        assert_eq!(t.check().unwrap_err(), "3 pixels for 2 x 2");
        let c = Texture {
            pattern: Pattern::Checkerboard {
                color0: Vec3::splat(0.4),
                color1: Vec3::new(0.2, 1.5, 0.2),
            },
            ..t.clone()
        };
        assert!(c.check().unwrap_err().starts_with("color1 is [0.2, 1.5, 0.2]"));
        let mut textures = vec![c.clone()];
        assert_eq!(intern(&mut textures, std::borrow::Cow::Borrowed(&c)), 0);
        assert_eq!(intern(&mut textures, std::borrow::Cow::Owned(t)), 1);
        assert_eq!(textures.len(), 2);
    }

    #[test]
    fn images_are_read_top_row_first_and_decoded() {
        let dir = crate::TempDir::new("texture-read");
        let path = dir.0.join("a.png");
        // 2 x 1: a red pixel then a grey one of code 188.
        write_png(&path, 2, 1, &[255, 0, 0, 188, 188, 188]);
        let (w, h, px) = read_image(&path, false).unwrap();
        assert_eq!((w, h), (2, 1));
        assert_eq!(px[0], Vec3::X);
        assert!((px[1].x - srgb_to_linear(188.0 / 255.0)).abs() < 1e-6);
        let (_, _, raw) = read_image(&path, true).unwrap();
        assert!((raw[1].x - 188.0 / 255.0).abs() < 1e-6);
    }

    /// The same 8-bit pixels as TGA, BMP and PPM read as the PNG does (sRGB-decoded, or raw), and a
    /// Radiance HDR as the linear floats written (within RGBE's precision: 8 bits of mantissa).
    #[test]
    fn tga_bmp_ppm_read_as_png_and_hdr_as_linear() {
        let dir = crate::TempDir::new("texture-formats");
        let rgb = [255u8, 0, 0, 188, 188, 188, 10, 120, 250, 0, 0, 0];
        write_png(&dir.0.join("a.png"), 2, 2, &rgb);
        let image = image::RgbImage::from_raw(2, 2, rgb.to_vec()).unwrap();
        for raw in [false, true] {
            let png = read_image(&dir.0.join("a.png"), raw).unwrap();
            for name in ["a.tga", "a.bmp", "a.ppm"] {
                image.save(dir.0.join(name)).unwrap();
                assert_eq!(read_image(&dir.0.join(name), raw).unwrap(), png, "{name} raw {raw}");
            }
        }
        let floats = [2.5f32, 0.0, 0.125, 0.3, 0.3, 0.3, 7.0, 1.0, 0.01, 0.0, 0.0, 0.0];
        image::Rgb32FImage::from_raw(2, 2, floats.to_vec())
            .unwrap()
            .save(dir.0.join("a.hdr"))
            .unwrap();
        let (w, h, px) = read_image(&dir.0.join("a.hdr"), false).unwrap();
        assert_eq!((w, h), (2, 2));
        for (p, want) in px.iter().zip(floats.chunks_exact(3)) {
            let want = Vec3::from_slice(want);
            assert!(
                (*p - want).abs().max_element() <= want.max_element() / 128.0,
                "{p} vs {want}"
            );
        }
    }
}
