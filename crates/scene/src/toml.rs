//! The scene file: a small TOML file with a camera, named materials, spheres, quads (parallelograms),
//! `[[mesh]]` entries that import OBJ files and `[[light]]`s with no surface (points, spots, the sun,
//! environments). See `docs/scene-format.md` for the user-facing spec.
//!
//! Parsing is two-stage: serde deserialises the file into `Raw*` structs whose leaves are
//! `toml::Spanned` (so every value keeps its byte range), read through serde_path_to_error (so a type
//! error knows the field it was reading), then `build` makes the [`Scene`] and runs
//! [`Scene::check`] on it; the field path of a failed check is mapped back to the span it came from.
//! What only the file can get wrong (unknown material names, two surface kinds in one material, a mesh
//! transform) is checked here. Every error is reported as `<origin>:<line>:<col>: <field path>: <what>`.

use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;
use std::ops::Range;
use std::path::Path;

use ::toml::Spanned;
use glam::{DAffine3, DMat3, DVec3, Mat3, Vec3};
use serde::Deserialize;

use crate::emitter::{Emitter, EnvMap, Environment};
use crate::error::{Error, Result};

use super::texture::{self, Filter, Pattern, Texture, Wrap};
use super::{obj, Camera, ImageRegion, Material, Microfacet, ObjImport, Quad, Scene, Sphere, Surface, MAX_TRIANGLES};

/// [`Scene::parse`]: mesh files are found relative to the directory of `origin`.
pub(super) fn parse(text: &str, origin: &str) -> Result<Scene> {
    let src = Source { origin, text };
    if is_blank(text) {
        return Err(src.error(
            0..0,
            None,
            "file is empty: a scene needs a [camera], materials and at least one light \
             (an emitting quad or mesh)",
        ));
    }
    let raw: RawScene =
        serde_path_to_error::deserialize(::toml::Deserializer::new(text)).map_err(|e| src.toml_error(e))?;
    let base = Path::new(origin).parent().unwrap_or(Path::new(""));
    build(&src, raw, base)
}

// ---------------------------------------------------------------------------
// Raw (as-written) file structure.

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    name: Option<Spanned<String>>,
    camera: Spanned<RawCamera>,
    #[serde(default)]
    materials: BTreeMap<String, Spanned<RawMaterial>>,
    #[serde(default)]
    sphere: Vec<Spanned<RawSphere>>,
    #[serde(default)]
    quad: Vec<Spanned<RawQuad>>,
    #[serde(default)]
    mesh: Vec<Spanned<RawMesh>>,
    #[serde(default)]
    region: Vec<Spanned<RawRegion>>,
    #[serde(default)]
    light: Vec<Spanned<RawLight>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRegion {
    name: Spanned<String>,
    x0: Spanned<f64>,
    y0: Spanned<f64>,
    x1: Spanned<f64>,
    y1: Spanned<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCamera {
    eye: Spanned<[f32; 3]>,
    look_at: Spanned<[f32; 3]>,
    up: Spanned<[f32; 3]>,
    vfov: Spanned<f32>,
    resolution: Spanned<[u32; 2]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMaterial {
    diffuse: Option<Spanned<RawReflectance>>,
    mirror: Option<Spanned<[f32; 3]>>,
    glass: Option<Spanned<f32>>,
    conductor: Option<Spanned<RawConductor>>,
    plastic: Option<Spanned<RawPlastic>>,
    thin: Option<Spanned<RawThin>>,
    rough_glass: Option<Spanned<RawRoughGlass>>,
    emission: Option<Spanned<[f32; 3]>>,
}

/// `rough_glass = { ior = 1.5, alpha = 0.1, distribution = "beckmann" }`: Mitsuba's roughdielectric, with
/// its defaults (BK7 in air, alpha 0.1, Beckmann).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRoughGlass {
    ior: Option<f32>,
    alpha: Option<RawAlpha>,
    distribution: Option<RawDistribution>,
}

/// A rough conductor's or rough glass's roughness: one alpha, or `[alpha_u, alpha_v]` (anisotropic, along
/// the surface's dp/du and across: docs/scene-format.md).
#[derive(Deserialize, Clone, Copy)]
#[serde(untagged, expecting = "a number or an array of 2 numbers [alpha_u, alpha_v]")]
enum RawAlpha {
    One(f32),
    Two([f32; 2]),
}

/// A microfacet distribution's name (Mitsuba's `distribution`).
#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "lowercase")]
enum RawDistribution {
    Beckmann,
    Ggx,
}

/// `plastic = { diffuse = [..], specular = [..], ior = 1.49, nonlinear = false }`: Mitsuba's plastic
/// (diffuse_reflectance, specular_reflectance, int_ior / ext_ior, nonlinear), with its defaults.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPlastic {
    diffuse: Option<Spanned<RawReflectance>>,
    specular: Option<[f32; 3]>,
    ior: Option<f32>,
    nonlinear: Option<bool>,
    /// Given: Mitsuba's roughplastic, its coat of this roughness.
    alpha: Option<f32>,
    distribution: Option<RawDistribution>,
}

/// A diffuse reflectance (a diffuse material's `diffuse`, a plastic's): `[r, g, b]`, or a texture table
/// ([`RawTexture`]).
enum RawReflectance {
    Constant([f32; 3]),
    Texture(RawTexture),
}

impl<'de> Deserialize<'de> for RawReflectance {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        use serde::de::{self, IgnoredAny, MapAccess, SeqAccess, Visitor};
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = RawReflectance;

            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str(
                    "an array of 3 numbers [r, g, b], or a texture table ({ texture = \"file.png\" } or \
                     { checkerboard = [[r, g, b], [r, g, b]] })",
                )
            }

            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> std::result::Result<Self::Value, A::Error> {
                let mut v = [0.0f32; 3];
                for (i, c) in v.iter_mut().enumerate() {
                    *c = seq
                        .next_element()?
                        .ok_or_else(|| de::Error::invalid_length(i, &"3 numbers"))?;
                }
                let mut n = 3;
                while seq.next_element::<IgnoredAny>()?.is_some() {
                    n += 1;
                }
                if n > 3 {
                    return Err(de::Error::invalid_length(n, &"3 numbers"));
                }
                Ok(RawReflectance::Constant(v))
            }

            fn visit_map<A: MapAccess<'de>>(self, map: A) -> std::result::Result<Self::Value, A::Error> {
                RawTexture::deserialize(de::value::MapAccessDeserializer::new(map)).map(RawReflectance::Texture)
            }
        }
        d.deserialize_any(V)
    }
}

/// `{ texture = "wood.png", filter = "bilinear", wrap = "repeat", raw = false, scale = [su, sv] }` (an
/// image, relative to the scene file) or `{ checkerboard = [[r, g, b], [r, g, b]], scale = [su, sv] }`:
/// Mitsuba's bitmap and checkerboard, `scale` their to_uv (u' = su u, v' = sv v).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTexture {
    texture: Option<Spanned<String>>,
    checkerboard: Option<Spanned<[[f32; 3]; 2]>>,
    filter: Option<Spanned<RawFilter>>,
    wrap: Option<Spanned<RawWrap>>,
    raw: Option<Spanned<bool>>,
    scale: Option<Spanned<[f32; 2]>>,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "lowercase")]
enum RawFilter {
    Bilinear,
    Nearest,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "lowercase")]
enum RawWrap {
    Repeat,
    Mirror,
    Clamp,
}

/// `thin = { ior = 1.5, reflectance = [..], transmittance = [..] }`: Mitsuba's thindielectric.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawThin {
    ior: Option<f32>,
    reflectance: Option<[f32; 3]>,
    transmittance: Option<[f32; 3]>,
}

/// `conductor = "Au"` (a metal Mitsuba names), or `conductor = { eta = [..], k = [..] }`, either with an
/// optional `reflectance` (Mitsuba's specular_reflectance) in the table form:
/// `conductor = { material = "Cu", reflectance = [0.9, 0.9, 0.9] }`, and rough with `alpha` (and
/// `distribution`): `conductor = { material = "Au", alpha = 0.2, distribution = "ggx" }`.
#[derive(Deserialize)]
#[serde(untagged)]
enum RawConductor {
    Named(String),
    Table(RawConductorTable),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawConductorTable {
    material: Option<String>,
    eta: Option<[f32; 3]>,
    k: Option<[f32; 3]>,
    reflectance: Option<[f32; 3]>,
    /// Given: a rough conductor (Mitsuba's roughconductor) of this roughness.
    alpha: Option<RawAlpha>,
    /// The rough conductor's distribution (default Beckmann, as Mitsuba's); needs `alpha`.
    distribution: Option<RawDistribution>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSphere {
    center: Spanned<[f32; 3]>,
    radius: Spanned<f32>,
    material: Spanned<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawQuad {
    origin: Spanned<[f32; 3]>,
    edge_u: Spanned<[f32; 3]>,
    edge_v: Spanned<[f32; 3]>,
    material: Spanned<String>,
    /// Only the ellipse inscribed in the parallelogram (a disk where the edges are equal and square).
    #[serde(default)]
    disk: bool,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMesh {
    file: Spanned<String>,
    translate: Option<Spanned<[f64; 3]>>,
    rotate: Option<Spanned<[f64; 3]>>,
    scale: Option<Spanned<RawScale>>,
    matrix: Option<Spanned<[[f64; 4]; 4]>>,
    material: Option<Spanned<String>>,
    /// Flat shading even where the OBJ gives vertex normals (Mitsuba's `face_normals`).
    face_normals: Option<bool>,
}

/// `[[light]]`: a light with no surface (Mitsuba's point, spot, directional, constant and envmap), one
/// table for every type; [`LIGHT_FIELDS`] says which fields each type reads.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLight {
    #[serde(rename = "type")]
    kind: Spanned<String>,
    position: Option<Spanned<[f32; 3]>>,
    direction: Option<Spanned<[f32; 3]>>,
    target: Option<Spanned<[f32; 3]>>,
    intensity: Option<Spanned<RawColour>>,
    irradiance: Option<Spanned<RawColour>>,
    radiance: Option<Spanned<RawColour>>,
    cutoff_angle: Option<Spanned<f32>>,
    beam_width: Option<Spanned<f32>>,
    filename: Option<Spanned<String>>,
    scale: Option<Spanned<f32>>,
    rotate: Option<Spanned<[f64; 3]>>,
}

/// Each light type with the fields it reads (besides `type`).
const LIGHT_FIELDS: &[(&str, &[&str])] = &[
    ("point", &["position", "intensity"]),
    (
        "spot",
        &[
            "position",
            "direction",
            "target",
            "intensity",
            "cutoff_angle",
            "beam_width",
        ],
    ),
    ("directional", &["direction", "irradiance"]),
    ("constant", &["radiance"]),
    ("envmap", &["filename", "scale", "rotate"]),
];

/// A light's colour: one number (grey) or `[r, g, b]`.
#[derive(Deserialize, Clone, Copy)]
#[serde(untagged, expecting = "a number or an array of 3 numbers [r, g, b]")]
enum RawColour {
    Grey(f32),
    Rgb([f32; 3]),
}

impl RawColour {
    fn rgb(self) -> Vec3 {
        match self {
            RawColour::Grey(x) => Vec3::splat(x),
            RawColour::Rgb(c) => Vec3::from_array(c),
        }
    }
}

#[derive(Deserialize)]
#[serde(untagged, expecting = "a number or an array of 3 numbers")]
enum RawScale {
    Uniform(f64),
    PerAxis([f64; 3]),
}

// ---------------------------------------------------------------------------
// Error formatting.

struct Source<'a> {
    origin: &'a str,
    text: &'a str,
}

impl Source<'_> {
    /// 1-based line and column (in characters) of a byte offset.
    fn line_col(&self, offset: usize) -> (usize, usize) {
        let mut offset = offset.min(self.text.len());
        // Spans come from toml and should be on char boundaries; be defensive anyway.
        while !self.text.is_char_boundary(offset) {
            offset -= 1;
        }
        let before = &self.text[..offset];
        let line = before.matches('\n').count() + 1;
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        let col = before[line_start..].chars().count() + 1;
        (line, col)
    }

    /// [`Error::Scene`] at the start of `span`, for field `path`.
    fn error(&self, span: Range<usize>, path: Option<&str>, msg: impl std::fmt::Display) -> Error {
        let (line, column) = self.line_col(span.start);
        Error::scene(self.origin, line, column, path.unwrap_or(""), msg.to_string())
    }

    /// Syntax and serde (type / missing / unknown field) errors: toml gives the span, and
    /// serde_path_to_error the path of the field being read when it failed.
    fn toml_error(&self, e: serde_path_to_error::Error<::toml::de::Error>) -> Error {
        let path = field_path(e.path());
        let e = e.into_inner();
        // toml's messages may be multi-line ("invalid array\nexpected `]`"); keep ours one line.
        let msg = e.message().trim().replace('\n', ": ");
        self.error(e.span().unwrap_or(0..0), Some(&path), msg)
    }
}

/// True when the text has no content but whitespace and comments.
fn is_blank(text: &str) -> bool {
    text.lines().map(str::trim).all(|l| l.is_empty() || l.starts_with('#'))
}

/// The field path as the rest of the engine writes it (`sphere[1].radius`, `materials.white.diffuse`,
/// `mesh[0].matrix[3]`), without the private keys through which `toml::Spanned` reads its value.
fn field_path(path: &serde_path_to_error::Path) -> String {
    use serde_path_to_error::Segment;
    let mut out = String::new();
    for segment in path {
        match segment {
            Segment::Seq { index } => write!(out, "[{index}]").unwrap(),
            Segment::Map { key } if key.starts_with("$__serde_spanned_private") => {}
            Segment::Map { key } | Segment::Enum { variant: key } => {
                if !out.is_empty() {
                    out.push('.');
                }
                out.push_str(key);
            }
            Segment::Unknown => {}
        }
    }
    out
}

// ---------------------------------------------------------------------------
// From the raw file to a Scene.

/// Field path -> span of what the file wrote there, to locate a failed [`Scene::check`].
#[derive(Default)]
struct Spans(HashMap<String, Range<usize>>);

impl Spans {
    fn insert(&mut self, path: impl Into<String>, span: Range<usize>) {
        self.0.insert(path.into(), span);
    }

