//! Kernels compiled at run time for one scene: the tracing kernels (ray, photon) with the scene's spheres
//! and quads written into the GLSL as constants (`SCENE_CONSTANTS`, shaders/common/bindings.glsl), and
//! with them the triangles of a small mesh (then no BVH is traversed) and the lights, when there are few.
//! On lavapipe this runs the photon stage about twice as fast as reading them from storage buffers. The
//! build-time kernels stay the fallback for scenes with too many primitives to inline.

use anyhow::{anyhow, Context as _, Result};

use crate::inline_pairs::InlinePair;
use crate::layout::{
    Light, Quad, Sphere, Triangle, LIGHT_DIRECTIONAL, LIGHT_ENVIRONMENT, LIGHT_POINT, LIGHT_QUAD, LIGHT_SPHERE,
    LIGHT_SPOT, LIGHT_TRIANGLE, MICROFACET_BECKMANN, MICROFACET_GGX, QUAD_DISK, SURFACE_BLEND, SURFACE_CONDUCTOR,
    SURFACE_PLASTIC, SURFACE_ROUGH_CONDUCTOR, SURFACE_ROUGH_GLASS, SURFACE_THIN,
};
use crate::reflected::{KernelInfo, SOURCES};
use crate::spirv_cache;

/// Scenes with more spheres and quads than this keep the buffer-reading kernels.
pub const MAX_INLINE_PRIMITIVES: usize = 64;
/// Meshes of at most this many triangles in all are written out, tested one by one, instead of traversed
/// through the BVH (docs/performance.md, "Triangle meshes", measured where the two cross).
pub const MAX_INLINE_TRIANGLES: usize = 64;
/// Scenes with more lights than this choose them from the light buffer (a binary search) rather than a
/// chain of selects over constants.
pub const MAX_INLINE_LIGHTS: usize = 64;

/// What [`scene_constants`] writes out.
pub struct SceneConstants<'a> {
    pub spheres: &'a [Sphere],
    pub quads: &'a [Quad],
    /// Every triangle, in the BVH's leaf order (`Light::index` of a triangle light indexes it).
    pub triangles: &'a [Triangle],
    /// Test `triangles` one by one (a small mesh) instead of traversing the BVH.
    pub inline_triangles: bool,
    /// Where `inline_triangles`: the triangles that pair into parallelograms and the rest
    /// (inline_pairs.rs), which together are all of them.
    pub pairs: &'a [InlinePair],
    pub singles: &'a [u32],
    pub lights: &'a [Light],
    /// The surfaces the scene's materials use, as bits `1 << SURFACE_*`: the kernels leave out the code of
    /// conductors, plastics, thin dielectrics and blends where there are none (lavapipe runs both sides of a
    /// branch, so code a scene never takes still costs).
    pub surfaces: u32,
    /// Whether any material has a texture: without one the kernels do not read the texture index.
    pub textures: bool,
    /// Whether any material has a texture on its specular reflectance or roughness, and on its emission:
    /// without one texture.glsl leaves that lookup out.
    pub parameter_textures: bool,
    pub emission_textures: bool,
    /// Whether any plastic is rough (Material::table): without one the plastics' code leaves it out.
    pub rough_plastics: bool,
    /// The microfacet distributions the rough surfaces use, as bits `1 << MICROFACET_*`
    /// (microfacet.glsl leaves out the other's code where there is one kind).
    pub microfacets: u32,
    /// Whether any mesh has vertex normals (shading.glsl): without one no shading normal is read.
    pub shading_normals: bool,
    /// Whether any rough surface is anisotropic (geometry.glsl's surface_tangent): without one no
    /// tangent is taken.
    pub anisotropic: bool,
    /// Whether any material has a bump or normal map (normal_map.glsl): without one no map is read and
    /// the hits take no dp/dv.
    pub normal_maps: bool,
    /// Whether any material is masked (materials/mask.glsl): without one the intersection loops and the
    /// traversal take every hit.
    pub masks: bool,
    /// Whether emitted photons are aimed at what casts caustics (photon/targets.glsl): without it no
    /// emission draws the choice.
    pub targets: bool,
    /// The kinds of light in `lights`, as bits `1 << LIGHT_*`: lights.glsl leaves out the code of glowing
    /// spheres, delta lights (point, spot, directional) and environments where there are none.
    pub light_kinds: u32,
}

