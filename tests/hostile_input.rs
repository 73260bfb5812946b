//! Hostile input: random and mutated scene files and texture images (the real ones in scenes/, bytes flipped, lines dropped
//! or repeated, numbers replaced by extreme ones, text cut short) give a scene or an error, never a panic,
//! a hang (each load under `MAX_LOAD`) or an allocation beyond a stated bound (`MAX_ALLOC`, counted by
//! this binary's allocator). And the scene limits hold at their bounds.
//!
//! Adding a format is one line in `formats()`.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use ppm_vk_engine::scene::{MAX_RESOLUTION, MAX_SCENE_BYTES, MAX_SHAPES};
use ppm_vk_engine::Scene;
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");
/// Cases per format: each is a fraction of a millisecond to a few ms, so the whole file takes seconds.
const CASES: u32 = 1500;
/// The slowest load allowed (the largest seed parses in about a millisecond).
const MAX_LOAD: Duration = Duration::from_secs(2);
/// The most one load may allocate at once: the seeds are at most 40 KiB, so 64 MiB is already far beyond
/// any honest parse of them (a resolution of 10^9 or a face index of 2^32 that allocated would pass it).
const MAX_ALLOC: usize = 64 << 20;

/// Counts the bytes live on this thread and their peak, so a test can bound what a load allocates.
struct Counting;
thread_local! {
    static LIVE: Cell<usize> = const { Cell::new(0) };
    static PEAK: Cell<usize> = const { Cell::new(0) };
}
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let _ = LIVE.try_with(|l| {
            l.set(l.get() + layout.size());
            let _ = PEAK.try_with(|p| p.set(p.get().max(l.get())));
        });
        System.alloc(layout)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        let _ = LIVE.try_with(|l| l.set(l.get().saturating_sub(layout.size())));
        System.dealloc(ptr, layout)
    }
}
#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// A loader under test: one file's bytes in, a scene or an error out.
type Load = fn(&[u8]) -> anyhow::Result<Scene>;

/// Each format, its loader and the files its mutations start from.
fn formats() -> Vec<(&'static str, Load, Vec<&'static str>)> {
    vec![
        (
            "toml",
            load_toml,
            vec![
                "scenes/cornell-spheres.toml",
                "scenes/cornell-mesh.toml",
                "scenes/glass-on-table.toml",
                "scenes/furnace.toml",
                "scenes/gold-ring.toml",
            ],
        ),
        (
            "obj",
            load_obj,
            vec!["scenes/meshes/cornell-box.obj", "scenes/meshes/furnace-sphere.obj"],
        ),
        (
            "image",
            load_image,
            vec![
                "scenes/textures/wood.png",
                "scenes/references/textures/gray.png",
                "scenes/references/textures/gradient.exr",
            ],
        ),
        (
            "xml",
            load_xml,
            vec![
                "../shared/reference/cornell-spheres.xml",
                "scenes/references/cornell-coated.xml",
            ],
        ),
    ]
}

/// A Mitsuba scene, read from a file (includes and meshes resolve against its directory).
fn load_xml(text: &[u8]) -> anyhow::Result<Scene> {
    let path = scratch("xml").join("s.xml");
    std::fs::write(&path, String::from_utf8_lossy(text).as_bytes())?;
    Ok(Scene::load(&path)?)
}

fn load_toml(text: &[u8]) -> anyhow::Result<Scene> {
    // Mesh paths resolve against the real scenes/ directory, so mutated scenes still find (or miss) them.
    Ok(Scene::parse(
        &String::from_utf8_lossy(text),
        &format!("{ROOT}/scenes/fuzzed.toml"),
    )?)
}

/// An image (PNG, JPEG or EXR: the decoder goes by its content) as a floor's texture in a minimal scene.
fn load_image(bytes: &[u8]) -> anyhow::Result<Scene> {
    let dir = scratch("image");
    std::fs::write(dir.join("t.img"), bytes)?;
    let scene = "[camera]\neye = [0.0, 1.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 1.0, 0.0]\nvfov = 40.0\n\
                 resolution = [8, 8]\n\n[materials.floor]\ndiffuse = { texture = \"t.img\", scale = [2, 2] }\n\n\
                 [[quad]]\norigin = [-1.0, 0.0, -1.0]\nedge_u = [0.0, 0.0, 2.0]\nedge_v = [2.0, 0.0, 0.0]\n\
                 material = \"floor\"\n\n[materials.light]\nemission = [1.0, 1.0, 1.0]\n\n[[quad]]\n\
                 origin = [-0.1, 1.0, -0.1]\nedge_u = [0.2, 0.0, 0.0]\nedge_v = [0.0, 0.0, 0.2]\nmaterial = \"light\"\n";
    Ok(Scene::parse(scene, &dir.join("s.toml").display().to_string())?)
}

