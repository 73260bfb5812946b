//! Mitsuba 3 scene files (XML): the subset that photon-mapping test scenes use, read into the one
//! [`Scene`]. See `docs/mitsuba.md` for what is read, approximated and refused.
//!
//! Reading is two-stage. First each file is parsed by roxmltree into an owned tree of [`Elem`]s in
//! document order, as Mitsuba's parser does it: `$name` parameters substituted in every attribute
//! (`-D` overrides first, then `<default>`s), `<include>`s spliced in place (relative to the including
//! file, cycles and nesting deeper than Mitsuba's limit refused). Then the scene's elements are
//! interpreted into cameras, materials, quads, spheres and meshes. Every error names the file, line,
//! column and element: `<file>:<line>:<col>: <shape type="rectangle" id="floor">: <what>`; every
//! approximation is one line of `Scene::warnings`.

use std::cell::Cell;
use std::collections::HashMap;
use std::fmt;
use std::path::{Path, PathBuf};
use std::rc::Rc;

use anyhow::{anyhow, bail, Result};
use glam::{DAffine3, DMat3, DMat4, DVec3, DVec4, Vec2, Vec3};

use super::conductors;
use super::obj::{self, RawMesh};
use super::texture::{self, Filter, Pattern, Texture, Wrap};
use super::{Camera, Material, Mesh, Microfacet, ObjImport, Quad, Scene, Sphere, Surface, MAX_TRIANGLES};
use crate::error::Error;

/// Deepest `<include>` nesting, Mitsuba's own limit (`ParserConfig::max_include_depth`).
pub const MAX_INCLUDE_DEPTH: usize = 15;

/// Elements nested deeper than this are refused (real scenes nest about five deep: scene, shape,
/// bsdf, bsdf, rgb).
pub const MAX_NESTING: usize = 64;

/// Just past the `>` that ends the tag starting at `at`: the first outside quotes (an attribute value
/// may hold `>` or `/>`), or the end of the text.
fn tag_end(b: &[u8], at: usize) -> usize {
    let mut quote = None;
    for (i, &c) in b.iter().enumerate().skip(at) {
        match (quote, c) {
            (None, b'"' | b'\'') => quote = Some(c),
            (Some(q), _) if c == q => quote = None,
            (None, b'>') => return i + 1,
            _ => {}
        }
    }
    b.len()
}

/// The line where elements first nest deeper than `max`, by a scan of the tags (`<a>` opens unless
/// it ends `/>`, `</a>` closes; comments, CDATA and `<?...?>` are skipped), if they do.
fn too_deep(text: &str, max: usize) -> Option<usize> {
    let b = text.as_bytes();
    let (mut depth, mut i) = (0usize, 0usize);
    let skip_past = |from: usize, end: &[u8]| -> usize {
        b[from..]
            .windows(end.len())
            .position(|w| w == end)
            .map_or(b.len(), |p| from + p + end.len())
    };
    while let Some(p) = b[i..].iter().position(|&c| c == b'<') {
        let at = i + p;
        let rest = &b[at..];
        i = if rest.starts_with(b"<!--") {
            skip_past(at, b"-->")
        } else if rest.starts_with(b"<![CDATA[") {
            skip_past(at, b"]]>")
        } else if rest.starts_with(b"<?") || rest.starts_with(b"<!") {
            skip_past(at, b">")
        } else {
            let end = tag_end(b, at);
            if rest.starts_with(b"</") {
                depth = depth.saturating_sub(1);
            } else if !b[..end].ends_with(b"/>") {
                depth += 1;
                if depth > max {
                    return Some(1 + b[..at].iter().filter(|&&c| c == b'\n').count());
                }
            }
            end
        };
    }
    None
}

/// Triangles in the fan a `disk` becomes. The polygon's radius is enlarged so that its area is the
/// disk's exactly (an emitting disk keeps its power); its outline then lies between 2.6e-5 of the
/// radius inside the circle (edge midpoints) and 5.1e-5 outside (corners).
pub const DISK_SEGMENTS: u32 = 256;

/// `name=value` of a `-D` override; the name is what `$name` refers to.
pub fn parse_define(s: &str) -> Result<(String, String), String> {
    let (name, value) = s.split_once('=').ok_or_else(|| format!("{s:?}: expected NAME=VALUE"))?;
    if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
        return Err(format!(
            "{s:?}: the name must be letters, digits and underscores (it is used as $NAME)"
        ));
    }
    Ok((name.to_string(), value.to_string()))
}

/// Reads the Mitsuba scene at `path`; `defines` override its `<default>` parameters (as Mitsuba's
/// `-D name=value`: one the scene never uses is an error).
pub(super) fn load(path: &Path, defines: &[(String, String)]) -> Result<Scene> {
    let mut reader = Reader {
        params: defines
            .iter()
            .map(|(k, v)| Param {
                key: format!("${k}"),
                value: v.clone(),
                used: false,
            })
            .collect(),
        open: Vec::new(),
    };
    let shown = path.display().to_string();
    let (root, children) = reader.read(path, &shown, None)?;
    if let Some(p) = reader.params.iter().find(|p| !p.used) {
        bail!(
            "{shown}: -D {}={}: the scene never uses ${0} (Mitsuba refuses unused parameters too)",
            &p.key[1..],
            p.value
        );
    }
    let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or(&shown).to_string();
    let mut b = Builder::new(name, root);
    for e in &children {
        b.top_level(e)?;
    }
    b.finish()
}

// ---------------------------------------------------------------------------
// Stage 1: XML files to one owned tree, parameters substituted, includes spliced.

/// Where an element starts.
#[derive(Clone, Debug)]
struct Loc {
    file: Rc<str>,
    line: u32,
    col: u32,
}

impl fmt::Display for Loc {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.file, self.line, self.col)
    }
}

/// An XML element with its attributes substituted.
#[derive(Clone, Debug)]
struct Elem {
    tag: String,
    attrs: Vec<(String, String)>,
    children: Vec<Elem>,
    loc: Loc,
}

impl Elem {
    fn attr(&self, name: &str) -> Option<&str> {
        self.attrs.iter().find(|(k, _)| k == name).map(|(_, v)| v.as_str())
    }

    fn kind(&self) -> &str {
        self.attr("type").unwrap_or("")
    }

    /// The element as messages name it: `<shape type="rectangle" id="floor">`, `<float name="fov">`.
    fn what(&self) -> String {
        let mut s = format!("<{}", self.tag);
        for key in ["type", "id", "name"] {
            if let Some(v) = self.attr(key) {
                s += &format!(" {key}=\"{v}\"");
            }
        }
        s + ">"
    }

    /// A located [`Error::Scene`] (inside anyhow; `Scene::load_with` takes it out): the element is its
    /// field.
    fn err(&self, msg: impl fmt::Display) -> anyhow::Error {
        let Loc { file, line, col } = &self.loc;
        anyhow::Error::from(Error::scene(
            file.to_string(),
            *line as usize,
            *col as usize,
            self.what(),
            msg.to_string(),
        ))
    }

    fn warning(&self, msg: impl fmt::Display) -> String {
        format!("{}: {}: {msg}", self.loc, self.what())
    }

    fn required(&self, name: &str) -> Result<&str> {
        self.attr(name)
            .ok_or_else(|| self.err(format!("needs the attribute {name}")))
    }
}

struct Param {
    /// `$name`.
    key: String,
    value: String,
    used: bool,
}

struct Reader {
    /// `-D` overrides first, then `<default>`s as they come (an override wins over a default).
    params: Vec<Param>,
    /// Canonical paths of the files being read, outermost first (to catch include cycles).
    open: Vec<PathBuf>,
}

impl Reader {
    /// The root element of the file at `path` and its children (includes spliced in).
    fn read(&mut self, path: &Path, shown: &str, included_at: Option<&Elem>) -> Result<(Elem, Vec<Elem>)> {
        let at = |msg: String| match included_at {
            Some(e) => e.err(msg),
            None => anyhow!(msg),
        };
        // Bounded and regular files only, as for TOML scenes (a device file would be read forever).
        let text = super::read_bounded(path, super::MAX_SCENE_BYTES, "scene file").map_err(|e| match included_at {
            Some(include) => include.err(e),
            None => anyhow::Error::from(e),
        })?;
        let canonical = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
        if let Some(i) = self.open.iter().position(|p| *p == canonical) {
            let chain: Vec<String> = self.open[i..]
                .iter()
                .chain([&canonical])
                .map(|p| p.display().to_string())
                .collect();
            return Err(at(format!("include cycle: {}", chain.join(" -> "))));
        }
        if self.open.len() > MAX_INCLUDE_DEPTH {
            return Err(at(format!(
                "includes nested deeper than {MAX_INCLUDE_DEPTH} files (Mitsuba's limit)"
            )));
        }
        // roxmltree's tokenizer recurses per level: refuse deep nesting before it parses.
        if let Some(line) = too_deep(&text, MAX_NESTING) {
            let message = format!("elements nested deeper than {MAX_NESTING} levels");
            return Err(match included_at {
                Some(include) => include.err(format!("{shown}:{line}: {message}")),
                None => Error::scene(shown, line, 1, "", message).into(),
            });
        }
        let doc = roxmltree::Document::parse(&text).map_err(|e| {
            let p = e.pos();
            at(format!("{shown}:{}:{}: malformed XML: {e}", p.row, p.col))
        })?;
        self.open.push(canonical);
        let file: Rc<str> = shown.into();
        let src = Src {
            doc: &doc,
            file,
            dir: path.parent().unwrap_or(Path::new("")),
        };
        let root = doc.root_element();
        let mut top = Vec::new();
        // The root is read like any element (its attributes substituted), without its children.
        let root_elem = self.element(&src, root, false)?;
        if root.tag_name().name() == "scene" {
            if let Some(v) = root_elem.attr("version") {
                let major = v.split('.').next().and_then(|m| m.parse::<u32>().ok());
                if major.is_none_or(|m| m < 2) {
                    return Err(root_elem.err(format!(
                        "version {v}: only scenes of version 2 and 3 are read (older ones name \
                         their parameters differently)"
                    )));
                }
            }
            for child in root.children().filter(|n| n.is_element()) {
                self.convert(&src, child, &mut top)?;
            }
        } else {
            // An included file may hold one object instead of a scene.
            self.convert(&src, root, &mut top)?;
        }
        self.open.pop();
        Ok((root_elem, top))
    }

    /// Appends what `node` stands for to `out`: itself, an included file's elements, or nothing (a
    /// `<default>`).
    fn convert(&mut self, src: &Src, node: roxmltree::Node, out: &mut Vec<Elem>) -> Result<()> {
        let e = self.element(src, node, true)?;
        match e.tag.as_str() {
            "default" => {
                let name = e.required("name")?;
                let value = e.required("value")?;
                if name.is_empty() {
                    return Err(e.err("the name must not be empty"));
                }
                let key = format!("${name}");
                if !self.params.iter().any(|p| p.key == key) {
                    self.params.push(Param {
                        key,
                        value: value.to_string(),
                        used: true,
                    });
                }
            }
            "include" => {
                let file = e.required("filename")?;
                let path = src.dir.join(file);
                let shown = path.display().to_string();
                let (_, children) = self.read(&path, &shown, Some(&e))?;
                out.extend(children);
            }
            _ => out.push(e),
        }
        Ok(())
    }

    /// `node` with its attributes substituted and (with `deep`) its children converted.
    fn element(&mut self, src: &Src, node: roxmltree::Node, deep: bool) -> Result<Elem> {
        let pos = src.doc.text_pos_at(node.range().start);
        let mut e = Elem {
            tag: node.tag_name().name().to_string(),
            attrs: Vec::new(),
            children: Vec::new(),
            loc: Loc {
                file: src.file.clone(),
                line: pos.row,
                col: pos.col,
            },
        };
        for a in node.attributes() {
            let value = self
                .substitute(a.value())
                .map_err(|m| e.err(format!("attribute {}=\"{}\": {m}", a.name(), a.value())))?;
            e.attrs.push((a.name().to_string(), value));
        }
        if deep {
            // Bounded, as the reader and the scene's drop recurse per level (a fuzzed file nested
            // thousands deep overflowed the stack).
            if node.ancestors().take(MAX_NESTING + 2).count() > MAX_NESTING {
                return Err(e.err(format!("elements nested deeper than {MAX_NESTING} levels")));
            }
            let mut children = Vec::new();
            for child in node.children().filter(|n| n.is_element()) {
                self.convert(src, child, &mut children)?;
            }
            e.children = children;
        }
        Ok(e)
    }

    /// Mitsuba's substitution: every `$key` (longest keys first) not escaped as `\$` is replaced;
    /// a `$` left over is an undefined parameter; `\$` then becomes `$`.
    fn substitute(&mut self, value: &str) -> Result<String, String> {
        if !value.contains('$') {
            return Ok(value.to_string());
        }
        let mut order: Vec<usize> = (0..self.params.len()).collect();
        order.sort_by_key(|&i| std::cmp::Reverse(self.params[i].key.len()));
        let mut s = value.to_string();
        for i in order {
            let p = &mut self.params[i];
            let mut pos = 0;
            while let Some(k) = s[pos..].find(&p.key).map(|k| k + pos) {
                if k > 0 && s.as_bytes()[k - 1] == b'\\' {
                    pos = k + p.key.len();
                } else {
                    s.replace_range(k..k + p.key.len(), &p.value);
                    p.used = true;
                    pos = k + p.value.len();
                }
            }
        }
        let bytes = s.as_bytes();
        for (k, _) in s.match_indices('$') {
            if k > 0 && bytes[k - 1] == b'\\' {
                continue;
            }
            let name: String = s[k + 1..]
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            return Err(format!(
                "undefined parameter ${name} (give it a <default name=\"{name}\" value=\"...\"/> \
                 or -D {name}=...)"
            ));
        }
        Ok(s.replace("\\$", "$"))
    }
}

/// The file being read.
struct Src<'a, 'input> {
    doc: &'a roxmltree::Document<'input>,
    file: Rc<str>,
    dir: &'a Path,
}

// ---------------------------------------------------------------------------
// Property values.

/// The properties (`<float name=..>`, `<transform name=..>`, ...) of one plugin element. Each one
/// read is marked; [`Props::finish`] refuses those never read, as Mitsuba refuses unused properties.
struct Props<'a> {
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
    "transform",
    "texture",
];

impl<'a> Props<'a> {
    /// The property children of `owner`; the other children are the caller's (`objects`).
    fn of(owner: &'a Elem) -> (Props<'a>, Vec<&'a Elem>) {
        let mut items = Vec::new();
        let mut objects = Vec::new();
        for c in &owner.children {
            // In a bsdf, a named `ref` is a parameter (a top-level texture); in a shape, `<ref id=".."
            // name="bsdf"/>` stays the shape's bsdf.
            let parameter = PROPERTY_TAGS.contains(&c.tag.as_str()) || (c.tag == "ref" && owner.tag == "bsdf");
            if parameter && c.attr("name").is_some() {
                items.push((c, Cell::new(false)));
            } else {
                objects.push(c);
            }
        }
        (Props { owner, items }, objects)
    }

