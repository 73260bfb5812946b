//! The demo meshes of `scenes/`: OBJ and MTL files generated here, so that nothing is downloaded and
//! the large ones need not be committed. A dev-only crate: the scene crate keeps only the list of these files
//! and the command that writes them (`ppm_vk_scene::generated`), which this crate reads.
//!
//! The small files (`cornell-box`, `furnace-sphere`) are committed; a test checks that they are what
//! this crate writes. The large ones (`water`, ~207k triangles; `glass-sphere`, 20k; `glass-on-table`;
//! the staircase hall of `scenes/interior.xml`, ~30k in four files, its `interior` module) are written
//! on demand by [`ensure`]: [`COMMAND`] (the `gen_scenes` program of this crate),
//! `scripts/ppm-vk` before a scene with meshes, and the tests that load them. Every file starts with
//! [`STAMP`]; a file whose first line differs (absent, or from an older generator) is rewritten.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context as _, Result};
use glam::DVec3;
pub use ppm_vk_scene::generated::{DemoFile, COMMAND, FILES};

/// First line of every generated file; bump the version when the geometry changes. (It still names the
/// generator's old path, crates/engine/src/scene/demo.rs: a new text would rewrite every generated file.)
pub const STAMP: &str = "# ppm-vk demo mesh v1: written by crates/engine/src/scene/demo.rs (gen_scenes), do not edit";

/// The content of file `f` of [`FILES`].
pub fn contents(f: &DemoFile) -> String {
    let make: fn() -> String = match f.name {
        "cornell-box.obj" => cornell_box_obj,
        "cornell-box.mtl" => cornell_box_mtl,
        "furnace-sphere.obj" => furnace_sphere_obj,
        "furnace-sphere.mtl" => furnace_sphere_mtl,
        "smooth-sphere.obj" => smooth_sphere_obj,
        "glass-sphere.obj" => glass_sphere_obj,
        "water.obj" => water_obj,
        "dense-sphere.obj" => dense_sphere_obj,
        "water.mtl" => water_mtl,
        "glass-on-table.obj" => glass_on_table_obj,
        "glass-on-table.mtl" => glass_on_table_mtl,
        "gold-ring.obj" => gold_ring_obj,
        "interior-shell.obj" => interior::shell_obj,
        "interior-wood.obj" => interior::wood_obj,
        "interior-glass.obj" => interior::glass_obj,
        "interior-metal.obj" => interior::metal_obj,
        name => panic!("no generator writes {name} (listed in the engine's scene/generated.rs)"),
    };
    make()
}

/// `scenes/meshes` of this repository, where the demo scenes look for their meshes.
pub fn default_dir() -> PathBuf {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    // crates/scene-gen -> the repository root.
    crate_dir.ancestors().nth(2).unwrap_or(crate_dir).join("scenes/meshes")
}

/// Writes every demo file into `dir` that is missing or was written by another generator version;
/// returns the paths written. Each file is written to a temporary name and renamed, so a reader
/// never sees half a file.
pub fn ensure(dir: &Path) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let mut written = Vec::new();
    for f in FILES {
        let path = dir.join(f.name);
        if first_line(&path).as_deref() == Some(STAMP) {
            continue;
        }
        // The process and a count: two threads of one process (tests) must not share a temporary name.
        static WRITES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let n = WRITES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let tmp = dir.join(format!("{}.tmp.{}.{n}", f.name, std::process::id()));
        std::fs::write(&tmp, contents(f)).with_context(|| format!("writing {}", tmp.display()))?;
        std::fs::rename(&tmp, &path).with_context(|| format!("renaming {} to {}", tmp.display(), path.display()))?;
        written.push(path);
    }
    Ok(written)
}

fn first_line(path: &Path) -> Option<String> {
    use std::io::BufRead as _;
    let f = std::fs::File::open(path).ok()?;
    std::io::BufReader::new(f).lines().next()?.ok()
}

// ---------------------------------------------------------------------------
// Geometry: vertices in f64, triangles counter-clockwise seen from their front.

/// Triangles with positions and, optionally, a normal index per corner.
#[derive(Default)]
struct Model {
    v: Vec<DVec3>,
    vn: Vec<DVec3>,
    /// Texture coordinates (`vt`), for the textured surfaces of the interior.
    vt: Vec<[f64; 2]>,
    groups: Vec<Group>,
}

struct Group {
    name: String,
    material: Option<String>,
    /// `[v, vn, vt]` (0-based) per corner; `vn` and `vt` are `u32::MAX` for none.
    faces: Vec<[[u32; 3]; 3]>,
}

const NO_NORMAL: u32 = u32::MAX;

impl Model {
    fn vertex(&mut self, p: DVec3) -> u32 {
        self.v.push(p);
        self.v.len() as u32 - 1
    }

    fn normal(&mut self, n: DVec3) -> u32 {
        self.vn.push(n.normalize());
        self.vn.len() as u32 - 1
    }

    fn group(&mut self, name: &str, material: Option<&str>) {
        self.groups.push(Group {
            name: name.into(),
            material: material.map(Into::into),
            faces: Vec::new(),
        });
    }

    /// Adds triangle `t`, flipped if needed so that its front faces along `outward`.
    fn face(&mut self, t: [u32; 3], n: [u32; 3], outward: DVec3) {
        self.face_uv(t, n, [NO_NORMAL; 3], outward);
    }

    /// [`Model::face`] with a texture coordinate index per corner.
    fn face_uv(&mut self, t: [u32; 3], n: [u32; 3], uv: [u32; 3], outward: DVec3) {
        let p = t.map(|i| self.v[i as usize]);
        let flip = (p[1] - p[0]).cross(p[2] - p[0]).dot(outward) < 0.0;
        let order = if flip { [0, 2, 1] } else { [0, 1, 2] };
        if let Some(g) = self.groups.last_mut() {
            g.faces.push(order.map(|k| [t[k], n[k], uv[k]]));
        }
    }

