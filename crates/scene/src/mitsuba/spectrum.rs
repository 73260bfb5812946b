//! Spectra as Mitsuba 3's RGB variants read them: `wavelength:value` lists and `.spd` files integrated
//! against the CIE 1931 curves into linear sRGB (Mitsuba's `spectrum_list_to_srgb`, src/core/spectrum.cpp),
//! a uniform value, and the black body (Planck's law, as src/spectra/blackbody.cpp), which Mitsuba 3's RGB
//! variants refuse to evaluate: it is converted as its spectral variants see it, the curve integrated
//! against the CIE curves.

use std::path::Path;

use super::cie::{CIE1931_XYZ, D65};
use crate::files::read_bounded;

/// Largest `.spd` spectrum file read: 1 MiB, some 50 000 `wavelength value` lines (a measured spectrum
/// has a few hundred).
pub const MAX_SPECTRUM_BYTES: u64 = 1 << 20;

/// Where a spectrum is used decides how it becomes RGB, as Mitsuba 3's `Properties::get_texture_impl`:
/// a reflectance is weighted by D65 and clamped to [0, 1]; an unbounded parameter (a conductor's eta and
/// k, a roughness) is weighted by D65 and only clamped at 0; an emitter's radiance, intensity or
/// irradiance is neither weighted nor bounded above.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Use {
    Reflectance,
    Unbounded,
    Emission,
}

const CIE_MIN: f64 = 360.0;
const CIE_MAX: f64 = 830.0;
const CIE_SAMPLES: usize = 95;
/// Makes a unit spectrum integrate to luminance 1 (Mitsuba's `MI_CIE_Y_NORMALIZATION`).
const CIE_Y_NORMALIZATION: f64 = 1.0 / 106.750_259_399_414_06;
/// Makes D65 integrate to luminance 1 (Mitsuba's `MI_CIE_D65_NORMALIZATION`).
const CIE_D65_NORMALIZATION: f64 = 1.0 / 98.997_417_518_762_55;

/// The tables' linear interpolation at `w` (zero outside [360, 830] nm), as Mitsuba's `cie1931_xyz` and
/// `cie_d65`.
fn table(w: f64, row: impl Fn(usize) -> f64) -> f64 {
    if !(CIE_MIN..=CIE_MAX).contains(&w) {
        return 0.0;
    }
    let t = (w - CIE_MIN) * ((CIE_SAMPLES - 1) as f64 / (CIE_MAX - CIE_MIN));
    let i0 = (t as usize).min(CIE_SAMPLES - 2);
    let w1 = t - i0 as f64;
    (1.0 - w1) * row(i0) + w1 * row(i0 + 1)
}

fn cie_xyz(w: f64) -> [f64; 3] {
    // Mitsuba stores the tables as 32-bit floats.
    let at = |c: usize| table(w, |i| f64::from(CIE1931_XYZ[c * CIE_SAMPLES + i] as f32));
    [at(0), at(1), at(2)]
}

fn cie_d65(w: f64) -> f64 {
    table(w, |i| f64::from(D65[i] as f32)) * CIE_D65_NORMALIZATION
}

/// CIE XYZ to linear sRGB (Rec. 709 primaries, D65 white), Mitsuba's `xyz_to_srgb`.
pub(super) fn xyz_to_srgb(xyz: [f64; 3]) -> [f64; 3] {
    const M: [[f32; 3]; 3] = [
        [3.240_479, -1.537_15, -0.498_535],
        [-0.969_256, 1.875_991, 0.041_556],
        [0.055_648, -0.204_043, 1.057_311],
    ];
    M.map(|r| f64::from(r[0]) * xyz[0] + f64::from(r[1]) * xyz[1] + f64::from(r[2]) * xyz[2])
}

