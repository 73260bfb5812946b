//! The photon grid's sizes: the starting search radius (eq. 8 or the setting), the cell, and the hash
//! table's buckets.

use ppm_vk_kernels::lookup::SCAN_BLOCK;

use crate::error::{Error, Result};
use crate::scene::Scene;
use crate::settings::Settings;

/// Eq. 8: r = 2 (X + Y + Z) / (3 s), X, Y, Z the extents of the scene's bounding box, s the image size
/// along one axis (the width).
pub fn default_radius(scene: &Scene) -> f32 {
    let (lo, hi) = scene.bounds();
    let e = hi - lo;
    2.0 * (e.x + e.y + e.z) / (3.0 * scene.camera.width as f32)
}

/// The starting search radius of every hit point: the setting, or eq. 8.
pub fn initial_radius(scene: &Scene, settings: &Settings) -> Result<f32> {
    let initial_radius = settings.initial_radius.unwrap_or_else(|| default_radius(scene));
    if !(initial_radius.is_finite() && initial_radius > 0.0) {
        return Err(Error::Settings {
            field: "initial_radius",
            message: format!("must be positive and finite, got {initial_radius}"),
        });
    }
    Ok(initial_radius)
}

/// The photon grid's starting cell: the setting, or [`CELL_PER_RADIUS`] starting radii.
pub fn cell_size(settings: &Settings, initial_radius: f32) -> Result<f32> {
    // Cells of CELL_PER_RADIUS starting radii. The probe may enlarge radii; the renderer then sizes
    // the cells for the largest (Renderer::fit_grid).
    let cell_size = CELL_PER_RADIUS * initial_radius;
    // A lookup window must stay under 1024 cells a side (grid_key in grid.glsl).
    let cell_size = match settings.grid_cell {
        Some(c) if !(c.is_finite() && c > 0.0 && c * 256.0 >= cell_size) => {
            return Err(Error::Settings {
                field: "grid_cell",
                message: format!("{c} must be positive and at least 1/256 of {cell_size} (the starting cell)"),
            })
        }
        Some(c) => c,
        None => cell_size,
    };
    Ok(cell_size)
}

/// Area of all surfaces (photons land only on them): sizes the grid's hash table.
pub fn surface_area(scene: &Scene) -> f64 {
    scene.quads.iter().map(|q| q.area() as f64).sum::<f64>()
        + scene
            .spheres
            .iter()
            .map(|s| 4.0 * std::f64::consts::PI * (s.radius as f64).powi(2))
            .sum::<f64>()
        + scene
            .meshes
            .iter()
            .flat_map(|m| m.triangles())
            .map(|t| t.area() as f64)
            .sum::<f64>()
}

/// A photon-grid cell's edge in search radii (of the largest radius live in the pass). The trade: smaller
/// cells read fewer photons outside each sphere (a lookup spans 2-3 cells a side, against 2 at twice the
/// radius) but want a larger hash table, which the grid build's scattered writes pay for. Measured on
/// lavapipe (docs/performance.md, "Issue 14, second session"): 1.4-1.7 fastest per pass; 2 and 1.2 about
/// 5-10% slower, 0.7 about 20%.
pub const CELL_PER_RADIUS: f32 = 1.5;

/// Buckets of the photon grid's hash table. Photons lie on surfaces, so the cells that ever hold one
/// are about (surface area / cell^2) times a small factor for cells a surface cuts at a slant; two
/// buckets per such cell keeps collisions rare while the table stays small enough to be cached (a table
/// sized by the photon count was 40x larger and its scan and atomics cost more than its collisions saved).
pub fn grid_buckets(surface_area: f64, cell_size: f32, photon_capacity: u32) -> u32 {
    let cells = 1.5 * surface_area / (cell_size as f64).powi(2);
    let wanted = (2.0 * cells).min(2.0 * photon_capacity as f64).max(1.0);
    (wanted as u64)
        .next_power_of_two()
        .clamp(SCAN_BLOCK as u64, SCAN_BLOCK as u64 * 65536) as u32
}
