//! Linear-RGB float images: EXR/PNG input and output and the few pixel operations the reports need.

use std::fs::{self, File};
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use anyhow::{bail, ensure, Context, Result};
use image::{DynamicImage, ImageBuffer, ImageFormat, ImageReader, Rgb};

/// A linear-RGB float image, row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 3]>,
}

impl RgbImage {
    /// A black image.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            pixels: vec![[0.0; 3]; pixel_count(width, height)],
        }
    }

    /// Drops alpha (the GPU's RGBA32F accumulation buffers carry an unused fourth channel).
    pub fn from_rgba(width: u32, height: u32, rgba: &[[f32; 4]]) -> Result<Self> {
        let expected = pixel_count(width, height);
        ensure!(
            rgba.len() == expected,
            "RGBA buffer has {} pixels but a {width}x{height} image needs {expected}",
            rgba.len()
        );
        let pixels = rgba.iter().map(|&[r, g, b, _]| [r, g, b]).collect();
        Ok(Self { width, height, pixels })
    }

    /// The pixel at column `x`, row `y` (row 0 at the top). Panics when out of bounds, like indexing.
    pub fn get(&self, x: u32, y: u32) -> [f32; 3] {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) outside a {}x{} image",
            self.width,
            self.height
        );
        self.pixels[self.index(x, y)]
    }

    /// Mean of each channel, accumulated in f64 (f32 sums drift visibly over a megapixel).
    /// NaN for an empty image.
    pub fn mean(&self) -> [f64; 3] {
        let mut sum = [0.0f64; 3];
        for p in &self.pixels {
            for c in 0..3 {
                sum[c] += f64::from(p[c]);
            }
        }
        let n = self.pixels.len() as f64;
        sum.map(|s| s / n)
    }

    /// Number of NaN or infinite components.
    pub fn count_non_finite(&self) -> usize {
        self.pixels.iter().flatten().filter(|v| !v.is_finite()).count()
    }

    /// Average of each `k` x `k` block: for box-filtered pixels this is exactly the box-filtered image at
    /// 1/k the resolution.
    pub fn downsample(&self, k: u32) -> Result<Self> {
        ensure!(
            // `checked_rem` also rejects k = 0 (and `is_multiple_of` is newer than our MSRV).
            self.width.checked_rem(k) == Some(0) && self.height.checked_rem(k) == Some(0),
            "cannot downsample a {}x{} image by {k}: the factor must divide both sizes",
            self.width,
            self.height
        );
        if k == 1 {
            return Ok(self.clone());
        }
        let (w, h) = (self.width / k, self.height / k);
        let inv = 1.0 / f64::from(k * k);
        let mut out = Self::new(w, h);
        for by in 0..h {
            for bx in 0..w {
                let mut sum = [0.0f64; 3];
                for y in by * k..(by + 1) * k {
                    let row = self.index(bx * k, y);
                    for p in &self.pixels[row..row + k as usize] {
                        for c in 0..3 {
                            sum[c] += f64::from(p[c]);
                        }
                    }
                }
                let i = out.index(bx, by);
                out.pixels[i] = sum.map(|s| (s * inv) as f32);
            }
        }
        Ok(out)
    }

    /// Each pixel repeated k x k times (nearest neighbour), for figures of small crops.
    pub fn upscale(&self, k: u32) -> Result<Self> {
        if k == 0 {
            bail!("upscale factor must be at least 1");
        }
        let (w, h) = (self.width * k, self.height * k);
        let pixels = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x / k, y / k)))
            .map(|(x, y)| self.get(x, y))
            .collect();
        Ok(RgbImage {
            width: w,
            height: h,
            pixels,
        })
    }

    /// The `w` x `h` rectangle whose top-left pixel is (`x0`, `y0`).
    pub fn crop(&self, x0: u32, y0: u32, w: u32, h: u32) -> Result<Self> {
        // u64 so that huge requests fail the bounds check instead of overflowing.
        let fits = u64::from(x0) + u64::from(w) <= u64::from(self.width)
            && u64::from(y0) + u64::from(h) <= u64::from(self.height);
        ensure!(
            w > 0 && h > 0 && fits,
            "crop {w}x{h} at ({x0}, {y0}) is empty or outside the {}x{} image",
            self.width,
            self.height
        );
        let mut pixels = Vec::with_capacity(pixel_count(w, h));
        for y in y0..y0 + h {
            let row = self.index(x0, y);
            pixels.extend_from_slice(&self.pixels[row..row + w as usize]);
        }
        Ok(Self {
            width: w,
            height: h,
            pixels,
        })
    }

    /// The images side by side, left to right (figure crops); they must share a height.
    pub fn hstack(images: &[&RgbImage]) -> Result<Self> {
        let Some(first) = images.first() else {
            bail!("hstack needs at least one image");
        };
        let height = first.height;
        let mut width = 0u32;
        for (i, img) in images.iter().enumerate() {
            ensure!(
                img.height == height,
                "hstack: image {i} is {}x{} but image 0 is {}x{}; heights must match",
                img.width,
                img.height,
                first.width,
                first.height
            );
            width = width
                .checked_add(img.width)
                .context("hstack: total width overflows u32")?;
        }
        let mut pixels = Vec::with_capacity(pixel_count(width, height));
        for y in 0..height {
            for img in images {
                let row = img.index(0, y);
                pixels.extend_from_slice(&img.pixels[row..row + img.width as usize]);
            }
        }
        Ok(Self { width, height, pixels })
    }

    /// Any EXR the `image` crate reads (RGB or RGBA, f32 or f16); alpha is dropped.
    /// A file that cannot be opened or decoded is [`crate::Error::Io`].
    pub fn load_exr(path: impl AsRef<Path>) -> crate::Result<Self> {
        let path = path.as_ref();
        // A regular file only, opened without blocking (a FIFO as --reference would wait for ever).
        let (file, _) = crate::scene::open_bounded(path, crate::scene::MAX_IMAGE_BYTES, "EXR image")?;
        Self::load_exr_inner(file).map_err(|e| crate::Error::decode(path, format!("{e:#}")))
    }

    fn load_exr_inner(file: std::fs::File) -> Result<Self> {
        // Decode as EXR whatever the file is called, so a misnamed file fails with a decoder error.
        let reader = ImageReader::with_format(std::io::BufReader::new(file), ImageFormat::OpenExr);
        let rgb = match reader.decode()? {
            DynamicImage::ImageRgb32F(buf) => buf,
            // Direct conversions keep the colour values untouched (no premultiplication).
            other => other.into_rgb32f(),
        };
        let (width, height) = rgb.dimensions();
        let pixels = rgb.into_raw().chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        Ok(Self { width, height, pixels })
    }

    /// Linear float32 RGB OpenEXR, written atomically.
    pub fn save_exr(&self, path: impl AsRef<Path>) -> crate::Result<()> {
        let path = path.as_ref();
        self.save_exr_inner(path).map_err(|e| write_error(path, e))
    }

    fn save_exr_inner(&self, path: &Path) -> Result<()> {
        let raw: Vec<f32> = self.pixels.iter().flatten().copied().collect();
        let buf = ImageBuffer::<Rgb<f32>, _>::from_raw(self.width, self.height, raw)
            .context("pixel buffer does not match the image size")
            .with_context(|| format!("writing {}", path.display()))?;
        write_atomically(path, "exr", |w| Ok(buf.write_to(w, ImageFormat::OpenExr)?))
    }

    /// Tone-mapped 8-bit sRGB PNG: scale by 2^`exposure`, clamp to [0, 1], sRGB OETF; NaN becomes black.
    pub fn save_png(&self, path: impl AsRef<Path>, exposure: f32) -> crate::Result<()> {
        let path = path.as_ref();
        self.save_png_inner(path, exposure).map_err(|e| write_error(path, e))
    }

    fn save_png_inner(&self, path: &Path, exposure: f32) -> Result<()> {
        let buf = self
            .tonemapped(exposure)
            .with_context(|| format!("writing {}", path.display()))?;
        write_atomically(path, "png", |w| Ok(buf.write_to(w, ImageFormat::Png)?))
    }

    /// The PNG [`RgbImage::save_png`] writes, in memory (for a notebook's inline image); a non-finite
    /// exposure is [`crate::Error::Settings`].
    pub fn encode_png(&self, exposure: f32) -> crate::Result<Vec<u8>> {
        if !exposure.is_finite() {
            let message = format!("must be finite, got {exposure}");
            return Err(crate::Error::Settings {
                field: "exposure",
                message,
            });
        }
        let mut out = std::io::Cursor::new(Vec::new());
        self.tonemapped(exposure)
            .and_then(|buf| Ok(buf.write_to(&mut out, ImageFormat::Png)?))
            .map_err(|e| crate::Error::io("PNG in memory", std::io::Error::other(format!("{e:#}"))))?;
        Ok(out.into_inner())
    }

    /// Scaled by 2^`exposure`, clamped to [0, 1], sRGB-encoded to 8 bits; NaN becomes black.
    fn tonemapped(&self, exposure: f32) -> Result<ImageBuffer<Rgb<u8>, Vec<u8>>> {
        ensure!(exposure.is_finite(), "exposure must be finite, got {exposure}");
        let scale = exposure.exp2();
        let raw: Vec<u8> = self
            .pixels
            .iter()
            .flatten()
            .map(|&v| srgb_encode_u8(v * scale))
            .collect();
        ImageBuffer::<Rgb<u8>, _>::from_raw(self.width, self.height, raw)
            .context("pixel buffer does not match the image size")
    }

    /// Chooses the format by extension: `.exr` (linear float) or `.png` (sRGB, exposure 0).
    pub fn save(&self, path: impl AsRef<Path>) -> crate::Result<()> {
        let path = path.as_ref();
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("exr") => self.save_exr(path),
            Some("png") => self.save_png(path, 0.0),
            _ => Err(crate::Error::io(
                path,
                std::io::Error::new(
                    std::io::ErrorKind::InvalidInput,
                    "unsupported extension (supported: .exr, .png)",
                ),
            )),
        }
    }

    fn index(&self, x: u32, y: u32) -> usize {
        y as usize * self.width as usize + x as usize
    }
}

