//! Stage 1: XML files to one owned tree of [`Elem`]s in document order, as Mitsuba's parser does it:
//! `$name` parameters substituted in every attribute (`-D` overrides first, then `<default>`s),
//! `<include>`s spliced in place (cycles and nesting deeper than Mitsuba's limit refused), file names
//! resolved by Mitsuba's search path (`<path>`), and files older than version 2 upgraded (`upgrade.rs`).

use std::path::{Path, PathBuf};
use std::rc::Rc;

use anyhow::{anyhow, bail, Result};

use super::elem::{Elem, Loc, Resolver, QUOTED};
use super::upgrade;
use crate::error::{truncated, Error};
use crate::files::{read_bounded, MAX_SCENE_BYTES};

/// Deepest `<include>` nesting, Mitsuba's own limit (`ParserConfig::max_include_depth`).
pub const MAX_INCLUDE_DEPTH: usize = 15;

/// Most files one scene may read, itself and its includes counted each time they are included: with the
/// depth alone, ten includes a file eight files deep were 10^8 files.
pub const MAX_INCLUDED_FILES: usize = 1000;

/// Most bytes of scene text one scene may read, its includes' counted each time they are included.
pub const MAX_INCLUDED_BYTES: u64 = 4 * MAX_SCENE_BYTES;

/// Most bytes `$name` substitution may produce in all a scene's attribute values: ten `<default>`s each
/// repeating the one before ten times made 10^10 bytes of a 1.6 KB file.
pub const MAX_SUBSTITUTED_BYTES: u64 = MAX_SCENE_BYTES;

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

/// The root element of the scene at `path` (`shown` in messages) and its top-level elements, includes
/// spliced in; `defines` override its `<default>`s, and one the scene never uses is an error.
/// Also returns the search path in force at the end of the scene file, which resolves the files the
/// scene's plugins name (meshes, images), as Mitsuba resolves them when it instantiates the plugins, and
/// the warnings of the upgrade of older files.
pub(super) fn read(path: &Path, shown: &str, defines: &[(String, String)]) -> Result<Read> {
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
        files: 0,
        bytes: 0,
        substituted: 0,
        // Mitsuba's `load_file` puts the scene's folder first (its working directory, which follows, is
        // not searched here: what a scene reads does not depend on where ppm-vk runs).
        resolver: Resolver::of_folder(parent(path)),
        warnings: Vec::new(),
    };
    let (root, children) = reader.read(path, shown, None)?;
    if let Some(p) = reader.params.iter().find(|p| !p.used) {
        bail!(
            "{shown}: -D {}={}: the scene never uses ${0} (Mitsuba refuses unused parameters too)",
            &p.key[1..],
            truncated(&p.value, QUOTED)
        );
    }
    Ok(Read {
        root,
        children,
        resolver: reader.resolver,
        warnings: reader.warnings,
    })
}

/// A scene file read: its root element and top-level elements, includes spliced in.
pub(super) struct Read {
    pub(super) root: Elem,
    pub(super) children: Vec<Elem>,
    pub(super) resolver: Resolver,
    pub(super) warnings: Vec<String>,
}

/// `path`'s folder (`.` for a bare file name).
fn parent(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
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
    /// Files read so far, and their bytes (within [`MAX_INCLUDED_FILES`], [`MAX_INCLUDED_BYTES`]).
    files: usize,
    bytes: u64,
    /// Bytes substitution has produced so far (within [`MAX_SUBSTITUTED_BYTES`]).
    substituted: u64,
    /// The search path in force (`<path>` prepends to it; an `<include>` reads with its file's folder
    /// prepended, and restores it after).
    resolver: Resolver,
    /// What the upgrade of older files approximates.
    warnings: Vec<String>,
}

