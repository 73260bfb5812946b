//! The progressive loop on the GPU: the ray pass once, then photon passes (photon -> lookup -> gather ->
//! update), and the resolve whenever an image is wanted.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

use ppm_vk_device::{barrier, vk, Buffer, BufferKind, BufferSlice, ComputePipeline, Context, Profiler, ScopeTiming};
use ppm_vk_kernels::gather::{self, GatherPush, GridReader, HitBuffers};
use ppm_vk_kernels::layout::{HitPoint, HitStats, PassAccum, PathCounters, Photon, PhotonWork, RenderParams, Triangle};
use ppm_vk_kernels::lookup::{Grid, Lookup};
use ppm_vk_kernels::photon::{self, PathLimits, PhotonPush, SALT_EYE, SALT_PHOTON, SALT_PROBE};
use ppm_vk_kernels::probe::{self, ProbePush, MODE_CURVATURE, MODE_NEAREST, MODE_PAPER, MODE_SCALE_FREE};
use ppm_vk_kernels::ray::{self, RayPush, SceneBuffers, JITTER_RANDOM, MARK_CHAIN, MARK_CURVED, MARK_SPLIT};
use ppm_vk_kernels::reflected;
use ppm_vk_kernels::resolve::{self, ResolvePush};
use ppm_vk_kernels::specialize::{self, KernelTiming, SceneConstants, MAX_INLINE_PRIMITIVES};
use ppm_vk_kernels::update::RadiusMax;
use ppm_vk_kernels::update::{self, UpdatePush};

use crate::checkpoint::{self, Checkpoint};
use crate::error::{DeviceContext as _, Error, Result};
use crate::image_io::RgbImage;
use crate::lower::{GpuScene, CELL_PER_RADIUS};
use crate::scene::{Camera, Scene};
use crate::settings::{Mode, ProbeMode, Settings};
use crate::stats::{KernelSetup, PassStats, PhotonVariant, PilotMarks, ProbeReport, SetupTimes};

/// Cancels [`Renderer::pass`] from another thread: clone it, give one clone to the renderer
/// ([`Renderer::set_cancel`]) and call [`CancelToken::cancel`] on the other. The pass stops at its next
/// dispatch boundary with [`Error::Cancelled`]; the passes completed before it stay in the estimate.
#[derive(Clone, Debug, Default)]
pub struct CancelToken(Arc<AtomicBool>);

impl CancelToken {
    pub fn new() -> CancelToken {
        CancelToken::default()
    }

    pub fn cancel(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }

    /// Clears a cancellation, so the renderer can go on.
    pub fn reset(&self) {
        self.0.store(false, Ordering::Relaxed);
    }
}

/// What one probabilistic pass gives each pixel on its own ([`Renderer::probabilistic_pass`]).
pub(crate) struct PassEstimate {
    /// The photons' radiance estimate.
    pub photons: Vec<[f64; 3]>,
    /// The emission samples' radiance sum (rgb) and count (w).
    pub direct: Vec<[f64; 4]>,
}

struct Kernels {
    ray: ComputePipeline,
    probe: GridReader,
    photon: ComputePipeline,
    photon_resume: ComputePipeline,
    lookup: Lookup,
    gather: GridReader,
    update: ComputePipeline,
    resolve: ComputePipeline,
}

/// A progressive photon mapping render in progress on one device.
///
/// ```no_run
/// # fn main() -> Result<(), ppm_vk_engine::Error> {
/// use ppm_vk_engine::{open_device, ContextOptions, Renderer, Scene, Settings};
/// let ctx = open_device(&ContextOptions::default())?;
/// let scene = Scene::load("scenes/cornell-spheres.toml")?;
/// let mut renderer = Renderer::new(&ctx, &scene, Settings::default())?;
/// for _ in 0..10 {
///     renderer.pass()?;
/// }
/// renderer.image()?.save("out.png")?;
/// # Ok(())
/// # }
/// ```
pub struct Renderer {
    ctx: Context,
    settings: Settings,
    gpu: GpuScene,
    kernels: Kernels,
    params: Buffer,
    spheres: Buffer,
    quads: Buffer,
    materials: Buffer,
    lights: Buffer,
    bvh_nodes: Buffer,
    bvh_triangles: Buffer,
    /// The textures, and the triangles' texture coordinates and vertex normals, as texels (texture.glsl,
    /// shading.glsl).
    textures: Buffer,
    triangle_texels: Buffer,
    /// `PathCounters`: paths cut at the depth backstops, over the whole render.
    cut: Buffer,
    limits: PathLimits,
    hit_points: Buffer,
    stats: Buffer,
    accum: Buffer,
    /// Non-empty hit-point slots in Morton order of their position (built after the ray pass), per tile:
    /// tile k's entries from its first slot on, relative to it.
    order: Buffer,
    /// The image's pixels in runs that the kernels bind one at a time ([`Tile`]).
    tiles: Vec<Tile>,
    direct: Buffer,
    /// `direct` and `cut` as the pass in flight found them: its eye pass adds to both, and a cancelled
    /// pass puts them back.
    direct_saved: Buffer,
    cut_saved: Buffer,
    /// Per pixel, 1 where the pilot eye pass saw emission, or beside such a pixel (ray.comp).
    busy: Buffer,
    image: Buffer,
    counter: Buffer,
    /// A BVH scene's photon work counters and suspended photons (photon.comp).
    photon_work: Buffer,
    suspended: Buffer,
    /// Each batch's record count, copied from `counter`, to detect overflow after the pass.
    batch_log: Buffer,
    grid: Grid,
    /// The largest R^2 the update saw (two f32 bit patterns, `gather::RadiusMax`).
    r2_max: Buffer,
    profiler: Profiler,
    /// Photons per batch: the whole pass until a pass overflows the record buffer.
    batch: u32,
    passes: u64,
    emitted: u64,
    ray_ms: f64,
    /// Pixels where the pilot took all its samples (`PilotMarks::pilot_all`).
    pilot_all: u32,
    probe_report: Option<ProbeReport>,
    cancel: CancelToken,
    /// What a checkpoint records the render is of.
    scene_name: String,
    scene_sha256: String,
    /// The scene's hash without its camera, and the camera: `set_camera` hashes them anew.
    geometry_sha256: String,
    camera: Camera,
    /// The parameters a render starts from (the grid's cells adapt as it goes): `set_camera` restarts
    /// from them.
    start_params: RenderParams,
    /// Where the set-up's time went.
    setup: SetupTimes,
}

/// A scoped thread's result; its panic goes on in the caller.
fn joined<T>(h: std::thread::ScopedJoinHandle<'_, T>) -> T {
    h.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic))
}

/// The stages of a photon batch, in order; one submission records all of them, or one
/// ([`Settings::split_submissions`]).
#[derive(Clone, Copy, PartialEq, Eq)]
enum BatchStage {
    Trace,
    Lookup,
    Gather,
}

const ALL_STAGES: &[BatchStage] = &[BatchStage::Trace, BatchStage::Lookup, BatchStage::Gather];

/// What the batches of photons feed their grid to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum GridUse {
    Gather,
    Probe,
}

/// Consecutive pixels whose per-pixel and per-slot data the kernels bind as one slice each, within the
/// device's largest storage binding (`maxStorageBufferRange`: 128 MiB on lavapipe, whose 2048x2048 SPPM
/// hit points alone are 192 MiB). The photons do not depend on the hit points: each batch is traced once
/// and gathered tile after tile. Pixel and slot indices stay global (random streams, camera rays), so
/// the image does not depend on the tiles, bit for bit.
#[derive(Clone, Copy, Debug)]
struct Tile {
    first_pixel: u32,
    pixels: u32,
    /// Entries of the tile's hit-point order (its non-empty slots).
    active: u32,
}

/// Every tile but the last has a multiple of this many pixels, so each slice starts at a multiple of
/// 64 x 4 = 256 bytes (the smallest element, a u32 of the order or the marks): the largest storage
/// offset alignment Vulkan allows a device to ask.
pub const TILE_ALIGN_PIXELS: u32 = 64;

/// Pixels per tile: the most, in multiples of [`TILE_ALIGN_PIXELS`], whose data in every per-pixel
/// buffer is at most `cap` bytes (`per_pixel`: the largest buffer's bytes per pixel). The bound: a
/// tile's slice of each buffer is at most `cap`, the device's `maxStorageBufferRange` (or
/// `Settings::max_tile_bytes`, below it). `None` where not even one aligned run fits.
fn tile_pixels(pixels: u32, per_pixel: u64, cap: u64) -> Option<u32> {
    let fit = (cap / per_pixel.max(1)).min(u32::MAX as u64) as u32 / TILE_ALIGN_PIXELS * TILE_ALIGN_PIXELS;
    match fit {
        0 => None,
        _ => Some(fit.min(pixels).max(1)),
    }
}

/// The image's `pixels` in runs of `per_tile` (the last may be shorter).
fn make_tiles(pixels: u32, per_tile: u32) -> Vec<Tile> {
    (0..pixels.div_ceil(per_tile).max(1))
        .map(|k| Tile {
            first_pixel: k * per_tile,
            pixels: per_tile.min(pixels - k * per_tile),
            active: 0,
        })
        .collect()
}

/// Largest batch log (batches per pass).
/// The adaptive shrink (update.comp) stops at this fraction of the starting radius: f32 positions hold
/// about 2^-24 of the scene's extent, eq. 8's radius is about 1e-3 of it at 1024 pixels. Below it eq. 3
/// alone shrinks the radius (tests/stability.rs, a point focus).
pub const SHRINK_FLOOR: f32 = 1e-4;

const MAX_BATCHES: u32 = 1024;

/// Most photons one batch traces: 2^20. Each batch is its own submission and a pass checks its
/// [`CancelToken`] between them, so a signal ends even a pass of `MAX_PHOTONS_PER_PASS` photons within
/// one batch (a 2^24-photon pass in one submission took 50 s on lavapipe). Passes of the default 10^6
/// photons are one batch, as before.
const MAX_BATCH_PHOTONS: u32 = 1 << 20;

impl Renderer {
    /// Uploads the scene, allocates per-hit-point state and runs the ray pass (and the probe pass).
    pub fn new(ctx: &Context, scene: &Scene, settings: Settings) -> Result<Renderer> {
        let mut r = Renderer::prepare(ctx, scene, settings)?;
        if r.settings.probe != ProbeMode::Off {
            let start = Instant::now();
            r.probe_pass()?;
            r.setup.probe_s = start.elapsed().as_secs_f64();
        }
        Ok(r)
    }

