//! Property values: the typed properties of a plugin element (`<float name=..>`, `<rgb>`,
//! `<transform>`, ...), each marked when read so that the unread ones are refused, and the numbers,
//! vectors, colours and transforms they hold.

use std::cell::Cell;

use anyhow::Result;
use glam::{DAffine3, DMat3, DMat4, DVec3, DVec4, Vec3};

use super::elem::Elem;
use super::spectrum::{self, Use};

/// The properties (`<float name=..>`, `<transform name=..>`, ...) of one plugin element. Each one
/// read is marked; [`Props::finish`] refuses those never read, as Mitsuba refuses unused properties.
pub(super) struct Props<'a> {
    owner: &'a Elem,
    items: Vec<(&'a Elem, Cell<bool>)>,
}

const PROPERTY_TAGS: &[&str] = &[
    "float",
    "integer",
    "boolean",
    "string",
    "point",
    "vector",
    "rgb",
    "spectrum",
    // Mitsuba 0.6's sRGB-encoded colour and black body.
    "srgb",
    "blackbody",
    "transform",
    "texture",
];

impl<'a> Props<'a> {
    /// The property children of `owner`; the other children are the caller's (`objects`).
    pub(super) fn of(owner: &'a Elem) -> (Props<'a>, Vec<&'a Elem>) {
        let mut items = Vec::new();
        let mut objects = Vec::new();
        for c in &owner.children {
            // In a bsdf or an emitter, a named `ref` is a parameter (a top-level texture); in a shape,
            // `<ref id=".." name="bsdf"/>` stays the shape's bsdf.
            let parameter = PROPERTY_TAGS.contains(&c.tag.as_str())
                || (c.tag == "ref" && matches!(owner.tag.as_str(), "bsdf" | "emitter"));
            if parameter && c.attr("name").is_some() {
                items.push((c, Cell::new(false)));
            } else {
                objects.push(c);
            }
        }
        (Props { owner, items }, objects)
    }

    pub(super) fn get(&self, name: &str) -> Option<&'a Elem> {
        self.items
            .iter()
            .find(|(e, _)| e.attr("name") == Some(name))
            .map(|(e, used)| {
                used.set(true);
                *e
            })
    }

    /// Marks `names` read without reading them: they do not change the image.
    pub(super) fn ignore(&self, names: &[&str]) {
        for n in names {
            self.get(n);
        }
    }

    pub(super) fn float(&self, name: &str) -> Result<Option<f64>> {
        self.get(name)
            .map(|e| {
                expect_tag(e, &["float", "integer"])?;
                number(e, e.required("value")?)
            })
            .transpose()
    }

    pub(super) fn string(&self, name: &str) -> Result<Option<&'a str>> {
        self.get(name)
            .map(|e| {
                expect_tag(e, &["string"])?;
                e.required("value")
            })
            .transpose()
    }

    pub(super) fn boolean(&self, name: &str) -> Result<bool> {
        self.boolean_or(name, false)
    }

    pub(super) fn boolean_or(&self, name: &str, default: bool) -> Result<bool> {
        let Some(e) = self.get(name) else {
            return Ok(default);
        };
        expect_tag(e, &["boolean"])?;
        match e.required("value")? {
            "true" => Ok(true),
            "false" => Ok(false),
            v => Err(e.err(format!("expected true or false, got \"{v}\""))),
        }
    }

    pub(super) fn point(&self, name: &str) -> Result<Option<DVec3>> {
        self.get(name)
            .map(|e| {
                expect_tag(e, &["point", "vector"])?;
                vector(e, 0.0)
            })
            .transpose()
    }

    /// A colour parameter, a spectrum made RGB as Mitsuba 3 makes it for this parameter: emission on an
    /// emitter (its `get_emissive_texture`), unbounded for a conductor's eta and k and a roughness (its
    /// `get_unbounded_texture`), a reflectance otherwise.
    pub(super) fn color(&self, name: &str) -> Result<Option<Vec3>> {
        let usage = if self.owner.tag == "emitter" {
            Use::Emission
        } else if matches!(name, "eta" | "k" | "alpha" | "alpha_u" | "alpha_v") {
            Use::Unbounded
        } else {
            Use::Reflectance
        };
        self.get(name).map(|e| color_as(e, usage)).transpose()
    }

    pub(super) fn transform(&self, name: &str) -> Result<DAffine3> {
        match self.get(name) {
            Some(e) => {
                expect_tag(e, &["transform"])?;
                transform(e)
            }
            None => Ok(DAffine3::IDENTITY),
        }
    }

    /// Refuses the properties nothing read.
    pub(super) fn finish(&self) -> Result<()> {
        match self.items.iter().find(|(_, used)| !used.get()) {
            Some((e, _)) if e.tag == "texture" || e.tag == "ref" => {
                Err(e.err(texture_refused(e.attr("name").unwrap_or_default())))
            }
            Some((e, _)) => Err(e.err(format!(
                "parameter not read by ppm-vk for {} (see docs/mitsuba.md)",
                self.owner.what()
            ))),
            None => Ok(()),
        }
    }
}

