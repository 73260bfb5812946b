//! Stage 3, `shaders/photon/photon.comp`: photons from the lights to diffuse surfaces.

use anyhow::{bail, Result};
use bytemuck::{Pod, Zeroable};
use ppm_vk_device::{vk, Buffer, ComputePipeline};

use crate::layout::{PhotonState, PhotonWork};
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
pub const SALT_EMISSION: u32 = crate::reflected::constants::SALT_EMISSION;
/// The first cell of a pixel's stratified emission-sample positions in an eye pass (`SALT_STRATA` in
/// ray.comp).
pub const SALT_STRATA: u32 = crate::reflected::constants::SALT_STRATA;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PhotonPush {
    /// Global index of the batch's first photon (its random stream).
    pub first: u64,
    pub count: u32,
    pub salt: u32,
    /// Photons per thread ([`PathLimits::per_thread`]).
    pub per_thread: u32,
    /// 1: the resume round of a BVH scene's batch ([`record`]).
    pub resume: u32,
    /// BVH scenes: the least loop budget a thread starts a photon with ([`PathLimits::photon_reserve`]).
    pub reserve: u32,
    /// BVH scenes: a thread's loop budget in the first round ([`PathLimits::photon_first_budget`]); the
    /// resume round's is `RenderParams::photon_bvh_budget`.
    pub budget: u32,
}
push_struct!(PhotonPush, PHOTON);

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PhotonResumePush {
    pub count: u32,
    pub local_size: u32,
}
push_struct!(PhotonResumePush, PHOTON_RESUME);

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
/// `paths * ((eye_depth + 2) * (1 + P) + 2 + L)` (each path's last intersection and light choice are its
/// shadow ray's, where direct light is sampled). Paths that reach a backstop are counted (`PathCounters`).
///
/// With triangles, a BVH traversal takes a number of steps no bound fits well, so the threads count what
/// their loops take. A photon thread counts everything against `photon_bvh_budget` and starts photons
/// while `photon_reserve` is left; a photon that runs out is suspended and finished, with the photons no
/// thread started, in a resume round where each has a thread and a whole budget (photon.comp). An eye
/// thread gets the budget its other loops leave (`eye_bvh_budget`). A traversal that overruns a whole
/// budget stops and is counted (`PathCounters::traversal_cut`), and the renderer fails: never a silent
/// miss.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PathLimits {
    pub per_thread: u32,
    /// Surface interactions of a photon path (`RenderParams::max_photon_depth`).
    pub photon_depth: u32,
    /// Specular bounces of an eye path (`RenderParams::max_eye_depth`).
    pub eye_depth: u32,
    /// BVH steps a photon thread / an eye thread may take in all (`u32::MAX`: unlimited). A photon thread
    /// of a BVH scene counts its path steps against it too.
    pub photon_bvh_budget: u32,
    pub eye_bvh_budget: u32,
    /// BVH scenes: the least of its budget a thread starts a photon with (0: no BVH).
    pub photon_reserve: u32,
    /// BVH scenes: a thread's budget in the first round of a batch, `photon_bvh_budget` but where a test
    /// lowers it to send photons through the resume round.
    pub photon_first_budget: u32,
    /// Emission samples one eye thread takes per dispatch; an eye pass that wants more runs the ray kernel
    /// again for the rest (`RayPush::chunk`).
    pub emission_per_dispatch: u32,
}

/// Specular bounces aimed at for an eye path without a BVH (a mirror of reflectance 0.95 keeps 2e-6 of a
/// path's weight after 256).
const EYE_DEPTH: u32 = 256;
/// The most emission samples per eye thread and dispatch with a BVH (fewer where the budget needs it).
const BVH_EMISSION_PER_DISPATCH: u32 = 16;