    fn get(&self, name: &str) -> Option<&'a Elem> {
        self.items
            .iter()
            .find(|(e, _)| e.attr("name") == Some(name))
            .map(|(e, used)| {
                used.set(true);
                *e
            })
    }

    /// Marks `names` read without reading them: they do not change the image.
    fn ignore(&self, names: &[&str]) {
        for n in names {
            self.get(n);
        }
    }

    fn float(&self, name: &str) -> Result<Option<f64>> {
        self.get(name)
            .map(|e| {
                expect_tag(e, &["float", "integer"])?;
                number(e, e.required("value")?)
            })
            .transpose()
    }

    fn string(&self, name: &str) -> Result<Option<&'a str>> {
        self.get(name)
            .map(|e| {
                expect_tag(e, &["string"])?;
                e.required("value")
            })
            .transpose()
    }

    fn boolean(&self, name: &str) -> Result<bool> {
        self.boolean_or(name, false)
    }

    fn boolean_or(&self, name: &str, default: bool) -> Result<bool> {
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

    fn point(&self, name: &str) -> Result<Option<DVec3>> {
        self.get(name)
            .map(|e| {
                expect_tag(e, &["point", "vector"])?;
                vector(e, 0.0)
            })
            .transpose()
    }

    fn color(&self, name: &str) -> Result<Option<Vec3>> {
        self.get(name).map(color).transpose()
    }

    fn transform(&self, name: &str) -> Result<DAffine3> {
        match self.get(name) {
            Some(e) => {
                expect_tag(e, &["transform"])?;
                transform(e)
            }
            None => Ok(DAffine3::IDENTITY),
        }
    }

    /// Refuses the properties nothing read.
    fn finish(&self) -> Result<()> {
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

fn number(e: &Elem, s: &str) -> Result<f64> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| e.err(format!("\"{s}\" is not a number")))?;
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

/// A constant colour: `<rgb>`, `<float>` (grey) or a `<spectrum>` of one value (grey).
fn color(e: &Elem) -> Result<Vec3> {
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
        "spectrum" => {
            let v = e
                .attr("value")
                .ok_or_else(|| e.err("only a constant spectrum (value=\"x\") is read, not a file"))?;
            if v.contains(':') {
                return Err(e.err(
                    "a sampled spectrum (wavelength:value pairs) is not supported: ppm-vk renders \
                     RGB (give an rgb)",
                ));
            }
            Ok(Vec3::splat(number(e, v)? as f32))
        }
        "texture" | "ref" => Err(e.err(texture_refused(e.attr("name").unwrap_or_default()))),
        _ => Err(e.err("expected a colour: <rgb>, <float> or <spectrum>")),
    }
}

/// Why a texture on parameter `name` is refused.
fn texture_refused(name: &str) -> String {
    format!(
        "a texture on {name} is not supported: only diffuse reflectance (diffuse reflectance, plastic \
         diffuse_reflectance) reads textures"
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

// ---------------------------------------------------------------------------
// Stage 2: the scene's elements to a Scene.

/// A BSDF as ppm-vk reads it.
#[derive(Clone, Debug)]
struct Bsdf {
    surface: Surface,
    /// Wrapped in `twosided` (or, for a dielectric, two-sided by nature).
    two_sided: bool,
    id: Option<String>,
    /// The texture its diffuse reflectance is read from (the surface's constant is then the texture's
    /// largest value in each channel).
    texture: Option<Rc<Tex>>,
}

/// A texture with the element it was read from (to locate what a later check finds wrong with it).
#[derive(Debug)]
struct Tex {
    texture: Texture,
    at: Elem,
}

/// Whether two bsdfs read the same texture (or neither reads one).
fn same_texture(a: &Option<Rc<Tex>>, b: &Option<Rc<Tex>>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => Rc::ptr_eq(a, b) || a.texture == b.texture,
        _ => false,
    }
}

/// Indices of the refraction of Mitsuba's named materials (`int_ior="bk7"`), from its documentation.
const IOR_TABLE: &[(&str, f64)] = &[
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.3330),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.5750),
    ("diamond", 2.419),
];

/// What the scene's objects became, and where each came from (to locate a failed check).
struct Builder {
    scene: Scene,
    root: Elem,
    bsdfs: HashMap<String, Bsdf>,
    /// Top-level textures by id (`<ref id=".." name="reflectance"/>` in a bsdf reads them).
    textures: HashMap<String, Rc<Tex>>,
    /// Field path prefix (`quad[3]`, `materials.white`, `camera`) -> the element it came from.
    origins: HashMap<String, Elem>,
    sensor: Option<Elem>,
    shapes: usize,
}

/// Shapes whose back side can be seen (a one-sided BSDF on them renders differently here).
#[derive(Clone, Copy, PartialEq)]
enum Closed {
    Yes,
    No,
}

impl Builder {
    fn new(name: String, root: Elem) -> Builder {
        Builder {
            scene: Scene {
                name,
                camera: Camera {
                    eye: Vec3::ZERO,
                    look_at: Vec3::NEG_Z,
                    up: Vec3::Y,
                    vfov_deg: 0.0,
                    width: 0,
                    height: 0,
                },
                materials: Vec::new(),
                textures: Vec::new(),
                spheres: Vec::new(),
                quads: Vec::new(),
                meshes: Vec::new(),
                regions: Vec::new(),
                warnings: Vec::new(),
            },
            root,
            bsdfs: HashMap::new(),
            textures: HashMap::new(),
            origins: HashMap::new(),
            sensor: None,
            shapes: 0,
        }
    }

    fn warn(&mut self, e: &Elem, msg: impl fmt::Display) {
        self.scene.warnings.push(e.warning(msg));
    }

    fn top_level(&mut self, e: &Elem) -> Result<()> {
        match e.tag.as_str() {
            "integrator" => self.integrator(e),
            "sensor" => {
                if self.sensor.is_some() {
                    self.warn(
                        e,
                        "a second sensor: ignored (ppm-vk renders the first, as Mitsuba does by default)",
                    );
                } else {
                    self.sensor = Some(e.clone());
                }
                Ok(())
            }
            "bsdf" => {
                let b = self.bsdf(e)?;
                match &b.id {
                    Some(id) if self.bsdfs.contains_key(id) || self.textures.contains_key(id) => {
                        return Err(e.err(format!(
                            "the id \"{id}\" is already taken (ids are unique, as in Mitsuba)"
                        )));
                    }
                    Some(id) => {
                        self.bsdfs.insert(id.clone(), b);
                    }
                    None => self.warn(e, "a top-level bsdf without an id cannot be used: ignored"),
                }
                Ok(())
            }
            "shape" => self.shape(e),
            "emitter" => Err(e.err(
                "only area emitters inside a shape are supported (no point, spot, directional, \
                 constant or environment lights)",
            )),
            "texture" => {
                let Some(id) = e.attr("id") else {
                    self.warn(e, "a top-level texture without an id cannot be used: ignored");
                    return Ok(());
                };
                if self.bsdfs.contains_key(id) || self.textures.contains_key(id) {
                    return Err(e.err(format!(
                        "the id \"{id}\" is already taken (ids are unique, as in Mitsuba)"
                    )));
                }
                let t = self.texture(e)?;
                self.textures.insert(id.to_string(), Rc::new(t));
                Ok(())
            }
            "medium" => Err(e.err("participating media are not supported")),
            _ => Err(e.err("not supported here (see docs/mitsuba.md for the subset read)")),
        }
    }

    /// Integrators only choose how Mitsuba estimates the image; ppm-vk computes the same image
    /// (all paths) with its own. What would make Mitsuba's image differ is warned about.
    fn integrator(&mut self, e: &Elem) -> Result<()> {
        const FULL: &[&str] = &["path", "volpath", "volpathmis", "ptracer", "prb", "prbvolpath"];
        if !FULL.contains(&e.kind()) {
            self.warn(
                e,
                "ppm-vk renders all light paths (global illumination), not this integrator's image",
            );
        }
        let (props, _) = Props::of(e);
        if let Some(d) = props.float("max_depth")? {
            if d != -1.0 {
                self.warn(e, format!("max_depth {d} ignored: ppm-vk renders paths of any length"));
            }
        }
        Ok(())
    }

    fn bsdf(&mut self, e: &Elem) -> Result<Bsdf> {
        let (props, objects) = Props::of(e);
        let id = e.attr("id").map(str::to_string);
        let nested: Vec<&Elem> = objects.iter().copied().filter(|c| c.tag == "bsdf").collect();
        if let Some(o) = objects.iter().find(|c| c.tag != "bsdf") {
            return Err(o.err(format!("not expected inside {}", e.what())));
        }
        if e.kind() != "twosided" {
            if let Some(n) = nested.first() {
                return Err(n.err(format!("a bsdf nested in {} is not supported", e.what())));
            }
        }
        let mut texture = None;
        let surface = match e.kind() {
            "diffuse" => {
                let (albedo, t) = self.reflectance(&props, "reflectance")?;
                texture = t;
                Surface::Diffuse { albedo }
            }
            "twosided" => {
                let inner = match nested[..] {
                    [one] => self.bsdf(one)?,
                    [a, b] => {
                        let (x, y) = (self.bsdf(a)?, self.bsdf(b)?);
                        if x.surface != y.surface || !same_texture(&x.texture, &y.texture) {
                            return Err(b.err(
                                "a different bsdf on the back side is not supported (ppm-vk \
                                 surfaces are the same on both sides)",
                            ));
                        }
                        x
                    }
                    _ => return Err(e.err("needs one nested bsdf")),
                };
                if inner.two_sided || matches!(inner.surface, Surface::Glass { .. }) {
                    return Err(e.err("wraps a two-sided bsdf (Mitsuba refuses this too)"));
                }
                props.finish()?;
                return Ok(Bsdf {
                    two_sided: true,
                    id,
                    ..inner
                });
            }
            kind @ ("conductor" | "roughconductor") => {
                // Mitsuba's conductor: a named metal (its RGB eta and k, scene/conductors.rs), or eta and
                // k given (both default to the "none" material's: a perfect mirror).
                let (none_eta, none_k) = conductors::named("none").expect("the default conductor");
                let (eta, k) = match props.string("material")? {
                    Some(name) => {
                        if props.get("eta").is_some() || props.get("k").is_some() {
                            return Err(e.err("give a material name or eta and k, not both (Mitsuba refuses this too)"));
                        }
                        conductors::named(name).ok_or_else(|| {
                            let known: Vec<&str> = conductors::names().collect();
                            e.err(format!(
                                "unknown conductor material \"{name}\" (known: {})",
                                known.join(", ")
                            ))
                        })?
                    }
                    None => (
                        props.color("eta")?.unwrap_or(none_eta),
                        props.color("k")?.unwrap_or(none_k),
                    ),
                };
                let reflectance = props.color("specular_reflectance")?.unwrap_or(Vec3::ONE);
                match kind {
                    "roughconductor" => Surface::RoughConductor {
                        reflectance,
                        eta,
                        k,
                        rough: microfacet(e, &props)?,
                    },
                    _ => Surface::conductor(reflectance, eta, k),
                }
            }
            kind @ ("dielectric" | "roughdielectric") => {
                let (int, ext) = (ior(e, &props, "int_ior", "bk7")?, ior(e, &props, "ext_ior", "air")?);
                for name in ["specular_reflectance", "specular_transmittance"] {
                    if let Some(c) = props.color(name)? {
                        if c != Vec3::ONE {
                            return Err(props
                                .get(name)
                                .unwrap()
                                .err("only 1 is supported (ppm-vk glass is clear and follows Fresnel)"));
                        }
                    }
                }
                if int < ext {
                    return Err(e.err(format!(
                        "int_ior {int} < ext_ior {ext}: ppm-vk glass is denser than its outside \
                         (relative index >= 1)"
                    )));
                }
                let ior = (int / ext) as f32;
                let surface = match kind {
                    "roughdielectric" => Surface::RoughGlass {
                        ior,
                        rough: microfacet(e, &props)?,
                    },
                    _ => Surface::Glass { ior },
                };
                props.finish()?;
                return Ok(Bsdf {
                    surface,
                    two_sided: true,
                    id,
                    texture: None,
                });
            }
            "thindielectric" => {
                let (int, ext) = (ior(e, &props, "int_ior", "bk7")?, ior(e, &props, "ext_ior", "air")?);
                let surface = Surface::ThinDielectric {
                    ior: (int / ext) as f32,
                    reflectance: props.color("specular_reflectance")?.unwrap_or(Vec3::ONE),
                    transmittance: props.color("specular_transmittance")?.unwrap_or(Vec3::ONE),
                };
                props.finish()?;
                // Mitsuba's thin dielectric is the same from both sides.
                return Ok(Bsdf {
                    surface,
                    two_sided: true,
                    id,
                    texture: None,
                });
            }
            kind @ ("plastic" | "roughplastic") => {
                let (int, ext) = (
                    ior(e, &props, "int_ior", "polypropylene")?,
                    ior(e, &props, "ext_ior", "air")?,
                );
                let (mut diffuse, t) = self.reflectance(&props, "diffuse_reflectance")?;
                let specular = props.color("specular_reflectance")?.unwrap_or(Vec3::ONE);
                let nonlinear = props.boolean("nonlinear")?;
                let rough = match kind {
                    "roughplastic" => {
                        let rough = microfacet(e, &props)?;
                        if rough.is_anisotropic() {
                            return Err(e.err("roughplastic is isotropic (Mitsuba reads alpha only): give alpha"));
                        }
                        Some(rough)
                    }
                    _ => None,
                };
                texture = t;
                // A texture above the photons' bound is lowered per pixel, as Surface::plastic lowers a
                // constant (which then stays within it).
                let coat = super::plastic::coat((int / ext) as f32, rough);
                let most = super::plastic::max_diffuse_reflectance((int / ext) as f32, nonlinear, &coat);
                if let Some(t) = &texture {
                    if let Some((lowered, n)) = t.texture.lowered(most) {
                        let what = match lowered.pattern {
                            Pattern::Bitmap { .. } => "pixels",
                            Pattern::Checkerboard { .. } => "colours",
                        };
                        self.warn(
                            e,
                            format!(
                                "diffuse_reflectance texture \"{}\": {n} {what} lowered to at most {most:.4} per \
                                 channel: above it a photon's diffuse bounce off this coat (index {}) would gain \
                                 flux (docs/scene-format.md, plastic)",
                                t.texture.name,
                                (int / ext) as f32
                            ),
                        );
                        diffuse = lowered.max();
                        texture = Some(Rc::new(Tex {
                            texture: lowered,
                            at: t.at.clone(),
                        }));
                    }
                }
                let (surface, lowered) = Surface::plastic(diffuse, specular, (int / ext) as f32, nonlinear, rough);
                if let Some(message) = lowered {
                    self.warn(e, message);
                }
                surface
            }
            _ => {
                return Err(e.err(
                    "unsupported bsdf (read: diffuse, twosided, conductor, roughconductor, \
                     dielectric, roughdielectric, thindielectric, plastic, roughplastic)",
                ))
            }
        };
        props.finish()?;
        Ok(Bsdf {
            surface,
            two_sided: false,
            id,
            texture,
        })
    }

    /// A diffuse reflectance parameter (`reflectance`, `diffuse_reflectance`; Mitsuba's default 0.5): a
    /// colour, or a texture (nested, or a `ref` to a top-level one) whose values are reflectances, with
    /// its largest value in each channel.
    fn reflectance(&self, props: &Props, name: &str) -> Result<(Vec3, Option<Rc<Tex>>)> {
        let Some(p) = props.get(name) else {
            return Ok((Vec3::splat(0.5), None));
        };
        let t = match p.tag.as_str() {
            "texture" => Rc::new(self.texture(p)?),
            "ref" => {
                let id = p.required("id")?;
                self.textures.get(id).cloned().ok_or_else(|| {
                    let mut known: Vec<&str> = self.textures.keys().map(String::as_str).collect();
                    known.sort();
                    let known = if known.is_empty() {
                        "none".to_string()
                    } else {
                        known.join(", ")
                    };
                    p.err(format!(
                        "no texture with id \"{id}\" defined before it (known: {known})"
                    ))
                })?
            }
            _ => return Ok((color(p)?, None)),
        };
        if let Some(bad) = t.texture.out_of_range() {
            return Err(t.at.err(format!(
                "{}: {bad}: a reflectance texture's values must be in [0, 1]",
                t.texture.name
            )));
        }
        Ok((t.texture.max(), Some(t)))
    }