/// The linear sRGB colour of a spectrum sampled at increasing `wavelengths` (nm), as Mitsuba 3's
/// `spectrum_list_to_srgb`: 1000 evenly spaced points over [360, 830] nm, the spectrum linearly
/// interpolated between its samples (zero outside them), times the CIE curves (and D65 with `d65`);
/// `bounded` clamps to [0, 1], else negatives are clamped to 0.
pub(super) fn list_to_srgb(wavelengths: &[f64], values: &[f64], bounded: bool, d65: bool) -> [f64; 3] {
    const STEPS: usize = 1000;
    let mut xyz = [0.0; 3];
    let (first, last) = (wavelengths[0], wavelengths[wavelengths.len() - 1]);
    for i in 0..STEPS {
        let w = CIE_MIN + (i as f64 / (STEPS - 1) as f64) * (CIE_MAX - CIE_MIN);
        if w < first || w > last {
            continue;
        }
        // The last sample at or before w, within [0, n - 2] (Mitsuba's find_interval).
        let index = wavelengths.partition_point(|&x| x <= w).clamp(1, wavelengths.len() - 1) - 1;
        let (w0, w1) = (wavelengths[index], wavelengths[index + 1]);
        let (v0, v1) = (values[index], values[index + 1]);
        let v = ((w - w1) * v0 + (w0 - w) * v1) / (w0 - w1);
        let weight = v * if d65 { cie_d65(w) } else { 1.0 };
        for (acc, c) in xyz.iter_mut().zip(cie_xyz(w)) {
            *acc += c * weight;
        }
    }
    let scale = (CIE_MAX - CIE_MIN) * CIE_Y_NORMALIZATION / STEPS as f64;
    let rgb = xyz_to_srgb(xyz.map(|c| c * scale));
    if bounded {
        rgb.map(|c| c.clamp(0.0, 1.0))
    } else {
        rgb.map(|c| c.max(0.0))
    }
}

/// The RGB of a sampled spectrum used as `usage` says.
pub(super) fn to_rgb(wavelengths: &[f64], values: &[f64], usage: Use) -> [f64; 3] {
    list_to_srgb(wavelengths, values, usage == Use::Reflectance, usage != Use::Emission)
}

/// The RGB of a uniform spectrum of `value`: grey, except on an emitter, where Mitsuba 3's RGB variants
/// give `value * xyz_to_srgb(1, 1, 1)` (a spectrally flat light is not white under sRGB's D65 white point,
/// so that the RGB and spectral variants agree).
pub(super) fn uniform(value: f64, usage: Use) -> [f64; 3] {
    match usage {
        Use::Emission => xyz_to_srgb([1.0; 3]).map(|c| value * f64::from(c as f32)),
        _ => [value; 3],
    }
}

/// The RGB of a black body at `kelvin`, in Mitsuba's units (W m^-2 sr^-1 nm^-1, Planck's law as
/// src/spectra/blackbody.cpp with its 32-bit constants), as Mitsuba 3's spectral variants render it: the
/// curve over [360, 830] nm integrated against the CIE curves, not weighted by D65, not bounded.
pub(super) fn blackbody(kelvin: f64) -> [f64; 3] {
    const STEPS: usize = 1000;
    // Mitsuba's constants (the speed of light, Planck's, Boltzmann's), rounded to 32 bits as its
    // ScalarFloat(...) rounds them.
    const C: f64 = 2.997_924_58e8;
    const H: f64 = 6.626_070_04e-34;
    const K: f64 = 1.380_648_52e-23;
    let (c, h, k) = (C as f32, H as f32, K as f32);
    let c0 = f64::from(2.0 * h * c * c);
    let c1 = f64::from(h * c / k);
    let wavelengths: Vec<f64> = (0..STEPS)
        .map(|i| CIE_MIN + (i as f64 / (STEPS - 1) as f64) * (CIE_MAX - CIE_MIN))
        .collect();
    let values: Vec<f64> = wavelengths
        .iter()
        .map(|&w| {
            let l = w * 1e-9;
            1e-9 * c0 / (l.powi(5) * ((c1 / (l * kelvin)).exp() - 1.0))
        })
        .collect();
    list_to_srgb(&wavelengths, &values, false, false)
}

/// Checks a sampled spectrum as Mitsuba's `Properties::Spectrum`: at least two entries, wavelengths
/// strictly increasing, every number finite.
pub(super) fn check(wavelengths: &[f64], values: &[f64]) -> Result<(), String> {
    if wavelengths.len() < 2 {
        return Err(format!(
            "a sampled spectrum needs at least two wavelength:value entries (got {}; give one value \
             without a wavelength for a uniform spectrum)",
            wavelengths.len()
        ));
    }
    if let Some(x) = wavelengths.iter().chain(values).find(|x| !x.is_finite()) {
        return Err(format!("{x} is not a finite number"));
    }
    if let Some(i) = (1..wavelengths.len()).find(|&i| wavelengths[i] <= wavelengths[i - 1]) {
        return Err(format!(
            "wavelengths must increase strictly: {} nm follows {} nm",
            wavelengths[i],
            wavelengths[i - 1]
        ));
    }
    if wavelengths[0] <= 0.0 {
        return Err(format!("wavelength {} nm is not positive", wavelengths[0]));
    }
    Ok(())
}