    /// The render's state after the passes so far, to continue later with [`Renderer::resume`]; `build`
    /// names the build (its kernels), which the resume must match.
    pub fn checkpoint(&self, build: &str) -> Result<Checkpoint> {
        let header = checkpoint::Header {
            build: build.into(),
            scene_name: self.scene_name.clone(),
            scene_sha256: self.scene_sha256.clone(),
            settings: self.settings.clone(),
            passes: self.passes,
            emitted: self.emitted,
            batch: self.batch,
            grid_cell: self.gpu.params.cell_size,
            probe: self.probe_report.clone(),
            sections: vec![],
        };
        let (slots, pixels) = (self.gpu.slots(), self.gpu.pixels());
        let hit_points = match self.settings.mode {
            Mode::Ppm => self.download(&self.hit_points, slots, "reading the hit points")?,
            Mode::Sppm => vec![],
        };
        let cut = self.download::<PathCounters>(&self.cut, 1, "reading the path counters")?[0];
        let stats = self.download(&self.stats, slots, "reading the hit-point statistics")?;
        let direct = self.download(&self.direct, pixels, "reading the direct emission")?;
        let busy = self.download(&self.busy, pixels, "reading the emission-sampled pixels")?;
        Ok(Checkpoint {
            header,
            stats,
            hit_points,
            direct,
            busy,
            cut,
        }
        .seal())
    }

    /// Continues the render `checkpoint` saved: the passes after it give the image the uninterrupted
    /// render would have, bit for bit. Fails, saying what differs, unless the checkpoint is of `scene`
    /// rendered with `settings` by `build`.
    pub fn resume(
        ctx: &Context,
        scene: &Scene,
        settings: Settings,
        checkpoint: &Checkpoint,
        build: &str,
    ) -> Result<Renderer> {
        let refused = |e: anyhow::Error| Error::Checkpoint {
            message: format!("cannot resume from this checkpoint: {e:#}"),
        };
        checkpoint.check(scene, &settings, build).map_err(refused)?;
        let mut r = Renderer::prepare(ctx, scene, settings)?;
        let c = checkpoint;
        let (slots, pixels) = (r.gpu.slots() as usize, r.gpu.pixels() as usize);
        let ppm_hits = if r.settings.mode == Mode::Ppm { slots } else { 0 };
        if !(c.stats.len() == slots
            && c.hit_points.len() == ppm_hits
            && c.direct.len() == pixels
            && c.busy.len() == pixels)
        {
            let message =
                format!("the checkpoint's buffers do not fit this render ({slots} hit points, {pixels} pixels)");
            return Err(Error::Checkpoint { message });
        }
        let restore = |buffer: &Buffer, bytes: &[u8]| r.ctx.upload(buffer, bytes).device("restoring the checkpoint");
        restore(&r.stats, bytemuck::cast_slice(&c.stats))?;
        restore(&r.direct, bytemuck::cast_slice(&c.direct))?;
        restore(&r.busy, bytemuck::cast_slice(&c.busy))?;
        restore(&r.cut, bytemuck::bytes_of(&c.cut))?;
        if r.settings.mode == Mode::Ppm {
            restore(&r.hit_points, bytemuck::cast_slice(&c.hit_points))?;
            r.set_order(morton_order(&c.hit_points))?;
        }
        let h = &c.header;
        (r.passes, r.emitted, r.batch, r.probe_report) = (h.passes, h.emitted, h.batch.max(1), h.probe.clone());
        r.use_cell(h.grid_cell)?;
        Ok(r)
    }

    /// [`Renderer::new`] up to the probe pass.
    fn prepare(ctx: &Context, scene: &Scene, settings: Settings) -> Result<Renderer> {
        settings.validate()?;
        let max_range = ctx.limits().max_storage_buffer_range as u64;
        let record_size = std::mem::size_of::<Photon>() as u64;
        // Room for the records a typical pass leaves (a few per photon); a pass that leaves more is split
        // into batches, so this bounds memory, never correctness.
        let wanted = settings.photons_per_pass as u64 * 4;
        let capacity = wanted.min(max_range / record_size).min(u32::MAX as u64 / 2) as u32;
        let capacity = capacity.max(1024);
        let mut setup = SetupTimes::default();
        let lower_start = Instant::now();
        let mut gpu = GpuScene::new(scene, &settings, capacity)?;
        setup.lower_s = lower_start.elapsed().as_secs_f64();
        setup.bvh_s = gpu.bvh_stats.build_seconds;
        // Depth backstops and photons per thread that keep every loop inside the device's budget. The
        // intersection loops are counted as loops even where the specialised kernels unroll them.
        let limits = if gpu.traverses_bvh() {
            PathLimits::with_bvh
        } else {
            PathLimits::new
        };
        let inline_triangles = if gpu.triangles_inline {
            gpu.params.num_triangles
        } else {
            0
        };
        let budget = ctx.info().loop_budget;
        let limits = limits(
            budget,
            gpu.params.num_spheres + gpu.params.num_quads + inline_triangles,
            // choose_emitter's binary search, and an environment map's two (photon.comp's LIGHT_LOOPS)
            u32::BITS - gpu.params.num_lights.leading_zeros() + 1 + if gpu.has_environment { 48 } else { 0 },
            gpu.params.hit_slots,
            settings.most_samples(),
            settings.max_photon_depth,
            settings.max_eye_depth,
        )
        .map_err(|e| {
            let lower =
                "the spheres and quads (or put them in meshes), the hit points per pixel or the emission samples";
            Error::limit(format!("{e:#}"), None, budget.unwrap_or(0) as u64, lower)
        })?;
        gpu.params.max_photon_depth = limits.photon_depth;
        gpu.params.max_eye_depth = limits.eye_depth;
        gpu.params.photon_bvh_budget = limits.photon_bvh_budget;
        gpu.params.eye_bvh_budget = limits.eye_bvh_budget;
        gpu.params.lookup_limit = ppm_vk_kernels::lookup::lookup_limit(budget);
        let slots = gpu.slots() as u64;
        let pixels = gpu.pixels() as u64;
        let tri_bytes = gpu.bvh_triangles.len() as u64 * std::mem::size_of::<Triangle>() as u64;
        let node_bytes = std::mem::size_of_val(gpu.bvh_nodes.as_slice()) as u64;
        let bvh_bytes = tri_bytes + node_bytes;
        if tri_bytes.max(node_bytes) > max_range {
            let triangles = gpu.bvh_triangles.len();
            let lower = format!(
                "the scene's {triangles} triangles (at most {} in all)",
                max_range / std::mem::size_of::<Triangle>() as u64
            );
            return Err(Error::limit(
                "the BVH (bytes in one buffer)",
                Some(bvh_bytes),
                max_range,
                lower,
            ));
        }
        // Every buffer within the device's largest binding and all of them within its memory, checked
        // before anything is allocated.
        let size = std::mem::size_of::<HitPoint>() as u64;
        let per_pixel_of = |slots: u64| {
            [
                ("the hit points", slots * size),
                (
                    "the hit-point statistics",
                    slots * std::mem::size_of::<HitStats>() as u64,
                ),
                ("the pass accumulators", slots * std::mem::size_of::<PassAccum>() as u64),
                ("the hit-point order", slots * 4),
                ("the direct emission", pixels * 32),
                ("the direct emission's copy (a cancelled pass restores it)", pixels * 32),
                ("the image", pixels * 16),
                ("the emission-sampled pixels' marks", pixels * 4),
            ]
        };
        let mut per_pixel = per_pixel_of(slots);
        // The flag that sets the hit points per pixel in this render.
        let slots_flag = match settings.mode {
            Mode::Ppm => "--hit-slots",
            Mode::Sppm if gpu.params.rough_split != 0 => "--rough-splits",
            Mode::Sppm => "--glass-splits",
        };
        let advice = format!(
            "the resolution ({}x{}) or the hit points per pixel ({}, {slots_flag})",
            gpu.params.width, gpu.params.height, gpu.params.hit_slots
        );
        // Only a BVH scene suspends photons (photon.comp); the others bind one entry's worth.
        let suspended_bytes = match gpu.traverses_bvh() {
            true => photon::suspended_bytes(settings.photons_per_pass, limits.per_thread),
            false => std::mem::size_of::<ppm_vk_kernels::layout::PhotonState>() as u64,
        };
        let others = [
            (
                "the photon records, their staging copy and the grid build's counts",
                capacity as u64 * Grid::bytes_per_record(),
            ),
            ("the BVH", bvh_bytes),
            (
                "the textures",
                (gpu.textures.len() * 16 + gpu.triangle_texels.len() * 16) as u64,
            ),
            ("the suspended photons", suspended_bytes),
        ];
        // The textures are one buffer: when it cannot be bound, the images are the cause, not the
        // resolution (an 8192 x 8192 image is 1 GiB of texels; lavapipe binds 128 MiB).
        let texture_bytes = gpu.textures.len() as u64 * 16;
        if texture_bytes > max_range {
            // An environment map's pixels (and its sampling tables, as many again) share the buffer
            // (lower/lights.rs).
            let maps = scene.emitters.iter().filter_map(|e| match e {
                crate::scene::Emitter::Environment(env) => env.map.as_ref(),
                _ => None,
            });
            let largest = (scene.textures.iter().map(|t| (t.name.as_str(), t.pixel_count())))
                .chain(maps.map(|m| (m.name.as_str(), u64::from(m.width) * u64::from(m.height))))
                .max_by_key(|&(_, pixels)| pixels);
            let lower = match largest {
                Some((name, pixels)) => format!(
                    "the texture images' size (the largest, \"{name}\", has {pixels} pixels; this device binds {} in all)",
                    max_range / 16
                ),
                None => "the texture images' size".into(),
            };
            return Err(Error::limit(
                "the textures (16 bytes a pixel, in one buffer)",
                Some(texture_bytes),
                max_range,
                lower,
            ));
        }
        // SPPM's glass splits only lower the variance: where their slots would not fit the device's memory,
        // the render takes one hit point a pixel, as with --glass-splits 1, and says so.
        let memory = ctx.info().memory_bytes;
        if settings.splits_glass(scene)
            && gpu.params.hit_slots > 1
            && fits_device(&per_pixel, &others, memory, &advice).is_err()
            && fits_device(&per_pixel_of(pixels), &others, memory, &advice).is_ok()
        {
            eprintln!(
                "note: {} glass splits a pixel do not fit this device's memory at {}x{}: one hit point a pixel \
                 (--glass-splits 1)",
                gpu.params.hit_slots, gpu.params.width, gpu.params.height
            );
            gpu.params.hit_slots = 1;
            per_pixel = per_pixel_of(pixels);
        }
        fits_device(&per_pixel, &others, memory, &advice)?;
        let slots = gpu.slots() as u64;
        // The largest per-pixel buffer sets the tiles: the statistics (slots of 64 bytes, hit points 48),
        // or the emission sums (32 bytes a pixel).
        let slot_bytes = [
            std::mem::size_of::<HitPoint>(),
            std::mem::size_of::<HitStats>(),
            std::mem::size_of::<PassAccum>(),
        ]
        .into_iter()
        .max()
        .unwrap_or(0) as u64;
        let per_pixel_bytes = (gpu.params.hit_slots as u64 * slot_bytes).max(32);
        let cap = settings.max_tile_bytes.unwrap_or(max_range).min(max_range);
        let Some(per_tile) = tile_pixels(pixels as u32, per_pixel_bytes, cap) else {
            let message = format!(
                "{cap} bytes hold fewer than {TILE_ALIGN_PIXELS} pixels of {per_pixel_bytes} bytes (at least {})",
                TILE_ALIGN_PIXELS as u64 * per_pixel_bytes
            );
            return Err(Error::Settings {
                field: "max_tile_bytes",
                message,
            });
        };
        // The kernels read the textures as texels: each buffer within the device's texel buffer.
        let max_texels = ctx.limits().max_texel_buffer_elements as u64;
        for (what, texels) in [
            ("the textures", gpu.textures.len()),
            (
                "the triangles' texture coordinates and normals",
                gpu.triangle_texels.len(),
            ),
        ] {
            if texels as u64 > max_texels {
                return Err(Error::limit(
                    format!("{what} ({texels} texels of 16 bytes)"),
                    Some(texels as u64),
                    max_texels,
                    "smaller or fewer texture images",
                ));
            }
        }

        let glsl_start = Instant::now();
        let constants = trace_constants(&gpu, &settings);
        setup.glsl_s = glsl_start.elapsed().as_secs_f64();
        let traced = |k: &reflected::KernelInfo| tracing_pipeline(ctx, constants.as_deref(), k, &[]);
        // Hit points per gather thread (measured, shaders/common/neighbours.glsl): two share their photon
        // reads where the probe enlarged the radii; where no radius can exceed eq. 8's (no probe, or the
        // curvature rule capped to shrink), each gathers fastest on its own (the shrinking curvature
        // probe's gather took 1.2-1.3x as long in pairs on cornell-box; docs/accuracy.md).
        let enlarged = match settings.probe {
            ProbeMode::Off => false,
            ProbeMode::Curvature => settings.probe_grow > 1.0,
            _ => true,
        };
        let group = if enlarged { gather::GROUP } else { 1 };
        // Whether any hit point can be glossy (a rough conductor of roughness glossy_alpha or more).
        let glossy = gpu.materials.iter().any(|m| {
            m.surface == ppm_vk_kernels::layout::SURFACE_ROUGH_CONDUCTOR && m.alpha_u >= gpu.params.glossy_alpha
        });
        let smooth = gpu.smooth_shading();
        let kernels_start = Instant::now();
        // The kernels compiled for this scene each on a thread of their own (shaderc and the driver's
        // compile of one kernel are serial, and they are seconds on a CPU); the build-time ones here.
        let pipelines = || -> anyhow::Result<(Kernels, Vec<KernelTiming>)> {
            std::thread::scope(|s| {
                let ray = s.spawn(|| traced(&reflected::RAY));
                let photon = s.spawn(|| traced(&reflected::PHOTON));
                let probe = s.spawn(|| gather::with_group(ctx, &reflected::PROBE, group));
                let gather = s.spawn(|| gather::with_variant(ctx, &reflected::GATHER, group, glossy, smooth));
                let mut timings = Vec::new();
                let mut built = |k: &reflected::KernelInfo| -> anyhow::Result<ComputePipeline> {
                    let (pipeline, timing) = specialize::build(ctx, k, &[], "")?;
                    timings.push(timing);
                    Ok(pipeline)
                };
                let photon_resume = built(&reflected::PHOTON_RESUME);
                let update = built(&reflected::UPDATE);
                let resolve = built(&reflected::RESOLVE);
                let lookup_start = Instant::now();
                let lookup = Lookup::new(ctx);
                timings.push(KernelTiming {
                    name: "lookup (6 kernels)",
                    pipeline_s: lookup_start.elapsed().as_secs_f64(),
                    ..KernelTiming::default()
                });
                let (ray, t_ray) = joined(ray)?;
                let (photon, t_photon) = joined(photon)?;
                let (probe, t_probe) = joined(probe)?;
                let (gather, t_gather) = joined(gather)?;
                let kernels = Kernels {
                    ray,
                    probe,
                    photon,
                    photon_resume: photon_resume?,
                    lookup: lookup?,
                    gather,
                    update: update?,
                    resolve: resolve?,
                };
                Ok((kernels, [vec![t_ray, t_photon, t_probe, t_gather], timings].concat()))
            })
        };
        let (kernels, timings) = pipelines().device("creating the compute pipelines")?;
        setup.kernels_s = kernels_start.elapsed().as_secs_f64();
        setup.kernels = timings.into_iter().map(KernelSetup::from).collect();
        let buffers_start = Instant::now();
        let storage = |name: &str, bytes: u64| Buffer::new(ctx, name, bytes, BufferKind::Storage);
        let buffers = || -> anyhow::Result<Renderer> {
            Ok(Renderer {
                probe_report: None,
                scene_name: scene.name.clone(),
                scene_sha256: scene.content_sha256(),
                geometry_sha256: scene.geometry_sha256(),
                camera: scene.camera,
                start_params: gpu.params,
                cancel: CancelToken::new(),
                params: ctx.buffer_from("params", &[gpu.params])?,
                spheres: ctx.buffer_from("spheres", &gpu.spheres)?,
                quads: ctx.buffer_from("quads", &gpu.quads)?,
                materials: ctx.buffer_from("materials", &gpu.materials)?,
                lights: ctx.buffer_from("lights", &gpu.lights)?,
                bvh_nodes: ctx.buffer_from("BVH nodes", &gpu.bvh_nodes)?,
                // One zeroed triangle where there are none (a buffer may not be empty); never read then.
                bvh_triangles: match gpu.bvh_triangles.is_empty() {
                    true => ctx.buffer_from("BVH triangles", &[Triangle::default()])?,
                    false => ctx.buffer_from("BVH triangles", &gpu.bvh_triangles)?,
                },
                textures: ctx.buffer_from("textures", &gpu.textures)?,
                triangle_texels: ctx.buffer_from("triangle texture coordinates and normals", &gpu.triangle_texels)?,
                cut: ctx.buffer_from("path counters", &[PathCounters::default()])?,
                limits,
                hit_points: storage("hit points", slots * std::mem::size_of::<HitPoint>() as u64)?,
                stats: storage("hit stats", slots * std::mem::size_of::<HitStats>() as u64)?,
                accum: storage("pass accumulators", slots * std::mem::size_of::<PassAccum>() as u64)?,
                order: storage("hit-point order", slots * 4)?,
                tiles: make_tiles(pixels as u32, per_tile),
                direct: storage("direct emission", pixels * 32)?,
                direct_saved: storage("direct emission before the pass", pixels * 32)?,
                cut_saved: storage(
                    "path counters before the pass",
                    std::mem::size_of::<PathCounters>() as u64,
                )?,
                busy: storage("emission-sampled pixels", pixels * 4)?,
                image: storage("image", pixels * 16)?,
                counter: storage("photon counter", 4)?,
                photon_work: storage("photon work", std::mem::size_of::<PhotonWork>() as u64)?,
                suspended: storage("suspended photons", suspended_bytes)?,
                batch_log: storage("batch log", MAX_BATCHES as u64 * 4)?,
                grid: Grid::new(ctx, gpu.max_buckets(), capacity)?,
                r2_max: storage("largest radius", 8)?,
                profiler: Profiler::new(ctx, 8 + 7 * MAX_BATCHES)?,
                batch: settings.photons_per_pass.min(MAX_BATCH_PHOTONS),
                passes: 0,
                emitted: 0,
                ray_ms: 0.0,
                pilot_all: 0,
                ctx: ctx.clone(),
                settings,
                gpu,
                kernels,
                setup: SetupTimes::default(),
            })
        };
        let mut r = buffers().device("allocating the render's buffers")?;
        setup.buffers_s = buffers_start.elapsed().as_secs_f64();
        let start = Instant::now();
        r.start()?;
        setup.start_s = start.elapsed().as_secs_f64();
        r.setup = setup;
        Ok(r)
    }

