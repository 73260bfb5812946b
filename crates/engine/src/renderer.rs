//! The progressive loop on the GPU: the ray pass once, then photon passes (photon -> lookup -> gather ->
//! update), and the resolve whenever an image is wanted.

use std::time::Instant;

use anyhow::{bail, Context as _, Result};
use ppm_vk_device::{barrier, vk, Buffer, BufferKind, ComputePipeline, Context, Profiler, ScopeTiming};
use ppm_vk_kernels::gather::{self, GatherPush, HitBuffers, UpdatePush};
use ppm_vk_kernels::layout::{HitPoint, HitStats, PassAccum, Photon};
use ppm_vk_kernels::lookup::{Grid, Lookup, SCAN_BLOCK};
use ppm_vk_kernels::photon::{self, PhotonPush, MAX_RECORDS, SALT_EYE, SALT_PHOTON};
use ppm_vk_kernels::ray::{self, RayPush, SceneBuffers};
use ppm_vk_kernels::resolve::{self, ResolvePush};
use ppm_vk_kernels::{pipeline, reflected};

use crate::gpu_scene::GpuScene;
use crate::image_io::RgbImage;
use crate::scene::Scene;
use crate::settings::Settings;

/// What one photon pass did and what it cost.
#[derive(Clone, Debug)]
pub struct PassStats {
    /// 1 for the first photon pass.
    pub index: u64,
    /// Photons emitted by this pass.
    pub photons: u64,
    /// Photons emitted by all passes so far.
    pub emitted_total: u64,
    /// Diffuse photon records this pass left (what the gather searched).
    pub records: u64,
    /// Batches the pass was split into to fit the record buffer.
    pub batches: u32,
    /// Host wall time of the pass, submission to completion.
    pub wall_ms: f64,
    /// GPU time of each stage (timestamp queries), in order.
    pub stages: Vec<ScopeTiming>,
}

impl PassStats {
    /// GPU milliseconds of the stages named `name`, summed over batches.
    pub fn stage_ms(&self, name: &str) -> f64 {
        self.stages.iter().filter(|s| s.name == name).map(|s| s.duration_ms).sum()
    }
}

struct Kernels {
    ray: ComputePipeline,
    photon: ComputePipeline,
    lookup: Lookup,
    gather: ComputePipeline,
    update: ComputePipeline,
    resolve: ComputePipeline,
}

/// A progressive photon mapping render in progress on one device.
///
/// ```no_run
/// # fn main() -> anyhow::Result<()> {
/// use ppm_vk_engine::{Context, ContextOptions, Renderer, Scene, Settings};
/// let ctx = Context::new(&ContextOptions::default())?;
/// let scene = Scene::load("scenes/cornell-spheres.toml".as_ref())?;
/// let mut renderer = Renderer::new(&ctx, &scene, Settings::default())?;
/// for _ in 0..10 {
///     renderer.pass()?;
/// }
/// renderer.image()?.save("out.png".as_ref())?;
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
    hit_points: Buffer,
    stats: Buffer,
    accum: Buffer,
    /// Non-empty hit-point slots in Morton order of their position (built after the ray pass).
    order: Buffer,
    active: u32,
    direct: Buffer,
    image: Buffer,
    photons: Buffer,
    counter: Buffer,
    /// Each batch's record count, copied from `counter`, to detect overflow after the pass.
    batch_log: Buffer,
    grid: Grid,
    profiler: Profiler,
    /// Photons per batch: the whole pass until a pass overflows the record buffer.
    batch: u32,
    passes: u64,
    emitted: u64,
    ray_ms: f64,
}

/// Largest batch log (batches per pass).
const MAX_BATCHES: u32 = 1024;

