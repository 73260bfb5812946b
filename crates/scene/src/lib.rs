//! Scenes: a camera, named materials, spheres, quads (parallelograms) and triangle meshes.
//! See `docs/scene-format.md` for the user-facing spec.
//!
//! Formats are loaders that all build this one [`Scene`] (model.rs): `toml` reads the scene file,
//! `mitsuba/` Mitsuba 3 XML, `obj` imports OBJ/MTL meshes through tobj, `ply` PLY meshes, `serialized` Mitsuba's serialized meshes, `texture`
//! bitmaps and procedural textures ([`generated`] lists the demo meshes that crates/scene-gen writes); load.rs
//! chooses the reader for a file. Every value check lives once, in [`Scene::validate`], so a scene built in
//! code, read from TOML or imported is checked the same way; the TOML loader maps a failed check's field
//! path (`sphere[1].radius`) back to the line and column it came from. This file only declares the modules
//! and re-exports what a user names; no file imports one that imports it back.

pub mod emitter;
pub mod error;
mod files;
pub mod generated;
mod load;
mod mitsuba;
mod model;
mod obj;
pub mod pfm;
mod ply;
mod serialized;
pub mod texture;
mod toml;

// The materials' host-side math, by the paths the loaders name it.
pub use ppm_vk_materials::conductor as conductors;
pub use ppm_vk_materials::{plastic, Microfacet};

pub use mitsuba::{
    parse_define, CYLINDER_SEGMENTS, DISK_SEGMENTS, MAX_INCLUDED_BYTES, MAX_INCLUDED_FILES, MAX_INCLUDE_DEPTH,
    MAX_NESTING, MAX_SPECTRUM_BYTES, MAX_SUBSTITUTED_BYTES,
};

pub use crate::error::{Error, Result};
pub use emitter::{Emitter, EnvMap, Environment};
#[cfg(test)]
use files::TempDir;
pub use files::{open_bounded, read_bounded_bytes, MAX_IMAGE_BYTES, MAX_MESH_BYTES, MAX_SCENE_BYTES};
pub use model::*;

pub use obj::ObjImport;
pub use serialized::{MAX_SERIALIZED_NAME, MAX_SERIALIZED_VERTICES};
