//! Mitsuba's `.serialized` meshes (file versions 3 and 4, the ones Mitsuba 3.9 reads), read into the
//! [`RawMesh`] that `obj::add_mesh` places in a scene: the loader of Mitsuba's `serialized` shape.
//!
//! The layout follows Mitsuba 3.9's src/shapes/serialized.cpp: per shape, an uncompressed header
//! (u16 0x041C, u16 version) and then a zlib stream holding a u32 flag word, (version 4) a
//! NUL-terminated name, u64 vertex and triangle counts, the positions, then normals, texture
//! coordinates and colours as the flags say (f32, or f64 with 0x2000), then u32 triangle indices;
//! all little-endian. The file ends with a dictionary of each shape's offset (u64 in version 4,
//! u32 in version 3) and the shape count (u32). Every count is checked against the bounds before
//! anything of its size is allocated, and no more is decompressed than the counts need.

use std::io::Read as _;
use std::path::Path;

use anyhow::{anyhow, bail, Result};
use glam::{DVec3, Vec2};

use super::obj::RawMesh;
use super::MAX_TRIANGLES;
use crate::files::{read_bounded_bytes, MAX_MESH_BYTES};

/// The first u16 of every shape's header.
const MAGIC: u16 = 0x041C;

/// Most bytes the name of a shape in a version 4 file may have (Mitsuba writes the mesh's name:
/// a few dozen). The name is read byte by byte up to its NUL: without a bound a stream of non-zero
/// bytes would be read to the end.
pub const MAX_SERIALIZED_NAME: usize = 4096;

/// Most vertices a serialized mesh may have: three per triangle of the largest mesh read.
pub const MAX_SERIALIZED_VERTICES: u64 = 3 * MAX_TRIANGLES as u64;

// The flag word's bits (Mitsuba's TriMeshFlags).
const HAS_NORMALS: u32 = 0x0001;
const HAS_TEXCOORDS: u32 = 0x0002;
const HAS_COLORS: u32 = 0x0008;
const DOUBLE_PRECISION: u32 = 0x2000;

fn u16_at(b: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes(b.get(at..at + 2)?.try_into().ok()?))
}

fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(b.get(at..at + 4)?.try_into().ok()?))
}

fn u64_at(b: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(b.get(at..at + 8)?.try_into().ok()?))
}

/// The byte offset of shape `index` in `bytes` (a file of `version`), from the end-of-file
/// dictionary (the first shape is at 0 without one, as Mitsuba reads it).
fn offset_of(shown: &str, bytes: &[u8], version: u16, index: u32) -> Result<usize> {
    if index == 0 {
        return Ok(0);
    }
    let len = bytes.len();
    let count = len
        .checked_sub(4)
        .and_then(|at| u32_at(bytes, at))
        .ok_or_else(|| anyhow!("{shown}: too short for the end-of-file dictionary of its shapes"))?;
    if index >= count {
        bail!(
            "{shown}: shape_index {index} is past the end: the file's dictionary lists {count} shape{}",
            if count == 1 { "" } else { "s" }
        );
    }
    let from_end = u64::from(count - index);
    let (entry, offset) = if version == 4 {
        let at = (len as u64).checked_sub(8 * from_end + 4);
        (at, at.and_then(|at| u64_at(bytes, at as usize)))
    } else {
        let at = (len as u64).checked_sub(4 * from_end + 4);
        (at, at.and_then(|at| u32_at(bytes, at as usize).map(u64::from)))
    };
    let (Some(_), Some(offset)) = (entry, offset) else {
        bail!("{shown}: the end-of-file dictionary claims {count} shapes, more than the file ({len} bytes) holds");
    };
    if offset.saturating_add(4) > len as u64 {
        bail!("{shown}: shape {index} is at offset {offset} in the dictionary, past the end of the file ({len} bytes)");
    }
    Ok(offset as usize)
}