/// The OBJ (with the cornell box's MTL beside it) imported by a minimal scene.
fn load_obj(text: &[u8]) -> anyhow::Result<Scene> {
    let dir = scratch("obj");
    std::fs::write(dir.join("m.obj"), String::from_utf8_lossy(text).as_bytes())?;
    std::fs::copy(
        format!("{ROOT}/scenes/meshes/cornell-box.mtl"),
        dir.join("cornell-box.mtl"),
    )?;
    std::fs::copy(
        format!("{ROOT}/scenes/meshes/furnace-sphere.mtl"),
        dir.join("furnace-sphere.mtl"),
    )?;
    let scene = "[camera]\neye = [0.0, 1.0, 3.0]\nlook_at = [0.0, 1.0, 0.0]\nup = [0.0, 1.0, 0.0]\nvfov = 40.0\n\
                 resolution = [8, 8]\n\n[[mesh]]\nfile = \"m.obj\"\n";
    Ok(Scene::parse(scene, &dir.join("s.toml").display().to_string())?)
}

/// One directory per test thread (tests run in parallel).
fn scratch(tag: &str) -> PathBuf {
    let thread = format!("{:?}", std::thread::current().id()).replace(|c: char| !c.is_ascii_alphanumeric(), "");
    let dir = std::env::temp_dir().join(format!("ppm-vk-hostile-{}-{tag}-{thread}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Numbers a mutation puts in place of one in the file.
const EXTREME: &[&str] = &[
    "0",
    "-0",
    "-1",
    "1e9",
    "1000000000",
    "4294967295",
    "4294967296",
    "18446744073709551616",
    "-2147483649",
    "1e39",
    "-1e39",
    "1e-45",
    "nan",
    "inf",
    "-inf",
    "0x10",
    "1e",
    ".",
    "99999999999999999999999999999999",
];

#[derive(Clone, Debug)]
enum Mutation {
    /// Replace the byte at (position modulo length) by this one.
    Byte(usize, u8),
    /// Drop a line.
    DropLine(usize),
    /// Repeat a line this many times.
    RepeatLine(usize, u16),
    /// Replace the n-th number by an extreme one.
    Number(usize, usize),
    /// Cut the text here.
    Truncate(usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Mutation::Byte(i, b)),
        any::<usize>().prop_map(Mutation::DropLine),
        (any::<usize>(), 1..2000u16).prop_map(|(i, n)| Mutation::RepeatLine(i, n)),
        (any::<usize>(), 0..EXTREME.len()).prop_map(|(i, k)| Mutation::Number(i, k)),
        any::<usize>().prop_map(Mutation::Truncate),
    ]
}

fn apply(text: &[u8], m: &Mutation) -> Vec<u8> {
    let mut t = text.to_vec();
    if t.is_empty() {
        return t;
    }
    let lines = |t: &[u8]| -> Vec<Vec<u8>> { t.split(|&c| c == b'\n').map(<[u8]>::to_vec).collect() };
    match *m {
        Mutation::Byte(i, b) => {
            let n = t.len();
            t[i % n] = b;
        }
        Mutation::DropLine(i) => {
            let mut l = lines(&t);
            let n = l.len();
            l.remove(i % n);
            t = l.join(&b'\n');
        }
        Mutation::RepeatLine(i, k) => {
            let mut l = lines(&t);
            let n = l.len();
            let line = l[i % n].clone();
            l.splice(i % n..i % n, std::iter::repeat_n(line, k as usize));
            t = l.join(&b'\n');
        }
        Mutation::Number(i, k) => {
            let text = String::from_utf8_lossy(&t).into_owned();
            let numbers: Vec<(usize, usize)> = regex_free_numbers(&text);
            if let Some(&(a, b)) = numbers.get(i % numbers.len().max(1)) {
                t = format!("{}{}{}", &text[..a], EXTREME[k], &text[b..]).into_bytes();
            }
        }
        Mutation::Truncate(i) => t.truncate(i % t.len()),
    }
    t
}

/// Byte ranges of the decimal numbers in `text`.
fn regex_free_numbers(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if b[i].is_ascii_digit() || (b[i] == b'-' && b.get(i + 1).is_some_and(u8::is_ascii_digit)) {
            let start = i;
            i += 1;
            while i < b.len() && (b[i].is_ascii_digit() || matches!(b[i], b'.' | b'e' | b'E' | b'-' | b'+')) {
                i += 1;
            }
            out.push((start, i));
        } else {
            i += 1;
        }
    }
    out
}

/// Loads the text once, bounded in time and allocation; the result may be a scene or an error (counted
/// in `outcomes`: scenes, errors).
fn load_bounded(load: Load, text: &[u8], outcomes: &Cell<(u32, u32)>) -> Result<(), TestCaseError> {
    let (live, start) = (LIVE.with(Cell::get), Instant::now());
    PEAK.with(|p| p.set(live));
    let result = load(text);
    let (took, peak) = (start.elapsed(), PEAK.with(Cell::get) - live);
    prop_assert!(took < MAX_LOAD, "a load took {took:?}");
    prop_assert!(peak <= MAX_ALLOC, "a load allocated {} MiB", peak >> 20);
    let (scenes, errors) = outcomes.get();
    match result {
        Ok(_) => outcomes.set((scenes + 1, errors)),
        Err(e) => {
            // An error says something (the loaders prefix the file name).
            let message = format!("{e:#}");
            prop_assert!(!message.trim().is_empty());
            outcomes.set((scenes, errors + 1));
        }
    }
    Ok(())
}

/// `load` on mutations of `seeds` (and on random text) returns, in bounded time and memory, for
/// `CASES` cases; a panic fails the case like an assertion (proptest catches it and shrinks).
fn never_panics(name: &str, load: Load, seeds: &[&str]) {
    let seeds: Vec<Vec<u8>> = seeds
        .iter()
        .map(|s| std::fs::read(Path::new(ROOT).join(s)).unwrap())
        .collect();
    let mut runner = TestRunner::new(Config {
        cases: CASES,
        failure_persistence: None,
        ..Config::default()
    });
    let strategy = (0..seeds.len(), prop::collection::vec(mutation(), 1..6));
    let outcomes = Cell::new((0, 0));
    runner
        .run(&strategy, |(seed, mutations)| {
            let text = mutations.iter().fold(seeds[seed].clone(), |t, m| apply(&t, m));
            load_bounded(load, &text, &outcomes)
        })
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    // The mutations reach both sides: some files still load, others are refused.
    let (scenes, errors) = outcomes.get();
    println!("{name}: {scenes} mutated files loaded, {errors} refused");
    // An image's mutations mostly break a checksum (PNG's CRCs): fewer of them load.
    let least = if name == "image" { CASES / 200 } else { CASES / 20 };
    assert!(
        scenes > least && errors > least,
        "{name}: {scenes} loaded, {errors} refused"
    );
    let mut runner = TestRunner::new(Config {
        cases: CASES / 4,
        failure_persistence: None,
        ..Config::default()
    });
    runner
        .run(&prop::collection::vec(any::<u8>(), 0..512), |bytes| {
            load_bounded(load, &bytes, &Cell::new((0, 0)))
        })
        .unwrap_or_else(|e| panic!("{name}, random bytes: {e}"));
}

#[test]
fn every_format_survives_mutated_files() {
    for (name, load, seeds) in formats() {
        // The unmutated seeds load: the mutations start from real scenes.
        if name == "toml" || name == "image" {
            for s in &seeds {
                load(&std::fs::read(Path::new(ROOT).join(s)).unwrap()).unwrap_or_else(|e| panic!("{s}: {e:#}"));
            }
        }
        never_panics(name, load, &seeds);
    }
}

/// The stated bounds, at the bound and one past it.
#[test]
fn scene_limits_hold_at_their_bounds() {
    let base = std::fs::read_to_string(format!("{ROOT}/scenes/cornell-spheres.toml")).unwrap();
    let with_resolution = |w: u32, h: u32| {
        let line = base
            .lines()
            .find(|l| l.trim_start().starts_with("resolution"))
            .expect("a resolution line");
        load_toml(base.replace(line, &format!("resolution = [{w}, {h}]")).as_bytes())
    };
    assert!(with_resolution(MAX_RESOLUTION, MAX_RESOLUTION).is_ok());
    let e = format!("{:#}", with_resolution(MAX_RESOLUTION + 1, 8).unwrap_err());
    assert!(e.contains("camera.resolution") && e.contains("1..=16384"), "{e}");
    let e = format!("{:#}", with_resolution(1_000_000_000, 1_000_000_000).unwrap_err());
    assert!(e.contains("camera.resolution"), "{e}");

    // Spheres and quads together: MAX_SHAPES is accepted, one more is not.
    let mut scene = load_toml(base.as_bytes()).unwrap();
    let sphere = scene.spheres[0];
    scene.spheres.resize(MAX_SHAPES - scene.quads.len(), sphere);
    scene.validate().unwrap();
    scene.spheres.push(sphere);
    let e = format!("{:#}", scene.validate().unwrap_err());
    assert!(e.contains("65537 spheres and quads") && e.contains("MAX_SHAPES"), "{e}");

    // A scene file over MAX_SCENE_BYTES is refused before it is read (a sparse file: no disk used), and
    // so is a device file that would never end.
    let dir = scratch("bounds");
    let big = dir.join("big.toml");
    std::fs::File::create(&big)
        .unwrap()
        .set_len(MAX_SCENE_BYTES + 1)
        .unwrap();
    let e = format!("{:#}", Scene::load(&big).unwrap_err());
    assert!(
        e.contains("big.toml") && e.contains("more than a scene file may have"),
        "{e}"
    );
    std::fs::File::create(&big).unwrap().set_len(MAX_SCENE_BYTES).unwrap();
    let e = format!("{:#}", Scene::load(&big).unwrap_err());
    assert!(
        !e.contains("may have"),
        "at the bound the file is read (and is no scene): {e}"
    );
    let e = format!("{:#}", Scene::load(Path::new("/dev/zero")).unwrap_err());
    assert!(e.contains("not a regular file"), "{e}");
    let e = format!(
        "{:#}",
        load_toml(
            base.replace("[[sphere]]", "[[mesh]]\nfile = \"/dev/zero\"\n\n[[sphere]]")
                .as_bytes()
        )
        .unwrap_err()
    );
    assert!(e.contains("/dev/zero") && e.contains("not a regular file"), "{e}");
}