    #[cfg(test)]
    fn triangles(&self) -> impl Iterator<Item = [u32; 3]> + '_ {
        self.groups
            .iter()
            .flat_map(|g| g.faces.iter().map(|f| [f[0][0], f[1][0], f[2][0]]))
    }

    fn write(&self, mtllib: Option<&str>) -> String {
        let mut s = String::with_capacity(64 * (self.v.len() + self.vn.len()) + 48 * 1024);
        let _ = writeln!(s, "{STAMP}");
        if let Some(m) = mtllib {
            let _ = writeln!(s, "mtllib {m}");
        }
        // f32 shortest round-trip text: exactly what the loader reads back, and short.
        for p in &self.v {
            let _ = writeln!(s, "v {} {} {}", p.x as f32, p.y as f32, p.z as f32);
        }
        for n in &self.vn {
            let _ = writeln!(s, "vn {} {} {}", n.x as f32, n.y as f32, n.z as f32);
        }
        for [u, v] in &self.vt {
            let _ = writeln!(s, "vt {} {}", *u as f32, *v as f32);
        }
        for g in &self.groups {
            let _ = writeln!(s, "o {}", g.name);
            if let Some(m) = &g.material {
                let _ = writeln!(s, "usemtl {m}");
            }
            for f in &g.faces {
                s.push('f');
                for &[v, n, t] in f {
                    let _ = match (n == NO_NORMAL, t == NO_NORMAL) {
                        (true, true) => write!(s, " {}", v + 1),
                        (false, true) => write!(s, " {}//{}", v + 1, n + 1),
                        (true, false) => write!(s, " {}/{}", v + 1, t + 1),
                        (false, false) => write!(s, " {}/{}/{}", v + 1, t + 1, n + 1),
                    };
                }
                s.push('\n');
            }
        }
        s
    }
}

/// A quad `origin + s u + t v` as two triangles whose front normal is `u x v` (as a TOML quad's).
fn quad(m: &mut Model, origin: [f64; 3], u: [f64; 3], v: [f64; 3]) {
    let (o, u, v) = (DVec3::from_array(origin), DVec3::from_array(u), DVec3::from_array(v));
    let c = [o, o + u, o + u + v, o + v].map(|p| m.vertex(p));
    let n = [NO_NORMAL; 3];
    m.face([c[0], c[1], c[2]], n, u.cross(v));
    m.face([c[0], c[2], c[3]], n, u.cross(v));
}

/// Unit icosphere: the icosahedron subdivided `level` times; `(positions, triangles)`, outward.
fn icosphere(level: u32) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut v: Vec<DVec3> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .map(|p| DVec3::from_array(p).normalize())
    .to_vec();
    let mut f: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut mid = std::collections::HashMap::new();
        let mut split = |a: u32, b: u32, v: &mut Vec<DVec3>| -> u32 {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                v.push(((v[a as usize] + v[b as usize]) * 0.5).normalize());
                v.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(f.len() * 4);
        for [a, b, c] in f {
            let (ab, bc, ca) = (split(a, b, &mut v), split(b, c, &mut v), split(c, a, &mut v));
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        f = next;
    }
    (v, f)
}

/// An icosphere of `level`, front side out, with the sphere's normals; or front side in (a room
/// inside it), flat.
fn sphere_model(level: u32, inward: bool, material: Option<&str>, name: &str) -> Model {
    let (v, f) = icosphere(level);
    let mut m = Model {
        v: v.clone(),
        ..Model::default()
    };
    if !inward {
        m.vn = v;
    }
    m.group(name, material);
    for t in f {
        let centre = t.iter().map(|&i| m.v[i as usize]).sum::<DVec3>();
        if inward {
            m.face(t, [NO_NORMAL; 3], -centre);
        } else {
            m.face(t, t, centre);
        }
    }
    m
}

/// Axis-aligned box, front sides out, one flat normal per side.
fn box_model(m: &mut Model, lo: DVec3, hi: DVec3) {
    let centre = (lo + hi) * 0.5;
    let corner = |i: u32| {
        DVec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    };
    let c: Vec<u32> = (0..8).map(|i| m.vertex(corner(i))).collect();
    // Each side: the 4 corners whose bit `axis` equals `side`, in an order going round the face.
    for axis in 0..3 {
        for side in 0..2u32 {
            let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
            let ring: Vec<u32> = [(0, 0), (1, 0), (1, 1), (0, 1)]
                .iter()
                .map(|&(x, y)| (side << axis) | (x << a) | (y << b))
                .collect();
            let p = ring.iter().map(|&i| corner(i)).sum::<DVec3>() / 4.0;
            let out = p - centre;
            let n = m.normal(out);
            let r = ring.iter().map(|&i| c[i as usize]).collect::<Vec<_>>();
            m.face([r[0], r[1], r[2]], [n; 3], out);
            m.face([r[0], r[2], r[3]], [n; 3], out);
        }
    }
}

/// Torus about the y axis through `centre`: ring radius `big`, tube radius `small`, with normals.
fn torus_model(m: &mut Model, centre: DVec3, big: f64, small: f64, nu: u32, nv: u32) {
    use std::f64::consts::TAU;
    let first = m.v.len() as u32;
    let first_n = m.vn.len() as u32;
    for i in 0..nu {
        let u = TAU * i as f64 / nu as f64;
        for j in 0..nv {
            let w = TAU * j as f64 / nv as f64;
            let n = DVec3::new(w.cos() * u.cos(), w.sin(), w.cos() * u.sin());
            m.vertex(centre + DVec3::new(big * u.cos(), 0.0, big * u.sin()) + small * n);
            m.normal(n);
        }
    }
    let at = |i: u32, j: u32| (i % nu) * nv + (j % nv);
    for i in 0..nu {
        for j in 0..nv {
            let q = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
            let out = m.vn[(first_n + q[0]) as usize] + m.vn[(first_n + q[2]) as usize];
            let (v, n) = (q.map(|k| first + k), q.map(|k| first_n + k));
            m.face([v[0], v[1], v[2]], [n[0], n[1], n[2]], out);
            m.face([v[0], v[2], v[3]], [n[0], n[2], n[3]], out);
        }
    }
}

// ---------------------------------------------------------------------------
// The files.

/// cornell-spheres' six walls and light, `[origin, edge_u, edge_v]` as in its TOML, with materials.
const CORNELL_QUADS: [(&str, &str, [[f64; 3]; 3]); 7] = [
    ("floor", "white", [[-1.0, 0.0, -1.0], [0.0, 0.0, 4.0], [2.0, 0.0, 0.0]]),
    (
        "ceiling",
        "white",
        [[-1.0, 2.0, -1.0], [2.0, 0.0, 0.0], [0.0, 0.0, 4.0]],
    ),
    ("back", "white", [[-1.0, 0.0, -1.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]]),
    ("front", "white", [[-1.0, 0.0, 3.0], [0.0, 2.0, 0.0], [2.0, 0.0, 0.0]]),
    ("left", "red", [[-1.0, 0.0, -1.0], [0.0, 2.0, 0.0], [0.0, 0.0, 4.0]]),
    ("right", "green", [[1.0, 0.0, -1.0], [0.0, 0.0, 4.0], [0.0, 2.0, 0.0]]),
    (
        "light",
        "light",
        [[-0.25, 1.99, -0.55], [0.5, 0.0, 0.0], [0.0, 0.0, 0.5]],
    ),
];