/// Shape `index` of the `.serialized` file at `path`: positions, the file's normals and texture
/// coordinates (Mitsuba's convention: stored as Mitsuba uses them), and its triangles with `material`.
/// Vertex colours are read past, as Mitsuba 3.9 does.
pub(super) fn read(path: &Path, index: u32, material: u32) -> Result<RawMesh> {
    let shown = path.display().to_string();
    let bytes = read_bounded_bytes(path, MAX_MESH_BYTES, "serialized mesh")?;
    let header = |at: usize| (u16_at(&bytes, at), u16_at(&bytes, at + 2));
    let version = match header(0) {
        (Some(MAGIC), Some(v @ (3 | 4))) => v,
        (Some(MAGIC), Some(v)) => {
            bail!("{shown}: serialized file version {v}: versions 3 and 4 are read (those Mitsuba 3.9 reads)")
        }
        (Some(_), Some(_)) => bail!("{shown}: not a serialized mesh (it does not start with 0x041C)"),
        _ => bail!("{shown}: too short for a serialized mesh's header"),
    };
    let at = offset_of(&shown, &bytes, version, index)?;
    if header(at) != (Some(MAGIC), Some(version)) {
        bail!("{shown}: shape {index}: no shape header (0x041C, version {version}) at its offset {at}");
    }
    let mut z = flate2::read::ZlibDecoder::new(&bytes[at + 4..]);
    let what = format!("{shown}: shape {index}");
    let bad = |e: std::io::Error, reading: &str| {
        if e.kind() == std::io::ErrorKind::UnexpectedEof {
            anyhow!("{what}: the compressed stream ends while reading {reading}: the file is cut short")
        } else {
            anyhow!("{what}: bad zlib stream while reading {reading}: {e}")
        }
    };
    let mut word = [0u8; 4];
    z.read_exact(&mut word).map_err(|e| bad(e, "the flags"))?;
    let flags = u32::from_le_bytes(word);
    if version == 4 {
        // The shape's name, up to its NUL: not used (the file names the mesh in messages).
        let mut name = Vec::new();
        let mut byte = [0u8; 1];
        loop {
            z.read_exact(&mut byte).map_err(|e| bad(e, "the shape's name"))?;
            if byte[0] == 0 {
                break;
            }
            if name.len() == MAX_SERIALIZED_NAME {
                bail!("{what}: the shape's name runs past {MAX_SERIALIZED_NAME} bytes (MAX_SERIALIZED_NAME) without its NUL");
            }
            name.push(byte[0]);
        }
    }
    let mut counts = [0u8; 16];
    z.read_exact(&mut counts)
        .map_err(|e| bad(e, "the vertex and triangle counts"))?;
    let vertices = u64::from_le_bytes(counts[..8].try_into().expect("8 bytes"));
    let faces = u64::from_le_bytes(counts[8..].try_into().expect("8 bytes"));
    if faces == 0 {
        bail!("{what}: no triangles: the mesh is empty");
    }
    if faces > MAX_TRIANGLES as u64 {
        bail!("{what}: {faces} triangles, more than MAX_TRIANGLES = {MAX_TRIANGLES}");
    }
    if vertices > MAX_SERIALIZED_VERTICES {
        bail!("{what}: {vertices} vertices, more than MAX_SERIALIZED_VERTICES = {MAX_SERIALIZED_VERTICES}");
    }
    let size = if flags & DOUBLE_PRECISION != 0 { 8 } else { 4 };
    let has = |bit: u32| flags & bit != 0;
    let per_vertex =
        3 + 3 * u64::from(has(HAS_NORMALS)) + 2 * u64::from(has(HAS_TEXCOORDS)) + 3 * u64::from(has(HAS_COLORS));
    // Both counts are bounded above, so this cannot overflow.
    let need = vertices * per_vertex * size + faces * 12;
    if need > MAX_MESH_BYTES {
        bail!(
            "{what}: its {vertices} vertices and {faces} triangles need {need} bytes, more than a mesh may \
             have (MAX_MESH_BYTES = {MAX_MESH_BYTES})"
        );
    }
    // The stream is read only as far as the counts need (a longer one, a zlib bomb, is never inflated
    // further), into a buffer that grows with what actually arrives (a lying count allocates nothing).
    let mut data = Vec::new();
    (&mut z)
        .take(need)
        .read_to_end(&mut data)
        .map_err(|e| bad(e, "the vertex and triangle data"))?;
    if (data.len() as u64) < need {
        bail!(
            "{what}: the compressed stream ends after {} bytes of data where its {vertices} vertices and \
             {faces} triangles need {need}: a count is wrong or the file is cut short",
            data.len()
        );
    }
    let vertices = vertices as usize;
    let mut at = 0usize;
    let mut array = |dim: usize| -> Vec<f64> {
        let n = vertices * dim;
        let values = (0..n)
            .map(|k| {
                let b = &data[at + k * size as usize..];
                if size == 8 {
                    f64::from_le_bytes(b[..8].try_into().expect("8 bytes"))
                } else {
                    f64::from(f32::from_le_bytes(b[..4].try_into().expect("4 bytes")))
                }
            })
            .collect();
        at += n * size as usize;
        values
    };
    let to_vec3 = |v: Vec<f64>| -> Vec<DVec3> { v.chunks_exact(3).map(DVec3::from_slice).collect() };
    let positions = to_vec3(array(3));
    if let Some(k) = positions.iter().position(|p| !p.is_finite()) {
        bail!("{what}: vertex {k} is not finite ({})", positions[k]);
    }
    let normals = has(HAS_NORMALS).then(|| to_vec3(array(3)));
    let uvs = has(HAS_TEXCOORDS).then(|| {
        array(2)
            .chunks_exact(2)
            .map(|t| Vec2::new(t[0] as f32, t[1] as f32))
            .collect::<Vec<_>>()
    });
    if has(HAS_COLORS) {
        array(3);
    }
    let mut triangles = Vec::with_capacity(faces as usize);
    for (f, t) in data[at..].chunks_exact(12).enumerate() {
        let i = [0, 4, 8].map(|k| u32::from_le_bytes(t[k..k + 4].try_into().expect("4 bytes")));
        if let Some(&bad) = i.iter().find(|&&i| i as usize >= vertices) {
            bail!("{what}: triangle {f} has vertex index {bad}, out of range ({vertices} vertices)");
        }
        triangles.push((i, material));
    }
    Ok(RawMesh {
        name: format!("{shown}@{index}"),
        positions,
        normals,
        partial_normals: false,
        uvs,
        triangles,
    })
}
