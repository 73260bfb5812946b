//! Writes the demo meshes of `scenes/*.toml` (OBJ and MTL) into `scenes/meshes/`, or the directory
//! given, skipping files already written by this version of the generator; `--force` rewrites all.
//!
//! `cargo run --release -p ppm-vk-scene-gen --bin gen_scenes [-- [--force] [DIR]]`

use std::path::PathBuf;

use anyhow::{bail, Context as _, Result};
use ppm_vk_scene_gen as demo;

fn main() -> Result<()> {
    let mut force = false;
    let mut dir: Option<PathBuf> = None;
    for a in std::env::args().skip(1) {
        match a.as_str() {
            "--force" => force = true,
            "-h" | "--help" => {
                println!("usage: gen_scenes [--force] [DIR]   (DIR defaults to the repository's scenes/meshes)");
                return Ok(());
            }
            _ if a.starts_with('-') => bail!("unknown option {a} (try --help)"),
            _ if dir.is_none() => dir = Some(PathBuf::from(a)),
            _ => bail!("one directory at most, got {a} as well"),
        }
    }
    let dir = dir.unwrap_or_else(demo::default_dir);
    if force {
        for f in demo::FILES {
            let p = dir.join(f.name);
            if p.exists() {
                std::fs::remove_file(&p).with_context(|| format!("removing {}", p.display()))?;
            }
        }
    }
    let written = demo::ensure(&dir)?;
    for p in &written {
        let size = std::fs::metadata(p).map(|m| m.len()).unwrap_or(0);
        println!("wrote {} ({:.1} MB)", p.display(), size as f64 / 1e6);
    }
    if written.is_empty() {
        println!("{}: every demo mesh is up to date", dir.display());
    }
    Ok(())
}
