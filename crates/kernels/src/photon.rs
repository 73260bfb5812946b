//! Stage 3, `shaders/photon/photon.comp`: photons from the lights to diffuse surfaces.

use anyhow::{bail, Result};
use bytemuck::{Pod, Zeroable};
use ppm_vk_device::{vk, Buffer, ComputePipeline};

use crate::push_struct;
use crate::ray::SceneBuffers;

/// Photons a thread traces one after another at most (`PhotonPush::per_thread`; fewer where the loop
/// budget needs it, see [`PathLimits`]).
pub const MAX_PER_THREAD: u32 = 8;
/// Random-stream families, so photon passes, the probe pass and the eye pass never share numbers.
pub const SALT_PHOTON: u32 = 1;
pub const SALT_PROBE: u32 = 2;
pub const SALT_EYE: u32 = 3;
/// The eye pass's emission-only samples (`SALT_EMISSION` in ray.comp).
pub const SALT_EMISSION: u32 = 4;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PhotonPush {
    /// Global index of the batch's first photon (its random stream).
    pub first: u64,
    pub count: u32,
    pub salt: u32,
    /// Photons per thread ([`PathLimits::per_thread`]).
    pub per_thread: u32,
    pub pad0: u32,
}
push_struct!(PhotonPush, PHOTON);

/// Surface interactions a photon path is allowed below which roulette alone ends paths for all practical
/// purposes: a path cut there has survived roulette at up to this many diffuse surfaces, probability
/// rho^512 (< 4e-12 at albedo 0.95). [`PathLimits`] aims at least this deep.
pub const TARGET_DEPTH: u32 = 512;
/// The shallowest photon backstop accepted: a diffuse path survives this many roulettes at albedo 0.95
/// with probability 0.95^135 < 0.1% (the loss the accuracy issue allows at that albedo).
pub const MIN_DEPTH: u32 = 135;
/// The shallowest eye backstop accepted. Eye paths end at the first diffuse surface; only a chain of
/// specular bounces reaches this, and its weight is then at most R^64 for mirrors of reflectance R (3% at
/// 0.95; glass can trap a path longer), so cut eye paths are counted and reported rather than bounded.
pub const MIN_EYE_DEPTH: u32 = 64;

/// How the tracing kernels bound their loops. Paths end by Russian roulette, absorption or escape; the
/// depth backstops exist because lavapipe silently ends every loop of a SIMD group after 65535 iterations
/// in all (`DeviceInfo::loop_budget`). They are chosen so that no group can reach that budget: a photon
/// thread's loop runs at most `per_thread * ((photon_depth + 1) * (1 + P) + L) + 1` iterations (P the
/// iterations of one intersection, L of choosing a light), and an eye thread's at most
/// `paths * ((eye_depth + 1) * (1 + P) + 2)`. Paths that reach a backstop are counted (`PathCounters`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PathLimits {
    pub per_thread: u32,
    /// Surface interactions of a photon path (`RenderParams::max_photon_depth`).
    pub photon_depth: u32,
    /// Specular bounces of an eye path (`RenderParams::max_eye_depth`).
    pub eye_depth: u32,
}

impl PathLimits {
    /// `budget`: the device's loop budget (`None`: unlimited); `intersect_steps`: loop iterations of one
    /// scene intersection (primitives looped over, or 0 when unrolled); `lights`: iterations of choosing a
    /// light; `eye_paths`: paths one eye thread traces (hit-point slots + emission samples); `photon_cap`
    /// and `eye_cap`: the depths asked for (Settings).
    pub fn new(budget: Option<u32>, intersect_steps: u32, lights: u32, eye_paths: u32, photon_cap: u32, eye_cap: u32) -> Result<PathLimits> {
        let Some(budget) = budget else {
            return Ok(PathLimits { per_thread: MAX_PER_THREAD, photon_depth: photon_cap, eye_depth: eye_cap });
        };
        let step = 1 + intersect_steps as u64;
        let budget = budget as u64 - 1;
        // Photons per thread: as many (up to 8) as leave TARGET_DEPTH (or the cap) within the budget.
        let want = TARGET_DEPTH.min(photon_cap) as u64;
        let per_thread = (budget / ((want + 1) * step + lights as u64)).clamp(1, MAX_PER_THREAD as u64);
        let photon_fit = (budget / per_thread).saturating_sub(lights as u64) / step;
        let photon_depth = photon_fit.saturating_sub(1).min(photon_cap as u64) as u32;
        let eye_fit = (budget / eye_paths.max(1) as u64).saturating_sub(2) / step;
        let eye_depth = eye_fit.saturating_sub(1).min(eye_cap as u64) as u32;
        if photon_depth < MIN_DEPTH.min(photon_cap) || eye_depth < MIN_EYE_DEPTH.min(eye_cap) {
            bail!(
                "the scene is too large for this device's loop budget ({} iterations per SIMD group): one ray \
                 intersection loops over {intersect_steps} primitives, which leaves photon paths {photon_depth} \
                 bounces (at least {MIN_DEPTH} keep the energy lost under 0.1%) and eye paths {eye_depth} \
                 (at least {MIN_EYE_DEPTH}); use fewer primitives, or fewer hit slots and emission samples",
                budget + 1
            );
        }
        Ok(PathLimits { per_thread: per_thread as u32, photon_depth, eye_depth })
    }
}