impl Reader {
    /// The root element of the file at `path` and its children (includes spliced in).
    fn read(&mut self, path: &Path, shown: &str, included_at: Option<&Elem>) -> Result<(Elem, Vec<Elem>)> {
        let at = |msg: String| match included_at {
            Some(e) => e.err(msg),
            None => anyhow!(msg),
        };
        // Bounded and regular files only, as for TOML scenes (a device file would be read forever).
        let text = read_bounded(path, MAX_SCENE_BYTES, "scene file").map_err(|e| match included_at {
            Some(include) => include.err(e),
            None => anyhow::Error::from(e),
        })?;
        self.files += 1;
        self.bytes += text.len() as u64;
        if self.files > MAX_INCLUDED_FILES || self.bytes > MAX_INCLUDED_BYTES {
            return Err(at(format!(
                "the scene and its includes are more than {MAX_INCLUDED_FILES} files or {} MiB read in all \
                 (each include counted every time it is included)",
                MAX_INCLUDED_BYTES >> 20
            )));
        }
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
        let mut src = Src {
            doc: &doc,
            file,
            dir: parent(path),
            legacy: false,
            cursor: std::cell::Cell::new(TextCursor::default()),
        };
        let root = doc.root_element();
        let mut top = Vec::new();
        // The root is read like any element (its attributes substituted), without its children.
        let root_elem = self.element(&src, root, false)?;
        // Each file is upgraded by its own version, as Mitsuba 3's parser does (`transform_upgrade`).
        if let Some(v) = root_elem.attr("version") {
            let major = v.split('.').next().and_then(|m| m.trim().parse::<u32>().ok());
            match major {
                Some(0..=1) => src.legacy = true,
                Some(2..=3) => {}
                _ => {
                    return Err(root_elem.err(format!(
                        "version \"{}\": expected a Mitsuba version such as 0.6.0, 2.1.0 or 3.0.0",
                        truncated(v, QUOTED)
                    )))
                }
            }
        }
        if root.tag_name().name() == "scene" {
            for child in root.children().filter(|n| n.is_element()) {
                self.convert(&src, child, &mut top, true)?;
            }
        } else {
            // An included file may hold one object instead of a scene.
            self.convert(&src, root, &mut top, false)?;
        }
        self.open.pop();
        Ok((root_elem, top))
    }

