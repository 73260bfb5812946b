//! OBJ/MTL import through tobj (`triangulate`, `single_index`), into one world-space [`Mesh`].
//!
//! tobj reports errors without a line number and panics on a few malformed lines (a colour with fewer
//! than three numbers in an MTL; a zero index in a debug build), so each file is first scanned here:
//! every line tobj would refuse or mis-read is reported as `<file>:<line>: <what>`, and tobj only ever
//! sees input it handles. MTL materials become engine materials by the table in
//! `docs/scene-format.md`; what they cannot express is reported once per material in `Scene::warnings`.

use std::cell::RefCell;
use std::collections::HashMap;
use std::panic::AssertUnwindSafe;
use std::path::Path;

use anyhow::{anyhow, bail, Result};
use glam::{DAffine3, DVec3, Vec2, Vec3};

use super::texture::{self, Filter, Texture, Wrap};
use super::{generated, Material, Mesh, Scene, Surface, Triangle};
use crate::error::fmt_vec;
use crate::files::{read_bounded, MAX_MESH_BYTES, MAX_SCENE_BYTES};

/// How [`Scene::import_obj`] places and dresses an OBJ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ObjImport {
    /// Object to world, applied to positions (and its inverse transpose to normals). A mirroring
    /// transform (negative determinant) reverses the winding, so the front side stays the one the
    /// file meant.
    pub transform: DAffine3,
    /// Every triangle gets this material (an index into `Scene::materials`); the MTL is not read.
    pub material: Option<u32>,
}

impl Default for ObjImport {
    fn default() -> Self {
        ObjImport {
            transform: DAffine3::IDENTITY,
            material: None,
        }
    }
}

/// Albedo of an MTL material that gives neither Kd nor emission (Blender's default).
const DEFAULT_KD: f32 = 0.8;
/// Index of refraction of a glass MTL material without Ni.
const DEFAULT_IOR: f32 = 1.5;

/// Imports the OBJ at `path` (see [`Scene::import_obj`]); `flip_tex_coords` turns its `vt` upside down
/// (v' = 1 - v) into Mitsuba's convention, where v grows downwards in the image, as Mitsuba's OBJ
/// reader does by default.
pub(super) fn import(
    scene: &mut Scene,
    path: &Path,
    import: &ObjImport,
    max_triangles: usize,
    flip_tex_coords: bool,
) -> Result<usize> {
    let shown = path.display().to_string();
    let text = read_bounded(path, MAX_MESH_BYTES, "OBJ file").map_err(|e| {
        let hint = if generated::is_generated(path) {
            format!(" (a generated demo mesh: run `{}` to write it)", generated::COMMAND)
        } else {
            String::new()
        };
        anyhow!("{e}{hint}")
    })?;
    let stats = prescan(&text, &shown, max_triangles)?;
    if stats.triangles == 0 {
        bail!("{shown}: no faces: the mesh is empty");
    }
    if import.material.is_none() {
        if stats.mtllibs.is_empty() {
            bail!(
                "{shown}: no materials: the OBJ names no MTL file (mtllib) and the scene gives the \
                 mesh no `material`"
            );
        }
        if let Some(line) = stats.first_bare_face {
            bail!(
                "{shown}:{line}: face without a material (no usemtl before it), and the scene gives \
                 the mesh no `material`"
            );
        }
    }

    let dir = path.parent().unwrap_or(Path::new(""));
    // tobj's loader callback can only return tobj's error codes: ours wait here.
    let mtl_error: RefCell<Option<anyhow::Error>> = RefCell::new(None);
    let mtl_of: RefCell<HashMap<String, String>> = RefCell::new(HashMap::new());
    let loader = |name: &Path| {
        if import.material.is_some() {
            // Overridden: the MTL is not needed, so not read (an empty library).
            return tobj::load_mtl_buf(&mut &b""[..]);
        }
        let line = stats
            .mtllibs
            .iter()
            .find(|(_, n)| Path::new(n) == name)
            .map_or(0, |(l, _)| *l);
        let full = dir.join(name);
        match read_mtl(&full, &format!("{shown}:{line}")) {
            Ok(Ok(lib)) => {
                let mut of = mtl_of.borrow_mut();
                for m in &lib.0 {
                    of.insert(m.name.clone(), full.display().to_string());
                }
                Ok(lib)
            }
            Ok(Err(e)) => {
                mtl_error.borrow_mut().get_or_insert(anyhow!("{}: {e}", full.display()));
                Err(e)
            }
            Err(e) => {
                mtl_error.borrow_mut().get_or_insert(e);
                Err(tobj::LoadError::OpenFileFailed)
            }
        }
    };
    // The update fills the fields tobj has only with its `merging`/`reordering` features.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    // The scan above leaves tobj nothing known to panic on; should it still, that is an error here.
    let result = std::panic::catch_unwind(AssertUnwindSafe(|| {
        tobj::load_obj_buf(&mut text.as_bytes(), &options, loader)
    }));
    if let Some(e) = mtl_error.take() {
        return Err(e);
    }
    let (models, mtl_materials) = match result {
        Err(_) => bail!("{shown}: the OBJ reader (tobj) failed on this file"),
        Ok(Err(e)) => bail!("{shown}: {e}"),
        Ok(Ok(r)) => r,
    };
    let mtl_materials = match (import.material, mtl_materials) {
        (Some(_), _) => Vec::new(),
        (None, Ok(m)) => m,
        (None, Err(e)) => bail!("{shown}: MTL: {e}"),
    };
    if import.material.is_none() {
        for (line, name) in &stats.usemtls {
            if !mtl_materials.iter().any(|m| m.name == *name) {
                let libs: Vec<&str> = stats.mtllibs.iter().map(|(_, n)| n.as_str()).collect();
                bail!("{shown}:{line}: usemtl {name}: no such material in {}", libs.join(", "));
            }
        }
    }

    // Whether every vertex has a (finite) texture coordinate: an MTL's map_Kd needs them.
    let uvs_complete = models.iter().filter(|m| !m.mesh.indices.is_empty()).all(|m| {
        m.mesh.texcoords.len() / 2 == m.mesh.positions.len() / 3 && m.mesh.texcoords.iter().all(|x| x.is_finite())
    });
    // tobj material index -> scene material index, made on first use.
    let mut index_of: HashMap<usize, u32> = HashMap::new();
    let mut warnings = Vec::new();
    let mtl_of = mtl_of.into_inner();
    let mut material_of = |id: Option<usize>, object: &str| -> Result<u32> {
        if let Some(k) = import.material {
            return Ok(k);
        }
        let Some(id) = id else {
            bail!("{shown}: object {object} has faces without a material");
        };
        if let Some(&k) = index_of.get(&id) {
            return Ok(k);
        }
        let m = mtl_materials
            .get(id)
            .ok_or_else(|| anyhow!("{shown}: object {object}: material {id} out of range"))?;
        let mtl = mtl_of.get(&m.name).map_or("MTL", String::as_str);
        let (mut mat, mut notes) = convert(m, format!("{shown}:{}", m.name), mtl)?;
        if let (Surface::Diffuse { albedo }, Some(map)) = (mat.surface, &m.diffuse_texture) {
            // A map that cannot be used (a missing image is common in exported files) leaves Kd alone.
            let map_kd = match uvs_complete {
                true => diffuse_map(map, mtl, m.diffuse.is_some().then_some(albedo)),
                false => Err("the OBJ has no texture coordinates (vt) on every face corner".into()),
            };
            match map_kd {
                Ok((t, more)) => {
                    // Without Kd the image alone is the colour: no 0.8 was assumed.
                    notes.retain(|n| !n.starts_with("no Kd"));
                    notes.extend(more);
                    mat.surface = Surface::Diffuse { albedo: t.max() };
                    mat.texture = Some(texture::intern(&mut scene.textures, std::borrow::Cow::Owned(t)));
                }
                Err(e) => notes.push(format!("map_Kd {map} ignored ({e}): the constant Kd is used")),
            }
        }
        let k = match scene.materials.iter().position(|x| x.name == mat.name) {
            // The same OBJ imported again: one material (and its warning) serves both.
            Some(i) if scene.materials[i] == mat => i,
            Some(_) => bail!(
                "{shown}: material name \"{}\" is already taken by a different material",
                mat.name
            ),
            None => {
                if !notes.is_empty() {
                    warnings.push(format!(
                        "{shown}: material \"{}\" ({mtl}): {}",
                        m.name,
                        notes.join("; ")
                    ));
                }
                scene.materials.push(mat);
                scene.materials.len() - 1
            }
        };
        let k = u32::try_from(k).map_err(|_| anyhow!("{shown}: too many materials"))?;
        index_of.insert(id, k);
        Ok(k)
    };

    let mut positions: Vec<DVec3> = Vec::new();
    let mut normals: Vec<DVec3> = Vec::new();
    let mut uvs: Vec<Vec2> = Vec::new();
    // Whether every vertex came with a normal, and whether any did; whether every one has a texture
    // coordinate.
    let (mut all_normals, mut any_normals, mut all_uvs) = (true, false, true);
    let mut triangles: Vec<([u32; 3], u32)> = Vec::new();
    for model in &models {
        let m = &model.mesh;
        // tobj ends the file with a model even when no face follows the last `o` or `usemtl`.
        if m.indices.is_empty() {
            continue;
        }
        let material = material_of(m.material_id, &model.name)?;
        let base = u32::try_from(positions.len()).map_err(|_| anyhow!("{shown}: too many vertices"))?;
        let dvec = |p: &[f32]| DVec3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2]));
        positions.extend(m.positions.chunks_exact(3).map(dvec));
        if !m.normals.is_empty() && m.normals.len() == m.positions.len() {
            any_normals = true;
            normals.extend(m.normals.chunks_exact(3).map(dvec));
        } else {
            any_normals |= !m.normals.is_empty();
            all_normals = false;
        }
        if m.texcoords.len() / 2 == m.positions.len() / 3 {
            let v = |t: f32| if flip_tex_coords { 1.0 - t } else { t };
            uvs.extend(m.texcoords.chunks_exact(2).map(|t| Vec2::new(t[0], v(t[1]))));
        } else {
            all_uvs = false;
        }
        for t in m.indices.chunks_exact(3) {
            triangles.push(([t[0] + base, t[1] + base, t[2] + base], material));
        }
    }
    if stats.skipped > 0 {
        warnings.push(format!(
            "{shown}: {} point and line elements ignored (only faces are surfaces)",
            stats.skipped
        ));
    }
    let raw = RawMesh {
        name: shown,
        positions,
        normals: (all_normals && any_normals).then_some(normals),
        partial_normals: any_normals && !all_normals,
        uvs: all_uvs.then_some(uvs),
        triangles,
    };
    scene.warnings.extend(warnings);
    add_mesh(scene, raw, &import.transform, false)
}

