//! PLY meshes (ASCII or binary, through ply-rs), read into the [`RawMesh`] that `obj::add_mesh` places
//! in a scene: the loader of Mitsuba's `ply` shape.

use std::path::Path;

use anyhow::{anyhow, bail, Result};
use glam::{DVec3, Vec2};

use super::obj::RawMesh;
use super::MAX_TRIANGLES;
use crate::files::{read_bounded_bytes, MAX_MESH_BYTES};

/// ply-rs's error as a sentence: `file:line: malformed PLY: what` for the header and ASCII data (the
/// line it names is the file's), `file: malformed PLY: binary data: what` for binary data, where a line
/// means nothing. Only its first line is kept, and the text of the line it quotes: the rest is a debug
/// dump of the inner parser's state.
fn parse_error(shown: &str, bytes: &[u8], e: &std::io::Error) -> String {
    let text = e.to_string();
    let mut lines = text.lines();
    let first = lines.next().unwrap_or("").trim();
    let (line, what) = match first.strip_prefix("Line ").and_then(|r| r.split_once(": ")) {
        Some((n, what)) => (n.parse::<usize>().ok(), what),
        None => (None, first),
    };
    let what = what.trim_end_matches('.');
    let header_end = bytes
        .windows(10)
        .position(|w| w == b"end_header")
        .unwrap_or(bytes.len());
    let binary = bytes[..header_end].windows(13).any(|w| w == b"format binary");
    let in_header = line.is_some_and(|n| bytes[..header_end].iter().filter(|&&c| c == b'\n').count() >= n);
    // The quoted line, short: it is the reader's own text, but may be a whole binary blob.
    let quoted = lines
        .find_map(|l| l.trim().strip_prefix("String: "))
        .map(|q| q.trim_matches('\'').trim())
        .filter(|q| !q.is_empty() && q.chars().all(|c| !c.is_control()))
        .map(|q| format!(" (the line reads {:?})", crate::error::truncated(q, 60)));
    let quoted = quoted.unwrap_or_default();
    match line {
        Some(n) if !binary || in_header => format!("{shown}:{n}: malformed PLY: {what}{quoted}"),
        _ if binary => format!("{shown}: malformed PLY: in its binary data: {what}"),
        _ => format!("{shown}: malformed PLY: {what}{quoted}"),
    }
}

/// A PLY mesh (ASCII or binary): vertex x, y, z (and nx, ny, nz when all three are there), faces
/// as `vertex_indices` (or `vertex_index`) lists, polygons split into fans from their first corner.
pub(super) fn read(path: &Path, material: u32) -> Result<RawMesh> {
    use ply_rs_bw::parser::Parser;
    use ply_rs_bw::ply::{DefaultElement, Property};
    let shown = path.display().to_string();
    // A regular file within the mesh bound only: /dev/zero would be read until memory ran out, a FIFO
    // would block forever.
    let bytes = read_bounded_bytes(path, MAX_MESH_BYTES, "PLY file")?;
    let ply = Parser::<DefaultElement>::new()
        .read_ply(&mut std::io::Cursor::new(&bytes))
        .map_err(|e| anyhow!("{}", parse_error(&shown, &bytes, &e)))?;
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
