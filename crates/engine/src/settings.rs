//! Render settings and their defaults.

use crate::error::{Error, Result};
use ppm_vk_kernels::lookup::SCAN_BLOCK;

/// Most photons one pass (or the probe pass) may emit: 2^24, 16 batches of `MAX_BATCH_PHOTONS` (a cancel
/// ends a pass between batches; 2^31 photons in one pass were days that Ctrl-C could not stop, and the
/// probe pass is never cut short). More photons: more passes.
pub const MAX_PHOTONS_PER_PASS: u32 = 1 << 24;

/// Most emission samples per pixel and eye pass (`Settings::emission_samples`).
pub const MAX_EMISSION_SAMPLES: u32 = 64;

/// Which progressive photon mapping.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Mode {
    /// PPM (Hachisuka et al. 2008): one eye pass at pixel centres, hit points fixed for the render, glass
    /// split into both Fresnel branches.
    Ppm,
    /// Stochastic PPM (Hachisuka and Jensen 2009): an eye pass before every photon pass, at a random point
    /// of each pixel, one hit point per pixel (`rough_splits` where a rough lobe splits the path), one
    /// branch at glass chosen by Fresnel.
    Sppm,
}

/// How the probe pass (eq. 7-9) sets the starting radii.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ProbeMode {
    /// No probe pass: every hit point starts at r (eq. 8).
    Off,
    /// Eq. 9 to the letter: r' = r (1 + lambda / r) where lambda / r > beta.
    Paper,
    /// r' = r (1 + lambda / r^2): the same rule without eq. 9's dependence on the scene's units.
    ScaleFree,
    /// r' = r min(sqrt(k / N), 2), N the probe photons within r (`Settings::probe_k`): the radius that
    /// holds k of them, as classic photon mapping's k nearest; smaller where photons crowd (caustics),
    /// larger where they are few. Free of units.
    Nearest,
    /// The radius of least error (bias^2 + variance) of the density estimate, after Kaplanyan and
    /// Dachsbacher's adaptive PPM: from the probe photons within r and within r / 2, which give the
    /// density and its Laplacian, (r' / r)^6 = 9 N1 / (32 (N1 - 4 N2)^2), counting only a curvature
    /// beyond twice its noise; r / 8 <= r' <= 2 r. Shrinks radii only where the density curves (a
    /// caustic), grows them where it is flat (at most `Settings::probe_grow`: by default not at all).
    /// Free of units. The default: at equal passes 4.7x less error than eq. 8 alone on glass-on-table's
    /// narrow caustic, within -5% to +2% of it on the Cornell boxes, at the same cost a pass within the
    /// machine's noise (docs/accuracy.md).
    Curvature,
}

/// How the light that reaches the eye paths' first diffuse points straight from an emitter is estimated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum DirectLight {
    /// By light sampling: each emission-sample path sends a shadow ray to a point of a light at its first
    /// diffuse point (pbrt-v4's SPPM does the same), and photons leave no record where they first land
    /// straight from a light; the photons estimate only the light that bounced on its way.
    Sample,
    /// By the photons, as all other light (the paper's estimator).
    Photons,
}

/// How eye paths take the light that their rough vertices (rough conductors and rough glass they sample
/// through) reflect straight from an emitter (shaders/ray/glossy_light.glsl).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum GlossyLight {
    /// Both a shadow ray to a light and the lobe's own sampled direction, weighed by the power heuristic
    /// (Veach 1997), as a path tracer does: each where it has the lower variance.
    #[default]
    Mis,
    /// The lobe's sampled direction alone, as before (points, spots and the sun, which no direction
    /// meets, by shadow rays).
    Bsdf,
    /// Shadow rays alone (glowing spheres, which they do not sample here, by the lobe).
    Lights,
}