/// A triangle mesh as its file gives it, in object space: what [`add_mesh`] places and cleans.
pub(super) struct RawMesh {
    /// The file as shown in messages (it names the mesh).
    pub name: String,
    pub positions: Vec<DVec3>,
    /// One per position when every vertex has one.
    pub normals: Option<Vec<DVec3>>,
    /// Some vertices had a normal and some not (they are all dropped, with a warning).
    pub partial_normals: bool,
    /// Texture coordinates in Mitsuba's convention (v grows downwards in the image), one per position
    /// when every vertex has one.
    pub uvs: Option<Vec<Vec2>>,
    /// Counter-clockwise seen from the front, with their material (an index into `Scene::materials`).
    pub triangles: Vec<([u32; 3], u32)>,
}

/// Places `raw` in the scene by `transform` (its inverse transpose for normals) and appends it to
/// `scene.meshes`; returns its index. A mirroring transform reverses the winding so that the front
/// side stays the one the file meant; `flip` turns every triangle (and normal) around on top of that.
/// Degenerate triangles are dropped with a warning, and the vertices only they used with them (texture
/// coordinates follow their vertices; ones that are not finite are dropped with a warning).
pub(super) fn add_mesh(scene: &mut Scene, raw: RawMesh, transform: &DAffine3, flip: bool) -> Result<usize> {
    let shown = raw.name;
    let mut warnings = Vec::new();
    let lin = transform.matrix3;
    let reverse = (lin.determinant() < 0.0) != flip;
    let normal_matrix = if flip {
        -lin.inverse().transpose()
    } else {
        lin.inverse().transpose()
    };
    let positions: Vec<Vec3> = raw
        .positions
        .iter()
        .map(|&p| transform.transform_point3(p).as_vec3())
        .collect();
    let normals: Option<Vec<Vec3>> = raw.normals.map(|n| {
        n.iter()
            .map(|&n| (normal_matrix * n).normalize_or_zero().as_vec3())
            .collect()
    });
    let mut triangles = raw.triangles;
    if reverse {
        for (t, _) in &mut triangles {
            t.swap(1, 2);
        }
    }
    if let Some(k) = positions.iter().position(|p| !p.is_finite()) {
        bail!(
            "{shown}: vertex {k} is {} after the transform: the transform overflows f32",
            fmt_vec(positions[k].to_array())
        );
    }

    // Drop degenerate triangles, then the vertices no triangle uses any more.
    let total = triangles.len();
    triangles.retain(|&([a, b, c], material)| {
        a != b
            && b != c
            && a != c
            && !Triangle {
                p: [a, b, c].map(|i| positions[i as usize]),
                material,
            }
            .is_degenerate()
    });
    let dropped = total - triangles.len();
    if triangles.is_empty() {
        bail!(
            "{shown}: every one of its {total} triangles is degenerate (zero area or a repeated \
             vertex): the mesh is empty"
        );
    }
    if dropped > 0 {
        warnings.push(format!(
            "{shown}: {dropped} degenerate triangles dropped (zero area or a repeated vertex)"
        ));
    }
    let mut remap = vec![u32::MAX; positions.len()];
    let mut kept: Vec<u32> = Vec::new();
    let mut indices = Vec::with_capacity(triangles.len());
    let mut materials = Vec::with_capacity(triangles.len());
    for (tri, material) in &triangles {
        indices.push(tri.map(|i| {
            let r = &mut remap[i as usize];
            if *r == u32::MAX {
                *r = kept.len() as u32;
                kept.push(i);
            }
            *r
        }));
        materials.push(*material);
    }
    let normals = if let Some(normals) = normals {
        let n: Vec<Vec3> = kept.iter().map(|&i| normals[i as usize]).collect();
        match n.iter().position(|v| *v == Vec3::ZERO) {
            None => Some(n),
            Some(k) => {
                warnings.push(format!(
                    "{shown}: vertex normals dropped (flat shading): normal {k} is zero or not \
                     finite"
                ));
                None
            }
        }
    } else {
        if raw.partial_normals {
            warnings.push(format!(
                "{shown}: vertex normals dropped (flat shading): only some vertices have one"
            ));
        }
        None
    };
    let uvs = raw.uvs.and_then(|uvs| {
        let uv: Vec<Vec2> = kept.iter().map(|&i| uvs[i as usize]).collect();
        match uv.iter().position(|t| !t.is_finite()) {
            None => Some(uv),
            Some(k) => {
                warnings.push(format!(
                    "{shown}: texture coordinates dropped: coordinate {k} is not finite ({})",
                    uv[k]
                ));
                None
            }
        }
    });
    scene.meshes.push(Mesh {
        name: shown,
        positions: kept.iter().map(|&i| positions[i as usize]).collect(),
        normals,
        uvs,
        indices,
        materials,
    });
    scene.warnings.extend(warnings);
    Ok(scene.meshes.len() - 1)
}

/// What the scan of an OBJ found.
#[derive(Debug, Default)]
struct ObjStats {
    /// After fan triangulation.
    triangles: usize,
    /// Point and two-vertex line elements (skipped).
    skipped: usize,
    /// `(line, name)` of every `mtllib` and `usemtl`, names as tobj reads them.
    mtllibs: Vec<(usize, String)>,
    usemtls: Vec<(usize, String)>,
    /// Line of the first face before any `usemtl`.
    first_bare_face: Option<usize>,
}

/// The name after a keyword, read as tobj does (the rest of the line after its first space).
fn tobj_name(line: &str) -> String {
    line.split_once(' ').map_or("", |(_, r)| r.trim()).to_string()
}

fn numbers<const N: usize>(words: &[&str]) -> Option<[f32; N]> {
    let mut out = [0.0; N];
    for (o, w) in out.iter_mut().zip(words) {
        *o = w.parse().ok()?;
    }
    (words.len() >= N).then_some(out)
}