/// `wavelength:value` pairs separated by commas and/or spaces (`"400:0.3, 500:0.5"`).
pub(super) fn parse_list(s: &str) -> Result<(Vec<f64>, Vec<f64>), String> {
    let (mut wavelengths, mut values) = (Vec::new(), Vec::new());
    for pair in s
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|p| !p.is_empty())
    {
        let parsed = pair
            .split_once(':')
            .and_then(|(w, v)| Some((w.trim().parse::<f64>().ok()?, v.trim().parse::<f64>().ok()?)));
        let Some((w, v)) = parsed else {
            return Err(format!(
                "\"{}\" is not a wavelength:value pair",
                crate::error::truncated(pair, 40)
            ));
        };
        wavelengths.push(w);
        values.push(v);
    }
    check(&wavelengths, &values)?;
    Ok((wavelengths, values))
}

/// A spectrum file in Mitsuba's text format: per line a wavelength (nm) and a value, separated by spaces,
/// `#` starting a comment; read within [`MAX_SPECTRUM_BYTES`]. Errors say the line.
pub(super) fn read_spd(path: &Path) -> Result<(Vec<f64>, Vec<f64>), String> {
    let text = read_bounded(path, MAX_SPECTRUM_BYTES, "spectrum file").map_err(|e| e.to_string())?;
    let shown = path.display();
    let (mut wavelengths, mut values) = (Vec::new(), Vec::new());
    for (n, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("");
        let words: Vec<&str> = line.split_whitespace().collect();
        let number = |w: &str| -> Result<f64, String> {
            w.parse::<f64>().ok().filter(|x| x.is_finite()).ok_or_else(|| {
                format!(
                    "{shown}:{}: \"{}\" is not a finite number",
                    n + 1,
                    crate::error::truncated(w, 40)
                )
            })
        };
        match words[..] {
            [] => {}
            [w, v] => {
                wavelengths.push(number(w)?);
                values.push(number(v)?);
            }
            _ => {
                return Err(format!(
                    "{shown}:{}: expected a wavelength and a value, got {} numbers",
                    n + 1,
                    words.len()
                ))
            }
        }
    }
    check(&wavelengths, &values).map_err(|m| format!("{shown}: {m}"))?;
    Ok((wavelengths, values))
}

/// A colour written sRGB-encoded, as Mitsuba 0.6's `<srgb>`: `"r, g, b"` (or one number: grey) in [0, 1],
/// or `#rrggbb`; returned linear (the sRGB transfer function inverted).
pub(super) fn srgb(s: &str) -> Result<[f64; 3], String> {
    let s = s.trim();
    let encoded: [f64; 3] = if let Some(hex) = s.strip_prefix('#') {
        if hex.len() != 6 || !hex.bytes().all(|b| b.is_ascii_hexdigit()) {
            return Err(format!("\"{s}\": expected #rrggbb"));
        }
        let byte = |i: usize| f64::from(u8::from_str_radix(&hex[i..i + 2], 16).unwrap_or(0)) / 255.0;
        [byte(0), byte(2), byte(4)]
    } else {
        let n: Vec<f64> = s
            .split(|c: char| c == ',' || c.is_whitespace())
            .filter(|w| !w.is_empty())
            .map(|w| w.parse::<f64>().ok().filter(|x| x.is_finite()))
            .collect::<Option<_>>()
            .ok_or_else(|| format!("\"{}\": expected 3 numbers or #rrggbb", crate::error::truncated(s, 40)))?;
        match n[..] {
            [x] => [x; 3],
            [r, g, b] => [r, g, b],
            _ => return Err(format!("\"{s}\": expected 3 numbers or #rrggbb")),
        }
    };
    Ok(encoded.map(|c| f64::from(crate::texture::srgb_to_linear(c as f32))))
}

#[cfg(test)]
mod tests {
    use super::super::properties::Props;
    use super::super::xml;
    use super::*;
    use crate::TempDir;