/// How to render. `Settings::default()` is stochastic PPM (at equal time it had the lower whole-image error
/// on the paper's scene from 10 s on: docs/accuracy.md, "What the numbers show") with the paper's other settings.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Settings {
    /// PPM or stochastic PPM.
    pub mode: Mode,
    /// Photons emitted per photon pass (the paper: 1M).
    pub photons_per_pass: u32,
    /// The fraction of new photons kept by the progressive update (eq. 3, 6); Hachisuka 2008: 0.7.
    pub alpha: f32,
    /// Seed of every random stream.
    pub seed: u32,
    /// Starting search radius; `None`: eq. 8 from the scene's bounds and the image width.
    pub initial_radius: Option<f32>,
    /// Cone filter constant k >= 1 (eq. 10-14); `None`: no filter.
    pub cone_k: Option<f32>,
    /// The probe pass (eq. 7-9 and the rules that follow the photons); the curvature rule, capped to only
    /// shrink, by default.
    pub probe: ProbeMode,
    /// beta of eq. 9 as a fraction of r (the paper's best: 1/5).
    pub probe_beta: f32,
    /// Photons the probe pass emits; `None`: `photons_per_pass`, as in the paper.
    pub probe_photons: Option<u32>,
    /// With `probe: Nearest`, the probe photons each starting radius is to hold.
    #[serde(default = "default_probe_k")]
    pub probe_k: f32,
    /// With `probe: Curvature`, the most a starting radius may grow, as r' / r in [1, 2] (1: it only
    /// shrinks, and no lookup reads more photons than eq. 8's radius would).
    #[serde(default = "default_probe_grow")]
    pub probe_grow: f32,
    /// The adaptive shrink after every pass (update.comp): the curvature fit of the probe, taken again over
    /// the photons each hit point has gathered so far, shrinks its radius where the fit's optimum is
    /// smaller, counting only the curvature beyond this many standard deviations of its noise. 0: off
    /// (eq. 3 alone). See [`DEFAULT_SHRINK_Z`].
    #[serde(default = "default_shrink_z")]
    pub shrink_z: f32,
    /// The share of every area light's photons aimed at what casts caustics (a sphere around the mirrors,
    /// glass and lobes sampled through of each material, photon/targets.glsl), each photon weighed by the
    /// mixture's density so that the light it carries stays the light's: more photons make the caustics,
    /// fewer the rest. 0: every photon leaves by the cosine; less than 1. See [`DEFAULT_CAUSTIC_PHOTONS`].
    #[serde(default = "default_caustic_photons")]
    pub caustic_photons: f32,
    /// Hit points per pixel in PPM: glass splits an eye path into both Fresnel branches up to this many
    /// leaves.
    pub hit_slots: u32,
    /// Hit points per pixel in SPPM where the scene has a rough surface that eye paths sample through
    /// (rough glass, a rough conductor that is no glossy hit point): an eye path's first such vertex splits
    /// it into this many directions of its lobe, each a hit point with statistics of its own, so the light
    /// seen through a glossy lobe gets this many samples a pass (ray.comp). Elsewhere SPPM has one.
    #[serde(default = "default_rough_splits")]
    pub rough_splits: u32,
    /// Hit points per pixel in SPPM where the scene has smooth glass or a thin pane and no rough surface
    /// that splits: in the pixels where a pilot chain left a curved mirror or glass (ray.comp's MARK_SPLIT),
    /// an eye path takes both Fresnel branches at smooth glass while the pixel has slots (the reflection
    /// weighted F, the refraction 1 - F), each leaf a hit point with statistics of its own, as PPM's
    /// `hit_slots`; past them, and in the other pixels, it draws one branch by Fresnel. So the view through
    /// curved glass is not a coin flip between two images each pass (docs/accuracy.md, "Fresnel splits in
    /// SPPM").
    #[serde(default = "default_glass_splits")]
    pub glass_splits: u32,
    /// Most specular bounces of an eye path. Eye paths end at diffuse surfaces or by escaping; this is a
    /// backstop (for a camera between parallel mirrors), lowered where the device's loop budget needs it
    /// (`PathLimits`). Paths cut there are counted in `PassStats::eye_paths_cut`.
    pub max_eye_depth: u32,
    /// Most surface interactions of a photon path. Paths end by Russian roulette; this is a backstop,
    /// lowered where the device's loop budget needs it, never below a depth that keeps the loss under 0.1%
    /// at albedo 0.95 (`PathLimits`). Paths cut there are counted in `PassStats::photon_paths_cut`.
    pub max_photon_depth: u32,
    /// Eye paths per pixel and eye pass that only collect the emission seen directly or through mirrors
    /// and glass (ray.comp): the light's edges and its images get this many more samples than the photon
    /// estimate's one hit point per pixel. 0: only the hit-point path's own sample.
    pub emission_samples: u32,
    /// Emission paths per pixel of the pilot eye pass (pass 0), which only marks the pixels that take
    /// `emission_samples` (and, with light sampling, those where a shadow ray reached a light). Where one
    /// of them leaves a mirror, smooth glass or a smooth coat the pilot takes all `emission_samples` there
    /// (what such a chain shows of a light can be an image a pixel wide). Fewer make the set-up faster
    /// and miss more of the light's smallest images seen straight, whose pixels then take
    /// `light_samples`. The marks choose how many samples a pixel takes, never what they estimate: no
    /// bias either way. At least `emission_samples`: every pixel takes them all (the rule before). See
    /// [`DEFAULT_PILOT_SAMPLES`].
    #[serde(default = "default_pilot_samples")]
    pub pilot_samples: u32,
    /// Emission paths per pixel and eye pass where the pilot's paths sampled through a rough lobe (rough
    /// metal, rough glass: its MARK_ROUGH), if more than `emission_samples`: the light such a vertex
    /// reflects, by its shadow ray and its lobe's direction, is the noisiest term there, and these pixels
    /// are few. With `emission_samples` 0 there are no emission paths anywhere. See
    /// [`DEFAULT_ROUGH_SAMPLES`].
    #[serde(default = "default_rough_samples")]
    pub rough_samples: u32,
    /// Direct light by light sampling (the default) or by the photons.
    #[serde(default = "default_direct")]
    pub direct: DirectLight,
    /// With `direct: Sample`, the light-sampling paths per pixel and eye pass in the pixels that do not take
    /// `emission_samples` (those the pilot saw no emitter in): each samples the emission along its specular
    /// chain and the direct light at its end.
    #[serde(default = "default_light_samples")]
    pub light_samples: u32,
    /// Glossy hit points: rough conductors of at least this roughness (alpha) end the eye paths with a hit
    /// point whose gather evaluates their BRDF per photon, and the photons leave records on them;
    /// rougher is closer to diffuse, where photons serve best. `None`: every rough lobe is sampled through
    /// by the eye paths (shaders/materials/rough_conductor.glsl; docs/accuracy.md compares the two).
    #[serde(default = "default_glossy_hits")]
    pub glossy_hits: Option<f32>,
    /// How the light that rough vertices reflect straight from an emitter is taken (multiple importance
    /// sampling by default).
    #[serde(default)]
    pub glossy_light: GlossyLight,
    /// Compile the tracing kernels with the scene inlined as constants (faster; same results up to the
    /// last bit of a fused multiply-add). `false` uses the kernels as built.
    pub specialize: bool,
    /// With `specialize`: meshes of at most this many triangles in all are compiled into the tracing
    /// kernels with the spheres and quads and tested one by one, instead of through the BVH (the same
    /// hits: the same watertight test). 0: always the BVH.
    #[serde(default = "default_inline_triangles")]
    pub max_inline_triangles: u32,
    /// Buckets of the photon grid's hash table (a power of two, at least 1024); `None` sizes it from the
    /// scene's surface area. Results do not depend on it; a small table makes grid cells share buckets,
    /// which the tests use to exercise that case.
    pub grid_buckets: Option<u32>,
    /// Edge of a photon-grid cell in scene units; `None`: `CELL_PER_RADIUS` (1.5) times the starting
    /// radius, then after each pass 1.5 times the largest radius left, so a lookup spans at most 3x3x3
    /// cells. Smaller cells mean wider lookups (tests use them for that).
    pub grid_cell: Option<f32>,
    /// Submit each photon batch's stages (trace, lookup, gather) on their own, checking the
    /// [`CancelToken`](crate::CancelToken) between them, so a cancelled pass stops within one stage rather
    /// than one batch: a viewer's camera change waits less. The same image bit for bit; a little more
    /// host-device round trip per pass.
    #[serde(default)]
    pub split_submissions: bool,
    /// Most bytes of any per-pixel buffer (hit points, their statistics, emission sums) one kernel binds
    /// at a time: the image is split into tiles of consecutive pixels that fit (the renderer's `Tile`).
    /// `None`: the device's largest storage binding (`maxStorageBufferRange`), above which it is also
    /// capped. The image does not depend on it, bit for bit; tests set it small to split small images.
    #[serde(default)]
    pub max_tile_bytes: Option<u64>,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            mode: Mode::Sppm,
            photons_per_pass: 1_000_000,
            alpha: 0.7,
            seed: 0,
            initial_radius: None,
            cone_k: None,
            probe: ProbeMode::Curvature,
            probe_beta: 0.2,
            probe_photons: None,
            probe_k: DEFAULT_PROBE_K,
            probe_grow: DEFAULT_PROBE_GROW,
            shrink_z: DEFAULT_SHRINK_Z,
            caustic_photons: DEFAULT_CAUSTIC_PHOTONS,
            hit_slots: 4,
            rough_splits: default_rough_splits(),
            glass_splits: default_glass_splits(),
            max_eye_depth: 1024,
            max_photon_depth: 4096,
            emission_samples: 16,
            pilot_samples: DEFAULT_PILOT_SAMPLES,
            rough_samples: DEFAULT_ROUGH_SAMPLES,
            direct: default_direct(),
            light_samples: default_light_samples(),
            glossy_hits: Some(DEFAULT_GLOSSY_ALPHA),
            glossy_light: GlossyLight::Mis,
            specialize: true,
            max_inline_triangles: default_inline_triangles(),
            grid_buckets: None,
            grid_cell: None,
            split_submissions: false,
            max_tile_bytes: None,
        }
    }
}