/// A failed write as [`crate::Error::Io`]: the kind of the io error in the chain (if any) and the
/// whole chain as its message (which step failed: creating, encoding, renaming).
pub(crate) fn write_error(path: &Path, e: anyhow::Error) -> crate::Error {
    let kind = e
        .chain()
        .find_map(|c| c.downcast_ref::<std::io::Error>())
        .map_or(std::io::ErrorKind::Other, |io| io.kind());
    crate::Error::io(path, std::io::Error::new(kind, format!("{e:#}")))
}

fn pixel_count(width: u32, height: u32) -> usize {
    width as usize * height as usize
}

/// The sRGB OETF (IEC 61966-2-1, piecewise) of a linear value, quantised to 8 bits.
pub(crate) fn srgb_encode_u8(linear: f32) -> u8 {
    // `clamp` passes NaN through, so map it to black first.
    let v = if linear.is_nan() { 0.0 } else { linear.clamp(0.0, 1.0) };
    let encoded = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (encoded * 255.0).round().clamp(0.0, 255.0) as u8
}

/// Writes through a sibling temporary file (`name.tmp.<ext>`) and renames it over `path`, so a reader
/// or an interrupted render never sees a truncated image.
pub(crate) fn write_atomically(
    path: &Path,
    ext: &str,
    write: impl FnOnce(&mut BufWriter<File>) -> Result<()>,
) -> Result<()> {
    let tmp: PathBuf = path.with_extension(format!("tmp.{ext}"));
    let result = (|| -> Result<()> {
        let mut w = BufWriter::new(File::create(&tmp).with_context(|| format!("creating {}", tmp.display()))?);
        write(&mut w)?;
        let file = w.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        fs::rename(&tmp, path).with_context(|| format!("renaming {} into place", tmp.display()))
    })();
    if result.is_err() {
        // Best effort: the original error is the one worth reporting.
        let _ = fs::remove_file(&tmp);
    }
    result.with_context(|| format!("writing {}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("ppm-vk-image-io-{}-{name}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn ramp(width: u32, height: u32) -> RgbImage {
        let pixels = (0..width * height)
            .map(|i| {
                let i = i as f32;
                [i, 0.5 * i + 1.0, -0.25 * i]
            })
            .collect();
        RgbImage { width, height, pixels }
    }

    #[test]
    fn from_rgba_drops_alpha_and_checks_size() {
        let img = RgbImage::from_rgba(2, 1, &[[1.0, 2.0, 3.0, 9.0], [4.0, 5.0, 6.0, 9.0]]).unwrap();
        assert_eq!(img.pixels, vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
        let err = RgbImage::from_rgba(2, 2, &[[0.0; 4]; 3]).unwrap_err().to_string();
        assert!(err.contains("3 pixels") && err.contains("2x2"), "{err}");
    }

    #[test]
    fn get_is_row_major_top_first() {
        let img = ramp(3, 2);
        assert_eq!(img.get(0, 0)[0], 0.0);
        assert_eq!(img.get(2, 0)[0], 2.0);
        assert_eq!(img.get(1, 1)[0], 4.0);
    }

    #[test]
    fn mean_and_non_finite() {
        let mut img = ramp(2, 2); // red 0,1,2,3; green 1,1.5,2,2.5; blue 0,-0.25,-0.5,-0.75
        assert_eq!(img.mean(), [1.5, 1.75, -0.375]);
        assert_eq!(img.count_non_finite(), 0);
        img.pixels[1] = [f32::NAN, f32::INFINITY, 0.0];
        img.pixels[3][2] = f32::NEG_INFINITY;
        assert_eq!(img.count_non_finite(), 3);
    }

    #[test]
    fn downsample_averages_blocks_exactly() {
        // 4x2 image, k = 2: block 0 holds red 0,1,4,5 -> 2.5; block 1 holds 2,3,6,7 -> 4.5.
        let img = ramp(4, 2);
        let half = img.downsample(2).unwrap();
        assert_eq!((half.width, half.height), (2, 1));
        assert_eq!(half.pixels[0], [2.5, 2.25, -0.625]);
        assert_eq!(half.pixels[1], [4.5, 3.25, -1.125]);
        // Averaging k x k blocks twice equals averaging (2k) x (2k) blocks once (dyadic values: exact).
        let big = ramp(8, 8);
        assert_eq!(
            big.downsample(2).unwrap().downsample(2).unwrap(),
            big.downsample(4).unwrap()
        );
        // A constant image stays exactly constant.
        let c = RgbImage {
            width: 6,
            height: 6,
            pixels: vec![[0.1, 0.2, 0.3]; 36],
        };
        assert_eq!(c.downsample(3).unwrap().pixels, vec![[0.1, 0.2, 0.3]; 4]);
        assert_eq!(img.downsample(1).unwrap(), img);
        assert!(img.downsample(3).is_err());
        assert!(img.downsample(0).is_err());
    }

    #[test]
    fn crop_and_hstack() {
        let img = ramp(4, 3);
        let c = img.crop(1, 1, 2, 2).unwrap();
        assert_eq!((c.width, c.height), (2, 2));
        assert_eq!(
            c.pixels.iter().map(|p| p[0]).collect::<Vec<_>>(),
            vec![5.0, 6.0, 9.0, 10.0]
        );
        assert!(img.crop(3, 0, 2, 1).is_err());
        assert!(img.crop(0, 0, 0, 1).is_err());
        assert!(img.crop(u32::MAX, 0, 2, 1).is_err());

        let s = RgbImage::hstack(&[&c, &img.crop(0, 0, 1, 2).unwrap()]).unwrap();
        assert_eq!((s.width, s.height), (3, 2));
        assert_eq!(
            s.pixels.iter().map(|p| p[0]).collect::<Vec<_>>(),
            vec![5.0, 6.0, 0.0, 9.0, 10.0, 4.0]
        );
        let err = RgbImage::hstack(&[&c, &img]).unwrap_err().to_string();
        assert!(err.contains("heights"), "{err}");
        assert!(RgbImage::hstack(&[]).is_err());
    }

    #[test]
    fn exr_round_trip_is_bit_exact() {
        let dir = scratch_dir("exr");
        let path = dir.join("round.exr");
        let mut img = RgbImage::new(5, 3);
        for (i, p) in img.pixels.iter_mut().enumerate() {
            let i = i as f32;
            // Values that f16 or a lossy path would not keep.
            *p = [i * 0.1 + 1e-7, 1.0 / (i + 3.0), -(i * 12345.678)];
        }
        img.pixels[4] = [f32::MAX, f32::MIN_POSITIVE, 34.0];
        img.save_exr(&path).unwrap();
        let back = RgbImage::load_exr(&path).unwrap();
        assert_eq!((back.width, back.height), (5, 3));
        let bits = |im: &RgbImage| im.pixels.iter().flatten().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&back), bits(&img));
        // No temporary file is left beside it.
        assert!(!path.with_extension("tmp.exr").exists());
        // save() picks EXR by extension, case-insensitively.
        let upper = dir.join("upper.EXR");
        img.save(&upper).unwrap();
        assert_eq!(RgbImage::load_exr(&upper).unwrap(), img);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn load_errors_name_the_path() {
        let dir = scratch_dir("missing");
        let path = dir.join("does-not-exist.exr");
        let err = format!("{:#}", RgbImage::load_exr(&path).unwrap_err());
        assert!(err.contains("does-not-exist.exr"), "{err}");
        // A PNG is not an EXR, whatever it is called.
        let fake = dir.join("fake.exr");
        RgbImage::new(2, 2).save_png(dir.join("real.png"), 0.0).unwrap();
        fs::rename(dir.join("real.png"), &fake).unwrap();
        let err = format!("{:#}", RgbImage::load_exr(&fake).unwrap_err());
        assert!(err.contains("fake.exr"), "{err}");
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn srgb_oetf_values() {
        assert_eq!(srgb_encode_u8(0.0), 0);
        // 1.055 * 0.5^(1/2.4) - 0.055 = 0.7354 -> 187.5 -> 188 (gamma 2.2 would give 186).
        assert_eq!(srgb_encode_u8(0.5), 188);
        assert_eq!(srgb_encode_u8(1.0), 255);
        // The branches meet at 0.0031308: 12.92 * 0.0031308 = 0.04045 -> 10.31 -> 10 on either side.
        assert_eq!(srgb_encode_u8(0.003_130_8), 10);
        assert_eq!(srgb_encode_u8(0.003_130_7), 10);
        assert_eq!(srgb_encode_u8(0.003_131), 10);
        // Linear segment: 12.92 * 0.001 * 255 = 3.29 -> 3.
        assert_eq!(srgb_encode_u8(0.001), 3);
        assert_eq!(srgb_encode_u8(f32::NAN), 0);
        assert_eq!(srgb_encode_u8(-1.0), 0);
        assert_eq!(srgb_encode_u8(34.0), 255);
        assert_eq!(srgb_encode_u8(f32::INFINITY), 255);
    }

    #[test]
    fn png_is_tone_mapped_srgb() {
        let dir = scratch_dir("png");
        let path = dir.join("tone.png");
        let img = RgbImage {
            width: 3,
            height: 1,
            pixels: vec![
                [0.5, 1.0, 0.0],
                [0.25, f32::NAN, 2.0],
                [0.003_130_8, -1.0, f32::INFINITY],
            ],
        };
        img.save(&path).unwrap();
        let png = image::open(&path).unwrap().into_rgb8();
        assert_eq!(png.dimensions(), (3, 1));
        assert_eq!(png.as_raw().as_slice(), &[188, 255, 0, 137, 0, 255, 10, 0, 255]);
        // Exposure +1 doubles: 0.25 -> 0.5 -> 188.
        img.save_png(&path, 1.0).unwrap();
        let png = image::open(&path).unwrap().into_rgb8();
        assert_eq!(png.get_pixel(1, 0).0[0], 188);
        // In memory, the same file byte for byte.
        assert_eq!(img.encode_png(1.0).unwrap(), fs::read(&path).unwrap());
        assert!(matches!(
            img.encode_png(f32::NAN),
            Err(crate::Error::Settings { field: "exposure", .. })
        ));
        assert!(img.save_png(&path, f32::NAN).is_err());
        assert!(!path.with_extension("tmp.png").exists());
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn save_rejects_unknown_extensions() {
        let img = RgbImage::new(1, 1);
        for name in ["out.jpg", "out"] {
            let err = img.save(Path::new(name)).unwrap_err().to_string();
            assert!(
                err.contains(name) && err.contains(".exr") && err.contains(".png"),
                "{err}"
            );
        }
    }

    #[test]
    fn write_errors_name_the_path() {
        let path = Path::new("/nonexistent-dir-for-ppm-vk/out.exr");
        let err = format!("{:#}", RgbImage::new(1, 1).save(path).unwrap_err());
        assert!(err.contains("writing /nonexistent-dir-for-ppm-vk/out.exr"), "{err}");
    }
}