    /// A `<texture>`: Mitsuba's `bitmap` (its image read here, relative to the scene file) or
    /// `checkerboard`.
    fn texture(&self, e: &Elem) -> Result<Tex> {
        let (props, objects) = Props::of(e);
        if let Some(o) = objects.first() {
            return Err(o.err(format!("not expected inside {}", e.what())));
        }
        let to_uv = texture::uv_map_from_affine(&props.transform("to_uv")?);
        let choice = |name: &str, default: &str, known: &[&str]| -> Result<String> {
            let v = props.string(name)?.unwrap_or(default);
            if known.contains(&v) {
                Ok(v.to_string())
            } else {
                Err(props
                    .get(name)
                    .unwrap()
                    .err(format!("\"{v}\": expected {}", known.join(", "))))
            }
        };
        let texture = match e.kind() {
            "bitmap" => {
                let path = self.file(e, &props)?;
                let filter = match choice("filter_type", "bilinear", &["bilinear", "nearest"])?.as_str() {
                    "nearest" => Filter::Nearest,
                    _ => Filter::Bilinear,
                };
                let wrap = match choice("wrap_mode", "repeat", &["repeat", "mirror", "clamp"])?.as_str() {
                    "mirror" => Wrap::Mirror,
                    "clamp" => Wrap::Clamp,
                    _ => Wrap::Repeat,
                };
                let raw = props.boolean("raw")?;
                // How Mitsuba stores the pixels (half or single precision) and whether it uses the GPU's
                // texture units: not what the image holds.
                choice("format", "auto", &["auto", "variant", "fp16"])?;
                props.ignore(&["accel"]);
                props.finish()?;
                let shown = path.display().to_string();
                Texture::bitmap(&path, &shown, raw, filter, wrap, to_uv).map_err(|m| e.err(format!("{shown}: {m}")))?
            }
            "checkerboard" => {
                let color0 = props.color("color0")?.unwrap_or(Vec3::splat(0.4));
                let color1 = props.color("color1")?.unwrap_or(Vec3::splat(0.2));
                props.finish()?;
                Texture {
                    name: "checkerboard".into(),
                    pattern: Pattern::Checkerboard { color0, color1 },
                    filter: Filter::Bilinear,
                    wrap: Wrap::Repeat,
                    to_uv,
                }
            }
            _ => return Err(e.err("unsupported texture (read: bitmap, checkerboard)")),
        };
        Ok(Tex { texture, at: e.clone() })
    }

    /// Index of the scene material for `bsdf` with `emission`, named `name` (made on first use; the
    /// same name for different contents gets a suffix).
    fn material(&mut self, name: &str, bsdf: &Bsdf, emission: Vec3, e: &Elem) -> u32 {
        let texture = bsdf
            .texture
            .as_ref()
            .map(|t| texture::intern(&mut self.scene.textures, std::borrow::Cow::Borrowed(&t.texture)));
        let wanted = Material {
            name: name.to_string(),
            surface: bsdf.surface,
            emission,
            texture,
        };
        let mut candidate = name.to_string();
        for n in 2.. {
            match self.scene.materials.iter().position(|m| m.name == candidate) {
                Some(i)
                    if self.scene.materials[i]
                        == Material {
                            name: candidate.clone(),
                            ..wanted.clone()
                        } =>
                {
                    return i as u32
                }
                Some(_) => candidate = format!("{name}#{n}"),
                None => break,
            }
        }
        self.origins.insert(format!("materials.{candidate}"), e.clone());
        if let Some(t) = &bsdf.texture {
            self.origins
                .insert(format!("materials.{candidate}.texture"), t.at.clone());
        }
        self.scene.materials.push(Material {
            name: candidate,
            ..wanted
        });
        (self.scene.materials.len() - 1) as u32
    }

    fn shape(&mut self, e: &Elem) -> Result<()> {
        let index = self.shapes;
        self.shapes += 1;
        let (props, objects) = Props::of(e);
        let mut bsdf: Option<(Bsdf, &Elem)> = None;
        let mut emission: Option<(Vec3, &Elem)> = None;
        for o in objects {
            match o.tag.as_str() {
                "bsdf" | "ref" => {
                    if bsdf.is_some() {
                        return Err(o.err("a second bsdf: a shape has one (as in Mitsuba)"));
                    }
                    let b = if o.tag == "bsdf" {
                        self.bsdf(o)?
                    } else {
                        let id = o.required("id")?;
                        self.bsdfs.get(id).cloned().ok_or_else(|| {
                            let mut known: Vec<&str> = self.bsdfs.keys().map(String::as_str).collect();
                            known.sort();
                            o.err(format!(
                                "no bsdf with id \"{id}\" defined before it (known: {})",
                                if known.is_empty() {
                                    "none".to_string()
                                } else {
                                    known.join(", ")
                                }
                            ))
                        })?
                    };
                    bsdf = Some((b, o));
                }
                "emitter" => {
                    if o.kind() != "area" {
                        return Err(o.err("only area emitters are supported on shapes"));
                    }
                    let (ep, rest) = Props::of(o);
                    if let Some(r) = rest.first() {
                        return Err(r.err(format!("not expected inside {}", o.what())));
                    }
                    let radiance = ep.color("radiance")?.unwrap_or(Vec3::ONE);
                    ep.finish()?;
                    emission = Some((radiance, o));
                }
                "medium" => return Err(o.err("participating media are not supported")),
                _ => return Err(o.err(format!("not expected inside {}", e.what()))),
            }
        }
        // Mitsuba gives a shape without a bsdf a diffuse one of reflectance 0.5.
        let (bsdf, bsdf_at) = bsdf.unwrap_or((
            Bsdf {
                surface: Surface::Diffuse {
                    albedo: Vec3::splat(0.5),
                },
                two_sided: false,
                id: None,
                texture: None,
            },
            e,
        ));
        let shape_name = e.attr("id").map_or_else(|| format!("shape[{index}]"), str::to_string);
        let (emission, emitter_at) = emission.unwrap_or((Vec3::ZERO, e));
        if emission.max_element() > 0.0 && !matches!(bsdf.surface, Surface::Diffuse { .. }) {
            return Err(emitter_at.err(format!(
                "an area emitter on a {} surface: ppm-vk lights are diffuse (or black) only",
                match bsdf.surface {
                    Surface::Glass { .. } | Surface::RoughGlass { .. } => "dielectric",
                    Surface::Plastic { .. } => "plastic",
                    Surface::ThinDielectric { .. } => "thin dielectric",
                    _ => "conductor",
                }
            )));
        }
        let name = match (&bsdf.id, emission.max_element() > 0.0) {
            (Some(id), false) => id.clone(),
            _ => shape_name,
        };
        let to_world = props.transform("to_world")?;
        let flip = props.boolean("flip_normals")?;
        let textured = bsdf.texture.is_some();
        // An anisotropic lobe lies along Mitsuba's dp/du: a rectangle's x axis (edge_u below), a sphere's
        // longitude, a mesh's texture coordinates (or the frame of its face normal without them).
        let anisotropic = bsdf.surface.rough().is_some_and(|r| r.is_anisotropic());
        if anisotropic && matches!(e.kind(), "cube" | "disk") {
            return Err(bsdf_at.err(format!(
                "anisotropic roughness on a {} is not supported yet (read on rectangles, spheres and OBJ and \
                 PLY meshes)",
                e.kind()
            )));
        }
        if textured && matches!(e.kind(), "cube" | "disk") {
            return Err(bsdf_at.err(format!(
                "texture coordinates of a {} are not supported yet (textures are read on rectangles, spheres, \
                 and OBJ and PLY meshes with texture coordinates)",
                e.kind()
            )));
        }
        // A rectangle's quad has Mitsuba's uv as its coordinates along edge_u and edge_v. A mirroring
        // to_world or flip_normals turns its front side around by swapping the edges, which would swap
        // u and v: a textured one instead runs its first edge backwards from the corner (1, -1), so that
        // its coordinates are (1 - u, v), and its texture's to_uv takes them back to (u, v) first.
        // An anisotropic one does the same, so that edge_u stays along (minus) Mitsuba's x axis.
        let turned = (to_world.matrix3.determinant() < 0.0) != flip;
        let backwards = e.kind() == "rectangle" && turned && (textured || anisotropic);
        let material = match (&bsdf.texture, backwards) {
            (Some(t), true) => {
                let mirrored = Texture {
                    to_uv: texture::compose_uv(t.texture.to_uv, [-1.0, 0.0, 1.0, 0.0, 1.0, 0.0]),
                    ..t.texture.clone()
                };
                let turned_bsdf = Bsdf {
                    texture: Some(Rc::new(Tex {
                        texture: mirrored,
                        at: t.at.clone(),
                    })),
                    ..bsdf.clone()
                };
                self.material(&name, &turned_bsdf, emission, bsdf_at)
            }
            _ => self.material(&name, &bsdf, emission, bsdf_at),
        };
        let closed = match e.kind() {
            "rectangle" if backwards => {
                // quad() swaps the edges of a turned quad: edge_u = -x, edge_v = +y from (1, -1).
                self.quad(
                    e,
                    &to_world,
                    flip,
                    [1.0, -1.0, 0.0],
                    [0.0, 2.0, 0.0],
                    [-2.0, 0.0, 0.0],
                    material,
                );
                Closed::No
            }
            "rectangle" => {
                self.quad(
                    e,
                    &to_world,
                    flip,
                    [-1.0, -1.0, 0.0],
                    [2.0, 0.0, 0.0],
                    [0.0, 2.0, 0.0],
                    material,
                );
                Closed::No
            }
            "cube" => {
                // Each face of [-1, 1]^3 with its normal outward: edges u x v along +axis, swapped
                // for the face on the negative side.
                for axis in 0..3 {
                    let unit = |k: usize| DVec3::AXES[k % 3];
                    for side in [1.0, -1.0] {
                        let (mut u, mut v) = (2.0 * unit(axis + 1), 2.0 * unit(axis + 2));
                        let origin = side * unit(axis) - 0.5 * (u + v);
                        if side < 0.0 {
                            std::mem::swap(&mut u, &mut v);
                        }
                        self.quad(
                            e,
                            &to_world,
                            flip,
                            origin.to_array(),
                            u.to_array(),
                            v.to_array(),
                            material,
                        );
                    }
                }
                Closed::Yes
            }
            "disk" => {
                let n = DISK_SEGMENTS;
                let step = std::f64::consts::TAU / f64::from(n);
                // The regular n-gon of area pi: radius sqrt(2 pi / (n sin(2 pi / n))).
                let r = (std::f64::consts::TAU / (f64::from(n) * step.sin())).sqrt();
                let mut positions = vec![DVec3::ZERO];
                positions.extend((0..n).map(|i| {
                    let a = step * f64::from(i);
                    DVec3::new(r * a.cos(), r * a.sin(), 0.0)
                }));
                let triangles = (0..n).map(|i| ([0, 1 + i, 1 + (i + 1) % n], material)).collect();
                let raw = RawMesh {
                    name: format!("{} disk", e.loc),
                    positions,
                    normals: None,
                    partial_normals: false,
                    uvs: None,
                    triangles,
                };
                self.mesh(e, raw, &to_world, flip)?;
                Closed::No
            }
            "sphere" => {
                let center = props.point("center")?.unwrap_or(DVec3::ZERO);
                let radius = props.float("radius")?.unwrap_or(1.0);
                let m = to_world * DAffine3::from_translation(center) * DAffine3::from_scale(DVec3::splat(radius));
                let gram = m.matrix3.transpose() * m.matrix3;
                let s2 = gram.x_axis.x;
                let off = (gram - DMat3::from_diagonal(DVec3::splat(s2))).to_cols_array();
                if off.iter().any(|x| x.abs() > 1e-6 * s2) {
                    return Err(e.err("to_world scales the sphere non-uniformly (an ellipsoid): not supported"));
                }
                if emission.max_element() > 0.0 {
                    return Err(
                        emitter_at.err("an emitting sphere: ppm-vk lights are quads and triangles (use a mesh)")
                    );
                }
                if flip && matches!(bsdf.surface, Surface::Glass { .. }) {
                    return Err(e.err("flip_normals on a dielectric sphere (its inside outside) is not supported"));
                }
                // Mitsuba's sphere uv is taken in its object axes, the engine's along the world's.
                let axes = m.matrix3 * (1.0 / s2.sqrt()) - DMat3::IDENTITY;
                if textured && axes.to_cols_array().iter().any(|x| x.abs() > 1e-6) {
                    return Err(e.err(
                        "a textured sphere whose to_world rotates or mirrors it is not supported (its texture \
                         coordinates are taken along the world's axes)",
                    ));
                }
                if anisotropic && axes.to_cols_array().iter().any(|x| x.abs() > 1e-6) {
                    return Err(e.err(
                        "an anisotropic sphere whose to_world rotates or mirrors it is not supported (its \
                         tangents are taken along the world's axes)",
                    ));
                }
                self.origins
                    .insert(format!("sphere[{}]", self.scene.spheres.len()), e.clone());
                self.scene.spheres.push(Sphere {
                    center: m.translation.as_vec3(),
                    radius: s2.sqrt() as f32,
                    material,
                });
                Closed::Yes
            }
            "obj" => {
                let path = self.file(e, &props)?;
                let flip_tex_coords = props.boolean_or("flip_tex_coords", true)?;
                let i = obj::import(
                    &mut self.scene,
                    &path,
                    &ObjImport {
                        transform: to_world,
                        material: Some(material),
                    },
                    MAX_TRIANGLES,
                    flip_tex_coords,
                )
                .map_err(|err| e.err(format!("{err:#}")))?;
                if textured && self.scene.meshes[i].uvs.is_none() {
                    return Err(e.err(format!(
                        "{}: no texture coordinates (a vt on every face corner), which the texture of {} needs",
                        path.display(),
                        bsdf_at.what()
                    )));
                }
                self.origins.insert(format!("mesh[{i}]"), e.clone());
                let m = &mut self.scene.meshes[i];
                if flip {
                    m.indices.iter_mut().for_each(|t| t.swap(1, 2));
                    m.normals.iter_mut().flatten().for_each(|n| *n = -*n);
                }
                // As Mitsuba: flat where asked, else the file's vertex normals or its own.
                match props.boolean("face_normals")? {
                    true => m.normals = None,
                    false if m.normals.is_none() => m.compute_vertex_normals(),
                    false => {}
                }
                closed(m)
            }
            "ply" => {
                let path = self.file(e, &props)?;
                let face_normals = props.boolean("face_normals")?;
                let mut raw = read_ply(&path, material).map_err(|err| e.err(format!("{err:#}")))?;
                if face_normals {
                    raw.normals = None;
                }
                if textured && raw.uvs.is_none() {
                    return Err(e.err(format!(
                        "{}: no texture coordinates (float or double vertex properties u and v, texture_u and \
                         texture_v, or s and t), which the texture of {} needs",
                        path.display(),
                        bsdf_at.what()
                    )));
                }
                let i = self.mesh(e, raw, &to_world, flip)?;
                let m = &mut self.scene.meshes[i];
                if !face_normals && m.normals.is_none() {
                    m.compute_vertex_normals();
                }
                closed(m)
            }
            _ => return Err(e.err("unsupported shape (read: rectangle, cube, disk, sphere, obj, ply)")),
        };
        props.finish()?;
        let one_sided = match bsdf.surface {
            Surface::Diffuse { albedo } => albedo != Vec3::ZERO,
            Surface::Mirror { .. }
            | Surface::Conductor { .. }
            | Surface::RoughConductor { .. }
            | Surface::Plastic { .. } => true,
            Surface::Glass { .. } | Surface::RoughGlass { .. } | Surface::ThinDielectric { .. } => false,
        };
        if closed == Closed::No && one_sided && !bsdf.two_sided {
            self.warn(
                bsdf_at,
                format!(
                    "one-sided in Mitsuba (black seen from behind) on {}, which ppm-vk renders \
                     reflecting on both sides: wrap it in a twosided bsdf to say so",
                    e.what()
                ),
            );
        }
        Ok(())
    }

    /// The quad `origin + s u + t v` (object space) placed by `m`; its front normal is `u x v` turned
    /// as Mitsuba turns normals (the inverse transpose), and flipped with `flip`.
    // The element, its transform, its flip and the quad's corner, edges and material: a struct would
    // only name them again.
    #[allow(clippy::too_many_arguments)]
    fn quad(&mut self, e: &Elem, m: &DAffine3, flip: bool, origin: [f64; 3], u: [f64; 3], v: [f64; 3], material: u32) {
        let (mut u, mut v) = (m.transform_vector3(u.into()), m.transform_vector3(v.into()));
        // A mirroring transform turns u x v against the inverse-transposed normal.
        if (m.matrix3.determinant() < 0.0) != flip {
            std::mem::swap(&mut u, &mut v);
        }
        self.origins
            .insert(format!("quad[{}]", self.scene.quads.len()), e.clone());
        self.scene.quads.push(Quad {
            origin: m.transform_point3(origin.into()).as_vec3(),
            edge_u: u.as_vec3(),
            edge_v: v.as_vec3(),
            material,
        });
    }