impl Renderer {
    /// Uploads the scene, allocates per-hit-point state and runs the ray pass.
    pub fn new(ctx: &Context, scene: &Scene, settings: Settings) -> Result<Renderer> {
        settings.validate()?;
        let max_range = ctx.limits().max_storage_buffer_range as u64;
        let record_size = std::mem::size_of::<Photon>() as u64;
        // Room for the records a typical pass leaves (a few per photon); a pass that leaves more is split
        // into batches, so this bounds memory, never correctness.
        let wanted = settings.photons_per_pass as u64 * 4;
        let capacity = wanted.min(max_range / record_size).min(u32::MAX as u64 / 2) as u32;
        let capacity = capacity.max(MAX_RECORDS * 64);
        let cells = (capacity as u64).next_power_of_two().clamp(SCAN_BLOCK as u64, SCAN_BLOCK as u64 * 65536) as u32;
        let gpu = GpuScene::new(scene, &settings, capacity, cells)?;
        let slots = gpu.slots() as u64;
        let pixels = gpu.pixels() as u64;
        let need = |what: &str, bytes: u64| -> Result<()> {
            if bytes > max_range {
                bail!(
                    "{what} needs {} MiB, more than this device's largest buffer ({} MiB): lower the resolution \
                     ({}x{}) or the hit points per pixel ({})",
                    bytes >> 20,
                    max_range >> 20,
                    gpu.params.width,
                    gpu.params.height,
                    settings.hit_slots
                );
            }
            Ok(())
        };
        need("the hit points", slots * std::mem::size_of::<HitPoint>() as u64)?;
        need("the hit-point statistics", slots * std::mem::size_of::<HitStats>() as u64)?;

        let kernels = Kernels {
            ray: pipeline(ctx, &reflected::RAY)?,
            photon: pipeline(ctx, &reflected::PHOTON)?,
            lookup: Lookup::new(ctx)?,
            gather: pipeline(ctx, &reflected::GATHER)?,
            update: pipeline(ctx, &reflected::UPDATE)?,
            resolve: pipeline(ctx, &reflected::RESOLVE)?,
        };
        let storage = |name: &str, bytes: u64| Buffer::new(ctx, name, bytes, BufferKind::Storage);
        let r2 = (gpu.initial_radius as f64).powi(2);
        let stats_init = vec![HitStats { r2, ..Default::default() }; slots as usize];
        let mut r = Renderer {
            params: ctx.buffer_from("params", &[gpu.params])?,
            spheres: ctx.buffer_from("spheres", &gpu.spheres)?,
            quads: ctx.buffer_from("quads", &gpu.quads)?,
            materials: ctx.buffer_from("materials", &gpu.materials)?,
            lights: ctx.buffer_from("lights", &gpu.lights)?,
            hit_points: storage("hit points", slots * std::mem::size_of::<HitPoint>() as u64)?,
            stats: ctx.buffer_from("hit stats", &stats_init)?,
            accum: storage("pass accumulators", slots * std::mem::size_of::<PassAccum>() as u64)?,
            order: storage("hit-point order", slots * 4)?,
            active: 0,
            direct: storage("direct emission", pixels * 16)?,
            image: storage("image", pixels * 16)?,
            photons: storage("photon records", capacity as u64 * record_size)?,
            counter: storage("photon counter", 4)?,
            batch_log: storage("batch log", MAX_BATCHES as u64 * 4)?,
            grid: Grid::new(ctx, cells, capacity)?,
            profiler: Profiler::new(ctx, 8 + 4 * MAX_BATCHES)?,
            batch: settings.photons_per_pass,
            passes: 0,
            emitted: 0,
            ray_ms: 0.0,
            ctx: ctx.clone(),
            settings,
            gpu,
            kernels,
        };
        drop(stats_init);
        r.ray_pass()?;
        Ok(r)
    }