    /// Starts the render from nothing with the current camera: every statistic at its initial value
    /// (eq. 8's radius, no photons), the emission sums and marks cleared, then the pilot eye pass (and its
    /// marks) and the hit-point order. `prepare` ends with it; `set_camera` runs it again.
    fn start(&mut self) -> Result<()> {
        let what = "starting the render";
        self.gpu.params = self.start_params;
        self.ctx
            .upload(&self.params, bytemuck::bytes_of(&self.gpu.params))
            .device(what)?;
        let r2 = (self.gpu.initial_radius as f64).powi(2);
        let stats_init = vec![
            HitStats {
                r2,
                ..Default::default()
            };
            self.gpu.slots() as usize
        ];
        self.ctx
            .upload(&self.stats, bytemuck::cast_slice(&stats_init))
            .device(what)?;
        drop(stats_init);
        self.ctx
            .upload(&self.cut, bytemuck::bytes_of(&PathCounters::default()))
            .device(what)?;
        (self.passes, self.emitted, self.batch, self.probe_report) =
            (0, 0, self.settings.photons_per_pass.min(MAX_BATCH_PHOTONS), None);
        self.grid.set_cells(self.gpu.params.grid_mask + 1).device(what)?;
        self.ctx
            .run(|cmd| {
                self.accum.cmd_fill(cmd, 0);
                self.direct.cmd_fill(cmd, 0);
                self.busy.cmd_fill(cmd, 0);
                Ok(())
            })
            .device(what)?;
        self.ray_ms = self.ray_pass(0, true, false)?.iter().map(|s| s.duration_ms).sum();
        self.path_counters()?;
        let (width, height) = (self.gpu.params.width, self.gpu.params.height);
        let mut busy: Vec<u32> = self.download(&self.busy, self.gpu.pixels(), "reading the pilot's marks")?;
        self.pilot_all = busy.iter().filter(|&&m| m & MARK_CHAIN != 0).count() as u32;
        // SPPM's glass splits: where a pilot chain left a curved mirror or glass, and beside it
        // (spread_marks). A flat pane's Fresnel choice is a few percent either way: splitting the
        // interior's glass rail cost 13% a pass for 4% lower error at equal passes.
        let glass_splits = self.glass_splits();
        if glass_splits {
            for m in busy.iter_mut().filter(|m| **m & MARK_CURVED != 0) {
                *m |= MARK_SPLIT;
            }
        }
        spread_marks(&mut busy, width, height);
        self.ctx
            .upload(&self.busy, bytemuck::cast_slice(&busy))
            .device("writing the pilot's marks")?;
        // The gather walks the hit points in Morton order, so neighbouring threads read the same buckets.
        // PPM's hit points never move: order them by position once, on the host. SPPM's move every pass:
        // order the pixels by their screen position, which is nearly as coherent and never changes; where
        // rough vertices split the eye paths, each slot's pixels in turn (the pixels' first slots, then
        // their second, ...), so that the slots most pixels leave empty fill whole subgroups rather than
        // idling lanes beside the live ones. Where glass splits them, only the pixels marked MARK_SPLIT
        // have slots past the first (ray.comp), and only theirs are visited: an empty slot still costs
        // lavapipe a thread of the gather and of the update (cornell-spheres' 3 more slots a pixel took
        // the gather from 129 to 279 ms a pass with none of them filled).
        let order = match self.settings.mode {
            Mode::Ppm => morton_order(&self.download(&self.hit_points, self.gpu.slots(), "reading the hit points")?),
            Mode::Sppm => {
                let pixels = pixel_order(self.gpu.params.width, self.gpu.params.height);
                let slots = self.gpu.params.hit_slots;
                let split: Vec<u32> = (pixels.iter().copied())
                    .filter(|&p| !glass_splits || busy[p as usize] & MARK_SPLIT != 0)
                    .collect();
                let first = pixels.iter().map(|&p| p * slots);
                first
                    .chain((1..slots).flat_map(|s| split.iter().map(move |&p| p * slots + s)))
                    .collect()
            }
        };
        self.set_order(order)
    }