/// Depths aimed at with a BVH: deep enough for roulette to end paths (0.95^512 < 4e-12), shallow enough to
/// leave most of the loop budget to traversal.
const BVH_PHOTON_DEPTH: u32 = 512;
const BVH_EYE_DEPTH: u32 = 128;
/// The least BVH budget a thread is left: about 100 traversals of a million-triangle BVH (58 steps per
/// ray measured, docs/measurements/bvh-build.txt) with room for incoherent ones.
pub const MIN_BVH_BUDGET: u32 = 16384;

impl PathLimits {
    /// `budget`: the device's loop budget (`None`: unlimited); `intersect_steps`: loop iterations of one
    /// scene intersection (primitives looped over, or 0 when unrolled); `lights`: iterations of choosing a
    /// light; `slots`: hit-point paths one eye thread traces; `emission`: emission samples per pixel and
    /// eye pass; `photon_cap` and `eye_cap`: the depths asked for (Settings).
    // Each argument is one of the budget's independent inputs, named where PathLimits is built.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        budget: Option<u32>,
        intersect_steps: u32,
        lights: u32,
        slots: u32,
        emission: u32,
        photon_cap: u32,
        eye_cap: u32,
    ) -> Result<PathLimits> {
        let Some(budget) = budget else {
            return Ok(PathLimits {
                per_thread: MAX_PER_THREAD,
                photon_depth: photon_cap,
                eye_depth: eye_cap,
                photon_bvh_budget: u32::MAX,
                eye_bvh_budget: u32::MAX,
                photon_reserve: 0,
                photon_first_budget: u32::MAX,
                emission_per_dispatch: emission,
            });
        };
        let step = 1 + intersect_steps as u64;
        let budget = budget as u64 - 1;
        // Photons per thread: as many (up to 8) as leave TARGET_DEPTH (or the cap) within the budget.
        let want = TARGET_DEPTH.min(photon_cap) as u64;
        let per_thread = (budget / ((want + 1) * step + lights as u64)).clamp(1, MAX_PER_THREAD as u64);
        let photon_fit = (budget / per_thread).saturating_sub(lights as u64) / step;
        let photon_depth = photon_fit.saturating_sub(1).min(photon_cap as u64) as u32;
        // Eye threads: the hit-point paths and as many emission samples as fit at EYE_DEPTH; the rest of the
        // samples go to further dispatches. Where not even one sample fits, as deep as the paths allow.
        let eye_target = EYE_DEPTH.min(eye_cap);
        let fit = budget / ((eye_target as u64 + 2) * step + 2 + lights as u64);
        let least = slots as u64 + emission.min(1) as u64;
        let (eye_depth, emission_per_dispatch) = if fit >= least {
            (eye_target, (fit - slots as u64).min(emission as u64) as u32)
        } else {
            let depth = ((budget / least.max(1)).saturating_sub(2 + lights as u64) / step).saturating_sub(2);
            (depth.min(eye_cap as u64) as u32, emission.min(1))
        };
        if photon_depth < MIN_DEPTH.min(photon_cap) || eye_depth < MIN_EYE_DEPTH.min(eye_cap) {
            bail!(
                "the scene is too large for this device's loop budget ({} iterations per SIMD group): one ray \
                 intersection loops over {intersect_steps} primitives, which leaves photon paths {photon_depth} \
                 bounces (at least {MIN_DEPTH} keep the energy lost under 0.1%) and eye paths {eye_depth} \
                 (at least {MIN_EYE_DEPTH}); use fewer primitives, or fewer hit slots and emission samples",
                budget + 1
            );
        }
        Ok(PathLimits {
            per_thread: per_thread as u32,
            photon_depth,
            eye_depth,
            photon_bvh_budget: u32::MAX,
            eye_bvh_budget: u32::MAX,
            photon_reserve: 0,
            photon_first_budget: u32::MAX,
            emission_per_dispatch,
        })
    }

    /// Paths one eye thread traces in a dispatch: the hit-point slots and its emission samples.
    pub fn eye_paths(&self, slots: u32) -> u32 {
        slots + self.emission_per_dispatch
    }

    /// The limits of a scene with a triangle BVH: one photon per thread, and what the depths leave of the
    /// budget goes to traversal (see the struct). Arguments as [`PathLimits::new`].
    // Each argument is one of the budget's independent inputs, named where PathLimits is built.
    #[allow(clippy::too_many_arguments)]
    pub fn with_bvh(
        budget: Option<u32>,
        intersect_steps: u32,
        lights: u32,
        slots: u32,
        emission: u32,
        photon_cap: u32,
        eye_cap: u32,
    ) -> Result<PathLimits> {
        let Some(budget) = budget else {
            return PathLimits::new(None, intersect_steps, lights, slots, emission, photon_cap, eye_cap);
        };
        let step = 1 + intersect_steps as u64;
        let total = budget as u64 - 1;
        // One photon path, as photon.comp counts it (PATH_STEP_LOOPS, LIGHT_LOOPS): the depth is the one
        // at which a path of its own, in the resume round, still leaves MIN_BVH_BUDGET to its traversals.
        let photon_loops = |depth: u32| (depth as u64 + 1) * (step + 2) + lights as u64 + 1;
        let eye_loops = |paths: u32, depth: u32| paths.max(1) as u64 * ((depth as u64 + 2) * step + 2 + lights as u64);
        let fit = |mut depth: u32, floor: u32, loops: &dyn Fn(u32) -> u64| -> Option<(u32, u32)> {
            loop {
                let left = total.saturating_sub(loops(depth));
                if left >= MIN_BVH_BUDGET as u64 {
                    return Some((depth, left as u32));
                }
                if depth <= floor {
                    return None;
                }
                depth = (depth / 2).max(floor);
            }
        };
        let photon = fit(
            BVH_PHOTON_DEPTH.min(photon_cap),
            MIN_DEPTH.min(photon_cap),
            &photon_loops,
        );
        // As many emission samples in one dispatch as leave the eye paths their depth (halving them, then
        // the depth): the fewer dispatches, the less an eye pass costs.
        let mut emission_per_dispatch = emission.min(BVH_EMISSION_PER_DISPATCH);
        let eye = loop {
            let paths = slots + emission_per_dispatch;
            let depth = BVH_EYE_DEPTH.min(eye_cap);
            let fitted = fit(depth, depth, &|d| eye_loops(paths, d));
            if fitted.is_some() || emission_per_dispatch <= 1 {
                let floor = MIN_EYE_DEPTH.min(eye_cap);
                break fitted.or_else(|| fit(depth, floor, &|d| eye_loops(paths, d)));
            }
            emission_per_dispatch /= 2;
        };
        let (Some((photon_depth, _)), Some((eye_depth, eye_bvh_budget))) = (photon, eye) else {
            bail!(
                "the scene is too large for this device's loop budget ({budget} iterations per SIMD group): \
                 one ray intersection loops over {intersect_steps} primitives besides the triangle BVH, which \
                 leaves too little for traversal (put the spheres and quads in meshes, or use fewer hit slots \
                 and emission samples)"
            );
        };
        Ok(PathLimits {
            per_thread: MAX_PER_THREAD,
            photon_depth,
            eye_depth,
            photon_bvh_budget: total as u32,
            eye_bvh_budget,
            photon_reserve: PHOTON_RESERVE,
            photon_first_budget: total as u32,
            emission_per_dispatch,
        })
    }
}