    /// The span of `path`, else of its nearest enclosing field that has one (`mesh[0]` for
    /// `mesh[0].x`), else of the empty path (the scene as a whole).
    fn find(&self, mut path: &str) -> Range<usize> {
        loop {
            if let Some(s) = self.0.get(path) {
                return s.clone();
            }
            match path.rfind('.') {
                Some(i) => path = &path[..i],
                None => break,
            }
        }
        self.0.get("").cloned().unwrap_or(0..0)
    }
}

fn vec3(v: &Spanned<[f32; 3]>) -> Vec3 {
    Vec3::from_array(*v.get_ref())
}

fn build(src: &Source, raw: RawScene, base: &Path) -> Result<Scene> {
    let mut spans = Spans::default();
    let name = match &raw.name {
        Some(n) => n.get_ref().clone(),
        None => Path::new(src.origin)
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or(src.origin)
            .to_string(),
    };

    let c = raw.camera.get_ref();
    for (field, span) in [
        ("eye", c.eye.span()),
        ("look_at", c.look_at.span()),
        ("up", c.up.span()),
        ("vfov", c.vfov.span()),
        ("resolution", c.resolution.span()),
    ] {
        spans.insert(format!("camera.{field}"), span);
    }
    let [width, height] = *c.resolution.get_ref();
    let camera = Camera {
        eye: vec3(&c.eye),
        look_at: vec3(&c.look_at),
        up: vec3(&c.up),
        vfov_deg: *c.vfov.get_ref(),
        width,
        height,
    };

    // BTreeMap sorts by name; keep file order so material indices follow the file.
    let mut raw_materials: Vec<_> = raw.materials.iter().collect();
    raw_materials.sort_by_key(|(_, m)| m.span().start);
    let mut materials = Vec::with_capacity(raw_materials.len());
    let mut textures = Vec::new();
    for (key, m) in raw_materials {
        materials.push(material(src, key, m, base, &mut textures, &mut spans)?);
    }

    let mut spheres = Vec::with_capacity(raw.sphere.len());
    for (i, s) in raw.sphere.iter().enumerate() {
        let p = format!("sphere[{i}]");
        let r = s.get_ref();
        spans.insert(p.clone(), s.span());
        spans.insert(format!("{p}.center"), r.center.span());
        spans.insert(format!("{p}.radius"), r.radius.span());
        spans.insert(format!("{p}.material"), r.material.span());
        spheres.push(Sphere {
            center: vec3(&r.center),
            radius: *r.radius.get_ref(),
            material: lookup(src, &materials, &r.material, &format!("{p}.material"))?,
        });
    }

    let mut quads = Vec::with_capacity(raw.quad.len());
    for (i, q) in raw.quad.iter().enumerate() {
        let p = format!("quad[{i}]");
        let r = q.get_ref();
        spans.insert(p.clone(), q.span());
        spans.insert(format!("{p}.origin"), r.origin.span());
        spans.insert(format!("{p}.edge_u"), r.edge_u.span());
        spans.insert(format!("{p}.edge_v"), r.edge_v.span());
        spans.insert(format!("{p}.material"), r.material.span());
        quads.push(Quad {
            origin: vec3(&r.origin),
            edge_u: vec3(&r.edge_u),
            edge_v: vec3(&r.edge_v),
            material: lookup(src, &materials, &r.material, &format!("{p}.material"))?,
            disk: r.disk,
        });
    }

    let mut regions = Vec::with_capacity(raw.region.len());
    for (i, g) in raw.region.iter().enumerate() {
        let p = format!("region[{i}]");
        let r = g.get_ref();
        spans.insert(p.clone(), g.span());
        for (field, span) in [
            ("name", r.name.span()),
            ("x0", r.x0.span()),
            ("y0", r.y0.span()),
            ("x1", r.x1.span()),
            ("y1", r.y1.span()),
        ] {
            spans.insert(format!("{p}.{field}"), span);
        }
        regions.push(ImageRegion {
            name: r.name.get_ref().clone(),
            x0: *r.x0.get_ref(),
            y0: *r.y0.get_ref(),
            x1: *r.x1.get_ref(),
            y1: *r.y1.get_ref(),
        });
    }

    let toml_materials = materials.len();
    let mut scene = Scene {
        name,
        camera,
        materials,
        spheres,
        quads,
        meshes: Vec::new(),
        textures,
        regions,
        warnings: Vec::new(),
        emitters: Vec::new(),
    };
    for (i, m) in raw.mesh.iter().enumerate() {
        import_mesh(src, &mut scene, i, m, base, toml_materials, &mut spans)?;
    }
    // `light[i]` is `emitter[i]` of the scene; `shown` names check paths as the file wrote them.
    let mut shown = HashMap::new();
    for (i, l) in raw.light.iter().enumerate() {
        scene.emitters.push(light(src, i, l, base, &mut spans, &mut shown)?);
    }

    // A problem of the whole scene (no light, too many triangles) points at the first quad, else the
    // first mesh, else line 1.
    let first = raw.quad.first().map(|q| q.span());
    spans.insert("", first.or(raw.mesh.first().map(|m| m.span())).unwrap_or(0..0));
    scene.check().map_err(|e| {
        let path = match shown.get(&e.path) {
            Some(p) => p.clone(),
            None => e.path.replacen("emitter[", "light[", 1),
        };
        src.error(spans.find(&e.path), Some(&path), &e.message)
    })?;
    Ok(scene)
}

/// `[[light]]` number `i`: its type's fields (others refused), Mitsuba's defaults, the map of an envmap
/// read (relative to the scene file). Its fields' spans go into `spans` under the check's paths
/// (`emitter[i].<field>`); `shown` names those whose field is written differently (`light[i].rotate`
/// for `emitter[i].to_world`).
fn light(
    src: &Source,
    i: usize,
    l: &Spanned<RawLight>,
    base: &Path,
    spans: &mut Spans,
    shown: &mut HashMap<String, String>,
) -> Result<Emitter> {
    let p = format!("light[{i}]");
    let e = format!("emitter[{i}]");
    let r = l.get_ref();
    let kind = r.kind.get_ref().as_str();
    let Some((_, fields)) = LIGHT_FIELDS.iter().find(|(k, _)| *k == kind) else {
        let known: Vec<&str> = LIGHT_FIELDS.iter().map(|(k, _)| *k).collect();
        return Err(src.error(
            r.kind.span(),
            Some(&format!("{p}.type")),
            format!("unknown light type \"{kind}\" (known: {})", known.join(", ")),
        ));
    };
    let given: [(&str, Option<Range<usize>>); 11] = [
        ("position", r.position.as_ref().map(Spanned::span)),
        ("direction", r.direction.as_ref().map(Spanned::span)),
        ("target", r.target.as_ref().map(Spanned::span)),
        ("intensity", r.intensity.as_ref().map(Spanned::span)),
        ("irradiance", r.irradiance.as_ref().map(Spanned::span)),
        ("radiance", r.radiance.as_ref().map(Spanned::span)),
        ("cutoff_angle", r.cutoff_angle.as_ref().map(Spanned::span)),
        ("beam_width", r.beam_width.as_ref().map(Spanned::span)),
        ("filename", r.filename.as_ref().map(Spanned::span)),
        ("scale", r.scale.as_ref().map(Spanned::span)),
        ("rotate", r.rotate.as_ref().map(Spanned::span)),
    ];
    for (field, span) in &given {
        if let Some(span) = span {
            if !fields.contains(field) {
                return Err(src.error(
                    span.clone(),
                    Some(&format!("{p}.{field}")),
                    format!(
                        "not a field of a {kind} light (its fields: type, {})",
                        fields.join(", ")
                    ),
                ));
            }
            spans.insert(format!("{e}.{field}"), span.clone());
        }
    }
    spans.insert(e.clone(), l.span());
    shown.insert(e.clone(), p.clone());
    let required = |v: Option<&Spanned<[f32; 3]>>, field: &str| {
        v.map(vec3)
            .ok_or_else(|| src.error(l.span(), Some(&p), format!("a {kind} light needs `{field}`")))
    };
    let colour = |c: &Option<Spanned<RawColour>>| c.as_ref().map_or(Vec3::ONE, |c| c.get_ref().rgb());
    // A direction as written, made unit (zero or not finite refused here: the check wants it unit).
    let unit = |d: Vec3, span: Range<usize>, field: &str| {
        let n = d.normalize_or_zero();
        if n == Vec3::ZERO {
            return Err(src.error(
                span,
                Some(&format!("{p}.{field}")),
                format!("must be a finite non-zero vector, got {d}"),
            ));
        }
        Ok(n)
    };
    Ok(match kind {
        "point" => Emitter::Point {
            position: required(r.position.as_ref(), "position")?,
            intensity: colour(&r.intensity),
        },
        "spot" => {
            let position = required(r.position.as_ref(), "position")?;
            let direction = match (&r.direction, &r.target) {
                (Some(d), None) => unit(vec3(d), d.span(), "direction")?,
                (None, Some(t)) => {
                    // The check's `direction` is the target the file gave.
                    spans.insert(format!("{e}.direction"), t.span());
                    shown.insert(format!("{e}.direction"), format!("{p}.target"));
                    // Blame a position that is not finite, not the axis it spoils.
                    if !position.is_finite() {
                        let at = r.position.as_ref().map_or(l.span(), Spanned::span);
                        return Err(src.error(
                            at,
                            Some(&format!("{p}.position")),
                            format!("must be finite, got {position}"),
                        ));
                    }
                    if vec3(t) == position {
                        return Err(src.error(
                            t.span(),
                            Some(&format!("{p}.target")),
                            "equals position: the spot's axis runs from position towards target",
                        ));
                    }
                    unit(vec3(t) - position, t.span(), "target")?
                }
                (Some(d), Some(_)) => {
                    return Err(src.error(
                        d.span(),
                        Some(&format!("{p}.direction")),
                        "give direction or target, not both",
                    ))
                }
                (None, None) => {
                    return Err(src.error(
                        l.span(),
                        Some(&p),
                        "a spot light needs `direction` (its axis) or `target` (a point on it)",
                    ))
                }
            };
            let cutoff = r.cutoff_angle.as_ref().map_or(20.0, |c| *c.get_ref());
            let beam = r.beam_width.as_ref().map_or(cutoff * 0.75, |b| *b.get_ref());
            Emitter::Spot {
                position,
                direction,
                intensity: colour(&r.intensity),
                cutoff: cutoff.to_radians(),
                beam: beam.to_radians(),
            }
        }
        "directional" => {
            let d = r.direction.as_ref().ok_or_else(|| {
                src.error(
                    l.span(),
                    Some(&p),
                    "a directional light needs `direction` (the way its light travels)",
                )
            })?;
            Emitter::Directional {
                direction: unit(vec3(d), d.span(), "direction")?,
                irradiance: colour(&r.irradiance),
            }
        }
        "constant" => Emitter::Environment(Environment {
            scale: colour(&r.radiance),
            map: None,
            to_world: Mat3::IDENTITY,
        }),
        _ => {
            let file = r.filename.as_ref().ok_or_else(|| {
                src.error(
                    l.span(),
                    Some(&p),
                    "an envmap light needs `filename` (a latitude-longitude image)",
                )
            })?;
            let to_world = match &r.rotate {
                Some(a) => {
                    finite_all(src, a.get_ref(), a.span(), &format!("{p}.rotate"))?;
                    spans.insert(format!("{e}.to_world"), a.span());
                    shown.insert(format!("{e}.to_world"), format!("{p}.rotate"));
                    rotation(*a.get_ref()).as_mat3()
                }
                None => Mat3::IDENTITY,
            };
            let path = base.join(file.get_ref());
            let name = path.display().to_string();
            // As Mitsuba: 8- and 16-bit images are sRGB-encoded, EXR and HDR (RGBE) linear.
            let (width, height, pixels) = texture::read_image(&path, false)
                .map_err(|m| src.error(file.span(), Some(&format!("{p}.filename")), format!("{name}: {m}")))?;
            Emitter::Environment(Environment {
                scale: Vec3::splat(r.scale.as_ref().map_or(1.0, |s| *s.get_ref())),
                map: Some(EnvMap {
                    name,
                    width,
                    height,
                    pixels,
                }),
                to_world,
            })
        }
    })
}

/// `rotate = [x, y, z]` (degrees): about x, then y, then z (as a mesh's).
fn rotation(degrees: [f64; 3]) -> DMat3 {
    let [x, y, z] = degrees.map(f64::to_radians);
    DMat3::from_rotation_z(z) * DMat3::from_rotation_y(y) * DMat3::from_rotation_x(x)
}

/// Index of the material `r` names among `materials`.
fn lookup(src: &Source, materials: &[Material], r: &Spanned<String>, path: &str) -> Result<u32> {
    match materials.iter().position(|m| m.name == *r.get_ref()) {
        Some(i) => u32::try_from(i).map_err(|_| src.error(r.span(), Some(path), "too many materials")),
        None => {
            let known: Vec<String> = materials.iter().map(|m| format!("\"{}\"", m.name)).collect();
            let known = if known.is_empty() {
                "none are defined".to_string()
            } else {
                format!("known: {}", known.join(", "))
            };
            Err(src.error(
                r.span(),
                Some(path),
                format!("unknown material \"{}\" ({known})", r.get_ref()),
            ))
        }
    }
}

/// The material as written; its values are checked by `Scene::check`, what only the file can get
/// wrong (two surface kinds, none, emission written beside mirror or glass) here.
fn material(
    src: &Source,
    name: &str,
    m: &Spanned<RawMaterial>,
    base: &Path,
    textures: &mut Vec<Texture>,
    spans: &mut Spans,
) -> Result<Material> {
    let p = format!("materials.{name}");
    let r = m.get_ref();
    spans.insert(p.clone(), m.span());
    for (field, v) in [("mirror", &r.mirror), ("emission", &r.emission)] {
        if let Some(v) = v {
            spans.insert(format!("{p}.{field}"), v.span());
        }
    }
    if let Some(d) = &r.diffuse {
        spans.insert(format!("{p}.diffuse"), d.span());
    }
    if let Some(g) = &r.glass {
        spans.insert(format!("{p}.glass"), g.span());
    }
    if let Some(c) = &r.conductor {
        spans.insert(format!("{p}.conductor"), c.span());
    }
    if let Some(c) = &r.plastic {
        spans.insert(format!("{p}.plastic"), c.span());
    }
    if let Some(c) = &r.thin {
        spans.insert(format!("{p}.thin"), c.span());
    }
    if let Some(c) = &r.rough_glass {
        spans.insert(format!("{p}.rough_glass"), c.span());
    }
    // Exactly one kind of surface: the second one written is the error.
    let kinds = [
        ("diffuse", r.diffuse.as_ref().map(|v| v.span())),
        ("mirror", r.mirror.as_ref().map(|v| v.span())),
        ("glass", r.glass.as_ref().map(|v| v.span())),
        ("conductor", r.conductor.as_ref().map(|v| v.span())),
        ("plastic", r.plastic.as_ref().map(|v| v.span())),
        ("thin", r.thin.as_ref().map(|v| v.span())),
        ("rough_glass", r.rough_glass.as_ref().map(|v| v.span())),
    ];
    let mut given = kinds.iter().filter_map(|(k, span)| span.clone().map(|s| (*k, s)));
    if let (Some((a, _)), Some((b, span))) = (given.next(), given.next()) {
        return Err(src.error(
            span,
            Some(&format!("{p}.{b}")),
            format!(
                "a material cannot be both {a} and {b}: give exactly one of diffuse, mirror, glass, conductor, \
                 plastic, thin, rough_glass"
            ),
        ));
    }
    if let Some(e) = &r.emission {
        // Refused even when zero: the file says something the engine cannot do.
        if r.diffuse.is_none() && kinds.iter().any(|(_, span)| span.is_some()) {
            return Err(src.error(
                e.span(),
                Some(&format!("{p}.emission")),
                "emission can only be combined with diffuse (or stand alone), \
                 not with mirror, glass, conductor, plastic, thin or rough_glass",
            ));
        }
    }
    let mut texture = None;
    let surface = if let Some(d) = &r.diffuse {
        let (albedo, t) = reflectance(src, &p, "diffuse", d, base, textures, spans)?;
        texture = t;
        Surface::Diffuse { albedo }
    } else if let Some(mr) = &r.mirror {
        Surface::Mirror { reflectance: vec3(mr) }
    } else if let Some(g) = &r.glass {
        Surface::Glass { ior: *g.get_ref() }
    } else if let Some(c) = &r.conductor {
        conductor(src, &format!("{p}.conductor"), c)?
    } else if let Some(c) = &r.plastic {
        let c = c.get_ref();
        let diffuse = match &c.diffuse {
            Some(d) => {
                spans.insert(format!("{p}.plastic.diffuse"), d.span());
                let (diffuse, t) = reflectance(src, &p, "plastic.diffuse", d, base, textures, spans)?;
                texture = t;
                diffuse
            }
            None => Vec3::splat(0.5),
        };
        if c.distribution.is_some() && c.alpha.is_none() {
            return Err(src.error(
                r.plastic.as_ref().map_or(m.span(), |p| p.span()),
                Some(&format!("{p}.plastic")),
                "a distribution needs alpha (the roughness)",
            ));
        }
        Surface::Plastic {
            diffuse,
            specular: c.specular.map_or(Vec3::ONE, Vec3::from),
            ior: c.ior.unwrap_or(PLASTIC_IOR),
            nonlinear: c.nonlinear.unwrap_or(false),
            rough: c.alpha.map(|a| microfacet(RawAlpha::One(a), c.distribution)),
        }
    } else if let Some(t) = &r.thin {
        let t = t.get_ref();
        Surface::ThinDielectric {
            ior: t.ior.unwrap_or(THIN_IOR),
            reflectance: t.reflectance.map_or(Vec3::ONE, Vec3::from),
            transmittance: t.transmittance.map_or(Vec3::ONE, Vec3::from),
        }
    } else if let Some(g) = &r.rough_glass {
        let g = g.get_ref();
        Surface::RoughGlass {
            ior: g.ior.unwrap_or(THIN_IOR),
            rough: microfacet(g.alpha.unwrap_or(RawAlpha::One(0.1)), g.distribution),
        }
    } else if r.emission.is_some() {
        // A pure emitter reflects nothing.
        Surface::Diffuse { albedo: Vec3::ZERO }
    } else {
        return Err(src.error(
            m.span(),
            Some(&p),
            "needs one of diffuse, mirror, glass, conductor, plastic, thin, rough_glass (or emission alone for a \
             black emitter)",
        ));
    };
    Ok(Material {
        name: name.to_string(),
        surface,
        emission: r.emission.as_ref().map_or(Vec3::ZERO, vec3),
        texture,
        normal_map: None,
        opacity: None,
        specular_texture: None,
        alpha_texture: None,
        emission_texture: None,
    })
}

/// A diffuse reflectance written at `{p}.{field}`: the constant, or the texture's largest value in each
/// channel and its index in `textures` (the same texture written twice is stored once). Its values are
/// checked by `Scene::check`, located at `{p}.texture`.
fn reflectance(
    src: &Source,
    p: &str,
    field: &str,
    d: &Spanned<RawReflectance>,
    base: &Path,
    textures: &mut Vec<Texture>,
    spans: &mut Spans,
) -> Result<(Vec3, Option<u32>)> {
    let t = match d.get_ref() {
        RawReflectance::Constant(v) => return Ok((Vec3::from_array(*v), None)),
        RawReflectance::Texture(t) => t,
    };
    let fp = format!("{p}.{field}");
    let fail = |span: Range<usize>, sub: &str, message: String| {
        let path = if sub.is_empty() {
            fp.clone()
        } else {
            format!("{fp}.{sub}")
        };
        src.error(span, Some(&path), message)
    };
    let to_uv = match &t.scale {
        Some(s) => {
            let [su, sv] = *s.get_ref();
            if !(su.is_finite() && sv.is_finite() && su != 0.0 && sv != 0.0) {
                return Err(fail(
                    s.span(),
                    "scale",
                    format!("both must be finite and non-zero, got [{su}, {sv}]"),
                ));
            }
            [su, 0.0, 0.0, 0.0, sv, 0.0]
        }
        None => texture::IDENTITY_UV,
    };
    let texture = match (&t.texture, &t.checkerboard) {
        (Some(_), Some(c)) => {
            return Err(fail(
                c.span(),
                "checkerboard",
                "give either texture (an image) or checkerboard, not both".into(),
            ))
        }
        (None, None) => {
            return Err(fail(
                d.span(),
                "",
                "a texture table needs texture = \"file.png\" or checkerboard = [[r, g, b], [r, g, b]]".into(),
            ))
        }
        (None, Some(c)) => {
            let image_only = [
                ("filter", t.filter.as_ref().map(|x| x.span())),
                ("wrap", t.wrap.as_ref().map(|x| x.span())),
                ("raw", t.raw.as_ref().map(|x| x.span())),
            ];
            if let Some((key, Some(span))) = image_only.into_iter().find(|(_, span)| span.is_some()) {
                return Err(fail(
                    span,
                    key,
                    "applies to an image texture only, not a checkerboard".into(),
                ));
            }
            spans.insert(format!("{p}.texture"), c.span());
            let [c0, c1] = *c.get_ref();
            Texture {
                name: "checkerboard".into(),
                pattern: Pattern::Checkerboard {
                    color0: Vec3::from_array(c0),
                    color1: Vec3::from_array(c1),
                },
                filter: Filter::Bilinear,
                wrap: Wrap::Repeat,
                to_uv,
            }
        }
        (Some(file), None) => {
            spans.insert(format!("{p}.texture"), file.span());
            if file.get_ref().trim().is_empty() {
                return Err(fail(file.span(), "texture", "must name an image file".into()));
            }
            let path = base.join(file.get_ref());
            let shown = path.display().to_string();
            let filter = match t.filter.as_ref().map(|f| *f.get_ref()) {
                Some(RawFilter::Nearest) => Filter::Nearest,
                Some(RawFilter::Bilinear) | None => Filter::Bilinear,
            };
            let wrap = match t.wrap.as_ref().map(|w| *w.get_ref()) {
                Some(RawWrap::Mirror) => Wrap::Mirror,
                Some(RawWrap::Clamp) => Wrap::Clamp,
                Some(RawWrap::Repeat) | None => Wrap::Repeat,
            };
            let raw = t.raw.as_ref().is_some_and(|r| *r.get_ref());
            Texture::bitmap(&path, &shown, raw, filter, wrap, to_uv)
                .map_err(|e| fail(file.span(), "texture", format!("{shown}: {e}")))?
        }
    };
    let most = texture.max();
    Ok((most, Some(texture::intern(textures, std::borrow::Cow::Owned(texture)))))
}

/// Mitsuba's default plastic coat: polypropylene (1.49) in air (1.000277).
const PLASTIC_IOR: f32 = 1.49 / 1.000277;
/// Mitsuba's default thin and rough dielectric: BK7 (1.5046) in air.
const THIN_IOR: f32 = 1.5046 / 1.000277;

/// A `conductor` entry: a named metal (Mitsuba's names and RGB values, crates/materials/src/conductor.rs) or eta and k.
fn conductor(src: &Source, p: &str, c: &Spanned<RawConductor>) -> Result<Surface> {
    let fail = |message: String| src.error(c.span(), Some(p), message);
    let named = |name: &str| {
        crate::conductors::named(name).ok_or_else(|| {
            let known: Vec<&str> = crate::conductors::names().collect();
            fail(format!(
                "unknown conductor \"{name}\" (Mitsuba's names: {})",
                known.join(", ")
            ))
        })
    };
    let (material, eta, k, reflectance, alpha, distribution) = match c.get_ref() {
        RawConductor::Named(name) => (Some(name.as_str()), None, None, None, None, None),
        RawConductor::Table(t) => (
            t.material.as_deref(),
            t.eta,
            t.k,
            t.reflectance,
            t.alpha,
            t.distribution,
        ),
    };
    let (eta, k) = match (material, eta, k) {
        (Some(name), None, None) => named(name)?,
        (None, Some(eta), Some(k)) => (Vec3::from(eta), Vec3::from(k)),
        (None, None, None) => named("none")?,
        (Some(_), _, _) => return Err(fail("give a material name or eta and k, not both".into())),
        (None, _, _) => return Err(fail("give both eta and k (or a material name)".into())),
    };
    let reflectance = reflectance.map_or(Vec3::ONE, Vec3::from);
    match (alpha, distribution) {
        (Some(alpha), distribution) => Ok(Surface::RoughConductor {
            reflectance,
            eta,
            k,
            rough: microfacet(alpha, distribution),
        }),
        (None, Some(_)) => Err(fail("a distribution needs alpha (the roughness)".into())),
        (None, None) => Ok(Surface::conductor(reflectance, eta, k)),
    }
}

/// A rough surface's distribution (Mitsuba's default: Beckmann); alpha is checked by `Scene::check`.
fn microfacet(alpha: RawAlpha, distribution: Option<RawDistribution>) -> Microfacet {
    let ggx = matches!(distribution, Some(RawDistribution::Ggx));
    match alpha {
        RawAlpha::One(a) => Microfacet::isotropic(ggx, a),
        RawAlpha::Two([alpha, alpha_v]) => Microfacet { ggx, alpha, alpha_v },
    }
}

/// Reads `[[mesh]]` number `i` into `scene`: the OBJ file relative to `base`, its transform, and the
/// material override (a TOML material: one of the first `toml_materials`).
fn import_mesh(
    src: &Source,
    scene: &mut Scene,
    i: usize,
    m: &Spanned<RawMesh>,
    base: &Path,
    toml_materials: usize,
    spans: &mut Spans,
) -> Result<()> {
    let p = format!("mesh[{i}]");
    let r = m.get_ref();
    spans.insert(p.clone(), m.span());
    let transform = mesh_transform(src, r, &p)?;
    let material = match &r.material {
        Some(name) => Some(lookup(
            src,
            &scene.materials[..toml_materials],
            name,
            &format!("{p}.material"),
        )?),
        None => None,
    };
    let fpath = format!("{p}.file");
    let file = r.file.get_ref();
    if file.trim().is_empty() {
        return Err(src.error(r.file.span(), Some(&fpath), "must name an OBJ file"));
    }
    let before = scene.materials.len();
    obj::import(
        scene,
        &base.join(file),
        &ObjImport { transform, material },
        MAX_TRIANGLES,
        true,
    )
    .map_err(|e| src.error(r.file.span(), Some(&fpath), format!("{e:#}")))?;
    if r.face_normals == Some(true) {
        if let Some(mesh) = scene.meshes.last_mut() {
            mesh.normals = None;
        }
    }
    // Imported materials are located at the mesh that brought them.
    for k in before..scene.materials.len() {
        spans.insert(format!("materials.{}", scene.materials[k].name), r.file.span());
    }
    Ok(())
}

fn finite_all(src: &Source, values: &[f64], span: Range<usize>, path: &str) -> Result<()> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        let list: Vec<String> = values.iter().map(|v| v.to_string()).collect();
        Err(src.error(
            span,
            Some(path),
            format!("every component must be finite, got [{}]", list.join(", ")),
        ))
    }
}