fn expect_tag(e: &Elem, tags: &[&str]) -> Result<()> {
    if tags.contains(&e.tag.as_str()) {
        Ok(())
    } else {
        Err(e.err(format!("expected a <{}> here", tags.join("> or <"))))
    }
}

pub(super) fn number(e: &Elem, s: &str) -> Result<f64> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| e.err(format!("\"{}\" is not a number", crate::error::truncated(s, 60))))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(e.err(format!("{s} is not finite")))
    }
}

/// Numbers separated by commas and/or spaces.
fn numbers(e: &Elem, s: &str) -> Result<Vec<f64>> {
    s.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|w| !w.is_empty())
        .map(|w| number(e, w))
        .collect()
}

/// `value="x, y, z"` (one number: all three), else the attributes x, y, z (absent: `default`).
fn vector(e: &Elem, default: f64) -> Result<DVec3> {
    if let Some(v) = e.attr("value") {
        return match numbers(e, v)?[..] {
            [x] => Ok(DVec3::splat(x)),
            [x, y, z] => Ok(DVec3::new(x, y, z)),
            _ => Err(e.err(format!("value \"{v}\": expected 1 or 3 numbers"))),
        };
    }
    let c = |k: &str| e.attr(k).map_or(Ok(default), |s| number(e, s));
    Ok(DVec3::new(c("x")?, c("y")?, c("z")?))
}

/// A constant reflectance: `<rgb>`, `<float>` (grey), `<spectrum>`, Mitsuba 0.6's `<srgb>`.
pub(super) fn color(e: &Elem) -> Result<Vec3> {
    color_as(e, Use::Reflectance)
}

/// A constant colour used as `usage` says: `<rgb>`, `<float>` (grey), `<spectrum>` (uniform, a
/// `wavelength:value` list, a file, a black body), Mitsuba 0.6's `<srgb>` and `<blackbody>`.
pub(super) fn color_as(e: &Elem, usage: Use) -> Result<Vec3> {
    let rgb = |c: [f64; 3]| Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32);
    match e.tag.as_str() {
        "rgb" => {
            let v = e.required("value")?;
            match numbers(e, v)?[..] {
                [x] => Ok(Vec3::splat(x as f32)),
                [r, g, b] => Ok(Vec3::new(r as f32, g as f32, b as f32)),
                _ => Err(e.err(format!("value \"{v}\": expected 3 numbers r, g, b"))),
            }
        }
        "float" => Ok(Vec3::splat(number(e, e.required("value")?)? as f32)),
        "spectrum" if e.attr("type").is_some() => match e.kind() {
            "blackbody" => {
                let (props, objects) = Props::of(e);
                if let Some(o) = objects.first() {
                    return Err(o.err(format!("not expected inside {}", e.what())));
                }
                let kelvin = props
                    .float("temperature")?
                    .ok_or_else(|| e.err("needs <float name=\"temperature\" .../> (in kelvin)"))?;
                // The spectral range Mitsuba integrates over is the CIE curves' own.
                props.ignore(&["wavelength_min", "wavelength_max"]);
                props.finish()?;
                blackbody(e, kelvin, 1.0, usage).map(rgb)
            }
            _ => Err(e.err(
                "unsupported spectrum type (read: blackbody; give a value, wavelength:value pairs or a \
                 filename for others)",
            )),
        },
        "spectrum" => {
            let (wavelengths, values) = match (e.attr("value"), e.attr("filename")) {
                (Some(_), Some(_)) | (None, None) => {
                    return Err(e.err("give either value or filename (as Mitsuba requires)"))
                }
                (Some(v), None) if !v.contains(':') => return Ok(rgb(spectrum::uniform(number(e, v)?, usage))),
                (Some(v), None) => spectrum::parse_list(v).map_err(|m| e.err(m))?,
                (None, Some(f)) => spectrum::read_spd(&e.loc.resolver.resolve(f)).map_err(|m| e.err(m))?,
            };
            Ok(rgb(spectrum::to_rgb(&wavelengths, &values, usage)))
        }
        "srgb" => Ok(rgb(spectrum::srgb(e.required("value")?).map_err(|m| e.err(m))?)),
        "blackbody" => {
            // Mitsuba 0.6: `<blackbody name=".." temperature="5000K" scale="1"/>`.
            let t = e.required("temperature")?;
            let kelvin = number(e, t.trim().trim_end_matches(['K', 'k']))?;
            let scale = e.attr("scale").map_or(Ok(1.0), |s| number(e, s))?;
            blackbody(e, kelvin, scale, usage).map(rgb)
        }
        "texture" | "ref" => Err(e.err(texture_refused(e.attr("name").unwrap_or_default()))),
        _ => Err(e.err("expected a colour: <rgb>, <float> or <spectrum>")),
    }
}