/// The least loop budget a photon thread of a BVH scene starts a photon with: as much as a whole path
/// usually takes many times over (a path of 5 bounces through a million triangles takes about 300 steps),
/// so that few photons are suspended, and a quarter of the budget, so that a thread gets through several.
pub const PHOTON_RESERVE: u32 = MIN_BVH_BUDGET;

/// What the photon kernel writes besides its records.
pub struct PhotonOutputs<'a> {
    /// The records (`Photon`, appended).
    pub photons: &'a Buffer,
    /// The records' count; zero before the batch. Records past the capacity are counted, not written.
    pub counter: &'a Buffer,
    /// Paths cut at the depth backstop and traversals cut short (`PathCounters`).
    pub cut: &'a Buffer,
    /// A BVH scene's work counters (`PhotonWork`); zero before the batch.
    pub work: &'a Buffer,
    /// The suspended photons (`PhotonState`), one per thread of the first round at most.
    pub suspended: &'a Buffer,
}

/// Traces `push.count` photons: one dispatch, and in a scene with a BVH (`bvh`) the resume round after it
/// (photon.comp): `resume` (photon_resume.comp) sizes it from the work counters, and it runs indirectly.
// One argument per buffer the kernels bind, in binding order (the reflected layout checks it).
#[allow(clippy::too_many_arguments)]
pub fn record(
    ctx: &ppm_vk_device::Context,
    k: &ComputePipeline,
    resume: &ComputePipeline,
    cmd: vk::CommandBuffer,
    scene: &SceneBuffers,
    lights: &Buffer,
    out: &PhotonOutputs,
    push: &PhotonPush,
    bvh: bool,
) -> Result<()> {
    let buffers = [
        &scene.bindings()[..],
        &[lights, out.photons, out.counter, out.cut, out.work, out.suspended],
    ]
    .concat();
    let first = PhotonPush { resume: 0, ..*push };
    k.dispatch(
        cmd,
        &buffers,
        bytemuck::bytes_of(&first),
        push.count.div_ceil(push.per_thread.max(1)) as u64,
    )?;
    if !bvh {
        return Ok(());
    }
    ppm_vk_device::barrier(ctx, cmd);
    let args = PhotonResumePush {
        count: push.count,
        local_size: k.local_size(),
    };
    resume.dispatch_groups(cmd, &[out.work], bytemuck::bytes_of(&args), [1, 1, 1])?;
    ppm_vk_device::barrier(ctx, cmd);
    let second = PhotonPush { resume: 1, ..*push };
    k.dispatch_indirect(
        cmd,
        &buffers,
        bytemuck::bytes_of(&second),
        out.work,
        PhotonWork::GROUPS_OFFSET,
    )
}