    fn mesh(&mut self, e: &Elem, raw: RawMesh, m: &DAffine3, flip: bool) -> Result<usize> {
        let i = obj::add_mesh(&mut self.scene, raw, m, flip).map_err(|err| e.err(format!("{err:#}")))?;
        self.origins.insert(format!("mesh[{i}]"), e.clone());
        Ok(i)
    }

    /// The `filename` of a mesh shape, relative to the scene file's directory.
    fn file(&self, e: &Elem, props: &Props) -> Result<PathBuf> {
        let name = props
            .string("filename")?
            .ok_or_else(|| e.err("needs <string name=\"filename\" .../>"))?;
        let dir = Path::new(&*e.loc.file).parent().unwrap_or(Path::new(""));
        Ok(dir.join(name))
    }

    fn camera(&mut self) -> Result<()> {
        let Some(e) = self.sensor.take() else {
            return Err(self
                .root
                .err("no <sensor>: give a perspective sensor (ppm-vk has no default camera)"));
        };
        if e.kind() != "perspective" {
            return Err(e.err("only the perspective (pinhole) sensor is supported"));
        }
        let (props, objects) = Props::of(&e);
        let mut size = (768, 576); // hdrfilm's defaults
        let mut film_seen = false;
        for o in objects {
            match (o.tag.as_str(), o.kind()) {
                ("film", "hdrfilm") => {
                    film_seen = true;
                    size = self.film(o)?;
                }
                ("film", _) => return Err(o.err("only hdrfilm is supported")),
                // The sampler decides only the noise of Mitsuba's estimate; ppm-vk's --seed is its own.
                ("sampler", _) => {}
                _ => return Err(o.err(format!("not expected inside {}", e.what()))),
            }
        }
        if !film_seen {
            self.warn(
                &e,
                "no film: hdrfilm's defaults (768 x 576, gaussian filter) apply; rendered with a box filter",
            );
        }
        let aspect = f64::from(size.0) / f64::from(size.1);
        let x_fov = fov_x(&props, aspect, &e)?;
        let m = props.transform("to_world")?;
        for name in ["principal_point_offset_x", "principal_point_offset_y"] {
            if props.float(name)?.is_some_and(|v| v != 0.0) {
                return Err(props
                    .get(name)
                    .unwrap()
                    .err("an off-centre principal point is not supported"));
            }
        }
        props.ignore(&["near_clip", "shutter_open", "shutter_close"]);
        let far = props.float("far_clip")?;
        props.finish()?;
        let l = m.matrix3;
        if (l.transpose() * l - DMat3::IDENTITY)
            .to_cols_array()
            .iter()
            .any(|x| x.abs() > 1e-4)
        {
            return Err(e.err("to_world of the sensor has a scale or shear (Mitsuba refuses scale factors too)"));
        }
        if l.determinant() < 0.0 {
            return Err(e.err("to_world of the sensor mirrors the image: not supported"));
        }
        let eye = m.translation;
        let vfov = 2.0 * ((0.5 * x_fov.to_radians()).tan() / aspect).atan();
        self.scene.camera = Camera {
            eye: eye.as_vec3(),
            look_at: (eye + l.z_axis).as_vec3(),
            up: l.y_axis.as_vec3(),
            vfov_deg: vfov.to_degrees() as f32,
            width: size.0,
            height: size.1,
        };
        self.origins.insert("camera".into(), e.clone());
        if let Some(far) = far {
            let (lo, hi) = self.scene.bounds();
            let farthest = (0..8)
                .map(|k| {
                    let c = DVec3::new(
                        if k & 1 == 0 { lo.x } else { hi.x } as f64,
                        if k & 2 == 0 { lo.y } else { hi.y } as f64,
                        if k & 4 == 0 { lo.z } else { hi.z } as f64,
                    );
                    (c - eye).length()
                })
                .fold(0.0, f64::max);
            if far < farthest {
                self.warn(
                    &e,
                    format!("far_clip {far} ignored: ppm-vk renders the scene out to {farthest:.3}"),
                );
            }
        }
        Ok(())
    }

    fn film(&mut self, o: &Elem) -> Result<(u32, u32)> {
        let (fp, rest) = Props::of(o);
        let size = |name: &str, default: u32| -> Result<u32> {
            match fp.float(name)? {
                None => Ok(default),
                Some(v) if v >= 1.0 && v.fract() == 0.0 && v <= f64::from(u32::MAX) => Ok(v as u32),
                Some(v) => Err(fp
                    .get(name)
                    .unwrap()
                    .err(format!("must be a positive integer, got {v}"))),
            }
        };
        let size = (size("width", 768)?, size("height", 576)?);
        for name in ["crop_offset_x", "crop_offset_y", "crop_width", "crop_height"] {
            if let Some(p) = fp.get(name) {
                return Err(p.err("a crop window is not supported"));
            }
        }
        // Output encoding only: the image is the same.
        fp.ignore(&[
            "pixel_format",
            "component_format",
            "file_format",
            "banner",
            "high_quality_edges",
            "sample_border",
            "compensate",
        ]);
        fp.finish()?;
        match rest[..] {
            [] => self.warn(
                o,
                "no rfilter: Mitsuba's default is gaussian; ppm-vk renders with a box filter",
            ),
            [r] if r.tag == "rfilter" && r.kind() == "box" => {}
            [r] if r.tag == "rfilter" => self.warn(r, "ppm-vk renders with a box filter"),
            _ => return Err(rest[0].err(format!("not expected inside {}", o.what()))),
        }
        Ok(size)
    }

    fn finish(mut self) -> Result<Scene> {
        self.camera()?;
        let root = self.root.clone();
        self.scene.check().map_err(|inv| {
            // The element of the field path's longest known prefix (`quad[3]` for `quad[3].edge_v`).
            let mut path = inv.path.as_str();
            let at = loop {
                if let Some(e) = self.origins.get(path) {
                    break e;
                }
                match path.rfind('.') {
                    Some(i) => path = &path[..i],
                    None => break &root,
                }
            };
            at.err(&inv)
        })?;
        Ok(self.scene)
    }
}

/// `fov` (with `fov_axis`) or `focal_length` as the horizontal field of view in degrees, as
/// Mitsuba's `parse_fov`.
fn fov_x(props: &Props, aspect: f64, e: &Elem) -> Result<f64> {
    let (fov, axis) = match (props.float("fov")?, props.string("focal_length")?) {
        (Some(_), Some(_)) => return Err(e.err("give either fov or focal_length, not both")),
        (Some(fov), None) => {
            let axis = props.string("fov_axis")?.unwrap_or("x").to_ascii_lowercase();
            let axis = match axis.as_str() {
                "smaller" => if aspect > 1.0 { "y" } else { "x" }.to_string(),
                "larger" => if aspect > 1.0 { "x" } else { "y" }.to_string(),
                _ => axis,
            };
            (fov, axis)
        }
        (None, focal) => {
            let f = focal.unwrap_or("50mm");
            let mm = number(e, f.strip_suffix("mm").unwrap_or(f))?;
            // The diagonal of a 36 x 24 mm frame.
            (
                (36f64.hypot(24.0) / (2.0 * mm)).atan().to_degrees() * 2.0,
                "diagonal".to_string(),
            )
        }
    };
    if !(fov > 0.0 && fov < 180.0) {
        return Err(e.err(format!("fov must be in (0, 180) degrees, got {fov}")));
    }
    let half = (0.5 * fov.to_radians()).tan();
    let x = match axis.as_str() {
        "x" => fov,
        "y" => (2.0 * (half * aspect).atan()).to_degrees(),
        "diagonal" => (2.0 * (half / (1.0 + 1.0 / (aspect * aspect)).sqrt()).atan()).to_degrees(),
        other => {
            return Err(e.err(format!(
                "fov_axis \"{other}\": expected x, y, diagonal, smaller or larger"
            )))
        }
    };
    Ok(x)
}

/// A bsdf's index of refraction `name` (int_ior, ext_ior): a <float>, a <string> naming a material, or
/// Mitsuba's `default` when absent.
/// A rough BSDF's microfacet distribution: `distribution` (Mitsuba's default "beckmann", or "ggx") and
/// `alpha` (default 0.1), or `alpha_u` and `alpha_v` (anisotropic: along the shape's dp/du and across),
/// each raised to Mitsuba's floor 1e-4 as Mitsuba does; `sample_visible` changes only how Mitsuba samples
/// (ppm-vk always samples visible normals).
fn microfacet(e: &Elem, props: &Props) -> Result<Microfacet> {
    let ggx = match props.string("distribution")? {
        None | Some("beckmann") => false,
        Some("ggx") => true,
        Some(other) => {
            let at = props.get("distribution").unwrap();
            return Err(at.err(format!("unknown distribution \"{other}\" (read: beckmann, ggx)")));
        }
    };
    props.ignore(&["sample_visible"]);
    let (alpha_u, alpha_v) = match (props.float("alpha")?, props.float("alpha_u")?, props.float("alpha_v")?) {
        (Some(a), None, None) => (a, a),
        (None, None, None) => (0.1, 0.1),
        (None, Some(u), Some(v)) => (u, v),
        (Some(_), _, _) => return Err(e.err("give alpha, or alpha_u and alpha_v, not both")),
        (None, _, _) => return Err(e.err("give both alpha_u and alpha_v")),
    };
    for (name, a) in [("alpha", alpha_u), ("alpha_u", alpha_u), ("alpha_v", alpha_v)] {
        if let Some(at) = props.get(name).filter(|_| !(a.is_finite() && a >= 0.0)) {
            return Err(at.err(format!("must be finite and >= 0, got {a}")));
        }
    }
    let floor = |a: f64| (a as f32).max(Microfacet::MIN_ALPHA);
    Ok(Microfacet {
        ggx,
        alpha: floor(alpha_u),
        alpha_v: floor(alpha_v),
    })
}

fn ior(e: &Elem, props: &Props, name: &str, default: &str) -> Result<f64> {
    let Some(p) = props.get(name) else {
        return ior_named(e, default);
    };
    match p.tag.as_str() {
        "float" => number(p, p.required("value")?),
        "string" => ior_named(p, p.required("value")?),
        _ => Err(p.err("expected a <float> or a <string> (a material name)")),
    }
}

fn ior_named(e: &Elem, name: &str) -> Result<f64> {
    if let Ok(v) = name.trim().parse::<f64>() {
        return Ok(v);
    }
    IOR_TABLE
        .iter()
        .find(|(n, _)| n.eq_ignore_ascii_case(name.trim()))
        .map(|(_, v)| *v)
        .ok_or_else(|| e.err(format!("unknown index of refraction \"{name}\"")))
}

/// Whether every edge of `m` (by vertex position) is shared by exactly two triangles.
fn closed(m: &Mesh) -> Closed {
    let mut edges: HashMap<[[u32; 3]; 2], u32> = HashMap::new();
    let key = |i: u32| m.positions[i as usize].to_array().map(f32::to_bits);
    for t in &m.indices {
        for k in 0..3 {
            let (a, b) = (key(t[k]), key(t[(k + 1) % 3]));
            *edges.entry(if a < b { [a, b] } else { [b, a] }).or_default() += 1;
        }
    }
    if edges.values().all(|&n| n == 2) {
        Closed::Yes
    } else {
        Closed::No
    }
}

