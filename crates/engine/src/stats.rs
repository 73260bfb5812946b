//! What the renderer reports of its passes: pure data, read by the report, the checkpoint and the CLI.
//! Apart from the renderer so that those read it without depending on the renderer.

use ppm_vk_device::ScopeTiming;
use ppm_vk_kernels::layout::{HitPoint, HitStats};

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
    /// Photon paths of the whole render so far that reached the depth backstop (`PathLimits`) instead of
    /// ending by roulette: 0 unless the scene traps light (mirrors facing each other, albedo 1).
    pub photon_paths_cut: u64,
    /// Eye paths of the whole render so far that reached the depth backstop.
    pub eye_paths_cut: u64,
    /// Times a photon's flux was held at the cap on Veach's correction for shading normals
    /// (`layout::FLUX_CAP_FIXED`, shading.glsl), over the whole render so far: 0 but in rare grazing light
    /// on smooth-shaded meshes.
    pub photons_capped: u64,
    /// The largest search radius after this pass's update, over the hit points live in it.
    pub radius_max: f32,
    /// The photon grid's cell size for the next pass (1.5 `radius_max`, see `Renderer::fit_grid`).
    pub cell_size: f32,
    /// Host wall time of the pass, submission to completion.
    pub wall_ms: f64,
    /// GPU time of each stage (timestamp queries), in order.
    pub stages: Vec<ScopeTiming>,
}

impl PassStats {
    /// GPU milliseconds of the stages named `name`, or `name/...` (its steps), summed over batches.
    pub fn stage_ms(&self, name: &str) -> f64 {
        self.stages
            .iter()
            .filter(|s| s.name == name || s.name.strip_prefix(name).is_some_and(|rest| rest.starts_with('/')))
            .fold(0.0, |sum, s| sum + s.duration_ms) // not sum(): an empty f64 sum is -0.0
    }
}

/// One variant of the photon kernel timed by [`crate::Renderer::photon_breakdown`].
#[derive(Clone, Debug, serde::Serialize)]
pub struct PhotonVariant {
    pub name: &'static str,
    pub photons: u32,
    /// GPU time of the one dispatch.
    pub gpu_ms: f64,
    /// Intersections it traced (path segments).
    pub steps: u64,
}

impl PhotonVariant {
    /// Intersections per second.
    pub fn steps_per_second(&self) -> f64 {
        self.steps as f64 / (self.gpu_ms * 1e-3)
    }
}

/// What the probe pass did (eq. 7-9).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ProbeReport {
    pub photons: u32,
    pub hit_points: u32,
    /// Hit points whose radius the probe enlarged.
    pub enlarged: u32,
    /// Hit points no probe photon reached (counted as sparse: lambda = r^2).
    pub empty: u32,
    /// lambda / r^2 over the hit points: min, quartiles, max.
    pub lambda_ratio_quantiles: [f64; 5],
    /// Mean starting radius over the hit points after probing, relative to r of eq. 8.
    pub mean_radius_ratio: f64,
    pub gpu_ms: f64,
}

impl ProbeReport {
    pub(crate) fn new(stats: &[HitStats], hits: &[HitPoint], r: f32, photons: u32, gpu_ms: f64) -> ProbeReport {
        let r2 = (r as f64).powi(2);
        let live: Vec<&HitStats> = stats
            .iter()
            .zip(hits)
            .filter(|(_, h)| !h.is_empty())
            .map(|(s, _)| s)
            .collect();
        let mut ratios: Vec<f64> = live.iter().map(|s| s.probe).collect();
        ratios.sort_by(|a, b| a.total_cmp(b));
        let q = |f: f64| {
            if ratios.is_empty() {
                0.0
            } else {
                ratios[((ratios.len() - 1) as f64 * f).round() as usize]
            }
        };
        ProbeReport {
            photons,
            hit_points: live.len() as u32,
            enlarged: live.iter().filter(|s| s.r2 > r2 * (1.0 + 1e-9)).count() as u32,
            empty: live.iter().filter(|s| s.probe >= 1.0).count() as u32,
            lambda_ratio_quantiles: [q(0.0), q(0.25), q(0.5), q(0.75), q(1.0)],
            mean_radius_ratio: live.iter().map(|s| (s.r2 / r2).sqrt()).sum::<f64>() / live.len().max(1) as f64,
            gpu_ms,
        }
    }
}

