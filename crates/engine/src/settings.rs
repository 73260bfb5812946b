//! Render settings and their defaults.

use anyhow::{bail, Result};

/// How to render. `Settings::default()` is the paper's setting for plain PPM.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Settings {
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
    /// Hit points per pixel: glass splits an eye path into both Fresnel branches up to this many leaves.
    pub hit_slots: u32,
    /// Specular bounces an eye path may take before it is dropped.
    pub max_eye_depth: u32,
    /// Bounces a photon path may take (diffuse records are further bounded by 16 per path).
    pub max_photon_depth: u32,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            photons_per_pass: 1_000_000,
            alpha: 0.7,
            seed: 0,
            initial_radius: None,
            cone_k: None,
            hit_slots: 4,
            max_eye_depth: 16,
            max_photon_depth: 64,
        }
    }
}

impl Settings {
    pub fn validate(&self) -> Result<()> {
        if self.photons_per_pass == 0 {
            bail!("photons per pass must be at least 1");
        }
        if !(self.alpha > 0.0 && self.alpha < 1.0) {
            bail!("alpha must be in (0, 1), got {}", self.alpha);
        }
        if let Some(k) = self.cone_k {
            if !(k.is_finite() && k >= 1.0) {
                bail!("cone filter constant k must be >= 1, got {k}");
            }
        }
        if let Some(r) = self.initial_radius {
            if !(r.is_finite() && r > 0.0) {
                bail!("initial radius must be positive and finite, got {r}");
            }
        }
        if !(1..=8).contains(&self.hit_slots) {
            bail!("hit slots per pixel must be in 1..=8, got {}", self.hit_slots);
        }
        if self.max_eye_depth == 0 || self.max_photon_depth == 0 {
            bail!("path depth limits must be at least 1");
        }
        Ok(())
    }

    /// The most a hit point's radius can grow above its start (1: radii only shrink in plain PPM).
    pub fn radius_growth_bound(&self) -> f32 {
        1.0
    }

    /// The cone filter's normalisation 1 - 2/(3k) (eq. 11), or 1 without it.
    pub fn cone_norm(&self) -> f32 {
        match self.cone_k {
            Some(k) => 1.0 - 2.0 / (3.0 * k),
            None => 1.0,
        }
    }
}
