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
//!
//! One file per thing read, so that a new plugin is a new function (or file), not a longer one:
//! - this file: the entry points ([`load`], [`parse_define`]) and the walk over the top-level elements
//!   ([`Builder`]), which also keeps bsdfs and textures by id and the first sensor;
//! - `xml.rs`: stage 1, files to [`Elem`]s (parameters, `<default>`, `<include>`, nesting bounds);
//! - `properties.rs`: a plugin's typed properties (numbers, points, colours, transforms), unread ones
//!   refused;
//! - `integrator.rs`: `<integrator>`; `sensor.rs`: `<sensor>` with its `<film>` and `<sampler>`;
//! - `bsdf.rs`: `<bsdf>`, one function per plugin; `texture.rs`: `<texture>` (bitmap, checkerboard);
//! - `shape.rs`: `<shape>`, one function per shape type; `instance.rs`: `shapegroup` and `instance`
//!   (flattened at load); `emitter.rs`: `<emitter>`.
//!
//! Uses run one way: the children use this file's [`Builder`], `xml.rs`'s [`Elem`] and `properties.rs`;
//! `shape.rs` uses `bsdf.rs`, `emitter.rs` and `texture.rs`, and `bsdf.rs` uses `texture.rs`; this file
//! calls into them. Mesh files are read by `obj.rs` (OBJ) and `ply.rs` (PLY).

mod blend;
mod bsdf;
mod cie;
mod elem;
mod emitter;
mod instance;
mod integrator;
mod mask;
mod modifiers;
mod properties;
mod sensor;
mod shape;
mod spectrum;
mod texture;
mod upgrade;
mod xml;

use std::collections::HashMap;
use std::fmt;
use std::path::{Path, PathBuf};
use std::rc::Rc;

use anyhow::Result;
use glam::Vec3;

use self::bsdf::Bsdf;
use self::elem::{Elem, Resolver};
use self::properties::Props;
use self::texture::Tex;
use super::plastic::Coats;
use super::{Camera, Scene};

pub use self::shape::{CYLINDER_SEGMENTS, DISK_SEGMENTS};
pub use self::spectrum::MAX_SPECTRUM_BYTES;
pub use self::xml::{MAX_INCLUDED_BYTES, MAX_INCLUDED_FILES, MAX_INCLUDE_DEPTH, MAX_NESTING, MAX_SUBSTITUTED_BYTES};

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
    let shown = path.display().to_string();
    let xml::Read {
        root,
        children,
        resolver,
        warnings,
    } = xml::read(path, &shown, defines)?;
    let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or(&shown).to_string();
    let mut b = Builder::new(name, root, resolver);
    b.scene.warnings = warnings;
    b.ids(&children)?;
    for e in &children {
        b.top_level(e)?;
    }
    b.finish()
}

/// A shapegroup's shapes, placed in its own space (their `to_world` applied), not in the scene (instances
/// copy them: instance.rs).
struct Group {
    quads: Vec<crate::Quad>,
    spheres: Vec<crate::Sphere>,
    meshes: Vec<crate::Mesh>,
}

/// What the scene's objects became, and where each came from (to locate a failed check).
struct Builder {
    scene: Scene,
    root: Elem,
    bsdfs: HashMap<String, Bsdf>,
    /// Top-level textures by id (`<ref id=".." name="reflectance"/>` in a bsdf reads them).
    textures: HashMap<String, Rc<Tex>>,
    /// Top-level area emitters by id, with whether a shape has referenced them: a `<ref>` in a shape
    /// naming one is that shape's emitter (mitsuba-data's cbox-rgb.xml).
    emitters: HashMap<String, (Elem, bool)>,
    /// Ids of top-level samplers: a sensor may refer to one (it only decides Mitsuba's noise).
    samplers: Vec<String>,
    /// Top-level shapegroups by id (instances copy them).
    groups: HashMap<String, Group>,
    /// Top-level bsdfs by id, for a shape that refers to one defined after it (Mitsuba resolves references
    /// after reading the file): such a bsdf is read when the shape needs it, and skipped where it stands
    /// (`early` holds where it stands).
    later_bsdfs: HashMap<String, Elem>,
    early: Vec<String>,
    /// Field path prefix (`quad[3]`, `materials.white`, `camera`) -> the element it came from.
    origins: HashMap<String, Elem>,
    sensor: Option<Elem>,
    shapes: usize,
    /// The search path at the end of the scene file: the files plugins name are found by it.
    resolver: Resolver,
    /// The plastics' coats, each made once for the whole file: the bsdfs' bounds and the final check
    /// read them.
    coats: Coats,
}

