//! The `<integrator>` element: read only for what would make Mitsuba's image differ from ppm-vk's.

use anyhow::Result;

use super::properties::Props;
use super::xml::Elem;
use super::Builder;

impl Builder {
    /// Integrators only choose how Mitsuba estimates the image; ppm-vk computes the same image
    /// (all paths) with its own. What would make Mitsuba's image differ is warned about.
    pub(super) fn integrator(&mut self, e: &Elem) -> Result<()> {
        // Mitsuba 3's, then Mitsuba 0.6's (bidirectional, Metropolis, photon mapping): all paths, each.
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
        if !FULL.contains(&e.kind()) {
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
        Ok(())
    }
}
