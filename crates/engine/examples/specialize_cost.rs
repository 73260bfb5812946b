//! What compiling the scene into the tracing kernels costs at set-up and buys per pass: each scene
//! rendered with `Settings::specialize` on and off, interleaved over rounds in one process, without
//! the on-disk kernel caches (every kernel compiled afresh). Prints one line per render and the medians
//! (docs/performance.md, "Set-up").
//!
//! cargo run --release -p ppm-vk-engine --example specialize_cost -- [--rounds N] [--photons N]
//!     [--resolution WxH] SCENE...

use ppm_vk_engine::{open_device, ContextOptions, Renderer, Scene, Settings};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> anyhow::Result<()> {
    let (mut rounds, mut photons, mut resolution, mut scenes) = (2, 200_000u32, (128u32, 128u32), Vec::new());
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = || args.next().ok_or_else(|| anyhow::anyhow!("{a} needs a value"));
        match a.as_str() {
            "--rounds" => rounds = value()?.parse()?,
            "--photons" => photons = value()?.parse()?,
            "--resolution" => {
                let v = value()?;
                let (w, h) = v
                    .split_once('x')
                    .ok_or_else(|| anyhow::anyhow!("--resolution {v}: expected WxH"))?;
                resolution = (w.parse()?, h.parse()?);
            }
            _ => scenes.push(a),
        }
    }
    // No pipeline cache and no SPIR-V cache: every renderer compiles its kernels.
    let ctx = open_device(&ContextOptions::default())?;
    println!("scene specialize setup_s kernels_s first_pass_ms pass_ms_median photon_ms eye_ms");
    for path in &scenes {
        let scene = Scene::load(path)?.with_resolution(resolution.0, resolution.1);
        let mut rows: Vec<(bool, f64, f64)> = Vec::new();
        for _ in 0..rounds {
            for specialize in [true, false] {
                let start = std::time::Instant::now();
                let mut r = Renderer::new(
                    &ctx,
                    &scene,
                    Settings {
                        photons_per_pass: photons,
                        specialize,
                        ..Settings::default()
                    },
                )?;
                let setup_s = start.elapsed().as_secs_f64();
                let first = r.pass()?.wall_ms;
                r.pass()?;
                let passes: Vec<_> = (0..3).map(|_| r.pass()).collect::<Result<_, _>>()?;
                let wall = median(passes.iter().map(|p| p.wall_ms).collect());
                let photon = median(passes.iter().map(|p| p.stage_ms("photon")).collect());
                let eye = median(passes.iter().map(|p| p.stage_ms("ray")).collect());
                println!(
                    "{path} {specialize} {setup_s:.2} {:.2} {first:.0} {wall:.0} {photon:.0} {eye:.0}",
                    r.setup_times().kernels_s
                );
                rows.push((specialize, setup_s, wall));
            }
        }
        let of = |on: bool, i: usize| {
            median(
                rows.iter()
                    .filter(|r| r.0 == on)
                    .map(|r| if i == 0 { r.1 } else { r.2 })
                    .collect(),
            )
        };
        println!(
            "{path}: specialised set-up {:.2} s vs {:.2} s as built; pass {:.0} ms vs {:.0} ms ({:.2}x)",
            of(true, 0),
            of(false, 0),
            of(true, 1),
            of(false, 1),
            of(false, 1) / of(true, 1)
        );
    }
    Ok(())
}