impl Builder {
    fn new(name: String, root: Elem, resolver: Resolver) -> Builder {
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
                emitters: Vec::new(),
                warnings: Vec::new(),
            },
            root,
            bsdfs: HashMap::new(),
            textures: HashMap::new(),
            emitters: HashMap::new(),
            samplers: Vec::new(),
            groups: HashMap::new(),
            later_bsdfs: HashMap::new(),
            early: Vec::new(),
            origins: HashMap::new(),
            sensor: None,
            shapes: 0,
            resolver,
            coats: Coats::default(),
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
            "bsdf" if self.early.contains(&e.loc.to_string()) => Ok(()),
            "bsdf" => {
                let b = self.bsdf(e)?;
                match &b.id {
                    Some(id) if self.taken(id) => {
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
            "shape" if e.kind() == "shapegroup" => self.shapegroup(e),
            "shape" => {
                let e = self.emitter_refs(e);
                self.bsdfs_ahead(&e)?;
                self.shape(&e)
            }
            // Read before the walk (`ids`).
            "emitter" if e.kind() == "area" && e.attr("id").is_some() => Ok(()),
            "emitter" => self.emitter(e),
            "sampler" if e.attr("id").is_some() => Ok(()),
            "texture" => {
                let Some(id) = e.attr("id") else {
                    self.warn(e, "a top-level texture without an id cannot be used: ignored");
                    return Ok(());
                };
                if self.taken(id) {
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

    /// The top-level objects a `<ref>` may name before they are defined (Mitsuba resolves references after
    /// reading the whole file): area emitters (Mitsuba makes an object once and lets any `<ref>` to its id
    /// use it: an area emitter at the top level is the emitter of each shape that refers to it) and
    /// samplers.
    fn ids(&mut self, top: &[Elem]) -> Result<()> {
        for e in top {
            match (e.tag.as_str(), e.attr("id")) {
                ("emitter", Some(id)) if e.kind() == "area" => {
                    if self.emitters.contains_key(id) {
                        return Err(e.err(format!(
                            "the id \"{id}\" is already taken (ids are unique, as in Mitsuba)"
                        )));
                    }
                    self.emitters.insert(id.to_string(), (e.clone(), false));
                }
                ("sampler", Some(id)) => self.samplers.push(id.to_string()),
                ("bsdf", Some(id)) => {
                    // The first of a duplicate id: the walk refuses the second where it stands.
                    self.later_bsdfs.entry(id.to_string()).or_insert_with(|| e.clone());
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// Reads now the top-level bsdfs that `shape`'s `<ref>`s name and that are defined after it.
    fn bsdfs_ahead(&mut self, shape: &Elem) -> Result<()> {
        for c in shape.children.iter().filter(|c| c.tag == "ref") {
            let Some(id) = c.attr("id") else { continue };
            if self.bsdfs.contains_key(id) {
                continue;
            }
            if let Some(b) = self.later_bsdfs.remove(id) {
                self.top_level(&b)?;
                self.early.push(b.loc.to_string());
            }
        }
        Ok(())
    }

    /// Whether a top-level object already has the id `id`.
    fn taken(&self, id: &str) -> bool {
        self.bsdfs.contains_key(id)
            || self.textures.contains_key(id)
            || self.emitters.contains_key(id)
            || self.groups.contains_key(id)
    }

    /// `e` (a shape) with each `<ref>` that names a top-level area emitter replaced by that emitter, so that
    /// a ref resolves by the kind of object its id names (the others stay: bsdfs).
    fn emitter_refs(&mut self, e: &Elem) -> Elem {
        let mut e = e.clone();
        for c in &mut e.children {
            if c.tag != "ref" {
                continue;
            }
            if let Some((emitter, used)) = c.attr("id").and_then(|id| self.emitters.get_mut(id)) {
                *used = true;
                *c = emitter.clone();
            }
        }
        e
    }

    /// The `filename` of a plugin (a mesh, an image), found as Mitsuba finds it when it makes the plugin:
    /// by the scene's search path (its folder, after the `<path>` folders). Not found there, the folder of
    /// the file that names it is tried too (where ppm-vk looked before it read `<path>`; Mitsuba would
    /// not find it).
    fn file(&self, e: &Elem, props: &Props) -> Result<PathBuf> {
        let name = props
            .string("filename")?
            .ok_or_else(|| e.err("needs <string name=\"filename\" .../>"))?;
        let own = Path::new(&*e.loc.file).parent().unwrap_or(Path::new("")).join(name);
        if !self.resolver.finds(name) && own.exists() {
            return Ok(own);
        }
        Ok(self.resolver.resolve(name))
    }

    fn finish(mut self) -> Result<Scene> {
        let mut unused: Vec<Elem> = self
            .emitters
            .values()
            .filter(|(_, used)| !used)
            .map(|(e, _)| e.clone())
            .collect();
        unused.sort_by_key(|e| e.loc.to_string());
        for e in unused {
            self.warn(&e, "an area emitter no shape refers to: it lights nothing (ignored)");
        }
        self.camera()?;
        let root = self.root.clone();
        self.scene.check_with(&mut self.coats).map_err(|inv| {
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

#[cfg(test)]
mod tests {
    //! The whole reader's tests, and the helpers the other files' tests share (`load_in`, `load_body`,
    //! `error`, `write_texture`).

    use super::*;
    use crate::texture;
    use crate::{Surface, TempDir};

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
    pub(super) fn load_in(dir: &TempDir, body: &str, defines: &[(&str, &str)]) -> Result<Scene> {
        let path = dir.write("scene.xml", &format!("{HEAD}{body}\n</scene>\n"));
        let defines: Vec<(String, String)> = defines.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
        load(&path, &defines)
    }

    pub(super) fn load_body(body: &str) -> Result<Scene> {
        load_in(&TempDir::new("mitsuba"), body, &[])
    }

    /// The error of `body`, as one line.
    pub(super) fn error(body: &str) -> String {
        match load_body(body) {
            Ok(_) => panic!("expected an error for {body}"),
            Err(e) => format!("{e:#}"),
        }
    }

    /// Writes `name` (a 2 x 2 PNG: red, green over blue, white) into `dir`.
    pub(super) fn write_texture(dir: &TempDir, name: &str) {
        let rgb = [255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255];
        texture::write_png(&dir.0.join(name), 2, 2, &rgb);
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
                r#"<shape type="bsplinecurve"/>"#,
                r#"<shape type="bsplinecurve">"#,
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
                r#"<shape type="cube"><bsdf type="conductor"><texture name="eta" type="checkerboard"/></bsdf></shape>"#,
                r#"<texture type="checkerboard" name="eta">"#,
                12,
                "a texture on eta is not supported: read on diffuse reflectances",
            ),
            (
                r#"<emitter type="envmap"/>"#,
                r#"<emitter type="envmap">"#,
                12,
                "needs <string name=\"filename\"",
            ),
            (
                r#"<emitter type="sunsky"/>"#,
                r#"<emitter type="sunsky">"#,
                12,
                "unsupported emitter",
            ),
            (
                r#"<shape type="cube"><emitter type="point"/></shape>"#,
                r#"<emitter type="point">"#,
                12,
                "only area emitters belong on shapes",
            ),
            (
                r#"<shape type="sphere"><boolean name="flip_normals" value="true"/><emitter type="area"/></shape>"#,
                r#"<emitter type="area">"#,
                12,
                "flip_normals on an emitting sphere",
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

    /// A `<ref>` in a shape resolves by the kind of object its id names: a top-level area emitter
    /// (defined before or after, as Mitsuba resolves references after reading the file) is the shape's
    /// emitter, next to its bsdf (mitsuba-data's cbox-rgb.xml), a bsdf (likewise before or after) its
    /// bsdf; a sensor may refer to a top-level sampler.
    #[test]
    fn refs_to_top_level_emitters_and_samplers() {
        let body = r#"<shape type="rectangle" id="a"><ref id="white"/><ref id="glow"/></shape>
            <bsdf type="diffuse" id="white"><rgb name="reflectance" value="0.25"/></bsdf>
            <emitter type="area" id="glow"><rgb name="radiance" value="2, 3, 4"/></emitter>
            <shape type="rectangle" id="b"><ref id="glow"/></shape>
            <emitter type="area" id="unused"/>
            <sampler type="independent" id="s"/>
            <shape type="rectangle" id="c"><ref id="white"/></shape>"#;
        // The bsdf is defined after the first shape, which refers to it: read when that shape needs it
        // (Mitsuba resolves references after reading the file), once.
        let s = load_body(body).unwrap_or_else(|e| panic!("{e:#}"));
        let surface = |i: usize| s.materials[s.quads[i].material as usize].surface;
        let white = Surface::Diffuse {
            albedo: Vec3::splat(0.25),
        };
        assert_eq!((surface(1), surface(3)), (white, white));
        assert_eq!(s.materials[s.quads[3].material as usize].name, "white");
        let emission = |i: usize| s.materials[s.quads[i].material as usize].emission;
        assert_eq!(
            (emission(1), emission(2)),
            (Vec3::new(2.0, 3.0, 4.0), Vec3::new(2.0, 3.0, 4.0))
        );
        assert!(
            s.warnings
                .iter()
                .any(|w| w.contains("<emitter type=\"area\" id=\"unused\">: an area emitter no shape refers to")),
            "{:?}",
            s.warnings
        );
        let e = error(r#"<emitter type="area" id="x"/><emitter type="area" id="x"/>"#);
        assert!(
            e.contains("scene.xml:12:") && e.contains("the id \"x\" is already taken"),
            "{e}"
        );
        let e = error(r#"<bsdf type="diffuse" id="x"/><emitter type="area" id="x"/>"#);
        assert!(e.contains("the id \"x\" is already taken"), "{e}");
        let dir = TempDir::new("mitsuba-sampler-ref");
        let path = dir.write(
            "s.xml",
            r#"<scene version="2.1.0"><sampler type="independent" id="s"><integer name="sample_count" value="4"/></sampler>
               <sensor type="perspective"><ref id="s"/><film type="hdrfilm"><rfilter type="box"/></film></sensor>
               <shape type="rectangle"><emitter type="area"/></shape></scene>"#,
        );
        load(&path, &[]).unwrap_or_else(|e| panic!("{e:#}"));
    }

    #[test]
    fn parse_define_takes_name_and_value() {
        assert_eq!(parse_define("spp=16"), Ok(("spp".into(), "16".into())));
        assert_eq!(parse_define("v=a=b"), Ok(("v".into(), "a=b".into())));
        assert!(parse_define("spp").is_err());
        assert!(parse_define("$spp=1").is_err());
    }
}