    /// Moves the camera and starts the render again from its first pass, as a new [`Renderer`] of the
    /// scene seen from `camera` would (the same image after the same passes, bit for bit), without
    /// compiling kernels, building the BVH or uploading the scene again: for a viewer, or any embedder
    /// that moves the view. The image size must stay (a new size needs a new renderer). The error is
    /// [`Error::Scene`] naming the camera's field.
    pub fn set_camera(&mut self, camera: &Camera) -> Result<()> {
        camera.validate(&self.scene_name)?;
        let (width, height) = (self.gpu.params.width, self.gpu.params.height);
        if (camera.width, camera.height) != (width, height) {
            let message = format!(
                "must stay {width}x{height} for this renderer (a new resolution needs a new Renderer), got {}x{}",
                camera.width, camera.height
            );
            return Err(Error::scene(&self.scene_name, 0, 0, "camera.resolution", message));
        }
        crate::lower::set_camera(&mut self.start_params, camera);
        self.camera = *camera;
        self.scene_sha256 = crate::scene::camera_sha256(camera, &self.geometry_sha256);
        self.start()?;
        if self.settings.probe != ProbeMode::Off {
            self.probe_pass()?;
        }
        Ok(())
    }

    /// The camera the render is seen from (the scene's, or the last [`Renderer::set_camera`]'s).
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// Whether SPPM's eye paths split at glass in marked pixels (`Settings::splits_glass`): more than one
    /// slot a pixel, and not for a rough vertex's lobe.
    fn glass_splits(&self) -> bool {
        self.settings.mode == Mode::Sppm && self.gpu.params.hit_slots > 1 && self.gpu.params.rough_split == 0
    }

    /// The hit-point slots the gather and the update visit, in this order.
    /// Each tile's entries go from its first slot on, relative to it, in the order given.
    fn set_order(&mut self, order: Vec<u32>) -> Result<()> {
        let slots = self.gpu.params.hit_slots;
        let per_tile = (self.tiles[0].pixels * slots) as usize;
        let mut tiled = vec![0u32; self.gpu.slots() as usize];
        // Where tile k's next entry goes.
        let mut next: Vec<usize> = (0..self.tiles.len()).map(|k| k * per_tile).collect();
        for slot in order {
            let k = slot as usize / per_tile;
            tiled[next[k]] = slot - (k * per_tile) as u32;
            next[k] += 1;
        }
        for (k, tile) in self.tiles.iter_mut().enumerate() {
            tile.active = (next[k] - k * per_tile) as u32;
        }
        self.ctx
            .upload(&self.order, bytemuck::cast_slice(&tiled))
            .device("uploading the hit-point order")
    }

    /// The ray kernel's dispatches for eye pass `eye_pass` (the CPU reference, `reference::eye_pass`,
    /// takes the same): the first traces the hit points (with `trace_hits`) and as many emission samples as
    /// the loop budget lets one thread take (`PathLimits::emission_per_dispatch`), the others the rest.
    fn eye_pushes(&self, eye_pass: u32, trace_hits: bool) -> Vec<RayPush> {
        let jitter = match self.settings.mode {
            Mode::Ppm => [0.5, 0.5],
            Mode::Sppm => JITTER_RANDOM,
        };
        let pilot = eye_pass == 0;
        let (marked, unmarked) = (self.settings.emission_samples, self.settings.unmarked_samples());
        // The pilot takes up to `marked` samples in a pixel (it only marks: `pilot_samples` in every pixel,
        // the rest where those met a mirror or glass, ray.comp); other passes as many dispatches as the most
        // numerous of the counts needs.
        let total = if pilot { marked } else { self.settings.most_samples() };
        let per = self.limits.emission_per_dispatch.max(1);
        let push = |chunk: u32| RayPush {
            jitter,
            salt: SALT_EYE,
            pass: eye_pass,
            emission_samples: marked,
            trace_hits: (trace_hits && chunk == 0) as u32,
            chunk,
            pilot: pilot as u32,
            light_samples: unmarked,
            pilot_samples: self.settings.pilot_samples,
            rough_samples: self.settings.rough_pixel_samples(),
            per_dispatch: per,
            // The whole image; `ray_pass` sets each tile's.
            first_pixel: 0,
            tile_pixels: self.gpu.pixels(),
        };
        (0..total.div_ceil(per).max(1)).map(push).collect()
    }

