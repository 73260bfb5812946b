//! Scene format: a small TOML file with a camera, named materials, spheres and
//! quads (parallelograms). See `docs/scene-format.md` for the user-facing spec.
//!
//! Parsing is two-stage: serde deserialises the file into `Raw*` structs whose
//! leaves are `toml::Spanned` (so every value keeps its byte range), then
//! `validate` checks the physics/geometry constraints and builds the public
//! types. Every error is reported as `<origin>:<line>:<col>: <field path>: <what>`.

use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;
use std::ops::Range;
use std::path::Path;

use anyhow::anyhow;
use glam::{DVec3, Vec3};
use serde::Deserialize;
use toml::Spanned;

/// Largest accepted image side; larger is almost certainly a typo and would
/// exhaust GPU memory long before rendering anything useful.
pub const MAX_RESOLUTION: u32 = 16384;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    pub look_at: Vec3,
    pub up: Vec3,
    /// Vertical field of view in degrees, in (0, 180).
    pub vfov_deg: f32,
    pub width: u32,
    pub height: u32,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Surface {
    /// Lambertian reflector; albedo components in [0, 1].
    Diffuse { albedo: Vec3 },
    /// Perfect specular reflector; reflectance components in [0, 1].
    Mirror { reflectance: Vec3 },
    /// Smooth dielectric; `ior` is the index inside, the outside is 1.
    Glass { ior: f32 },
}

#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    pub surface: Surface,
    /// Emitted radiance (linear RGB); zero means the material is not a light.
    pub emission: Vec3,
}

impl Material {
    pub fn is_light(&self) -> bool {
        self.emission.max_element() > 0.0
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    pub center: Vec3,
    pub radius: f32,
    /// Index into `Scene::materials`.
    pub material: u32,
}

/// Parallelogram `origin + s*edge_u + t*edge_v`, `s, t` in [0, 1].
/// Front normal is `normalize(edge_u x edge_v)`; emission leaves the front side only.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quad {
    pub origin: Vec3,
    pub edge_u: Vec3,
    pub edge_v: Vec3,
    /// Index into `Scene::materials`.
    pub material: u32,
}

impl Quad {
    pub fn normal(&self) -> Vec3 {
        self.edge_u.cross(self.edge_v).normalize()
    }

    pub fn area(&self) -> f32 {
        self.edge_u.cross(self.edge_v).length()
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    pub name: String,
    pub camera: Camera,
    /// In file order.
    pub materials: Vec<Material>,
    pub spheres: Vec<Sphere>,
    pub quads: Vec<Quad>,
}

impl Scene {
    /// Reads and parses a scene file; every error message starts with the path.
    pub fn load(path: &Path) -> anyhow::Result<Scene> {
        // The io error goes into the message itself (not only an anyhow context) so
        // that `{}` formatting still says why the file could not be read.
        let text = std::fs::read_to_string(path)
            .map_err(|e| anyhow!("{}: cannot read scene file: {e}", path.display()))?;
        Scene::parse(&text, &path.display().to_string())
    }

    /// Parses scene text; `origin` (usually the file name) prefixes every error.
    pub fn parse(text: &str, origin: &str) -> anyhow::Result<Scene> {
        let src = Source { origin, text };
        if is_blank(text) {
            return Err(src.error(
                0..0,
                None,
                "file is empty: a scene needs a [camera], materials and at least one emitting quad",
            ));
        }
        let raw: RawScene = toml::from_str(text).map_err(|e| src.toml_error(&e))?;
        validate(&src, raw)
    }

