//! Each BSDF is found by one name on both sides: its host-side module `src/<name>.rs` and its kernel code
//! `shaders/materials/<name>.glsl`. A new BSDF adds both, or this fails.

use std::collections::BTreeSet;
use std::path::Path;

/// The modules of src/ that are no BSDF, so have no GLSL of their own in shaders/materials/:
/// - `lib`: the crate's root;
/// - `math`: the leaf math all of them share (its GLSL is shaders/common/geometry.glsl and sampling.glsl);
/// - `rng`: the random numbers of shaders/common/rng.glsl, for the CPU twin and the samplers' tests;
/// - `testing`: the tests' shared helpers;
/// - `rough_plastic`: the rough coat's tables, made on the host only (plastic.glsl reads them).
const NOT_BSDFS: &[&str] = &["lib", "math", "rng", "testing", "rough_plastic"];

/// The names of the files in `dir` ending in `.ext`, without it.
fn stems(dir: &Path, ext: &str) -> BTreeSet<String> {
    std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("reading {}: {e}", dir.display()))
        .map(|entry| entry.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == ext))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect()
}

#[test]
fn every_bsdf_module_has_its_glsl_and_every_glsl_its_module() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let modules = stems(&root.join("src"), "rs");
    for name in NOT_BSDFS {
        assert!(
            modules.contains(*name),
            "src/{name}.rs is listed as no BSDF but does not exist"
        );
    }
    let bsdfs: BTreeSet<String> = modules
        .into_iter()
        .filter(|m| !NOT_BSDFS.contains(&m.as_str()))
        .collect();
    let glsl = stems(&root.join("../../shaders/materials"), "glsl");
    assert_eq!(
        bsdfs, glsl,
        "src/*.rs (less {NOT_BSDFS:?}) and shaders/materials/*.glsl must pair up by name"
    );
}