    fn scene_buffers(&self) -> SceneBuffers<'_> {
        SceneBuffers {
            params: &self.params,
            spheres: &self.spheres,
            quads: &self.quads,
            materials: &self.materials,
            bvh_nodes: &self.bvh_nodes,
            bvh_triangles: &self.bvh_triangles,
            textures: &self.textures,
            triangle_texels: &self.triangle_texels,
        }
    }

    /// `tile`'s slots of the per-slot buffers.
    fn hit_buffers(&self, tile: &Tile) -> HitBuffers<'_> {
        let slots = self.gpu.params.hit_slots as u64;
        let (first, count) = (tile.first_pixel as u64 * slots, tile.pixels as u64 * slots);
        fn part(b: &Buffer, first: u64, count: u64, size: usize) -> BufferSlice<'_> {
            b.slice(first * size as u64, count * size as u64)
        }
        HitBuffers {
            hit_points: part(&self.hit_points, first, count, std::mem::size_of::<HitPoint>()),
            stats: part(&self.stats, first, count, std::mem::size_of::<HitStats>()),
            accum: part(&self.accum, first, count, std::mem::size_of::<PassAccum>()),
            order: part(&self.order, first, count, 4),
        }
    }

    /// Pass 1, eye pass number `eye_pass`: PPM's one pass through pixel centres, or one of SPPM's, through
    /// a random point of each pixel; with `trace_hits` false only the emission samples (PPM's later passes).
    /// With `save`, the emission sums and path counters are first copied aside, for a cancelled pass to
    /// put back (`drop_pass`).
    fn ray_pass(&mut self, eye_pass: u32, trace_hits: bool, save: bool) -> Result<Vec<ScopeTiming>> {
        self.profiler.reset();
        let pushes = self.eye_pushes(eye_pass, trace_hits);
        let tiles = &self.tiles;
        let slots = self.gpu.params.hit_slots as u64;
        let scene = self.scene_buffers();
        let (profiler, k) = (&self.profiler, &self.kernels);
        let (hit_points, direct, cut, busy, lights) =
            (&self.hit_points, &self.direct, &self.cut, &self.busy, &self.lights);
        self.ctx
            .run(|cmd| {
                if save {
                    direct.cmd_copy_to(cmd, &self.direct_saved, direct.size());
                    cut.cmd_copy_to(cmd, &self.cut_saved, cut.size());
                    barrier(&self.ctx, cmd);
                }
                profiler.scope(cmd, "ray", || {
                    for push in &pushes {
                        for t in tiles {
                            let push = RayPush {
                                first_pixel: t.first_pixel,
                                tile_pixels: t.pixels,
                                ..*push
                            };
                            let size = std::mem::size_of::<HitPoint>() as u64 * slots;
                            let hits = pixel_slice(hit_points, t, size);
                            let (direct, busy) = (pixel_slice(direct, t, 32), pixel_slice(busy, t, 4));
                            ray::record(&k.ray, cmd, &scene, hits, direct, cut, busy, lights, &push)?;
                        }
                        barrier(&self.ctx, cmd); // the next dispatch adds to the same `direct`
                    }
                    Ok(())
                })?;
                barrier(&self.ctx, cmd);
                Ok(())
            })
            .device("the eye pass")?;
        self.profiler.read().device("the eye pass")
    }

    /// Records the photon kernel `k` (the renderer's, or a variant of it) tracing photons `first..first +
    /// count` of stream family `salt` into the grid's record buffer, its counters cleared first.
    fn record_photons(
        &self,
        cmd: vk::CommandBuffer,
        k: &ComputePipeline,
        first: u64,
        count: u32,
        salt: u32,
    ) -> anyhow::Result<()> {
        self.counter.cmd_fill(cmd, 0);
        self.photon_work.cmd_fill(cmd, 0);
        barrier(&self.ctx, cmd);
        let push = PhotonPush {
            first,
            count,
            salt,
            per_thread: self.limits.per_thread,
            resume: 0,
            reserve: self.limits.photon_reserve,
            budget: self.limits.photon_first_budget,
        };
        let out = photon::PhotonOutputs {
            photons: &self.grid.records,
            counter: &self.counter,
            cut: &self.cut,
            work: &self.photon_work,
            suspended: &self.suspended,
        };
        let scene = self.scene_buffers();
        let bvh = self.gpu.traverses_bvh();
        photon::record(
            &self.ctx,
            k,
            &self.kernels.photon_resume,
            cmd,
            &scene,
            &self.lights,
            &out,
            &push,
            bvh,
        )
    }

    /// Records photon tracing, the grid build and what uses the grid (the gather, or the probe's first
    /// phase) for one batch of photons `first..first+count` (global indices).
    fn record_batch(
        &self,
        cmd: vk::CommandBuffer,
        first: u64,
        count: u32,
        log_index: u32,
        use_: GridUse,
        stages: &[BatchStage],
    ) -> anyhow::Result<()> {
        let ctx = &self.ctx;
        let k = &self.kernels;
        let salt = match use_ {
            GridUse::Gather => SALT_PHOTON,
            GridUse::Probe => SALT_PROBE,
        };
        if stages.contains(&BatchStage::Trace) {
            self.profiler.scope(cmd, "photon", || {
                self.record_photons(cmd, &k.photon, first, count, salt)
            })?;
            barrier(ctx, cmd);
            self.counter.cmd_copy(cmd, &self.batch_log, 0, log_index as u64 * 4, 4);
        }
        if stages.contains(&BatchStage::Lookup) {
            k.lookup
                .record(ctx, cmd, &self.profiler, &self.params, &self.counter, &self.grid)?;
            barrier(ctx, cmd);
        }
        if !stages.contains(&BatchStage::Gather) {
            return Ok(());
        }
        match use_ {
            GridUse::Gather => {
                self.profiler.scope(cmd, "gather", || {
                    for t in &self.tiles {
                        let push = GatherPush {
                            count: t.active,
                            cone_k: self.settings.cone_k.unwrap_or(0.0),
                        };
                        let hits = self.hit_buffers(t);
                        gather::record_gather(&k.gather, cmd, &self.params, &hits, &self.grid, &self.materials, &push)?;
                    }
                    Ok(())
                })?;
            }
            GridUse::Probe => {
                self.profiler.scope(cmd, "probe", || self.record_probe(cmd, 0))?;
            }
        }
        barrier(ctx, cmd);
        Ok(())
    }

    /// The probe kernel's phase `phase` over every tile.
    fn record_probe(&self, cmd: vk::CommandBuffer, phase: u32) -> anyhow::Result<()> {
        for t in &self.tiles {
            let push = self.probe_push(phase, t.active);
            probe::record(
                &self.kernels.probe,
                cmd,
                &self.params,
                &self.hit_buffers(t),
                &self.grid,
                &push,
            )?;
        }
        Ok(())
    }

    fn update_push(&self, count: u32) -> UpdatePush {
        UpdatePush {
            count,
            alpha: self.settings.alpha,
            flux_fixed: self.gpu.params.flux_fixed,
            shrink_z: self.settings.shrink_z,
            r2_floor: self.shrink_r2_floor(),
        }
    }

    /// The least R^2 the adaptive shrink sets: `SHRINK_FLOOR` of the starting radius, squared.
    pub fn shrink_r2_floor(&self) -> f32 {
        (self.gpu.initial_radius * SHRINK_FLOOR).powi(2)
    }

    fn probe_push(&self, phase: u32, count: u32) -> ProbePush {
        let (mode, param) = match self.settings.probe {
            ProbeMode::Paper => (MODE_PAPER, self.settings.probe_beta),
            ProbeMode::Nearest => (MODE_NEAREST, self.settings.probe_k),
            ProbeMode::Curvature => (MODE_CURVATURE, self.settings.probe_grow),
            _ => (MODE_SCALE_FREE, self.settings.probe_beta),
        };
        ProbePush {
            count,
            phase,
            mode,
            param,
        }
    }

    /// Traces `total` photons from global index `first` and feeds each batch's grid to `use_`, in as few
    /// batches as fit the record buffer and keep every lookup within the device's loop budget. On overflow
    /// or a cut lookup, clears the accumulators and goes again in smaller batches: the same photons, since
    /// streams are by global index. Returns the GPU stages, the records
    /// and the batch count.
    fn run_batches(&mut self, first: u64, total: u32, use_: GridUse) -> Result<(Vec<ScopeTiming>, u64, u32)> {
        let capacity = self.gpu.params.photon_capacity as u64;
        loop {
            let batches = total.div_ceil(self.batch);
            if batches > MAX_BATCHES {
                let what = "photon batches in one pass (the scene leaves too many records per photon)";
                return Err(Error::limit(
                    what,
                    Some(batches as u64),
                    MAX_BATCHES as u64,
                    "the photons per pass",
                ));
            }
            self.profiler.reset();
            let batch = self.batch;
            let split = self.settings.split_submissions && use_ == GridUse::Gather;
            // One submission a batch (a stage, split), the cancel checked between them; the probe pass
            // is never cancelled halfway (its radii would be half probed).
            let stages: Vec<&[BatchStage]> = match split {
                false => vec![ALL_STAGES],
                true => ALL_STAGES.iter().map(std::slice::from_ref).collect(),
            };
            for b in 0..batches {
                let start = b * batch;
                let count = batch.min(total - start);
                for stage in &stages {
                    // The caller sees the cancel and drops what the batches summed.
                    if use_ == GridUse::Gather && self.cancel.is_cancelled() {
                        return Ok((Vec::new(), 0, b));
                    }
                    self.ctx
                        .run(|cmd| self.record_batch(cmd, first + start as u64, count, b, use_, stage))
                        .device("a photon pass")?;
                }
            }
            let log: Vec<u32> = self
                .ctx
                .download_prefix(&self.batch_log, batches as usize)
                .device("a photon pass")?;
            let overflow = log.iter().any(|&n| n as u64 > capacity);
            let cut = self.lookups_cut()?;
            if !overflow && !cut {
                return Ok((
                    self.profiler.read().device("a photon pass")?,
                    log.iter().map(|&n| n as u64).sum(),
                    batches,
                ));
            }
            if self.batch == 1 {
                return Err(match overflow {
                    true => Error::limit(
                        "the records one photon left",
                        None,
                        capacity,
                        "the photon depth (max_photon_depth)",
                    ),
                    // One photon's batch still cut: the cells a lookup spans are too many, which only a
                    // fixed `grid_cell` far below the radii can do (the renderer's own cells follow them).
                    false => Error::limit(
                        "a photon lookup was cut short at the device's limit on loop iterations per SIMD group \
                         even with one photon per batch (the grid cells one subgroup reads are too many)",
                        None,
                        self.ctx.info().loop_budget.unwrap_or(0) as u64,
                        "the radius or raise the grid cell size",
                    ),
                });
            }
            // Records past the buffer, or a lookup that may have stopped at lavapipe's loop budget: go
            // again in halves. Half the photons per batch put half as many in the cells a subgroup reads,
            // so the gather and the probe are split across dispatches rather than refused; the same
            // photons, and fixed-point sums, so the same image bit for bit.
            self.batch = self.batch.div_ceil(2);
            self.ctx
                .run(|cmd| {
                    self.accum.cmd_fill(cmd, 0);
                    Ok(())
                })
                .device("a photon pass")?;
        }
    }

    /// Whether a gather or probe lookup of the batches just run may have stopped early (lavapipe ends every
    /// loop of a SIMD group after 65535 iterations in all, and a cut lookup would silently lose photons);
    /// clears the flag for the next try.
    fn lookups_cut(&self) -> Result<bool> {
        let status: Vec<u32> = self
            .ctx
            .download_prefix(&self.grid.status, 1)
            .device("reading the lookup status")?;
        if status[0] == 0 {
            return Ok(false);
        }
        self.ctx
            .run(|cmd| {
                self.grid.status.cmd_fill(cmd, 0);
                Ok(())
            })
            .device("clearing the lookup status")?;
        Ok(true)
    }

    /// Pass 2, once: photon probing sets each hit point's starting radius (eq. 7-9).
    fn probe_pass(&mut self) -> Result<()> {
        let photons = self.settings.probe_photons.unwrap_or(self.settings.photons_per_pass);
        // The probe's lookups may read far more photons than the gather's (out to 2 r for the curvature
        // rule): where they halve the batches to stay within the loop budget, the passes after it start
        // again from the batch size before it (they halve it themselves if they need to).
        let gather_batch = self.batch;
        let probed = self.run_batches(0, photons, GridUse::Probe);
        self.batch = gather_batch;
        let (mut stages, _, _) = probed?;
        self.profiler.reset();
        self.ctx
            .run(|cmd| self.profiler.scope(cmd, "probe", || self.record_probe(cmd, 1)))
            .device("the probe pass")?;
        stages.extend(self.profiler.read().device("the probe pass")?);
        let gpu_ms = stages.iter().map(|s| s.duration_ms).sum();
        let stats: Vec<HitStats> = self.download(&self.stats, self.gpu.slots(), "reading the probe's radii")?;
        let hits: Vec<HitPoint> = self.download(&self.hit_points, self.gpu.slots(), "reading the hit points")?;
        self.probe_report = Some(ProbeReport::new(
            &stats,
            &hits,
            self.gpu.initial_radius,
            photons,
            gpu_ms,
        ));
        // The largest radius as the update would report it (as f32, the lookups' precision).
        let radius_max = RadiusMax {
            live: stats
                .iter()
                .zip(&hits)
                .filter(|(_, h)| !h.is_empty())
                .map(|(s, _)| s.r2 as f32)
                .fold(0.0, f32::max),
            all: stats.iter().map(|s| s.r2 as f32).fold(0.0, f32::max),
        };
        self.fit_grid(radius_max)
    }

    /// Sizes the photon grid's cells for the next pass from the largest radii after this one. Which
    /// photons a lookup finds does not depend on the cell size (the image is the same bit for bit); its
    /// cost does. Cells of [`CELL_PER_RADIUS`] times the largest live radius keep every live hit point's
    /// lookup within 3x3x3 cells, and follow the radii as they shrink (eq. 3), so a lookup reads ever
    /// fewer photons outside its sphere. An SPPM slot not live this pass may be larger when it next is:
    /// its window is then wider, but covers the area a window sized for it would, so it reads no more
    /// photons; cells sized for at least 1/8 of the largest radius of any slot bound its window to
    /// 2 * 8 / 1.5 + 1 < 12 cells a side, within the loop budget and the 1024-cell range of a cell key
    /// (grid.glsl).
    fn fit_grid(&mut self, max: RadiusMax) -> Result<()> {
        let r2 = max.live.max(max.all / 64.0);
        let cell = CELL_PER_RADIUS * r2.sqrt() * (1.0 + f32::EPSILON * 4.0);
        if let Some(c) = self.settings.grid_cell {
            // A set cell size must keep lookups under 1024 cells a side (grid_key in grid.glsl).
            let widest = 2.0 * max.all.sqrt();
            if widest > 512.0 * c {
                let message = format!("{c} is under 1/512 of twice the largest search radius ({widest})");
                return Err(Error::Settings {
                    field: "grid_cell",
                    message,
                });
            }
            return Ok(());
        }
        self.use_cell(cell)
    }

    /// Gives the photon grid cells of size `cell` from the next batch on.
    fn use_cell(&mut self, cell: f32) -> Result<()> {
        if !(cell.is_finite() && cell > 0.0) || cell == self.gpu.params.cell_size {
            return Ok(());
        }
        self.gpu.set_grid_cell(cell, self.gpu.params.photon_capacity);
        self.grid
            .set_cells(self.gpu.params.grid_mask + 1)
            .device("resizing the photon grid")?;
        self.ctx
            .upload(&self.params, bytemuck::bytes_of(&self.gpu.params))
            .device("resizing the photon grid")
    }

    /// One photon pass: `photons_per_pass` photons traced and gathered, then the progressive update.
    /// Returns [`Error::Cancelled`] if the renderer's [`CancelToken`] is set before the pass or between
    /// its submissions (the eye pass, the photon batches, the update); a cancelled pass leaves the
    /// estimate as the passes before it left it.
    pub fn pass(&mut self) -> Result<PassStats> {
        self.check_cancel()?;
        let start = Instant::now();
        let total = self.settings.photons_per_pass;
        // SPPM traces new hit points before every photon pass but the first, which uses the eye pass the
        // renderer was made with (and probed).
        // PPM keeps its hit points; an eye pass per photon pass adds emission samples (eye pass 0, in
        // `new`, was the pilot that only marks the pixels needing them: ray.comp).
        let eye_pass = match self.settings.mode {
            Mode::Sppm => (self.passes > 0).then_some((self.passes as u32, true)),
            Mode::Ppm => (self.settings.emission_samples > 0).then_some((self.passes as u32 + 1, false)),
        };
        let mut stages = Vec::new();
        if let Some((index, trace_hits)) = eye_pass {
            stages = self.ray_pass(index, trace_hits, true)?;
        }
        if self.cancel.is_cancelled() {
            return Err(self.drop_pass(eye_pass.is_some()));
        }
        let (batch_stages, records, batches) = self.run_batches(self.emitted, total, GridUse::Gather)?;
        stages.extend(batch_stages);
        if self.cancel.is_cancelled() {
            return Err(self.drop_pass(eye_pass.is_some()));
        }
        // The update in its own submission, so an overflowed try above never touches the statistics.
        self.profiler.reset();
        self.ctx
            .run(|cmd| self.profiler.scope(cmd, "update", || self.record_update(cmd)))
            .device("the photon pass")?;
        stages.extend(self.profiler.read().device("the photon pass")?);
        self.passes += 1;
        self.emitted += total as u64;
        let cut = self.path_counters()?;
        let radius_max = self.radius_max()?;
        self.fit_grid(radius_max)?;
        Ok(PassStats {
            index: self.passes,
            photons: total as u64,
            emitted_total: self.emitted,
            records,
            batches,
            photon_paths_cut: cut.photon_paths as u64,
            eye_paths_cut: cut.eye_paths as u64,
            photons_capped: cut.capped as u64,
            radius_max: radius_max.live.sqrt(),
            cell_size: self.gpu.params.cell_size,
            wall_ms: start.elapsed().as_secs_f64() * 1e3,
            stages,
        })
    }

    /// The per-slot statistics and per-pixel emission sums as [`Renderer::new`] left them: every
    /// probabilistic pass starts from those radii (the probe's, if on), and the sums are the pilot eye
    /// pass's samples, which belong to pass 0 (`crate::distributed`).
    pub(crate) fn start_state(&self) -> Result<(Vec<HitStats>, Vec<[f64; 4]>)> {
        let stats = self.download(&self.stats, self.gpu.slots(), "reading the starting radii")?;
        let direct = self.download(&self.direct, self.gpu.pixels(), "reading the pilot's emission samples")?;
        Ok((stats, direct))
    }

    /// Photon pass `index` of probabilistic PPM (Knaus and Zwicker 2011) on its own: every slot starts
    /// from `start` (see [`Renderer::start_state`]) with its R^2 times `r2_scale` and nothing gathered, the
    /// pass's eye and photon streams are those of pass `index` of a render, and the pass's estimate is
    /// read back: per pixel the photons' radiance (eq. 1-2 with this pass's photons only) and the
    /// emission samples' sum and count. A pass depends only on `index` and `r2_scale`, never on the
    /// passes run before it, so workers that split the passes between them compute the same numbers.
    /// SPPM's pass 0 uses the hit points of the pilot eye pass: it must be the renderer's first.
    pub(crate) fn probabilistic_pass(
        &mut self,
        index: u64,
        start: &[HitStats],
        r2_scale: f64,
    ) -> Result<(PassStats, PassEstimate)> {
        let what = "a probabilistic pass";
        if self.settings.mode == Mode::Sppm && index == 0 && self.passes != 0 {
            let message = "SPPM's pass 0 must be the renderer's first (it uses the pilot's hit points)".into();
            return Err(Error::Settings {
                field: "passes",
                message,
            });
        }
        let per_pass = self.settings.photons_per_pass as u64;
        let emitted = index.checked_mul(per_pass).filter(|_| index < checkpoint::MAX_PASSES);
        let Some(emitted) = emitted else {
            let message = format!(
                "pass {index} is past the last a render may have ({})",
                checkpoint::MAX_PASSES
            );
            return Err(Error::Settings {
                field: "passes",
                message,
            });
        };
        let stats: Vec<HitStats> = start
            .iter()
            .map(|s| HitStats {
                n: 0.0,
                r2: s.r2 * r2_scale,
                tau_r: 0.0,
                tau_g: 0.0,
                tau_b: 0.0,
                probe: s.probe,
                ..Default::default()
            })
            .collect();
        self.ctx
            .upload(&self.stats, bytemuck::cast_slice(&stats))
            .device(what)?;
        self.ctx
            .run(|cmd| {
                self.direct.cmd_fill(cmd, 0);
                Ok(())
            })
            .device(what)?;
        // Cells for this pass's radii (the update shrank the last pass's below them).
        let largest = stats.iter().map(|s| s.r2 as f32).fold(0.0, f32::max);
        self.fit_grid(RadiusMax {
            live: largest,
            all: largest,
        })?;
        (self.passes, self.emitted) = (index, emitted);
        let pass = self.pass()?;
        // The update scaled tau and R^2 by the same ratio: tau / R^2 is this pass's flux over its radius.
        let stats: Vec<HitStats> = self.download(&self.stats, self.gpu.slots(), what)?;
        let direct: Vec<[f64; 4]> = self.download(&self.direct, self.gpu.pixels(), what)?;
        let slots = self.gpu.params.hit_slots as usize;
        let norm = self.settings.cone_norm() as f64 * std::f64::consts::PI * per_pass as f64;
        let photons = stats
            .chunks_exact(slots)
            .map(|pixel| {
                pixel.iter().fold([0.0; 3], |sum, s| {
                    let area = norm * s.r2;
                    [
                        sum[0] + s.tau_r / area,
                        sum[1] + s.tau_g / area,
                        sum[2] + s.tau_b / area,
                    ]
                })
            })
            .collect();
        Ok((pass, PassEstimate { photons, direct }))
    }

    /// Undoes a cancelled pass: the photon batches' sums wait in the pass accumulators for the update, and
    /// its eye pass (if it ran) added to the emission sums and path counters. Returns the error to give,
    /// [`Error::Cancelled`] unless undoing failed.
    fn drop_pass(&self, eye_pass: bool) -> Error {
        let undone = self.ctx.run(|cmd| {
            self.accum.cmd_fill(cmd, 0);
            if eye_pass {
                self.direct_saved.cmd_copy_to(cmd, &self.direct, self.direct.size());
                self.cut_saved.cmd_copy_to(cmd, &self.cut, self.cut.size());
            }
            barrier(&self.ctx, cmd);
            Ok(())
        });
        match undone.device("cancelling the photon pass") {
            Ok(()) => Error::Cancelled,
            Err(e) => e,
        }
    }

    /// Makes `token` the one [`Renderer::pass`] checks (the renderer starts with one of its own).
    pub fn set_cancel(&mut self, token: CancelToken) {
        self.cancel = token;
    }

    /// The token [`Renderer::pass`] checks: cancel a clone of it from another thread.
    pub fn cancel_token(&self) -> CancelToken {
        self.cancel.clone()
    }

    fn check_cancel(&self) -> Result<()> {
        match self.cancel.is_cancelled() {
            true => Err(Error::Cancelled),
            false => Ok(()),
        }
    }

    /// Resolves the current estimate into an image buffer on the device (eq. 1-2) and returns its GPU time.
    pub fn resolve(&mut self) -> Result<f64> {
        self.profiler.reset();
        let (profiler, k) = (&self.profiler, &self.kernels);
        let (params, stats, direct, image) = (&self.params, &self.stats, &self.direct, &self.image);
        let stats_size = std::mem::size_of::<HitStats>() as u64 * self.gpu.params.hit_slots as u64;
        self.ctx
            .run(|cmd| {
                profiler.scope(cmd, "resolve", || {
                    for t in &self.tiles {
                        let push = ResolvePush {
                            emitted: self.emitted as f64,
                            norm: self.settings.cone_norm(),
                            tile_pixels: t.pixels,
                        };
                        let (stats, direct) = (pixel_slice(stats, t, stats_size), pixel_slice(direct, t, 32));
                        let image = pixel_slice(image, t, 16);
                        resolve::record(&k.resolve, cmd, params, stats, direct, image, &push)?;
                    }
                    Ok(())
                })?;
                barrier(&self.ctx, cmd);
                Ok(())
            })
            .device("the resolve")?;
        Ok(self
            .profiler
            .read()
            .device("the resolve")?
            .iter()
            .map(|s| s.duration_ms)
            .sum())
    }

    /// The buffer [`Renderer::resolve`] writes the image to: linear RGBA f32 per pixel, rows top first.
    pub(crate) fn image_buffer(&self) -> &Buffer {
        &self.image
    }

    /// The current image (resolves, then reads it back).
    pub fn image(&mut self) -> Result<RgbImage> {
        self.resolve()?;
        let rgba: Vec<[f32; 4]> = self.ctx.download(&self.image).device("reading the image back")?;
        RgbImage::from_rgba(
            self.gpu.params.width,
            self.gpu.params.height,
            &rgba[..self.gpu.pixels() as usize],
        )
        .device("reading the image back")
    }

    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// Where this renderer's set-up went: the scene lowered, the kernels compiled, the buffers, the
    /// pilot eye pass and the probe pass.
    pub fn setup_times(&self) -> &SetupTimes {
        &self.setup
    }

    /// What the BVH build over the scene's triangles made (all zero without triangles).
    pub fn bvh_stats(&self) -> &crate::BvhStats {
        &self.gpu.bvh_stats
    }

    /// Device bytes of the scene's BVH (nodes and triangles).
    pub fn bvh_bytes(&self) -> usize {
        self.gpu.bvh_bytes()
    }

    /// Hit-point slots: pixels times hit points per pixel.
    pub fn hit_point_slots(&self) -> u32 {
        self.gpu.slots()
    }

    /// The starting radius of every hit point before the probe (eq. 8, or `Settings::initial_radius`).
    pub fn initial_radius(&self) -> f32 {
        self.gpu.initial_radius
    }

    pub fn context(&self) -> &Context {
        &self.ctx
    }

    /// Photon passes done.
    pub fn passes(&self) -> u64 {
        self.passes
    }

    /// Photons emitted by all passes (64-bit: the paper's 2.25 billion do not fit 31 bits).
    pub fn emitted(&self) -> u64 {
        self.emitted
    }

    /// What the probe pass did, if it ran.
    pub fn probe_report(&self) -> Option<&ProbeReport> {
        self.probe_report.as_ref()
    }

    /// What the pilot eye pass marked (read back from the device).
    pub fn pilot_marks(&self) -> anyhow::Result<PilotMarks> {
        Ok(PilotMarks {
            pilot_all: self.pilot_all,
            ..PilotMarks::new(&self.marks()?)
        })
    }

    /// The pilot's marks per pixel, row by row (ray.comp's `busy`, spread to the neighbours), read back
    /// from the device: what decides each pixel's emission and light samples (`reference::samples_for_mark`).
    pub fn marks(&self) -> anyhow::Result<Vec<u32>> {
        Ok(self.download(&self.busy, self.gpu.pixels(), "reading the pilot's marks")?)
    }

    /// GPU time of the ray pass, in milliseconds.
    pub fn ray_ms(&self) -> f64 {
        self.ray_ms
    }

    /// Non-empty hit-point slots (the hit points the gather visits).
    pub fn active_hit_points(&self) -> u32 {
        self.tiles.iter().map(|t| t.active).sum()
    }

    /// The tiles the kernels bind the per-pixel buffers in ([`Tile`]): 1 wherever every per-pixel buffer
    /// fits one binding.
    pub fn tile_count(&self) -> usize {
        self.tiles.len()
    }

    /// The depth backstops and photons per thread this render uses.
    pub fn path_limits(&self) -> PathLimits {
        self.limits
    }

    /// Paths cut at the depth backstops so far (photon passes including the probe's, and eye passes).
    /// Fails if a BVH traversal ran out of the device's loop budget: its hit, and so the image, would be
    /// wrong.
    pub fn path_counters(&self) -> Result<PathCounters> {
        let c: Vec<PathCounters> = self
            .ctx
            .download_prefix(&self.cut, 1)
            .device("reading the path counters")?;
        if c[0].traversal_cut > 0 {
            let what = format!(
                "{} ray(s) through the triangle BVH were stopped at the device's limit on loop iterations per \
                 SIMD group (this render leaves photon threads {} and eye threads {} traversal steps)",
                c[0].traversal_cut, self.limits.photon_bvh_budget, self.limits.eye_bvh_budget
            );
            let lower = "the overlap of the scene's triangles (degenerate or duplicated geometry?)";
            return Err(Error::limit(
                what,
                None,
                self.ctx.info().loop_budget.unwrap_or(0) as u64,
                lower,
            ));
        }
        Ok(c[0])
    }

    /// Times the photon kernel as this render uses it against variants of itself with parts removed
    /// (photon.comp: no record stores, no append, trace only), each over the same first `photons`
    /// photons, and counts the intersections each traces (an untimed run of each). For `ppm-vk bench`:
    /// the trace-only variant is this design's ceiling. The render's state is left as it was.
    pub fn photon_breakdown(&mut self, photons: u32) -> Result<Vec<PhotonVariant>> {
        self.photon_variants(photons)
            .device("timing the photon kernel's variants")
    }

    fn photon_variants(&mut self, photons: u32) -> anyhow::Result<Vec<PhotonVariant>> {
        let saved: Vec<PathCounters> = self.ctx.download_prefix(&self.cut, 1)?;
        let photons = photons.min(self.batch); // one batch: the records must fit
        let constants = trace_constants(&self.gpu, &self.settings);
        let variant = |r: &Self, defines: &[(&str, &str)]| {
            tracing_pipeline(&r.ctx, constants.as_deref(), &reflected::PHOTON, defines).map(|(k, _)| k)
        };
        // One dispatch over the counters cleared; its GPU milliseconds.
        let dispatch = |r: &Self, k: &ComputePipeline| -> anyhow::Result<f64> {
            r.ctx.upload(&r.cut, bytemuck::bytes_of(&PathCounters::default()))?;
            r.profiler.reset();
            r.ctx.run(|cmd| {
                r.profiler
                    .scope(cmd, "photon", || r.record_photons(cmd, k, 0, photons, SALT_PHOTON))
            })?;
            Ok(r.profiler.read()?.iter().map(|s| s.duration_ms).sum())
        };
        // Twice, timing the second: lavapipe compiles a pipeline at its first dispatch.
        let time = |r: &Self, defines: &[(&str, &str)]| -> anyhow::Result<f64> {
            let k = variant(r, defines)?;
            dispatch(r, &k)?;
            dispatch(r, &k)
        };
        // The intersections the variant traces, from a build of it that counts them (untimed).
        let count = |r: &Self, defines: &[(&str, &str)]| -> anyhow::Result<u64> {
            dispatch(r, &variant(r, &[defines, &[("PHOTON_COUNT_STEPS", "1")]].concat())?)?;
            Ok(r.ctx.download_prefix::<PathCounters>(&r.cut, 1)?[0].capped as u64)
        };
        let full_steps = count(self, &[])?;
        // Trace-only paths as long as the real ones on average, so both amortise a path's start alike.
        let segments = ((full_steps as f64 / photons as f64).round() as u32)
            .clamp(1, self.limits.photon_depth)
            .to_string();
        let mut out = Vec::new();
        for (name, defines) in [
            ("as rendered", vec![]),
            ("no record stores", vec![("PHOTON_NO_STORE", "1")]),
            ("no append", vec![("PHOTON_NO_APPEND", "1")]),
            ("trace only", vec![("PHOTON_TRACE_ONLY", segments.as_str())]),
        ] {
            let gpu_ms = time(self, &defines)?;
            let steps = if defines.is_empty() {
                full_steps
            } else {
                count(self, &defines)?
            };
            out.push(PhotonVariant {
                name,
                photons,
                gpu_ms,
                steps,
            });
        }
        self.ctx.upload(&self.cut, bytemuck::cast_slice(&saved))?;
        Ok(out)
    }

    /// The largest R^2 the last update saw (see `update.comp`), as the lookups read it (f32).
    pub fn radius_max(&self) -> Result<RadiusMax> {
        let bits: Vec<u32> = self.download(&self.r2_max, 2, "reading the largest radius")?;
        Ok(RadiusMax::from_bits([bits[0], bits[1]]))
    }

    /// Records the update (eq. 3, 6, 14) and the reduction to the largest radius after it.
    fn record_update(&self, cmd: vk::CommandBuffer) -> anyhow::Result<()> {
        self.r2_max.cmd_fill(cmd, 0);
        barrier(&self.ctx, cmd);
        for t in &self.tiles {
            let push = self.update_push(t.active);
            update::record_update(&self.kernels.update, cmd, &self.hit_buffers(t), &self.r2_max, &push)?;
        }
        barrier(&self.ctx, cmd);
        Ok(())
    }

    /// A device buffer's first `count` records (waits for the device).
    fn download<T: bytemuck::Pod>(&self, buffer: &Buffer, count: u32, what: &str) -> Result<Vec<T>> {
        self.ctx.download_prefix(buffer, count as usize).device(what)
    }
}