/// An f32 written so GLSL reads back exactly the same bits: nine significant digits name an f32 uniquely
/// and lie far enough from the midpoint between two floats that glslang's parse (to double, then to
/// float) cannot round the other way.
fn f(x: f32) -> String {
    format!("{x:.8e}")
}

fn v(a: [f32; 3]) -> String {
    format!("vec3({}, {}, {})", f(a[0]), f(a[1]), f(a[2]))
}

/// `const T NAME[n] = T[](...)`, with one zeroed element when the list is empty (GLSL has no empty arrays).
fn array(ty: &str, name: &str, items: Vec<String>, zero: &str) -> String {
    let n = items.len().max(1);
    let body = if items.is_empty() {
        zero.to_string()
    } else {
        items.join(",\n    ")
    };
    format!("const {ty} {name}[{n}] = {ty}[](\n    {body});\n")
}

/// The GLSL of the scene as constants: its spheres and quads, a small mesh's triangles, and (when there
/// are at most [`MAX_INLINE_LIGHTS`]) each light with its emitting quad or triangle written out
/// (photon.comp's `Emitter`), so choosing a light reads no memory either.
pub fn scene_constants(c: &SceneConstants) -> String {
    let (spheres, quads, lights) = (c.spheres, c.quads, c.lights);
    let mut s = String::from("// Generated by crates/kernels/src/specialize.rs for one scene.\n");
    s += &format!(
        "const uint NUM_SPHERES = {}u;\nconst uint NUM_QUADS = {}u;\n",
        spheres.len(),
        quads.len()
    );
    let inline: &[Triangle] = if c.inline_triangles { c.triangles } else { &[] };
    let has = |surface: u32| c.surfaces & (1 << surface) != 0;
    s += &format!(
        "const bool SCENE_CONDUCTORS = {};\nconst bool SCENE_PLASTICS = {};\nconst bool SCENE_THIN = {};\n\
         const bool SCENE_ROUGH_CONDUCTORS = {};\nconst bool SCENE_ROUGH_GLASS = {};\n",
        has(SURFACE_CONDUCTOR),
        has(SURFACE_PLASTIC),
        has(SURFACE_THIN),
        has(SURFACE_ROUGH_CONDUCTOR),
        has(SURFACE_ROUGH_GLASS)
    );
    // Without blends, blend.glsl's resolve_blend reads nothing.
    s += &format!("const bool SCENE_BLENDS = {};\n", has(SURFACE_BLEND));
    s += &format!("const bool SCENE_TEXTURES = {};\n", c.textures);
    s += &format!("const bool SCENE_PARAMETER_TEXTURES = {};\n", c.parameter_textures);
    s += &format!("const bool SCENE_EMISSION_TEXTURES = {};\n", c.emission_textures);
    s += &format!("const bool SCENE_ROUGH_PLASTICS = {};\n", c.rough_plastics);
    s += &format!(
        "const bool SCENE_BECKMANN = {};\nconst bool SCENE_GGX = {};\n",
        c.microfacets & (1 << MICROFACET_BECKMANN) != 0,
        c.microfacets & (1 << MICROFACET_GGX) != 0
    );
    s += &format!("const bool SCENE_SHADING_NORMALS = {};\n", c.shading_normals);
    s += &format!("const bool SCENE_ANISOTROPIC = {};\n", c.anisotropic);
    s += &format!("const bool SCENE_NORMAL_MAPS = {};\n", c.normal_maps);
    s += &format!("const bool SCENE_MASKS = {};\n", c.masks);
    s += &format!("const bool SCENE_TARGETS = {};\n", c.targets);
    let kind = |k: u32| c.light_kinds & (1 << k) != 0;
    s += &format!(
        "const bool SCENE_SPHERE_LIGHTS = {};\nconst bool SCENE_DELTA_LIGHTS = {};\nconst bool SCENE_ENVIRONMENT = {};\n",
        kind(LIGHT_SPHERE),
        kind(LIGHT_POINT) || kind(LIGHT_SPOT) || kind(LIGHT_DIRECTIONAL),
        kind(LIGHT_ENVIRONMENT)
    );
    s += &format!(
        "const uint NUM_INLINE_TRIANGLES = {}u;\nconst bool SCENE_BVH = {};\n",
        inline.len(),
        !c.inline_triangles && !c.triangles.is_empty()
    );
    s += &array(
        "Triangle",
        "SCENE_TRIANGLES",
        inline
            .iter()
            .map(|t| {
                format!(
                    "Triangle({}, {}u, {}, {}u, {}, 0u)",
                    v(t.v0),
                    t.material,
                    v(t.v1),
                    t.source,
                    v(t.v2)
                )
            })
            .collect(),
        "Triangle(vec3(0.0), 0u, vec3(0.0), 0u, vec3(0.0), 0u)",
    );
    // The written-out triangles by pairs, then those left single (geometry.glsl's loops).
    let (pairs, singles): (&[InlinePair], &[u32]) = match c.inline_triangles {
        true => (c.pairs, c.singles),
        false => (&[], &[]),
    };
    s += &format!(
        "const uint NUM_INLINE_PAIRS = {}u;\nconst uint NUM_INLINE_SINGLES = {}u;\n",
        pairs.len(),
        singles.len()
    );
    s += &array(
        "InlinePair",
        "SCENE_PAIRS",
        pairs
            .iter()
            .map(|p| {
                let corners =
                    p.first_corners[0] | p.first_corners[1] << 2 | p.second_corners[0] << 4 | p.second_corners[1] << 6;
                format!(
                    "InlinePair({}, {}u, {}, {}u, {}, {corners}u)",
                    v(p.origin),
                    p.first,
                    v(p.edge_u),
                    p.second,
                    v(p.edge_v)
                )
            })
            .collect(),
        "InlinePair(vec3(0.0), 0u, vec3(0.0), 0u, vec3(0.0), 0u)",
    );
    s += &array(
        "uint",
        "SCENE_SINGLES",
        singles.iter().map(|i| format!("{i}u")).collect(),
        "0u",
    );
    s += &array(
        "Sphere",
        "SCENE_SPHERES",
        spheres
            .iter()
            .map(|p| format!("Sphere({}, {}, {}u, 0u, 0u, 0u)", v(p.center), f(p.radius), p.material))
            .collect(),
        "Sphere(vec3(0.0), 0.0, 0u, 0u, 0u, 0u)",
    );
    s += &array(
        "Quad",
        "SCENE_QUADS",
        quads
            .iter()
            .map(|q| {
                format!(
                    "Quad({}, {}u, {}, {}, {}, {}, {}, {}u, {}, 0.0)",
                    v(q.origin),
                    q.material,
                    v(q.edge_u),
                    f(q.area),
                    v(q.edge_v),
                    f(q.plane_d),
                    v(q.normal),
                    q.shape,
                    v(q.w)
                )
            })
            .collect(),
        "Quad(vec3(0.0), 0u, vec3(0.0), 0.0, vec3(0.0), 0.0, vec3(0.0), 0u, vec3(0.0), 0.0)",
    );
    if lights.len() > MAX_INLINE_LIGHTS {
        return s;
    }
    s += &format!(
        "#define SCENE_INLINE_LIGHTS 1\nconst uint NUM_LIGHTS = {}u;\n",
        lights.len()
    );
    let sub = |a: [f32; 3], b: [f32; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let cross = |a: [f32; 3], b: [f32; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    // The fields after the kind, zero for quads and triangles (lights.glsl's emitter_of fills them alike).
    const NO_MORE: &str = "vec3(0.0), 0.0, 0.0, 0.0, 0.0, 0.0, 0u";
    // A quad's or triangle's value is its radiance, not divided (lights.glsl's emitter_of); the fields
    // after it are zero but a disk's radius (1) and the last, its radiance texture, a textured
    // triangle's 1 + its index (Emitter::table).
    const QUAD_NO_MORE: &str = "0.0, 0.0, 0.0, 0.0, 0.0, ";
    const DISK_NO_MORE: &str = "1.0, 0.0, 0.0, 0.0, 0.0, ";
    s += &array(
        "Emitter",
        "SCENE_EMITTERS",
        lights
            .iter()
            .map(|l| {
                // The flux a photon starts with, divided here exactly as photon.comp would (f32).
                let flux = if l.kind == LIGHT_SPOT || l.texture != 0 {
                    l.flux
                } else {
                    l.power
                }
                .map(|p| p / l.prob);
                if l.kind == LIGHT_TRIANGLE {
                    // Edges subtracted in f32 as photon.comp's buffer path does; the normal is computed
                    // there from them (choose_emitter), not written here.
                    let t = &c.triangles[l.index as usize];
                    return format!(
                        "Emitter({}, {}, {}, vec3(0.0), {}, {}, {LIGHT_TRIANGLE}u, {}, {QUAD_NO_MORE}{}u)",
                        v(t.v0),
                        v(sub(t.v1, t.v0)),
                        v(sub(t.v2, t.v0)),
                        v(flux),
                        f(l.cdf),
                        v(l.value),
                        if l.texture != 0 { l.index + 1 } else { 0 }
                    );
                }
                if l.kind == LIGHT_QUAD {
                    let q = &quads[l.index as usize];
                    return format!(
                        "Emitter({}, {}, {}, {}, {}, {}, {LIGHT_QUAD}u, {}, {}{}u)",
                        v(q.origin),
                        v(q.edge_u),
                        v(q.edge_v),
                        v(q.normal),
                        v(flux),
                        f(l.cdf),
                        v(l.value),
                        if q.shape == QUAD_DISK {
                            DISK_NO_MORE
                        } else {
                            QUAD_NO_MORE
                        },
                        l.texture
                    );
                }
                // As emitter_of: an environment's value is not divided by its prob (its cdf, as light 0).
                let value = if l.kind == LIGHT_ENVIRONMENT {
                    l.value
                } else {
                    l.value.map(|x| x / l.prob)
                };
                format!(
                    "Emitter({}, {}, {}, {}, {}, {}, {}u, {}, {}, {}, {}, {}, {}, {}u)",
                    v(l.origin),
                    v(l.edge_u),
                    v(cross(l.edge_u, l.normal)),
                    v(l.normal),
                    v(flux),
                    f(l.cdf),
                    l.kind,
                    v(value),
                    f(l.radius),
                    f(l.cos_cutoff),
                    f(l.cos_beam),
                    f(l.cutoff),
                    f(l.inv_width),
                    l.index
                )
            })
            .collect(),
        &format!("Emitter(vec3(0.0), vec3(0.0), vec3(0.0), vec3(0.0), vec3(0.0), 0.0, 0u, {NO_MORE})"),
    );
    s
}

/// What making one kernel's pipeline cost, for the set-up's breakdown (`Renderer::setup_times`).
#[derive(Clone, Debug, Default)]
pub struct KernelTiming {
    pub name: &'static str,
    /// Seconds to compile its GLSL with shaderc, or to read that SPIR-V from the cache (0: the build-time
    /// SPIR-V was used).
    pub compile_s: f64,
    /// `Some(true)`: the compiled SPIR-V came from the on-disk cache; `None`: the build-time SPIR-V.
    pub spirv_cached: Option<bool>,
    /// Seconds in vkCreateComputePipelines (and the layouts and module around it).
    pub pipeline_s: f64,
    /// Why the SPIR-V cache was not used or written, when it was not.
    pub note: Option<String>,
}

/// Creates `k`'s pipeline: from its build-time SPIR-V when `defines` and `constants` are empty, else
/// compiled with them (see [`compile_cached`]) through the SPIR-V cache in the context's cache
/// directory. Says what each step cost.
pub fn build(
    ctx: &ppm_vk_device::Context,
    k: &KernelInfo,
    defines: &[(&str, &str)],
    constants: &str,
) -> Result<(ppm_vk_device::ComputePipeline, KernelTiming)> {
    let mut timing = KernelTiming {
        name: k.name,
        ..KernelTiming::default()
    };
    let compiled = match defines.is_empty() && constants.is_empty() {
        true => None,
        false => Some(compile_cached(k, defines, constants, ctx.cache_dir())?),
    };
    let start = std::time::Instant::now();
    let pipeline = match &compiled {
        None => crate::pipeline(ctx, k)?,
        Some(c) => crate::pipeline_from(ctx, k, &c.spirv)?,
    };
    timing.pipeline_s = start.elapsed().as_secs_f64();
    if let Some(c) = compiled {
        (timing.compile_s, timing.spirv_cached, timing.note) = (c.seconds, Some(c.cached), c.note);
    }
    Ok((pipeline, timing))
}

/// SPIR-V compiled at run time, and what it cost.
pub struct Compiled {
    pub spirv: Vec<u32>,
    /// Seconds spent: shaderc's compile, or reading the cache file.
    pub seconds: f64,
    /// Whether the SPIR-V came from the on-disk cache.
    pub cached: bool,
    /// Why a cache file was not used or not written (damaged, unwritable), in one line.
    pub note: Option<String>,
}

/// [`compile_with`] through the SPIR-V cache in `cache_dir` (spirv_cache.rs): a compile done by an earlier
/// run is read back instead of compiled; a damaged file is compiled again and replaced. `None`: no cache.
pub fn compile_cached(
    kernel: &KernelInfo,
    defines: &[(&str, &str)],
    constants: &str,
    cache_dir: Option<&std::path::Path>,
) -> Result<Compiled> {
    let start = std::time::Instant::now();
    let key = spirv_cache::key(kernel, defines, constants);
    let mut note = None;
    if let Some(dir) = cache_dir {
        match spirv_cache::read(dir, &key) {
            Ok(Some(spirv)) => {
                return Ok(Compiled {
                    spirv,
                    seconds: start.elapsed().as_secs_f64(),
                    cached: true,
                    note,
                })
            }
            Ok(None) => {}
            Err(why) => note = Some(format!("cached kernel {} compiled again: {why}", kernel.name)),
        }
    }
    let spirv = compile_with(kernel, defines, constants)?;
    if let Some(dir) = cache_dir {
        if let Err(e) = spirv_cache::write(dir, &key, &spirv) {
            note = Some(format!("kernel {} not cached: {e:#}", kernel.name));
        }
    }
    Ok(Compiled {
        spirv,
        seconds: start.elapsed().as_secs_f64(),
        cached: false,
        note,
    })
}

/// Compiles `kernel` again with `defines` (name, value) added, and `constants` as scene_constants.glsl
/// for kernels that include it.
pub fn compile_with(kernel: &KernelInfo, defines: &[(&str, &str)], constants: &str) -> Result<Vec<u32>> {
    let source = |path: &str| SOURCES.iter().find(|(p, _)| *p == path).map(|(_, s)| *s);
    let text = source(kernel.source).ok_or_else(|| anyhow!("no embedded source for kernel {}", kernel.name))?;
    let compiler = shaderc::Compiler::new().map_err(|e| anyhow!("shaderc: {e}"))?;
    let mut options = shaderc::CompileOptions::new().map_err(|e| anyhow!("shaderc options: {e}"))?;
    options.set_target_env(shaderc::TargetEnv::Vulkan, shaderc::EnvVersion::Vulkan1_2 as u32);
    options.set_optimization_level(shaderc::OptimizationLevel::Performance);
    for (name, value) in defines {
        options.add_macro_definition(name, Some(value));
    }
    let stage_dir = kernel.stage.to_string();
    let constants = constants.to_string();
    options.set_include_callback(move |requested, _, requester, _| {
        if requested == "scene_constants.glsl" {
            return Ok(shaderc::ResolvedInclude {
                resolved_name: requested.into(),
                content: constants.clone(),
            });
        }
        // As build.rs resolves them: the kernel's folder, common/, then the path under shaders/.
        for candidate in [
            format!("{stage_dir}/{requested}"),
            format!("common/{requested}"),
            requested.to_string(),
        ] {
            if let Some(content) = source(&candidate) {
                return Ok(shaderc::ResolvedInclude {
                    resolved_name: candidate,
                    content: content.into(),
                });
            }
        }
        Err(format!("{requester}: no embedded include {requested:?}"))
    });
    let artifact = compiler
        .compile_into_spirv(
            text,
            shaderc::ShaderKind::Compute,
            kernel.source,
            "main",
            Some(&options),
        )
        .with_context(|| format!("compiling kernel {} for this scene", kernel.name))?;
    Ok(artifact.as_binary().to_vec())
}

#[cfg(test)]
mod tests {
    #[test]
    fn literals_round_trip_through_double() {
        for x in [0.725f32, -1.0, 1.0 / 3.0, 3.4e-38, 1.99, -0.0, 16777217.0, 0.010416667] {
            let text = super::f(x);
            assert_eq!(
                (text.parse::<f64>().unwrap() as f32).to_bits(),
                x.to_bits(),
                "{x} -> {text}"
            );
        }
    }
}