/// Bytes of the suspended photons' buffer for batches of up to `photons` photons at `per_thread` each.
pub fn suspended_bytes(photons: u32, per_thread: u32) -> u64 {
    photons.div_ceil(per_thread.max(1)) as u64 * std::mem::size_of::<PhotonState>() as u64
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Worst-case loop iterations of one photon thread and one eye thread, as the struct's doc counts them.
    fn worst(l: &PathLimits, steps: u32, lights: u32, slots: u32) -> (u64, u64) {
        let step = 1 + steps as u64;
        (
            l.per_thread as u64 * ((l.photon_depth as u64 + 1) * step + lights as u64) + 1,
            l.eye_paths(slots) as u64 * ((l.eye_depth as u64 + 2) * step + 2 + lights as u64),
        )
    }

    #[test]
    fn limits_fit_the_budget_and_reach_the_target_depth() {
        for (steps, lights, slots, emission) in [
            (0, 0, 1, 0),
            (10, 1, 1, 16),
            (11, 2, 4, 16),
            (64, 1, 8, 16),
            (100, 3, 1, 4),
            (70, 2, 4, 16),
        ] {
            let l = PathLimits::new(Some(65535), steps, lights, slots, emission, 4096, 1024).unwrap();
            let (photon, eye) = worst(&l, steps, lights, slots);
            assert!(
                photon <= 65535 && eye <= 65535,
                "{steps} steps: {l:?} needs {photon} / {eye}"
            );
            assert!(l.photon_depth >= MIN_DEPTH && l.eye_depth >= MIN_EYE_DEPTH, "{l:?}");
            assert!(
                l.emission_per_dispatch >= emission.min(1) && l.emission_per_dispatch <= emission,
                "{l:?}"
            );
            // The budget is used, not wasted: one more bounce would not fit.
            let deeper = PathLimits {
                photon_depth: l.photon_depth + 1,
                ..l
            };
            assert!(
                l.photon_depth == 4096 || worst(&deeper, steps, lights, slots).0 > 65535,
                "{l:?}"
            );
        }
        // Small scenes keep 8 photons per thread at the target depth and every emission sample in one go.
        let l = PathLimits::new(Some(65535), 11, 1, 1, 16, 4096, 1024).unwrap();
        assert!(
            l.per_thread == 8 && l.photon_depth >= TARGET_DEPTH && l.emission_per_dispatch == 16,
            "{l:?}"
        );
    }

    #[test]
    fn caps_are_kept_and_an_unlimited_device_takes_them() {
        let l = PathLimits::new(Some(65535), 11, 1, 4, 1, 40, 3).unwrap();
        assert_eq!((l.photon_depth, l.eye_depth), (40, 3));
        let l = PathLimits::new(None, 1000, 1, 4, 16, 4096, 1024).unwrap();
        assert_eq!(l.per_thread, MAX_PER_THREAD);
        assert_eq!(
            (l.photon_depth, l.eye_depth, l.photon_bvh_budget, l.eye_bvh_budget),
            (4096, 1024, u32::MAX, u32::MAX)
        );
        assert_eq!(l.emission_per_dispatch, 16);
    }

    #[test]
    fn a_scene_too_large_for_the_budget_is_an_error() {
        let e = PathLimits::new(Some(65535), 1000, 1, 4, 1, 4096, 4096)
            .unwrap_err()
            .to_string();
        assert!(e.contains("loop budget") && e.contains("1000 primitives"), "{e}");
    }

    #[test]
    fn bvh_limits_leave_the_traversal_its_budget() {
        for (steps, lights, slots, emission) in [(0, 1, 1, 16), (10, 18, 4, 16), (60, 3, 8, 4), (60, 3, 8, 16)] {
            let l = PathLimits::with_bvh(Some(65535), steps, lights, slots, emission, 4096, 1024).unwrap();
            assert!((1..=emission).contains(&l.emission_per_dispatch), "{l:?}");
            if steps < 60 {
                assert_eq!(
                    l.emission_per_dispatch, emission,
                    "a small scene takes them all at once: {l:?}"
                );
            }
            let step = 1 + steps as u64;
            // A photon thread counts all its loops against the whole budget; one path of the backstop's
            // depth on its own (the resume round) leaves its traversals MIN_BVH_BUDGET.
            let path = (l.photon_depth as u64 + 1) * (step + 2) + lights as u64 + 1;
            let eye = l.eye_paths(slots) as u64 * ((l.eye_depth as u64 + 2) * step + 2 + lights as u64)
                + l.eye_bvh_budget as u64;
            assert!(path + MIN_BVH_BUDGET as u64 <= 65534 && eye <= 65534, "{l:?}");
            assert!(
                l.photon_bvh_budget == 65534 && l.photon_reserve == PHOTON_RESERVE,
                "{l:?}"
            );
            assert!(
                l.per_thread == MAX_PER_THREAD && l.eye_bvh_budget >= MIN_BVH_BUDGET,
                "{l:?}"
            );
            assert!(l.photon_depth >= MIN_DEPTH && l.eye_depth >= MIN_EYE_DEPTH, "{l:?}");
        }
        assert!(PathLimits::with_bvh(Some(65535), 500, 1, 8, 4, 4096, 1024).is_err());
        // A device without a loop limit (any but lavapipe) takes the caps and an unbounded traversal,
        // however many primitives the scene has.
        let l = PathLimits::with_bvh(None, 500, 1, 8, 4, 4096, 1024).unwrap();
        assert_eq!(
            (l.photon_depth, l.eye_depth, l.photon_bvh_budget, l.eye_bvh_budget),
            (4096, 1024, u32::MAX, u32::MAX)
        );
        assert_eq!(l.emission_per_dispatch, 4);
    }
}