/// Hooks into device state for the tests (feature `test-hooks`): read-backs, overwrites and single
/// stages. Each waits for the device.
#[cfg(feature = "test-hooks")]
impl Renderer {
    /// The flattened scene and render constants the kernels use.
    pub fn gpu_scene(&self) -> &GpuScene {
        &self.gpu
    }

    /// Sets the loop steps a subgroup's lookups may take before they count as cut short
    /// (`RenderParams::lookup_limit`), as on a device with that loop budget; 0: every lookup counts as cut.
    pub fn set_lookup_limit(&mut self, steps: u32) -> anyhow::Result<()> {
        self.gpu.params.lookup_limit = steps;
        self.ctx.upload(&self.params, bytemuck::bytes_of(&self.gpu.params))
    }

    /// Photons per batch the passes currently use.
    pub fn batch_size(&self) -> u32 {
        self.batch
    }

    /// The ray kernel's dispatches for eye pass `eye_pass` (see `eye_pushes`).
    pub fn ray_pushes(&self, eye_pass: u32, trace_hits: bool) -> Vec<RayPush> {
        self.eye_pushes(eye_pass, trace_hits)
    }

    pub fn read_hit_points(&self) -> anyhow::Result<Vec<HitPoint>> {
        self.ctx.download_prefix(&self.hit_points, self.gpu.slots() as usize)
    }

