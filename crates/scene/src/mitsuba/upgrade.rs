//! Files written for Mitsuba before version 2 (0.3 to 0.6), upgraded element by element as Mitsuba 3's
//! parser upgrades them (src/core/parser.cpp `upgrade_from_v1`, and the older xml.cpp `upgrade_tree`):
//! camelCase property names in snake_case, `<lookAt>` as `<lookat>`, ids starting with `_` renamed, a
//! diffuse bsdf's `diffuse_reflectance` as `reflectance`, `uoffset`/`voffset`/`uscale`/`vscale` as a
//! `to_uv` transform. Beyond Mitsuba 3: 0.6's `mixturebsdf` of two weights summing to 1 is exactly a
//! `blendbsdf`, and the 0.6 plugins Mitsuba 3 dropped are refused by name, saying what they were.

use anyhow::Result;

use super::elem::Elem;

/// camelCase to snake_case as Mitsuba 3's `camel_to_underscore_case`: an underscore before an upper-case
/// letter that follows a lower-case one, that letter and the upper-case run after it lowered
/// (`intIOR` -> `int_ior`, `toWorld` -> `to_world`, `cropOffsetX` -> `crop_offset_x`).
pub(super) fn snake_case(name: &str) -> String {
    let c: Vec<char> = name.chars().collect();
    let mut out = String::with_capacity(name.len() + 4);
    let mut i = 0;
    while i < c.len() {
        if i > 0 && c[i - 1].is_ascii_lowercase() && c[i].is_ascii_uppercase() {
            out.push('_');
            out.push(c[i].to_ascii_lowercase());
            while i + 1 < c.len() && c[i + 1].is_ascii_uppercase() {
                i += 1;
                out.push(c[i].to_ascii_lowercase());
            }
        } else {
            out.push(c[i]);
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
/// refusal of plugins Mitsuba 3 dropped; approximations go to `warnings`.
pub(super) fn children(e: &mut Elem, warnings: &mut Vec<String>) -> Result<()> {
    images(e, warnings);
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

/// Mitsuba 0.6's image parameters Mitsuba 3 dropped, on a bitmap or an envmap: `gamma` -1 (the default:
/// sRGB for 8-bit images, linear for HDR ones, as Mitsuba 3 reads them) dropped, `gamma` 1 (linear) as
/// `raw` (a bitmap's; other values are left to be refused); `cache` (its MIP map cache file) dropped; EWA
/// and trilinear filtering read as bilinear with a warning, `max_anisotropy` (EWA's) with it.
fn images(e: &mut Elem, warnings: &mut Vec<String>) {
    let bitmap = e.tag == "texture" && e.kind() == "bitmap";
    let envmap = e.tag == "emitter" && e.kind() == "envmap";
    if !(bitmap || envmap) {
        return;
    }
    let value = |c: &Elem| c.attr("value").and_then(|v| v.trim().parse::<f64>().ok());
    let mut filtered = None;
    let mut kept = Vec::new();
    for mut c in std::mem::take(&mut e.children) {
        match c.attr("name") {
            Some("gamma") if value(&c) == Some(-1.0) => {}
            Some("gamma") if bitmap && value(&c) == Some(1.0) => {
                c.tag = "boolean".into();
                c.attrs = vec![("name".into(), "raw".into()), ("value".into(), "true".into())];
                kept.push(c);
            }
            Some("cache") => {}
            Some("max_anisotropy") if bitmap => {}
            Some("filter_type") if bitmap && matches!(c.attr("value"), Some("ewa" | "trilinear")) => {
                filtered = c.attr("value").map(str::to_string);
                set(&mut c, "value", "bilinear");
                kept.push(c);
            }
            _ => kept.push(c),
        }
    }
    e.children = kept;
    // 0.6's default filter is EWA: a bitmap without one is filtered so too.
    let filter = filtered.or_else(|| {
        (bitmap && !e.children.iter().any(|c| c.attr("name") == Some("filter_type"))).then(|| "ewa".to_string())
    });
    if let Some(f) = filter {
        warnings.push(e.warning(format!(
            "Mitsuba 0.6's {f} filtering read as bilinear: ppm-vk looks the image up bilinearly, without \
             averaging it over the pixel's footprint (the same where the texture is not minified)"
        )));
    }
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

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::super::tests::{load_in, write_texture};
    use super::super::{load, spectrum, xml};
    use super::*;
    use crate::{Scene, Surface, TempDir};

    /// The names 0.6 scenes use, upgraded to Mitsuba 3's.
    #[test]
    fn camel_case_names_become_mitsuba_3s() {
        for (old, new) in [
            ("intIOR", "int_ior"),
            ("extIOR", "ext_ior"),
            ("alphaU", "alpha_u"),
            ("toWorld", "to_world"),
            ("fovAxis", "fov_axis"),
            ("sampleCount", "sample_count"),
            ("maxDepth", "max_depth"),
            ("shapeIndex", "shape_index"),
            ("faceNormals", "face_normals"),
            ("specularReflectance", "specular_reflectance"),
            ("cropOffsetX", "crop_offset_x"),
            ("flipTexCoords", "flip_tex_coords"),
            ("radiance", "radiance"),
            ("already_snake", "already_snake"),
            ("UPPER", "UPPER"),
            ("éA", "éA"),
            ("aéB", "aéB"),
        ] {
            assert_eq!(snake_case(old), new);
        }
    }

    /// The test scene rewritten as a Mitsuba 0.5 file (scenes/legacy/cornell-spheres.xml) is the same
    /// scene as the Mitsuba 3 file; only the integrator's strictNormals and the ldrfilm's tone mapping are
    /// warned about.
    #[test]
    fn a_0_5_scene_is_the_same_scene_as_its_3_0_original() {
        let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");
        let new = load(
            std::path::Path::new(&format!("{root}/../shared/reference/cornell-spheres.xml")),
            &[],
        )
        .unwrap();
        let mut old = load(
            std::path::Path::new(&format!("{root}/scenes/legacy/cornell-spheres.xml")),
            &[],
        )
        .unwrap_or_else(|e| panic!("{e:#}"));
        assert_eq!(old.warnings.len(), 2, "{:?}", old.warnings);
        assert!(
            old.warnings[0].contains("<integrator type=\"path\">: not read: strict_normals"),
            "{}",
            old.warnings[0]
        );
        assert!(
            old.warnings[1].contains("<film type=\"ldrfilm\">: a Mitsuba 0.6 film: ppm-vk writes the linear image")
                && old.warnings[1].contains("(ignored: tonemap_method, gamma, exposure, banner, high_quality_edges)"),
            "{}",
            old.warnings[1]
        );
        assert!(new.warnings.is_empty());
        old.warnings.clear();
        assert_eq!(old, new);
    }

    fn legacy(dir: &TempDir, body: &str) -> anyhow::Result<Scene> {
        let head = r#"<scene version="0.6.0"><sensor type="perspective"><float name="fov" value="40"/>
            <transform name="toWorld"><lookAt origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
            <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
            <shape type="rectangle"><transform name="toWorld"><rotate x="1" angle="90"/><translate y="3"/></transform>
            <bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>"#;
        let path = dir.write("old.xml", &format!("{head}\n{body}\n</scene>\n"));
        load(&path, &[])
    }

    #[test]
    fn each_file_is_upgraded_by_its_own_version() {
        let dir = TempDir::new("mitsuba-legacy");
        // A 3.0 file included by a 0.6 one keeps its names (toWorld is no Mitsuba 3 name); a 0.6 file
        // included by a 3.0 one is upgraded.
        dir.write(
            "new.xml",
            r#"<scene version="3.0.0"><shape type="sphere"><transform name="toWorld"/></shape></scene>"#,
        );
        let e = format!("{:#}", legacy(&dir, r#"<include filename="new.xml"/>"#).unwrap_err());
        assert!(
            e.contains("new.xml:1:") && e.contains("<transform name=\"toWorld\">: parameter not read"),
            "{e}"
        );
        dir.write(
            "old-part.xml",
            r#"<scene version="0.6.0"><bsdf type="dielectric" id="_glass"><float name="intIOR" value="1.33"/></bsdf></scene>"#,
        );
        let s = load_in(
            &dir,
            r#"<include filename="old-part.xml"/><shape type="sphere"><ref id="ID_glass__UPGR"/></shape>"#,
            &[],
        )
        .unwrap_or_else(|e| panic!("{e:#}"));
        assert_eq!(s.materials.last().unwrap().name, "ID_glass__UPGR");
        // int_ior over Mitsuba's default ext_ior (air, 1.000277): intIOR was read.
        let glass = s.materials.last().unwrap().surface;
        assert!(
            matches!(glass, Surface::Glass { ior, .. } if (ior - 1.33 / 1.000_277).abs() < 1e-6),
            "{glass:?}"
        );
    }

    #[test]
    fn texture_offsets_and_scales_become_to_uv() {
        let dir = TempDir::new("mitsuba-legacy-uv");
        write_texture(&dir, "t.png");
        let old = legacy(
            &dir,
            r#"<shape type="rectangle"><bsdf type="diffuse"><texture type="bitmap" name="diffuseReflectance">
               <string name="filename" value="t.png"/><float name="uscale" value="2"/><float name="voffset" value="0.25"/>
               <string name="filterType" value="trilinear"/><float name="maxAnisotropy" value="20"/>
               <float name="gamma" value="-1"/><boolean name="cache" value="false"/>
               </texture></bsdf></shape>"#,
        )
        .unwrap_or_else(|e| panic!("{e:#}"));
        let path = dir.write(
            "new.xml",
            &std::fs::read_to_string(dir.0.join("old.xml"))
                .unwrap()
                .replace("0.6.0", "3.0.0")
                .replace("toWorld", "to_world")
                .replace("lookAt", "lookat")
                .replace("diffuseReflectance", "reflectance")
                .replace(
                    r#"<float name="uscale" value="2"/><float name="voffset" value="0.25"/>"#,
                    r#"<transform name="to_uv"><translate y="0.25"/><scale x="2"/></transform>"#,
                )
                .replace(
                    r#"<string name="filterType" value="trilinear"/><float name="maxAnisotropy" value="20"/>"#,
                    "",
                )
                .replace(
                    r#"<float name="gamma" value="-1"/><boolean name="cache" value="false"/>"#,
                    "",
                ),
        );
        let mut new = load(&path, &[]).unwrap();
        // The filter is warned about; then the same warning (the rectangle is one-sided in Mitsuba), each
        // naming its own file.
        assert_eq!(old.warnings.len(), 2, "{:?}", old.warnings);
        assert!(
            old.warnings[0].contains("<texture type=\"bitmap\" name=\"diffuse_reflectance\">: Mitsuba 0.6's trilinear filtering read as bilinear"),
            "{}",
            old.warnings[0]
        );
        assert_eq!(old.warnings[1].replace("old.xml", "new.xml"), new.warnings[0]);
        new.name = old.name.clone();
        new.warnings = old.warnings.clone();
        assert_eq!(old, new);
        assert_eq!(old.textures[0].to_uv, [2.0, 0.0, 0.0, 0.0, 1.0, 0.25]);
    }

    #[test]
    fn plugins_mitsuba_3_dropped_are_refused_by_name_and_exact_mixtures_are_blends() {
        let dir = TempDir::new("mitsuba-legacy-dropped");
        let e = format!(
            "{:#}",
            legacy(&dir, r#"<shape type="sphere"><bsdf type="phong"/></shape>"#).unwrap_err()
        );
        assert!(
            e.contains("old.xml:6:")
                && e.contains("<bsdf type=\"phong\">: a Mitsuba 0.6 plugin (the modified Phong model)"),
            "{e}"
        );
        let e = format!("{:#}", legacy(&dir, r#"<emitter type="sunsky"/>"#).unwrap_err());
        assert!(e.contains("Mitsuba 3's sunsky is another model"), "{e}");
        // Weights summing to 1: a blendbsdf of the second's weight; otherwise refused.
        let mixture = |weights: &str| {
            format!(
                r#"<scene version="0.6.0"><bsdf type="mixturebsdf" id="m"><string name="weights" value="{weights}"/>
                   <bsdf type="diffuse"/><bsdf type="conductor"/></bsdf></scene>"#
            )
        };
        let path = dir.write("m.xml", &mixture("0.3, 0.7"));
        let top = xml::read(&path, "m.xml", &[]).unwrap().children;
        assert_eq!(top[0].kind(), "blendbsdf");
        let w = &top[0].children[0];
        assert_eq!(
            (w.tag.as_str(), w.attr("name"), w.attr("value")),
            ("float", Some("weight"), Some("0.7"))
        );
        let path = dir.write("m.xml", &mixture("0.3, 0.6"));
        let e = format!("{:#}", xml::read(&path, "m.xml", &[]).err().expect("refused"));
        assert!(e.contains("a weighted sum of bsdfs"), "{e}");
    }

    #[test]
    fn srgb_and_blackbody_of_0_6() {
        let dir = TempDir::new("mitsuba-legacy-colours");
        let s = legacy(
            &dir,
            r##"<shape type="sphere"><bsdf type="diffuse"><srgb name="reflectance" value="#808080"/></bsdf></shape>
                <shape type="sphere"><point name="center" x="3"/><emitter type="area"><blackbody name="radiance" temperature="5000K" scale="1e-4"/></emitter></shape>"##,
        )
        .unwrap_or_else(|e| panic!("{e:#}"));
        // sRGB 128/255 is linear 0.2158605.
        assert!(matches!(s.materials[1].surface, Surface::Diffuse { albedo } if (albedo.x - 0.215_860_5).abs() < 1e-6));
        let want = spectrum::blackbody(5000.0).map(|c| (c * 1e-4) as f32);
        assert_eq!(s.materials[2].emission, Vec3::from_array(want));
        let e = format!(
            "{:#}",
            legacy(&dir, r#"<shape type="sphere"><bsdf type="diffuse"><blackbody name="reflectance" temperature="5000"/></bsdf></shape>"#)
                .unwrap_err()
        );
        assert!(e.contains("a black body is an emission spectrum"), "{e}");
    }
}