fn cornell_box_obj() -> String {
    let mut m = Model::default();
    for (name, material, [o, u, v]) in CORNELL_QUADS {
        m.group(name, Some(material));
        quad(&mut m, o, u, v);
    }
    m.write(Some("cornell-box.mtl"))
}

fn cornell_box_mtl() -> String {
    format!(
        "{STAMP}\n# cornell-spheres' materials: Kd diffuse albedo; the light is a black emitter (Kd 0, Ke)\n\
         newmtl white\nKd 0.725 0.71 0.68\n\n\
         newmtl red\nKd 0.63 0.065 0.05\n\n\
         newmtl green\nKd 0.14 0.45 0.091\n\n\
         newmtl light\nKd 0 0 0\nKe 34 30 24\n"
    )
}

/// Level 3: 1280 triangles, facing the centre.
fn furnace_sphere_obj() -> String {
    sphere_model(3, true, Some("grey"), "furnace").write(Some("furnace-sphere.mtl"))
}

fn furnace_sphere_mtl() -> String {
    format!(
        "{STAMP}\n# albedo 0.5, emission 1: inside, L = Le / (1 - rho) = 2 everywhere\n\
         newmtl grey\nKd 0.5 0.5 0.5\nKe 1 1 1\n"
    )
}

/// Level 2: 320 triangles, unit radius at the origin, with the sphere's normals, no MTL: a coarse mesh
/// that smooth shading makes round (`scenes/cornell-smooth.toml`).
fn smooth_sphere_obj() -> String {
    sphere_model(2, false, None, "sphere").write(None)
}

/// Level 5: 20480 triangles, unit radius at the origin, no MTL (the scene gives the material).
fn glass_sphere_obj() -> String {
    sphere_model(5, false, None, "sphere").write(None)
}

/// Level 8: 1310720 triangles, unit radius at the origin, flat (no normals), no MTL: the million-triangle
/// benchmark scene (`scenes/cornell-dense.toml`).
fn dense_sphere_obj() -> String {
    let (v, f) = icosphere(8);
    let mut m = Model { v, ..Model::default() };
    m.group("sphere", None);
    for t in f {
        let centre = t.iter().map(|&i| m.v[i as usize]).sum::<DVec3>();
        m.face(t, [NO_NORMAL; 3], centre);
    }
    m.write(None)
}

/// Waves of the water surface: (amplitude, wavelength, direction in radians, phase), all metres.
const WAVES: [(f64, f64, f64, f64); 3] = [
    (0.006, 0.31, 0.3, 0.0),
    (0.005, 0.23, 1.9, 1.3),
    (0.004, 0.17, 3.7, 2.1),
];

/// Height above the mean level and its gradient (d/dx, d/dz).
fn wave(x: f64, z: f64) -> (f64, f64, f64) {
    let (mut h, mut gx, mut gz) = (0.0, 0.0, 0.0);
    for (a, wavelength, dir, phase) in WAVES {
        let k = std::f64::consts::TAU / wavelength;
        let (kx, kz) = (k * dir.cos(), k * dir.sin());
        let arg = kx * x + kz * z + phase;
        h += a * arg.sin();
        gx += a * kx * arg.cos();
        gz += a * kz * arg.cos();
    }
    (h, gx, gz)
}

/// The water of cornell-water: a closed slab over the Cornell box's floor, 1 cm from the walls, flat
/// bottom 2 mm above the floor, wavy top around y = 0.3; a 160 x 320 grid top and bottom, joined by
/// sides: 206,720 triangles. Top vertices carry the waves' normals, the rest flat ones.
fn water_obj() -> String {
    let (nx, nz) = (160u32, 320u32);
    let (x0, x1, z0, z1) = (-0.99, 0.99, -0.99, 2.99);
    let (bottom, level) = (0.002, 0.3);
    let mut m = Model::default();
    m.group("water", Some("water"));
    let pos = |i: u32, k: u32| {
        (
            x0 + (x1 - x0) * i as f64 / nx as f64,
            z0 + (z1 - z0) * k as f64 / nz as f64,
        )
    };
    let at = |i: u32, k: u32| k * (nx + 1) + i;
    let cells = (nx + 1) * (nz + 1);
    for k in 0..=nz {
        for i in 0..=nx {
            let (x, z) = pos(i, k);
            let (h, gx, gz) = wave(x, z);
            m.vertex(DVec3::new(x, level + h, z));
            m.normal(DVec3::new(-gx, 1.0, -gz));
        }
    }
    for k in 0..=nz {
        for i in 0..=nx {
            let (x, z) = pos(i, k);
            m.vertex(DVec3::new(x, bottom, z));
        }
    }
    let down = m.normal(DVec3::NEG_Y);
    for k in 0..nz {
        for i in 0..nx {
            let q = [at(i, k), at(i + 1, k), at(i + 1, k + 1), at(i, k + 1)];
            m.face([q[0], q[1], q[2]], [q[0], q[1], q[2]], DVec3::Y);
            m.face([q[0], q[2], q[3]], [q[0], q[2], q[3]], DVec3::Y);
            let b = q.map(|v| v + cells);
            m.face([b[0], b[1], b[2]], [down; 3], DVec3::NEG_Y);
            m.face([b[0], b[2], b[3]], [down; 3], DVec3::NEG_Y);
        }
    }
    // Sides: each rim segment (top a -> b) and the bottom below it, facing away from the slab.
    let sides: [(DVec3, Vec<u32>); 4] = [
        (DVec3::NEG_Z, (0..=nx).map(|i| at(i, 0)).collect()),
        (DVec3::Z, (0..=nx).map(|i| at(i, nz)).collect()),
        (DVec3::NEG_X, (0..=nz).map(|k| at(0, k)).collect()),
        (DVec3::X, (0..=nz).map(|k| at(nx, k)).collect()),
    ];
    for (out, rim) in sides {
        let n = m.normal(out);
        for w in rim.windows(2) {
            let (a, b) = (w[0], w[1]);
            m.face([a, a + cells, b + cells], [n; 3], out);
            m.face([a, b + cells, b], [n; 3], out);
        }
    }
    m.write(Some("water.mtl"))
}

fn water_mtl() -> String {
    format!("{STAMP}\n# clear water: illum 7 (refraction), Ni its index\nnewmtl water\nNi 1.33\nillum 7\n")
}

/// A table (a 1.2 x 0.5 x 0.8 m box) with a glass torus lying on it (ring 0.15 m, tube 0.05 m,
/// 96 x 48 segments: 9216 triangles), 0.5 mm above the top so they do not touch.
fn glass_on_table_obj() -> String {
    let mut m = Model::default();
    m.group("table", Some("wood"));
    box_model(&mut m, DVec3::new(-0.6, 0.0, -0.4), DVec3::new(0.6, 0.5, 0.4));
    m.group("torus", Some("glass"));
    torus_model(&mut m, DVec3::new(0.0, 0.5505, 0.0), 0.15, 0.05, 96, 48);
    m.write(Some("glass-on-table.mtl"))
}