    pub fn read_stats(&self) -> anyhow::Result<Vec<HitStats>> {
        self.ctx.download_prefix(&self.stats, self.gpu.slots() as usize)
    }

    pub fn read_accum(&self) -> anyhow::Result<Vec<PassAccum>> {
        self.ctx.download_prefix(&self.accum, self.gpu.slots() as usize)
    }

    /// Per pixel, 1 where the pilot eye pass marked it for all its emission samples.
    pub fn read_busy(&self) -> anyhow::Result<Vec<u32>> {
        self.ctx.download_prefix(&self.busy, self.gpu.pixels() as usize)
    }

    /// Per pixel: the emission samples' sum (rgb) and count (w).
    pub fn read_direct(&self) -> anyhow::Result<Vec<[f64; 4]>> {
        self.ctx.download_prefix(&self.direct, self.gpu.pixels() as usize)
    }

    /// Overwrites the per-hit-point statistics (tests start counters near their limits this way).
    pub fn write_stats(&self, stats: &[HitStats]) -> anyhow::Result<()> {
        if stats.len() != self.gpu.slots() as usize {
            anyhow::bail!("write_stats: {} entries for {} slots", stats.len(), self.gpu.slots());
        }
        self.ctx.upload(&self.stats, bytemuck::cast_slice(stats))
    }

    /// Overwrites the pass accumulators (tests feed the update chosen inputs this way).
    pub fn write_accum(&self, accum: &[PassAccum]) -> anyhow::Result<()> {
        if accum.len() != self.gpu.slots() as usize {
            anyhow::bail!("write_accum: {} entries for {} slots", accum.len(), self.gpu.slots());
        }
        self.ctx.upload(&self.accum, bytemuck::cast_slice(accum))
    }

    /// Traces and gathers one batch of photons with global indices `first..first+count` without the
    /// update, and returns the batch's records, grouped by grid bucket (the pass accumulators keep the
    /// gathered sums).
    pub fn trace_and_gather(&mut self, first: u64, count: u32) -> anyhow::Result<Vec<Photon>> {
        self.trace_batch(first, count, GridUse::Gather)
    }

    /// Traces one batch of probe photons (the probe's random streams) and runs the probe's first phase
    /// (per hit point N and the sum of d^2 / r^2 into the pass accumulators) without setting radii;
    /// returns the batch's records. `finish_probe` sets the radii (eq. 9).
    pub fn trace_and_probe(&mut self, first: u64, count: u32) -> anyhow::Result<Vec<Photon>> {
        self.trace_batch(first, count, GridUse::Probe)
    }

    /// The probe's second phase: lambda (eq. 7) and the starting radii (eq. 9) from the accumulators.
    pub fn finish_probe(&mut self) -> anyhow::Result<()> {
        self.ctx.run(|cmd| self.record_probe(cmd, 1))
    }

    fn trace_batch(&mut self, first: u64, count: u32, use_: GridUse) -> anyhow::Result<Vec<Photon>> {
        self.profiler.reset();
        self.ctx
            .run(|cmd| self.record_batch(cmd, first, count, 0, use_, ALL_STAGES))?;
        let n: Vec<u32> = self.ctx.download_prefix(&self.counter, 1)?;
        if self.lookups_cut()? {
            anyhow::bail!("a test batch of {count} photons had a lookup cut short at the device's loop budget");
        }
        self.path_counters()?;
        if n[0] > self.gpu.params.photon_capacity {
            anyhow::bail!(
                "a test batch of {count} photons left {} records, over the capacity {}",
                n[0],
                self.gpu.params.photon_capacity
            );
        }
        self.ctx.download_prefix(&self.grid.records, n[0] as usize)
    }

    /// Runs the update kernel alone (after `trace_and_gather`).
    pub fn update_only(&mut self) -> anyhow::Result<()> {
        self.ctx.run(|cmd| self.record_update(cmd))
    }

    /// Sets the emitted-photon total the resolve divides by (tests start it near 2^32 this way).
    pub fn set_emitted(&mut self, emitted: u64) {
        self.emitted = emitted;
    }

    /// Sets a BVH scene's photon threads' first-round budget and reserve (`PathLimits`), so that photons
    /// are suspended and left to the resume round.
    pub fn set_photon_round(&mut self, first_budget: u32, reserve: u32) {
        self.limits.photon_first_budget = first_budget;
        self.limits.photon_reserve = reserve;
    }

    /// The last photon batch's work counters (`PhotonWork`: photons started and suspended).
    pub fn read_photon_work(&self) -> anyhow::Result<ppm_vk_kernels::layout::PhotonWork> {
        Ok(self.ctx.download_prefix(&self.photon_work, 1)?[0])
    }
}

