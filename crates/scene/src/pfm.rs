//! Portable float maps (PFM), which Mitsuba 3 reads and the `image` crate does not, read as Mitsuba 3's
//! `Bitmap::read_pfm` (its src/core/bitmap.cpp) reads them: "PF" (RGB) or "Pf" (grey) and one more byte,
//! then three whitespace-separated tokens, the width, the height and the scale, and one whitespace byte;
//! then the pixels as 32-bit floats, little-endian where the scale is at most 0 and big-endian above, each
//! multiplied by |scale| (Mitsuba does so where |scale| is not 1), rows from the bottom one up. Linear.

use std::io::Read;

use glam::Vec3;

/// Whether `head` (a file's first bytes) starts like a PFM.
pub fn is_pfm(head: &[u8]) -> bool {
    head.len() >= 3 && head[0] == b'P' && (head[1] == b'F' || head[1] == b'f') && head[2].is_ascii_whitespace()
}

/// The next header token of `r` (leading whitespace skipped, the whitespace byte after it consumed), at
/// most 64 bytes, and 4096 bytes of whitespace before it.
fn token(r: &mut impl Read, what: &str) -> Result<String, String> {
    let mut token = Vec::new();
    let mut skipped = 0;
    loop {
        let mut b = [0u8];
        match r.read(&mut b) {
            Ok(1) => {}
            Ok(_) => return Err(format!("PFM header: the file ends in its {what}")),
            Err(e) => return Err(format!("cannot read the image: {e}")),
        }
        if b[0].is_ascii_whitespace() {
            if !token.is_empty() {
                break;
            }
            skipped += 1;
            if skipped > 4096 {
                return Err(format!("PFM header: no {what} in its first 4096 bytes"));
            }
            continue;
        }
        token.push(b[0]);
        if token.len() > 64 {
            return Err(format!("PFM header: its {what} is longer than 64 bytes"));
        }
    }
    String::from_utf8(token).map_err(|_| format!("PFM header: its {what} is not a number"))
}