/// `Settings::probe_grow`'s default: the curvature rule only shrinks radii. Growing them (up to 2, as far as
/// the other probe rules grow one) lowered the error at equal passes but not at equal time: every lookup
/// then reads up to 4 times the photons (docs/accuracy.md).
pub const DEFAULT_PROBE_GROW: f32 = 1.0;

fn default_probe_grow() -> f32 {
    DEFAULT_PROBE_GROW
}

/// `Settings::shrink_z`'s default. At 48 passes (docs/accuracy.md) 2 took glass-on-table's error from
/// 0.0112 to 0.0024 and left the Cornell boxes within 1%; 1 took a little more off glass-on-table (0.0021)
/// but added 8-13% to cornell-spheres and cornell-box, where flat regions then shrink on noise; 3 kept less
/// of the gain (0.0029).
pub const DEFAULT_SHRINK_Z: f32 = 2.0;

fn default_shrink_z() -> f32 {
    DEFAULT_SHRINK_Z
}

/// `Settings::caustic_photons`'s default.
pub const DEFAULT_CAUSTIC_PHOTONS: f32 = 0.0;

fn default_caustic_photons() -> f32 {
    DEFAULT_CAUSTIC_PHOTONS
}

/// `Settings::probe_k`'s default.
pub const DEFAULT_PROBE_K: f32 = 64.0;

