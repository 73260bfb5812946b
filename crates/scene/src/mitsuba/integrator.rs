//! The `<integrator>` element: read only for what would make Mitsuba's image differ from ppm-vk's.

use anyhow::Result;

use super::elem::Elem;
use super::properties::Props;
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

/// Integrators that wrap another, whose image is the nested one's: Mitsuba 3's `moment` (it adds the
/// second moment as other channels) and `aov` (likewise, other channels), Mitsuba 0.6's `adaptive` and
/// `irrcache`.
const WRAPPERS: &[&str] = &["moment", "aov", "adaptive", "irrcache"];

/// Parameters that change only the noise of Mitsuba's estimate, or its speed: not warned about.
const NOISE_ONLY: &[&str] = &["max_depth", "rr_depth", "samples_per_pass", "timeout", "block_size"];

impl Builder {
    /// Integrators only choose how Mitsuba estimates the image; ppm-vk computes the same image
    /// (all paths) with its own. What would make Mitsuba's image differ is warned about.
    pub(super) fn integrator(&mut self, e: &Elem) -> Result<()> {
        let nested: Vec<&Elem> = e.children.iter().filter(|c| c.tag == "integrator").collect();
        if WRAPPERS.contains(&e.kind()) && !nested.is_empty() {
            // The nested integrators say what they render (nesting is bounded by the reader's MAX_NESTING).
            for n in nested {
                self.integrator(n)?;
            }
        } else if !FULL.contains(&e.kind()) {
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

#[cfg(test)]
mod tests {
    use super::super::tests::load_body;

    /// The warnings of `body`'s integrator (the test head has none).
    fn warnings(body: &str) -> Vec<String> {
        let s = load_body(body).unwrap_or_else(|e| panic!("{e:#}"));
        s.warnings
            .iter()
            .filter(|w| w.contains("<integrator"))
            .cloned()
            .collect()
    }

    #[test]
    fn full_transport_integrators_wrappers_and_unread_parameters() {
        for kind in ["path", "bdpt", "sppm", "photonmapper"] {
            assert!(
                warnings(&format!(r#"<integrator type="{kind}"/>"#)).is_empty(),
                "{kind}"
            );
        }
        let w = warnings(r#"<integrator type="direct"/>"#);
        assert!(w.len() == 1 && w[0].contains("not this integrator's image"), "{w:?}");
        // A wrapper's image is its nested integrator's: that one is read.
        assert!(warnings(r#"<integrator type="moment"><integrator type="volpath"/></integrator>"#).is_empty());
        let w = warnings(
            r#"<integrator type="aov"><string name="aovs" value="nn:sh_normal"/><integrator type="path"><integer name="max_depth" value="6"/></integrator></integrator>"#,
        );
        assert_eq!(w.len(), 2, "{w:?}");
        assert!(
            w[0].contains("<integrator type=\"path\">: max_depth 6 ignored"),
            "{w:?}"
        );
        assert!(w[1].contains("<integrator type=\"aov\">: not read: aovs"), "{w:?}");
        let w = warnings(r#"<integrator type="moment"/>"#);
        assert!(w.len() == 1 && w[0].contains("not this integrator's image"), "{w:?}");
        // Parameters of the noise only are not warned about; the others are named once.
        let w = warnings(
            r#"<integrator type="path"><integer name="rr_depth" value="5"/><boolean name="hide_emitters" value="true"/><boolean name="strict_normals" value="true"/></integrator>"#,
        );
        assert!(
            w.len() == 1 && w[0].contains("not read: hide_emitters, strict_normals"),
            "{w:?}"
        );
    }
}