    fn scene_buffers(&self) -> SceneBuffers<'_> {
        SceneBuffers { params: &self.params, spheres: &self.spheres, quads: &self.quads, materials: &self.materials }
    }

    fn hit_buffers(&self) -> HitBuffers<'_> {
        HitBuffers { hit_points: &self.hit_points, stats: &self.stats, accum: &self.accum, order: &self.order }
    }

    /// Pass 1: hit points through each pixel's centre.
    fn ray_pass(&mut self) -> Result<()> {
        self.profiler.reset();
        let push = RayPush { jitter: [0.5, 0.5], salt: SALT_EYE, pad0: 0 };
        let pixels = self.gpu.pixels();
        let scene = self.scene_buffers();
        let (profiler, k) = (&self.profiler, &self.kernels);
        let (hit_points, direct, accum) = (&self.hit_points, &self.direct, &self.accum);
        self.ctx.run(|cmd| {
            accum.cmd_fill(cmd, 0);
            profiler.scope(cmd, "ray", || ray::record(&k.ray, cmd, &scene, hit_points, direct, pixels, &push))?;
            barrier(&self.ctx, cmd);
            Ok(())
        })?;
        self.ray_ms = self.profiler.read()?.iter().map(|s| s.duration_ms).sum();
        // The gather walks the hit points in Morton order, so neighbouring threads read the same buckets.
        // Done once per render on the host: the hit points of PPM never move.
        let hits = self.read_hit_points()?;
        let order = morton_order(&hits);
        self.active = order.len() as u32;
        self.ctx.upload(&self.order, bytemuck::cast_slice(&order))?;
        Ok(())
    }

    /// Records photon tracing, the grid build and the gather for one batch.
    fn record_batch(&mut self, cmd: vk::CommandBuffer, first: u64, count: u32, log_index: u32) -> Result<()> {
        let ctx = &self.ctx;
        let scene = SceneBuffers { params: &self.params, spheres: &self.spheres, quads: &self.quads, materials: &self.materials };
        let hits = HitBuffers { hit_points: &self.hit_points, stats: &self.stats, accum: &self.accum, order: &self.order };
        let k = &self.kernels;
        let capacity = self.gpu.params.photon_capacity;
        self.counter.cmd_fill(cmd, 0);
        barrier(ctx, cmd);
        let push = PhotonPush { first, count, salt: SALT_PHOTON };
        self.profiler.scope(cmd, "photon", || {
            photon::record(&k.photon, cmd, &scene, &self.lights, &self.photons, &self.counter, &push)
        })?;
        barrier(ctx, cmd);
        self.counter.cmd_copy(cmd, &self.batch_log, 0, log_index as u64 * 4, 4);
        self.profiler.scope(cmd, "lookup", || {
            k.lookup.record(ctx, cmd, &self.params, &self.photons, &self.counter, &self.grid, capacity)
        })?;
        barrier(ctx, cmd);
        let push = GatherPush { count: self.active, cone_k: self.settings.cone_k.unwrap_or(0.0) };
        self.profiler.scope(cmd, "gather", || {
            gather::record_gather(&k.gather, cmd, &self.params, &hits, &self.photons, &self.grid, &push)
        })?;
        barrier(ctx, cmd);
        Ok(())
    }

    /// One photon pass: `photons_per_pass` photons traced and gathered, then the progressive update.
    pub fn pass(&mut self) -> Result<PassStats> {
        let start = Instant::now();
        let total = self.settings.photons_per_pass;
        let capacity = self.gpu.params.photon_capacity as u64;
        // Trace and gather in as few batches as fit the record buffer; on overflow, clear this pass's
        // accumulators and go again in smaller batches (the same photons: streams are by global index).
        let (stages, records, batches) = loop {
            let batches = total.div_ceil(self.batch);
            if batches > MAX_BATCHES {
                bail!("a photon pass needs more than {MAX_BATCHES} batches: the scene leaves too many records per photon");
            }
            self.profiler.reset();
            let emitted = self.emitted;
            let batch = self.batch;
            let ctx = self.ctx.clone();
            ctx.run(|cmd| {
                for b in 0..batches {
                    let first = b * batch;
                    let count = batch.min(total - first);
                    self.record_batch(cmd, emitted + first as u64, count, b)?;
                }
                Ok(())
            })?;
            let log: Vec<u32> = self.ctx.download_prefix(&self.batch_log, batches as usize)?;
            if log.iter().all(|&n| n as u64 <= capacity) {
                break (self.profiler.read()?, log.iter().map(|&n| n as u64).sum::<u64>(), batches);
            }
            if self.batch == 1 {
                bail!("one photon left more records than the record buffer holds ({capacity})");
            }
            self.batch = self.batch.div_ceil(2);
            self.ctx.run(|cmd| {
                self.accum.cmd_fill(cmd, 0);
                Ok(())
            })?;
        };
        // The update in its own submission, so an overflowed pass above never touches the statistics.
        let mut stages = stages;
        self.profiler.reset();
        let push = UpdatePush { count: self.active, alpha: self.settings.alpha };
        let hits = self.hit_buffers();
        let (profiler, k) = (&self.profiler, &self.kernels);
        self.ctx.run(|cmd| profiler.scope(cmd, "update", || gather::record_update(&k.update, cmd, &hits, &push)))?;
        stages.extend(self.profiler.read()?);
        self.passes += 1;
        self.emitted += total as u64;
        Ok(PassStats {
            index: self.passes,
            photons: total as u64,
            emitted_total: self.emitted,
            records,
            batches,
            wall_ms: start.elapsed().as_secs_f64() * 1e3,
            stages,
        })
    }

    /// Resolves the current estimate into an image buffer on the device (eq. 1-2) and returns its GPU time.
    pub fn resolve(&mut self) -> Result<f64> {
        self.profiler.reset();
        let push = ResolvePush { emitted: self.emitted as f64, norm: self.settings.cone_norm(), pad0: 0.0 };
        let pixels = self.gpu.pixels();
        let (profiler, k) = (&self.profiler, &self.kernels);
        let (params, hp, stats, direct, image) = (&self.params, &self.hit_points, &self.stats, &self.direct, &self.image);
        self.ctx.run(|cmd| {
            profiler.scope(cmd, "resolve", || {
                resolve::record(&k.resolve, cmd, params, hp, stats, direct, image, pixels, &push)
            })?;
            barrier(&self.ctx, cmd);
            Ok(())
        })?;
        Ok(self.profiler.read()?.iter().map(|s| s.duration_ms).sum())
    }

    /// The current image (resolves, then reads it back).
    pub fn image(&mut self) -> Result<RgbImage> {
        self.resolve()?;
        let rgba: Vec<[f32; 4]> = self.ctx.download(&self.image).context("reading the image back")?;
        RgbImage::from_rgba(self.gpu.params.width, self.gpu.params.height, &rgba[..self.gpu.pixels() as usize])
    }

    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// The flattened scene and render constants the kernels use.
    pub fn gpu_scene(&self) -> &GpuScene {
        &self.gpu
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

    /// GPU time of the ray pass, in milliseconds.
    pub fn ray_ms(&self) -> f64 {
        self.ray_ms
    }

    /// Non-empty hit-point slots (the hit points the gather visits).
    pub fn active_hit_points(&self) -> u32 {
        self.active
    }

    /// Photons per batch the passes currently use.
    pub fn batch_size(&self) -> u32 {
        self.batch
    }

    // Read-backs of device state, for tests and tools. Each waits for the device.

    pub fn read_hit_points(&self) -> Result<Vec<HitPoint>> {
        self.ctx.download_prefix(&self.hit_points, self.gpu.slots() as usize)
    }

    pub fn read_stats(&self) -> Result<Vec<HitStats>> {
        self.ctx.download_prefix(&self.stats, self.gpu.slots() as usize)
    }

    pub fn read_accum(&self) -> Result<Vec<PassAccum>> {
        self.ctx.download_prefix(&self.accum, self.gpu.slots() as usize)
    }

    pub fn read_direct(&self) -> Result<Vec<[f32; 4]>> {
        self.ctx.download_prefix(&self.direct, self.gpu.pixels() as usize)
    }

    /// Overwrites the per-hit-point statistics (tests start counters near their limits this way).
    pub fn write_stats(&self, stats: &[HitStats]) -> Result<()> {
        if stats.len() != self.gpu.slots() as usize {
            bail!("write_stats: {} entries for {} slots", stats.len(), self.gpu.slots());
        }
        self.ctx.upload(&self.stats, bytemuck::cast_slice(stats))
    }

    /// Traces and gathers one batch of photons with global indices `first..first+count` without the
    /// update, and returns the batch's records (the pass accumulators keep the gathered sums).
    pub fn trace_and_gather(&mut self, first: u64, count: u32) -> Result<Vec<Photon>> {
        self.profiler.reset();
        let ctx = self.ctx.clone();
        ctx.run(|cmd| self.record_batch(cmd, first, count, 0))?;
        let n: Vec<u32> = self.ctx.download_prefix(&self.counter, 1)?;
        if n[0] > self.gpu.params.photon_capacity {
            bail!("trace_and_gather: {} records overflow the capacity {}", n[0], self.gpu.params.photon_capacity);
        }
        self.ctx.download_prefix(&self.photons, n[0] as usize)
    }

    /// Runs the update kernel alone (after `trace_and_gather`).
    pub fn update_only(&mut self) -> Result<()> {
        let push = UpdatePush { count: self.active, alpha: self.settings.alpha };
        let hits = self.hit_buffers();
        let k = &self.kernels;
        self.ctx.run(|cmd| gather::record_update(&k.update, cmd, &hits, &push))
    }

    /// Sets the emitted-photon total the resolve divides by (tests start it near 2^32 this way).
    pub fn set_emitted(&mut self, emitted: u64) {
        self.emitted = emitted;
    }
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
            (spread(q.x as u32) | (spread(q.y as u32) << 1) | (spread(q.z as u32) << 2), i as u32)
        })
        .collect();
    keyed.sort_unstable();
    keyed.into_iter().map(|(_, i)| i).collect()
}