fn default_probe_k() -> f32 {
    DEFAULT_PROBE_K
}

fn default_direct() -> DirectLight {
    DirectLight::Sample
}

/// The least roughness of a glossy hit point by default: on cornell-rough's gold sphere (alpha 0.2) glossy
/// hit points gave 0.20x the error of sampling through at equal time, on cornell-glossy10's (alpha 0.1)
/// 1.04x it, on cornell-glossy's (alpha 0.05) 6x it (docs/accuracy.md): past the tie.
pub const DEFAULT_GLOSSY_ALPHA: f32 = 0.15;

fn default_glossy_hits() -> Option<f32> {
    Some(DEFAULT_GLOSSY_ALPHA)
}

/// `Settings::rough_splits`'s default (docs/accuracy.md measures it at equal time).
pub const DEFAULT_ROUGH_SPLITS: u32 = 4;

fn default_rough_splits() -> u32 {
    DEFAULT_ROUGH_SPLITS
}

/// `Settings::glass_splits`'s default (docs/accuracy.md, "Fresnel splits in SPPM").
pub const DEFAULT_GLASS_SPLITS: u32 = 4;

fn default_glass_splits() -> u32 {
    DEFAULT_GLASS_SPLITS
}

/// `Settings::pilot_samples`'s default (docs/performance.md, "The pilot's samples"): at equal passes the
/// same error as all 16 on cornell-spheres, glass-on-table, cornell-aniso and penumbra, 2% more on the
/// interior, for a pilot eye pass 0.7x as long there (0.1x on cornell-spheres); 2 costs the interior
/// and textured-light 3-4%.
pub const DEFAULT_PILOT_SAMPLES: u32 = 4;

