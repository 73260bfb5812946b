//! `ppm-vk check`: reads scene files the way `render` does and says what each holds, without a device:
//! the quick answer to "does ppm-vk read this scene, and what did it approximate?".

use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::Args;
use ppm_vk_engine::Scene;

#[derive(Args)]
pub struct CheckArgs {
    /// Scene files (TOML or Mitsuba XML); each is read and checked on its own.
    #[arg(required = true)]
    pub scenes: Vec<PathBuf>,
    /// Override a Mitsuba scene's parameter, as `render -D` (applies to every file given).
    #[arg(short = 'D', long = "define", value_name = "NAME=VALUE", value_parser = ppm_vk_engine::scene::parse_define)]
    pub defines: Vec<(String, String)>,
}

/// One line per file (`ok` with what it holds, or `error` with the reader's located message), each
/// warning under it; fails when any file could not be read.
pub fn run(args: CheckArgs) -> Result<()> {
    let mut failed = 0;
    for path in &args.scenes {
        match Scene::load_with(path, &args.defines) {
            Ok(scene) => {
                println!("ok: {}: {}", path.display(), summary(&scene));
                for w in &scene.warnings {
                    println!("  warning: {w}");
                }
            }
            Err(e) => {
                failed += 1;
                println!("error: {e:#}");
            }
        }
    }
    if failed > 0 {
        bail!("{failed} of {} scene file(s) could not be read", args.scenes.len());
    }
    Ok(())
}

fn summary(scene: &Scene) -> String {
    let triangles: usize = scene.meshes.iter().map(|m| m.indices.len()).sum();
    let lights = scene.materials.iter().filter(|m| m.is_light()).count() + scene.emitters.len();
    let c = &scene.camera;
    format!(
        "{}x{}, {} materials ({} emitting or lights), {} spheres, {} quads, {} triangles in {} meshes, {} textures, {} warnings",
        c.width,
        c.height,
        scene.materials.len(),
        lights,
        scene.spheres.len(),
        scene.quads.len(),
        triangles,
        scene.meshes.len(),
        scene.textures.len(),
        scene.warnings.len()
    )
}