/// Checks every line tobj reads (so that its errors, which carry no line, cannot happen) and counts.
fn prescan(text: &str, shown: &str, max_triangles: usize) -> Result<ObjStats> {
    // Totals first: a positive index may point at a vertex defined further down (tobj resolves
    // them at the end), a negative one counts back from the line it is on.
    let mut total = [0usize; 3];
    for line in text.lines() {
        match line.split_whitespace().next() {
            Some("v") => total[0] += 1,
            Some("vt") => total[1] += 1,
            Some("vn") => total[2] += 1,
            _ => {}
        }
    }
    let mut st = ObjStats::default();
    let mut so_far = [0usize; 3];
    let mut have_material = false;
    for (i, line) in text.lines().enumerate() {
        let ln = i + 1;
        let fail = |msg: String| anyhow!("{shown}:{ln}: {msg}");
        let words: Vec<&str> = line.split_whitespace().collect();
        let Some((&kw, args)) = words.split_first() else {
            continue;
        };
        match kw {
            "v" => {
                so_far[0] += 1;
                let k = so_far[0];
                let Some(mut p) = numbers::<3>(args) else {
                    return Err(fail(format!("vertex {k} needs three numbers x y z: {:?}", line.trim())));
                };
                match args.len() {
                    // x y z, or with colours r g b (which tobj reads leniently).
                    3 | 6 => {}
                    4 => match args[3].parse::<f32>() {
                        Ok(w) if w != 0.0 => p = p.map(|c| c / w),
                        _ => {
                            return Err(fail(format!(
                                "vertex {k}: w must be a non-zero number, got {:?}",
                                args[3]
                            )))
                        }
                    },
                    n => {
                        return Err(fail(format!(
                            "vertex {k}: expected x y z with an optional w or r g b, got {n} numbers"
                        )))
                    }
                }
                if !p.iter().all(|c| c.is_finite()) {
                    return Err(fail(format!("vertex {k} is not finite: {:?}", line.trim())));
                }
            }
            "vt" => {
                so_far[1] += 1;
                if numbers::<2>(args).is_none() {
                    return Err(fail(format!(
                        "texture coordinate needs two numbers u v: {:?}",
                        line.trim()
                    )));
                }
            }
            "vn" => {
                so_far[2] += 1;
                if numbers::<3>(args).is_none() {
                    return Err(fail(format!("normal needs three numbers x y z: {:?}", line.trim())));
                }
            }
            "f" | "l" => {
                for r in args {
                    check_ref(r, so_far, total).map_err(fail)?;
                }
                let n = args.len();
                if n == 0 {
                    return Err(fail(format!("`{kw}` without vertices")));
                }
                if kw == "l" && n >= 3 {
                    return Err(fail(
                        "polylines (l) of 3 or more points are not supported (tobj would read \
                         them as faces)"
                            .into(),
                    ));
                }
                if n < 3 {
                    st.skipped += 1;
                    continue;
                }
                st.triangles += n - 2;
                if st.triangles > max_triangles {
                    return Err(fail(format!(
                        "more than {max_triangles} triangles: the limit (MAX_TRIANGLES) is \
                         reached here"
                    )));
                }
                if !have_material {
                    st.first_bare_face.get_or_insert(ln);
                }
            }
            "usemtl" | "mtllib" => {
                let name = tobj_name(line);
                if name.is_empty() {
                    return Err(fail(format!("`{kw}` needs a name")));
                }
                if kw == "usemtl" {
                    have_material = true;
                    st.usemtls.push((ln, name));
                } else {
                    st.mtllibs.push((ln, name));
                }
            }
            _ => {}
        }
    }
    Ok(st)
}

/// One `v`, `v/vt`, `v//vn` or `v/vt/vn` of a face: every index in range.
fn check_ref(token: &str, so_far: [usize; 3], total: [usize; 3]) -> Result<(), String> {
    const KIND: [&str; 3] = ["vertex", "texture coordinate", "normal"];
    let parts: Vec<&str> = token.split('/').collect();
    if parts.len() > 3 {
        return Err(format!("bad face vertex {token:?}"));
    }
    for (k, part) in parts.iter().enumerate() {
        if part.is_empty() {
            if k == 0 {
                return Err(format!("face vertex {token:?} has no position index"));
            }
            continue;
        }
        let x: isize = part.parse().map_err(|_| format!("bad face vertex {token:?}"))?;
        // tobj ignores texture and normal indices when the file has none of that kind.
        if k > 0 && total[k] == 0 {
            continue;
        }
        let kind = KIND[k];
        if x == 0 {
            return Err(format!("{kind} index 0 in {token:?}: OBJ indices start at 1"));
        }
        if x > 0 && x as usize > total[k] {
            return Err(format!("{kind} index {x} out of range ({} in the file)", total[k]));
        }
        if x < 0 && x.unsigned_abs() > so_far[k] {
            return Err(format!(
                "{kind} index {x} out of range ({} before this line)",
                so_far[k]
            ));
        }
    }
    Ok(())
}

/// Reads one MTL file through tobj, after checking the lines tobj would panic on or refuse (the
/// outer error: ours, with a line; the inner one: tobj's).
fn read_mtl(path: &Path, mtllib_at: &str) -> Result<tobj::MTLLoadResult> {
    let shown = path.display();
    // Bounded and regular only: `mtllib /dev/zero` would be read until memory ran out.
    let text = read_bounded(path, MAX_SCENE_BYTES, &format!("MTL file (mtllib at {mtllib_at})"))?;
    for (i, line) in text.lines().enumerate() {
        let fail = |msg: String| anyhow!("{shown}:{}: {msg}", i + 1);
        let t = line.trim();
        let words: Vec<&str> = t.split_whitespace().collect();
        let Some((&kw, args)) = words.split_first() else {
            continue;
        };
        // The part of the line after the keyword, where tobj takes file names from.
        let rest = |n: usize| t.get(n..).map_or("", str::trim);
        match kw {
            "Ka" | "Kd" | "Ks" | "Ke" if numbers::<3>(args).is_none() => {
                return Err(fail(format!("{kw} needs three numbers r g b: {t:?}")))
            }
            "Ns" | "Ni" | "d" if numbers::<1>(args).is_none() => {
                return Err(fail(format!("{kw} needs a number: {t:?}")))
            }
            "illum" if args.first().and_then(|a| a.parse::<u8>().ok()).is_none() => {
                return Err(fail(format!("illum needs a model number (0-10): {t:?}")))
            }
            "newmtl" if rest(6).is_empty() => return Err(fail("newmtl needs a name".into())),
            "map_Ka" | "map_Kd" | "map_Ks" | "map_Ns" | "map_ns" | "map_NS" if rest(6).is_empty() => {
                return Err(fail(format!("{kw} needs a file name")))
            }
            "map_Bump" | "map_bump" if rest(8).is_empty() => return Err(fail(format!("{kw} needs a file name"))),
            "bump" if rest(4).is_empty() => return Err(fail(format!("{kw} needs a file name"))),
            "map_d" if rest(5).is_empty() => return Err(fail(format!("{kw} needs a file name"))),
            _ => {}
        }
    }
    Ok(tobj::load_mtl_buf(&mut text.as_bytes()))
}