/// A PLY mesh (ASCII or binary): vertex x, y, z (and nx, ny, nz when all three are there), faces
/// as `vertex_indices` (or `vertex_index`) lists, polygons split into fans from their first corner.
fn read_ply(path: &Path, material: u32) -> Result<RawMesh> {
    use ply_rs_bw::parser::Parser;
    use ply_rs_bw::ply::{DefaultElement, Property};
    let shown = path.display().to_string();
    let file = std::fs::File::open(path).map_err(|e| anyhow!("{shown}: cannot read PLY file: {e}"))?;
    let ply = Parser::<DefaultElement>::new()
        .read_ply(&mut std::io::BufReader::new(file))
        .map_err(|e| anyhow!("{shown}: malformed PLY: {e}"))?;
    let scalar = |p: &Property| -> Option<f64> {
        Some(match *p {
            Property::Float(v) => f64::from(v),
            Property::Double(v) => v,
            Property::Char(v) => f64::from(v),
            Property::UChar(v) => f64::from(v),
            Property::Short(v) => f64::from(v),
            Property::UShort(v) => f64::from(v),
            Property::Int(v) => f64::from(v),
            Property::UInt(v) => f64::from(v),
            _ => return None,
        })
    };
    let vertices = ply
        .payload
        .get("vertex")
        .ok_or_else(|| anyhow!("{shown}: no vertex element"))?;
    let mut positions = Vec::with_capacity(vertices.len());
    let mut normals = Vec::with_capacity(vertices.len());
    let has_normals = vertices
        .first()
        .is_some_and(|v| ["nx", "ny", "nz"].iter().all(|k| v.contains_key(*k)));
    // Texture coordinates under the names Mitsuba reads, in its order, not flipped (as Mitsuba). Only
    // float and double ones: Mitsuba would rescale integer ones.
    let float = |p: Option<&Property>| match p {
        Some(Property::Float(v)) => Some(f64::from(*v)),
        Some(Property::Double(v)) => Some(*v),
        _ => None,
    };
    let uv_names = vertices.first().and_then(|v| {
        [("u", "v"), ("texture_u", "texture_v"), ("s", "t")]
            .into_iter()
            .find(|(a, b)| v.contains_key(*a) && v.contains_key(*b))
            .filter(|(a, b)| float(v.get(*a)).is_some() && float(v.get(*b)).is_some())
    });
    let mut uvs = Vec::with_capacity(if uv_names.is_some() { vertices.len() } else { 0 });
    for (k, v) in vertices.iter().enumerate() {
        let get = |name: &str| -> Result<f64> {
            let x = v
                .get(name)
                .and_then(scalar)
                .ok_or_else(|| anyhow!("{shown}: vertex {k} has no number {name}"))?;
            if x.is_finite() {
                Ok(x)
            } else {
                bail!("{shown}: vertex {k}: {name} is not finite")
            }
        };
        positions.push(DVec3::new(get("x")?, get("y")?, get("z")?));
        if has_normals {
            normals.push(DVec3::new(get("nx")?, get("ny")?, get("nz")?));
        }
        if let Some((a, b)) = uv_names {
            let uv = |name: &str| float(v.get(name)).ok_or_else(|| anyhow!("{shown}: vertex {k} has no number {name}"));
            uvs.push(Vec2::new(uv(a)? as f32, uv(b)? as f32));
        }
    }
    let faces = ply
        .payload
        .get("face")
        .ok_or_else(|| anyhow!("{shown}: no face element"))?;
    let mut triangles = Vec::new();
    for (f, face) in faces.iter().enumerate() {
        let list = face.get("vertex_indices").or_else(|| face.get("vertex_index"));
        let idx: Vec<i64> = match list {
            Some(Property::ListChar(l)) => l.iter().map(|&i| i64::from(i)).collect(),
            Some(Property::ListUChar(l)) => l.iter().map(|&i| i64::from(i)).collect(),
            Some(Property::ListShort(l)) => l.iter().map(|&i| i64::from(i)).collect(),
            Some(Property::ListUShort(l)) => l.iter().map(|&i| i64::from(i)).collect(),
            Some(Property::ListInt(l)) => l.iter().map(|&i| i64::from(i)).collect(),
            Some(Property::ListUInt(l)) => l.iter().map(|&i| i64::from(i)).collect(),
            _ => bail!("{shown}: face {f} has no integer list vertex_indices"),
        };
        if let Some(&bad) = idx.iter().find(|&&i| i < 0 || i as usize >= positions.len()) {
            bail!(
                "{shown}: face {f} has vertex index {bad}, out of range ({} vertices)",
                positions.len()
            );
        }
        if idx.len() < 3 {
            bail!(
                "{shown}: face {f} has {} corners (at least 3 make a surface)",
                idx.len()
            );
        }
        for k in 1..idx.len() - 1 {
            triangles.push(([idx[0] as u32, idx[k] as u32, idx[k + 1] as u32], material));
        }
        if triangles.len() > MAX_TRIANGLES {
            bail!("{shown}: face {f}: more than {MAX_TRIANGLES} triangles: the limit (MAX_TRIANGLES) is reached here");
        }
    }
    if triangles.is_empty() {
        bail!("{shown}: no faces: the mesh is empty");
    }
    Ok(RawMesh {
        name: shown,
        positions,
        normals: has_normals.then_some(normals),
        partial_normals: false,
        uvs: uv_names.map(|_| uvs),
        triangles,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::TempDir;

    /// A camera and a light, so that a scene with one more shape validates.
    const HEAD: &str = r#"<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film>
    </sensor>
    <shape type="rectangle" id="lamp">
        <transform name="to_world"><rotate x="1" angle="90"/><translate y="3"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
        <emitter type="area"><rgb name="radiance" value="1"/></emitter>
    </shape>
"#;

    /// `body` after [`HEAD`], in a scene file of its own (with `files` beside it).
    fn load_in(dir: &TempDir, body: &str, defines: &[(&str, &str)]) -> Result<Scene> {
        let path = dir.write("scene.xml", &format!("{HEAD}{body}\n</scene>\n"));
        let defines: Vec<(String, String)> = defines.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
        load(&path, &defines)
    }

    fn load_body(body: &str) -> Result<Scene> {
        load_in(&TempDir::new("mitsuba"), body, &[])
    }

    /// The error of `body`, as one line.
    fn error(body: &str) -> String {
        match load_body(body) {
            Ok(_) => panic!("expected an error for {body}"),
            Err(e) => format!("{e:#}"),
        }
    }

    /// The TOML quads of `quads` (inline tables) after the same camera and light as [`HEAD`].
    fn toml_quads(quads: &str) -> Vec<Quad> {
        let text = format!(
            "[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\nup = [0, 1, 0]\nvfov = 40\nresolution = [8, 8]\n\
             [materials.m]\ndiffuse = [0.5, 0.5, 0.5]\n[materials.light]\nemission = [1, 1, 1]\n\
             [[quad]]\norigin = [-1, 3, 1]\nedge_u = [2, 0, 0]\nedge_v = [0, 0, -2]\nmaterial = \"light\"\n{quads}"
        );
        let s = Scene::parse(&text, "test.toml").expect("TOML equivalent");
        s.quads[1..].to_vec()
    }

    /// The corners of a quad, as a sorted list (so that corner order does not matter).
    fn corners(q: &Quad) -> Vec<[i64; 3]> {
        let mut c: Vec<[i64; 3]> = [
            q.origin,
            q.origin + q.edge_u,
            q.origin + q.edge_v,
            q.origin + q.edge_u + q.edge_v,
        ]
        .iter()
        .map(|p| p.to_array().map(|x| (x * 1e4).round() as i64))
        .collect();
        c.sort();
        c
    }

    /// Same corners and same front normal.
    fn assert_same_quads(got: &[Quad], want: &[Quad]) {
        assert_eq!(got.len(), want.len(), "{got:?}\nvs\n{want:?}");
        for w in want {
            assert!(
                got.iter()
                    .any(|g| corners(g) == corners(w) && g.normal().distance(w.normal()) < 1e-5),
                "no quad like {w:?} (normal {}) among {got:?}",
                w.normal()
            );
        }
    }

    fn rectangle(transform: &str, extra: &str) -> Vec<Quad> {
        let s = load_body(&format!(
            r#"<shape type="rectangle"><transform name="to_world">{transform}</transform>{extra}
               <bsdf type="twosided"><bsdf type="diffuse"/></bsdf></shape>"#
        ))
        .unwrap_or_else(|e| panic!("{e:#}"));
        s.quads[1..].to_vec()
    }

    #[test]
    fn each_transform_of_a_rectangle_matches_its_toml_quad() {
        let cases: &[(&str, &str)] = &[
            // [-1, 1]^2 at z = 0, normal +z.
            ("", "origin = [-1, -1, 0]\nedge_u = [2, 0, 0]\nedge_v = [0, 2, 0]"),
            (
                r#"<translate x="1" y="2" z="3"/>"#,
                "origin = [0, 1, 3]\nedge_u = [2, 0, 0]\nedge_v = [0, 2, 0]",
            ),
            (
                r#"<translate value="1 2 3"/>"#,
                "origin = [0, 1, 3]\nedge_u = [2, 0, 0]\nedge_v = [0, 2, 0]",
            ),
            (
                r#"<scale x="2" y="3"/>"#,
                "origin = [-2, -3, 0]\nedge_u = [4, 0, 0]\nedge_v = [0, 6, 0]",
            ),
            (
                r#"<scale value="0.5"/>"#,
                "origin = [-0.5, -0.5, 0]\nedge_u = [1, 0, 0]\nedge_v = [0, 1, 0]",
            ),
            // Right-handed: +90 degrees about y takes +z to +x.
            (
                r#"<rotate y="1" angle="90"/>"#,
                "origin = [0, -1, 1]\nedge_u = [0, 0, -2]\nedge_v = [0, 2, 0]",
            ),
            // -90 degrees about x takes +z to +y (the reference's floor).
            (
                r#"<rotate value="1, 0, 0" angle="-90"/>"#,
                "origin = [-1, 0, 1]\nedge_u = [2, 0, 0]\nedge_v = [0, 0, -2]",
            ),
            // Document order: scale first, then translate (the centre moves by 1)...
            (
                r#"<scale value="2"/><translate x="1"/>"#,
                "origin = [-1, -2, 0]\nedge_u = [4, 0, 0]\nedge_v = [0, 4, 0]",
            ),
            // ...against translate first, then scale (the translation is scaled too).
            (
                r#"<translate x="1"/><scale value="2"/>"#,
                "origin = [0, -2, 0]\nedge_u = [4, 0, 0]\nedge_v = [0, 4, 0]",
            ),
            (
                r#"<matrix value="2 0 0 1  0 2 0 0  0 0 2 0  0 0 0 1"/>"#,
                "origin = [-1, -2, 0]\nedge_u = [4, 0, 0]\nedge_v = [0, 4, 0]",
            ),
            // lookat: z to the target direction (+x), y up, x = up x dir = -z.
            (
                r#"<lookat origin="0, 0, 0" target="1, 0, 0" up="0, 1, 0"/>"#,
                "origin = [0, -1, 1]\nedge_u = [0, 0, -2]\nedge_v = [0, 2, 0]",
            ),
            // A mirror keeps the normal Mitsuba computes with the inverse transpose: +z.
            (
                r#"<scale x="-1"/>"#,
                "origin = [-1, -1, 0]\nedge_u = [2, 0, 0]\nedge_v = [0, 2, 0]",
            ),
            (
                r#"<scale z="-1"/>"#,
                "origin = [-1, -1, 0]\nedge_u = [0, 2, 0]\nedge_v = [2, 0, 0]",
            ),
        ];
        for (transform, quad) in cases {
            let want = toml_quads(&format!("[[quad]]\n{quad}\nmaterial = \"m\"\n"));
            assert_same_quads(&rectangle(transform, ""), &want);
        }
        // flip_normals turns the normal to -z.
        let want =
            toml_quads("[[quad]]\norigin = [-1, -1, 0]\nedge_u = [0, 2, 0]\nedge_v = [2, 0, 0]\nmaterial = \"m\"\n");
        assert_same_quads(&rectangle("", r#"<boolean name="flip_normals" value="true"/>"#), &want);
    }

    #[test]
    fn cube_is_six_outward_quads() {
        let box_toml = |inward: bool| {
            let mut s = String::new();
            for (o, u, v) in [
                ("[1, -1, -1]", "[0, 2, 0]", "[0, 0, 2]"),
                ("[-1, -1, -1]", "[0, 0, 2]", "[0, 2, 0]"),
                ("[-1, 1, -1]", "[0, 0, 2]", "[2, 0, 0]"),
                ("[-1, -1, -1]", "[2, 0, 0]", "[0, 0, 2]"),
                ("[-1, -1, 1]", "[2, 0, 0]", "[0, 2, 0]"),
                ("[-1, -1, -1]", "[0, 2, 0]", "[2, 0, 0]"),
            ] {
                let (u, v) = if inward { (v, u) } else { (u, v) };
                s += &format!("[[quad]]\norigin = {o}\nedge_u = {u}\nedge_v = {v}\nmaterial = \"m\"\n");
            }
            toml_quads(&s)
        };
        let cube = |extra: &str| {
            load_body(&format!(r#"<shape type="cube">{extra}<bsdf type="diffuse"/></shape>"#))
                .unwrap()
                .quads[1..]
                .to_vec()
        };
        let outward = cube("");
        assert_same_quads(&outward, &box_toml(false));
        for q in &outward {
            // Outward: the normal points away from the centre.
            assert!(q.normal().dot(q.origin + 0.5 * (q.edge_u + q.edge_v)) > 0.99);
        }
        assert_same_quads(&cube(r#"<boolean name="flip_normals" value="true"/>"#), &box_toml(true));
        // A mirroring transform keeps them outward (Mitsuba flips the winding of a mirrored mesh).
        let mirrored = cube(r#"<transform name="to_world"><scale x="-1"/></transform>"#);
        assert_same_quads(&mirrored, &box_toml(false));
    }

    #[test]
    fn disk_is_an_area_exact_fan_facing_z() {
        let s = load_body(
            r#"<shape type="disk"><transform name="to_world"><scale value="0.5"/><translate z="1"/></transform>
               <bsdf type="diffuse"/><emitter type="area"><rgb name="radiance" value="2"/></emitter></shape>"#,
        )
        .unwrap();
        let m = &s.meshes[0];
        assert_eq!(m.indices.len(), DISK_SEGMENTS as usize);
        let area: f64 = m.triangles().map(|t| f64::from(t.area())).sum();
        let exact = std::f64::consts::PI * 0.25;
        assert!((area / exact - 1.0).abs() < 1e-6, "area {area} vs {exact}");
        for t in m.triangles() {
            assert!(t.normal().distance(Vec3::Z) < 1e-5);
            assert!(t.p.iter().all(|p| (p.z - 1.0).abs() < 1e-6));
        }
        // Every rim vertex 5.0e-5 outside the radius 0.5 (relative: (2 pi / n)^2 / 12), the centre
        // at the centre.
        for p in &m.positions {
            let r = p.truncate().length();
            assert!(r < 1e-6 || (r / 0.5 - 1.0 - 5.02e-5).abs() < 1e-6, "{p}");
        }
        assert_eq!(s.emitting_triangles().len(), DISK_SEGMENTS as usize);
        let flipped = load_body(
            r#"<shape type="disk"><boolean name="flip_normals" value="true"/><bsdf type="diffuse"/></shape>"#,
        )
        .unwrap();
        assert!(flipped.meshes[0]
            .triangles()
            .all(|t| t.normal().distance(Vec3::NEG_Z) < 1e-5));
    }

    #[test]
    fn sphere_from_center_radius_or_to_world_matches_toml() {
        let want = Sphere {
            center: Vec3::new(1.0, 2.0, 3.0),
            radius: 0.5,
            material: 1,
        };
        for body in [
            r#"<point name="center" x="1" y="2" z="3"/><float name="radius" value="0.5"/>"#,
            r#"<point name="center" value="1, 2, 3"/><float name="radius" value="0.5"/>"#,
            r#"<transform name="to_world"><scale value="0.5"/><translate x="1" y="2" z="3"/></transform>"#,
            // Both: centre and radius first, then to_world.
            r#"<float name="radius" value="0.25"/><transform name="to_world"><scale value="2"/><translate x="1" y="2" z="3"/></transform>"#,
        ] {
            let s = load_body(&format!(r#"<shape type="sphere">{body}<bsdf type="diffuse"/></shape>"#)).unwrap();
            let got = s.spheres[0];
            assert!(
                got.center.distance(want.center) < 1e-6 && (got.radius - want.radius).abs() < 1e-6,
                "{body}: {got:?}"
            );
        }
        let e = error(r#"<shape type="sphere"><transform name="to_world"><scale x="2"/></transform></shape>"#);
        assert!(
            e.contains("<shape type=\"sphere\">") && e.contains("non-uniformly"),
            "{e}"
        );
    }

    /// A unit square at z = 0 as two triangles facing +z, as an OBJ and an ASCII PLY (one quad face).
    fn write_square_meshes(dir: &TempDir) {
        dir.write(
            "sq.obj",
            "mtllib ignored.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nusemtl nothing\nf 1 2 3 4\n",
        );
        dir.write(
            "sq.ply",
            "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
             element face 1\nproperty list uchar int vertex_indices\nend_header\n-1 -1 0\n1 -1 0\n1 1 0\n-1 1 0\n4 0 1 2 3\n",
        );
    }

    /// Most published meshes are binary PLY: both byte orders, double positions, float normals, texture
    /// coordinates (read past, not used yet) and an int index list give the mesh the ASCII file gives.
    #[test]
    fn binary_ply_in_both_byte_orders_reads_as_ascii() {
        let dir = TempDir::new("mitsuba-ply");
        let corners = [
            [-1.0f64, -1.0, 0.0],
            [1.0, -1.0, 0.0],
            [1.0, 1.0, 0.0],
            [-1.0, 1.0, 0.0],
        ];
        let header = |format: &str| {
            format!(
                "ply\nformat {format} 1.0\ncomment written by a test\nelement vertex 4\nproperty double x\n\
                 property double y\nproperty double z\nproperty float nx\nproperty float ny\nproperty float nz\n\
                 property float u\nproperty float v\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
            )
        };
        for (format, big) in [("binary_little_endian", false), ("binary_big_endian", true)] {
            let mut bytes = header(format).into_bytes();
            let mut put = |b: &[u8]| {
                let mut b = b.to_vec();
                if big {
                    b.reverse();
                }
                bytes.extend_from_slice(&b);
            };
            for (i, c) in corners.iter().enumerate() {
                for x in c {
                    put(&x.to_le_bytes());
                }
                for n in [0.0f32, 0.0, 1.0] {
                    put(&n.to_le_bytes());
                }
                for t in [(i % 2) as f32, (i / 2) as f32] {
                    put(&t.to_le_bytes());
                }
            }
            put(&[4u8]); // the list's length (one byte: the same in either order)
            for i in 0..4i32 {
                put(&i.to_le_bytes());
            }
            std::fs::write(dir.0.join(format!("{format}.ply")), &bytes).unwrap();
        }
        write_square_meshes(&dir);
        let mesh = |file: &str| {
            let body = format!(r#"<shape type="ply"><string name="filename" value="{file}"/></shape>"#);
            let s = load_in(&dir, &body, &[]).unwrap_or_else(|e| panic!("{file}: {e:#}"));
            s.meshes[0].clone()
        };
        let ascii = mesh("sq.ply");
        for format in ["binary_little_endian", "binary_big_endian"] {
            let m = mesh(&format!("{format}.ply"));
            assert_eq!(m.positions, ascii.positions, "{format}");
            assert_eq!(m.indices, ascii.indices, "{format}");
            assert_eq!(
                m.normals.as_deref(),
                Some(&[Vec3::Z; 4][..]),
                "{format}: the normals are read"
            );
        }
    }

    /// A mesh without normals gets Mitsuba's own (angle-weighted: its `recompute_vertex_normals`), unless
    /// `face_normals` asks for flat shading. The expected normals are Mitsuba 3.9's for this file
    /// (`mi.load_dict({'type': 'obj', ...}).vertex_normal(i)`, scalar_rgb).
    #[test]
    fn meshes_without_normals_get_mitsubas_vertex_normals() {
        let dir = TempDir::new("mitsuba-normals");
        dir.write("fold.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0.5\nf 1 2 3\nf 2 4 3\n");
        let shape = |face_normals: &str| {
            format!(
                r#"<shape type="obj"><string name="filename" value="fold.obj"/>
                   <boolean name="face_normals" value="{face_normals}"/><bsdf type="diffuse"/></shape>"#
            )
        };
        let s = load_in(&dir, &shape("false"), &[]).unwrap();
        let normals = s.meshes[0].normals.as_ref().expect("computed normals");
        let mitsuba = [
            Vec3::Z,
            Vec3::new(-0.227046, -0.227046, 0.947048),
            Vec3::new(-0.227046, -0.227046, 0.947048),
            Vec3::new(-0.408248, -0.408248, 0.816497),
        ];
        // Our loader keeps the file's vertex order for a mesh of positions only.
        for (i, (n, want)) in normals.iter().zip(mitsuba).enumerate() {
            assert!(n.distance(want) < 1e-5, "vertex {i}: {n} against Mitsuba's {want}");
        }
        assert!(load_in(&dir, &shape("true"), &[]).unwrap().meshes[0].normals.is_none());
    }

    #[test]
    fn obj_and_ply_match_the_rectangle_with_to_world_and_flip() {
        let dir = TempDir::new("mitsuba-mesh");
        write_square_meshes(&dir);
        for kind in ["obj", "ply"] {
            for (flip, normal) in [("false", Vec3::Y), ("true", Vec3::NEG_Y)] {
                let s = load_in(
                    &dir,
                    &format!(
                        r#"<shape type="{kind}"><string name="filename" value="sq.{kind}"/>
                           <boolean name="flip_normals" value="{flip}"/>
                           <transform name="to_world"><rotate x="1" angle="-90"/><translate y="1"/></transform>
                           <bsdf type="twosided"><bsdf type="diffuse"/></bsdf></shape>"#
                    ),
                    &[],
                )
                .unwrap_or_else(|e| panic!("{kind}: {e:#}"));
                let m = &s.meshes[0];
                assert_eq!(m.indices.len(), 2, "{kind}");
                let area: f32 = m.triangles().map(|t| t.area()).sum();
                assert!((area - 4.0).abs() < 1e-5, "{kind}: area {area}");
                for t in m.triangles() {
                    assert!(t.normal().distance(normal) < 1e-5, "{kind} flip {flip}: {}", t.normal());
                    assert!(t.p.iter().all(|p| (p.y - 1.0).abs() < 1e-6));
                }
                // The bsdf is the XML's: the MTL is never read.
                assert_eq!(
                    s.materials[m.materials[0] as usize].surface,
                    Surface::Diffuse {
                        albedo: Vec3::splat(0.5)
                    }
                );
            }
        }
        let e = format!(
            "{:#}",
            load_in(
                &dir,
                r#"<shape type="ply"><string name="filename" value="none.ply"/></shape>"#,
                &[]
            )
            .unwrap_err()
        );
        assert!(
            e.contains("<shape type=\"ply\">") && e.contains("none.ply: cannot read PLY file"),
            "{e}"
        );
    }

    fn camera(sensor_body: &str, film: &str) -> Result<Camera> {
        let dir = TempDir::new("mitsuba-cam");
        let path = dir.write(
            "cam.xml",
            &format!(
                r#"<scene version="3.0.0"><sensor type="perspective">{sensor_body}
                   <film type="hdrfilm">{film}<rfilter type="box"/></film></sensor>
                   <shape type="rectangle"><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape></scene>"#
            ),
        );
        load(&path, &[]).map(|s| s.camera)
    }

    #[test]
    fn camera_lookat_and_fov_axes_match_the_toml_camera() {
        let look =
            r#"<transform name="to_world"><lookat origin="0, 1, 2.9" target="0, 0.8, 0" up="0, 1, 0"/></transform>"#;
        let c = camera(
            &format!(r#"<float name="fov" value="50"/><string name="fov_axis" value="y"/>{look}"#),
            "",
        )
        .unwrap();
        assert_eq!((c.width, c.height), (768, 576));
        assert!((c.vfov_deg - 50.0).abs() < 1e-4, "{c:?}");
        assert!(c.eye.distance(Vec3::new(0.0, 1.0, 2.9)) < 1e-6);
        let dir = (c.look_at - c.eye).normalize();
        assert!(dir.distance(Vec3::new(0.0, -0.2, -2.9).normalize()) < 1e-6);
        // up is orthogonalised by Mitsuba's lookat; it spans the same plane with dir as (0, 1, 0).
        assert!(c.up.cross(dir).normalize().distance(Vec3::Y.cross(dir).normalize()) < 1e-6);

        // Horizontal fov 60 on a 2:1 image: vertical 2 atan(tan 30 / 2).
        let want = 2.0 * ((30f64.to_radians().tan()) / 2.0).atan().to_degrees();
        let film = r#"<integer name="width" value="200"/><integer name="height" value="100"/>"#;
        for (axis, fov) in [
            ("x", 60.0),
            ("larger", 60.0),
            ("y", want),
            ("smaller", want),
            (
                "diagonal",
                2.0 * (30f64.to_radians().tan() * (1.0 + 0.25f64).sqrt()).atan().to_degrees(),
            ),
        ] {
            let c = camera(
                &format!(r#"<float name="fov" value="{fov}"/><string name="fov_axis" value="{axis}"/>{look}"#),
                film,
            )
            .unwrap();
            assert!(
                (f64::from(c.vfov_deg) - want).abs() < 1e-4,
                "{axis}: {} vs {want}",
                c.vfov_deg
            );
        }
        // focal_length: 50mm by default, on the diagonal of a 36 x 24 mm frame.
        let c = camera(look, film).unwrap();
        let diag = 2.0 * (36f64.hypot(24.0) / 100.0).atan();
        let half_w = (0.5 * diag).tan() / (1.0 + 0.25f64).sqrt();
        assert!((f64::from(c.vfov_deg) - (2.0 * (half_w / 2.0).atan()).to_degrees()).abs() < 1e-4);

        // The same camera by rotate + translate: looking down -z from (0, 0, 3) is a 180 degree turn.
        let c = camera(r#"<float name="fov" value="40"/><transform name="to_world"><rotate y="1" angle="180"/><translate z="3"/></transform>"#, "").unwrap();
        assert!(
            c.eye.distance(Vec3::new(0.0, 0.0, 3.0)) < 1e-6
                && (c.look_at - c.eye).normalize().distance(Vec3::NEG_Z) < 1e-6
        );
        assert!(c.up.distance(Vec3::Y) < 1e-6);

        let e = format!(
            "{:#}",
            camera(
                r#"<float name="fov" value="40"/><transform name="to_world"><scale x="-1"/></transform>"#,
                ""
            )
            .unwrap_err()
        );
        assert!(
            e.contains("mirrors the image") && e.contains("<sensor type=\"perspective\">"),
            "{e}"
        );
        let e = format!(
            "{:#}",
            camera(
                r#"<float name="fov" value="40"/><transform name="to_world"><scale value="2"/></transform>"#,
                ""
            )
            .unwrap_err()
        );
        assert!(e.contains("scale"), "{e}");
    }

    fn surface_of(s: &Scene, sphere: usize) -> Surface {
        s.materials[s.spheres[sphere].material as usize].surface
    }

    #[test]
    fn materials_conductor_dielectric_and_emitter() {
        let s = load_body(
            r#"<shape type="sphere"><bsdf type="conductor"><rgb name="specular_reflectance" value="0.9, 0.8, 0.7"/></bsdf></shape>
               <shape type="sphere"><bsdf type="dielectric"><float name="int_ior" value="1.5"/><float name="ext_ior" value="1.25"/></bsdf></shape>
               <shape type="sphere"><bsdf type="dielectric"><string name="int_ior" value="water"/><string name="ext_ior" value="vacuum"/></bsdf></shape>
               <shape type="sphere"><bsdf type="dielectric"/></shape>"#,
        )
        .unwrap();
        let surface = |i: usize| s.materials[s.spheres[i].material as usize].surface;
        assert_eq!(
            surface(0),
            Surface::Mirror {
                reflectance: Vec3::new(0.9, 0.8, 0.7)
            }
        );
        assert_eq!(surface(1), Surface::Glass { ior: 1.2 });
        assert_eq!(surface(2), Surface::Glass { ior: 1.333 });
        // Mitsuba's defaults: bk7 in air.
        assert_eq!(
            surface(3),
            Surface::Glass {
                ior: (1.5046f64 / 1.000277) as f32
            }
        );
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        // The light of HEAD: a black emitter with radiance 1, a quad facing -y.
        let lamp = &s.materials[s.quads[0].material as usize];
        assert_eq!(
            (lamp.surface, lamp.emission),
            (Surface::Diffuse { albedo: Vec3::ZERO }, Vec3::ONE)
        );
        assert!(s.quads[0].normal().distance(Vec3::NEG_Y) < 1e-6);

        // Rough conductors and dielectrics: Mitsuba's defaults (Beckmann, alpha 0.1), GGX, alpha_u and
        // alpha_v when equal, and Mitsuba's floor on alpha.
        let s = load_body(
            r#"<shape type="sphere"><bsdf type="roughconductor"/></shape>
               <shape type="sphere"><bsdf type="roughconductor"><string name="distribution" value="ggx"/>
                 <float name="alpha_u" value="0.3"/><float name="alpha_v" value="0.3"/><string name="material" value="Cu"/>
                 <boolean name="sample_visible" value="false"/></bsdf></shape>
               <shape type="sphere"><bsdf type="roughdielectric"><float name="alpha" value="0"/><float name="int_ior" value="1.5"/></bsdf></shape>"#,
        )
        .unwrap();
        let (none_eta, none_k) = conductors::named("none").unwrap();
        let (cu_eta, cu_k) = conductors::named("Cu").unwrap();
        assert_eq!(
            surface_of(&s, 0),
            Surface::RoughConductor {
                reflectance: Vec3::ONE,
                eta: none_eta,
                k: none_k,
                rough: Microfacet::isotropic(false, 0.1)
            }
        );
        assert_eq!(
            surface_of(&s, 1),
            Surface::RoughConductor {
                reflectance: Vec3::ONE,
                eta: cu_eta,
                k: cu_k,
                rough: Microfacet::isotropic(true, 0.3)
            }
        );
        assert_eq!(
            surface_of(&s, 2),
            Surface::RoughGlass {
                ior: (1.5 / 1.000277f64) as f32,
                rough: Microfacet::isotropic(false, Microfacet::MIN_ALPHA)
            }
        );
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        // Anisotropic: alpha_u along the shape's dp/du, alpha_v across; refused where ppm-vk does not know
        // Mitsuba's dp/du (cube, disk, a rotated sphere) and on roughplastic (Mitsuba's is isotropic).
        let aniso = r#"<bsdf type="roughconductor"><float name="alpha_u" value="0.05"/><float name="alpha_v" value="0.3"/></bsdf>"#;
        let s = load_body(&format!(
            r#"<shape type="sphere">{aniso}</shape><shape type="rectangle">{aniso}</shape>"#
        ))
        .unwrap();
        assert_eq!(
            s.materials[s.spheres[0].material as usize].surface.rough(),
            Some(Microfacet {
                ggx: false,
                alpha: 0.05,
                alpha_v: 0.3
            })
        );
        for (shape, message) in [
            ("<shape type=\"cube\">", "anisotropic roughness on a cube"),
            ("<shape type=\"disk\">", "anisotropic roughness on a disk"),
            (
                "<shape type=\"sphere\"><transform name=\"to_world\"><rotate x=\"1\" angle=\"30\"/></transform>",
                "an anisotropic sphere whose to_world rotates",
            ),
        ] {
            let e = format!("{:#}", load_body(&format!("{shape}{aniso}</shape>")).unwrap_err());
            assert!(e.contains(message), "{shape}: {e}");
        }
        let e = format!(
            "{:#}",
            load_body(r#"<shape type="sphere"><bsdf type="roughplastic"><float name="alpha_u" value="0.05"/><float name="alpha_v" value="0.3"/></bsdf></shape>"#)
                .unwrap_err()
        );
        assert!(e.contains("roughplastic is isotropic"), "{e}");
        for (body, message) in [
            (
                r#"<string name="distribution" value="phong"/>"#,
                "unknown distribution \"phong\"",
            ),
            (
                r#"<float name="alpha" value="0.1"/><float name="alpha_u" value="0.1"/>"#,
                "not both",
            ),
            (
                r#"<float name="alpha_u" value="0.1"/>"#,
                "give both alpha_u and alpha_v",
            ),
            (r#"<float name="alpha" value="-1"/>"#, "must be finite and >= 0"),
        ] {
            for kind in ["roughconductor", "roughdielectric"] {
                let e = load_body(&format!(
                    r#"<shape type="sphere"><bsdf type="{kind}">{body}</bsdf></shape>"#
                ))
                .map(|_| ())
                .unwrap_err();
                let e = format!("{e:#}");
                assert!(e.contains(message) && e.contains("scene.xml:12:"), "{kind} {body}: {e}");
            }
        }
        // A named metal, and eta/k given as rgb or float: the conductor's Fresnel term.
        let s = load_body(
            r#"<shape type="sphere"><bsdf type="conductor"><string name="material" value="Au"/></bsdf></shape>
               <shape type="sphere"><bsdf type="conductor"><rgb name="eta" value="0.2, 0.9, 1.1"/><float name="k" value="3"/>
                 <rgb name="specular_reflectance" value="0.5"/></bsdf></shape>"#,
        )
        .unwrap();
        let (eta, k) = conductors::named("Au").unwrap();
        assert_eq!(
            surface_of(&s, 0),
            Surface::Conductor {
                reflectance: Vec3::ONE,
                eta,
                k
            }
        );
        assert_eq!(
            surface_of(&s, 1),
            Surface::Conductor {
                reflectance: Vec3::splat(0.5),
                eta: Vec3::new(0.2, 0.9, 1.1),
                k: Vec3::splat(3.0)
            }
        );
        for (body, said) in [
            (
                r#"<string name="material" value="Kryptonite"/>"#,
                "unknown conductor material \"Kryptonite\"",
            ),
            (
                r#"<string name="material" value="Au"/><float name="k" value="1"/>"#,
                "not both",
            ),
        ] {
            let e = load_body(&format!(
                r#"<shape type="sphere"><bsdf type="conductor">{body}</bsdf></shape>"#
            ));
            let e = format!("{:#}", e.unwrap_err());
            assert!(e.contains(said) && e.contains(r#"<bsdf type="conductor">"#), "{e}");
        }
        // Plastic and thin dielectric with Mitsuba's defaults (polypropylene and BK7 in air), and given;
        // rough plastic renders smooth with a warning, and a diffuse_reflectance above the photons' bound is
        // lowered with one.
        let s = load_body(
            r#"<shape type="sphere"><bsdf type="plastic"/></shape>
               <shape type="sphere"><bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.1, 0.2, 0.3"/>
                 <float name="specular_reflectance" value="0.5"/><float name="int_ior" value="1.6"/>
                 <float name="ext_ior" value="1.25"/><boolean name="nonlinear" value="true"/></bsdf></shape>
               <shape type="sphere"><bsdf type="thindielectric"/></shape>
               <shape type="sphere"><bsdf type="thindielectric"><string name="int_ior" value="water"/>
                 <rgb name="specular_reflectance" value="0.5"/><rgb name="specular_transmittance" value="0.9, 0.8, 0.7"/></bsdf></shape>"#,
        )
        .unwrap();
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        assert_eq!(
            surface_of(&s, 0),
            Surface::Plastic {
                diffuse: Vec3::splat(0.5),
                specular: Vec3::ONE,
                ior: (1.49f64 / 1.000277) as f32,
                nonlinear: false,
                rough: None
            }
        );
        assert_eq!(
            surface_of(&s, 1),
            Surface::Plastic {
                diffuse: Vec3::new(0.1, 0.2, 0.3),
                specular: Vec3::splat(0.5),
                ior: 1.28,
                nonlinear: true,
                rough: None
            }
        );
        assert_eq!(
            surface_of(&s, 2),
            Surface::ThinDielectric {
                ior: (1.5046f64 / 1.000277) as f32,
                reflectance: Vec3::ONE,
                transmittance: Vec3::ONE
            }
        );
        assert_eq!(
            surface_of(&s, 3),
            Surface::ThinDielectric {
                ior: (1.333f64 / 1.000277) as f32,
                reflectance: Vec3::splat(0.5),
                transmittance: Vec3::new(0.9, 0.8, 0.7)
            }
        );
        let s = load_body(
            r#"<shape type="sphere"><bsdf type="roughplastic"><float name="alpha" value="0.2"/>
                 <rgb name="diffuse_reflectance" value="0.99, 0.5, 0.2"/></bsdf></shape>"#,
        )
        .unwrap();
        // roughplastic: Mitsuba's default Beckmann, the bound of its rough coat (which transmits less than
        // a smooth one at normal incidence, so it may allow 0.99).
        let ior = (1.49f64 / 1.000277) as f32;
        let rough = Some(Microfacet::isotropic(false, 0.2));
        let most = crate::scene::plastic::max_diffuse_reflectance(ior, false, &crate::scene::plastic::coat(ior, rough));
        let lowered = most < 0.99;
        assert!(
            s.warnings.len() == lowered as usize
                && s.warnings
                    .iter()
                    .all(|w| w.contains("diffuse_reflectance [0.99, 0.5, 0.2] lowered")),
            "{most}: {:?}",
            s.warnings
        );
        assert!(matches!(surface_of(&s, 0),
            Surface::Plastic { diffuse, rough: r, .. } if diffuse == Vec3::new(most.min(0.99), 0.5, 0.2) && r == rough));
        // One-sided diffuse on an open shape: warned; on a closed one or twosided: not.
        let s = load_body(r#"<shape type="rectangle"><bsdf type="diffuse"/></shape><shape type="cube"><bsdf type="diffuse"/></shape>"#).unwrap();
        assert!(
            s.warnings.len() == 1 && s.warnings[0].contains("one-sided in Mitsuba"),
            "{:?}",
            s.warnings
        );
        // A shape without a bsdf is diffuse 0.5, as in Mitsuba.
        let s = load_body(r#"<shape type="cube"/>"#).unwrap();
        assert_eq!(
            s.materials[s.quads[1].material as usize].surface,
            Surface::Diffuse {
                albedo: Vec3::splat(0.5)
            }
        );
    }

    #[test]
    fn refused_and_malformed_input_is_located() {
        // (body, the element named, the line in the file (HEAD has 11 lines), what is said)
        let cases: &[(&str, &str, usize, &str)] = &[
            (
                r#"<bsdf type="diffuse" id="a"/><bsdf type="conductor" id="a"/>"#,
                r#"<bsdf type="conductor" id="a">"#,
                12,
                "the id \"a\" is already taken",
            ),
            (
                r#"<shape type="cylinder"/>"#,
                r#"<shape type="cylinder">"#,
                12,
                "unsupported shape",
            ),
            (
                r#"<shape type="cube"><ref id="nowhere"/></shape>"#,
                r#"<ref id="nowhere">"#,
                12,
                "no bsdf with id \"nowhere\"",
            ),
            (
                r#"<shape type="cube"><float name="radius" value="$r"/></shape>"#,
                r#"<float name="radius">"#,
                12,
                "undefined parameter $r",
            ),
            (
                "\n<shape type=\"cube\"><bsdf type=\"principled\"/></shape>",
                r#"<bsdf type="principled">"#,
                13,
                "unsupported bsdf",
            ),
            (
                r#"<shape type="cube"><bsdf type="plastic"/><emitter type="area"/></shape>"#,
                r#"<emitter type="area">"#,
                12,
                "an area emitter on a plastic surface",
            ),
            (
                r#"<shape type="cube"><bsdf type="plastic"><string name="int_ior" value="unobtainium"/></bsdf></shape>"#,
                r#"<string name="int_ior">"#,
                12,
                "unknown index of refraction \"unobtainium\"",
            ),
            (
                r#"<shape type="cube"><bsdf type="thindielectric"><boolean name="nonlinear" value="true"/></bsdf></shape>"#,
                r#"<boolean name="nonlinear">"#,
                12,
                "parameter not read by ppm-vk",
            ),
            (
                r#"<shape type="cube"><bsdf type="conductor"><texture name="specular_reflectance" type="checkerboard"/></bsdf></shape>"#,
                r#"<texture type="checkerboard" name="specular_reflectance">"#,
                12,
                "a texture on specular_reflectance is not supported: only diffuse reflectance",
            ),
            (
                r#"<emitter type="envmap"/>"#,
                r#"<emitter type="envmap">"#,
                12,
                "only area emitters",
            ),
            (
                r#"<shape type="sphere"><emitter type="area"/></shape>"#,
                r#"<emitter type="area">"#,
                12,
                "emitting sphere",
            ),
            (
                r#"<shape type="cube"><float name="radiuss" value="1"/></shape>"#,
                r#"<float name="radiuss">"#,
                12,
                "parameter not read",
            ),
            (
                r#"<shape type="rectangle"><bsdf type="diffuse"><rgb name="reflectance" value="2, 0, 0"/></bsdf></shape>"#,
                r#"<bsdf type="diffuse">"#,
                12,
                "must be in [0, 1]",
            ),
            (
                r#"<shape type="cube"><bsdf type="dielectric"><float name="int_ior" value="1"/><float name="ext_ior" value="1.5"/></bsdf></shape>"#,
                r#"<bsdf type="dielectric">"#,
                12,
                "int_ior 1 < ext_ior 1.5",
            ),
        ];
        for (body, element, line, says) in cases {
            let e = error(body);
            assert!(
                e.contains(&format!("scene.xml:{line}:")),
                "{e} should be at line {line}"
            );
            assert!(e.contains(element), "{e} should name {element}");
            assert!(e.contains(says), "{e} should say {says}");
        }
        // Malformed XML: roxmltree's position.
        let e = error("<shape type=\"cube\">\n  <bsdf type=\"diffuse\">\n</shape>");
        assert!(e.contains("scene.xml:14:1: malformed XML: expected 'bsdf' tag"), "{e}");
        // Nesting past the bound is refused, not a stack overflow (found by tests/hostile_input.rs).
        let deep = format!("{}{}", "<bsdf type=\"twosided\">".repeat(1000), "</bsdf>".repeat(1000));
        let e = error(&deep);
        assert!(e.contains(&format!("nested deeper than {MAX_NESTING} levels")), "{e}");
        // Attribute values may hold "/>": they hide no level from the scan (roxmltree would overflow).
        let hidden = format!(
            "{}{}",
            "<bsdf type=\"twosided\" id=\"a/>\">".repeat(20000),
            "</bsdf>".repeat(20000)
        );
        let e = error(&hidden);
        assert!(e.contains(&format!("nested deeper than {MAX_NESTING} levels")), "{e}");
    }

    #[test]
    fn defaults_overrides_refs_and_includes() {
        let dir = TempDir::new("mitsuba-inc");
        std::fs::create_dir_all(dir.0.join("sub")).unwrap();
        // Included from sub/, it includes its sibling relative to itself.
        dir.write(
            "sub/materials.xml",
            r#"<scene version="3.0.0"><include filename="more.xml"/></scene>"#,
        );
        dir.write("sub/more.xml", r#"<scene version="3.0.0"><bsdf type="diffuse" id="grey"><rgb name="reflectance" value="$albedo"/></bsdf></scene>"#);
        let body = r#"<default name="albedo" value="0.25"/><default name="albedo_" value="0.75"/>
            <include filename="sub/materials.xml"/>
            <shape type="cube"><ref id="grey"/></shape>
            <shape type="cube"><bsdf type="diffuse"><float name="reflectance" value="$albedo_"/></bsdf></shape>"#;
        let albedo = |s: &Scene, i: usize| match s.materials[s.quads[i].material as usize].surface {
            Surface::Diffuse { albedo } => albedo.x,
            _ => panic!(),
        };
        let s = load_in(&dir, body, &[]).unwrap_or_else(|e| panic!("{e:#}"));
        // $albedo_ is not $albedo followed by "_": the longer name is substituted first.
        assert_eq!((albedo(&s, 1), albedo(&s, 7)), (0.25, 0.75));
        assert_eq!(s.materials[s.quads[1].material as usize].name, "grey");
        let s = load_in(&dir, body, &[("albedo", "0.5")]).unwrap();
        assert_eq!((albedo(&s, 1), albedo(&s, 7)), (0.5, 0.75));
        let e = format!("{:#}", load_in(&dir, body, &[("albdo", "0.5")]).unwrap_err());
        assert!(e.contains("-D albdo=0.5: the scene never uses $albdo"), "{e}");

        // A cycle: a includes b includes a.
        dir.write("a.xml", r#"<scene version="3.0.0"><include filename="b.xml"/></scene>"#);
        dir.write(
            "b.xml",
            "<scene version=\"3.0.0\">\n<include filename=\"a.xml\"/></scene>",
        );
        let e = format!(
            "{:#}",
            load_in(&dir, r#"<include filename="a.xml"/>"#, &[]).unwrap_err()
        );
        assert!(
            e.contains("b.xml:2:1: <include>: include cycle: ") && e.contains("a.xml -> ") && e.ends_with("a.xml"),
            "{e}"
        );
        let e = format!(
            "{:#}",
            load_in(&dir, r#"<include filename="missing.xml"/>"#, &[]).unwrap_err()
        );
        assert!(
            e.contains("scene.xml:12:1: <include>: ") && e.contains("missing.xml: cannot read scene file"),
            "{e}"
        );
    }

    #[test]
    fn parse_define_takes_name_and_value() {
        assert_eq!(parse_define("spp=16"), Ok(("spp".into(), "16".into())));
        assert_eq!(parse_define("v=a=b"), Ok(("v".into(), "a=b".into())));
        assert!(parse_define("spp").is_err());
        assert!(parse_define("$spp=1").is_err());
    }

    /// Writes `name` (a 2 x 2 PNG: red, green over blue, white) into `dir`.
    fn write_texture(dir: &TempDir, name: &str) {
        let rgb = [255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255];
        texture::write_png(&dir.0.join(name), 2, 2, &rgb);
    }

    fn material_of_quad(s: &Scene, quad: usize) -> &Material {
        &s.materials[s.quads[quad].material as usize]
    }

    /// The texture coordinates a quad gives world point `p`: its coordinates along edge_u and edge_v,
    /// through its material's texture's to_uv.
    fn quad_uv(s: &Scene, q: &Quad, p: Vec3) -> Vec2 {
        let (u, v, d) = (q.edge_u, q.edge_v, p - q.origin);
        // The dual basis of (u, v) in their plane.
        let n = u.cross(v);
        let (a, b) = (
            d.dot(v.cross(n)) / u.dot(v.cross(n)),
            d.dot(u.cross(n)) / v.dot(u.cross(n)),
        );
        let m = s.textures[s.materials[q.material as usize].texture.unwrap() as usize].to_uv;
        Vec2::new(m[0] * a + m[1] * b + m[2], m[3] * a + m[4] * b + m[5])
    }

    #[test]
    fn bitmap_and_checkerboard_textures_on_diffuse_and_plastic() {
        let dir = TempDir::new("mitsuba-tex");
        std::fs::create_dir_all(dir.0.join("tex")).unwrap();
        write_texture(&dir, "tex/rgbw.png");
        let s = load_in(
            &dir,
            r#"<shape type="rectangle"><bsdf type="diffuse"><texture type="bitmap" name="reflectance">
                 <string name="filename" value="tex/rgbw.png"/></texture></bsdf></shape>
               <shape type="rectangle"><bsdf type="twosided"><bsdf type="diffuse"><texture type="bitmap" name="reflectance">
                 <string name="filename" value="tex/rgbw.png"/><string name="filter_type" value="nearest"/>
                 <string name="wrap_mode" value="clamp"/><boolean name="raw" value="true"/>
                 <string name="format" value="fp16"/><boolean name="accel" value="false"/>
                 <transform name="to_uv"><scale x="2" y="3"/><translate x="0.5"/></transform></texture></bsdf></bsdf></shape>
               <shape type="sphere"><bsdf type="plastic"><texture type="checkerboard" name="diffuse_reflectance">
                 <rgb name="color0" value="0.1, 0.2, 0.3"/></texture></bsdf></shape>
               <shape type="sphere"><transform name="to_world"><scale value="2"/><translate x="3"/></transform>
                 <bsdf type="diffuse"><texture type="checkerboard" name="reflectance"/></bsdf></shape>"#,
            &[],
        )
        .unwrap_or_else(|e| panic!("{e:#}"));
        // One texture for each distinct (image, parameters): three, the checkerboards differing in colour.
        assert_eq!(
            s.textures.len(),
            4,
            "{:?}",
            s.textures.iter().map(|t| &t.name).collect::<Vec<_>>()
        );
        let m = material_of_quad(&s, 1);
        let t = &s.textures[m.texture.unwrap() as usize];
        assert!(t.name.ends_with("tex/rgbw.png"), "{}", t.name);
        assert_eq!(
            (t.filter, t.wrap, t.to_uv),
            (Filter::Bilinear, Wrap::Repeat, texture::IDENTITY_UV)
        );
        assert_eq!(
            t.pattern,
            Pattern::Bitmap {
                width: 2,
                height: 2,
                pixels: vec![Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE]
            },
            "top row first"
        );
        // The constant is the texture's largest value in each channel.
        assert_eq!(m.surface, Surface::Diffuse { albedo: Vec3::ONE });
        let t2 = &s.textures[material_of_quad(&s, 2).texture.unwrap() as usize];
        assert_eq!((t2.filter, t2.wrap), (Filter::Nearest, Wrap::Clamp));
        assert_eq!(t2.to_uv, [2.0, 0.0, 0.5, 0.0, 3.0, 0.0]);
        assert_ne!(
            material_of_quad(&s, 1),
            material_of_quad(&s, 2),
            "different textures, different materials"
        );
        let plastic = &s.materials[s.spheres[0].material as usize];
        let board = &s.textures[plastic.texture.unwrap() as usize];
        assert_eq!(
            board.pattern,
            Pattern::Checkerboard {
                color0: Vec3::new(0.1, 0.2, 0.3),
                color1: Vec3::splat(0.2)
            }
        );
        assert!(matches!(plastic.surface, Surface::Plastic { diffuse, .. } if diffuse == Vec3::new(0.2, 0.2, 0.3)));
        // Mitsuba's defaults, on a sphere scaled and moved (not rotated).
        let grey = &s.materials[s.spheres[1].material as usize];
        assert_eq!(
            s.textures[grey.texture.unwrap() as usize].pattern,
            Pattern::Checkerboard {
                color0: Vec3::splat(0.4),
                color1: Vec3::splat(0.2)
            }
        );
        assert_eq!(
            grey.surface,
            Surface::Diffuse {
                albedo: Vec3::splat(0.4)
            }
        );
        s.validate().unwrap();

        // A top-level texture, referenced twice: one texture, one material; a plastic above the photons'
        // bound is lowered per pixel, with a warning, in a copy of its own.
        let s = load_in(
            &dir,
            r#"<texture type="bitmap" id="wood"><string name="filename" value="tex/rgbw.png"/></texture>
               <bsdf type="diffuse" id="a"><ref name="reflectance" id="wood"/></bsdf>
               <shape type="rectangle"><ref id="a"/></shape>
               <shape type="rectangle"><bsdf type="diffuse" id="a2"><ref id="wood" name="reflectance"/></bsdf></shape>
               <shape type="rectangle"><bsdf type="twosided"><bsdf type="roughplastic"><ref name="diffuse_reflectance" id="wood"/></bsdf></bsdf></shape>"#,
            &[],
        )
        .unwrap_or_else(|e| panic!("{e:#}"));
        let (a, a2, p) = (
            material_of_quad(&s, 1),
            material_of_quad(&s, 2),
            material_of_quad(&s, 3),
        );
        assert_eq!(a.texture, a2.texture);
        assert_ne!(p.texture, a.texture);
        assert_eq!(s.textures.len(), 2);
        let ior = (1.49f64 / 1.000277) as f32;
        let coat = crate::scene::plastic::coat(ior, Some(Microfacet::isotropic(false, 0.1)));
        let most = crate::scene::plastic::max_diffuse_reflectance(ior, false, &coat);
        assert_eq!(s.textures[p.texture.unwrap() as usize].max(), Vec3::splat(most));
        assert!(matches!(p.surface, Surface::Plastic { diffuse, .. } if diffuse == Vec3::splat(most)));
        assert!(
            s.warnings
                .iter()
                .any(|w| w.contains("rgbw.png\": 4 pixels lowered to at most 0.9")),
            "{:?}",
            s.warnings
        );
        s.validate().unwrap();
    }

    #[test]
    fn a_textured_rectangle_has_mitsubas_uv_turned_or_not() {
        let dir = TempDir::new("mitsuba-tex-rect");
        write_texture(&dir, "t.png");
        // Mitsuba 3.9.1: the local point (0.3, -0.6, 0) of a rectangle has uv (0.65, 0.2) whatever to_world
        // and flip_normals do; its world position, and the side its area emitter lights, for each.
        let cases: &[(&str, &str, Vec3, Vec3)] = &[
            ("", "false", Vec3::new(0.3, -0.6, 0.0), Vec3::Z),
            ("", "true", Vec3::new(0.3, -0.6, 0.0), Vec3::NEG_Z),
            (r#"<scale x="-1"/>"#, "false", Vec3::new(-0.3, -0.6, 0.0), Vec3::Z),
            (r#"<scale x="-1"/>"#, "true", Vec3::new(-0.3, -0.6, 0.0), Vec3::NEG_Z),
            (
                r#"<scale x="2" y="-3"/><rotate x="1" angle="-90"/><translate y="1"/>"#,
                "false",
                Vec3::new(0.6, 1.0, -1.8),
                Vec3::Y,
            ),
        ];
        for (transform, flip, p, normal) in cases {
            let s = load_in(
                &dir,
                &format!(
                    r#"<shape type="rectangle"><transform name="to_world">{transform}</transform>
                       <boolean name="flip_normals" value="{flip}"/>
                       <bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="t.png"/>
                         <transform name="to_uv"><scale x="2"/><translate y="0.25"/></transform></texture></bsdf></shape>"#
                ),
                &[],
            )
            .unwrap_or_else(|e| panic!("{e:#}"));
            let q = s.quads[1];
            let uv = quad_uv(&s, &q, *p);
            // Mitsuba's uv through the texture's own to_uv: (2 u, v + 0.25).
            let want = Vec2::new(2.0 * 0.65, 0.2 + 0.25);
            assert!(
                uv.distance(want) < 1e-5,
                "{transform} flip {flip}: uv {uv}, want {want}"
            );
            assert!(
                q.normal().distance(*normal) < 1e-5,
                "{transform} flip {flip}: normal {}",
                q.normal()
            );
            s.validate().unwrap();
        }
    }

    #[test]
    fn textured_meshes_need_texture_coordinates() {
        let dir = TempDir::new("mitsuba-tex-mesh");
        write_texture(&dir, "t.png");
        let tex = r#"<bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="t.png"/></texture></bsdf>"#;
        dir.write(
            "uv.obj",
            "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nvt 0.1 0.2\nvt 0.9 0.2\nvt 0.9 0.8\nf 1/1 2/2 3/3\n",
        );
        // Mitsuba flips an OBJ's v unless flip_tex_coords is false.
        for (flag, want) in [
            ("", [Vec2::new(0.1, 0.8), Vec2::new(0.9, 0.8), Vec2::new(0.9, 0.2)]),
            (
                r#"<boolean name="flip_tex_coords" value="true"/>"#,
                [Vec2::new(0.1, 0.8), Vec2::new(0.9, 0.8), Vec2::new(0.9, 0.2)],
            ),
            (
                r#"<boolean name="flip_tex_coords" value="false"/>"#,
                [Vec2::new(0.1, 0.2), Vec2::new(0.9, 0.2), Vec2::new(0.9, 0.8)],
            ),
        ] {
            let s = load_in(
                &dir,
                &format!(r#"<shape type="obj"><string name="filename" value="uv.obj"/>{flag}{tex}</shape>"#),
                &[],
            )
            .unwrap_or_else(|e| panic!("{e:#}"));
            let m = &s.meshes[0];
            let got: Vec<Vec2> = m.indices[0]
                .iter()
                .map(|&i| m.uvs.as_ref().unwrap()[i as usize])
                .collect();
            assert!(
                got.iter().zip(want).all(|(g, w)| g.distance(w) < 1e-6),
                "{flag}: {got:?}"
            );
            assert!(s.materials[m.materials[0] as usize].texture.is_some());
        }
        // PLY: s and t, not flipped (Mitsuba's ply reader does not).
        dir.write(
            "st.ply",
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
             property float s\nproperty float t\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
             -1 -1 0 0.1 0.2\n1 -1 0 0.9 0.2\n1 1 0 0.9 0.8\n3 0 1 2\n",
        );
        let s = load_in(
            &dir,
            &format!(r#"<shape type="ply"><string name="filename" value="st.ply"/>{tex}</shape>"#),
            &[],
        )
        .unwrap_or_else(|e| panic!("{e:#}"));
        assert_eq!(
            s.meshes[0].uvs.as_deref(),
            Some(&[Vec2::new(0.1, 0.2), Vec2::new(0.9, 0.2), Vec2::new(0.9, 0.8)][..])
        );
        // Without texture coordinates: refused, the file named.
        write_square_meshes(&dir);
        for kind in ["obj", "ply"] {
            let e = format!(
                "{:#}",
                load_in(
                    &dir,
                    &format!(r#"<shape type="{kind}"><string name="filename" value="sq.{kind}"/>{tex}</shape>"#),
                    &[]
                )
                .unwrap_err()
            );
            assert!(
                e.contains(&format!("scene.xml:12:1: <shape type=\"{kind}\">: "))
                    && e.contains(&format!("sq.{kind}: no texture coordinates")),
                "{e}"
            );
        }
    }

    #[test]
    fn texture_errors_name_the_file_and_line() {
        let dir = TempDir::new("mitsuba-tex-err");
        write_texture(&dir, "t.png");
        dir.write("corrupt.png", "\u{89}PNG\r\n\u{1a}\nthis is not a PNG");
        // A valid PNG header (signature, IHDR) claiming 100000 x 1 pixels, then an empty IDAT and IEND.
        let chunk = |kind: &[u8], data: &[u8]| -> Vec<u8> {
            let mut c = (data.len() as u32).to_be_bytes().to_vec();
            c.extend_from_slice(kind);
            c.extend_from_slice(data);
            // CRC-32 of the chunk's type and data.
            let mut crc = !0u32;
            for &b in &c[4..] {
                crc ^= u32::from(b);
                for _ in 0..8 {
                    crc = if crc & 1 != 0 {
                        0xEDB8_8320 ^ (crc >> 1)
                    } else {
                        crc >> 1
                    };
                }
            }
            c.extend_from_slice(&(!crc).to_be_bytes());
            c
        };
        let claiming = |w: u32, h: u32| {
            let mut ihdr = w.to_be_bytes().to_vec();
            ihdr.extend_from_slice(&h.to_be_bytes());
            ihdr.extend_from_slice(&[8, 2, 0, 0, 0]);
            let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
            png.extend(chunk(b"IHDR", &ihdr));
            png.extend(chunk(b"IDAT", &[]));
            png.extend(chunk(b"IEND", &[]));
            png
        };
        std::fs::write(dir.0.join("huge.png"), claiming(100_000, 1)).unwrap();
        // Sides within bounds, but 2^28 pixels: refused before anything is decoded.
        std::fs::write(dir.0.join("vast.png"), claiming(16384, 16384)).unwrap();
        // An EXR with a value above 1.
        image::Rgb32FImage::from_raw(1, 1, vec![1.5, 0.5, 0.5])
            .unwrap()
            .save(dir.0.join("bright.exr"))
            .unwrap();
        let bitmap = |file: &str| {
            format!(
                r#"<shape type="rectangle"><bsdf type="diffuse">
<texture type="bitmap" name="reflectance"><string name="filename" value="{file}"/></texture></bsdf></shape>"#
            )
        };
        let diffuse =
            |texture: &str| format!(r#"<shape type="rectangle"><bsdf type="diffuse">{texture}</bsdf></shape>"#);
        let tex = r#"<texture type="bitmap" name="reflectance"><string name="filename" value="t.png"/></texture>"#;
        // (body, the element named, its line, what is said)
        let cases: Vec<(String, &str, usize, &str)> = vec![
            (bitmap("missing.png"), r#"<texture type="bitmap" name="reflectance">"#, 13, "missing.png: cannot open the image"),
            (bitmap("corrupt.png"), r#"<texture type="bitmap" name="reflectance">"#, 13, "corrupt.png: not a readable PNG"),
            (bitmap("huge.png"), r#"<texture type="bitmap" name="reflectance">"#, 13, "huge.png: image of 100000 x 1 pixels"),
            (bitmap("vast.png"), r#"<texture type="bitmap" name="reflectance">"#, 13, "vast.png: image of 16384 x 16384 pixels: at most"),
            (
                bitmap("bright.exr"),
                r#"<texture type="bitmap" name="reflectance">"#,
                13,
                "bright.exr: pixel (0, 0) (column, row from the top) is [1.5, 0.5, 0.5]: a reflectance texture's values must be in [0, 1]",
            ),
            (
                diffuse(r#"<texture type="mesh_attribute" name="reflectance"/>"#),
                r#"<texture type="mesh_attribute" name="reflectance">"#,
                12,
                "unsupported texture (read: bitmap, checkerboard)",
            ),
            (
                diffuse(r#"<texture type="bitmap" name="reflectance"><string name="filename" value="t.png"/><string name="filter_type" value="cubic"/></texture>"#),
                r#"<string name="filter_type">"#,
                12,
                "\"cubic\": expected bilinear, nearest",
            ),
            (
                diffuse(r#"<texture type="bitmap" name="reflectance"><string name="filename" value="t.png"/><float name="gamma" value="2.2"/></texture>"#),
                r#"<float name="gamma">"#,
                12,
                "parameter not read by ppm-vk for <texture type=\"bitmap\" name=\"reflectance\">",
            ),
            (
                diffuse(r#"<texture type="checkerboard" name="reflectance"><texture type="checkerboard" name="color0"/></texture>"#),
                r#"<texture type="checkerboard" name="color0">"#,
                12,
                "a texture on color0 is not supported",
            ),
            (diffuse(r#"<ref name="reflectance" id="nothing"/>"#), r#"<ref id="nothing" name="reflectance">"#, 12, "no texture with id \"nothing\""),
            (
                format!(r#"<shape type="rectangle"><bsdf type="conductor">{}</bsdf></shape>"#, tex.replace("reflectance", "eta")),
                r#"<texture type="bitmap" name="eta">"#,
                12,
                "a texture on eta is not supported: only diffuse reflectance",
            ),
            (
                format!(r#"<shape type="rectangle"><bsdf type="plastic">{}</bsdf></shape>"#, tex.replace("reflectance", "specular_reflectance")),
                r#"<texture type="bitmap" name="specular_reflectance">"#,
                12,
                "a texture on specular_reflectance is not supported",
            ),
            (
                format!(r#"<shape type="rectangle"><emitter type="area">{}</emitter></shape>"#, tex.replace("reflectance", "radiance")),
                r#"<texture type="bitmap" name="radiance">"#,
                12,
                "a texture on radiance is not supported",
            ),
            (
                format!(r#"<shape type="cube"><bsdf type="diffuse">{tex}</bsdf></shape>"#),
                r#"<bsdf type="diffuse">"#,
                12,
                "texture coordinates of a cube are not supported yet",
            ),
            (
                format!(r#"<shape type="disk"><bsdf type="diffuse">{tex}</bsdf></shape>"#),
                r#"<bsdf type="diffuse">"#,
                12,
                "texture coordinates of a disk are not supported yet",
            ),
            (
                format!(r#"<shape type="sphere"><transform name="to_world"><rotate x="1" angle="30"/></transform><bsdf type="diffuse">{tex}</bsdf></shape>"#),
                r#"<shape type="sphere">"#,
                12,
                "a textured sphere whose to_world rotates or mirrors it",
            ),
            (
                format!(r#"<shape type="sphere"><transform name="to_world"><scale value="-1"/></transform><bsdf type="diffuse">{tex}</bsdf></shape>"#),
                r#"<shape type="sphere">"#,
                12,
                "rotates or mirrors",
            ),
            (
                r#"<texture type="bitmap" id="a"><string name="filename" value="t.png"/></texture><bsdf type="diffuse" id="a"/>"#.to_string(),
                r#"<bsdf type="diffuse" id="a">"#,
                12,
                "the id \"a\" is already taken",
            ),
        ];
        for (body, element, line, says) in &cases {
            let e = match load_in(&dir, body, &[]) {
                Ok(_) => panic!("expected an error for {body}"),
                Err(e) => format!("{e:#}"),
            };
            assert!(
                e.contains(&format!("scene.xml:{line}:")),
                "{e} should be at line {line}"
            );
            assert!(e.contains(element), "{e} should name {element}");
            assert!(e.contains(says), "{e} should say {says}");
        }
    }

    #[test]
    fn ply_texture_coordinates_under_each_name_and_type() {
        let dir = TempDir::new("mitsuba-ply-uv");
        let uv = [[0.1f64, 0.2], [0.9, 0.2], [0.9, 0.8]];
        let want: Vec<Vec2> = uv.iter().map(|t| Vec2::new(t[0] as f32, t[1] as f32)).collect();
        let body = |file: &str| format!(r#"<shape type="ply"><string name="filename" value="{file}"/></shape>"#);
        // ASCII, each name Mitsuba reads; texture_s/texture_t Mitsuba 3.9 ignores ("can't start with postfix").
        for (a, b, read) in [
            ("u", "v", true),
            ("texture_u", "texture_v", true),
            ("s", "t", true),
            ("texture_s", "texture_t", false),
        ] {
            let mut text = format!(
                "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                 property float {a}\nproperty float {b}\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
            );
            for (p, t) in [[-1, -1], [1, -1], [1, 1]].iter().zip(uv) {
                text += &format!("{} {} 0 {} {}\n", p[0], p[1], t[0], t[1]);
            }
            text += "3 0 1 2\n";
            dir.write("a.ply", &text);
            let s = load_in(&dir, &body("a.ply"), &[]).unwrap_or_else(|e| panic!("{a}: {e:#}"));
            assert_eq!(s.meshes[0].uvs.as_deref(), read.then_some(&want[..]), "{a} {b}");
        }
        // Binary, both byte orders, float and double; integer ones are not read (Mitsuba rescales them).
        for (format, big) in [("binary_little_endian", false), ("binary_big_endian", true)] {
            for kind in ["float", "double", "uchar"] {
                let mut bytes = format!(
                    "ply\nformat {format} 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                     property {kind} u\nproperty {kind} v\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                )
                .into_bytes();
                let mut put = |b: &[u8]| {
                    let mut b = b.to_vec();
                    if big {
                        b.reverse();
                    }
                    bytes.extend_from_slice(&b);
                };
                for (p, t) in [[-1.0f32, -1.0], [1.0, -1.0], [1.0, 1.0]].iter().zip(uv) {
                    for x in [p[0], p[1], 0.0] {
                        put(&x.to_le_bytes());
                    }
                    for x in t {
                        match kind {
                            "float" => put(&(x as f32).to_le_bytes()),
                            "double" => put(&x.to_le_bytes()),
                            _ => put(&[(x * 255.0) as u8]),
                        }
                    }
                }
                put(&[3u8]);
                for i in 0..3i32 {
                    put(&i.to_le_bytes());
                }
                std::fs::write(dir.0.join("b.ply"), &bytes).unwrap();
                let s = load_in(&dir, &body("b.ply"), &[]).unwrap_or_else(|e| panic!("{format} {kind}: {e:#}"));
                let expected = (kind != "uchar").then_some(&want[..]);
                assert_eq!(s.meshes[0].uvs.as_deref(), expected, "{format} {kind}");
            }
        }
    }
}
