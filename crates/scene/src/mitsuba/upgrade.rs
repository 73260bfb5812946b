//! Files written for Mitsuba before version 2 (0.3 to 0.6), upgraded element by element as Mitsuba 3's
//! parser upgrades them (src/core/parser.cpp `upgrade_from_v1`, and the older xml.cpp `upgrade_tree`):
//! camelCase property names in snake_case, `<lookAt>` as `<lookat>`, ids starting with `_` renamed, a
//! diffuse bsdf's `diffuse_reflectance` as `reflectance`, `uoffset`/`voffset`/`uscale`/`vscale` as a
//! `to_uv` transform. Beyond Mitsuba 3: 0.6's `mixturebsdf` of two weights summing to 1 is exactly a
//! `blendbsdf`, and the 0.6 plugins Mitsuba 3 dropped are refused by name, saying what they were.

use anyhow::Result;

use super::xml::Elem;

/// camelCase to snake_case as Mitsuba 3's `camel_to_underscore_case`: an underscore before an upper-case
/// letter that follows a lower-case one, that letter and the upper-case run after it lowered
/// (`intIOR` -> `int_ior`, `toWorld` -> `to_world`, `cropOffsetX` -> `crop_offset_x`).
pub(super) fn snake_case(name: &str) -> String {
    let b = name.as_bytes();
    let mut out = String::with_capacity(name.len() + 4);
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        if i > 0 && b[i - 1].is_ascii_lowercase() && c.is_ascii_uppercase() {
            out.push('_');
            out.push(c.to_ascii_lowercase() as char);
            while i + 1 < b.len() && b[i + 1].is_ascii_uppercase() {
                i += 1;
                out.push(b[i].to_ascii_lowercase() as char);
            }
        } else {
            out.push(c as char);
        }
        i += 1;
    }
    out
}

/// The element's own renames (its attributes already substituted).
pub(super) fn rename(e: &mut Elem) {
    if e.tag == "lookAt" {
        e.tag = "lookat".into();
    }
    let tag = e.tag.clone();
    for (k, v) in &mut e.attrs {
        match k.as_str() {
            "name" if tag != "default" => *v = snake_case(v),
            // Mitsuba 3 reserves ids starting with `_`; its upgrade renames them (references too).
            "id" if v.starts_with('_') => *v = format!("ID{v}__UPGR"),
            _ => {}
        }
    }
}

/// 0.6 plugins Mitsuba 3 does not have, with what they were: refused by name.
const DROPPED: &[(&str, &str, &str)] = &[
    ("bsdf", "phong", "the modified Phong model"),
    ("bsdf", "ward", "the anisotropic Ward model"),
    ("bsdf", "roughdiffuse", "Oren-Nayar rough diffuse reflection"),
    ("bsdf", "coating", "a smooth dielectric coating over another bsdf"),
    ("bsdf", "roughcoating", "a rough dielectric coating over another bsdf"),
    (
        "bsdf",
        "mixturebsdf",
        "a weighted sum of bsdfs (read only as two weights summing to 1: a blendbsdf)",
    ),
    ("bsdf", "difftrans", "diffuse transmission"),
    ("bsdf", "hk", "the Hanrahan-Krueger layered subsurface model"),
    ("bsdf", "irawan", "the Irawan-Marschner woven cloth model"),
    ("bsdf", "dipole", "dipole subsurface scattering"),
    ("subsurface", "dipole", "dipole subsurface scattering"),
    ("emitter", "sun", "the Preetham sun"),
    ("emitter", "sky", "the Hosek-Wilkie sky"),
    (
        "emitter",
        "sunsky",
        "the Preetham sun and Hosek-Wilkie sky (Mitsuba 3's sunsky is another model with other parameters)",
    ),
    ("emitter", "collimated", "a collimated beam"),
    ("texture", "scale", "a texture scaled by a factor"),
    ("texture", "vertexcolors", "a mesh's vertex colours"),
    ("texture", "wireframe", "a wireframe over a mesh"),
    ("texture", "curvature", "a mesh's curvature"),
    ("texture", "gridtexture", "a grid"),
    ("shape", "hair", "hair fibres"),
    ("shape", "heightfield", "a height field"),
    ("sensor", "telecentric", "a telecentric lens"),
    ("sensor", "spherical", "a spherical camera"),
    ("sensor", "fluencemeter", "a fluence meter"),
];