/// Object to world: `matrix`, or translate * rotate (z * y * x) * scale.
fn mesh_transform(src: &Source, r: &RawMesh, p: &str) -> Result<DAffine3> {
    if let Some(mx) = &r.matrix {
        let mp = format!("{p}.matrix");
        if r.translate.is_some() || r.rotate.is_some() || r.scale.is_some() {
            return Err(src.error(
                mx.span(),
                Some(&mp),
                "cannot be combined with translate, rotate or scale (the matrix is the whole \
                 transform)",
            ));
        }
        let rows = mx.get_ref();
        finite_all(src, rows.as_flattened(), mx.span(), &mp)?;
        if rows[3] != [0.0, 0.0, 0.0, 1.0] {
            return Err(src.error(
                mx.span(),
                Some(&mp),
                format!(
                    "the last row must be [0, 0, 0, 1] (an affine transform), got {:?}",
                    rows[3]
                ),
            ));
        }
        let col = |j: usize| DVec3::new(rows[0][j], rows[1][j], rows[2][j]);
        let m3 = DMat3::from_cols(col(0), col(1), col(2));
        let det = m3.determinant();
        // Scale-free, as for quads: the volume of the columns against the product of their lengths.
        let lengths = col(0).length() * col(1).length() * col(2).length();
        // Both finite: the entries are.
        if det.abs() <= 1e-6 * lengths {
            return Err(src.error(
                mx.span(),
                Some(&mp),
                format!("is not invertible (determinant {det}): it would flatten the mesh"),
            ));
        }
        return Ok(DAffine3::from_mat3_translation(m3, col(3)));
    }
    let translate = match &r.translate {
        Some(t) => {
            finite_all(src, t.get_ref(), t.span(), &format!("{p}.translate"))?;
            DVec3::from_array(*t.get_ref())
        }
        None => DVec3::ZERO,
    };
    let rotate = match &r.rotate {
        Some(a) => {
            finite_all(src, a.get_ref(), a.span(), &format!("{p}.rotate"))?;
            rotation(*a.get_ref())
        }
        None => DMat3::IDENTITY,
    };
    let scale = match &r.scale {
        Some(s) => {
            let sp = format!("{p}.scale");
            let v = match s.get_ref() {
                RawScale::Uniform(k) => [*k; 3],
                RawScale::PerAxis(a) => *a,
            };
            finite_all(src, &v, s.span(), &sp)?;
            if v.contains(&0.0) {
                return Err(src.error(s.span(), Some(&sp), "must be non-zero (a zero scale flattens the mesh)"));
            }
            DVec3::from_array(v)
        }
        None => DVec3::ONE,
    };
    Ok(DAffine3::from_mat3_translation(
        rotate * DMat3::from_diagonal(scale),
        translate,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::TempDir;

    const CORNELL: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/cornell-spheres.toml");
    const FURNACE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/furnace.toml");

    /// A valid scene; tests replace one line (1-based numbers in comments) to break it.
    const BASE: &str = r#"name = "t"
[camera]
eye = [0.0, 1.0, 3.0]
look_at = [0.0, 1.0, 0.0]
up = [0.0, 1.0, 0.0]
vfov = 45.0
resolution = [64, 48]

[materials.white]
diffuse = [0.5, 0.5, 0.5]
[materials.light]
emission = [10.0, 10.0, 10.0]
[materials.glass]
glass = 1.5

[[sphere]]
center = [0.0, 0.5, 0.0]
radius = 0.5
material = "glass"

[[sphere]]
center = [1.0, 0.5, 0.0]
radius = 0.25
material = "white"

[[quad]]
origin = [-1.0, 0.0, -1.0]
edge_u = [0.0, 0.0, 2.0]
edge_v = [2.0, 0.0, 0.0]
material = "white"

[[quad]]
origin = [-0.25, 2.0, -0.25]
edge_u = [0.5, 0.0, 0.0]
edge_v = [0.0, 0.0, 0.5]
material = "light"
"#;

    /// BASE with 1-based line `line` replaced by `with`.
    fn edit(line: usize, with: &str) -> String {
        let mut lines: Vec<&str> = BASE.lines().collect();
        lines[line - 1] = with;
        lines.join("\n") + "\n"
    }

    fn err(text: &str) -> String {
        match Scene::parse(text, "t.toml") {
            Ok(_) => panic!("expected an error for:\n{text}"),
            Err(e) => format!("{e:#}"),
        }
    }

    /// Asserts the error is located at `line` and names `path`.
    fn assert_err(text: &str, line: usize, path: &str, needle: &str) {
        let e = err(text);
        assert_located(&e, line, path, needle);
        assert!(!e.contains('\n'), "error {e:?} should be one line");
    }

    /// Asserts that error text `e` starts at `t.toml:line:`, names field `path` and contains `needle`.
    fn assert_located(e: &str, line: usize, path: &str, needle: &str) {
        let prefix = format!("t.toml:{line}:");
        assert!(e.starts_with(&prefix), "error {e:?} should start with {prefix:?}");
        assert!(
            e.contains(&format!(" {path}: ")),
            "error {e:?} should name field {path:?}"
        );
        assert!(e.contains(needle), "error {e:?} should contain {needle:?}");
    }

    #[test]
    fn base_parses() {
        let s = Scene::parse(BASE, "dir/t.toml").expect("base scene is valid");
        assert_eq!(s.name, "t");
        assert_eq!(s.camera.width, 64);
        assert_eq!(s.camera.height, 48);
        assert_eq!(s.camera.vfov_deg, 45.0);
        // Materials keep file order (not alphabetical).
        let names: Vec<&str> = s.materials.iter().map(|m| m.name.as_str()).collect();
        assert_eq!(names, ["white", "light", "glass"]);
        assert_eq!(s.materials[1].surface, Surface::Diffuse { albedo: Vec3::ZERO });
        assert!(s.materials[1].is_light());
        assert!(!s.materials[0].is_light());
        assert_eq!(s.materials[2].surface, Surface::Glass { ior: 1.5 });
        assert_eq!(s.spheres[0].material, 2);
        assert_eq!(s.spheres[1].material, 0);
        assert_eq!(s.quads[1].material, 1);
    }

    #[test]
    fn regions_are_fractions_of_the_image() {
        let region = |x0: &str, name: &str| {
            format!("{BASE}\n[[region]]\nname = \"{name}\"\nx0 = {x0}\ny0 = 0\nx1 = 0.5\ny1 = 1\n")
        };
        let s = Scene::parse(&region("0.25", "left"), "t.toml").expect("valid");
        assert_eq!(
            s.regions,
            [ImageRegion {
                name: "left".into(),
                x0: 0.25,
                y0: 0.0,
                x1: 0.5,
                y1: 1.0
            }]
        );
        // 64 x 48 pixels: x 16-31, all rows; at 6 x 4 the edge at 1.5 pixels rounds outward.
        assert_eq!(s.regions[0].pixels(64, 48), crate::Region::new("left", 16, 0, 16, 48));
        assert_eq!(s.regions[0].pixels(6, 4), crate::Region::new("left", 1, 0, 2, 4));
        // The region's table starts on line 38 (BASE has 36 lines and a blank one follows): x0 is line 40.
        assert_err(&region("0.5", "left"), 40, "region[0].x0", "0 <= x0 < x1 <= 1");
        assert_err(&region("-0.1", "left"), 40, "region[0].x0", "got x0 = -0.1");
        assert_err(&region("0.1", ""), 39, "region[0].name", "must not be empty");
        let twice = format!(
            "{}[[region]]\nname = \"left\"\nx0 = 0\ny0 = 0\nx1 = 1\ny1 = 1\n",
            region("0.1", "left")
        );
        assert_err(&twice, 45, "region[1].name", "named twice");
        let e = err(&format!("{BASE}\n[[region]]\nname = \"a\"\nx0 = 0\ny0 = 0\nx1 = 1\n"));
        assert!(e.contains("y1"), "{e}");
    }

    #[test]
    fn name_defaults_to_file_stem() {
        let s = Scene::parse(&edit(1, ""), "scenes/my-scene.toml").expect("valid");
        assert_eq!(s.name, "my-scene");
    }

    #[test]
    fn cornell_scene_matches_spec() {
        let s = Scene::load(Path::new(CORNELL)).expect("cornell-spheres.toml parses");
        assert_eq!(s.name, "cornell-spheres");
        let c = s.camera;
        assert_eq!(
            (c.eye, c.look_at, c.up),
            (Vec3::new(0.0, 1.0, 2.9), Vec3::new(0.0, 0.8, 0.0), Vec3::Y)
        );
        assert_eq!((c.vfov_deg, c.width, c.height), (50.0, 512, 512));

        let lights = s.lights();
        assert_eq!(lights.len(), 1);
        let light = s.quads[lights[0] as usize];
        assert_eq!(light.normal(), Vec3::new(0.0, -1.0, 0.0));
        assert!((light.area() - 0.25).abs() < 1e-6);
        let lm = &s.materials[light.material as usize];
        assert_eq!(lm.emission, Vec3::new(34.0, 30.0, 24.0));
        assert_eq!(
            lm.surface,
            Surface::Diffuse { albedo: Vec3::ZERO },
            "the light reflects nothing"
        );
        let lc = light.origin + 0.5 * (light.edge_u + light.edge_v);
        assert!((lc - Vec3::new(0.0, 1.99, -0.3)).length() < 1e-6);

        // Six walls, each facing the box centre, covering the 2 x 2 x 4 box.
        let walls: Vec<&Quad> = s
            .quads
            .iter()
            .filter(|q| !s.materials[q.material as usize].is_light())
            .collect();
        assert_eq!(walls.len(), 6);
        let centre = Vec3::new(0.0, 1.0, 1.0);
        for w in &walls {
            let wc = w.origin + 0.5 * (w.edge_u + w.edge_v);
            assert!(w.normal().dot(centre - wc) > 0.0, "wall {w:?} must face into the box");
        }
        let total: f32 = walls.iter().map(|w| w.area()).sum();
        assert!((total - 2.0 * (2.0 * 2.0 + 2.0 * 4.0 + 2.0 * 4.0)).abs() < 1e-4);
        assert_eq!(s.bounds(), (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 2.0, 3.0)));

        let albedo = |n: Vec3| {
            walls
                .iter()
                .find(|w| w.normal().abs_diff_eq(n, 1e-6))
                .map(|w| s.materials[w.material as usize].surface)
        };
        let white = Some(Surface::Diffuse {
            albedo: Vec3::new(0.725, 0.71, 0.68),
        });
        assert_eq!(albedo(Vec3::Y), white, "floor");
        assert_eq!(albedo(Vec3::NEG_Y), white, "ceiling");
        assert_eq!(albedo(Vec3::Z), white, "back wall");
        assert_eq!(albedo(Vec3::NEG_Z), white, "front wall");
        assert_eq!(
            albedo(Vec3::X),
            Some(Surface::Diffuse {
                albedo: Vec3::new(0.63, 0.065, 0.05)
            }),
            "left wall red"
        );
        assert_eq!(
            albedo(Vec3::NEG_X),
            Some(Surface::Diffuse {
                albedo: Vec3::new(0.14, 0.45, 0.091)
            }),
            "right wall green"
        );

        let sph: Vec<(Vec3, f32, Surface)> = s
            .spheres
            .iter()
            .map(|p| (p.center, p.radius, s.materials[p.material as usize].surface))
            .collect();
        assert_eq!(
            sph,
            [
                (
                    Vec3::new(-0.5, 0.4, -0.4),
                    0.4,
                    Surface::Mirror {
                        reflectance: Vec3::splat(0.95)
                    }
                ),
                (
                    Vec3::new(0.6, 0.3, -0.5),
                    0.3,
                    Surface::Diffuse {
                        albedo: Vec3::new(0.3, 0.5, 0.8)
                    }
                ),
                (Vec3::new(0.1, 0.35, 0.5), 0.35, Surface::Glass { ior: 1.5 }),
            ]
        );
        // Spheres rest on the floor.
        for p in &s.spheres {
            assert!((p.center.y - p.radius).abs() < 1e-6);
        }
    }

    #[test]
    fn furnace_scene_is_a_closed_emitting_box() {
        let s = Scene::load(Path::new(FURNACE)).expect("furnace.toml parses");
        assert_eq!((s.camera.width, s.camera.height), (64, 64));
        assert_eq!(s.quads.len(), 6);
        assert_eq!(s.lights().len(), 6);
        assert!(s.spheres.is_empty());
        let (lo, hi) = s.bounds();
        assert_eq!((lo, hi), (Vec3::splat(-1.0), Vec3::splat(1.0)));
        let eye = s.camera.eye;
        assert!(eye.cmpgt(lo).all() && eye.cmplt(hi).all(), "camera inside the box");
        let mut normals_sum = Vec3::ZERO;
        for q in &s.quads {
            let m = &s.materials[q.material as usize];
            assert_eq!(
                m.surface,
                Surface::Diffuse {
                    albedo: Vec3::splat(0.5)
                }
            );
            assert_eq!(m.emission, Vec3::ONE);
            assert!((q.area() - 4.0).abs() < 1e-6);
            let qc = q.origin + 0.5 * (q.edge_u + q.edge_v);
            assert!(q.normal().dot(-qc) > 0.0, "wall faces inward");
            normals_sum += q.normal();
        }
        assert!(normals_sum.length() < 1e-6, "six distinct axis walls");
    }

    #[test]
    fn quad_normal_and_area() {
        let q = Quad {
            origin: Vec3::ZERO,
            edge_u: Vec3::new(2.0, 0.0, 0.0),
            edge_v: Vec3::new(1.0, 3.0, 0.0),
            material: 0,
            disk: false,
        };
        assert_eq!(q.normal(), Vec3::Z);
        assert!((q.area() - 6.0).abs() < 1e-6);
        let flipped = Quad {
            edge_u: q.edge_v,
            edge_v: q.edge_u,
            ..q
        };
        assert_eq!(flipped.normal(), Vec3::NEG_Z);
        // The ellipse inscribed in it: pi / 4 of the parallelogram.
        let ellipse = Quad { disk: true, ..q };
        assert!((ellipse.area() - 1.5 * std::f32::consts::PI).abs() < 1e-6);
    }

    #[test]
    fn bounds_lights_scaled_resolution() {
        let s = Scene::parse(BASE, "t.toml").expect("valid");
        // Quad 0 spans x,z in [-1,1] at y=0; the light tops out at y=2; spheres inside x <= 1.25.
        assert_eq!(s.bounds(), (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.25, 2.0, 1.0)));
        assert_eq!(s.lights(), vec![1]);

        let k = 2.5;
        let t = s.scaled(k);
        assert_eq!(t.bounds(), (s.bounds().0 * k, s.bounds().1 * k));
        assert_eq!(t.camera.eye, s.camera.eye * k);
        assert_eq!(t.camera.look_at, s.camera.look_at * k);
        assert_eq!(t.camera.up, s.camera.up);
        assert_eq!(t.camera.vfov_deg, s.camera.vfov_deg);
        assert_eq!(t.spheres[1].radius, 0.25 * k);
        assert!((t.quads[1].area() - s.quads[1].area() * k * k).abs() < 1e-5);
        assert_eq!(t.quads[1].normal(), s.quads[1].normal());
        assert_eq!(t.materials, s.materials, "emission and albedo unchanged");

        let r = s.with_resolution(7, 3);
        assert_eq!((r.camera.width, r.camera.height), (7, 3));
        assert_eq!(Scene { camera: s.camera, ..r }, s);
    }

    #[test]
    fn missing_file_names_path() {
        let e = format!(
            "{:#}",
            Scene::load(Path::new("/nonexistent/dir/nope.toml")).unwrap_err()
        );
        assert!(e.contains("/nonexistent/dir/nope.toml"), "{e}");
    }

    #[test]
    fn load_errors_carry_the_path() {
        let dir = std::env::temp_dir().join(format!("ppm-scene-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let path = dir.join("bad.toml");
        std::fs::write(&path, edit(18, "radius = -0.3")).expect("write temp file");
        let e = format!("{:#}", Scene::load(&path).unwrap_err());
        let _ = std::fs::remove_dir_all(&dir);
        assert!(
            e.starts_with(&format!(
                "{}:18:10: sphere[0].radius: must be positive and finite, got -0.3",
                path.display()
            )),
            "{e}"
        );
    }

    #[test]
    fn empty_file() {
        for text in ["", "   \n\n", "# only a comment\n"] {
            let e = err(text);
            assert!(e.starts_with("t.toml:1:1: ") && e.contains("empty"), "{e}");
        }
    }

    #[test]
    fn syntax_error() {
        // An unclosed array is detected on the next line. Text that is not TOML has no field yet: the
        // error gives the line and column and toml's message.
        let e = err(&edit(10, "diffuse = [0.5, 0.5"));
        assert!(e.starts_with("t.toml:11:1: ") && e.contains("expected `]`"), "{e}");
        let e = err(&edit(5, "up = 0.0, 1.0"));
        assert!(e.starts_with("t.toml:5:"), "{e}");
        // Duplicate table is a TOML error, located at the second header.
        let e = err(&edit(9, "[materials.light]"));
        assert!(
            e.starts_with("t.toml:11:") && e.contains("duplicate key `light`"),
            "{e}"
        );
    }

    #[test]
    fn wrong_types_and_missing_fields() {
        assert_err(&edit(18, "radius = \"big\""), 18, "sphere[0].radius", "invalid type");
        assert_err(&edit(23, "radius = true"), 23, "sphere[1].radius", "invalid type");
        // Inside an array: the element, at its column.
        assert_err(&edit(7, "resolution = [64, -48]"), 7, "camera.resolution[1]", "");
        assert!(err(&edit(7, "resolution = [64, -48]")).starts_with("t.toml:7:19:"));
        assert_err(&edit(3, "eye = [0.0, 1.0]"), 3, "camera.eye", "length 2");
        // Missing field: located at the table header.
        assert_err(&edit(23, ""), 21, "sphere[1]", "missing field `radius`");
        assert_err(&edit(6, ""), 2, "camera", "missing field `vfov`");
        let e = err(&BASE.replace("[camera]", "[kamera]"));
        assert!(e.contains("unknown field `kamera`"), "{e}");
        let no_camera: String = BASE
            .lines()
            .enumerate()
            .filter(|(i, _)| !(1..=6).contains(i))
            .map(|(_, l)| format!("{l}\n"))
            .collect();
        // Reported at the document root, not at `name` on line 1.
        assert_eq!(err(&no_camera), "t.toml:1:1: missing field `camera`");
    }

    #[test]
    fn unknown_keys() {
        assert_err(
            &edit(30, "colour = \"white\""),
            30,
            "quad[0].colour",
            "unknown field `colour`",
        );
        assert_err(
            &edit(10, "difuse = [0.5, 0.5, 0.5]"),
            10,
            "materials.white.difuse",
            "unknown field `difuse`",
        );
        assert_err(&edit(1, "title = \"x\""), 1, "title", "unknown field `title`");
    }

    #[test]
    fn unknown_material_names_known_ones() {
        assert_err(
            &edit(24, "material = \"whit\""),
            24,
            "sphere[1].material",
            "unknown material \"whit\" (known: \"white\", \"light\", \"glass\")",
        );
        assert_err(
            &edit(36, "material = \"lamp\""),
            36,
            "quad[1].material",
            "unknown material \"lamp\"",
        );
    }

    #[test]
    fn bad_radius() {
        assert_err(
            &edit(18, "radius = -0.3"),
            18,
            "sphere[0].radius",
            "must be positive and finite, got -0.3",
        );
        assert_err(&edit(18, "radius = 0.0"), 18, "sphere[0].radius", "must be positive");
        assert_err(&edit(23, "radius = nan"), 23, "sphere[1].radius", "got NaN");
        assert_err(&edit(23, "radius = inf"), 23, "sphere[1].radius", "got inf");
        // Overflows f32 to infinity.
        assert_err(
            &edit(23, "radius = 1e300"),
            23,
            "sphere[1].radius",
            "must be positive and finite",
        );
    }

    #[test]
    fn non_finite_vectors_refused_everywhere() {
        let cases = [
            (3, "eye = [nan, 1.0, 3.0]", "camera.eye"),
            (4, "look_at = [0.0, inf, 0.0]", "camera.look_at"),
            (5, "up = [0.0, 1.0, -inf]", "camera.up"),
            (10, "diffuse = [0.5, nan, 0.5]", "materials.white.diffuse"),
            (12, "emission = [inf, 1.0, 1.0]", "materials.light.emission"),
            (17, "center = [0.0, nan, 0.0]", "sphere[0].center"),
            (27, "origin = [nan, 0.0, -1.0]", "quad[0].origin"),
            (28, "edge_u = [0.0, 0.0, inf]", "quad[0].edge_u"),
            (35, "edge_v = [0.0, 0.0, nan]", "quad[1].edge_v"),
        ];
        for (line, text, path) in cases {
            assert_err(&edit(line, text), line, path, "must be finite");
        }
        assert_err(&edit(14, "glass = nan"), 14, "materials.glass.glass", "finite");
    }

    #[test]
    fn albedo_and_reflectance_range() {
        assert_err(
            &edit(10, "diffuse = [0.5, 1.2, 0.5]"),
            10,
            "materials.white.diffuse",
            "in [0, 1], got [0.5, 1.2, 0.5]",
        );
        assert_err(
            &edit(10, "diffuse = [-0.1, 0.5, 0.5]"),
            10,
            "materials.white.diffuse",
            "in [0, 1]",
        );
        assert_err(
            &edit(10, "mirror = [1.5, 0.5, 0.5]"),
            10,
            "materials.white.mirror",
            "in [0, 1]",
        );
    }

    #[test]
    fn bad_emission() {
        assert_err(
            &edit(12, "emission = [1.0, -1.0, 1.0]"),
            12,
            "materials.light.emission",
            ">= 0",
        );
        // Emission with a specular surface is refused; with diffuse it is fine.
        let text = BASE.replace("glass = 1.5", "glass = 1.5\nemission = [1.0, 1.0, 1.0]");
        assert_err(
            &text,
            15,
            "materials.glass.emission",
            "not with mirror, glass, conductor, plastic, thin or rough_glass",
        );
        let text = BASE.replace(
            "diffuse = [0.5, 0.5, 0.5]",
            "diffuse = [0.5, 0.5, 0.5]\nemission = [1.0, 1.0, 1.0]",
        );
        // Sphere 1 (line 24, one line lower now) uses "white", which now emits: a glowing sphere.
        let s = Scene::parse(&text, "t.toml").expect("an emitting sphere");
        assert!(s.materials[s.spheres[1].material as usize].is_light());
        let text = text.replace(
            "radius = 0.25\nmaterial = \"white\"",
            "radius = 0.25\nmaterial = \"glass\"",
        );
        let s = Scene::parse(&text, "t.toml").expect("emitting diffuse quad material is valid");
        assert_eq!(s.materials[0].emission, Vec3::ONE);
        assert_eq!(
            s.materials[0].surface,
            Surface::Diffuse {
                albedo: Vec3::splat(0.5)
            }
        );
        assert_eq!(s.lights(), vec![0, 1]);
    }

    #[test]
    fn emitting_spheres_load() {
        let s = Scene::parse(&edit(19, "material = \"light\""), "t.toml").expect("a glowing sphere");
        let m = &s.materials[s.spheres[0].material as usize];
        assert_eq!(m.emission, Vec3::splat(10.0));
        assert_eq!(m.surface, Surface::Diffuse { albedo: Vec3::ZERO });
        // Without the emitting quad, the sphere alone lights the scene.
        let mut lines: Vec<&str> = BASE.lines().collect();
        lines[18] = "material = \"light\"";
        lines[35] = "material = \"white\"";
        let s = Scene::parse(&lines.join("\n"), "t.toml").expect("a sphere is the only light");
        assert!(s.lights().is_empty() && s.materials[s.spheres[0].material as usize].is_light());
    }

    #[test]
    fn material_kind_conflicts() {
        let text = BASE.replace("glass = 1.5", "glass = 1.5\nmirror = [0.9, 0.9, 0.9]");
        assert_err(&text, 14, "materials.glass.glass", "cannot be both mirror and glass");
        let text = BASE.replace("glass = 1.5", "glass = 1.5\ndiffuse = [0.9, 0.9, 0.9]");
        assert_err(
            &text,
            14,
            "materials.glass.glass",
            "exactly one of diffuse, mirror, glass, conductor",
        );
        let text = BASE.replace("glass = 1.5", "glass = 1.5\nconductor = \"Au\"");
        assert_err(&text, 15, "materials.glass.conductor", "both glass and conductor");
        // A material with nothing in it.
        assert_err(
            &edit(14, ""),
            13,
            "materials.glass",
            "needs one of diffuse, mirror, glass",
        );
        assert_err(&edit(14, "glass = 0.9"), 14, "materials.glass.glass", ">= 1");
    }

    #[test]
    fn plastics_and_thin_dielectrics() {
        let surface = |line: &str| {
            let text = BASE.replace("glass = 1.5", line);
            let s = Scene::parse(&text, "t.toml").unwrap_or_else(|e| panic!("{line}: {e}"));
            s.materials.iter().find(|m| m.name == "glass").unwrap().surface
        };
        assert_eq!(
            surface("plastic = {}"),
            Surface::Plastic {
                diffuse: Vec3::splat(0.5),
                specular: Vec3::ONE,
                ior: PLASTIC_IOR,
                nonlinear: false,
                rough: None
            }
        );
        assert_eq!(
            surface("plastic = { diffuse = [0.1, 0.2, 0.3], specular = [0.5, 0.5, 0.5], ior = 1.6, nonlinear = true }"),
            Surface::Plastic {
                diffuse: Vec3::new(0.1, 0.2, 0.3),
                specular: Vec3::splat(0.5),
                ior: 1.6,
                nonlinear: true,
                rough: None
            }
        );
        assert_eq!(
            surface("thin = {}"),
            Surface::ThinDielectric {
                ior: THIN_IOR,
                reflectance: Vec3::ONE,
                transmittance: Vec3::ONE
            }
        );
        assert_eq!(
            surface("thin = { ior = 1.33, reflectance = [0.5, 0.5, 0.5], transmittance = [0.9, 0.8, 0.7] }"),
            Surface::ThinDielectric {
                ior: 1.33,
                reflectance: Vec3::splat(0.5),
                transmittance: Vec3::new(0.9, 0.8, 0.7)
            }
        );
        // Rough plastic: a coat of roughness alpha (Mitsuba's roughplastic, Beckmann by default).
        assert_eq!(
            surface(r#"plastic = { alpha = 0.2, distribution = "ggx" }"#),
            Surface::Plastic {
                diffuse: Vec3::splat(0.5),
                specular: Vec3::ONE,
                ior: PLASTIC_IOR,
                nonlinear: false,
                rough: Some(Microfacet::isotropic(true, 0.2))
            }
        );
        assert_err(
            &edit(14, r#"plastic = { distribution = "ggx" }"#),
            14,
            "materials.glass.plastic",
            "needs alpha",
        );
        // Anisotropic: alpha = [alpha_u, alpha_v].
        assert_eq!(
            surface(r#"rough_glass = { alpha = [0.05, 0.3] }"#).rough(),
            Some(Microfacet {
                ggx: false,
                alpha: 0.05,
                alpha_v: 0.3
            })
        );
        // Rough surfaces: Mitsuba's defaults (Beckmann, alpha 0.1, BK7 in air) and GGX.
        assert_eq!(
            surface("rough_glass = {}"),
            Surface::RoughGlass {
                ior: THIN_IOR,
                rough: Microfacet::isotropic(false, 0.1)
            }
        );
        assert_eq!(
            surface(r#"rough_glass = { ior = 1.33, alpha = 0.3, distribution = "ggx" }"#),
            Surface::RoughGlass {
                ior: 1.33,
                rough: Microfacet::isotropic(true, 0.3)
            }
        );
        let (au_eta, au_k) = crate::conductors::named("Au").unwrap();
        assert_eq!(
            surface(r#"conductor = { material = "Au", alpha = 0.2, distribution = "ggx" }"#),
            Surface::RoughConductor {
                reflectance: Vec3::ONE,
                eta: au_eta,
                k: au_k,
                rough: Microfacet::isotropic(true, 0.2)
            }
        );
        assert_err(
            &edit(14, r#"conductor = { material = "Au", alpha = 0.0 }"#),
            14,
            "materials.glass.conductor.alpha",
            ">= 0.0001",
        );
        assert_err(
            &edit(14, r#"conductor = { material = "Au", distribution = "ggx" }"#),
            14,
            "materials.glass.conductor",
            "needs alpha",
        );
        assert_err(
            &edit(14, r#"rough_glass = { distribution = "phong" }"#),
            14,
            "materials.glass.rough_glass.distribution",
            "unknown variant",
        );
        assert_err(
            &edit(14, "rough_glass = { ior = 0.5 }"),
            14,
            "materials.glass.rough_glass.ior",
            ">= 1",
        );
        // Errors name the line and the field.
        assert_err(
            &edit(14, "plastic = { ior = -1.5 }"),
            14,
            "materials.glass.plastic.ior",
            "> 0",
        );
        assert_err(
            &edit(14, "plastic = { diffuse = [0.99, 0.5, 0.5] }"),
            14,
            "materials.glass.plastic.diffuse",
            "at most 0.9",
        );
        assert_err(
            &edit(14, "thin = { transmittance = [1.5, 0.5, 0.5] }"),
            14,
            "materials.glass.thin.transmittance",
            "",
        );
        assert_err(
            &edit(14, "thin = { roughness = 0.1 }"),
            14,
            "materials.glass.thin.roughness",
            "unknown field",
        );
        assert_err(
            &BASE.replace("glass = 1.5", "plastic = {}\nemission = [1.0, 1.0, 1.0]"),
            15,
            "materials.glass.emission",
            "not with mirror, glass, conductor, plastic, thin or rough_glass",
        );
    }

    #[test]
    fn conductors_by_name_or_by_eta_and_k() {
        let surface = |line: &str| {
            let text = BASE.replace("glass = 1.5", line);
            let s = Scene::parse(&text, "t.toml").unwrap_or_else(|e| panic!("{line}: {e}"));
            s.materials.iter().find(|m| m.name == "glass").unwrap().surface
        };
        let (eta, k) = crate::conductors::named("Au").unwrap();
        assert_eq!(
            surface("conductor = \"Au\""),
            Surface::Conductor {
                reflectance: Vec3::ONE,
                eta,
                k
            }
        );
        assert_eq!(
            surface("conductor = { material = \"Au\", reflectance = [0.5, 0.6, 0.7] }"),
            Surface::Conductor {
                reflectance: Vec3::new(0.5, 0.6, 0.7),
                eta,
                k
            }
        );
        assert_eq!(
            surface("conductor = { eta = [0.2, 0.3, 0.4], k = [3.0, 2.0, 1.0] }"),
            Surface::Conductor {
                reflectance: Vec3::ONE,
                eta: Vec3::new(0.2, 0.3, 0.4),
                k: Vec3::new(3.0, 2.0, 1.0)
            }
        );
        // Mitsuba's default, "none", is exactly a mirror: it becomes one.
        assert_eq!(surface("conductor = {}"), Surface::Mirror { reflectance: Vec3::ONE });
        assert_eq!(
            surface("conductor = \"none\""),
            Surface::Mirror { reflectance: Vec3::ONE }
        );
        assert_err(
            &edit(14, "conductor = \"Unobtainium\""),
            14,
            "materials.glass.conductor",
            "unknown conductor \"Unobtainium\"",
        );
        assert_err(
            &edit(14, "conductor = { eta = [1.0, 1.0, 1.0] }"),
            14,
            "materials.glass.conductor",
            "both eta and k",
        );
        assert_err(
            &edit(14, "conductor = { material = \"Au\", k = [1.0, 1.0, 1.0] }"),
            14,
            "materials.glass.conductor",
            "not both",
        );
        assert_err(
            &edit(14, "conductor = { eta = [1.0, -1.0, 1.0], k = [1.0, 1.0, 1.0] }"),
            14,
            "materials.glass.conductor.eta",
            ">= 0",
        );
        assert_err(
            &edit(14, "conductor = { eta = [0.0, 1.0, 1.0], k = [0.0, 1.0, 1.0] }"),
            14,
            "materials.glass.conductor",
            "no such metal",
        );
    }

    #[test]
    fn degenerate_quads() {
        assert_err(
            &edit(29, "edge_v = [0.0, 0.0, 1.0]"),
            29,
            "quad[0].edge_v",
            "parallel to edge_u",
        );
        assert_err(
            &edit(29, "edge_v = [0.0, 0.0, -3.0]"),
            29,
            "quad[0].edge_v",
            "zero-area",
        );
        assert_err(
            &edit(28, "edge_u = [0.0, 0.0, 0.0]"),
            28,
            "quad[0].edge_u",
            "zero length",
        );
        assert_err(
            &edit(35, "edge_v = [0.0, 0.0, 0.0]"),
            35,
            "quad[1].edge_v",
            "zero length",
        );
        // Nearly parallel at the scale of the edges, though the raw cross product is not tiny.
        assert_err(
            &edit(29, "edge_v = [1e-9, 0.0, 1000.0]"),
            29,
            "quad[0].edge_v",
            "parallel",
        );
        // Small but well-shaped quads are fine.
        let s = Scene::parse(
            &edit(28, "edge_u = [0.0, 0.0, 1e-4]").replace("edge_v = [2.0, 0.0, 0.0]", "edge_v = [1e-4, 0.0, 0.0]"),
            "t.toml",
        );
        assert!(s.is_ok(), "{s:?}");
    }

    #[test]
    fn bad_camera() {
        assert_err(&edit(6, "vfov = 0.0"), 6, "camera.vfov", "(0, 180)");
        assert_err(&edit(6, "vfov = 180.0"), 6, "camera.vfov", "got 180");
        assert_err(&edit(6, "vfov = -10"), 6, "camera.vfov", "(0, 180)");
        assert_err(&edit(6, "vfov = nan"), 6, "camera.vfov", "NaN");
        assert_err(&edit(6, "vfov = inf"), 6, "camera.vfov", "inf");
        assert_err(&edit(7, "resolution = [0, 48]"), 7, "camera.resolution", "1..=16384");
        assert_err(
            &edit(7, "resolution = [64, 20000]"),
            7,
            "camera.resolution",
            "1..=16384",
        );
        assert_err(
            &edit(4, "look_at = [0.0, 1.0, 3.0]"),
            4,
            "camera.look_at",
            "must differ from camera.eye",
        );
        assert_err(
            &edit(5, "up = [0.0, 0.0, -2.0]"),
            5,
            "camera.up",
            "parallel to the view direction",
        );
        assert_err(&edit(5, "up = [0.0, 0.0, 0.0]"), 5, "camera.up", "non-zero");
    }

    #[test]
    fn no_light() {
        let e = err(&edit(36, "material = \"white\""));
        assert!(e.contains("no light: nothing to render"), "{e}");
        assert!(e.starts_with("t.toml:"), "{e}");
        // No quads at all: same message.
        let text = BASE.split("[[quad]]").next().unwrap_or("").to_string();
        assert!(err(&text).contains("no light: nothing to render"));
    }

    #[test]
    fn multiline_arrays_keep_the_key_path() {
        let text = edit(17, "center = [\n  0.0,\n  nan,\n  0.0,\n]");
        assert_err(&text, 17, "sphere[0].center", "finite");
        // A type error inside the multi-line array: reported on its own line, same key.
        let text = edit(17, "center = [\n  0.0,\n  \"x\",\n  0.0,\n]");
        let e = err(&text);
        assert!(e.contains("sphere[0].center"), "{e}");
    }

    #[test]
    fn inline_tables_are_located_exactly() {
        // A type error inside an inline table: the path and column of the value itself.
        let text = edit(10, "white = { diffuse = [0.5, \"x\", 0.5] }").replace("[materials.white]\n", "[materials]\n");
        let e = Scene::parse(&text, "t.toml").expect_err("a string in an albedo");
        match &e {
            Error::Scene {
                line, column, field, ..
            } => {
                assert_eq!((*line, field.as_str()), (10, "materials.white.diffuse[1]"), "{e}");
                assert_eq!(*column, 27, "the column of \"x\": {e}");
            }
            other => panic!("expected a scene error, got {other:?}"),
        }
        // Spheres as an inline array of inline tables: a missing field names its table.
        let spheres = "sphere = [{ center = [0.0, 0.5, 0.0], radius = 0.5, material = \"white\" },\n\
                       { center = [1.0, 0.5, 0.0], material = \"white\" }]\n";
        let text = BASE.replace("[camera]", &format!("{spheres}[camera]"));
        let text = text.replace("[[sphere]]", "[[ignored]]");
        let text: String =
            text.split("[[ignored]]").next().unwrap().to_string() + &BASE[BASE.find("[[quad]]").unwrap()..];
        assert_err(&text, 3, "sphere[1]", "missing field `radius`");
        // A value check after parsing, in an inline table: located at the value.
        let text = text.replace("radius = 0.5", "radius = -0.5");
        let text = text.replace(
            "{ center = [1.0, 0.5, 0.0], material",
            "{ center = [1.0, 0.5, 0.0], radius = 1.0, material",
        );
        assert_err(&text, 2, "sphere[0].radius", "positive");
    }

    #[test]
    fn line_and_column() {
        let src = Source {
            origin: "o",
            text: "ab\ncdé\nf",
        };
        assert_eq!(src.line_col(0), (1, 1));
        assert_eq!(src.line_col(3), (2, 1));
        assert_eq!(src.line_col(7), (2, 4));
        assert_eq!(src.line_col(8), (3, 1));
        assert_eq!(src.line_col(100), (3, 2));
    }

    // --- [[mesh]] ---

    /// A triangle in the yz plane (front normal -x) with one grey MTL material.
    const OBJ: &str = "mtllib a.mtl\nusemtl m\nv 0 1 0\nv 0 0 0\nv 0 0 1\nf 1 2 3\n";

    /// BASE (36 lines) and a blank line, then `[[mesh]]` on line 38 and `lines` from line 39,
    /// parsed as `<dir>/t.toml`; `a.obj` and `a.mtl` are written into `dir`.
    fn with_mesh(dir: &TempDir, lines: &str) -> Result<Scene> {
        dir.write("a.obj", OBJ);
        dir.write("a.mtl", "newmtl m\nKd 0.5 0.5 0.5\n");
        let text = format!("{BASE}\n[[mesh]]\n{lines}\n");
        Scene::parse(&text, &dir.0.join("t.toml").display().to_string())
    }

    /// The error of [`with_mesh`], the temp dir cut out; asserts line and field as `assert_err`.
    fn assert_mesh_err(lines: &str, line: usize, path: &str, needle: &str) {
        let dir = TempDir::new("toml-mesh");
        let e = match with_mesh(&dir, lines) {
            Ok(_) => panic!("expected an error for\n{lines}"),
            Err(e) => format!("{e:#}").replace(&format!("{}/", dir.0.display()), ""),
        };
        assert_located(&e, line, path, needle);
    }

    fn positions(s: &Scene) -> Vec<Vec3> {
        s.meshes[0].positions.clone()
    }

    #[test]
    fn mesh_transform_scales_then_rotates_then_translates() {
        let dir = TempDir::new("toml-mesh");
        let s = with_mesh(
            &dir,
            "file = \"a.obj\"\nscale = 2\nrotate = [90, 90, 0]\ntranslate = [1, 2, 3]",
        )
        .expect("valid");
        // Scale 2, then x by 90 degrees, then y by 90 (R = Ry Rx), then the translation.
        let want = [
            Vec3::new(3.0, 2.0, 3.0),
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(1.0, 0.0, 3.0),
        ];
        for (p, w) in positions(&s).iter().zip(want) {
            assert!(p.abs_diff_eq(w, 1e-6), "{p} against {w}");
        }
        assert_eq!(s.meshes[0].name, dir.0.join("a.obj").display().to_string());
        let m = &s.materials[s.meshes[0].materials[0] as usize];
        assert_eq!(m.name, format!("{}:m", dir.0.join("a.obj").display()));
        assert_eq!(s.triangle_count(), 1);
        // The same transform as a matrix (rows, acting on [x, y, z, 1]).
        let s2 = with_mesh(
            &dir,
            "file = \"a.obj\"\nmatrix = [\n  [0, 2, 0, 1],\n  [0, 0, -2, 2],\n  [-2, 0, 0, 3],\n  [0, 0, 0, 1],\n]",
        )
        .expect("valid");
        for (p, w) in positions(&s2).iter().zip(want) {
            assert!(p.abs_diff_eq(w, 1e-6), "{p} against {w}");
        }
        // No transform: the file's coordinates.
        let s3 = with_mesh(&dir, "file = \"a.obj\"").expect("valid");
        assert_eq!(positions(&s3), [Vec3::Y, Vec3::ZERO, Vec3::Z]);
        assert_eq!(s3.meshes[0].triangle(0).normal(), Vec3::NEG_X);
        // A mirroring scale keeps the front side.
        let s4 = with_mesh(&dir, "file = \"a.obj\"\nscale = [1, -1, 1]").expect("valid");
        assert_eq!(s4.meshes[0].triangle(0).normal(), Vec3::NEG_X);
        assert!(positions(&s4).contains(&Vec3::NEG_Y));
    }

    #[test]
    fn mesh_material_override_and_relative_paths() {
        let dir = TempDir::new("toml-mesh");
        std::fs::create_dir_all(dir.0.join("meshes")).expect("mkdir");
        // No MTL next to this one: the override means it is not looked for.
        dir.write(
            "meshes/b.obj",
            "mtllib gone.mtl\nusemtl x\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        );
        let s = with_mesh(&dir, "file = \"meshes/b.obj\"\nmaterial = \"glass\"").expect("valid");
        assert_eq!(s.meshes[0].materials, [2]);
        assert_eq!(s.materials.len(), 3, "no MTL material added");
        // A mesh may be the only light.
        dir.write(
            "lamp.obj",
            "mtllib lamp.mtl\nusemtl lamp\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        );
        dir.write("lamp.mtl", "newmtl lamp\nKe 2 2 2\n");
        let text = edit(36, "material = \"white\"") + "[[mesh]]\nfile = \"lamp.obj\"\n";
        let s = Scene::parse(&text, &dir.0.join("t.toml").display().to_string()).expect("valid");
        assert!(s.lights().is_empty());
        assert_eq!(s.emitting_triangles().len(), 1);
        // Nothing emits at all: located at the first quad, as before meshes.
        dir.write("lamp.mtl", "newmtl lamp\nKd 0.5 0.5 0.5\n");
        let e = format!(
            "{:#}",
            Scene::parse(&text, &dir.0.join("t.toml").display().to_string()).unwrap_err()
        );
        assert!(e.contains("t.toml:26:1: no light"), "{e}");
    }

    /// An OBJ's vertex normals shade it smooth; `face_normals = true` shades it flat; an OBJ without
    /// normals stays flat (the TOML format computes none, unlike Mitsuba's reader).
    #[test]
    fn face_normals_shade_a_mesh_flat() {
        let dir = TempDir::new("toml-face-normals");
        dir.write(
            "n.obj",
            "mtllib a.mtl\nusemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n",
        );
        dir.write(
            "flat.obj",
            "mtllib a.mtl\nusemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        );
        let smooth = with_mesh(&dir, "file = \"n.obj\"").expect("valid");
        assert_eq!(smooth.meshes[0].normals.as_deref(), Some(&[Vec3::Z; 3][..]));
        let flat = with_mesh(&dir, "file = \"n.obj\"\nface_normals = true").expect("valid");
        assert_eq!(flat.meshes[0].normals, None);
        let none = with_mesh(&dir, "file = \"flat.obj\"\nface_normals = false").expect("valid");
        assert_eq!(none.meshes[0].normals, None);
    }

    #[test]
    fn mesh_errors_name_line_and_field() {
        let f = "file = \"a.obj\"\n";
        assert_mesh_err(&format!("{f}scale = 0"), 40, "mesh[0].scale", "must be non-zero");
        assert_mesh_err(
            &format!("{f}scale = [1, 0, 1]"),
            40,
            "mesh[0].scale",
            "must be non-zero",
        );
        assert_mesh_err(
            &format!("{f}scale = \"big\""),
            40,
            "mesh[0].scale",
            "a number or an array of 3 numbers",
        );
        assert_mesh_err(
            &format!("{f}scale = [1, nan, 1]"),
            40,
            "mesh[0].scale",
            "must be finite",
        );
        assert_mesh_err(
            &format!("{f}translate = [nan, 0, 0]"),
            40,
            "mesh[0].translate",
            "must be finite, got [NaN, 0, 0]",
        );
        assert_mesh_err(
            &format!("{f}rotate = [0, inf, 0]"),
            40,
            "mesh[0].rotate",
            "must be finite",
        );
        assert_mesh_err(&format!("{f}rotate = [0, 0]"), 40, "mesh[0].rotate", "length 2");
        let identity = "matrix = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]";
        assert_mesh_err(
            &format!("{f}translate = [1, 0, 0]\n{identity}"),
            41,
            "mesh[0].matrix",
            "cannot be combined with translate, rotate or scale",
        );
        assert_mesh_err(
            &format!("{f}{}", identity.replace("[0, 0, 1, 0]", "[0, 0, 0, 0]")),
            40,
            "mesh[0].matrix",
            "is not invertible (determinant 0)",
        );
        assert_mesh_err(
            &format!("{f}{}", identity.replace("[0, 0, 1, 0]", "[1, 1, 0, 0]")),
            40,
            "mesh[0].matrix",
            "is not invertible",
        );
        assert_mesh_err(
            &format!("{f}{}", identity.replace("[0, 1, 0, 0]", "[0, nan, 0, 0]")),
            40,
            "mesh[0].matrix",
            "must be finite",
        );
        assert_mesh_err(
            &format!("{f}{}", identity.replace("[0, 0, 0, 1]]", "[0, 0, 1, 1]]")),
            40,
            "mesh[0].matrix",
            "the last row must be [0, 0, 0, 1]",
        );
        assert_mesh_err(
            &format!("{f}rotation = [0, 0, 0]"),
            40,
            "mesh[0].rotation",
            "unknown field `rotation`",
        );
        assert_mesh_err(
            &format!("{f}material = \"nope\""),
            40,
            "mesh[0].material",
            "unknown material \"nope\" (known: \"white\", \"light\", \"glass\")",
        );
        assert_mesh_err("scale = 1", 38, "mesh[0]", "missing field `file`");
        assert_mesh_err("file = \"\"", 39, "mesh[0].file", "must name an OBJ file");
        assert_mesh_err(
            "file = \"none.obj\"",
            39,
            "mesh[0].file",
            "none.obj: cannot read OBJ file: ",
        );
        // What the OBJ loader finds is reported under the mesh's `file`, with the OBJ's own line.
        let dir = TempDir::new("toml-mesh");
        dir.write("bad.obj", "mtllib a.mtl\nusemtl m\nv 0 0 0\nf 1 2 3\n");
        let e = format!("{:#}", with_mesh(&dir, "file = \"bad.obj\"").unwrap_err());
        let want = format!(
            "{0}/t.toml:39:8: mesh[0].file: {0}/bad.obj:4: vertex index 2 out of range (1 in the file)",
            dir.0.display()
        );
        assert_eq!(e, want);
    }

    /// `dir` with `tex/t.png` (2 x 1: white, then sRGB (128, 64, 0)), a corrupt PNG and an EXR above 1.
    fn texture_dir() -> TempDir {
        let dir = TempDir::new("toml-tex");
        std::fs::create_dir_all(dir.0.join("tex")).unwrap();
        texture::write_png(&dir.0.join("tex/t.png"), 2, 1, &[255, 255, 255, 128, 64, 0]);
        dir.write("corrupt.png", "not a PNG at all");
        image::Rgb32FImage::from_raw(1, 1, vec![0.5, 2.0, 0.5])
            .unwrap()
            .save(dir.0.join("bright.exr"))
            .unwrap();
        dir
    }

    /// BASE with line `line` replaced by `with` (and `more` appended), parsed as `<dir>/t.toml`.
    fn in_dir(dir: &TempDir, line: usize, with: &str, more: &str) -> Result<Scene> {
        Scene::parse(
            &format!("{}{more}", edit(line, with)),
            &dir.0.join("t.toml").display().to_string(),
        )
    }

    fn assert_dir_err(dir: &TempDir, line: usize, with: &str, at: usize, path: &str, needle: &str) {
        let e = match in_dir(dir, line, with, "") {
            Ok(_) => panic!("expected an error for {with}"),
            Err(e) => format!("{e:#}").replace(&format!("{}/", dir.0.display()), ""),
        };
        assert_located(&e, at, path, needle);
    }

    #[test]
    fn diffuse_and_plastic_textures() {
        let dir = texture_dir();
        let s = in_dir(&dir, 10, r#"diffuse = { texture = "tex/t.png" }"#, "").unwrap_or_else(|e| panic!("{e:#}"));
        let white = &s.materials[0];
        let t = &s.textures[white.texture.unwrap() as usize];
        assert!(t.name.ends_with("tex/t.png"), "{}", t.name);
        assert_eq!(
            (t.filter, t.wrap, t.to_uv),
            (Filter::Bilinear, Wrap::Repeat, texture::IDENTITY_UV)
        );
        let dark = Vec3::new(
            texture::srgb_to_linear(128.0 / 255.0),
            texture::srgb_to_linear(64.0 / 255.0),
            0.0,
        );
        assert_eq!(
            t.pattern,
            Pattern::Bitmap {
                width: 2,
                height: 1,
                pixels: vec![Vec3::ONE, dark]
            }
        );
        assert_eq!(white.surface, Surface::Diffuse { albedo: Vec3::ONE });

        let s = in_dir(
            &dir,
            10,
            r#"diffuse = { texture = "tex/t.png", filter = "nearest", wrap = "mirror", raw = true, scale = [4, 2] }"#,
            "",
        )
        .unwrap_or_else(|e| panic!("{e:#}"));
        let t = &s.textures[0];
        assert_eq!(
            (t.filter, t.wrap, t.to_uv),
            (Filter::Nearest, Wrap::Mirror, [4.0, 0.0, 0.0, 0.0, 2.0, 0.0])
        );
        assert!(
            matches!(&t.pattern, Pattern::Bitmap { pixels, .. } if (pixels[1].x - 128.0 / 255.0).abs() < 1e-6),
            "raw"
        );

        // A checkerboard on the diffuse material, the same image on a plastic and on a second material:
        // the image is stored once.
        let more = "[materials.plain]\ndiffuse = { texture = \"tex/t.png\" }\n";
        let s = in_dir(
            &dir,
            14,
            r#"plastic = { diffuse = { texture = "tex/t.png" }, ior = 1.2 }"#,
            more,
        );
        let e = format!("{:#}", s.unwrap_err());
        assert!(
            e.contains("materials.glass.plastic.diffuse: at most"),
            "white pixels exceed a plastic's bound: {e}"
        );
        let text = edit(
            14,
            r#"plastic = { diffuse = { texture = "tex/t.png", scale = [0.5, 0.5] } }"#,
        )
        .replace(
            "diffuse = [0.5, 0.5, 0.5]",
            "diffuse = { checkerboard = [[0.1, 0.2, 0.3], [0.5, 0.5, 0.5]], scale = [8, 8] }",
        );
        let text = format!("{text}{}", more.replace("t.png\"", "t.png\", scale = [0.5, 0.5]"));
        // A plastic's white pixels would exceed its bound: darker ones, through an EXR, are fine.
        image::Rgb32FImage::from_raw(1, 1, vec![0.5, 0.25, 0.125])
            .unwrap()
            .save(dir.0.join("tex/t.png.exr"))
            .unwrap();
        let text = text.replace("tex/t.png", "tex/t.png.exr");
        let s = Scene::parse(&text, &dir.0.join("t.toml").display().to_string()).unwrap_or_else(|e| panic!("{e:#}"));
        let m = |name: &str| s.materials.iter().find(|m| m.name == name).unwrap();
        assert_eq!(
            s.textures[m("white").texture.unwrap() as usize].pattern,
            Pattern::Checkerboard {
                color0: Vec3::new(0.1, 0.2, 0.3),
                color1: Vec3::splat(0.5)
            }
        );
        assert_eq!(
            s.textures[m("white").texture.unwrap() as usize].to_uv,
            [8.0, 0.0, 0.0, 0.0, 8.0, 0.0]
        );
        assert_eq!(
            m("white").surface,
            Surface::Diffuse {
                albedo: Vec3::splat(0.5)
            }
        );
        assert_eq!(m("glass").texture, m("plain").texture, "one image, stored once");
        assert_eq!(s.textures.len(), 2);
        assert!(
            matches!(m("glass").surface, Surface::Plastic { diffuse, .. } if diffuse == Vec3::new(0.5, 0.25, 0.125))
        );
    }

    #[test]
    fn texture_errors_name_line_and_field() {
        let dir = texture_dir();
        let cases: &[(&str, &str, &str)] = &[
            (
                r#"diffuse = { texture = "missing.png" }"#,
                "materials.white.diffuse.texture",
                "missing.png: cannot read the image",
            ),
            (
                r#"diffuse = { texture = "corrupt.png" }"#,
                "materials.white.diffuse.texture",
                "corrupt.png: not a readable PNG, JPEG or EXR image",
            ),
            (
                r#"diffuse = { texture = " " }"#,
                "materials.white.diffuse.texture",
                "must name an image file",
            ),
            (
                r#"diffuse = { texture = "tex/t.png", checkerboard = [[0.1, 0.1, 0.1], [0.2, 0.2, 0.2]] }"#,
                "materials.white.diffuse.checkerboard",
                "not both",
            ),
            (
                r#"diffuse = { filter = "nearest" }"#,
                "materials.white.diffuse",
                "needs texture = \"file.png\" or checkerboard",
            ),
            (
                r#"diffuse = { checkerboard = [[0.1, 0.1, 0.1], [0.2, 0.2, 0.2]], wrap = "clamp" }"#,
                "materials.white.diffuse.wrap",
                "applies to an image texture only",
            ),
            (
                r#"diffuse = { texture = "tex/t.png", filter = "cubic" }"#,
                "materials.white.diffuse.filter",
                "unknown variant `cubic`, expected `bilinear` or `nearest`",
            ),
            (
                r#"diffuse = { texture = "tex/t.png", tile = 2 }"#,
                "materials.white.diffuse.tile",
                "unknown field `tile`",
            ),
            (
                r#"diffuse = { texture = "tex/t.png", scale = [0, 1] }"#,
                "materials.white.diffuse.scale",
                "finite and non-zero",
            ),
            (
                r#"diffuse = { texture = "tex/t.png", scale = [1] }"#,
                "materials.white.diffuse.scale",
                "invalid length 1",
            ),
            (
                r#"diffuse = { checkerboard = [[0.1, 0.2, 1.5], [0.5, 0.5, 0.5]] }"#,
                "materials.white.texture",
                "texture \"checkerboard\": color0 is [0.1, 0.2, 1.5]: a reflectance must be finite and in [0, 1]",
            ),
            (
                r#"diffuse = { texture = "bright.exr" }"#,
                "materials.white.texture",
                "bright.exr\": pixel (0, 0) (column, row from the top) is [0.5, 2, 0.5]",
            ),
            ("diffuse = [0.5, 0.5]", "materials.white.diffuse", "invalid length 2"),
            (
                "diffuse = [0.5, 0.5, 0.5, 0.5, 0.5]",
                "materials.white.diffuse",
                "invalid length 5, expected 3 numbers",
            ),
            (
                "diffuse = [0.5, \"x\", 0.5]",
                "materials.white.diffuse[1]",
                "invalid type: string",
            ),
            (
                "diffuse = \"red\"",
                "materials.white.diffuse",
                "expected an array of 3 numbers [r, g, b], or a texture table",
            ),
        ];
        for (with, path, needle) in cases {
            assert_dir_err(&dir, 10, with, 10, path, needle);
        }
        assert_dir_err(
            &dir,
            14,
            "plastic = { diffuse = { checkerboard = [[0.99, 0.5, 0.5], [0.1, 0.1, 0.1]] } }",
            14,
            "materials.glass.plastic.diffuse",
            "at most 0.9",
        );
    }

    #[test]
    fn textured_meshes_get_flipped_texture_coordinates_or_are_refused() {
        let dir = texture_dir();
        dir.write("a.mtl", "newmtl m\nKd 0.5 0.5 0.5\n");
        dir.write("a.obj", OBJ);
        dir.write(
            "uv.obj",
            "v 0 1 0\nv 0 0 0\nv 0 0 1\nvt 0 0.25\nvt 1 0.5\nvt 0 1\nf 1/1 2/2 3/3\n",
        );
        let mesh = |file: &str| format!("\n[[mesh]]\nfile = \"{file}\"\nmaterial = \"white\"\n");
        let textured = r#"diffuse = { texture = "tex/t.png" }"#;
        let s = in_dir(&dir, 10, textured, &mesh("uv.obj")).unwrap_or_else(|e| panic!("{e:#}"));
        let m = &s.meshes[0];
        let uvs = m.uvs.as_ref().expect("every vertex has a vt");
        for (i, p) in m.positions.iter().enumerate() {
            let want = match p.to_array() {
                [0.0, 1.0, 0.0] => glam::Vec2::new(0.0, 0.75),
                [0.0, 0.0, 0.0] => glam::Vec2::new(1.0, 0.5),
                _ => glam::Vec2::new(0.0, 0.0),
            };
            assert_eq!(uvs[i], want, "{p}");
        }
        let e = format!("{:#}", in_dir(&dir, 10, textured, &mesh("a.obj")).unwrap_err());
        assert!(
            e.contains("t.toml:38:1: mesh[0]: ")
                && e.contains("a.obj: material \"white\" reads a texture, but the mesh has no texture coordinates"),
            "{e}"
        );
    }

    /// BASE with `lights` appended (its first line is line 38), parsed as `<dir>/t.toml`.
    fn with_lights(dir: &TempDir, lights: &str) -> Result<Scene> {
        Scene::parse(
            &format!("{BASE}\n{lights}"),
            &dir.0.join("t.toml").display().to_string(),
        )
    }

    fn lights(text: &str) -> Vec<Emitter> {
        with_lights(&TempDir::new("toml-lights"), text)
            .unwrap_or_else(|e| panic!("{e:#}"))
            .emitters
    }

    #[test]
    fn each_light_with_mitsubas_defaults() {
        let got = lights(
            "[[light]]\ntype = \"point\"\nposition = [0, 2, 0]\n\
             [[light]]\ntype = \"spot\"\nposition = [0, 2, 0]\ndirection = [0, -1, 0]\n\
             [[light]]\ntype = \"directional\"\ndirection = [0, 0, -3]\n\
             [[light]]\ntype = \"constant\"\n",
        );
        assert_eq!(
            got,
            [
                Emitter::Point {
                    position: Vec3::new(0.0, 2.0, 0.0),
                    intensity: Vec3::ONE
                },
                Emitter::Spot {
                    position: Vec3::new(0.0, 2.0, 0.0),
                    direction: Vec3::NEG_Y,
                    intensity: Vec3::ONE,
                    cutoff: 20f32.to_radians(),
                    beam: 15f32.to_radians()
                },
                Emitter::Directional {
                    direction: Vec3::NEG_Z,
                    irradiance: Vec3::ONE
                },
                Emitter::Environment(Environment {
                    scale: Vec3::ONE,
                    map: None,
                    to_world: Mat3::IDENTITY
                }),
            ]
        );
    }

    #[test]
    fn each_light_with_every_field() {
        let got = lights(
            "[[light]]\ntype = \"point\"\nposition = [1, 2, 3]\nintensity = 4\n\
             [[light]]\ntype = \"spot\"\nposition = [1, 4, 1]\ntarget = [1, 0, 1]\nintensity = [1, 2, 3]\n\
             cutoff_angle = 40\nbeam_width = 10\n\
             [[light]]\ntype = \"spot\"\nposition = [0, 0, 0]\ndirection = [1, 0, 0]\ncutoff_angle = 60\n\
             [[light]]\ntype = \"directional\"\ndirection = [1, -1, 0]\nirradiance = [0.5, 1, 2]\n\
             [[light]]\ntype = \"constant\"\nradiance = 0.25\n",
        );
        assert_eq!(
            got[0],
            Emitter::Point {
                position: Vec3::new(1.0, 2.0, 3.0),
                intensity: Vec3::splat(4.0)
            }
        );
        assert_eq!(
            got[1],
            Emitter::Spot {
                position: Vec3::new(1.0, 4.0, 1.0),
                direction: Vec3::NEG_Y,
                intensity: Vec3::new(1.0, 2.0, 3.0),
                cutoff: 40f32.to_radians(),
                beam: 10f32.to_radians()
            }
        );
        // The beam's default follows the cutoff given.
        let Emitter::Spot {
            direction,
            cutoff,
            beam,
            ..
        } = got[2]
        else {
            panic!("{:?}", got[2])
        };
        assert_eq!(
            (direction, cutoff, beam),
            (Vec3::X, 60f32.to_radians(), 45f32.to_radians())
        );
        let Emitter::Directional { direction, irradiance } = got[3] else {
            panic!("{:?}", got[3])
        };
        assert!(
            direction.distance(Vec3::new(1.0, -1.0, 0.0).normalize()) < 1e-6,
            "{direction}"
        );
        assert_eq!(irradiance, Vec3::new(0.5, 1.0, 2.0));
        assert_eq!(
            got[4],
            Emitter::Environment(Environment {
                scale: Vec3::splat(0.25),
                map: None,
                to_world: Mat3::IDENTITY
            })
        );
    }

    #[test]
    fn envmaps_read_back_from_exr_hdr_and_png() {
        let dir = TempDir::new("toml-envmap");
        std::fs::create_dir_all(dir.0.join("maps")).unwrap();
        // Powers of two within a factor 256 of each pixel's largest: exact in RGBE too.
        let value = |x: u32, y: u32| [(1 << x) as f32, 0.5 * (y + 1) as f32, 0.25];
        let img = image::Rgb32FImage::from_fn(4, 2, |x, y| image::Rgb(value(x, y)));
        for ext in ["exr", "hdr"] {
            img.save(dir.0.join(format!("maps/sky.{ext}"))).unwrap();
            let s = with_lights(
                &dir,
                &format!("[[light]]\ntype = \"envmap\"\nfilename = \"maps/sky.{ext}\"\n"),
            )
            .unwrap_or_else(|e| panic!("{ext}: {e:#}"));
            let [Emitter::Environment(env)] = &s.emitters[..] else {
                panic!("{:?}", s.emitters)
            };
            assert_eq!((env.scale, env.to_world), (Vec3::ONE, Mat3::IDENTITY), "{ext}");
            let map = env.map.as_ref().expect("a map");
            assert_eq!((map.width, map.height), (4, 2), "{ext}");
            for (k, p) in map.pixels.iter().enumerate() {
                let want = Vec3::from_array(value(k as u32 % 4, k as u32 / 4));
                assert!(p.distance(want) < 1e-6, "{ext}: pixel {k} is {p}, want {want}");
            }
        }
        // PNG: sRGB-encoded, decoded to linear; scale and rotate (about y by 90 degrees: local +z is world +x).
        texture::write_png(&dir.0.join("maps/sky.png"), 2, 2, &[255, 128, 0].repeat(4));
        let s = with_lights(
            &dir,
            "[[light]]\ntype = \"envmap\"\nfilename = \"maps/sky.png\"\nscale = 3\nrotate = [0, 90, 0]\n",
        )
        .unwrap_or_else(|e| panic!("{e:#}"));
        let [Emitter::Environment(env)] = &s.emitters[..] else {
            panic!("{:?}", s.emitters)
        };
        assert_eq!(env.scale, Vec3::splat(3.0));
        assert!((env.to_world * Vec3::Z).distance(Vec3::X) < 1e-6, "{}", env.to_world);
        let want = Vec3::new(1.0, texture::srgb_to_linear(128.0 / 255.0), 0.0);
        let map = env.map.as_ref().unwrap();
        assert!(map.pixels.iter().all(|p| p.distance(want) < 1e-6), "{:?}", map.pixels);
    }

    #[test]
    fn light_errors_name_line_and_field() {
        let dir = TempDir::new("toml-light-errors");
        texture::write_png(&dir.0.join("one.png"), 1, 1, &[1, 2, 3]);
        // (the lights, line, field, what is said); the first [[light]] is line 38.
        let cases: &[(&str, usize, &str, &str)] = &[
            (
                "[[light]]\ntype = \"area\"",
                39,
                "light[0].type",
                "unknown light type \"area\" (known: point, spot",
            ),
            (
                "[[light]]\ntype = \"point\"\nposition = [0, 1, 0]\ncutoff_angle = 10",
                41,
                "light[0].cutoff_angle",
                "not a field of a point light (its fields: type, position, intensity)",
            ),
            (
                "[[light]]\ntype = \"point\"",
                38,
                "light[0]",
                "a point light needs `position`",
            ),
            (
                "[[light]]\ntype = \"point\"\nposition = [0, 1, 0]\npower = 1",
                41,
                "light[0].power",
                "unknown field `power`",
            ),
            (
                "[[light]]\ntype = \"point\"\nposition = [0, 1, 0]\nintensity = [1, -1, 1]",
                41,
                "light[0].intensity",
                "every component must be finite and >= 0, got [1, -1, 1]",
            ),
            (
                "[[light]]\ntype = \"point\"\nposition = [0, 1, 0]\nintensity = \"bright\"",
                41,
                "light[0].intensity",
                "a number or an array of 3 numbers [r, g, b]",
            ),
            (
                "[[light]]\ntype = \"point\"\nposition = [0, 1, 0]\n[[light]]\ntype = \"spot\"\nposition = [0, 1, 0]\n\
                 direction = [0, -1, 0]\ncutoff_angle = 20\nbeam_width = 30",
                46,
                "light[1].beam_width",
                "must be in (0, cutoff_angle = 20] degrees, got 30",
            ),
            (
                "[[light]]\ntype = \"spot\"\nposition = [0, 1, 0]\ndirection = [0, -1, 0]\ncutoff_angle = 100",
                42,
                "light[0].cutoff_angle",
                "must be in (0, 90] degrees, got 100",
            ),
            (
                "[[light]]\ntype = \"spot\"\nposition = [0, 1, 0]",
                38,
                "light[0]",
                "needs `direction` (its axis) or `target`",
            ),
            (
                "[[light]]\ntype = \"spot\"\nposition = [0, 1, 0]\ndirection = [0, -1, 0]\ntarget = [0, 0, 0]",
                41,
                "light[0].direction",
                "give direction or target, not both",
            ),
            (
                "[[light]]\ntype = \"spot\"\nposition = [0, 1, 0]\ntarget = [0, 1, 0]",
                41,
                "light[0].target",
                "equals position",
            ),
            (
                "[[light]]\ntype = \"spot\"\nposition = [0, nan, 0]\ntarget = [0, 0, 0]",
                40,
                "light[0].position",
                "must be finite, got [0, NaN, 0]",
            ),
            (
                "[[light]]\ntype = \"spot\"\nposition = [0, inf, 0]\ndirection = [0, -1, 0]",
                40,
                "light[0].position",
                "must be finite",
            ),
            (
                "[[light]]\ntype = \"directional\"\ndirection = [0, 0, 0]",
                40,
                "light[0].direction",
                "must be a finite non-zero vector, got [0, 0, 0]",
            ),
            (
                "[[light]]\ntype = \"directional\"",
                38,
                "light[0]",
                "needs `direction` (the way its light travels)",
            ),
            (
                "[[light]]\ntype = \"constant\"\nradiance = -1",
                40,
                "light[0].radiance",
                ">= 0",
            ),
            ("[[light]]\ntype = \"envmap\"", 38, "light[0]", "needs `filename`"),
            (
                "[[light]]\ntype = \"envmap\"\nfilename = \"none.exr\"",
                40,
                "light[0].filename",
                "none.exr: cannot read the image",
            ),
            (
                "[[light]]\ntype = \"envmap\"\nfilename = \"one.png\"",
                40,
                "light[0].filename",
                "one.png: 1 x 1 with 1 pixels: an environment map needs at least 2 x 2",
            ),
            (
                "[[light]]\ntype = \"envmap\"\nfilename = \"one.png\"\nrotate = [0, nan, 0]",
                41,
                "light[0].rotate",
                "every component must be finite",
            ),
            (
                "[[light]]\ntype = \"envmap\"\nfilename = \"one.png\"\nscale = [1, 2, 3]",
                41,
                "light[0].scale",
                "invalid type",
            ),
        ];
        for (text, line, path, needle) in cases {
            let e = match with_lights(&dir, text) {
                Ok(_) => panic!("expected an error for {text}"),
                Err(e) => format!("{e:#}").replace(&format!("{}/", dir.0.display()), ""),
            };
            assert_located(&e, *line, path, needle);
        }
    }

    /// The `[[light]]` examples of docs/scene-format.md load as written.
    #[test]
    fn the_documented_light_examples_load() {
        let doc = include_str!("../../../docs/scene-format.md");
        let block = doc
            .split("Examples, one of each:\n\n```toml\n")
            .nth(1)
            .and_then(|rest| rest.split("```").next())
            .expect("the examples in docs/scene-format.md");
        let dir = TempDir::new("toml-light-docs");
        std::fs::create_dir_all(dir.0.join("maps")).unwrap();
        image::Rgb32FImage::from_pixel(4, 2, image::Rgb([1.0, 2.0, 4.0]))
            .save(dir.0.join("maps/sky.hdr"))
            .unwrap();
        let s = with_lights(&dir, block).unwrap_or_else(|e| panic!("{e:#}"));
        let kinds: Vec<&str> = s.emitters.iter().map(Emitter::kind).collect();
        assert_eq!(kinds, ["point", "spot", "directional", "constant", "envmap"]);
    }
}