    /// Axis-aligned bounds `(min, max)` of all spheres and quads; `(0, 0)` for
    /// an empty scene (a validated scene is never empty: it has a light).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for s in &self.spheres {
            lo = lo.min(s.center - Vec3::splat(s.radius));
            hi = hi.max(s.center + Vec3::splat(s.radius));
        }
        for q in &self.quads {
            for p in [
                q.origin,
                q.origin + q.edge_u,
                q.origin + q.edge_v,
                q.origin + q.edge_u + q.edge_v,
            ] {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        if lo.cmple(hi).all() {
            (lo, hi)
        } else {
            (Vec3::ZERO, Vec3::ZERO)
        }
    }

    /// Indices (into `quads`) of the quads whose material emits.
    pub fn lights(&self) -> Vec<u32> {
        self.quads
            .iter()
            .enumerate()
            .filter(|(_, q)| {
                self.materials
                    .get(q.material as usize)
                    .is_some_and(Material::is_light)
            })
            .map(|(i, _)| i as u32)
            .collect()
    }

    /// Uniform scale about the world origin of all geometry and the camera
    /// position/target; `s` must be positive and finite. Radiance (emission) is
    /// unchanged, so a correct renderer produces the same image.
    pub fn scaled(&self, s: f32) -> Scene {
        debug_assert!(
            s.is_finite() && s > 0.0,
            "scale must be positive and finite, got {s}"
        );
        let mut out = self.clone();
        out.camera.eye *= s;
        out.camera.look_at *= s;
        for sp in &mut out.spheres {
            sp.center *= s;
            sp.radius *= s;
        }
        for q in &mut out.quads {
            q.origin *= s;
            q.edge_u *= s;
            q.edge_v *= s;
        }
        out
    }

    /// Same scene at another image size (both at least 1).
    pub fn with_resolution(&self, w: u32, h: u32) -> Scene {
        debug_assert!(
            w >= 1 && h >= 1,
            "resolution must be at least 1x1, got {w}x{h}"
        );
        let mut out = self.clone();
        out.camera.width = w;
        out.camera.height = h;
        out
    }
}

// ---------------------------------------------------------------------------
// Raw (as-written) file structure.

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    name: Option<Spanned<String>>,
    camera: Spanned<RawCamera>,
    #[serde(default)]
    materials: BTreeMap<Spanned<String>, Spanned<RawMaterial>>,
    #[serde(default)]
    sphere: Vec<Spanned<RawSphere>>,
    #[serde(default)]
    quad: Vec<Spanned<RawQuad>>,
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
    diffuse: Option<Spanned<[f32; 3]>>,
    mirror: Option<Spanned<[f32; 3]>>,
    glass: Option<Spanned<f32>>,
    emission: Option<Spanned<[f32; 3]>>,
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

    fn error(
        &self,
        span: Range<usize>,
        path: Option<&str>,
        msg: impl std::fmt::Display,
    ) -> anyhow::Error {
        let (line, col) = self.line_col(span.start);
        let mut s = format!("{}:{line}:{col}: ", self.origin);
        if let Some(p) = path.filter(|p| !p.is_empty()) {
            let _ = write!(s, "{p}: ");
        }
        let _ = write!(s, "{msg}");
        anyhow!(s)
    }

    /// Syntax and serde (type / missing / unknown field) errors from toml. toml
    /// gives a span but not the key path, so the path is recovered from the text.
    fn toml_error(&self, e: &toml::de::Error) -> anyhow::Error {
        let span = e.span().unwrap_or(0..0);
        // A missing field is reported at its table (or at the document root):
        // the key on that line, if any, is not the culprit.
        let table_only = e.message().starts_with("missing field");
        let path = field_path_at(self.text, span.start, table_only);
        // toml's messages may be multi-line ("invalid array\nexpected `]`"); keep ours one line.
        let msg = e.message().trim().replace('\n', ": ");
        self.error(span, path.as_deref(), msg)
    }
}

/// True when the text has no content but whitespace and comments.
fn is_blank(text: &str) -> bool {
    text.lines()
        .map(str::trim)
        .all(|l| l.is_empty() || l.starts_with('#'))
}