/// Rewrites that look at the element's children (read, substituted and upgraded already), and the
/// refusal of plugins Mitsuba 3 dropped.
pub(super) fn children(e: &mut Elem) -> Result<()> {
    if let Some((_, _, what)) = DROPPED.iter().find(|(t, k, _)| *t == e.tag && *k == e.kind()) {
        if !(e.kind() == "mixturebsdf" && mixture_as_blend(e)?) {
            return Err(e.err(format!(
                "a Mitsuba 0.6 plugin ({what}) that Mitsuba 3 no longer has: not supported (see \
                 docs/mitsuba.md)"
            )));
        }
    }
    if e.tag == "bsdf" && e.kind() == "diffuse" {
        for c in &mut e.children {
            if c.attr("name") == Some("diffuse_reflectance") {
                set(c, "name", "reflectance");
            }
        }
    }
    // uoffset, voffset, uscale, vscale as to_uv = scale * translate (offset first).
    let uv = ["uoffset", "voffset", "uscale", "vscale"];
    if e.children
        .iter()
        .any(|c| c.tag == "float" && uv.iter().any(|n| c.attr("name") == Some(n)))
    {
        let mut values = [None; 4];
        let mut at = None;
        let mut kept = Vec::new();
        for c in std::mem::take(&mut e.children) {
            match uv.iter().position(|n| c.tag == "float" && c.attr("name") == Some(n)) {
                Some(i) => {
                    values[i] = Some(super::properties::number(&c, c.required("value")?)?);
                    at.get_or_insert(c);
                }
                None => kept.push(c),
            }
        }
        e.children = kept;
        let mut t = at.expect("one of them was seen");
        t.tag = "transform".into();
        t.attrs = vec![("name".into(), "to_uv".into())];
        let step = |tag: &str, x: f64, y: f64| {
            let mut s = t.clone();
            s.tag = tag.into();
            s.attrs = vec![("x".into(), x.to_string()), ("y".into(), y.to_string())];
            s
        };
        let translate = step("translate", values[0].unwrap_or(0.0), values[1].unwrap_or(0.0));
        let mut scale = step("scale", values[2].unwrap_or(1.0), values[3].unwrap_or(1.0));
        scale.attrs.push(("z".into(), "1".into()));
        t.children = vec![translate, scale];
        e.children.retain(|c| c.attr("name") != Some("to_uv"));
        e.children.push(t);
    }
    Ok(())
}

fn set(e: &mut Elem, key: &str, value: &str) {
    if let Some((_, v)) = e.attrs.iter_mut().find(|(k, _)| k == key) {
        *v = value.to_string();
    }
}

/// A 0.6 `mixturebsdf` (`weights` w1, w2 of two bsdfs: w1 A + w2 B) rewritten in place as Mitsuba 3's
/// `blendbsdf` ((1 - t) A + t B with t = w2) when that is the same sum, w1 + w2 = 1; false otherwise.
fn mixture_as_blend(e: &mut Elem) -> Result<bool> {
    let weights: Vec<&Elem> = e
        .children
        .iter()
        .filter(|c| c.attr("name") == Some("weights"))
        .collect();
    let bsdfs = e.children.iter().filter(|c| c.tag == "bsdf" || c.tag == "ref").count();
    let [w] = weights[..] else { return Ok(false) };
    let Some(v) = w.attr("value") else { return Ok(false) };
    let parsed: Vec<f64> = v
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|s| !s.is_empty())
        .map(|s| super::properties::number(w, s))
        .collect::<Result<_>>()?;
    let [w1, w2] = parsed[..] else { return Ok(false) };
    // Weights as written in decimal rarely sum to 1 exactly in binary (0.1 + 0.2): 1e-9 is their rounding.
    if bsdfs != 2 || (w1 + w2 - 1.0).abs() > 1e-9 || !(0.0..=1.0).contains(&w2) {
        return Ok(false);
    }
    set(e, "type", "blendbsdf");
    for c in &mut e.children {
        if c.attr("name") == Some("weights") {
            c.tag = "float".into();
            c.attrs = vec![("name".into(), "weight".into()), ("value".into(), w2.to_string())];
        }
    }
    Ok(true)
}