/// A black body's RGB (see [`spectrum::blackbody`]), on emitters only (Mitsuba: "only makes sense for
/// specifying emission").
fn blackbody(e: &Elem, kelvin: f64, scale: f64, usage: Use) -> Result<[f64; 3]> {
    if usage != Use::Emission {
        return Err(e.err("a black body is an emission spectrum: give it to an emitter"));
    }
    if !(kelvin > 0.0 && kelvin <= 1e6) {
        return Err(e.err(format!("temperature {kelvin} K: expected one in (0, 10^6] kelvin")));
    }
    Ok(spectrum::blackbody(kelvin).map(|c| c * scale))
}

/// Why a texture on parameter `name` is refused.
fn texture_refused(name: &str) -> String {
    format!(
        "a texture on {name} is not supported: read on diffuse reflectances (diffuse reflectance, plastic \
         diffuse_reflectance), specular_reflectance (conductor, roughconductor, thindielectric) and alpha \
         (roughconductor, roughdielectric)"
    )
}

/// A `<transform>`: its steps in document order, each applied after the ones before (M = step * M).
fn transform(e: &Elem) -> Result<DAffine3> {
    let mut m = DMat4::IDENTITY;
    for step in &e.children {
        let s = match step.tag.as_str() {
            "translate" => DMat4::from_translation(vector(step, 0.0)?),
            "scale" => DMat4::from_scale(vector(step, 1.0)?),
            "rotate" => {
                let axis = vector(step, 0.0)?;
                let angle = number(step, step.required("angle")?)?;
                if axis.length() == 0.0 {
                    return Err(step.err("the rotation axis (x, y, z or value) is zero"));
                }
                // Rodrigues' formula with the axis as written, as Mitsuba 3's Transform::rotate: it does not
                // normalise it, so an axis that is not unit also scales and shears (tangents.py found it).
                let (sin, cos) = angle.to_radians().sin_cos();
                let k = DMat3::from_cols(
                    DVec3::new(0.0, axis.z, -axis.y),
                    DVec3::new(-axis.z, 0.0, axis.x),
                    DVec3::new(axis.y, -axis.x, 0.0),
                );
                let outer = DMat3::from_cols(axis * axis.x, axis * axis.y, axis * axis.z);
                DMat4::from_mat3(DMat3::IDENTITY * cos + k * sin + outer * (1.0 - cos))
            }
            "matrix" => {
                let v = step.required("value")?;
                match numbers(step, v)?[..] {
                    // Row-major, as written.
                    ref n if n.len() == 16 => DMat4::from_cols_array(n.try_into().unwrap()).transpose(),
                    ref n if n.len() == 9 => {
                        DMat4::from_mat3(DMat3::from_cols_array(n.try_into().unwrap()).transpose())
                    }
                    _ => return Err(step.err(format!("value: expected 16 or 9 numbers, got \"{v}\""))),
                }
            }
            "lookat" => {
                let p = |k: &str| -> Result<DVec3> {
                    let v = step.required(k)?;
                    match numbers(step, v)?[..] {
                        [x, y, z] => Ok(DVec3::new(x, y, z)),
                        _ => Err(step.err(format!("{k}=\"{v}\": expected 3 numbers"))),
                    }
                };
                let (origin, target, up) = (p("origin")?, p("target")?, p("up")?);
                let dir = (target - origin).normalize_or_zero();
                let left = up.cross(dir).normalize_or_zero();
                if dir == DVec3::ZERO || left == DVec3::ZERO {
                    return Err(step.err("origin equals target, or up is zero or parallel to the view direction"));
                }
                // Mitsuba's look_at: camera x = left, y = up, z = forward.
                DMat4::from_cols(
                    left.extend(0.0),
                    dir.cross(left).extend(0.0),
                    dir.extend(0.0),
                    origin.extend(1.0),
                )
            }
            _ => return Err(step.err("expected translate, rotate, scale, matrix or lookat")),
        };
        m = s * m;
    }
    if m.row(3) != DVec4::new(0.0, 0.0, 0.0, 1.0) || !m.is_finite() {
        return Err(e.err(format!(
            "not an affine transform (last row {:?}, must be [0, 0, 0, 1])",
            m.row(3).to_array()
        )));
    }
    Ok(DAffine3::from_mat4(m))
}