fn default_pilot_samples() -> u32 {
    DEFAULT_PILOT_SAMPLES
}

/// `Settings::rough_samples`'s default (docs/accuracy.md, "Eye paths through rough lobes"): as many as
/// `emission_samples`. 32 takes cornell-aniso's gold sphere's error at 60 s to 0.71x and its glass's to
/// 0.87x with the whole image's unchanged, but costs cornell-rough, -glossy and -glossy10 7% in the
/// whole image (fewer passes, so more photon noise in the dark): not a win everywhere measured.
pub const DEFAULT_ROUGH_SAMPLES: u32 = 16;

fn default_rough_samples() -> u32 {
    DEFAULT_ROUGH_SAMPLES
}

fn default_light_samples() -> u32 {
    4
}

fn default_inline_triangles() -> u32 {
    ppm_vk_kernels::specialize::MAX_INLINE_TRIANGLES as u32
}

fn invalid(field: &'static str, message: String) -> Error {
    Error::Settings { field, message }
}

impl Settings {
    /// Eye paths per pixel and eye pass, besides the hit points' own, in the pixels the pilot did not mark:
    /// `light_samples` with direct light sampled, else one (the emission seen directly there, if any).
    pub fn unmarked_samples(&self) -> u32 {
        match self.direct {
            DirectLight::Sample => self.light_samples,
            DirectLight::Photons => self.emission_samples.min(1),
        }
    }

    /// Eye paths per pixel and eye pass in the pixels the pilot marked for a rough lobe (`rough_samples`,
    /// at least `emission_samples`; none where there are no emission paths).
    pub fn rough_pixel_samples(&self) -> u32 {
        match self.emission_samples {
            0 => 0,
            e => e.max(self.rough_samples),
        }
    }

    /// The most eye paths a pixel takes in one eye pass besides its hit-point path's.
    pub fn most_samples(&self) -> u32 {
        self.emission_samples
            .max(self.unmarked_samples())
            .max(self.rough_pixel_samples())
    }

