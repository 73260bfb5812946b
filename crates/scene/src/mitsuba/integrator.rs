//! The `<integrator>` element: read only for what would make Mitsuba's image differ from ppm-vk's.

use anyhow::Result;

use super::properties::Props;
use super::xml::Elem;
use super::Builder;

/// Integrators that render all light paths: Mitsuba 3's, then Mitsuba 0.6's (bidirectional, Metropolis,
/// photon mapping).
const FULL: &[&str] = &[
    "path",
    "volpath",
    "volpathmis",
    "ptracer",
    "prb",
    "prbvolpath",
    "volpath_simple",
    "bdpt",
    "pssmlt",
    "mlt",
    "erpt",
    "ppm",
    "sppm",
    "photonmapper",
];

/// Mitsuba 0.6's integrators that wrap another (adaptive sampling, irradiance caching): the image is the
/// nested one's.
const WRAPPERS: &[&str] = &["adaptive", "irrcache"];

/// Parameters that change only the noise of Mitsuba's estimate, or its speed: not warned about.
const NOISE_ONLY: &[&str] = &["max_depth", "rr_depth", "samples_per_pass", "timeout", "block_size"];

impl Builder {
    /// Integrators only choose how Mitsuba estimates the image; ppm-vk computes the same image
    /// (all paths) with its own. What would make Mitsuba's image differ is warned about.
    pub(super) fn integrator(&mut self, e: &Elem) -> Result<()> {
        let nested: Vec<&Elem> = e.children.iter().filter(|c| c.tag == "integrator").collect();
        let full = FULL.contains(&e.kind())
            || (WRAPPERS.contains(&e.kind()) && nested.iter().all(|n| FULL.contains(&n.kind())) && !nested.is_empty());
        if !full {
            self.warn(
                e,
                "ppm-vk renders all light paths (global illumination), not this integrator's image",
            );
        }
        let (props, _) = Props::of(e);
        if let Some(d) = props.float("max_depth")? {
            if d != -1.0 {
                self.warn(e, format!("max_depth {d} ignored: ppm-vk renders paths of any length"));
            }
        }
        // The others (Mitsuba 0.6's strictNormals, hideEmitters, photon counts, ...) are not read: said once.
        let mut unread: Vec<&str> = e
            .children
            .iter()
            .filter(|c| c.tag != "integrator")
            .filter_map(|c| c.attr("name"))
            .filter(|n| !NOISE_ONLY.contains(n))
            .collect();
        unread.dedup();
        if !unread.is_empty() {
            self.warn(
                e,
                format!(
                    "not read: {} (ppm-vk's estimator replaces the integrator's; it shows emitters seen directly)",
                    unread.join(", ")
                ),
            );
        }
        Ok(())
    }
}
