//! Embedding the engine without the CLI: open a device, load a scene, run passes, save the image.
//!
//! cargo run --release -p ppm-vk-engine --example render -- scenes/cornell-spheres.toml out.png

use ppm_vk_engine::{open_device, ContextOptions, Renderer, Scene, Settings};

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let scene_path = args.next().unwrap_or_else(|| "scenes/cornell-spheres.toml".into());
    let out = args.next().unwrap_or_else(|| "example.png".into());

    let ctx = open_device(&ContextOptions::default())?;
    let scene = Scene::load(&scene_path)?.with_resolution(256, 256);
    let mut renderer = Renderer::new(
        &ctx,
        &scene,
        Settings {
            photons_per_pass: 200_000,
            ..Settings::default()
        },
    )?;
    for _ in 0..10 {
        let stats = renderer.pass()?;
        println!(
            "pass {:>2}: {:>7} records, {:.1} ms (gather {:.1} ms GPU)",
            stats.index,
            stats.records,
            stats.wall_ms,
            stats.stage_ms("gather")
        );
    }
    renderer.image()?.save(&out)?;
    println!("wrote {out}");
    Ok(())
}