fn glass_on_table_mtl() -> String {
    format!(
        "{STAMP}\nnewmtl wood\nKd 0.55 0.38 0.22\n\n\
         # glass: illum 7 (refraction), Ni its index\nnewmtl glass\nNi 1.5\nillum 7\n"
    )
}

/// A ring standing on its edge circle (axis vertical, base at y = 0): outer radius 0.1 m, wall 6 mm,
/// height 4 cm, 192 segments (1536 triangles); its material comes from the scene (gold-ring.toml).
fn gold_ring_obj() -> String {
    use std::f64::consts::TAU;
    let (outer, inner, height, n) = (0.1, 0.094, 0.04, 192u32);
    let mut m = Model::default();
    m.group("ring", None);
    let at = |r: f64, y: f64, i: u32| {
        let a = TAU * (i % n) as f64 / n as f64;
        DVec3::new(r * a.cos(), y, r * a.sin())
    };
    let none = [NO_NORMAL; 3];
    for i in 0..n {
        let mid = TAU * (i as f64 + 0.5) / n as f64;
        let radial = DVec3::new(mid.cos(), 0.0, mid.sin());
        // (corner a at segment i, corner b at i + 1) for each of the four walls, and which way it faces.
        let walls = [
            (outer, outer, 0.0, height, radial),      // outside
            (inner, inner, 0.0, height, -radial),     // inside, facing the axis
            (inner, outer, height, height, DVec3::Y), // top
            (inner, outer, 0.0, 0.0, -DVec3::Y),      // bottom
        ];
        for &(r0, r1, y0, y1, facing) in &walls {
            let (p00, p10) = (at(r0, y0, i), at(r0, y0, i + 1));
            let (p01, p11) = (at(r1, y1, i), at(r1, y1, i + 1));
            let v = [p00, p10, p11, p01].map(|p| m.vertex(p));
            m.face([v[0], v[1], v[2]], none, facing);
            m.face([v[0], v[2], v[3]], none, facing);
        }
    }
    m.write(None)
}

// ---------------------------------------------------------------------------
// The interior (issue 39): a module of its own in this file (it uses the geometry above, and `contents` its
// files).

mod interior {
    //! The interior of `scenes/interior.xml` (issue 39): a staircase hall of about 30k triangles, one OBJ per
    //! material, since a Mitsuba `obj` shape carries one BSDF. Units: metres, +y up.
    //!
    //! The hall is x in [-4, 4], y in [0, 6], z in [-5, 3]. A straight flight of 16 steps along the left wall
    //! (x in [-3.9, -2.3]) rises from z = 2 to a landing (a slab, top at y = 3) across the back (z in
    //! [-5, -2]). A glass balustrade (closed panels 2 cm thick) runs up the open side of the flight and
    //! along the landing's edge, held by metal posts under a metal handrail; a metal ring stands on a
    //! pedestal in the hall. The scene file places the 13 lights (disks and rectangles).

    use glam::DVec3;

    use super::{icosphere, torus_model, Model, NO_NORMAL};

    /// The hall's extent.
    const LO: DVec3 = DVec3::new(-4.0, 0.0, -5.0);
    const HI: DVec3 = DVec3::new(4.0, 6.0, 3.0);
    /// Steps of the flight, their rise (16 x 0.1875 = 3 m) and run (16 x 0.25 = 4 m).
    pub const STEPS: u32 = 16;
    const RISE: f64 = 3.0 / STEPS as f64;
    const RUN: f64 = 4.0 / STEPS as f64;
    /// The flight's sides and where it starts (its foot, z) and ends (the landing's edge).
    const STAIR_X: (f64, f64) = (-3.9, -2.3);
    const STAIR_FOOT: f64 = 2.0;
    const LANDING_EDGE: f64 = -2.0;
    const LANDING_TOP: f64 = 3.0;
    /// The balustrade's line on the flight (x) and on the landing (z); its rail height above the nosing.
    const RAIL_X: f64 = -2.26;
    const RAIL_Z: f64 = -2.1;
    const RAIL_HEIGHT: f64 = 1.0;
    /// Glass panels on the flight and on the landing, and the pedestal's box.
    pub const STAIR_PANELS: u32 = 4;
    pub const LANDING_PANELS: u32 = 6;
    const PEDESTAL: (DVec3, DVec3) = (DVec3::new(1.1, 0.0, 0.1), DVec3::new(1.9, 0.8, 0.9));
    /// Texture repeats per metre on the wood (the 512 x 256 wood.png spans 1 x 0.5 m).
    const WOOD_UV_PER_M: [f64; 2] = [1.0, 2.0];

    /// Height of the flight's nosing line at `z` (the stair's slope).
    fn nosing(z: f64) -> f64 {
        ((STAIR_FOOT - z) / (STAIR_FOOT - LANDING_EDGE)).clamp(0.0, 1.0) * LANDING_TOP
    }

    /// A hexahedron from its 8 corners, indexed by bits (x: 1, y: 2, z: 4) as [`super::box_model`]'s, front
    /// sides out; flat (a normal per side), with texture coordinates projected on each side's own axes when `uv` is set.
    fn hexa(m: &mut Model, corner: [DVec3; 8], uv: bool) {
        let centre = corner.iter().sum::<DVec3>() / 8.0;
        let c = corner.map(|p| m.vertex(p));
        for axis in 0..3 {
            for side in 0..2u32 {
                let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
                let ring =
                    [(0, 0), (1, 0), (1, 1), (0, 1)].map(|(x, y)| ((side << axis) | (x << a) | (y << b)) as usize);
                let mid = ring.iter().map(|&i| corner[i]).sum::<DVec3>() / 4.0;
                let out = mid - centre;
                let t = match uv {
                    // The side's two in-plane axes (the world axes other than its normal's largest).
                    true => {
                        let (ua, va) = match out.abs().max_element() {
                            x if x == out.x.abs() => (DVec3::Z, DVec3::Y),
                            y if y == out.y.abs() => (DVec3::X, DVec3::Z),
                            _ => (DVec3::X, DVec3::Y),
                        };
                        ring.map(|i| {
                            m.vt.push([
                                corner[i].dot(ua) * WOOD_UV_PER_M[0],
                                corner[i].dot(va) * WOOD_UV_PER_M[1],
                            ]);
                            m.vt.len() as u32 - 1
                        })
                    }
                    false => [NO_NORMAL; 4],
                };
                // A flat normal per side (without one, Mitsuba's OBJ loader would smooth across the corners).
                let p = ring.map(|i| corner[i]);
                let normal = (p[1] - p[0]).cross(p[3] - p[0]);
                let n = m.normal(if normal.dot(out) < 0.0 { -normal } else { normal });
                let r = ring.map(|i| c[i]);
                m.face_uv([r[0], r[1], r[2]], [n; 3], [t[0], t[1], t[2]], out);
                m.face_uv([r[0], r[2], r[3]], [n; 3], [t[0], t[2], t[3]], out);
            }
        }
    }