/// Marks the 8 neighbours of every marked pixel of a `width` x `height` image (row-major, nonzero:
/// marked). The pilot eye pass marks the pixels where one of its emission samples met an emitter; a pixel
/// an edge of the light (or of its image in a mirror or glass) only clips may have had none, and its
/// neighbour inside the edge did. The marks choose sample counts before those samples are drawn, so the
/// estimate stays unbiased whatever they are (ray.comp); they only move where the samples go.
pub fn spread_marks(marks: &mut [u32], width: u32, height: u32) {
    let (w, h) = (width as usize, height as usize);
    // The pilot's own marks, taken before any is added: the spread does not chain. Each kind of mark
    // (reference::MARK_EMISSION, MARK_LIT, MARK_ROUGH, MARK_NEAR, MARK_SPLIT) spreads on its own;
    // MARK_CHAIN and MARK_CURVED, the pilot's notes to itself, are dropped.
    for m in marks.iter_mut() {
        *m &= !(MARK_CHAIN | MARK_CURVED);
    }
    let seeds: Vec<(usize, u32)> = (0..marks.len())
        .filter(|&i| marks[i] != 0)
        .map(|i| (i, marks[i]))
        .collect();
    for (i, mark) in seeds {
        let (x, y) = (i % w, i / w);
        for yy in y.saturating_sub(1)..=(y + 1).min(h - 1) {
            for xx in x.saturating_sub(1)..=(x + 1).min(w - 1) {
                marks[yy * w + xx] |= mark;
            }
        }
    }
}

/// The scene as GLSL constants for the tracing kernels (see specialize.rs), or `None` where it is too big
/// to inline (or specialising is off): then they read it from buffers.
fn trace_constants(gpu: &GpuScene, settings: &Settings) -> Option<String> {
    let inline = settings.specialize && gpu.spheres.len() + gpu.quads.len() <= MAX_INLINE_PRIMITIVES;
    inline.then(|| {
        specialize::scene_constants(&SceneConstants {
            spheres: &gpu.spheres,
            quads: &gpu.quads,
            triangles: &gpu.bvh_triangles,
            inline_triangles: gpu.triangles_inline,
            pairs: &gpu.inline_pairs,
            singles: &gpu.inline_singles,
            lights: &gpu.lights,
            surfaces: gpu.materials.iter().fold(0, |bits, m| bits | 1 << m.surface),
            textures: gpu
                .materials
                .iter()
                .any(|m| m.texture != 0 || m.specular_texture != 0 || m.alpha_texture != 0 || m.emission_texture != 0),
            parameter_textures: gpu
                .materials
                .iter()
                .any(|m| m.specular_texture != 0 || m.alpha_texture != 0),
            emission_textures: gpu.materials.iter().any(|m| m.emission_texture != 0),
            rough_plastics: gpu.materials.iter().any(|m| m.table != 0),
            microfacets: gpu
                .materials
                .iter()
                .filter(|m| m.is_rough())
                .fold(0, |bits, m| bits | 1 << m.distribution),
            shading_normals: gpu.smooth_shading(),
            anisotropic: gpu.materials.iter().any(|m| m.alpha_u != m.alpha_v),
            normal_maps: gpu.materials.iter().any(|m| m.normal_map != 0),
            masks: gpu.materials.iter().any(|m| m.opacity != 0),
            targets: gpu.params.num_targets > 0,
            light_kinds: gpu.light_kinds,
        })
    })
}

/// A tracing kernel (ray or photon) with `defines` added to its source: compiled with `constants`
/// ([`trace_constants`]) where there are some, else with the scene in buffers.
fn tracing_pipeline(
    ctx: &Context,
    constants: Option<&str>,
    k: &reflected::KernelInfo,
    defines: &[(&str, &str)],
) -> anyhow::Result<(ComputePipeline, KernelTiming)> {
    match constants {
        Some(constants) => {
            let defines = [&[("SCENE_CONSTANTS", "1")][..], defines].concat();
            specialize::build(ctx, k, &defines, constants)
        }
        None => specialize::build(ctx, k, defines, ""),
    }
}

/// Fails, saying what to lower, unless all the buffers fit the device's memory (`memory` bytes; 0:
/// unknown, not checked). `per_pixel` grow with the image (`advice` says how to shrink them), and are
/// bound in tiles ([`Tile`]), so none is limited to one binding.
fn fits_device(per_pixel: &[(&str, u64)], others: &[(&str, u64)], memory: u64, advice: &str) -> Result<()> {
    let total: u64 = per_pixel.iter().chain(others).map(|(_, b)| b).sum();
    if memory > 0 && total > memory {
        let list: Vec<String> = per_pixel
            .iter()
            .chain(others)
            .map(|(w, b)| format!("{w} {} MiB", b >> 20))
            .collect();
        let what = format!("the render's device memory ({} MiB: {})", total >> 20, list.join(", "));
        return Err(Error::limit(
            what,
            Some(total),
            memory,
            format!("{advice}, or --photons-per-pass"),
        ));
    }
    Ok(())
}

/// `tile`'s part of a per-pixel buffer of `size` bytes a pixel.
fn pixel_slice<'a>(buffer: &'a Buffer, tile: &Tile, size: u64) -> BufferSlice<'a> {
    buffer.slice(tile.first_pixel as u64 * size, tile.pixels as u64 * size)
}

/// Every pixel, in Morton order of its (x, y).
fn pixel_order(width: u32, height: u32) -> Vec<u32> {
    fn spread(v: u32) -> u64 {
        let mut x = v as u64 & 0xffff;
        x = (x | (x << 8)) & 0x00ff00ff;
        x = (x | (x << 4)) & 0x0f0f0f0f;
        x = (x | (x << 2)) & 0x33333333;
        (x | (x << 1)) & 0x55555555
    }
    let mut keyed: Vec<(u64, u32)> = (0..width * height)
        .map(|p| (spread(p % width) | (spread(p / width) << 1), p))
        .collect();
    keyed.sort_unstable();
    keyed.into_iter().map(|(_, p)| p).collect()
}

/// Indices of the non-empty slots sorted by the Morton code of their position in a 2^10 grid over the
/// scene's bounds.
fn morton_order(hits: &[HitPoint]) -> Vec<u32> {
    fn spread(v: u32) -> u64 {
        // Interleave 10 bits with two zero bits between each.
        let mut x = v as u64 & 0x3ff;
        x = (x | (x << 16)) & 0x30000ff;
        x = (x | (x << 8)) & 0x300f00f;
        x = (x | (x << 4)) & 0x30c30c3;
        (x | (x << 2)) & 0x9249249
    }
    let (mut min, mut max) = (glam::Vec3::splat(f32::MAX), glam::Vec3::splat(f32::MIN));
    for h in hits.iter().filter(|h| !h.is_empty()) {
        min = min.min(glam::Vec3::from_array(h.pos));
        max = max.max(glam::Vec3::from_array(h.pos));
    }
    let scale = 1023.0 / (max - min).max_element().max(f32::MIN_POSITIVE);
    let mut keyed: Vec<(u64, u32)> = hits
        .iter()
        .enumerate()
        .filter(|(_, h)| !h.is_empty())
        .map(|(i, h)| {
            let q = ((glam::Vec3::from_array(h.pos) - min) * scale).clamp(glam::Vec3::ZERO, glam::Vec3::splat(1023.0));
            (
                spread(q.x as u32) | (spread(q.y as u32) << 1) | (spread(q.z as u32) << 2),
                i as u32,
            )
        })
        .collect();
    keyed.sort_unstable();
    keyed.into_iter().map(|(_, i)| i).collect()
}

#[cfg(test)]
mod tests {
    use super::{fits_device, make_tiles, spread_marks, tile_pixels, HitStats, TILE_ALIGN_PIXELS};

    #[test]
    fn marks_spread_to_the_eight_neighbours_only() {
        // 5x4 image, marks at (1, 1) and at the corner (4, 3).
        let mut m = vec![0u32; 20];
        m[5 + 1] = 1;
        m[15 + 4] = 7;
        spread_marks(&mut m, 5, 4);
        let want = [
            1, 1, 1, 0, 0, //
            1, 1, 1, 0, 0, //
            1, 1, 1, 1, 1, //
            0, 0, 0, 1, 1,
        ];
        let got: Vec<u32> = m.iter().map(|&x| (x != 0) as u32).collect();
        assert_eq!(got, want);
        // Nothing marked stays nothing; the spread does not chain.
        let mut none = vec![0u32; 12];
        spread_marks(&mut none, 4, 3);
        assert!(none.iter().all(|&x| x == 0));
    }

    /// The memory limit at its bound: a total of exactly the device's memory fits; a byte more is an
    /// error naming the buffers and what to lower. A per-pixel buffer past one binding (128 MiB here) is
    /// no error: the tiles bind it in parts.
    #[test]
    fn buffers_are_checked_against_the_device_memory() {
        let memory = 512 << 20;
        let others = [("records", 256 << 20)];
        let full = [("hits", 192 << 20), ("stats", 64 << 20)];
        assert!(fits_device(&full, &others, memory, "it").is_ok());
        let over = [("hits", 192 << 20), ("stats", 64 << 20), ("order", 1)];
        let e = fits_device(&over, &others, memory, "it").unwrap_err();
        assert!(
            matches!(e, crate::Error::Limit { value: Some(v), limit, .. } if v == memory + 1 && limit == memory),
            "{e:?}"
        );
        let e = e.to_string();
        assert!(
            e.contains("device memory (512 MiB: ")
                && e.contains("records 256 MiB")
                && e.contains("lower it, or --photons-per-pass"),
            "{e}"
        );
        // Unknown memory (0) is not checked.
        assert!(fits_device(&over, &others, 0, "it").is_ok());
    }

    /// The tile bound: a tile's data in the largest per-pixel buffer is at most the cap, in whole runs of
    /// `TILE_ALIGN_PIXELS`, and every pixel is in exactly one tile.
    #[test]
    fn tiles_fit_the_cap_and_cover_the_image() {
        let (range, hits) = (128u64 << 20, std::mem::size_of::<HitStats>() as u64);
        // lavapipe's 128 MiB at 2048x2048 SPPM: 64-byte statistics, so a tile of 2^27 / 64 rounded down to 64.
        let per = tile_pixels(2048 * 2048, hits, range).unwrap();
        assert_eq!(per as u64, range / hits / 64 * 64);
        assert!(per as u64 * hits <= range && (per as u64 + 64) * hits > range);
        // Exactly one run fits at its bound, none a byte below it.
        assert_eq!(tile_pixels(4096, hits, 64 * hits), Some(64));
        assert_eq!(tile_pixels(4096, hits, 64 * hits - 1), None);
        // An image under the cap is one tile, whatever its size.
        assert_eq!(tile_pixels(37 * 11, hits, range), Some(37 * 11));
        for (pixels, per_tile) in [(4096u32, 1536u32), (2048 * 2048, per), (100, 64), (64, 64)] {
            let tiles = make_tiles(pixels, per_tile);
            let mut next = 0;
            for t in &tiles {
                assert_eq!(t.first_pixel, next);
                assert!(t.pixels >= 1 && t.pixels <= per_tile && t.first_pixel % TILE_ALIGN_PIXELS == 0);
                next += t.pixels;
            }
            assert_eq!(next, pixels);
        }
        assert_eq!(make_tiles(4096, 1536).len(), 3);
    }
}