/// The image the PFM file `r` holds: width, height and linear RGB pixels from the top row (a grey
/// one's value in all three channels). Errors: a header that is not a PFM's, a side outside 1..=max_side or
/// more than max_pixels pixels (the texture bounds: texture.rs), data cut short, a value that is not finite.
pub fn read(r: &mut impl Read, max_side: u32, max_pixels: u64) -> Result<(u32, u32, Vec<Vec3>), String> {
    let mut magic = [0u8; 3];
    r.read_exact(&mut magic)
        .map_err(|_| "not a PFM image: it does not start with \"PF\" or \"Pf\"".to_string())?;
    if !is_pfm(&magic) {
        return Err("not a PFM image: it does not start with \"PF\" or \"Pf\"".into());
    }
    let channels = if magic[1] == b'F' { 3 } else { 1 };
    let side = |t: &str, what: &str| -> Result<u32, String> {
        match t.parse::<u64>() {
            Ok(n) if (1..=max_side as u64).contains(&n) => Ok(n as u32),
            Ok(n) => Err(format!("PFM image {what} {n}: each side must be in 1..={max_side}")),
            Err(_) => Err(format!("PFM header: its {what} \"{t}\" is not a whole number")),
        }
    };
    let width = side(&token(r, "width")?, "width")?;
    let height = side(&token(r, "height")?, "height")?;
    let scale_token = token(r, "scale")?;
    let scale: f32 = match scale_token.parse::<f32>() {
        Ok(s) if s.is_finite() => s,
        _ => {
            return Err(format!(
                "PFM header: its scale \"{scale_token}\" is not a finite number"
            ))
        }
    };
    if width as u64 * height as u64 > max_pixels {
        return Err(format!(
            "PFM image of {width} x {height} pixels: at most {max_pixels} pixels"
        ));
    }
    let count = width as usize * height as usize * channels;
    // Read to at most the bytes the header announces (bounded above).
    let mut data = Vec::new();
    r.take(count as u64 * 4)
        .read_to_end(&mut data)
        .map_err(|e| format!("cannot read the image: {e}"))?;
    if data.len() < count * 4 {
        return Err(format!(
            "PFM image of {width} x {height} pixels: its data ends after {} of {} bytes (the file is cut short)",
            data.len(),
            count * 4
        ));
    }
    let little = scale <= 0.0;
    let factor = scale.abs();
    let value = |k: usize| {
        let b = [data[4 * k], data[4 * k + 1], data[4 * k + 2], data[4 * k + 3]];
        let v = if little {
            f32::from_le_bytes(b)
        } else {
            f32::from_be_bytes(b)
        };
        if factor != 1.0 {
            v * factor
        } else {
            v
        }
    };
    let (w, h) = (width as usize, height as usize);
    let mut pixels = Vec::with_capacity(w * h);
    // Rows from the top: the file's last row first.
    for y in (0..h).rev() {
        for x in 0..w {
            let k = (y * w + x) * channels;
            let p = if channels == 3 {
                Vec3::new(value(k), value(k + 1), value(k + 2))
            } else {
                Vec3::splat(value(k))
            };
            if !p.is_finite() {
                return Err(format!(
                    "PFM pixel ({x}, {}) (column, row from the top) is {p}: values must be finite",
                    h - 1 - y
                ));
            }
            pixels.push(p);
        }
    }
    Ok((width, height, pixels))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::texture::{MAX_TEXTURE_PIXELS, MAX_TEXTURE_SIDE};

    fn read(r: &mut impl Read) -> Result<(u32, u32, Vec<Vec3>), String> {
        super::read(r, MAX_TEXTURE_SIDE, MAX_TEXTURE_PIXELS)
    }

    fn pfm(header: &str, values: &[f32], little: bool) -> Vec<u8> {
        let mut bytes = header.as_bytes().to_vec();
        for v in values {
            bytes.extend(if little { v.to_le_bytes() } else { v.to_be_bytes() });
        }
        bytes
    }

    /// RGB and grey, both byte orders, the scale's magnitude applied (as Mitsuba), rows bottom to top.
    #[test]
    fn reads_rgb_and_grey_in_both_byte_orders() {
        let values: Vec<f32> = (0..12).map(|i| i as f32 * 0.25).collect();
        for (scale, little, factor) in [("-1", true, 1.0), ("1.0", false, 1.0), ("-2", true, 2.0)] {
            let (w, h, px) = read(&mut &pfm(&format!("PF\n2 2\n{scale}\n"), &values, little)[..]).unwrap();
            assert_eq!((w, h), (2, 2));
            // The file's first row (pixels 0, 1) is the image's bottom one.
            let want = |k: usize| factor * Vec3::new(values[3 * k], values[3 * k + 1], values[3 * k + 2]);
            assert_eq!(px, vec![want(2), want(3), want(0), want(1)], "scale {scale}");
        }
        let (w, h, px) = read(&mut &pfm("Pf 3 1 -1\n", &[0.5, 1.5, 2.5], true)[..]).unwrap();
        assert_eq!((w, h), (3, 1));
        assert_eq!(px, vec![Vec3::splat(0.5), Vec3::splat(1.5), Vec3::splat(2.5)]);
    }

    /// The PFMs scenes/references/pfm.py wrote (three by Mitsuba's mi.Bitmap, one big-endian with scale 2
    /// by hand) read as Mitsuba 3 reads them (pfm.json): every channel of every pixel equal, through
    /// texture::read_image as scenes read images.
    #[test]
    fn reads_as_mitsuba_reads() {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/references");
        let text = std::fs::read_to_string(format!("{dir}/pfm.json")).unwrap();
        let json: serde_json::Value = serde_json::from_str(&text).unwrap();
        let files = json["files"].as_object().unwrap();
        assert_eq!(files.len(), 4);
        for (name, want) in files {
            let path = std::path::PathBuf::from(format!("{dir}/textures/{name}"));
            for raw in [false, true] {
                let (w, h, px) = crate::texture::read_image(&path, raw).unwrap();
                assert_eq!(
                    (w as u64, h as u64),
                    (want["width"].as_u64().unwrap(), want["height"].as_u64().unwrap())
                );
                let rows = want["pixels"].as_array().unwrap();
                for (y, row) in rows.iter().enumerate() {
                    for (x, p) in row.as_array().unwrap().iter().enumerate() {
                        let c: Vec<f32> = p
                            .as_array()
                            .unwrap()
                            .iter()
                            .map(|c| c.as_f64().unwrap() as f32)
                            .collect();
                        let want = if c.len() == 1 {
                            Vec3::splat(c[0])
                        } else {
                            Vec3::new(c[0], c[1], c[2])
                        };
                        assert_eq!(px[y * w as usize + x], want, "{name} pixel ({x}, {y})");
                    }
                }
            }
        }
    }

    /// Hostile headers and data: errors that say what is wrong, never a panic or a huge allocation.
    #[test]
    fn refuses_bad_headers_short_data_and_nan() {
        let two = [0.5f32; 6];
        for (bytes, said) in [
            (b"P6\n2 1\n255\n".to_vec(), "not a PFM image"),
            (b"PF\n".to_vec(), "ends in its width"),
            (b"PF\n2".to_vec(), "ends in its width"),
            (b"PF\nx 1 -1\n".to_vec(), "width \"x\" is not a whole number"),
            (b"PF\n-2 1 -1\n".to_vec(), "width \"-2\" is not a whole number"),
            (b"PF\n0 1 -1\n".to_vec(), "each side must be in 1..="),
            (b"PF\n2 99999999999999999999 -1\n".to_vec(), "is not a whole number"),
            (b"PF\n16384 16384 -1\n".to_vec(), "at most"),
            (b"PF\n16385 1 -1\n".to_vec(), "each side must be in 1..="),
            (b"PF\n2 1 nan\n".to_vec(), "not a finite number"),
            (b"PF\n2 1 inf\n".to_vec(), "not a finite number"),
            (pfm("PF\n2 1\n-1\n", &two[..5], true), "cut short"),
            (
                pfm("PF\n2 1\n-1\n", &[0.5, f32::NAN, 0.5, 0.5, 0.5, 0.5], true),
                "values must be finite",
            ),
            (pfm("PF\n2 1\n-1e38\n", &[1e10; 6], true), "values must be finite"),
        ] {
            let e = read(&mut &bytes[..]).unwrap_err();
            assert!(
                e.contains(said),
                "{:?}: {e}",
                String::from_utf8_lossy(&bytes[..bytes.len().min(30)])
            );
        }
        // At the bounds: the largest side and pixel count are read (here: the header only, then cut short).
        let e = read(&mut &b"PF\n16384 4096 -1\n"[..]).unwrap_err();
        assert!(e.contains("cut short"), "{e}");
    }
}
