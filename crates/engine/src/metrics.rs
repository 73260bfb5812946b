//! Error against a reference image, for the "speed against error" reports.

use std::path::{Path, PathBuf};

use anyhow::{bail, ensure, Context, Result};

use crate::image_io::RgbImage;

/// Added to ref^2 in relMSE's denominator so that black pixels do not dominate.
const REL_EPSILON: f64 = 0.01;

#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ErrorStats {
    pub rmse: f64,
    pub rel_mse: f64,
    pub mean_bias: f64,
    /// Pixels compared (each contributes three channels).
    pub pixels: u64,
}

/// A named rectangle of pixels: the scene crate's, where scene files name their regions.
pub use ppm_vk_scene::Region;

pub struct Reference {
    pub image: RgbImage,
    /// Per-pixel variance of the reference's mean (its own noise), when known.
    pub variance: Option<RgbImage>,
}

impl Reference {
    /// Loads `X.exr` and, if it exists beside it, `X_var.exr`.
    pub fn load(path: &Path) -> Result<Self> {
        let image = RgbImage::load_exr(path)?;
        let bad = image.count_non_finite();
        ensure!(
            bad == 0,
            "reference {} has {bad} non-finite pixel components",
            path.display()
        );
        let var_path = variance_path(path);
        let variance = if var_path.exists() {
            let var = RgbImage::load_exr(&var_path)?;
            ensure!(
                (var.width, var.height) == (image.width, image.height),
                "variance {} is {}x{} but reference {} is {}x{}",
                var_path.display(),
                var.width,
                var.height,
                path.display(),
                image.width,
                image.height
            );
            let bad = var
                .pixels
                .iter()
                .flatten()
                .filter(|v| !(v.is_finite() && **v >= 0.0))
                .count();
            ensure!(
                bad == 0,
                "variance {} has {bad} negative or non-finite components",
                var_path.display()
            );
            Some(var)
        } else {
            None
        };
        Ok(Self { image, variance })
    }

    /// The reference block-averaged down to `w` x `h` (exact for its box pixel filter). The variance of a
    /// mean of k^2 independent pixels is the mean of their variances / k^2.
    pub fn at_resolution(&self, w: u32, h: u32) -> Result<Reference> {
        let k = self.scale_factor(w, h)?;
        let image = self.image.downsample(k)?;
        let variance = match &self.variance {
            Some(var) => {
                let mut v = var.downsample(k)?;
                let inv = 1.0 / (f64::from(k) * f64::from(k));
                for p in &mut v.pixels {
                    *p = p.map(|c| (f64::from(c) * inv) as f32);
                }
                Some(v)
            }
            None => None,
        };
        Ok(Reference { image, variance })
    }

    /// The integer factor k with the reference's size = k * (`w`, `h`).
    fn scale_factor(&self, w: u32, h: u32) -> Result<u32> {
        let (rw, rh) = (self.image.width, self.image.height);
        let divides = rw.checked_rem(w) == Some(0) && rh.checked_rem(h) == Some(0);
        let k = if divides && rw / w == rh / h {
            Some(rw / w)
        } else {
            None
        };
        k.with_context(|| format!("{w}x{h} is not the {rw}x{rh} reference reduced by an integer factor"))
    }
}

/// `X.exr` -> `X_var.exr`.
fn variance_path(path: &Path) -> PathBuf {
    let stem = path.file_stem().unwrap_or_default().to_string_lossy();
    let name = match path.extension() {
        Some(ext) => format!("{stem}_var.{}", ext.to_string_lossy()),
        None => format!("{stem}_var"),
    };
    path.with_file_name(name)
}