/// Best-effort field path (`sphere[1].radius`, `materials.white`, `camera.vfov`)
/// of the key whose line contains byte `offset`, found by scanning table headers
/// and `key =` lines. Array-of-table indices are 0-based. Handles the layout
/// this format is written in (one key per line, arrays possibly multi-line);
/// for exotic layouts it may return a shorter path or none. With `table_only`
/// the key is left out (`None` for the document root).
fn field_path_at(text: &str, offset: usize, table_only: bool) -> Option<String> {
    let mut table = String::new();
    let mut key: Option<String> = None;
    let mut counts: HashMap<String, usize> = HashMap::new();
    // Open-bracket depth of a value spanning several lines, so that an array
    // element line such as `[1, 2, 3],` is not taken for a table header.
    let mut depth: i32 = 0;
    let mut line_start = 0;
    for line in text.split_inclusive('\n') {
        if line_start > offset {
            break;
        }
        line_start += line.len();
        let code = strip_comment(line).trim();
        if depth > 0 {
            depth += bracket_balance(code);
            continue;
        }
        if let Some(rest) = code.strip_prefix("[[") {
            let name = rest.split("]]").next().unwrap_or("").trim().to_string();
            let n = counts.entry(name.clone()).or_insert(0);
            table = format!("{name}[{n}]");
            *n += 1;
            key = None;
        } else if let Some(rest) = code.strip_prefix('[') {
            table = rest.split(']').next().unwrap_or("").trim().to_string();
            key = None;
        } else if let Some((k, v)) = code.split_once('=') {
            let k = k.trim();
            if !k.is_empty()
                && k.chars()
                    .all(|c| c.is_alphanumeric() || "_-.\"' ".contains(c))
            {
                key = Some(k.to_string());
                depth = bracket_balance(v).max(0);
            }
        }
    }
    match (table.is_empty(), key.filter(|_| !table_only)) {
        (true, None) => None,
        (true, Some(k)) => Some(k),
        (false, None) => Some(table),
        (false, Some(k)) => Some(format!("{table}.{k}")),
    }
}

/// Drops a trailing `# comment`, ignoring `#` inside quoted strings.
fn strip_comment(line: &str) -> &str {
    let mut quote: Option<char> = None;
    for (i, c) in line.char_indices() {
        match (quote, c) {
            (None, '"' | '\'') => quote = Some(c),
            (Some(q), _) if c == q => quote = None,
            (None, '#') => return &line[..i],
            _ => {}
        }
    }
    line
}

fn bracket_balance(s: &str) -> i32 {
    s.chars()
        .map(|c| match c {
            '[' | '{' => 1,
            ']' | '}' => -1,
            _ => 0,
        })
        .sum()
}

fn fmt_vec(v: [f32; 3]) -> String {
    format!("[{}, {}, {}]", v[0], v[1], v[2])
}

// ---------------------------------------------------------------------------
// Validation.

fn finite_vec(src: &Source, v: &Spanned<[f32; 3]>, path: &str) -> anyhow::Result<Vec3> {
    let a = *v.get_ref();
    if a.iter().all(|x| x.is_finite()) {
        Ok(Vec3::from_array(a))
    } else {
        Err(src.error(
            v.span(),
            Some(path),
            format!("every component must be finite, got {}", fmt_vec(a)),
        ))
    }
}

/// A finite vector with every component in [0, 1] (albedo, reflectance).
fn unit_vec(src: &Source, v: &Spanned<[f32; 3]>, path: &str) -> anyhow::Result<Vec3> {
    let out = finite_vec(src, v, path)?;
    if out.cmpge(Vec3::ZERO).all() && out.cmple(Vec3::ONE).all() {
        Ok(out)
    } else {
        Err(src.error(
            v.span(),
            Some(path),
            format!(
                "every component must be in [0, 1], got {}",
                fmt_vec(*v.get_ref())
            ),
        ))
    }
}