/// An MTL's `map_Kd` (the rest of its line: options, then the image file, relative to the MTL's folder)
/// as a texture: sRGB-encoded unless the image holds floats, bilinear, repeating (`-clamp on`: clamped),
/// `-s` and `-o` (scale and offset of the OBJ's texture coordinates) made its `to_uv`. `kd`, when the MTL
/// gives Kd, multiplies it, as the format says. Also returns notes on the options it ignores.
fn diffuse_map(spec: &str, mtl: &str, kd: Option<Vec3>) -> Result<(Texture, Vec<String>), String> {
    let words: Vec<&str> = spec.split_whitespace().collect();
    let (mut scale, mut offset, mut wrap) = ([1.0f32, 1.0], [0.0f32, 0.0], Wrap::Repeat);
    let mut notes = Vec::new();
    let mut i = 0;
    while i < words.len() && words[i].starts_with('-') {
        let option = words[i];
        i += 1;
        // How many words the option takes: numbers (at least one) or one word.
        let numbers: Vec<f32> = words[i..]
            .iter()
            .take(3)
            .map_while(|w| w.parse::<f32>().ok().filter(|x| x.is_finite()))
            .collect();
        match option {
            "-s" | "-o" | "-t" | "-mm" => {
                let n = if option == "-mm" {
                    numbers.len().min(2)
                } else {
                    numbers.len()
                };
                if n == 0 {
                    return Err(format!("option {option} needs numbers"));
                }
                match option {
                    "-s" => scale = [numbers[0], numbers.get(1).copied().unwrap_or(1.0)],
                    "-o" => offset = [numbers[0], numbers.get(1).copied().unwrap_or(0.0)],
                    _ => notes.push(format!("map_Kd option {option} ignored")),
                }
                i += n;
            }
            "-clamp" | "-blendu" | "-blendv" | "-cc" | "-imfchan" | "-bm" | "-boost" | "-texres" => {
                let Some(&value) = words.get(i) else {
                    return Err(format!("option {option} needs a value"));
                };
                match (option, value) {
                    ("-clamp", "on") => wrap = Wrap::Clamp,
                    ("-clamp", "off") => {}
                    ("-clamp", _) => return Err(format!("-clamp {value}: expected on or off")),
                    _ => notes.push(format!("map_Kd option {option} {value} ignored")),
                }
                i += 1;
            }
            _ => return Err(format!("unknown option {option}")),
        }
    }
    let file = words[i..].join(" ");
    if file.is_empty() {
        return Err("no image file after the options".into());
    }
    // Exporters on Windows write backslashes.
    let path = Path::new(mtl)
        .parent()
        .unwrap_or(Path::new(""))
        .join(file.replace('\\', "/"));
    // The OBJ's v runs up the image and is stored flipped (v' = 1 - v): its scale and offset, applied
    // before the flip, become v' -> 1 - (s (1 - v') + o) after it.
    let to_uv = [scale[0], 0.0, offset[0], 0.0, scale[1], 1.0 - scale[1] - offset[1]];
    let shown = path.display().to_string();
    let mut t =
        Texture::bitmap(&path, &shown, false, Filter::Bilinear, wrap, to_uv).map_err(|e| format!("{shown}: {e}"))?;
    if let (Some(kd), texture::Pattern::Bitmap { pixels, .. }) = (kd, &mut t.pattern) {
        pixels.iter_mut().for_each(|p| *p *= kd);
    }
    if let Some(bad) = t.out_of_range() {
        return Err(format!("{shown}: {bad}: a diffuse reflectance must be in [0, 1]"));
    }
    Ok((t, notes))
}

// tobj's numbers are f32, or f64 where a crate turns on its `use_f64`: taken either way.
fn f32x1<T: Into<f64>>(x: T) -> f32 {
    x.into() as f32
}

fn f32x3<T: Into<f64>>(v: Option<[T; 3]>) -> Option<[f32; 3]> {
    v.map(|a| a.map(f32x1))
}

/// The least GGX alpha an MTL mirror's roughness makes rough: below it (Ns above 937) the lobe is
/// narrower than the image resolves, and the mirror stays a mirror.
const MTL_MIN_ALPHA: f32 = 1e-3;