/// Error of `image` against `reference` over the whole image (`region` None) or a region.
///
/// `reference` is the full-resolution one; an image smaller by an integer factor k is scored against the
/// reference block-averaged by k, and the region (full-resolution coordinates) is shrunk to the smallest
/// box of k x k blocks that covers it.
///
/// RMSE = sqrt(mean over pixels and RGB of (x - ref)^2); relMSE = mean((x - ref)^2 / (ref^2 + 0.01));
/// mean_bias = mean(x - ref). With `remove_reference_noise` and a variance image, the mean reference
/// variance is subtracted from the MSE (clamped at 0) and mean(var / (ref^2 + 0.01)) from relMSE, since
/// E[(x - ref)^2] = E[(x - truth)^2] + var_ref for independent images. Without a variance image the flag
/// has no effect.
pub fn compare(
    image: &RgbImage,
    reference: &Reference,
    region: Option<&Region>,
    remove_reference_noise: bool,
) -> Result<ErrorStats> {
    let (rw, rh) = (reference.image.width, reference.image.height);
    let k = reference.scale_factor(image.width, image.height).with_context(|| {
        format!(
            "image size {}x{} does not match reference size {rw}x{rh}",
            image.width, image.height
        )
    })?;
    let bad = image.count_non_finite();
    ensure!(bad == 0, "image has {bad} non-finite pixels");
    if let Some(var) = &reference.variance {
        // `Reference` has public fields, so this one may not have come through `load`.
        ensure!(
            (var.width, var.height) == (rw, rh),
            "reference variance is {}x{} but the reference is {rw}x{rh}",
            var.width,
            var.height
        );
    }

    let scaled;
    let reference = if k == 1 {
        reference
    } else {
        scaled = reference.at_resolution(image.width, image.height)?;
        &scaled
    };

    // The box to score, in the image's pixels: [x0, x1) x [y0, y1).
    let (x0, y0, x1, y1) = match region {
        None => (0, 0, image.width, image.height),
        Some(r) => {
            let (end_x, end_y) = (u64::from(r.x0) + u64::from(r.w), u64::from(r.y0) + u64::from(r.h));
            if r.w == 0 || r.h == 0 || end_x > u64::from(rw) || end_y > u64::from(rh) {
                bail!(
                    "region {:?} ({}x{} at ({}, {})) is empty or outside the {rw}x{rh} reference",
                    r.name,
                    r.w,
                    r.h,
                    r.x0,
                    r.y0
                );
            }
            // end_* <= the reference's u32 size, so these fit.
            (
                r.x0 / k,
                r.y0 / k,
                (end_x as u32).div_ceil(k),
                (end_y as u32).div_ceil(k),
            )
        }
    };

    let variance = reference.variance.as_ref().filter(|_| remove_reference_noise);
    let (mut sq, mut rel, mut bias, mut var_sum, mut var_rel) = (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for y in y0..y1 {
        for x in x0..x1 {
            let p = image.get(x, y);
            let r = reference.image.get(x, y);
            let v = variance.map(|v| v.get(x, y));
            for c in 0..3 {
                let rc = f64::from(r[c]);
                let d = f64::from(p[c]) - rc;
                let denom = rc * rc + REL_EPSILON;
                sq += d * d;
                rel += d * d / denom;
                bias += d;
                if let Some(v) = v {
                    var_sum += f64::from(v[c]);
                    var_rel += f64::from(v[c]) / denom;
                }
            }
        }
    }
    let pixels = u64::from(x1 - x0) * u64::from(y1 - y0);
    let n = 3.0 * pixels as f64;
    let mse = (sq - var_sum).max(0.0) / n;
    Ok(ErrorStats {
        rmse: mse.sqrt(),
        rel_mse: (rel - var_rel).max(0.0) / n,
        mean_bias: bias / n,
        pixels,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn img(width: u32, height: u32, pixels: &[[f32; 3]]) -> RgbImage {
        RgbImage {
            width,
            height,
            pixels: pixels.to_vec(),
        }
    }

    fn reference(image: RgbImage, variance: Option<RgbImage>) -> Reference {
        Reference { image, variance }
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * b.abs().max(1.0)
    }

    fn assert_stats(s: ErrorStats, rmse: f64, rel_mse: f64, mean_bias: f64, pixels: u64) {
        assert!(close(s.rmse, rmse), "rmse {} != {rmse}", s.rmse);
        assert!(close(s.rel_mse, rel_mse), "rel_mse {} != {rel_mse}", s.rel_mse);
        assert!(
            close(s.mean_bias, mean_bias),
            "mean_bias {} != {mean_bias}",
            s.mean_bias
        );
        assert_eq!(s.pixels, pixels);
    }

    #[test]
    fn hand_computed_2x2() {
        // Reference: every channel 1 except pixel 3 which is 0 in every channel.
        // Image: pixel 0 = 1.5 (d = +0.5), pixel 1 = 1 (d = 0), pixel 2 = 0 (d = -1), pixel 3 = 0.1 (d = +0.1),
        // the same in all three channels, so per-channel means equal per-pixel means (n = 12, 3 per pixel).
        // Sum d^2 over pixels = 0.25 + 0 + 1 + 0.01 = 1.26  -> MSE = 1.26 / 4 = 0.315, RMSE = sqrt(0.315).
        // relMSE terms: 0.25/1.01, 0, 1/1.01, 0.01/0.01 = 1 -> (1.25/1.01 + 1) / 4.
        // bias = (0.5 + 0 - 1 + 0.1) / 4 = -0.1.
        let r = img(2, 2, &[[1.0; 3], [1.0; 3], [1.0; 3], [0.0; 3]]);
        let x = img(2, 2, &[[1.5; 3], [1.0; 3], [0.0; 3], [0.1; 3]]);
        let s = compare(&x, &reference(r.clone(), None), None, false).unwrap();
        // f32 0.1 is not 0.1: use its exact value in the expected numbers.
        let t = f64::from(0.1f32);
        assert_stats(
            s,
            ((0.25 + 1.0 + t * t) / 4.0f64).sqrt(),
            (1.25 / 1.01 + t * t / 0.01) / 4.0,
            (0.5 - 1.0 + t) / 4.0,
            4,
        );
        // Identical images score zero.
        assert_stats(
            compare(&r, &reference(r.clone(), None), None, false).unwrap(),
            0.0,
            0.0,
            0.0,
            4,
        );
    }

    #[test]
    fn hand_computed_per_channel() {
        // 1x1, reference (0, 1, 2), image (1, 1, 0): d = (1, 0, -2).
        // MSE = (1 + 0 + 4) / 3 = 5/3; relMSE = (1/0.01 + 0 + 4/4.01) / 3; bias = (1 + 0 - 2) / 3 = -1/3.
        let s = compare(
            &img(1, 1, &[[1.0, 1.0, 0.0]]),
            &reference(img(1, 1, &[[0.0, 1.0, 2.0]]), None),
            None,
            false,
        )
        .unwrap();
        assert_stats(s, (5.0f64 / 3.0).sqrt(), (100.0 + 4.0 / 4.01) / 3.0, -1.0 / 3.0, 1);
    }

    #[test]
    fn reference_noise_removal() {
        // 1x2, reference all 1 (so ref^2 + 0.01 = 1.01), image all 2 (d = 1 everywhere):
        // MSE = 1, relMSE = 1/1.01. Variance 0.25 everywhere: MSE - 0.25 = 0.75, relMSE - 0.25/1.01 = 0.75/1.01.
        let r = img(2, 1, &[[1.0; 3]; 2]);
        let x = img(2, 1, &[[2.0; 3]; 2]);
        let var = img(2, 1, &[[0.25; 3]; 2]);
        let refr = reference(r.clone(), Some(var));
        assert_stats(compare(&x, &refr, None, false).unwrap(), 1.0, 1.0 / 1.01, 1.0, 2);
        assert_stats(
            compare(&x, &refr, None, true).unwrap(),
            0.75f64.sqrt(),
            0.75 / 1.01,
            1.0,
            2,
        );
        // Comparing the reference with itself would go negative: clamped at zero.
        assert_stats(compare(&r, &refr, None, true).unwrap(), 0.0, 0.0, 0.0, 2);
        // No variance image: the flag changes nothing.
        let plain = reference(r, None);
        assert_eq!(
            compare(&x, &plain, None, true).unwrap(),
            compare(&x, &plain, None, false).unwrap()
        );
    }

    #[test]
    fn regions_and_lower_resolutions() {
        // 4x4 reference with red = column index x, green = row y, blue = 0; image all zero.
        let pixels: Vec<[f32; 3]> = (0..16).map(|i| [(i % 4) as f32, (i / 4) as f32, 0.0]).collect();
        let refr = reference(img(4, 4, &pixels), Some(img(4, 4, &[[0.5; 3]; 16])));
        let zero4 = RgbImage::new(4, 4);
        // Region x 2-3, y 0: pixels (2,0,0) and (3,0,0). d^2 sum = 4 + 9 = 13 over n = 6.
        let region = Region::new("r", 2, 0, 2, 1);
        let s = compare(&zero4, &refr, Some(&region), false).unwrap();
        assert_stats(
            s,
            (13.0f64 / 6.0).sqrt(),
            (4.0 / 4.01 + 9.0 / 9.01) / 6.0,
            -5.0 / 6.0,
            2,
        );

        // At half resolution the reference is [[0.5, 0.5], [2.5, 0.5]], [[0.5, 2.5], [2.5, 2.5]] (red, green)
        // and the variance 0.5 / 4 = 0.125. The region maps to block (1, 0): reference (2.5, 0.5, 0).
        let half = refr.at_resolution(2, 2).unwrap();
        assert_eq!(
            half.image.pixels,
            vec![[0.5, 0.5, 0.0], [2.5, 0.5, 0.0], [0.5, 2.5, 0.0], [2.5, 2.5, 0.0]]
        );
        assert_eq!(half.variance.as_ref().unwrap().pixels, vec![[0.125; 3]; 4]);
        let zero2 = RgbImage::new(2, 2);
        let s = compare(&zero2, &refr, Some(&region), false).unwrap();
        // d^2 = 6.25 + 0.25 + 0 = 6.5 over n = 3; rel = 6.25/6.26 + 0.25/0.26 + 0.
        assert_stats(s, (6.5f64 / 3.0).sqrt(), (6.25 / 6.26 + 0.25 / 0.26) / 3.0, -1.0, 1);
        // With noise removal: minus 0.125 per channel -> (6.5 - 0.375) / 3.
        let s = compare(&zero2, &refr, Some(&region), true).unwrap();
        assert!(close(s.rmse, (6.125f64 / 3.0).sqrt()), "{s:?}");
        // A region not on the block grid grows to the blocks covering it: x 1-2 -> blocks 0-1.
        let s = compare(&zero2, &refr, Some(&Region::new("odd", 1, 0, 2, 1)), false).unwrap();
        assert_eq!(s.pixels, 2);
    }

    #[test]
    fn errors() {
        let refr = reference(RgbImage::new(4, 4), None);
        let err = compare(&RgbImage::new(3, 4), &refr, None, false).unwrap_err();
        let msg = format!("{err:#}");
        assert!(msg.contains("3x4") && msg.contains("4x4"), "{msg}");
        assert!(compare(&RgbImage::new(8, 8), &refr, None, false).is_err());
        assert!(compare(&RgbImage::new(2, 1), &refr, None, false).is_err());
        assert!(refr.at_resolution(3, 3).is_err());
        assert!(refr.at_resolution(0, 0).is_err());

        let mut bad = RgbImage::new(4, 4);
        bad.pixels[3] = [f32::NAN, 0.0, f32::INFINITY];
        let msg = compare(&bad, &refr, None, false).unwrap_err().to_string();
        assert_eq!(msg, "image has 2 non-finite pixels");

        let outside = Region::new("outside", 2, 2, 3, 1);
        let msg = compare(&RgbImage::new(4, 4), &refr, Some(&outside), false)
            .unwrap_err()
            .to_string();
        assert!(msg.contains("outside"), "{msg}");
        assert!(compare(&RgbImage::new(4, 4), &refr, Some(&Region::new("e", 0, 0, 0, 1)), false).is_err());
        let mismatched = reference(RgbImage::new(4, 4), Some(RgbImage::new(2, 2)));
        let msg = compare(&RgbImage::new(4, 4), &mismatched, None, true)
            .unwrap_err()
            .to_string();
        assert!(msg.contains("2x2") && msg.contains("4x4"), "{msg}");
    }

    #[test]
    fn variance_path_is_beside() {
        assert_eq!(
            variance_path(Path::new("/a/b/scene.exr")),
            PathBuf::from("/a/b/scene_var.exr")
        );
        assert_eq!(variance_path(Path::new("scene")), PathBuf::from("scene_var"));
    }

    /// The regions of scenes/cornell-spheres.toml (fractions of the image) in the 512 x 512 reference's
    /// pixels.
    fn cornell_regions() -> Vec<Region> {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/cornell-spheres.toml");
        let scene = crate::Scene::load(path).unwrap();
        scene.regions.iter().map(|r| r.pixels(512, 512)).collect()
    }

    /// The scene file's regions are the boxes picked on the reference (x0, y0, w, h in its pixels).
    #[test]
    fn cornell_regions_are_the_picked_boxes() {
        let boxes: Vec<(String, u32, u32, u32, u32)> = cornell_regions()
            .into_iter()
            .map(|r| (r.name, r.x0, r.y0, r.w, r.h))
            .collect();
        let picked = [
            ("caustic", 250, 436, 70, 40),
            ("shadow_edge", 364, 384, 40, 24),
            ("back_wall", 296, 152, 64, 64),
            ("interior", 16, 16, 480, 480),
        ];
        assert_eq!(boxes, picked.map(|(n, x, y, w, h)| (n.to_string(), x, y, w, h)));
    }

    /// The shared reference is a required fixture: this fails (not skips) when it is missing.
    #[test]
    fn shared_reference() {
        let path = Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../../shared/reference/cornell-spheres.exr"
        ));
        assert!(
            path.exists(),
            "required fixture {} is missing (the shared reference image of the test scene)",
            path.display()
        );
        let refr = Reference::load(path).unwrap();
        assert_eq!((refr.image.width, refr.image.height), (512, 512));
        assert_eq!(refr.image.count_non_finite(), 0);
        let var = refr
            .variance
            .as_ref()
            .expect("cornell-spheres_var.exr beside the reference");
        let mean = refr.image.mean();
        println!("cornell-spheres mean RGB {mean:?}, mean variance {:?}", var.mean());
        // A closed, mostly white box lit by a radiance-34 light: mean radiance well inside (0.05, 5).
        for c in mean {
            assert!(c > 0.05 && c < 5.0, "implausible mean {mean:?}");
        }

        let zero = compare(&refr.image, &refr, None, false).unwrap();
        assert_eq!(
            zero,
            ErrorStats {
                rmse: 0.0,
                rel_mse: 0.0,
                mean_bias: 0.0,
                pixels: 512 * 512
            }
        );
        let denoised = compare(&refr.image, &refr, None, true).unwrap();
        assert!(denoised.rmse >= 0.0 && denoised.rel_mse >= 0.0, "{denoised:?}");
        for r in cornell_regions() {
            let s = compare(&refr.image, &refr, Some(&r), true).unwrap();
            assert_eq!(s.rmse, 0.0, "{r:?}");
        }

        let small = refr.at_resolution(128, 128).unwrap();
        assert_eq!((small.image.width, small.image.height), (128, 128));
        let small_mean = small.image.mean();
        for c in 0..3 {
            assert!(
                (small_mean[c] - mean[c]).abs() <= 1e-5 * mean[c],
                "{small_mean:?} vs {mean:?}"
            );
        }
        // The reference's own noise at 1/4 resolution: variance / 16 per block, on average.
        let small_var = small.variance.as_ref().unwrap().mean();
        let full_var = var.mean();
        for c in 0..3 {
            assert!((small_var[c] * 16.0 - full_var[c]).abs() <= 1e-5 * full_var[c]);
        }
        // A quarter-resolution image scored directly against the full reference uses the same blocks.
        let s = compare(&small.image, &refr, cornell_regions().first(), false).unwrap();
        assert_eq!(s.rmse, 0.0);
    }
}