/// Traces `push.count` photons, appending their records to `photons` and counting them in `counter`
/// (which must be zero before; records past the capacity are counted but not written), and counting
/// paths cut at the depth backstop in `cut` (`PathCounters`).
#[allow(clippy::too_many_arguments)]
pub fn record(
    k: &ComputePipeline,
    cmd: vk::CommandBuffer,
    scene: &SceneBuffers,
    lights: &Buffer,
    photons: &Buffer,
    counter: &Buffer,
    cut: &Buffer,
    push: &PhotonPush,
) -> Result<()> {
    k.dispatch(
        cmd,
        &[scene.params, scene.spheres, scene.quads, scene.materials, lights, photons, counter, cut],
        bytemuck::bytes_of(push),
        push.count.div_ceil(push.per_thread.max(1)) as u64,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Worst-case loop iterations of one photon thread and one eye thread, as the struct's doc counts them.
    fn worst(l: &PathLimits, steps: u32, lights: u32, eye_paths: u32) -> (u64, u64) {
        let step = 1 + steps as u64;
        (
            l.per_thread as u64 * ((l.photon_depth as u64 + 1) * step + lights as u64) + 1,
            eye_paths as u64 * ((l.eye_depth as u64 + 1) * step + 2),
        )
    }

    #[test]
    fn limits_fit_the_budget_and_reach_the_target_depth() {
        for (steps, lights, eye_paths) in [(0, 0, 1), (10, 1, 5), (11, 2, 12), (64, 1, 8), (100, 3, 1)] {
            let l = PathLimits::new(Some(65535), steps, lights, eye_paths, 4096, 4096).unwrap();
            let (photon, eye) = worst(&l, steps, lights, eye_paths);
            assert!(photon <= 65535 && eye <= 65535, "{steps} steps: {l:?} needs {photon} / {eye}");
            assert!(l.photon_depth >= MIN_DEPTH && l.eye_depth >= MIN_EYE_DEPTH, "{l:?}");
            // The budget is used, not wasted: one more bounce would not fit.
            let deeper = PathLimits { photon_depth: l.photon_depth + 1, ..l };
            assert!(l.photon_depth == 4096 || worst(&deeper, steps, lights, eye_paths).0 > 65535, "{l:?}");
        }
        // Small scenes keep 8 photons per thread at the target depth.
        let l = PathLimits::new(Some(65535), 11, 1, 5, 4096, 4096).unwrap();
        assert!(l.per_thread == 8 && l.photon_depth >= TARGET_DEPTH, "{l:?}");
    }

    #[test]
    fn caps_are_kept_and_an_unlimited_device_takes_them() {
        let l = PathLimits::new(Some(65535), 11, 1, 5, 40, 3).unwrap();
        assert_eq!((l.photon_depth, l.eye_depth), (40, 3));
        let l = PathLimits::new(None, 1000, 1, 5, 4096, 1024).unwrap();
        assert_eq!(l, PathLimits { per_thread: MAX_PER_THREAD, photon_depth: 4096, eye_depth: 1024 });
    }

    #[test]
    fn a_scene_too_large_for_the_budget_is_an_error() {
        let e = PathLimits::new(Some(65535), 1000, 1, 5, 4096, 4096).unwrap_err().to_string();
        assert!(e.contains("loop budget") && e.contains("1000 primitives"), "{e}");
    }
}