    fn aabb(lo: DVec3, hi: DVec3) -> [DVec3; 8] {
        std::array::from_fn(|i| {
            DVec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            )
        })
    }

    /// A closed cylinder from `a` to `b` of radius `r`: `around` segments, `along` bands, flat caps; smooth
    /// normals on the side.
    fn cylinder(m: &mut Model, a: DVec3, b: DVec3, r: f64, around: u32, along: u32) {
        use std::f64::consts::TAU;
        let axis = (b - a).normalize();
        let (e1, e2) = axis.any_orthonormal_pair();
        let dir = |k: u32| {
            let t = TAU * (k % around) as f64 / around as f64;
            e1 * t.cos() + e2 * t.sin()
        };
        let first = m.v.len() as u32;
        let first_n = m.vn.len() as u32;
        for k in 0..around {
            m.normal(dir(k));
        }
        for j in 0..=along {
            let p = a.lerp(b, j as f64 / along as f64);
            for k in 0..around {
                m.vertex(p + r * dir(k));
            }
        }
        let at = |j: u32, k: u32| first + j * around + k % around;
        for j in 0..along {
            for k in 0..around {
                let q = [at(j, k), at(j, k + 1), at(j + 1, k + 1), at(j + 1, k)];
                let n = [k, k + 1, k + 1, k].map(|k| first_n + k % around);
                let out = dir(k) + dir(k + 1);
                m.face([q[0], q[1], q[2]], [n[0], n[1], n[2]], out);
                m.face([q[0], q[2], q[3]], [n[0], n[2], n[3]], out);
            }
        }
        // Caps: a fan about each end's centre, facing along the axis.
        for (j, centre, out) in [(0, a, -axis), (along, b, axis)] {
            let c = m.vertex(centre);
            let n = m.normal(out);
            for k in 0..around {
                m.face([c, at(j, k), at(j, k + 1)], [n; 3], out);
            }
        }
    }

    /// A sphere of radius `r` at `centre` (icosphere `level`), with its normals.
    fn ball(m: &mut Model, centre: DVec3, r: f64, level: u32) {
        let (v, f) = icosphere(level);
        let (first, first_n) = (m.v.len() as u32, m.vn.len() as u32);
        for p in &v {
            m.vertex(centre + r * *p);
            m.normal(*p);
        }
        for t in f {
            let out = t.iter().map(|&i| v[i as usize]).sum::<DVec3>();
            m.face(t.map(|i| first + i), t.map(|i| first_n + i), out);
        }
    }

    /// Walls, floor and ceiling (facing in) and the pedestal: plain diffuse.
    pub fn shell_obj() -> String {
        let mut m = Model::default();
        m.group("hall", None);
        let c = aabb(LO, HI);
        let centre = (LO + HI) * 0.5;
        let cv = c.map(|p| m.vertex(p));
        for axis in 0..3 {
            for side in 0..2u32 {
                let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
                let r =
                    [(0, 0), (1, 0), (1, 1), (0, 1)].map(|(x, y)| cv[((side << axis) | (x << a) | (y << b)) as usize]);
                let mid = [(0, 0), (1, 1)]
                    .map(|(x, y)| c[((side << axis) | (x << a) | (y << b)) as usize])
                    .iter()
                    .sum::<DVec3>()
                    / 2.0;
                // Facing into the hall, flat.
                let n = m.normal(centre - mid);
                m.face([r[0], r[1], r[2]], [n; 3], centre - mid);
                m.face([r[0], r[2], r[3]], [n; 3], centre - mid);
            }
        }
        m.group("pedestal", None);
        hexa(&mut m, aabb(PEDESTAL.0, PEDESTAL.1), false);
        m.write(None)
    }

    /// The steps, the landing slab and the hall's wooden floor boards (a slab 2 cm thick on the floor
    /// would double the floor; the floor instead is a thin deck over the shell's floor): textured.
    pub fn wood_obj() -> String {
        let mut m = Model::default();
        m.group("steps", None);
        for i in 0..STEPS {
            let z1 = STAIR_FOOT - i as f64 * RUN;
            let lo = DVec3::new(STAIR_X.0, 0.0, z1 - RUN);
            let hi = DVec3::new(STAIR_X.1, (i + 1) as f64 * RISE, z1);
            hexa(&mut m, aabb(lo, hi), true);
        }
        m.group("landing", None);
        hexa(
            &mut m,
            aabb(
                DVec3::new(LO.x, LANDING_TOP - 0.2, LO.z),
                DVec3::new(HI.x, LANDING_TOP, LANDING_EDGE),
            ),
            true,
        );
        m.group("deck", None);
        hexa(
            &mut m,
            aabb(
                DVec3::new(STAIR_X.1 + 0.3, 0.0, LANDING_EDGE + 0.3),
                DVec3::new(HI.x - 0.3, 0.01, HI.z - 0.3),
            ),
            true,
        );
        m.write(None)
    }

    /// The glass panels: parallelepipeds 2 cm thick, 5 cm clear of the posts at each end.
    pub fn glass_obj() -> String {
        let mut m = Model::default();
        m.group("balustrade", None);
        let (gap, t, low, high) = (0.05, 0.01, 0.08, RAIL_HEIGHT - 0.08);
        // The flight: bottom and top follow the slope.
        let step = (STAIR_FOOT - LANDING_EDGE) / STAIR_PANELS as f64;
        for k in 0..STAIR_PANELS {
            let (z0, z1) = (
                STAIR_FOOT - k as f64 * step - gap,
                STAIR_FOOT - (k + 1) as f64 * step + gap,
            );
            let corner = std::array::from_fn(|i| {
                let x = RAIL_X + if i & 1 == 0 { -t } else { t };
                let z = if i & 4 == 0 { z1 } else { z0 };
                let y = nosing(z) + if i & 2 == 0 { low } else { high };
                DVec3::new(x, y, z)
            });
            hexa(&mut m, corner, false);
        }
        // The landing's edge.
        let (x0, x1) = (RAIL_X, HI.x - 0.1);
        let step = (x1 - x0) / LANDING_PANELS as f64;
        for k in 0..LANDING_PANELS {
            let lo = DVec3::new(x0 + k as f64 * step + gap, LANDING_TOP + low, RAIL_Z - t);
            let hi = DVec3::new(x0 + (k + 1) as f64 * step - gap, LANDING_TOP + high, RAIL_Z + t);
            hexa(&mut m, aabb(lo, hi), false);
        }
        m.write(None)
    }

    /// Posts, handrails, newel balls and the ring on the pedestal: rough metal. Most of the hall's triangles
    /// are here, in round things, as in a modelled interior.
    pub fn metal_obj() -> String {
        let mut m = Model::default();
        m.group("posts", None);
        let post = |m: &mut Model, base: DVec3| cylinder(m, base, base + DVec3::Y * RAIL_HEIGHT, 0.02, 48, 6);
        let step = (STAIR_FOOT - LANDING_EDGE) / STAIR_PANELS as f64;
        for k in 0..=STAIR_PANELS {
            let z = STAIR_FOOT - k as f64 * step;
            post(&mut m, DVec3::new(RAIL_X, nosing(z), z));
        }
        let (x0, x1) = (RAIL_X, HI.x - 0.1);
        let step = (x1 - x0) / LANDING_PANELS as f64;
        for k in 1..=LANDING_PANELS {
            post(&mut m, DVec3::new(x0 + k as f64 * step, LANDING_TOP, RAIL_Z));
        }
        m.group("rails", None);
        let top = |z: f64| DVec3::new(RAIL_X, nosing(z) + RAIL_HEIGHT, z);
        cylinder(&mut m, top(STAIR_FOOT), top(LANDING_EDGE), 0.03, 48, 48);
        cylinder(
            &mut m,
            DVec3::new(RAIL_X, LANDING_TOP + RAIL_HEIGHT, RAIL_Z),
            DVec3::new(x1, LANDING_TOP + RAIL_HEIGHT, RAIL_Z),
            0.03,
            48,
            48,
        );
        m.group("newels", None);
        for p in [
            top(STAIR_FOOT),
            top(LANDING_EDGE),
            DVec3::new(x1, LANDING_TOP + RAIL_HEIGHT, RAIL_Z),
        ] {
            ball(&mut m, p + DVec3::Y * 0.04, 0.06, 3);
        }
        m.group("ring", None);
        let (r, tube) = (0.32, 0.07);
        let centre = DVec3::new(
            (PEDESTAL.0.x + PEDESTAL.1.x) / 2.0,
            PEDESTAL.1.y + tube + 0.0005,
            (PEDESTAL.0.z + PEDESTAL.1.z) / 2.0,
        );
        torus_model(&mut m, centre, r, tube, 96, 48);
        m.write(None)
    }

    #[cfg(test)]
    mod tests {
        use super::*;

        fn faces(text: &str) -> usize {
            text.lines().filter(|l| l.starts_with("f ")).count()
        }

        #[test]
        fn the_hall_has_about_30k_triangles_and_uv_on_the_wood() {
            let counts = [shell_obj(), wood_obj(), glass_obj(), metal_obj()].map(|t| faces(&t));
            assert_eq!(counts[0], 12 + 12, "the shell's 6 sides and the pedestal");
            assert_eq!(counts[1], 12 * (STEPS as usize + 2), "steps, landing, deck");
            assert_eq!(counts[2], 12 * (STAIR_PANELS + LANDING_PANELS) as usize);
            let total: usize = counts.iter().sum();
            assert!((25_000..=35_000).contains(&total), "{total} triangles");
            let wood = wood_obj();
            // Every corner of the wood has a texture coordinate and a normal (v/vt/vn); the others a normal.
            assert!(wood
                .lines()
                .filter(|l| l.starts_with("f "))
                .all(|l| l
                    .split(' ')
                    .skip(1)
                    .all(|c| c.split('/').count() == 3 && !c.contains("//"))));
            for t in [shell_obj(), glass_obj(), metal_obj()] {
                assert!(t
                    .lines()
                    .filter(|l| l.starts_with("f "))
                    .all(|l| l.split(' ').skip(1).all(|c| c.contains("//"))));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use ppm_vk_engine::scene::{Scene, Surface};
    use std::collections::HashMap;
    use std::sync::OnceLock;

    /// Loads `scenes/<name>.toml`, the demo meshes written first (once per test process).
    fn demo_scene(name: &str) -> Scene {
        static READY: OnceLock<()> = OnceLock::new();
        READY.get_or_init(|| {
            ensure(&default_dir()).expect("writing the demo meshes");
        });
        let path = default_dir().join(format!("../{name}.toml"));
        let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e:#}"));
        assert!(scene.warnings.is_empty(), "{name}: {:?}", scene.warnings);
        scene
    }

    fn cornell_spheres() -> Scene {
        Scene::load(default_dir().join("../cornell-spheres.toml")).expect("cornell-spheres")
    }

    #[test]
    fn committed_meshes_are_what_the_generator_writes() {
        for f in FILES.iter().filter(|f| f.committed) {
            let path = default_dir().join(f.name);
            let on_disk = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            assert!(on_disk == contents(f), "{} differs from the generator's", f.name);
        }
    }

    #[test]
    fn ensure_writes_only_what_is_missing_or_stale() {
        let dir = std::env::temp_dir().join(format!("ppm-vk-demo-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let first = ensure(&dir).expect("first");
        assert_eq!(first.len(), FILES.len());
        assert!(ensure(&dir).expect("second").is_empty(), "nothing to do");
        std::fs::write(dir.join("water.mtl"), "# an older version\n").expect("write");
        std::fs::remove_file(dir.join("cornell-box.obj")).expect("remove");
        let again = ensure(&dir).expect("third");
        let names: Vec<_> = again.iter().filter_map(|p| p.file_name()?.to_str()).collect();
        assert_eq!(names, ["cornell-box.obj", "water.mtl"]);
        assert_eq!(
            std::fs::read_to_string(dir.join("water.mtl")).expect("read"),
            water_mtl()
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn cornell_mesh_is_cornell_spheres_in_triangles() {
        let quads = cornell_spheres();
        let mesh = demo_scene("cornell-mesh");
        assert!(mesh.quads.is_empty());
        assert_eq!(
            mesh.spheres,
            quads
                .spheres
                .iter()
                .map(|s| {
                    let name = &quads.materials[s.material as usize].name;
                    let k = mesh
                        .materials
                        .iter()
                        .position(|m| m.name == *name)
                        .expect("sphere material");
                    ppm_vk_engine::scene::Sphere {
                        material: k as u32,
                        ..*s
                    }
                })
                .collect::<Vec<_>>()
        );
        assert_eq!(mesh.bounds(), quads.bounds());
        assert_eq!(mesh.triangle_count(), 14);
        assert_eq!(mesh.meshes.len(), 1);
        assert!(mesh.meshes[0].name.ends_with("meshes/cornell-box.obj"));
        // Each quad is two triangles, in file order: same corners, same front normal, same material.
        for (i, q) in quads.quads.iter().enumerate() {
            let qm = &quads.materials[q.material as usize];
            let corners = [
                q.origin,
                q.origin + q.edge_u,
                q.origin + q.edge_u + q.edge_v,
                q.origin + q.edge_v,
            ];
            for (k, t) in [(0, [0, 1, 2]), (1, [0, 2, 3])] {
                let tri = mesh.meshes[0].triangle(2 * i + k);
                for (p, c) in tri.p.iter().zip(t) {
                    assert!(p.abs_diff_eq(corners[c], 1e-6), "quad {i}: {p} against {}", corners[c]);
                }
                assert!(tri.normal().abs_diff_eq(q.normal(), 1e-6));
                let m = &mesh.materials[tri.material as usize];
                assert_eq!((m.surface, m.emission), (qm.surface, qm.emission), "quad {i}");
                assert!(m.name.ends_with(&format!("cornell-box.obj:{}", qm.name)), "{}", m.name);
            }
        }
        // The light: the two triangles of the one emitting quad.
        let lights = mesh.emitting_triangles();
        assert_eq!(lights.len(), 2);
        let light = &quads.quads[quads.lights()[0] as usize];
        let area: f32 = lights
            .iter()
            .map(|l| mesh.meshes[0].triangle(l.triangle as usize).area())
            .sum();
        assert!((area - light.area()).abs() < 1e-6);
        for l in &lights {
            assert_eq!(mesh.meshes[0].triangle(l.triangle as usize).normal(), Vec3::NEG_Y);
        }
    }

    #[test]
    fn furnace_mesh_is_a_closed_emitting_sphere_facing_in() {
        let s = demo_scene("furnace-mesh");
        assert_eq!(s.triangle_count(), 1280);
        assert_eq!(s.emitting_triangles().len(), 1280, "every triangle emits");
        assert_eq!(s.materials.len(), 1);
        assert_eq!(
            s.materials[0].surface,
            Surface::Diffuse {
                albedo: Vec3::splat(0.5)
            }
        );
        assert_eq!(s.materials[0].emission, Vec3::ONE);
        let (lo, hi) = s.bounds();
        assert!(lo.abs_diff_eq(Vec3::splat(-1.0), 1e-6) && hi.abs_diff_eq(Vec3::ONE, 1e-6));
        for t in s.meshes[0].triangles() {
            let c = (t.p[0] + t.p[1] + t.p[2]) / 3.0;
            assert!(t.normal().dot(s.camera.eye - c) > 0.9 * c.length(), "faces the centre");
        }
        assert!(s.meshes[0].normals.is_none(), "flat");
    }

    #[test]
    fn cornell_glass_mesh_replaces_the_glass_sphere() {
        let quads = cornell_spheres();
        let s = demo_scene("cornell-glass-mesh");
        assert_eq!(s.spheres.len(), 2);
        assert_eq!(s.quads, quads.quads);
        assert_eq!(s.triangle_count(), 20480);
        let glass = quads.spheres[2];
        let m = &s.meshes[0];
        assert!(m
            .materials
            .iter()
            .all(|&k| s.materials[k as usize].surface == Surface::Glass { ior: 1.5 }));
        let normals = m.normals.as_ref().expect("sphere normals");
        for (p, n) in m.positions.iter().zip(normals) {
            let r = *p - glass.center;
            assert!((r.length() - glass.radius).abs() < 1e-5, "vertex on the sphere");
            assert!(n.abs_diff_eq(r / glass.radius, 1e-4), "radial unit normal");
        }
        for t in m.triangles() {
            let c = (t.p[0] + t.p[1] + t.p[2]) / 3.0;
            assert!(t.normal().dot(c - glass.center) > 0.0, "front side out");
        }
        // Facets lie inside the sphere, at most about 1e-4 m below its surface.
        let (lo, hi) = s.bounds();
        assert_eq!((lo, hi), quads.bounds());
    }

    #[test]
    fn cornell_water_has_a_closed_water_slab() {
        let s = demo_scene("cornell-water");
        assert_eq!(s.triangle_count(), 206_720);
        assert_eq!(s.lights().len(), 1);
        let light = s.quads[s.lights()[0] as usize];
        assert!((light.area() - 0.04).abs() < 1e-6);
        assert!(s.emitting_triangles().is_empty());
        let m = &s.meshes[0];
        let water = &s.materials[m.materials[0] as usize];
        assert!(water.name.ends_with("water.obj:water"));
        assert_eq!(water.surface, Surface::Glass { ior: 1.33 });
        assert!(m.materials.iter().all(|&k| k == m.materials[0]));
        let lo = m.positions.iter().fold(Vec3::INFINITY, |a, p| a.min(*p));
        let hi = m.positions.iter().fold(Vec3::NEG_INFINITY, |a, p| a.max(*p));
        assert!(lo.abs_diff_eq(Vec3::new(-0.99, 0.002, -0.99), 1e-6), "{lo}");
        assert!(
            (hi.x - 0.99).abs() < 1e-6 && (hi.z - 2.99).abs() < 1e-6 && hi.y < 0.316,
            "{hi}"
        );
        // Closed: each edge between two positions is used by exactly two triangles.
        assert!(edges(m).values().all(|&(n, _)| n == 2), "watertight");
        assert_eq!(s.bounds(), cornell_spheres().bounds());
    }

    #[test]
    fn glass_on_table_has_a_torus_on_a_box() {
        let s = demo_scene("glass-on-table");
        assert_eq!(s.triangle_count(), 12 + 9216);
        let m = &s.meshes[0];
        let kinds: Vec<Surface> = m.materials.iter().map(|&k| s.materials[k as usize].surface).collect();
        assert_eq!(
            kinds[0],
            Surface::Diffuse {
                albedo: Vec3::new(0.55, 0.38, 0.22)
            }
        );
        assert!(kinds[..12].iter().all(|k| *k == kinds[0]));
        assert!(kinds[12..].iter().all(|k| *k == Surface::Glass { ior: 1.5 }));
        let torus_low = m
            .triangles()
            .skip(12)
            .flat_map(|t| t.p)
            .map(|p| p.y)
            .fold(f32::MAX, f32::min);
        assert!(
            (torus_low - 0.5005).abs() < 1e-6,
            "rests 0.5 mm above the table: {torus_low}"
        );
        assert!(m.normals.is_some());
        assert_eq!(s.lights().len(), 1);
    }

    /// Per edge between two positions (by their bits): the triangles that use it, and how many more run
    /// along it one way than the other (0 where the two sides' windings agree).
    fn edges(m: &ppm_vk_engine::scene::Mesh) -> HashMap<([u32; 3], [u32; 3]), (u32, i32)> {
        let key = |p: Vec3| p.to_array().map(f32::to_bits);
        let mut edges: HashMap<([u32; 3], [u32; 3]), (u32, i32)> = HashMap::new();
        for t in m.triangles() {
            for (a, b) in [(0, 1), (1, 2), (2, 0)] {
                let (a, b) = (key(t.p[a]), key(t.p[b]));
                let e = edges.entry((a.min(b), a.max(b))).or_default();
                *e = (e.0 + 1, e.1 + if a < b { 1 } else { -1 });
            }
        }
        edges
    }

    #[test]
    fn gold_ring_is_a_closed_gold_ring_standing_on_the_table() {
        let s = demo_scene("gold-ring");
        assert_eq!(s.triangle_count(), 192 * 8);
        let m = &s.meshes[0];
        let (eta, k) = ppm_vk_engine::scene::conductors::named("Au").unwrap();
        assert!(m.materials.iter().all(|&i| s.materials[i as usize].surface
            == Surface::Conductor {
                reflectance: Vec3::ONE,
                eta,
                k
            }));
        let lo = m.positions.iter().fold(Vec3::INFINITY, |a, p| a.min(*p));
        let hi = m.positions.iter().fold(Vec3::NEG_INFINITY, |a, p| a.max(*p));
        assert!(lo.abs_diff_eq(Vec3::new(-0.1, 0.0, -0.1), 1e-6) && hi.abs_diff_eq(Vec3::new(0.1, 0.04, 0.1), 1e-6));
        // Closed, and every face's front outward: each edge is used by two triangles, once each way.
        assert!(edges(m).values().all(|&e| e == (2, 0)), "closed and consistently wound");
        assert_eq!(s.lights().len(), 1);
    }

    #[test]
    fn mesh_scenes_become_gpu_scenes_with_a_bvh() {
        for name in ["cornell-mesh", "furnace-mesh", "cornell-glass-mesh"] {
            let s = demo_scene(name);
            let g = ppm_vk_engine::lower::GpuScene::new(&s, &ppm_vk_engine::Settings::default(), 1 << 16).unwrap();
            assert_eq!(g.params.num_triangles as usize, s.triangle_count(), "{name}");
            assert_eq!(g.bvh_triangles.len(), s.triangle_count(), "{name}");
            let tri_lights = g
                .lights
                .iter()
                .filter(|l| l.kind == ppm_vk_engine::layout::LIGHT_TRIANGLE)
                .count();
            assert_eq!(tri_lights, s.emitting_triangles().len(), "{name}");
            let p: f64 = g.lights.iter().map(|l| l.prob as f64).sum();
            assert!((p - 1.0).abs() < 1e-6, "{name}: light probabilities sum to {p}");
        }
    }

    /// Every directed edge once and its reverse once: closed, and consistently wound.
    fn assert_closed(tris: impl Iterator<Item = [u32; 3]>, what: &str) {
        let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
        for [a, b, c] in tris {
            for e in [(a, b), (b, c), (c, a)] {
                *edges.entry(e).or_default() += 1;
            }
        }
        for (&(a, b), &n) in &edges {
            assert_eq!(n, 1, "{what}: edge {a}->{b} used {n} times");
            assert_eq!(edges.get(&(b, a)), Some(&1), "{what}: edge {a}->{b} has no twin");
        }
    }

    /// Signed volume (positive: front sides out).
    fn volume(v: &[DVec3], tris: impl Iterator<Item = [u32; 3]>) -> f64 {
        tris.map(|[a, b, c]| v[a as usize].dot(v[b as usize].cross(v[c as usize])) / 6.0)
            .sum()
    }

    #[test]
    fn generated_solids_are_closed_and_face_outward() {
        use std::f64::consts::PI;
        let s = sphere_model(3, false, None, "s");
        assert_eq!(s.triangles().count(), 1280);
        assert_closed(s.triangles(), "icosphere");
        let vol = volume(&s.v, s.triangles());
        assert!(vol > 0.95 * 4.0 / 3.0 * PI && vol < 4.0 / 3.0 * PI, "{vol}");
        let inward = sphere_model(3, true, None, "s");
        assert!((volume(&inward.v, inward.triangles()) + vol).abs() < 1e-9);

        let mut b = Model::default();
        b.group("b", None);
        box_model(&mut b, DVec3::new(-1.0, 0.0, 2.0), DVec3::new(1.0, 0.5, 3.0));
        assert_eq!(b.triangles().count(), 12);
        assert_closed(b.triangles(), "box");
        assert!((volume(&b.v, b.triangles()) - 1.0).abs() < 1e-12);

        let mut t = Model::default();
        t.group("t", None);
        torus_model(&mut t, DVec3::ZERO, 0.15, 0.05, 96, 48);
        assert_closed(t.triangles(), "torus");
        let exact = 2.0 * PI * PI * 0.15 * 0.05 * 0.05;
        let vol = volume(&t.v, t.triangles());
        assert!(vol > 0.99 * exact && vol < exact, "{vol} against {exact}");
    }

    #[test]
    fn water_is_a_closed_slab_of_about_200k_triangles() {
        let text = water_obj();
        let v: Vec<DVec3> = text
            .lines()
            .filter_map(|l| l.strip_prefix("v "))
            .map(|l| {
                let c: Vec<f64> = l.split(' ').map(|x| x.parse().expect("number")).collect();
                DVec3::new(c[0], c[1], c[2])
            })
            .collect();
        let tris: Vec<[u32; 3]> = text
            .lines()
            .filter_map(|l| l.strip_prefix("f "))
            .map(|l| {
                let i: Vec<u32> = l
                    .split(' ')
                    .map(|c| c.split('/').next().and_then(|x| x.parse::<u32>().ok()).expect("index") - 1)
                    .collect();
                [i[0], i[1], i[2]]
            })
            .collect();
        assert_eq!(tris.len(), 206_720);
        assert_closed(tris.iter().copied(), "water");
        // Mean height about 0.298 over 1.98 x 3.98 m; the waves average out to within a few mm^3.
        let vol = volume(&v, tris.iter().copied());
        let slab = 1.98 * 3.98 * 0.298;
        assert!((vol - slab).abs() < 0.01 * slab, "{vol} against {slab}");
        let top = v.iter().map(|p| p.y).fold(f64::MIN, f64::max);
        assert!(top > 0.305 && top < 0.316, "crests {top}");
    }
}