fn validate(src: &Source, raw: RawScene) -> anyhow::Result<Scene> {
    let name = match &raw.name {
        Some(n) => n.get_ref().clone(),
        None => Path::new(src.origin)
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or(src.origin)
            .to_string(),
    };
    let camera = validate_camera(src, raw.camera.get_ref())?;

    // BTreeMap sorts by name; keep file order so material indices follow the file.
    let mut raw_materials: Vec<_> = raw.materials.iter().collect();
    raw_materials.sort_by_key(|(k, _)| k.span().start);
    let mut materials = Vec::with_capacity(raw_materials.len());
    let mut spans = Vec::with_capacity(raw_materials.len());
    for (key, m) in raw_materials {
        materials.push(validate_material(src, key.get_ref(), m)?);
        spans.push(key.span());
    }
    let lookup = |r: &Spanned<String>, path: &str| -> anyhow::Result<u32> {
        match materials.iter().position(|m| m.name == *r.get_ref()) {
            Some(i) => {
                u32::try_from(i).map_err(|_| src.error(r.span(), Some(path), "too many materials"))
            }
            None => {
                let known: Vec<String> = materials
                    .iter()
                    .map(|m| format!("\"{}\"", m.name))
                    .collect();
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
    };

    let mut spheres = Vec::with_capacity(raw.sphere.len());
    for (i, s) in raw.sphere.iter().enumerate() {
        let s = s.get_ref();
        let p = format!("sphere[{i}]");
        let center = finite_vec(src, &s.center, &format!("{p}.center"))?;
        let radius = *s.radius.get_ref();
        if !(radius.is_finite() && radius > 0.0) {
            return Err(src.error(
                s.radius.span(),
                Some(&format!("{p}.radius")),
                format!("must be positive and finite, got {radius}"),
            ));
        }
        let mpath = format!("{p}.material");
        let material = lookup(&s.material, &mpath)?;
        if materials[material as usize].is_light() {
            return Err(src.error(
                s.material.span(),
                Some(&mpath),
                format!(
                    "material \"{}\" emits light, but only quads may be emitters \
                     (spheres cannot be lights)",
                    s.material.get_ref()
                ),
            ));
        }
        spheres.push(Sphere {
            center,
            radius,
            material,
        });
    }

    let mut quads = Vec::with_capacity(raw.quad.len());
    for (i, q) in raw.quad.iter().enumerate() {
        let q = q.get_ref();
        let p = format!("quad[{i}]");
        let origin = finite_vec(src, &q.origin, &format!("{p}.origin"))?;
        let edge_u = finite_vec(src, &q.edge_u, &format!("{p}.edge_u"))?;
        let edge_v = finite_vec(src, &q.edge_v, &format!("{p}.edge_v"))?;
        // f64 so that huge (but finite) f32 edges cannot overflow the tests below.
        let (u, v) = (edge_u.as_dvec3(), edge_v.as_dvec3());
        for (len, span, field) in [
            (u.length(), q.edge_u.span(), "edge_u"),
            (v.length(), q.edge_v.span(), "edge_v"),
        ] {
            // Checked separately so the message can say which edge is at fault.
            if len == 0.0 {
                return Err(src.error(
                    span,
                    Some(&format!("{p}.{field}")),
                    "edge has zero length (degenerate quad)",
                ));
            }
        }
        // Relative test: sin(angle between edges) below 1e-6 is parallel at f32 precision.
        if u.cross(v).length() <= 1e-6 * u.length() * v.length() {
            return Err(src.error(
                q.edge_v.span(),
                Some(&format!("{p}.edge_v")),
                format!(
                    "parallel to edge_u {} (zero-area, degenerate quad)",
                    fmt_vec(*q.edge_u.get_ref())
                ),
            ));
        }
        let material = lookup(&q.material, &format!("{p}.material"))?;
        quads.push(Quad {
            origin,
            edge_u,
            edge_v,
            material,
        });
    }

    let scene = Scene {
        name,
        camera,
        materials,
        spheres,
        quads,
    };
    if scene.lights().is_empty() {
        let span = raw.quad.first().map_or(0..0, |q| q.span());
        return Err(src.error(
            span,
            Some("quad"),
            "no emitting quad: nothing to render (give a quad a material with positive `emission`)",
        ));
    }
    Ok(scene)
}

fn validate_camera(src: &Source, c: &RawCamera) -> anyhow::Result<Camera> {
    let eye = finite_vec(src, &c.eye, "camera.eye")?;
    let look_at = finite_vec(src, &c.look_at, "camera.look_at")?;
    let up = finite_vec(src, &c.up, "camera.up")?;
    let vfov = *c.vfov.get_ref();
    if !(vfov.is_finite() && vfov > 0.0 && vfov < 180.0) {
        return Err(src.error(
            c.vfov.span(),
            Some("camera.vfov"),
            format!("must be in (0, 180) degrees, got {vfov}"),
        ));
    }
    let [width, height] = *c.resolution.get_ref();
    if !(1..=MAX_RESOLUTION).contains(&width) || !(1..=MAX_RESOLUTION).contains(&height) {
        return Err(src.error(
            c.resolution.span(),
            Some("camera.resolution"),
            format!(
                "width and height must each be in 1..={MAX_RESOLUTION}, got [{width}, {height}]"
            ),
        ));
    }
    // In f64 so that far-apart finite points cannot overflow; zero length gives zero.
    let view = look_at.as_dvec3() - eye.as_dvec3();
    let dir = view.normalize_or_zero();
    if dir == DVec3::ZERO {
        return Err(src.error(
            c.look_at.span(),
            Some("camera.look_at"),
            format!(
                "must differ from camera.eye, both are {}",
                fmt_vec(*c.eye.get_ref())
            ),
        ));
    }
    let up_n = up.as_dvec3().normalize_or_zero();
    if up_n == DVec3::ZERO {
        return Err(src.error(c.up.span(), Some("camera.up"), "must be a non-zero vector"));
    }
    // ~0.006 degrees: closer than that the camera basis is numerically meaningless.
    if dir.cross(up_n).length() < 1e-4 {
        return Err(src.error(
            c.up.span(),
            Some("camera.up"),
            format!(
                "is parallel to the view direction (look_at - eye = {}); \
                 choose an up vector not along it",
                fmt_vec(view.as_vec3().to_array())
            ),
        ));
    }
    Ok(Camera {
        eye,
        look_at,
        up,
        vfov_deg: vfov,
        width,
        height,
    })
}

fn validate_material(
    src: &Source,
    name: &str,
    m: &Spanned<RawMaterial>,
) -> anyhow::Result<Material> {
    let p = format!("materials.{name}");
    let r = m.get_ref();
    if let (Some(_), Some(g)) = (&r.mirror, &r.glass) {
        return Err(src.error(
            g.span(),
            Some(&format!("{p}.glass")),
            "a material cannot be both mirror and glass",
        ));
    }
    if let (Some(_), Some(x)) = (
        &r.diffuse,
        r.mirror
            .as_ref()
            .map(|s| s.span())
            .or(r.glass.as_ref().map(|s| s.span())),
    ) {
        return Err(src.error(x, Some(&p), "give exactly one of diffuse, mirror, glass"));
    }
    let emission = match &r.emission {
        Some(e) => {
            let ep = format!("{p}.emission");
            let v = finite_vec(src, e, &ep)?;
            if v.cmplt(Vec3::ZERO).any() {
                return Err(src.error(
                    e.span(),
                    Some(&ep),
                    format!(
                        "every component must be >= 0, got {}",
                        fmt_vec(*e.get_ref())
                    ),
                ));
            }
            if r.mirror.is_some() || r.glass.is_some() {
                return Err(src.error(
                    e.span(),
                    Some(&ep),
                    "emission can only be combined with diffuse (or stand alone), \
                     not with mirror or glass",
                ));
            }
            v
        }
        None => Vec3::ZERO,
    };
    let surface = if let Some(d) = &r.diffuse {
        Surface::Diffuse {
            albedo: unit_vec(src, d, &format!("{p}.diffuse"))?,
        }
    } else if let Some(mr) = &r.mirror {
        Surface::Mirror {
            reflectance: unit_vec(src, mr, &format!("{p}.mirror"))?,
        }
    } else if let Some(g) = &r.glass {
        let ior = *g.get_ref();
        if !(ior.is_finite() && ior >= 1.0) {
            return Err(src.error(
                g.span(),
                Some(&format!("{p}.glass")),
                format!("index of refraction must be finite and >= 1, got {ior}"),
            ));
        }
        Surface::Glass { ior }
    } else if r.emission.is_some() {
        // A pure emitter reflects nothing.
        Surface::Diffuse { albedo: Vec3::ZERO }
    } else {
        return Err(src.error(
            m.span(),
            Some(&p),
            "needs one of diffuse, mirror, glass (or emission alone for a black emitter)",
        ));
    };
    Ok(Material {
        name: name.to_string(),
        surface,
        emission,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const CORNELL: &str = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenes/cornell-spheres.toml"
    );
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
        let prefix = format!("t.toml:{line}:");
        assert!(
            e.starts_with(&prefix),
            "error {e:?} should start with {prefix:?}"
        );
        assert!(
            e.contains(&format!(" {path}: ")),
            "error {e:?} should name field {path:?}"
        );
        assert!(e.contains(needle), "error {e:?} should contain {needle:?}");
        assert!(!e.contains('\n'), "error {e:?} should be one line");
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
        assert_eq!(
            s.materials[1].surface,
            Surface::Diffuse { albedo: Vec3::ZERO }
        );
        assert!(s.materials[1].is_light());
        assert!(!s.materials[0].is_light());
        assert_eq!(s.materials[2].surface, Surface::Glass { ior: 1.5 });
        assert_eq!(s.spheres[0].material, 2);
        assert_eq!(s.spheres[1].material, 0);
        assert_eq!(s.quads[1].material, 1);
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
            assert!(
                w.normal().dot(centre - wc) > 0.0,
                "wall {w:?} must face into the box"
            );
        }
        let total: f32 = walls.iter().map(|w| w.area()).sum();
        assert!((total - 2.0 * (2.0 * 2.0 + 2.0 * 4.0 + 2.0 * 4.0)).abs() < 1e-4);
        assert_eq!(
            s.bounds(),
            (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 2.0, 3.0))
        );

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
        assert!(
            eye.cmpgt(lo).all() && eye.cmplt(hi).all(),
            "camera inside the box"
        );
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
        };
        assert_eq!(q.normal(), Vec3::Z);
        assert!((q.area() - 6.0).abs() < 1e-6);
        let flipped = Quad {
            edge_u: q.edge_v,
            edge_v: q.edge_u,
            ..q
        };
        assert_eq!(flipped.normal(), Vec3::NEG_Z);
    }

    #[test]
    fn bounds_lights_scaled_resolution() {
        let s = Scene::parse(BASE, "t.toml").expect("valid");
        // Quad 0 spans x,z in [-1,1] at y=0; the light tops out at y=2; spheres inside x <= 1.25.
        assert_eq!(
            s.bounds(),
            (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.25, 2.0, 1.0))
        );
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
        assert_eq!(
            Scene {
                camera: s.camera,
                ..r
            },
            s
        );
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
        // An unclosed array is detected on the next line; the path still names the key.
        assert_err(
            &edit(10, "diffuse = [0.5, 0.5"),
            11,
            "materials.white.diffuse",
            "expected `]`",
        );
        let e = err(&edit(5, "up = 0.0, 1.0"));
        assert!(e.starts_with("t.toml:5:"), "{e}");
        // Duplicate table is a TOML error, located at the second header.
        assert_err(
            &edit(9, "[materials.light]"),
            11,
            "materials.light",
            "duplicate",
        );
    }

    #[test]
    fn wrong_types_and_missing_fields() {
        assert_err(
            &edit(18, "radius = \"big\""),
            18,
            "sphere[0].radius",
            "invalid type",
        );
        assert_err(
            &edit(23, "radius = true"),
            23,
            "sphere[1].radius",
            "invalid type",
        );
        assert_err(
            &edit(7, "resolution = [64, -48]"),
            7,
            "camera.resolution",
            "",
        );
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
        assert_err(
            &edit(1, "title = \"x\""),
            1,
            "title",
            "unknown field `title`",
        );
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
        assert_err(
            &edit(18, "radius = 0.0"),
            18,
            "sphere[0].radius",
            "must be positive",
        );
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
        assert_err(
            &edit(14, "glass = nan"),
            14,
            "materials.glass.glass",
            "finite",
        );
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
            "not with mirror or glass",
        );
        let text = BASE.replace(
            "diffuse = [0.5, 0.5, 0.5]",
            "diffuse = [0.5, 0.5, 0.5]\nemission = [1.0, 1.0, 1.0]",
        );
        // Sphere 1 (line 24, one line lower now) uses "white", which now emits.
        assert_err(
            &text,
            25,
            "sphere[1].material",
            "only quads may be emitters",
        );
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
    fn emitting_sphere_refused() {
        assert_err(
            &edit(19, "material = \"light\""),
            19,
            "sphere[0].material",
            "only quads may be emitters",
        );
    }

    #[test]
    fn material_kind_conflicts() {
        let text = BASE.replace("glass = 1.5", "glass = 1.5\nmirror = [0.9, 0.9, 0.9]");
        assert_err(
            &text,
            14,
            "materials.glass.glass",
            "cannot be both mirror and glass",
        );
        let text = BASE.replace("glass = 1.5", "glass = 1.5\ndiffuse = [0.9, 0.9, 0.9]");
        assert_err(
            &text,
            14,
            "materials.glass",
            "exactly one of diffuse, mirror, glass",
        );
        // A material with nothing in it.
        assert_err(
            &edit(14, ""),
            13,
            "materials.glass",
            "needs one of diffuse, mirror, glass",
        );
        assert_err(
            &edit(14, "glass = 0.9"),
            14,
            "materials.glass.glass",
            ">= 1",
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
            &edit(28, "edge_u = [0.0, 0.0, 1e-4]")
                .replace("edge_v = [2.0, 0.0, 0.0]", "edge_v = [1e-4, 0.0, 0.0]"),
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
        assert_err(
            &edit(7, "resolution = [0, 48]"),
            7,
            "camera.resolution",
            "1..=16384",
        );
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
        assert!(e.contains("no emitting quad: nothing to render"), "{e}");
        assert!(e.starts_with("t.toml:"), "{e}");
        // No quads at all: same message.
        let text = BASE.split("[[quad]]").next().unwrap_or("").to_string();
        assert!(err(&text).contains("no emitting quad"));
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
    fn path_scanner() {
        let t = "a = 1\n[camera] # c\nvfov = [\n [1], # x\n 2]\n\
                 [[quad]]\nx = 1\n[[quad]]\ny = \"#\" # z\n";
        let at = |needle: &str| field_path_at(t, t.find(needle).unwrap_or(0), false);
        assert_eq!(at("a =").as_deref(), Some("a"));
        assert_eq!(at("[camera]").as_deref(), Some("camera"));
        assert_eq!(at("[1]").as_deref(), Some("camera.vfov"));
        assert_eq!(at(" 2]").as_deref(), Some("camera.vfov"));
        assert_eq!(at("x = 1").as_deref(), Some("quad[0].x"));
        assert_eq!(at("y =").as_deref(), Some("quad[1].y"));
        assert_eq!(field_path_at("", 0, false), None);
        assert_eq!(field_path_at(t, 0, true), None);
        assert_eq!(
            field_path_at(t, t.find("x =").unwrap_or(0), true).as_deref(),
            Some("quad[0]")
        );
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
}