    /// Appends what `node` stands for to `out`: itself, an included file's elements, or nothing (a
    /// `<default>`, a `<path>`); `top` when `node` is a child of the file's root.
    fn convert(&mut self, src: &Src, node: roxmltree::Node, out: &mut Vec<Elem>, top: bool) -> Result<()> {
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
                // As Mitsuba's parser: the including file's folder first, for this include only.
                let file = e.required("filename")?;
                let outer = self.resolver.clone();
                self.resolver = outer.prepend(src.dir.clone());
                let path = self.resolver.resolve(file);
                let shown = path.display().to_string();
                let read = self.read(&path, &shown, Some(&e));
                self.resolver = outer;
                out.extend(read?.1);
            }
            "path" => {
                // Mitsuba's `<path value="dir"/>`: a folder searched first from here on, relative to this
                // file's folder, else found by the search path; a child of the root only.
                if !top {
                    return Err(e.err("<path> belongs directly in the <scene> (as Mitsuba requires)"));
                }
                let value = e.required("value")?;
                let mut dir = PathBuf::from(value);
                if !dir.is_absolute() {
                    dir = src.dir.join(value);
                    if !dir.exists() {
                        dir = self.resolver.resolve(value);
                    }
                }
                if !dir.is_dir() {
                    return Err(e.err(format!("folder \"{}\" not found", dir.display())));
                }
                self.resolver = self.resolver.prepend(dir);
            }
            _ => out.push(e),
        }
        Ok(())
    }

    /// `node` with its attributes substituted and (with `deep`) its children converted.
    fn element(&mut self, src: &Src, node: roxmltree::Node, deep: bool) -> Result<Elem> {
        let pos = src.position(node.range().start);
        let mut e = Elem {
            tag: node.tag_name().name().to_string(),
            attrs: Vec::new(),
            children: Vec::new(),
            loc: Loc {
                file: src.file.clone(),
                line: pos.row,
                col: pos.col,
                resolver: self.resolver.clone(),
            },
        };
        for a in node.attributes() {
            let value = self.substitute(a.value()).map_err(|m| {
                e.err(format!(
                    "attribute {}=\"{}\": {m}",
                    a.name(),
                    truncated(a.value(), QUOTED)
                ))
            })?;
            e.attrs.push((a.name().to_string(), value));
        }
        if src.legacy {
            upgrade::rename(&mut e);
        }
        if deep {
            // Bounded, as the reader and the scene's drop recurse per level (a fuzzed file nested
            // thousands deep overflowed the stack).
            if node.ancestors().take(MAX_NESTING + 2).count() > MAX_NESTING {
                return Err(e.err(format!("elements nested deeper than {MAX_NESTING} levels")));
            }
            let mut children = Vec::new();
            for child in node.children().filter(|n| n.is_element()) {
                self.convert(src, child, &mut children, false)?;
            }
            e.children = children;
            if src.legacy {
                upgrade::children(&mut e, &mut self.warnings)?;
            }
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
                    // Counted before it is made: a value repeating another grows tenfold a level.
                    self.substituted += p.value.len() as u64;
                    if self.substituted > MAX_SUBSTITUTED_BYTES {
                        return Err(format!(
                            "substituting {} makes more than {} MiB of attribute values in all (a <default> \
                             that repeats another many times over?)",
                            p.key,
                            MAX_SUBSTITUTED_BYTES >> 20
                        ));
                    }
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
            // A defined one left over came from a value (`-D res=$res`): values are not substituted again.
            if let Some(p) = self.params.iter().find(|p| p.key[1..] == name) {
                return Err(format!(
                    "${name} is left after substitution: it stands for \"{}\", which holds a $ parameter \
                     itself, and a parameter's value is used as written, not substituted again (give \
                     {name} a value without $, or write a literal $ as \\$)",
                    truncated(&p.value, QUOTED)
                ));
            }
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
    dir: PathBuf,
    /// Written for Mitsuba before version 2: upgraded as it is read.
    legacy: bool,
    /// The last position converted to a line and column.
    cursor: std::cell::Cell<TextCursor>,
}

/// A byte offset in the file with its line and column (1-based, the column in characters, as roxmltree
/// counts them).
#[derive(Clone, Copy, Debug, PartialEq)]
struct TextCursor {
    pos: usize,
    row: u32,
    col: u32,
}

impl Default for TextCursor {
    fn default() -> Self {
        TextCursor { pos: 0, row: 1, col: 1 }
    }
}

impl Src<'_, '_> {
    /// The line and column of byte offset `pos`. Elements are read in document order, so each step goes
    /// on from the last position: the whole file is scanned once (roxmltree's `text_pos_at` scans from the
    /// start each time, which made a file of 65k elements take minutes).
    fn position(&self, pos: usize) -> TextCursor {
        let text = self.doc.input_text();
        let mut c = self.cursor.get();
        if pos < c.pos {
            c = TextCursor::default();
        }
        for ch in text[c.pos..pos].chars() {
            match ch {
                '\n' => {
                    c.row += 1;
                    c.col = 1;
                }
                _ => c.col += 1,
            }
        }
        c.pos = pos;
        self.cursor.set(c);
        c
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::load_in;
    use crate::{Scene, Surface, TempDir};

    /// Lines and columns as roxmltree's own `text_pos_at` gives them, for every element in document order
    /// and out of it (the cursor restarts), across multi-byte characters and CRLF line ends.
    #[test]
    fn positions_are_roxmltree_s() {
        let text = "<scene version=\"3.0.0\">\r\n  <!-- é, ü -->\n\t<bsdf type=\"diffuse\" id=\"ä\"><rgb name=\"reflectance\" value=\"1\"/></bsdf>\n\n   <shape type=\"sphere\"/>\r\n</scene>\n";
        let doc = roxmltree::Document::parse(text).unwrap();
        let src = super::Src {
            doc: &doc,
            file: "t.xml".into(),
            dir: std::path::PathBuf::new(),
            legacy: false,
            cursor: std::cell::Cell::new(super::TextCursor::default()),
        };
        let starts: Vec<usize> = doc
            .descendants()
            .filter(|n| n.is_element())
            .map(|n| n.range().start)
            .collect();
        assert_eq!(starts.len(), 4);
        for &p in starts.iter().chain(starts.iter().rev()) {
            let (ours, theirs) = (src.position(p), doc.text_pos_at(p));
            assert_eq!((ours.row, ours.col), (theirs.row, theirs.col), "at byte {p}");
        }
    }

    fn albedo(s: &Scene, quad: usize) -> glam::Vec3 {
        match s.materials[s.quads[quad].material as usize].surface {
            Surface::Diffuse { albedo } => albedo,
            _ => panic!("a diffuse quad"),
        }
    }

    /// What Mitsuba 3 read in the same files (scenes/references/file_resolver.py wrote it).
    fn mitsubas(name: &str) -> glam::Vec3 {
        let text = include_str!("../../../../scenes/references/file-resolver.json");
        let json: serde_json::Value = serde_json::from_str(text).unwrap();
        let c: Vec<f32> = json[name]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap() as f32)
            .collect();
        glam::Vec3::new(c[0], c[1], c[2])
    }

    /// `<path>` folders are searched first, latest first; a spectrum file resolves by the search path in
    /// force where it is read, a plugin's file (a mesh) by the one at the end of the scene file, as in
    /// Mitsuba 3; an include by the including file's folder first, then the search path in force. The
    /// spectra read are Mitsuba's own in the same files (file-resolver.json) within 1e-5.
    #[test]
    fn path_folders_and_includes_resolve_as_mitsubas_file_resolver() {
        let dir = TempDir::new("mitsuba-path");
        for (sub, value) in [("", 0.4), ("a/", 0.2), ("b/", 0.6)] {
            std::fs::create_dir_all(dir.0.join(sub)).unwrap();
            dir.write(&format!("{sub}t.spd"), &format!("360 {value}\n830 {value}\n"));
        }
        std::fs::create_dir_all(dir.0.join("meshes")).unwrap();
        dir.write(
            "meshes/sq.obj",
            "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nf 1 2 3\nf 1 3 4\n",
        );
        let cube = |file: &str| {
            format!(
                r#"<shape type="cube"><bsdf type="diffuse"><spectrum name="reflectance" filename="{file}"/></bsdf></shape>"#
            )
        };
        let body = format!(
            r#"<shape type="obj"><string name="filename" value="sq.obj"/></shape>{}<path value="a"/>{}<path value="b"/>{}
               <path value="meshes"/>"#,
            cube("t.spd"),
            cube("t.spd"),
            cube("t.spd")
        );
        let s = load_in(&dir, &body, &[]).unwrap_or_else(|e| panic!("{e:#}"));
        // The head's lamp is quad 0, then three cubes of six quads.
        for (cube, read) in ["before", "after_a", "after_b"].iter().enumerate() {
            let (got, want) = (albedo(&s, 1 + 6 * cube), mitsubas(read));
            assert!(
                (got - want).abs().max_element() < 1e-5 * want.max_element(),
                "{read}: {got} vs {want}"
            );
        }
        assert_eq!(s.meshes.len(), 1, "sq.obj found by the <path> after it");
        let e = format!(
            "{:#}",
            load_in(
                &dir,
                r#"<shape type="obj"><string name="filename" value="sq.obj"/></shape>"#,
                &[]
            )
            .unwrap_err()
        );
        assert!(e.contains("sq.obj") && e.contains("cannot read"), "{e}");
        let e = format!("{:#}", load_in(&dir, r#"<path value="nowhere"/>"#, &[]).unwrap_err());
        assert!(
            e.contains("scene.xml:12:1: <path>: folder") && e.contains("nowhere\" not found"),
            "{e}"
        );
        let e = format!(
            "{:#}",
            load_in(&dir, r#"<shape type="cube"><path value="a"/></shape>"#, &[]).unwrap_err()
        );
        assert!(e.contains("<path> belongs directly in the <scene>"), "{e}");

        // mitsuba-data's participating_media: include/a.xml includes "include/b.xml", found from the
        // outer scene's folder (include/include/b.xml does not exist).
        std::fs::create_dir_all(dir.0.join("include")).unwrap();
        dir.write(
            "include/a.xml",
            r#"<scene version="3.0.0"><include filename="include/b.xml"/></scene>"#,
        );
        dir.write(
            "include/b.xml",
            r#"<scene version="3.0.0"><bsdf type="diffuse" id="included"><spectrum name="reflectance" filename="t.spd"/></bsdf></scene>"#,
        );
        let s = load_in(
            &dir,
            r#"<include filename="include/a.xml"/><shape type="cube"><ref id="included"/></shape>"#,
            &[],
        )
        .unwrap_or_else(|e| panic!("{e:#}"));
        let (got, want) = (albedo(&s, 1), mitsubas("included"));
        assert!(
            (got - want).abs().max_element() < 1e-5 * want.max_element(),
            "{got} vs {want}"
        );
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
}