/// An MTL material as an engine material, with notes on what it approximates (the table in
/// docs/scene-format.md). `mtl` names the file in errors.
fn convert(m: &tobj::Material, name: String, mtl: &str) -> Result<(Material, Vec<String>)> {
    let fail = |msg: String| anyhow!("{mtl}: material \"{}\": {msg}", m.name);
    let color = |v: Option<[f32; 3]>, key: &str, unit: bool| -> Result<Option<Vec3>> {
        let Some(a) = v else { return Ok(None) };
        let v = Vec3::from_array(a);
        if v.is_finite() && v.cmpge(Vec3::ZERO).all() && (!unit || v.cmple(Vec3::ONE).all()) {
            Ok(Some(v))
        } else {
            let range = if unit { "in [0, 1]" } else { "finite and >= 0" };
            Err(fail(format!("{key} must be {range}, got {}", fmt_vec(a))))
        }
    };
    let kd = color(f32x3(m.diffuse), "Kd", true)?;
    let ks = color(f32x3(m.specular), "Ks", true)?;
    let ke = color(f32x3(m.emissive), "Ke", false)?;
    let number = |v: Option<f32>, key: &str| -> Result<Option<f32>> {
        match v {
            Some(x) if !x.is_finite() => Err(fail(format!("{key} must be finite, got {x}"))),
            _ => Ok(v),
        }
    };
    let d = number(m.dissolve.map(f32x1), "d")?;
    let ni = number(m.optical_density.map(f32x1), "Ni")?;
    // A key tobj does not know (Tr, Pr): its first number, where `valid` takes it, else `message`.
    let unknown_number = |key: &str, valid: fn(f32) -> bool, message: &str| -> Result<Option<f32>> {
        match m.unknown_param.get(key) {
            None => Ok(None),
            Some(s) => s
                .split_whitespace()
                .next()
                .and_then(|x| x.parse::<f32>().ok())
                .filter(|&x| valid(x))
                .map(Some)
                .ok_or_else(|| fail(format!("{message}, got {s:?}"))),
        }
    };
    let tr = unknown_number("Tr", f32::is_finite, "Tr needs a number")?;
    let illum = m.illumination_model;
    let nonzero = |v: Option<Vec3>| v.is_some_and(|v| v.max_element() > 0.0);
    let mut notes = Vec::new();

    let transparent = d.is_some_and(|d| d < 1.0) || tr.is_some_and(|t| t > 0.0);
    let glass = matches!(illum, Some(4 | 6 | 7 | 9)) || transparent;
    let mirror = !glass && (matches!(illum, Some(3 | 5 | 8)) || (nonzero(ks) && !nonzero(kd)));
    let surface = if glass {
        let ior = ni.unwrap_or(DEFAULT_IOR);
        if ior < 1.0 {
            return Err(fail(format!(
                "Ni (index of refraction) must be >= 1 for glass, got {ior}"
            )));
        }
        if d.is_some_and(|d| d > 0.0 && d < 1.0) || tr.is_some_and(|t| t > 0.0 && t < 1.0) {
            notes.push("partial transparency (d or Tr) rendered as clear glass".to_string());
        }
        if nonzero(kd) {
            notes.push("Kd ignored: glass is clear".into());
        }
        if let Some(tf) = m.unknown_param.get("Tf") {
            if numbers::<3>(&tf.split_whitespace().collect::<Vec<_>>()) != Some([1.0; 3]) {
                notes.push("Tf ignored: glass is clear".into());
            }
        }
        Surface::Glass { ior }
    } else if mirror {
        if nonzero(kd) {
            notes.push("Kd ignored: a mirror reflects Ks only".into());
        }
        let reflectance = ks.unwrap_or_else(|| {
            notes.push("no Ks: mirror reflectance 1 assumed".into());
            Vec3::ONE
        });
        // Roughness: the PBR extension's Pr, else Ns read as Blender's exporter writes it
        // (Ns = 1000 (1 - roughness)^2), and GGX alpha = roughness^2 as Blender's shaders use it.
        let pr = unknown_number(
            "Pr",
            |x| (0.0..=1.0).contains(&x),
            "Pr (roughness) must be a number in [0, 1]",
        )?;
        let ns = number(m.shininess.map(f32x1), "Ns")?;
        let roughness = pr.or(ns.map(|ns| 1.0 - (ns.clamp(0.0, 1000.0) / 1000.0).sqrt()));
        match roughness.map(|r| r * r).filter(|&a| a >= MTL_MIN_ALPHA) {
            Some(alpha) => {
                let (eta, k) = super::conductors::named("none").expect("the default conductor");
                Surface::RoughConductor {
                    reflectance,
                    eta,
                    k,
                    rough: super::Microfacet::isotropic(true, alpha),
                }
            }
            None => Surface::Mirror { reflectance },
        }
    } else {
        if nonzero(ks) && !matches!(illum, Some(0 | 1)) {
            notes.push("Ks/Ns glossy lobe ignored (diffuse Kd only)".into());
        }
        Surface::Diffuse {
            albedo: match kd {
                Some(k) => k,
                // An emitter without Kd is a black emitter, as in the TOML.
                None if nonzero(ke) => Vec3::ZERO,
                None => {
                    notes.push(format!("no Kd: diffuse albedo {DEFAULT_KD} assumed"));
                    Vec3::splat(DEFAULT_KD)
                }
            },
        }
    };
    let diffuse = matches!(surface, Surface::Diffuse { .. });
    if nonzero(ke) && !diffuse {
        notes.push("Ke ignored: only diffuse surfaces emit".into());
    }
    if let (false, Some(t)) = (diffuse, &m.diffuse_texture) {
        notes.push(format!("map_Kd {t} ignored (only a diffuse material reads it)"));
    }
    for (key, tex) in [
        ("map_Ka", &m.ambient_texture),
        ("map_Ks", &m.specular_texture),
        ("map_Ns", &m.shininess_texture),
        ("map_d", &m.dissolve_texture),
        ("bump map", &m.normal_texture),
    ] {
        if let Some(t) = tex {
            notes.push(format!("{key} {t} ignored (only map_Kd is read)"));
        }
    }
    // Other statements (PBR extensions, map_Ke, disp, refl, ...), in a stable order.
    let mut other: Vec<&String> = m
        .unknown_param
        .keys()
        .filter(|k| !matches!(k.as_str(), "Tr" | "Tf"))
        .collect();
    other.sort();
    for k in other {
        notes.push(format!("{k} ignored"));
    }
    let emission = match (diffuse, ke) {
        (true, Some(e)) => e,
        _ => Vec3::ZERO,
    };
    Ok((
        Material {
            name,
            surface,
            emission,
            texture: None,
            normal_map: None,
            opacity: None,
            specular_texture: None,
            alpha_texture: None,
            emission_texture: None,
        },
        notes,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Camera, TempDir};
    use glam::{DMat3, DVec3};

    /// A scene with a camera and one material ("white"), nothing else.
    fn scene() -> Scene {
        Scene {
            name: "t".into(),
            camera: Camera {
                eye: Vec3::new(0.0, 0.0, 5.0),
                look_at: Vec3::ZERO,
                up: Vec3::Y,
                vfov_deg: 40.0,
                width: 8,
                height: 8,
            },
            materials: vec![Material {
                name: "white".into(),
                surface: Surface::Diffuse {
                    albedo: Vec3::splat(0.5),
                },
                emission: Vec3::ZERO,
                texture: None,
                normal_map: None,
                opacity: None,
                specular_texture: None,
                alpha_texture: None,
                emission_texture: None,
            }],
            spheres: vec![],
            quads: vec![],
            meshes: vec![],
            textures: vec![],
            regions: vec![],
            emitters: Vec::new(),
            warnings: vec![],
        }
    }

    /// Writes `a.obj` (and `a.mtl`) into `dir` and imports it into [`scene`].
    fn import_into(dir: &TempDir, obj: &str, mtl: Option<&str>, opts: &ObjImport) -> Result<Scene> {
        if let Some(m) = mtl {
            dir.write("a.mtl", m);
        }
        let path = dir.write("a.obj", obj);
        let mut s = scene();
        s.import_obj(&path, opts)?;
        Ok(s)
    }

    /// The error of importing, with the temp dir's path cut out of it.
    fn err(obj: &str, mtl: Option<&str>) -> String {
        let dir = TempDir::new("obj-err");
        match import_into(&dir, obj, mtl, &ObjImport::default()) {
            Ok(s) => panic!("expected an error for\n{obj}\ngot {:?}", s.meshes),
            Err(e) => format!("{e:#}").replace(&format!("{}/", dir.0.display()), ""),
        }
    }

    const TRI: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    const MTL: &str = "newmtl m\nKd 0.5 0.5 0.5\n";

    #[test]
    fn mtl_materials_follow_the_mapping_table() {
        let mtl = "\
newmtl matte\nKd 0.5 0.6 0.7\n\
newmtl lamp\nKd 0.2 0.2 0.2\nKe 5 4 3\n\
newmtl blacklamp\nKe 1 1 1\n\
newmtl mirror3\nKd 0.3 0.3 0.3\nKs 0.9 0.8 0.7\nillum 3\n\
newmtl chrome\nKs 0.6 0.6 0.6\n\
newmtl water\nNi 1.33\nillum 7\n\
newmtl clear\nd 0.5\n\
newmtl tr\nTr 1\nNi 1.6\n\
newmtl glossy\nKd 0.4 0.4 0.4\nKs 0.5 0.5 0.5\nNs 100\nillum 2\nmap_Kd wood.png\n\
newmtl plain\nNs 10\n";
        let names = [
            "matte",
            "lamp",
            "blacklamp",
            "mirror3",
            "chrome",
            "water",
            "clear",
            "tr",
            "glossy",
            "plain",
        ];
        let mut obj = format!("mtllib a.mtl\n{TRI}");
        for n in names {
            obj += &format!("usemtl {n}\nf 1 2 3\n");
        }
        let dir = TempDir::new("obj-mtl");
        let s = import_into(&dir, &obj, Some(mtl), &ObjImport::default()).expect("loads");
        let m = &s.meshes[0];
        assert_eq!(m.indices.len(), names.len());
        let got = |i: usize| {
            let k = &s.materials[m.materials[i] as usize];
            assert_eq!(k.name, format!("{}:{}", dir.0.join("a.obj").display(), names[i]));
            (k.surface, k.emission)
        };
        let d = |r: f32, g: f32, b: f32| Surface::Diffuse {
            albedo: Vec3::new(r, g, b),
        };
        let z = Vec3::ZERO;
        assert_eq!(got(0), (d(0.5, 0.6, 0.7), z));
        assert_eq!(got(1), (d(0.2, 0.2, 0.2), Vec3::new(5.0, 4.0, 3.0)));
        assert_eq!(got(2), (d(0.0, 0.0, 0.0), Vec3::ONE), "a black emitter");
        assert_eq!(
            got(3),
            (
                Surface::Mirror {
                    reflectance: Vec3::new(0.9, 0.8, 0.7)
                },
                z
            )
        );
        assert_eq!(
            got(4),
            (
                Surface::Mirror {
                    reflectance: Vec3::splat(0.6)
                },
                z
            )
        );
        assert_eq!(got(5), (Surface::Glass { ior: 1.33 }, z));
        assert_eq!(got(6), (Surface::Glass { ior: 1.5 }, z), "d < 1 without Ni");
        assert_eq!(got(7), (Surface::Glass { ior: 1.6 }, z), "Tr > 0");
        assert_eq!(got(8), (d(0.4, 0.4, 0.4), z));
        assert_eq!(got(9), (d(0.8, 0.8, 0.8), z));
        // One warning per approximated material, naming it and the MTL.
        let w = &s.warnings;
        assert_eq!(w.len(), 4, "{w:#?}");
        let about = |name: &str| -> &String {
            let tag = format!("material \"{name}\" (");
            let found: Vec<&String> = w.iter().filter(|x| x.contains(&tag)).collect();
            assert_eq!(found.len(), 1, "{name}: {w:#?}");
            assert!(found[0].contains("a.mtl"), "{}", found[0]);
            found[0]
        };
        assert!(about("mirror3").contains("Kd ignored"));
        assert!(about("clear").contains("partial transparency"));
        let glossy = about("glossy");
        assert!(
            glossy.contains("Ks/Ns glossy lobe ignored") && glossy.contains("map_Kd wood.png ignored"),
            "{glossy}"
        );
        assert!(about("plain").contains("no Kd: diffuse albedo 0.8"));

        // A mirror's roughness: Pr, else Ns as Blender writes it; GGX alpha = roughness^2.
        let mtl = "newmtl a\nKs 1 1 1\nNs 250\nillum 3\nnewmtl b\nKs 0.9 0.9 0.9\nPr 0.3\nNs 5\n\
                   newmtl c\nKs 1 1 1\nNs 1000\nillum 3\nnewmtl d\nKs 1 1 1\nPr 2\n";
        let obj = format!("mtllib a.mtl\n{TRI}usemtl a\nf 1 2 3\nusemtl b\nf 1 2 3\nusemtl c\nf 1 2 3\n");
        let rdir = TempDir::new("obj-rough");
        let r = import_into(
            &rdir,
            &obj,
            Some(&mtl.replace("newmtl d\nKs 1 1 1\nPr 2\n", "")),
            &ObjImport::default(),
        )
        .expect("loads");
        let rough = |i: usize| r.materials[r.meshes[0].materials[i] as usize].surface;
        let (eta, k) = crate::conductors::named("none").unwrap();
        let rc = |reflectance: f32, alpha: f32| Surface::RoughConductor {
            reflectance: Vec3::splat(reflectance),
            eta,
            k,
            rough: crate::Microfacet::isotropic(true, alpha),
        };
        assert_eq!(rough(0), rc(1.0, 0.25), "Ns 250: roughness 0.5");
        assert!(
            matches!(rough(1), Surface::RoughConductor { rough, .. } if (rough.alpha - 0.09).abs() < 1e-6),
            "Pr 0.3"
        );
        assert_eq!(rough(2), Surface::Mirror { reflectance: Vec3::ONE }, "Ns 1000: smooth");
        let e = err(&format!("mtllib a.mtl\n{TRI}usemtl d\nf 1 2 3\n"), Some(mtl));
        assert!(
            e.contains("Pr (roughness) must be a number in [0, 1]") && e.contains("a.mtl"),
            "{e}"
        );

        // The same file again: its materials (and their warnings) are not repeated.
        let mut again = s.clone();
        again
            .import_obj(dir.0.join("a.obj"), &ObjImport::default())
            .expect("again");
        assert_eq!(again.materials.len(), s.materials.len());
        assert_eq!(again.warnings, s.warnings);
        assert_eq!(again.meshes[1].materials, s.meshes[0].materials);
    }

    #[test]
    fn polygons_are_fanned_counter_clockwise() {
        let obj = "mtllib a.mtl\nusemtl m\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv -1 0.5 0\n\
                   f 1 2 3 4\nf 1 2 3 4 5\n";
        let dir = TempDir::new("obj-fan");
        let s = import_into(&dir, obj, Some(MTL), &ObjImport::default()).expect("loads");
        let m = &s.meshes[0];
        assert_eq!(m.indices.len(), 2 + 3);
        for t in m.triangles() {
            assert_eq!(t.normal(), Vec3::Z, "counter-clockwise seen from +z");
        }
        let area: f32 = m.triangles().take(2).map(|t| t.area()).sum();
        assert!((area - 1.0).abs() < 1e-6);
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    }

    #[test]
    fn transform_places_the_mesh_and_mirroring_keeps_the_front() {
        let obj = format!("mtllib a.mtl\nusemtl m\n{TRI}vn 0 0 1\nf 1//1 2//1 3//1\n");
        let dir = TempDir::new("obj-xf");
        let moved = ObjImport {
            transform: DAffine3::from_mat3_translation(
                DMat3::from_diagonal(DVec3::new(2.0, 3.0, 4.0)),
                DVec3::new(1.0, 0.0, -1.0),
            ),
            material: None,
        };
        let s = import_into(&dir, &obj, Some(MTL), &moved).expect("loads");
        let t = s.meshes[0].triangle(0);
        assert_eq!(
            t.p,
            [
                Vec3::new(1.0, 0.0, -1.0),
                Vec3::new(3.0, 0.0, -1.0),
                Vec3::new(1.0, 3.0, -1.0)
            ]
        );
        assert_eq!(t.normal(), Vec3::Z);
        // A mirror in x: positions reflected, winding reversed so that the front stays +z, and the
        // shading normal (inverse transpose) agrees with it.
        let mirror = ObjImport {
            transform: DAffine3::from_mat3(DMat3::from_diagonal(DVec3::new(-1.0, 1.0, 1.0))),
            material: None,
        };
        let s = import_into(&dir, &obj, Some(MTL), &mirror).expect("loads");
        let m = &s.meshes[0];
        assert!(m.positions.contains(&Vec3::new(-1.0, 0.0, 0.0)));
        assert_eq!(m.triangle(0).normal(), Vec3::Z);
        assert_eq!(m.normals.as_deref(), Some(&[Vec3::Z; 3][..]));
    }

    #[test]
    fn material_override_needs_no_mtl() {
        let obj = format!("mtllib nowhere.mtl\nusemtl x\n{TRI}f 1 2 3\n");
        let dir = TempDir::new("obj-override");
        let opts = ObjImport {
            material: Some(0),
            ..ObjImport::default()
        };
        let s = import_into(&dir, &obj, None, &opts).expect("the MTL is not read");
        assert_eq!(s.meshes[0].materials, [0]);
        assert_eq!(s.materials.len(), 1, "no MTL material added");
        // Without an MTL nor an override: refused.
        let e = err(&format!("{TRI}f 1 2 3\n"), None);
        assert!(e.starts_with("a.obj: no materials: the OBJ names no MTL file"), "{e}");
    }

    #[test]
    fn degenerate_triangles_are_dropped_and_counted() {
        let obj = "mtllib a.mtl\nusemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nv 5 5 5\n\
                   f 1 2 3\nf 1 1 2\nf 1 2 4\n";
        let dir = TempDir::new("obj-degen");
        let s = import_into(&dir, obj, Some(MTL), &ObjImport::default()).expect("loads");
        let m = &s.meshes[0];
        assert_eq!(m.indices, [[0, 1, 2]]);
        assert_eq!(m.positions.len(), 3, "unused vertices dropped");
        assert_eq!(s.warnings.len(), 1);
        assert!(
            s.warnings[0].ends_with("a.obj: 2 degenerate triangles dropped (zero area or a repeated vertex)"),
            "{:?}",
            s.warnings
        );
        // All degenerate: an empty mesh, refused.
        let e = err(
            "mtllib a.mtl\nusemtl m\nv 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 3 3 1\n",
            Some(MTL),
        );
        assert!(e.contains("a.obj: every one of its 2 triangles is degenerate"), "{e}");
    }

    #[test]
    fn normals_are_kept_only_when_every_vertex_has_one() {
        let dir = TempDir::new("obj-normals");
        let obj = format!("mtllib a.mtl\nusemtl m\n{TRI}vn 0 0 2\nf 1//1 2//1 3//1\n");
        let s = import_into(&dir, &obj, Some(MTL), &ObjImport::default()).expect("loads");
        assert_eq!(s.meshes[0].normals.as_deref(), Some(&[Vec3::Z; 3][..]), "unit length");
        let obj = format!("mtllib a.mtl\nusemtl m\n{TRI}v 1 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\nf 2 4 3\n");
        let s = import_into(&dir, &obj, Some(MTL), &ObjImport::default()).expect("loads");
        assert_eq!(s.meshes[0].normals, None);
        assert!(
            s.warnings[0].contains("vertex normals dropped (flat shading): only some"),
            "{:?}",
            s.warnings
        );
        let obj = format!("mtllib a.mtl\nusemtl m\n{TRI}vn 0 0 0\nf 1//1 2//1 3//1\n");
        let s = import_into(&dir, &obj, Some(MTL), &ObjImport::default()).expect("loads");
        assert_eq!(s.meshes[0].normals, None);
        assert!(s.warnings[0].contains("normal 0 is zero"), "{:?}", s.warnings);
    }

    #[test]
    fn objects_without_faces_are_ignored() {
        // A trailing `o` and `usemtl` with no face after them: tobj still makes a (faceless) model.
        let mtl = "newmtl m\nKd 0.5 0.5 0.5\nnewmtl unused\nKd 0.1 0.1 0.1\n";
        let obj = format!("mtllib a.mtl\nusemtl m\n{TRI}f 1 2 3\no empty\nusemtl unused\n");
        let dir = TempDir::new("obj-empty-object");
        let s = import_into(&dir, &obj, Some(mtl), &ObjImport::default()).expect("loads");
        assert_eq!(s.meshes[0].indices.len(), 1);
        assert_eq!(s.materials.len(), 2, "white and m only: {:?}", s.materials);
        let s = import_into(
            &dir,
            &format!("mtllib a.mtl\nusemtl m\n{TRI}f 1 2 3\no tail\n"),
            Some(mtl),
            &ObjImport::default(),
        )
        .expect("loads");
        assert_eq!(s.meshes[0].indices.len(), 1);
    }

    #[test]
    fn points_and_lines_are_skipped_with_a_warning() {
        let obj = format!("mtllib a.mtl\nusemtl m\n{TRI}f 1 2 3\nf 1\nl 1 2\n");
        let dir = TempDir::new("obj-lines");
        let s = import_into(&dir, &obj, Some(MTL), &ObjImport::default()).expect("loads");
        assert_eq!(s.meshes[0].indices.len(), 1);
        assert!(
            s.warnings
                .iter()
                .any(|w| w.ends_with("2 point and line elements ignored (only faces are surfaces)")),
            "{:?}",
            s.warnings
        );
    }

    #[test]
    fn bad_obj_lines_are_named_by_line() {
        let head = "mtllib a.mtl\nusemtl m\n";
        let cases: &[(&str, &str)] = &[
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n",
                "a.obj:6: vertex index 4 out of range (3 in the file)",
            ),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
                "a.obj:6: vertex index 0 in \"0\": OBJ indices start at 1",
            ),
            (
                "v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n",
                "a.obj:5: vertex index -3 out of range (2 before this line)",
            ),
            (
                "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n",
                "a.obj:4: vertex 2 is not finite: \"v nan 0 0\"",
            ),
            (
                "v 0 0 0\nv 1 inf 0\nv 0 1 0\nf 1 2 3\n",
                "a.obj:4: vertex 2 is not finite",
            ),
            (
                "v 0 0 0\nv 1 1e39 0\nv 0 1 0\nf 1 2 3\n",
                "a.obj:4: vertex 2 is not finite",
            ),
            (
                "v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n",
                "a.obj:4: vertex 2 needs three numbers x y z",
            ),
            ("v 0 0 0 0\n", "a.obj:3: vertex 1: w must be a non-zero number"),
            (
                "v 0 0 0 1 2\n",
                "a.obj:3: vertex 1: expected x y z with an optional w or r g b, got 5",
            ),
            ("vn 0 0\n", "a.obj:3: normal needs three numbers"),
            ("vt x 0\n", "a.obj:3: texture coordinate needs two numbers"),
            (
                &format!("{TRI}vn 0 0 1\nf 1//1 2//1 3//2\n"),
                "a.obj:7: normal index 2 out of range (1 in the file)",
            ),
            (&format!("{TRI}f 1 2 x\n"), "a.obj:6: bad face vertex \"x\""),
            (&format!("{TRI}f 1 2 3/1/1/1\n"), "a.obj:6: bad face vertex"),
            (
                &format!("{TRI}f 1 2 /1\n"),
                "a.obj:6: face vertex \"/1\" has no position index",
            ),
            (
                &format!("{TRI}l 1 2 3\n"),
                "a.obj:6: polylines (l) of 3 or more points are not supported",
            ),
            (&format!("{TRI}f\n"), "a.obj:6: `f` without vertices"),
            (TRI, "a.obj: no faces: the mesh is empty"),
            (
                &format!("{TRI}usemtl nope\nf 1 2 3\n"),
                "a.obj:6: usemtl nope: no such material in a.mtl",
            ),
        ];
        for (body, needle) in cases {
            let e = err(&format!("{head}{body}"), Some(MTL));
            assert!(e.starts_with(needle), "{e:?} should start with {needle:?}");
        }
        let e = err(&format!("mtllib a.mtl\n{TRI}f 1 2 3\nusemtl m\nf 1 2 3\n"), Some(MTL));
        assert!(
            e.starts_with("a.obj:5: face without a material (no usemtl before it)"),
            "{e}"
        );
    }

    #[test]
    fn bad_mtl_files_are_named() {
        let obj = format!("\nmtllib a.mtl\nusemtl m\n{TRI}f 1 2 3\n");
        let cases: &[(&str, &str)] = &[
            (
                "newmtl m\nKd 0.5\n",
                "a.mtl:2: Kd needs three numbers r g b: \"Kd 0.5\"",
            ),
            ("newmtl m\nKe 1 x 1\n", "a.mtl:2: Ke needs three numbers"),
            ("newmtl m\nNi\n", "a.mtl:2: Ni needs a number"),
            ("newmtl m\nillum 300\n", "a.mtl:2: illum needs a model number"),
            ("newmtl\n", "a.mtl:1: newmtl needs a name"),
            ("newmtl m\nmap_Kd\n", "a.mtl:2: map_Kd needs a file name"),
            (
                "newmtl m\nKd 0.5 1.5 0.5\n",
                "a.mtl: material \"m\": Kd must be in [0, 1], got [0.5, 1.5, 0.5]",
            ),
            (
                "newmtl m\nKs 0.5 -1 0.5\n",
                "a.mtl: material \"m\": Ks must be in [0, 1]",
            ),
            (
                "newmtl m\nKe nan 1 1\n",
                "a.mtl: material \"m\": Ke must be finite and >= 0, got [NaN, 1, 1]",
            ),
            (
                "newmtl m\nillum 7\nNi 0.5\n",
                "a.mtl: material \"m\": Ni (index of refraction) must be >= 1 for glass, got 0.5",
            ),
            ("newmtl m\nTr lots\n", "a.mtl: material \"m\": Tr needs a number"),
        ];
        for (mtl, needle) in cases {
            let e = err(&obj, Some(mtl));
            assert!(e.starts_with(needle), "{e:?} should start with {needle:?}");
        }
        let e = err(&obj.replace("a.mtl", "gone.mtl"), Some(MTL));
        assert!(
            e.starts_with("gone.mtl: cannot read MTL file (mtllib at a.obj:2): "),
            "{e}"
        );
    }

    #[test]
    fn missing_obj_and_too_many_triangles() {
        let dir = TempDir::new("obj-missing");
        let mut s = scene();
        let e = format!(
            "{:#}",
            s.import_obj(dir.0.join("none.obj"), &ObjImport::default()).unwrap_err()
        );
        assert!(
            e.contains("none.obj: cannot read OBJ file: ") && !e.contains("gen_scenes"),
            "{e}"
        );
        let e = format!(
            "{:#}",
            s.import_obj(dir.0.join("water.obj"), &ObjImport::default())
                .unwrap_err()
        );
        assert!(e.contains(generated::COMMAND), "a generated file's hint: {e}");
        // The limit, scaled down: three triangles against a limit of two.
        let path = dir.write("a.obj", &format!("{TRI}v 1 1 0\nf 1 2 3\nf 2 4 3\nf 1 2 4\n"));
        let opts = ObjImport {
            material: Some(0),
            ..ObjImport::default()
        };
        let e = format!("{:#}", import(&mut s, &path, &opts, 2, true).unwrap_err());
        assert!(
            e.ends_with("a.obj:7: more than 2 triangles: the limit (MAX_TRIANGLES) is reached here"),
            "{e}"
        );
        import(&mut s, &path, &opts, 3, true).expect("three is within a limit of three");
        assert!(s.meshes.len() == 1 && s.warnings.is_empty());
    }

    #[test]
    fn a_name_taken_by_another_material_is_refused() {
        let dir = TempDir::new("obj-clash");
        let obj = format!("mtllib a.mtl\nusemtl m\n{TRI}f 1 2 3\n");
        dir.write("a.mtl", MTL);
        let path = dir.write("a.obj", &obj);
        let mut s = scene();
        s.materials[0].name = format!("{}:m", path.display());
        s.materials[0].surface = Surface::Glass { ior: 1.5 };
        let e = format!("{:#}", s.import_obj(&path, &ObjImport::default()).unwrap_err());
        assert!(e.contains("is already taken by a different material"), "{e}");
    }

    /// The texture coordinate of each vertex of `m`, by its position.
    fn uv_by_position(m: &Mesh) -> Vec<([f32; 3], [f32; 2])> {
        let uvs = m.uvs.as_ref().expect("texture coordinates");
        let mut v: Vec<([f32; 3], [f32; 2])> = m
            .positions
            .iter()
            .zip(uvs)
            .map(|(p, t)| (p.to_array(), t.to_array()))
            .collect();
        v.sort_by(|a, b| a.partial_cmp(b).unwrap());
        v
    }

    #[test]
    fn texture_coordinates_are_flipped_and_follow_their_vertices() {
        let dir = TempDir::new("obj-uv");
        // Vertex 1 unused, the second face degenerate (collinear): both go, and the coordinates stay with
        // the vertices kept. v is flipped (v' = 1 - v): Mitsuba's convention.
        let obj = "mtllib a.mtl\nusemtl m\nv 5 5 5\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\n\
                   vt 0 0\nvt 0.25 0.5\nvt 1 0\nvt 0 1\nvt 0.5 0.5\nf 2/2 3/3 4/4\nf 2/2 3/3 5/5\n";
        let s = import_into(&dir, obj, Some(MTL), &ObjImport::default()).expect("loads");
        let m = &s.meshes[0];
        assert_eq!(m.indices.len(), 1);
        assert_eq!(
            uv_by_position(m),
            [
                ([0.0, 0.0, 0.0], [0.25, 0.5]),
                ([0.0, 1.0, 0.0], [0.0, 0.0]),
                ([1.0, 0.0, 0.0], [1.0, 1.0])
            ]
        );
        // Without the flip (Mitsuba's flip_tex_coords="false"), through a mirroring transform (which turns
        // the winding, not the coordinates).
        let path = dir.0.join("a.obj");
        let mut t = scene();
        let mirror = ObjImport {
            transform: DAffine3::from_mat3(DMat3::from_diagonal(DVec3::new(-1.0, 1.0, 1.0))),
            material: None,
        };
        import(&mut t, &path, &mirror, 100, false).expect("loads");
        assert_eq!(
            uv_by_position(&t.meshes[0]),
            [
                ([-1.0, 0.0, 0.0], [1.0, 0.0]),
                ([0.0, 0.0, 0.0], [0.25, 0.5]),
                ([0.0, 1.0, 0.0], [0.0, 1.0])
            ]
        );
        // One position with two texture coordinates (a seam) is two vertices.
        let seam = format!(
            "mtllib a.mtl\nusemtl m\n{TRI}v 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\nf 1/1 2/2 3/3\nf 2/4 4/4 3/1\n"
        );
        let s = import_into(&dir, &seam, Some(MTL), &ObjImport::default()).expect("loads");
        let m = &s.meshes[0];
        assert_eq!((m.positions.len(), m.uvs.as_ref().map(Vec::len)), (6, Some(6)));
        // Only some corners with a vt, or one not finite: none kept (the latter with a warning).
        let some = format!("mtllib a.mtl\nusemtl m\n{TRI}v 1 1 0\nvt 0 0\nf 1/1 2/1 3/1\nf 2 4 3\n");
        let s = import_into(&dir, &some, Some(MTL), &ObjImport::default()).expect("loads");
        assert_eq!(s.meshes[0].uvs, None);
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        let nan = format!("mtllib a.mtl\nusemtl m\n{TRI}vt 0 0\nvt nan 0\nf 1/1 2/2 3/1\n");
        let s = import_into(&dir, &nan, Some(MTL), &ObjImport::default()).expect("loads");
        assert_eq!(s.meshes[0].uvs, None);
        assert!(
            s.warnings.len() == 1 && s.warnings[0].contains("texture coordinates dropped: coordinate 1 is not finite"),
            "{:?}",
            s.warnings
        );
    }

    #[test]
    fn mtl_map_kd_is_a_texture_on_a_diffuse_material() {
        let dir = TempDir::new("obj-map-kd");
        std::fs::create_dir_all(dir.0.join("mats/tex")).unwrap();
        // 2 x 1: white, then sRGB (128, 64, 0).
        texture::write_png(&dir.0.join("mats/tex/w.png"), 2, 1, &[255, 255, 255, 128, 64, 0]);
        dir.write(
            "mats/a.mtl",
            "newmtl wood\nKd 0.5 0.5 0.5\nmap_Kd -s 2 2 1 -o 0.25 0.5 tex\\w.png\n\
             newmtl bare\nmap_Kd -clamp on tex/w.png\n\
             newmtl gone\nKd 0.3 0.3 0.3\nmap_Kd missing.png\n\
             newmtl shiny\nKs 1 1 1\nillum 3\nmap_Kd tex/w.png\n\
             newmtl odd\nKd 1 1 1\nmap_Kd -bm 0.5 tex/w.png\n",
        );
        let names = ["wood", "bare", "gone", "shiny", "odd"];
        let mut obj = format!("mtllib mats/a.mtl\n{TRI}vt 0 0\nvt 1 0\nvt 0 1\n");
        for n in names {
            obj += &format!("usemtl {n}\nf 1/1 2/2 3/3\n");
        }
        let path = dir.write("a.obj", &obj);
        let mut s = scene();
        s.import_obj(&path, &ObjImport::default())
            .unwrap_or_else(|e| panic!("{e:#}"));
        let m = &s.meshes[0];
        assert!(m.uvs.is_some());
        let material = |i: usize| &s.materials[m.materials[i] as usize];
        let texture = |i: usize| &s.textures[material(i).texture.expect("textured") as usize];
        let dark = Vec3::new(
            texture::srgb_to_linear(128.0 / 255.0),
            texture::srgb_to_linear(64.0 / 255.0),
            0.0,
        );
        // Kd multiplies the image; -s and -o scale and offset the OBJ's (unflipped) coordinates.
        let wood = texture(0);
        assert_eq!(
            wood.pattern,
            texture::Pattern::Bitmap {
                width: 2,
                height: 1,
                pixels: vec![Vec3::splat(0.5), dark * 0.5]
            }
        );
        assert_eq!((wood.filter, wood.wrap), (Filter::Bilinear, Wrap::Repeat));
        assert_eq!(wood.to_uv, [2.0, 0.0, 0.25, 0.0, 2.0, -1.5]);
        assert_eq!(
            material(0).surface,
            Surface::Diffuse {
                albedo: Vec3::splat(0.5)
            }
        );
        // The OBJ's (u, v) = (0.1, 0.2) is stored as (0.1, 0.8); through to_uv it is the image's
        // (2 u + 0.25, 1 - (2 v + 0.5)) = (0.45, 0.1), v from the top.
        let (u, v) = (0.1f32, 0.8f32);
        let t = wood.to_uv;
        let looked_up = (t[0] * u + t[1] * v + t[2], t[3] * u + t[4] * v + t[5]);
        assert!(
            (looked_up.0 - 0.45).abs() < 1e-6 && (looked_up.1 - 0.1).abs() < 1e-6,
            "{looked_up:?}"
        );
        let bare = texture(1);
        assert_eq!((bare.wrap, bare.to_uv), (Wrap::Clamp, texture::IDENTITY_UV));
        assert_eq!(material(1).surface, Surface::Diffuse { albedo: Vec3::ONE });
        assert_eq!(material(2).texture, None);
        assert_eq!(
            material(2).surface,
            Surface::Diffuse {
                albedo: Vec3::splat(0.3)
            }
        );
        assert_eq!(material(3).texture, None);
        assert_eq!(texture(4).wrap, Wrap::Repeat);
        assert_eq!(s.textures.len(), 3);
        let notes = |name: &str| {
            s.warnings
                .iter()
                .find(|w| w.contains(&format!("material \"{name}\"")))
                .cloned()
                .unwrap_or_default()
        };
        assert!(
            notes("gone").contains("map_Kd missing.png ignored (") && notes("gone").contains("the constant Kd is used"),
            "{:?}",
            s.warnings
        );
        assert!(
            notes("shiny").contains("map_Kd tex/w.png ignored (only a diffuse material reads it)"),
            "{:?}",
            s.warnings
        );
        assert!(
            notes("odd").contains("map_Kd option -bm 0.5 ignored"),
            "{:?}",
            s.warnings
        );
        assert!(notes("wood").is_empty() && notes("bare").is_empty(), "{:?}", s.warnings);
        s.validate().unwrap_err(); // no light: everything else is valid
        let e = format!("{:#}", s.validate().unwrap_err());
        assert!(e.contains("no light: nothing to render"), "{e}");
        // Imported again: the same textures and materials.
        let (textures, materials) = (s.textures.len(), s.materials.len());
        s.import_obj(&path, &ObjImport::default()).unwrap();
        assert_eq!((s.textures.len(), s.materials.len()), (textures, materials));
        assert_eq!(s.meshes[1].materials, s.meshes[0].materials);
        // Without texture coordinates the map cannot be read: Kd alone, with a warning.
        let path = dir.write("b.obj", &format!("mtllib mats/a.mtl\n{TRI}usemtl wood\nf 1 2 3\n"));
        let mut s = scene();
        s.import_obj(&path, &ObjImport::default()).unwrap();
        let m = &s.materials[s.meshes[0].materials[0] as usize];
        assert_eq!(
            (m.texture, m.surface),
            (
                None,
                Surface::Diffuse {
                    albedo: Vec3::splat(0.5)
                }
            )
        );
        assert!(
            s.warnings.len() == 1
                && s.warnings[0]
                    .contains("map_Kd -s 2 2 1 -o 0.25 0.5 tex\\w.png ignored (the OBJ has no texture coordinates"),
            "{:?}",
            s.warnings
        );
    }
}