/// What the pilot eye pass marked (ray.comp): pixels of the image with each mark, after the marks spread to
/// the neighbours. A pixel marked for emission or rough takes all the emission samples each pass.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PilotMarks {
    pub pixels: u32,
    pub emission: u32,
    pub lit: u32,
    pub rough: u32,
    /// Pixels where a chain passed near a light after a curved vertex (ray.comp's MARK_NEAR).
    #[serde(default)]
    pub near: u32,
    /// Pixels with MARK_EMISSION, MARK_NEAR or MARK_ROUGH: those that take all the emission samples.
    pub all_samples: u32,
    /// Pixels where the pilot itself took all the emission samples, not only `Settings::pilot_samples`:
    /// one of those met a mirror or glass (ray.comp's MARK_CHAIN). 0 after a resume (the checkpoint keeps
    /// the marks, not the pilot's own count) and from `new`.
    #[serde(default)]
    pub pilot_all: u32,
}

impl PilotMarks {
    pub fn new(busy: &[u32]) -> PilotMarks {
        use ppm_vk_kernels::ray::{MARK_EMISSION, MARK_LIT, MARK_NEAR, MARK_ROUGH};
        let count = |bits: u32| busy.iter().filter(|&&m| m & bits != 0).count() as u32;
        PilotMarks {
            pixels: busy.len() as u32,
            emission: count(MARK_EMISSION),
            lit: count(MARK_LIT),
            rough: count(MARK_ROUGH),
            near: count(MARK_NEAR),
            all_samples: count(MARK_EMISSION | MARK_NEAR | MARK_ROUGH),
            pilot_all: 0,
        }
    }
}

/// Where a renderer's set-up went (`Renderer::setup_times`), in seconds of wall time.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct SetupTimes {
    /// Lowering the scene for the device (`GpuScene::new`), the BVH build included.
    pub lower_s: f64,
    /// The BVH build alone.
    pub bvh_s: f64,
    /// Writing the scene's GLSL constants for the specialised kernels.
    pub glsl_s: f64,
    /// Every kernel's pipeline, made in parallel: the wall time of all of them.
    pub kernels_s: f64,
    /// Each kernel (or group of them) on its own.
    pub kernels: Vec<KernelSetup>,
    /// Allocating and filling the buffers (the scene's upload).
    pub buffers_s: f64,
    /// The pilot eye pass and the hit-point order (on lavapipe with the ray kernel's first-dispatch
    /// compile).
    pub start_s: f64,
    /// The probe pass (0 without probing).
    pub probe_s: f64,
}

impl SetupTimes {
    /// Why the cache of compiled kernels was not used or written, one line each.
    pub fn notes(&self) -> impl Iterator<Item = &str> {
        self.kernels.iter().filter_map(|k| k.note.as_deref())
    }

    /// The sum of the stages: what the renderer's constructor took.
    pub fn total_s(&self) -> f64 {
        self.lower_s + self.glsl_s + self.kernels_s + self.buffers_s + self.start_s + self.probe_s
    }
}

/// What making one kernel's pipeline took (`ppm_vk_kernels::specialize::KernelTiming`).
#[derive(Clone, Debug, serde::Serialize)]
pub struct KernelSetup {
    pub name: String,
    /// shaderc's compile, or reading its SPIR-V from the cache (0: the build-time SPIR-V).
    pub compile_s: f64,
    /// Whether the compiled SPIR-V came from the on-disk cache (`None`: the build-time SPIR-V).
    pub spirv_cached: Option<bool>,
    /// vkCreateComputePipelines.
    pub pipeline_s: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

impl From<ppm_vk_kernels::specialize::KernelTiming> for KernelSetup {
    fn from(t: ppm_vk_kernels::specialize::KernelTiming) -> KernelSetup {
        KernelSetup {
            name: t.name.to_string(),
            compile_s: t.compile_s,
            spirv_cached: t.spirv_cached,
            pipeline_s: t.pipeline_s,
            note: t.note,
        }
    }
}