    /// Checks every setting's range; the error is [`Error::Settings`] naming the field.
    pub fn validate(&self) -> Result<()> {
        let per_pass = |field: &'static str, n: u32| match (1..=MAX_PHOTONS_PER_PASS).contains(&n) {
            true => Ok(()),
            false => Err(invalid(
                field,
                format!(
                    "must be in 1..={MAX_PHOTONS_PER_PASS}, got {n} (more photons: more passes, which a \
                     signal can end between them)"
                ),
            )),
        };
        per_pass("photons_per_pass", self.photons_per_pass)?;
        if let Some(n) = self.probe_photons {
            per_pass("probe_photons", n)?;
        }
        let most = ppm_vk_kernels::specialize::MAX_INLINE_TRIANGLES;
        if self.max_inline_triangles as usize > most {
            let got = self.max_inline_triangles;
            return Err(invalid(
                "max_inline_triangles",
                format!("must be at most {most}, got {got}"),
            ));
        }
        if !(self.alpha > 0.0 && self.alpha < 1.0) {
            return Err(invalid("alpha", format!("must be in (0, 1), got {}", self.alpha)));
        }
        if !(self.shrink_z.is_finite() && self.shrink_z >= 0.0) {
            return Err(invalid(
                "shrink_z",
                format!("must be finite and >= 0 (0: off), got {}", self.shrink_z),
            ));
        }
        if !(0.0..=0.95).contains(&self.caustic_photons) {
            return Err(invalid(
                "caustic_photons",
                format!(
                    "the share of photons aimed at caustics must be in 0..=0.95, got {}",
                    self.caustic_photons
                ),
            ));
        }
        if let Some(k) = self.cone_k {
            if !(k.is_finite() && k >= 1.0) {
                return Err(invalid(
                    "cone_k",
                    format!("the cone filter constant k must be >= 1, got {k}"),
                ));
            }
        }
        if let Some(r) = self.initial_radius {
            if !(r.is_finite() && r > 0.0) {
                return Err(invalid(
                    "initial_radius",
                    format!("must be positive and finite, got {r}"),
                ));
            }
        }
        if !(1.0..=2.0).contains(&self.probe_grow) {
            return Err(invalid(
                "probe_grow",
                format!("must be in [1, 2] (r' / r at most), got {}", self.probe_grow),
            ));
        }
        if !(self.probe_k.is_finite() && self.probe_k >= 1.0) {
            return Err(invalid(
                "probe_k",
                format!("must be at least 1 photon, got {}", self.probe_k),
            ));
        }
        if !(self.probe_beta.is_finite() && self.probe_beta > 0.0 && self.probe_beta < 1.0) {
            return Err(invalid(
                "probe_beta",
                format!("must be a fraction of r in (0, 1), got {}", self.probe_beta),
            ));
        }
        if !(1..=8).contains(&self.hit_slots) {
            return Err(invalid(
                "hit_slots",
                format!("hit slots per pixel must be in 1..=8, got {}", self.hit_slots),
            ));
        }
        if !(1..=8).contains(&self.rough_splits) {
            return Err(invalid(
                "rough_splits",
                format!("rough splits per pixel must be in 1..=8, got {}", self.rough_splits),
            ));
        }
        if !(1..=8).contains(&self.glass_splits) {
            return Err(invalid(
                "glass_splits",
                format!("glass splits per pixel must be in 1..=8, got {}", self.glass_splits),
            ));
        }
        if let Some(b) = self.grid_buckets {
            if !b.is_power_of_two() || !(SCAN_BLOCK..=SCAN_BLOCK * 65536).contains(&b) {
                return Err(invalid(
                    "grid_buckets",
                    format!(
                        "photon grid buckets must be a power of two in [{SCAN_BLOCK}, {}], got {b}",
                        SCAN_BLOCK as u64 * 65536
                    ),
                ));
            }
        }
        if self.max_eye_depth == 0 || self.max_photon_depth == 0 {
            return Err(invalid(
                if self.max_eye_depth == 0 {
                    "max_eye_depth"
                } else {
                    "max_photon_depth"
                },
                "path depth limits must be at least 1".into(),
            ));
        }
        if self.direct == DirectLight::Sample && !(1..=MAX_EMISSION_SAMPLES).contains(&self.light_samples) {
            return Err(invalid(
                "light_samples",
                format!(
                    "must be 1..={MAX_EMISSION_SAMPLES} when direct light is sampled, got {}",
                    self.light_samples
                ),
            ));
        }
        if let Some(a) = self.glossy_hits {
            if !(a.is_finite() && a >= 0.0) {
                return Err(invalid(
                    "glossy_hits",
                    format!("the least roughness (alpha) of a glossy hit point must be finite and >= 0, got {a}"),
                ));
            }
        }
        if !(1..=MAX_EMISSION_SAMPLES).contains(&self.pilot_samples) {
            return Err(invalid(
                "pilot_samples",
                format!("must be 1..={MAX_EMISSION_SAMPLES}, got {}", self.pilot_samples),
            ));
        }
        if self.rough_samples > MAX_EMISSION_SAMPLES {
            return Err(invalid(
                "rough_samples",
                format!("must be at most {MAX_EMISSION_SAMPLES}, got {}", self.rough_samples),
            ));
        }
        if self.emission_samples > MAX_EMISSION_SAMPLES {
            return Err(invalid(
                "emission_samples",
                format!(
                    "emission samples per pixel and pass must be at most {MAX_EMISSION_SAMPLES}, got {}",
                    self.emission_samples
                ),
            ));
        }
        Ok(())
    }

    /// Hit points per pixel as the renderer uses them for `scene`: PPM's glass leaves; in SPPM the lobe
    /// directions of the first rough vertex where eye paths sample through one in `scene`, else one.
    pub fn slots(&self, scene: &crate::scene::Scene) -> u32 {
        match self.mode {
            Mode::Ppm => self.hit_slots,
            Mode::Sppm if self.splits_rough(scene) => self.rough_splits,
            Mode::Sppm if self.splits_glass(scene) => self.glass_splits,
            Mode::Sppm => 1,
        }
    }

    /// Whether SPPM's eye paths split at rough vertices in `scene` (ray.comp): it has a material the eye
    /// paths sample through by a lobe, rough glass or a rough conductor that holds no glossy hit point
    /// (rough_conductor.glsl's `glossy_hit`), and more than one split is asked for.
    pub fn splits_rough(&self, scene: &crate::scene::Scene) -> bool {
        use crate::scene::Surface;
        let glossy = self.glossy_hits.unwrap_or(f32::INFINITY);
        self.mode == Mode::Sppm
            && self.rough_splits > 1
            && scene.materials.iter().any(|m| match &m.surface {
                Surface::RoughGlass { .. } => true,
                Surface::RoughConductor { rough, .. } => {
                    !(rough.alpha >= glossy && rough.alpha == rough.alpha_v && m.alpha_texture.is_none())
                }
                _ => false,
            })
    }

    /// Whether SPPM's eye paths split at smooth glass and thin panes in `scene` (ray.comp: both Fresnel
    /// branches while the pixel has slots): it has such a material, no rough split (`splits_rough`, whose
    /// slots glass then leaves to the lobe), and more than one split is asked for.
    pub fn splits_glass(&self, scene: &crate::scene::Scene) -> bool {
        use crate::scene::Surface;
        self.mode == Mode::Sppm
            && self.glass_splits > 1
            && !self.splits_rough(scene)
            && scene
                .materials
                .iter()
                .any(|m| matches!(m.surface, Surface::Glass { .. } | Surface::ThinDielectric { .. }))
    }

    /// The cone filter's normalisation 1 - 2/(3k) (eq. 11), or 1 without it.
    pub fn cone_norm(&self) -> f32 {
        match self.cone_k {
            Some(k) => 1.0 - 2.0 / (3.0 * k),
            None => 1.0,
        }
    }
}