    /// Each case of scenes/references/spectra.json (Mitsuba 3's `scalar_rgb` read back by spectra.py)
    /// read by our reader inside the same plugin: the same RGB within 1e-5, or an error where Mitsuba
    /// gave one; the black body as Mitsuba's spectral variant integrates it.
    #[test]
    fn spectra_match_mitsubas_rgb() {
        let refs = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/references");
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(format!("{refs}/spectra.json")).unwrap()).unwrap();
        let dir = TempDir::new("spectra");
        std::fs::copy(format!("{refs}/spectra-test.spd"), dir.0.join("spectra-test.spd")).unwrap();
        let close = |got: [f64; 3], want: &serde_json::Value, what: &str| {
            let want: Vec<f64> = want.as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
            let scale = want.iter().fold(1e-3f64, |m, w| m.max(w.abs()));
            let err = (0..3).map(|i| (got[i] - want[i]).abs() / scale).fold(0.0, f64::max);
            assert!(
                err < 1e-5,
                "{what}: ours {got:?}, Mitsuba's {want:?} (relative error {err:e})"
            );
        };
        let mut checked = 0;
        for case in json["cases"].as_array().unwrap() {
            let (owner, kind, property) = (
                case["owner"].as_str().unwrap(),
                case["type"].as_str().unwrap(),
                case["property"].as_str().unwrap(),
            );
            let path = dir.write(
                "case.xml",
                &format!(r#"<scene version="3.0.0"><{owner} type="{kind}">{property}</{owner}></scene>"#),
            );
            let top = xml::read(&path, "case.xml", &[]).unwrap().children;
            let (props, _) = Props::of(&top[0]);
            let name = top[0].children[0].attr("name").unwrap();
            let got = props.color(name).map(|c| c.expect("the property is there"));
            match (&case["rgb"], got) {
                (serde_json::Value::Null, Err(e)) => {
                    let e = format!("{e:#}");
                    assert!(
                        e.contains("case.xml:1:") && e.contains("<spectrum name=\"reflectance\">"),
                        "{e}"
                    );
                }
                (serde_json::Value::Null, Ok(c)) => panic!("{property}: Mitsuba refuses it, we read {c}"),
                (want, Ok(c)) => close([c.x, c.y, c.z].map(f64::from), want, property),
                (_, Err(e)) => panic!("{property}: {e:#}"),
            }
            checked += 1;
        }
        assert_eq!(checked, 17);
        assert!(json["blackbody"]["rgb_variant"]
            .as_str()
            .unwrap()
            .starts_with("refused"));
        for b in json["blackbody"]["spectral"].as_array().unwrap() {
            let t = b["temperature"].as_f64().unwrap();
            close(blackbody(t), &b["rgb"], &format!("black body at {t} K"));
        }
    }

    #[test]
    fn a_flat_spectrum_is_white_under_d65_and_purple_as_light() {
        // A unit reflectance weighted by D65 integrates to D65's white: (1, 1, 1) to within the tables'
        // resolution.
        let rgb = list_to_srgb(&[360.0, 830.0], &[1.0, 1.0], false, true);
        assert!(rgb.iter().all(|c| (c - 1.0).abs() < 0.01), "{rgb:?}");
        // Without D65 it is the flat light's colour.
        let flat = list_to_srgb(&[360.0, 830.0], &[1.0, 1.0], false, false);
        assert!(
            (0..3).all(|i| (flat[i] - uniform(1.0, Use::Emission)[i]).abs() < 0.02),
            "{flat:?}"
        );
        // Unit luminance: Y of a flat unit spectrum is 1 (the normalisation's meaning).
        let y = 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
        assert!((y - 1.0).abs() < 0.01, "{y}");
        // As a light: xyz_to_srgb(1, 1, 1), the rows of the matrix summed: (1.204794, 0.948291, 0.908916).
        let light = uniform(2.0, Use::Emission);
        let want = [1.204_794, 0.948_291, 0.908_916];
        assert!((0..3).all(|i| (light[i] - 2.0 * want[i]).abs() < 1e-6), "{light:?}");
        assert_eq!(uniform(0.3, Use::Reflectance), [0.3; 3]);
    }

    #[test]
    fn malformed_spectra_are_refused() {
        assert!(parse_list("400:0.5").unwrap_err().contains("at least two"));
        assert!(parse_list("500:0.5, 400:0.2")
            .unwrap_err()
            .contains("increase strictly"));
        assert!(parse_list("400:0.5, 400:0.2")
            .unwrap_err()
            .contains("increase strictly"));
        assert!(parse_list("400:NaN, 500:0.2")
            .unwrap_err()
            .contains("not a finite number"));
        assert!(parse_list("400:0.1, 500")
            .unwrap_err()
            .contains("not a wavelength:value pair"));
        assert_eq!(
            parse_list("400:0.1 500:0.2").unwrap(),
            (vec![400.0, 500.0], vec![0.1, 0.2])
        );
        assert!(srgb("#12345").is_err() && srgb("1, 2").is_err());
        let white = srgb("#ffffff").unwrap();
        assert!(white.iter().all(|c| (c - 1.0).abs() < 1e-12));
        // sRGB 0.5 is linear 0.214.
        assert!((srgb("0.5").unwrap()[0] - 0.214_041).abs() < 1e-6);
    }
}
