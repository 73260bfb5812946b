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

use ppm_vk_engine::scene::{MAX_RESOLUTION, MAX_SCENE_BYTES, MAX_SHAPES, MAX_SPECTRUM_BYTES};
use ppm_vk_engine::Scene;
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRng, TestRunner};

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
                "scenes/references/textures/unit.pfm",
            ],
        ),
        (
            "serialized",
            load_serialized,
            vec![
                "scenes/references/serialized/shapes-v4.serialized",
                "scenes/references/serialized/shapes-v3.serialized",
            ],
        ),
        (
            "xml",
            load_xml,
            vec![
                "../shared/reference/cornell-spheres.xml",
                "scenes/references/cornell-coated.xml",
                "scenes/legacy/cornell-spheres.xml",
                "scenes/bump-plane.xml",
                "scenes/blend-plane.xml",
                "scenes/textured-light-mesh.xml",
            ],
        ),
        ("spd", load_spd, vec!["scenes/references/spectra-test.spd"]),
    ]
}

/// A spectrum file (Mitsuba's .spd text) as a light's radiance and a floor's reflectance.
fn load_spd(text: &[u8]) -> anyhow::Result<Scene> {
    let dir = scratch("spd");
    std::fs::write(dir.join("s.spd"), String::from_utf8_lossy(text).as_bytes())?;
    let path = xml_scene(
        &dir,
        "s.xml",
        r#"<shape type="rectangle"><bsdf type="diffuse"><spectrum name="reflectance" filename="s.spd"/></bsdf></shape>
           <shape type="sphere"><emitter type="area"><spectrum name="radiance" filename="s.spd"/></emitter></shape>"#,
    );
    Ok(Scene::load(&path)?)
}

/// A Mitsuba scene, read from a file (includes and meshes resolve against its directory, where
/// `textures/` and `meshes/` link to the real ones under scenes/, so the seeds' files are found).
fn load_xml(text: &[u8]) -> anyhow::Result<Scene> {
    let dir = scratch("xml");
    for sub in ["textures", "meshes"] {
        if !dir.join(sub).exists() {
            std::os::unix::fs::symlink(Path::new(ROOT).join("scenes").join(sub), dir.join(sub))?;
        }
    }
    let path = dir.join("s.xml");
    std::fs::write(&path, String::from_utf8_lossy(text).as_bytes())?;
    Ok(Scene::load(&path)?)
}

/// A serialized mesh, its second shape (so that the end-of-file dictionary is read), in a minimal scene.
fn load_serialized(bytes: &[u8]) -> anyhow::Result<Scene> {
    let dir = scratch("serialized");
    std::fs::write(dir.join("m.serialized"), bytes)?;
    let body = r#"<shape type="serialized"><string name="filename" value="m.serialized"/>
                  <integer name="shape_index" value="1"/></shape>"#;
    Ok(Scene::load(xml_scene(&dir, "s.xml", body))?)
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
    // A fixed seed: the counts below are the same on every run and machine (CI sees what a developer saw).
    let config = Config {
        cases: CASES,
        failure_persistence: None,
        ..Config::default()
    };
    let mut runner = TestRunner::new_with_rng(config.clone(), TestRng::deterministic_rng(config.rng_algorithm));
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
    let config = Config {
        cases: CASES / 4,
        ..config
    };
    let mut runner = TestRunner::new_with_rng(config.clone(), TestRng::deterministic_rng(config.rng_algorithm));
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
        if matches!(name, "toml" | "image" | "xml") {
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

/// Runs `load` on a thread of its own and returns its outcome, failing if it takes over `limit` (a load
/// blocked in `open()` on a FIFO would otherwise hang the test) or allocates over `MAX_ALLOC` at once.
fn bounded<T: Send + 'static>(what: &str, limit: Duration, load: impl FnOnce() -> T + Send + 'static) -> T {
    bounded_to(what, limit, MAX_ALLOC, load)
}

/// [`bounded`] with an allocation bound of `max_alloc` bytes.
fn bounded_to<T: Send + 'static>(
    what: &str,
    limit: Duration,
    max_alloc: usize,
    load: impl FnOnce() -> T + Send + 'static,
) -> T {
    let (send, recv) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        PEAK.with(|p| p.set(LIVE.with(Cell::get)));
        let base = LIVE.with(Cell::get);
        let out = load();
        let peak = PEAK.with(Cell::get).saturating_sub(base);
        let _ = send.send((out, peak));
    });
    let (out, peak) = recv
        .recv_timeout(limit)
        .unwrap_or_else(|_| panic!("{what}: no answer within {limit:?} (blocked?)"));
    assert!(peak <= max_alloc, "{what}: allocated {peak} bytes at once");
    out
}

/// A scene in `dir` whose floor's material is `material`, with `extra` appended (TOML).
fn toml_scene(dir: &Path, name: &str, material: &str, extra: &str) -> PathBuf {
    let text = format!(
        "[camera]\neye = [0.0, 1.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 1.0, 0.0]\nvfov = 40.0\n\
         resolution = [8, 8]\n\n[materials.floor]\n{material}\n\n[materials.light]\nemission = [1.0, 1.0, 1.0]\n\n\
         [[quad]]\norigin = [-1.0, 0.0, -1.0]\nedge_u = [0.0, 0.0, 2.0]\nedge_v = [2.0, 0.0, 0.0]\n\
         material = \"floor\"\n\n[[quad]]\norigin = [-0.1, 1.0, -0.1]\nedge_u = [0.2, 0.0, 0.0]\n\
         edge_v = [0.0, 0.0, 0.2]\nmaterial = \"light\"\n{extra}"
    );
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// A Mitsuba scene in `dir` with a camera, a light and `body`.
fn xml_scene(dir: &Path, name: &str, body: &str) -> PathBuf {
    let text = format!(
        "<scene version=\"3.0.0\">\n<sensor type=\"perspective\"><float name=\"fov\" value=\"40\"/>\
         <transform name=\"to_world\"><lookat origin=\"0, 1, 3\" target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform>\
         <film type=\"hdrfilm\"><integer name=\"width\" value=\"8\"/><integer name=\"height\" value=\"8\"/></film>\
         </sensor>\n<shape type=\"rectangle\"><transform name=\"to_world\"><rotate x=\"1\" angle=\"-90\"/>\
         </transform><emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter></shape>\n{body}\n</scene>\n"
    );
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// A FIFO at `path` (no writer ever opens it: reading it would block forever).
fn mkfifo(path: &Path) {
    let c = std::ffi::CString::new(path.as_os_str().as_encoded_bytes()).unwrap();
    let _ = std::fs::remove_file(path);
    // SAFETY: a NUL-terminated path and a mode.
    assert_eq!(
        unsafe { libc::mkfifo(c.as_ptr(), 0o600) },
        0,
        "mkfifo {}",
        path.display()
    );
}

/// The load's error (it must fail), under the time and allocation bounds.
fn load_fails(path: PathBuf) -> String {
    let what = path.display().to_string();
    let out = bounded(&what, Duration::from_secs(5), move || {
        Scene::load(&path).map(|_| ()).map_err(|e| e.to_string())
    });
    let e = out.expect_err(&what);
    assert!(!e.contains("panicked"), "{e}");
    e
}

/// Bump maps with a scale that is not a finite f32 (NaN, infinite, or finite in f64 and infinite in f32) and
/// a normal map without its texture or with two bsdfs: an error naming the element or field, never a panic.
#[test]
fn hostile_bump_and_normal_maps_are_refused() {
    let dir = scratch("modifiers");
    let bump = |scale: &str| {
        format!(
            "<shape type=\"rectangle\"><bsdf type=\"bumpmap\"><float name=\"scale\" value=\"{scale}\"/>\
             <texture type=\"bitmap\"><string name=\"filename\" value=\"{}\"/></texture>\
             <bsdf type=\"diffuse\"/></bsdf></shape>",
            Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("scenes/textures/bump-height.exr")
                .display()
        )
    };
    let cases = [
        (bump("nan"), "scale"),
        (bump("inf"), "scale"),
        (bump("1e39"), "scale"),
        (
            "<shape type=\"rectangle\"><bsdf type=\"normalmap\"><bsdf type=\"diffuse\"/></bsdf></shape>".to_string(),
            "needs the texture \"normalmap\"",
        ),
        (
            "<shape type=\"rectangle\"><bsdf type=\"normalmap\"><texture type=\"checkerboard\" name=\"normalmap\"/>\
             <bsdf type=\"diffuse\"/><bsdf type=\"diffuse\"/></bsdf></shape>"
                .to_string(),
            "a second bsdf",
        ),
    ];
    for (i, (body, says)) in cases.iter().enumerate() {
        let e = load_fails(xml_scene(&dir, &format!("m{i}.xml"), body));
        assert!(e.contains(says), "{body}: {e}");
    }
}

/// Radiance textures (an area emitter's `radiance`, issue 37) with a NaN, an infinite or a negative pixel,
/// a `ref` to no texture, one on a sphere, one on a mesh without texture coordinates: an error naming the
/// element or file, never a panic.
#[test]
fn hostile_radiance_textures_are_refused() {
    let dir = scratch("radiance");
    let exr = |name: &str, bad: f32| {
        let img = image::Rgb32FImage::from_fn(3, 2, |x, y| {
            image::Rgb([1.0, if (x, y) == (2, 1) { bad } else { 2.0 }, 0.5])
        });
        img.save(dir.join(name)).unwrap();
    };
    exr("nan.exr", f32::NAN);
    exr("inf.exr", f32::INFINITY);
    exr("neg.exr", -1.0);
    exr("good.exr", 3.0);
    std::fs::write(dir.join("bare.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let light = |shape: &str, extra: &str, radiance: &str| {
        format!("<shape type=\"{shape}\">{extra}<emitter type=\"area\">{radiance}</emitter></shape>")
    };
    let bitmap = |file: &str| {
        format!("<texture type=\"bitmap\" name=\"radiance\"><string name=\"filename\" value=\"{file}\"/></texture>")
    };
    let cases = [
        (
            light("rectangle", "", &bitmap("nan.exr")),
            "a radiance must be finite and at least 0",
        ),
        (
            light("rectangle", "", &bitmap("inf.exr")),
            "a radiance must be finite and at least 0",
        ),
        (
            light("rectangle", "", &bitmap("neg.exr")),
            "a radiance must be finite and at least 0",
        ),
        (
            light("rectangle", "", "<ref name=\"radiance\" id=\"nowhere\"/>"),
            "no texture with id \"nowhere\"",
        ),
        (
            light("sphere", "", &bitmap("good.exr")),
            "radiance on a sphere is not supported",
        ),
        (
            light(
                "obj",
                "<string name=\"filename\" value=\"bare.obj\"/>",
                &bitmap("good.exr"),
            ),
            "bare.obj",
        ),
    ];
    for (i, (body, says)) in cases.iter().enumerate() {
        let e = load_fails(xml_scene(&dir, &format!("r{i}.xml"), body));
        assert!(e.contains(says), "{body}: {e}");
    }
}

/// Every file a scene names is opened only if it is a regular file, without blocking, and read within a
/// size bound: a FIFO as a texture (TOML `texture`, XML bitmap `filename`, MTL `map_Kd`), a PLY
/// `filename` or an `mtllib`, and /dev/zero as a PLY or an MTL, each end within 5 s (the FIFOs blocked
/// in open() for ever, /dev/zero was read until memory ran out) with an error naming the path.
#[test]
fn fifos_and_devices_a_scene_names_are_refused_at_once() {
    let dir = scratch("fifos");
    let fifo = dir.join("fifo");
    mkfifo(&fifo);
    let tri = "usemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n";
    std::fs::write(dir.join("fifo-lib.obj"), format!("mtllib fifo\n{tri}")).unwrap();
    std::fs::write(dir.join("zero-lib.obj"), format!("mtllib /dev/zero\n{tri}")).unwrap();
    std::fs::write(dir.join("map.obj"), format!("mtllib map.mtl\n{tri}")).unwrap();
    std::fs::write(dir.join("map.mtl"), "newmtl m\nKd 0.5 0.5 0.5\nmap_Kd fifo\n").unwrap();
    let refused = |path: PathBuf, named: &str| {
        let e = load_fails(path);
        assert!(e.contains(named) && e.contains("not a regular file"), "{e}");
    };
    refused(
        toml_scene(&dir, "t.toml", "diffuse = { texture = \"fifo\" }", ""),
        "fifo",
    );
    let bitmap = "<shape type=\"rectangle\"><bsdf type=\"diffuse\"><texture type=\"bitmap\" name=\"reflectance\">\
                  <string name=\"filename\" value=\"fifo\"/></texture></bsdf></shape>";
    refused(xml_scene(&dir, "bitmap.xml", bitmap), "fifo");
    let ply = |file: &str| format!("<shape type=\"ply\"><string name=\"filename\" value=\"{file}\"/></shape>");
    refused(xml_scene(&dir, "ply-fifo.xml", &ply("fifo")), "fifo");
    refused(xml_scene(&dir, "ply-zero.xml", &ply("/dev/zero")), "/dev/zero");
    let mesh = |file: &str| format!("[[mesh]]\nfile = \"{file}\"\n");
    let plain = "diffuse = [0.5, 0.5, 0.5]";
    refused(toml_scene(&dir, "lib-fifo.toml", plain, &mesh("fifo-lib.obj")), "fifo");
    refused(
        toml_scene(&dir, "lib-zero.toml", plain, &mesh("zero-lib.obj")),
        "/dev/zero",
    );
    refused(toml_scene(&dir, "obj-fifo.toml", plain, &mesh("fifo")), "fifo");
    // An MTL's map_Kd that cannot be read is a warning (the constant Kd is used), as for a missing file.
    let path = toml_scene(&dir, "map.toml", plain, &mesh("map.obj"));
    let scene = bounded("map_Kd fifo", Duration::from_secs(5), move || {
        Scene::load(&path).map_err(|e| e.to_string())
    });
    let warnings = scene.unwrap().warnings.join("\n");
    assert!(
        warnings.contains("map_Kd fifo ignored") && warnings.contains("not a regular file"),
        "{warnings}"
    );
}

/// Parameter expansion and includes have a total budget, not only a depth: ten `<default>`s each
/// repeating the one before ten times (10^10 bytes from 1.6 KB) and ten includes a file eight files deep
/// (10^8 files) end within 2 s with one short line; a six-level expansion used in a value is quoted short.
#[test]
fn expansion_and_include_bombs_end_fast_with_a_short_error() {
    let dir = scratch("bombs");
    let defaults = |levels: usize| {
        let mut s = "<default name=\"p0\" value=\"xxxxxxxxxx\"/>\n".to_string();
        for i in 1..=levels {
            s += &format!(
                "<default name=\"p{i}\" value=\"{}\"/>\n",
                format!("$p{}", i - 1).repeat(10)
            );
        }
        s
    };
    let e = load_fails(xml_scene(&dir, "bomb10.xml", &defaults(10)));
    assert!(e.contains("MiB of attribute values in all") && e.len() < 500, "{e}");
    // Used as a number, five levels (1 MB) are quoted cut short; six (10 MB, whose message was 10 MB
    // long) are over the budget.
    for (levels, says) in [(5, "is not a number"), (6, "MiB of attribute values in all")] {
        let body = format!(
            "{}<shape type=\"sphere\"><float name=\"radius\" value=\"$p{levels}\"/></shape>",
            defaults(levels)
        );
        let e = load_fails(xml_scene(&dir, &format!("bomb{levels}.xml"), &body));
        assert!(e.contains(says) && e.len() < 600, "{} bytes: {e:.600}", e.len());
    }

    for i in 0..8 {
        let includes = format!("<include filename=\"inc{}.xml\"/>\n", i + 1).repeat(10);
        std::fs::write(
            dir.join(format!("inc{i}.xml")),
            format!("<scene version=\"3.0.0\">{includes}</scene>"),
        )
        .unwrap();
    }
    std::fs::write(
        dir.join("inc8.xml"),
        "<scene version=\"3.0.0\"><bsdf type=\"diffuse\"/></scene>",
    )
    .unwrap();
    let e = load_fails(dir.join("inc0.xml"));
    assert!(e.contains("more than 1000 files") && e.len() < 500, "{e}");
}

/// `-D res=$res`: the value holds the parameter itself, which is not substituted again; the error says so
/// rather than calling $res undefined and asking for the -D that was given.
#[test]
fn a_parameter_left_in_a_value_is_explained() {
    let dir = scratch("define");
    let path = xml_scene(&dir, "res.xml", "<default name=\"res\" value=\"8\"/>");
    let text = std::fs::read_to_string(&path)
        .unwrap()
        .replace("name=\"width\" value=\"8\"", "name=\"width\" value=\"$res\"");
    std::fs::write(&path, text).unwrap();
    let defines = [("res".to_string(), "$res".to_string())];
    let e = Scene::load_with(&path, &defines).unwrap_err().to_string();
    assert!(
        e.contains("$res is left after substitution")
            && e.contains("not substituted again")
            && !e.contains("undefined"),
        "{e}"
    );
}

/// Values that would render black without a word: a sphere beyond what f32 intersection holds (radius
/// 1e30, its top the floor), a light whose power underflows (emission 1e-45), each an error naming the
/// file, line and field (TOML) or the element (XML).
#[test]
fn geometry_beyond_f32_and_underflowing_lights_are_refused() {
    let dir = scratch("f32");
    let plain = "diffuse = [0.5, 0.5, 0.5]";
    let sphere = "[[sphere]]\ncenter = [0.0, -1e30, 0.0]\nradius = 1e30\nmaterial = \"floor\"\n";
    let e = load_fails(toml_scene(&dir, "s.toml", plain, sphere));
    assert!(
        e.contains("s.toml:27:10: sphere[0].radius: a sphere of radius 1e30") && e.contains("2^60"),
        "{e}"
    );
    let body = "<shape type=\"sphere\"><float name=\"radius\" value=\"1e30\"/>\
                <point name=\"center\" x=\"0\" y=\"-1e30\" z=\"0\"/></shape>";
    let e = load_fails(xml_scene(&dir, "s.xml", body));
    assert!(
        e.contains("s.xml:4:1: <shape type=\"sphere\">") && e.contains("2^60"),
        "{e}"
    );
    let path = toml_scene(&dir, "l.toml", plain, "");
    let text = std::fs::read_to_string(&path)
        .unwrap()
        .replace("emission = [1.0, 1.0, 1.0]", "emission = [1e-45, 0, 0]");
    std::fs::write(&path, text).unwrap();
    let e = load_fails(path);
    assert!(
        e.contains("l.toml:12:12: materials.light.emission") && e.contains("would round to 0"),
        "{e}"
    );
}

/// PLY errors are sentences with the file and, for text, the line: not ply-rs's debug dump, and no
/// "Line 17" inside binary data.
#[test]
fn ply_errors_are_sentences() {
    let dir = scratch("ply");
    let header = |format: &str| {
        format!(
            "ply\nformat {format} 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
             element face 1\nproperty list uchar int vertex_indices\nend_header\n"
        )
    };
    std::fs::write(dir.join("a.ply"), header("ascii") + "0 0 0\n1 0 0\nzz 1 0\n3 0 1 2\n").unwrap();
    let mut binary = header("binary_little_endian").into_bytes();
    binary.extend_from_slice(&[0; 8]);
    std::fs::write(dir.join("b.ply"), binary).unwrap();
    let ply = |file: &str| format!("<shape type=\"ply\"><string name=\"filename\" value=\"{file}\"/></shape>");
    let e = load_fails(xml_scene(&dir, "a.xml", &ply("a.ply")));
    assert!(e.contains("a.ply:12: malformed PLY") && e.contains("\"zz 1 0\""), "{e}");
    let text = e;
    let e = load_fails(xml_scene(&dir, "b.xml", &ply("b.ply")));
    assert!(
        e.contains("b.ply: malformed PLY: in its binary data") && !e.contains("Line "),
        "{e}"
    );
    for e in [&text, &e] {
        assert!(!e.contains('{') && !e.contains('\n') && !e.contains("Custom"), "{e}");
    }
}

/// A floor textured with the image file `name` in `dir`.
fn textured(dir: &Path, name: &str) -> PathBuf {
    let material = format!("diffuse = {{ texture = \"{name}\" }}");
    toml_scene(dir, &format!("{name}.toml"), &material, "")
}

/// Damaged images are refused in sentences: a JPEG cut after its scan header (it decoded grey without a
/// word) like a truncated PNG, a PNG with a bad checksum without the PNG decoder's debug dump.
#[test]
fn damaged_images_are_refused_in_sentences() {
    let dir = scratch("images");
    let rgb = image::RgbImage::from_fn(64, 64, |x, y| image::Rgb([(x * 4) as u8, (y * 4) as u8, 128]));
    let mut jpeg = Vec::new();
    image::codecs::jpeg::JpegEncoder::new(&mut jpeg)
        .encode_image(&rgb)
        .unwrap();
    std::fs::write(dir.join("whole.jpg"), &jpeg).unwrap();
    let path = textured(&dir, "whole.jpg");
    bounded("a whole JPEG", Duration::from_secs(5), move || {
        Scene::load(&path).map(drop).unwrap()
    });
    let sos = jpeg.windows(2).position(|w| w == [0xFF, 0xDA]).unwrap();
    let header = u16::from_be_bytes([jpeg[sos + 2], jpeg[sos + 3]]) as usize;
    std::fs::write(dir.join("cut.jpg"), &jpeg[..sos + 2 + header + 10]).unwrap();
    let e = load_fails(textured(&dir, "cut.jpg"));
    assert!(e.contains("cut.jpg") && e.contains("cut short"), "{e}");

    let mut png = Vec::new();
    rgb.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    let idat = png.windows(4).position(|w| w == b"IDAT").unwrap();
    let len = u32::from_be_bytes(png[idat - 4..idat].try_into().unwrap()) as usize;
    png[idat + 4 + len] ^= 0xFF; // the first byte of the IDAT chunk's CRC
    std::fs::write(dir.join("crc.png"), &png).unwrap();
    let e = load_fails(textured(&dir, "crc.png"));
    assert!(e.contains("crc.png") && e.contains("damaged"), "{e}");
    assert!(!e.contains("ChunkType") && !e.contains('{'), "{e}");
}

/// PFM images (crates/scene/src/pfm.rs): one read; a bad header, data cut short, sides beyond
/// MAX_TEXTURE_SIDE or MAX_TEXTURE_PIXELS (refused from the header, before any allocation), a NaN pixel
/// and a scale that is not finite are refused in sentences naming the file.
#[test]
fn damaged_pfms_are_refused_in_sentences() {
    let dir = scratch("pfm");
    let pfm = |name: &str, header: &str, values: &[f32]| {
        let mut bytes = header.as_bytes().to_vec();
        for v in values {
            bytes.extend(v.to_le_bytes());
        }
        std::fs::write(dir.join(name), bytes).unwrap();
        textured(&dir, name)
    };
    let good = pfm("good.pfm", "PF\n2 1\n-1\n", &[0.1, 0.2, 0.3, 0.4, 0.5, 0.6]);
    let scene = Scene::load(&good).unwrap();
    assert_eq!(scene.textures[0].pixel_count(), 2);
    for (name, header, values, said) in [
        ("magic.pfm", "PX\n2 1\n-1\n", &[0.5f32; 6][..], "first bytes"),
        (
            "width.pfm",
            "PF\nwide 1\n-1\n",
            &[0.5; 6][..],
            "width \"wide\" is not a whole number",
        ),
        ("cut.pfm", "PF\n2 1\n-1\n", &[0.5; 5][..], "cut short"),
        (
            "huge.pfm",
            "PF\n4000000000 4000000000\n-1\n",
            &[][..],
            "each side must be in 1..=",
        ),
        ("many.pfm", "PF\n16384 16384\n-1\n", &[][..], "at most"),
        (
            "nan.pfm",
            "Pf\n2 1\n-1\n",
            &[0.5, f32::NAN][..],
            "values must be finite",
        ),
        ("scale.pfm", "PF\n2 1\nnan\n", &[0.5; 6][..], "is not a finite number"),
    ] {
        let path = pfm(name, header, values);
        let e = load_fails(path);
        assert!(e.contains(name) && e.contains(said), "{name}: {e}");
    }
}

/// An EXR of 16384 x 4096 pixels, at MAX_TEXTURE_SIDE and MAX_TEXTURE_PIXELS, loads (the image crate's
/// default memory limit refused it with just "Memory limit exceeded"), within 2.5 GiB of allocation.
#[test]
fn an_exr_at_the_documented_pixel_limit_loads() {
    use exr::prelude::*;
    let dir = scratch("exr");
    let path = dir.join("wide.exr");
    let (w, h) = (16384usize, 4096usize);
    assert_eq!(w as u64 * h as u64, ppm_vk_engine::scene::texture::MAX_TEXTURE_PIXELS);
    let grey = f16::from_f32(0.5);
    let channels = SpecificChannels::rgb(|_: Vec2<usize>| (grey, grey, grey));
    let layer = Layer::new((w, h), LayerAttributes::named("rgb"), Encoding::FAST_LOSSLESS, channels);
    Image::from_layer(layer).write().to_file(&path).unwrap();
    let scene = textured(&dir, "wide.exr");
    let loaded = bounded_to("a 16384 x 4096 EXR", Duration::from_secs(60), 5 << 29, move || {
        Scene::load(&scene).map_err(|e| e.to_string())
    });
    let scene = loaded.unwrap();
    assert_eq!(scene.textures[0].pixel_count(), w as u64 * h as u64);
    std::fs::remove_file(&path).ok();
}

/// Spectra Mitsuba refuses (one entry, wavelengths that do not increase, NaN) and a spectrum file beyond
/// its bound are errors naming the file, the line and the element; a file at the bound is read.
#[test]
fn malformed_spectra_are_refused_in_sentences() {
    let dir = scratch("spectra");
    let body = |value: &str| {
        format!(
            r#"<shape type="cube"><bsdf type="diffuse"><spectrum name="reflectance" value="{value}"/></bsdf></shape>"#
        )
    };
    for (value, says) in [
        ("500:0.5", "at least two wavelength:value entries"),
        (
            "600:0.5, 500:0.2",
            "wavelengths must increase strictly: 500 nm follows 600 nm",
        ),
        (
            "500:0.5, 500:0.2",
            "wavelengths must increase strictly: 500 nm follows 500 nm",
        ),
        ("400:0.5, 500:nan", "NaN is not a finite number"),
        ("400:0.5, 500:1e999", "inf is not a finite number"),
        ("400:0.5 500", "\"500\" is not a wavelength:value pair"),
    ] {
        let e = load_fails(xml_scene(&dir, "s.xml", &body(value)));
        assert!(
            e.contains("s.xml:4:") && e.contains("<spectrum name=\"reflectance\">") && e.contains(says),
            "{value}: {e}"
        );
    }
    let file = |text: &str| {
        std::fs::write(dir.join("f.spd"), text).unwrap();
        xml_scene(
            &dir,
            "f.xml",
            r#"<shape type="cube"><bsdf type="diffuse"><spectrum name="reflectance" filename="f.spd"/></bsdf></shape>"#,
        )
    };
    let e = load_fails(file("# measured\n400 0.5\n450 0.6 0.7\n"));
    assert!(
        e.contains("f.xml:4:") && e.contains("f.spd:3: expected a wavelength and a value, got 3 numbers"),
        "{e}"
    );
    let e = load_fails(file("400 0.5\n380 0.6\n"));
    assert!(e.contains("f.spd: wavelengths must increase strictly"), "{e}");
    let e = load_fails(file("400 0.5\n500 nan\n"));
    assert!(e.contains("f.spd:2: \"nan\" is not a finite number"), "{e}");
    // At the bound: read; one byte more (a sparse file) is refused before it is read.
    let line = "500 0.5\n";
    let mut text = format!(
        "400 0.5\n{}",
        "#".repeat(MAX_SPECTRUM_BYTES as usize - 8 - line.len() - 1)
    );
    text += "\n";
    text += line;
    assert_eq!(text.len() as u64, MAX_SPECTRUM_BYTES);
    assert!(Scene::load(file(&text)).is_ok());
    std::fs::File::create(dir.join("f.spd"))
        .unwrap()
        .set_len(MAX_SPECTRUM_BYTES + 1)
        .unwrap();
    let path = xml_scene(
        &dir,
        "f.xml",
        r#"<shape type="cube"><bsdf type="diffuse"><spectrum name="reflectance" filename="f.spd"/></bsdf></shape>"#,
    );
    let e = load_fails(path);
    assert!(
        e.contains("f.xml:4:") && e.contains("f.spd") && e.contains("more than a spectrum file may have"),
        "{e}"
    );
}

/// One shape of a version 4 serialized file: its header, then `body` (the flags onwards) compressed.
fn serialized_shape(body: &[u8]) -> Vec<u8> {
    use std::io::Write as _;
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
    z.write_all(body).unwrap();
    let mut out = vec![0x1C, 0x04, 4, 0];
    out.extend(z.finish().unwrap());
    out
}

/// The uncompressed body of a version 4 shape: float positions only, `vertices` and `faces` as the header
/// says, then the arrays of a triangle (three vertices, one face).
fn triangle_body(vertices: u64, faces: u64) -> Vec<u8> {
    let mut b = 0x1000u32.to_le_bytes().to_vec();
    b.extend(b"tri\0");
    b.extend(vertices.to_le_bytes());
    b.extend(faces.to_le_bytes());
    for x in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        b.extend(x.to_le_bytes());
    }
    for i in [0u32, 1, 2] {
        b.extend(i.to_le_bytes());
    }
    b
}

/// `shapes` concatenated, with the end-of-file dictionary of their offsets.
fn serialized_file(shapes: &[Vec<u8>]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut offsets = Vec::new();
    for s in shapes {
        offsets.push(out.len() as u64);
        out.extend(s);
    }
    for o in offsets {
        out.extend(o.to_le_bytes());
    }
    out.extend((shapes.len() as u32).to_le_bytes());
    out
}

/// Damaged serialized meshes are each an error naming the file and what is wrong, within the time and
/// allocation bounds: a lying vertex count, counts past the bounds, a bad zlib stream, a file cut short,
/// a shape_index past the dictionary's end, a dictionary offset past the file's end, an endless name. A
/// zlib bomb behind an honest header is never inflated past what its counts need.
#[test]
fn damaged_serialized_meshes_are_refused_in_sentences() {
    use ppm_vk_engine::scene::{MAX_SERIALIZED_NAME, MAX_SERIALIZED_VERTICES, MAX_TRIANGLES};
    let dir = scratch("serialized-damaged");
    let scene = |name: &str, bytes: &[u8], index: u32| {
        std::fs::write(dir.join(name), bytes).unwrap();
        let body = format!(
            r#"<shape type="serialized"><string name="filename" value="{name}"/>
               <integer name="shape_index" value="{index}"/></shape>"#
        );
        xml_scene(&dir, &format!("{name}.xml"), &body)
    };
    let good = serialized_file(&[
        serialized_shape(&triangle_body(3, 1)),
        serialized_shape(&triangle_body(3, 1)),
    ]);
    let s = Scene::load(scene("good.serialized", &good, 1)).unwrap();
    assert_eq!(s.meshes[0].indices.len(), 1);

    let many = serialized_file(&[serialized_shape(&triangle_body(1 << 30, 1))]);
    // A count within the bounds that the data does not bear out.
    let lying = serialized_file(&[serialized_shape(&triangle_body(1 << 24, 1))]);
    let mut bad_zlib = good.clone();
    bad_zlib[4..12].copy_from_slice(b"garbage!");
    let mut far = good.clone();
    let n = far.len();
    far[n - 12..n - 4].copy_from_slice(&(1u64 << 40).to_le_bytes());
    let mut endless = 0x1000u32.to_le_bytes().to_vec();
    endless.extend(vec![b'a'; MAX_SERIALIZED_NAME + 1]);
    let mut at_bound = 0x1000u32.to_le_bytes().to_vec();
    at_bound.extend(vec![b'a'; MAX_SERIALIZED_NAME]);
    at_bound.extend(&triangle_body(3, 1)[7..]);
    let name_ok = Scene::load(scene(
        "name.serialized",
        &serialized_file(&[serialized_shape(&at_bound)]),
        0,
    ));
    assert!(
        name_ok.is_ok(),
        "a name of MAX_SERIALIZED_NAME bytes: {:?}",
        name_ok.err()
    );
    let cases: Vec<(&str, Vec<u8>, u32, &str)> = vec![
        (
            "many.serialized",
            many,
            0,
            "vertices, more than MAX_SERIALIZED_VERTICES",
        ),
        (
            "lying.serialized",
            lying,
            0,
            "the compressed stream ends after 48 bytes of data where its 16777216 vertices and 1 triangles need",
        ),
        (
            "triangles.serialized",
            serialized_file(&[serialized_shape(&triangle_body(3, MAX_TRIANGLES as u64 + 1))]),
            0,
            "triangles, more than MAX_TRIANGLES",
        ),
        (
            "zlib.serialized",
            bad_zlib,
            0,
            "bad zlib stream while reading the flags",
        ),
        ("short.serialized", good[..24].to_vec(), 0, "the file is cut short"),
        (
            "index.serialized",
            good.clone(),
            2,
            "shape_index 2 is past the end: the file's dictionary lists 2 shapes",
        ),
        (
            "far.serialized",
            far,
            1,
            "shape 1 is at offset 1099511627776 in the dictionary, past the end of the file",
        ),
        (
            "name-long.serialized",
            serialized_file(&[serialized_shape(&endless)]),
            0,
            "runs past 4096 bytes (MAX_SERIALIZED_NAME)",
        ),
        (
            "version.serialized",
            [&[0x1C, 0x04, 5, 0][..], &good[4..]].concat(),
            0,
            "version 5: versions 3 and 4 are read",
        ),
    ];
    // The lying count above is past the bound.
    const { assert!(MAX_SERIALIZED_VERTICES < 1 << 30) };
    for (name, bytes, index, says) in cases {
        let e = load_fails(scene(name, &bytes, index));
        assert!(
            e.contains(&format!("{name}.xml:")) && e.contains("<shape type=\"serialized\">"),
            "{e}"
        );
        assert!(e.contains(name) && e.contains(says), "{name}: {e}");
    }

    // A bomb: an honest triangle, then 256 MiB more of zeros in the same stream (about a MiB
    // compressed). Only the triangle's 48 bytes are inflated.
    let mut body = triangle_body(3, 1);
    body.resize(body.len() + (256 << 20), 0);
    let bomb = serialized_file(&[serialized_shape(&body)]);
    assert!(bomb.len() < 2 << 20, "{} bytes", bomb.len());
    let path = scene("bomb.serialized", &bomb, 0);
    let s = bounded("a zlib bomb", Duration::from_secs(5), move || {
        Scene::load(&path).map_err(|e| e.to_string())
    });
    assert_eq!(s.unwrap().meshes[0].indices.len(), 1);
}

/// Instancing is bounded as the shapes it copies are: a scene reaches MAX_SHAPES spheres and quads, or
/// MAX_TRIANGLES triangles, through instances and loads; one instance more is refused naming it, before
/// its copy is made.
#[test]
fn instancing_holds_the_scene_limits_at_their_bounds() {
    use ppm_vk_engine::scene::MAX_TRIANGLES;
    let dir = scratch("instancing");
    // Quads: the lamp and 257 instances of a group of 255 rectangles (MAX_SHAPES = 1 + 257 * 255), then
    // one more instance. (Few elements: the XML reader locates each element from the file's start.)
    assert_eq!(MAX_SHAPES, 1 + 257 * 255);
    let rectangles = format!(
        r#"<shape type="shapegroup" id="g">{}</shape>"#,
        r#"<shape type="rectangle"/>"#.repeat(255)
    );
    let instances = |n: usize| r#"<shape type="instance"><ref id="g"/></shape>"#.repeat(n);
    let s = Scene::load(xml_scene(&dir, "quads.xml", &format!("{rectangles}{}", instances(257)))).unwrap();
    assert_eq!(s.quads.len(), MAX_SHAPES);
    let e = load_fails(xml_scene(
        &dir,
        "quads1.xml",
        &format!("{rectangles}{}", instances(258)),
    ));
    assert!(
        e.contains("quads1.xml:4:")
            && e.contains("<shape type=\"instance\">")
            && e.contains(&format!("{} spheres and quads, more than MAX_SHAPES", MAX_SHAPES + 255)),
        "{e}"
    );
    // Triangles: a serialized mesh of MAX_TRIANGLES / 4 (equal) triangles, instanced four times, then five.
    let quarter = MAX_TRIANGLES as u64 / 4;
    let mut body = triangle_body(3, quarter);
    body.truncate(body.len() - 12);
    for _ in 0..quarter {
        for i in [0u32, 1, 2] {
            body.extend(i.to_le_bytes());
        }
    }
    std::fs::write(dir.join("many.serialized"), serialized_file(&[serialized_shape(&body)])).unwrap();
    let group = r#"<shape type="shapegroup" id="g"><shape type="serialized"><string name="filename" value="many.serialized"/>
                   <bsdf type="twosided"><bsdf type="diffuse"/></bsdf></shape></shape>"#;
    let s = Scene::load(xml_scene(&dir, "tris.xml", &format!("{group}{}", instances(4)))).unwrap();
    assert_eq!(s.meshes.iter().map(|m| m.indices.len()).sum::<usize>(), MAX_TRIANGLES);
    drop(s);
    let e = Scene::load(xml_scene(&dir, "tris1.xml", &format!("{group}{}", instances(5))))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("<shape type=\"instance\">")
            && e.contains(&format!(
                "{} triangles, more than MAX_TRIANGLES",
                MAX_TRIANGLES + MAX_TRIANGLES / 4
            )),
        "{e}"
    );
}

/// Blends (Mitsuba's blendbsdf) with one or three nested bsdfs, a weight outside [0, 1] (a value, a
/// texture), and nested past `MAX_BLEND_DEPTH` (at the bound they load): an error naming the file, line and
/// element, never a panic.
#[test]
fn hostile_blends_are_refused() {
    use ppm_vk_engine::scene::MAX_BLEND_DEPTH;
    let dir = scratch("blends");
    let diffuse = "<bsdf type=\"diffuse\"/>";
    let blend = |inside: &str| format!("<bsdf type=\"blendbsdf\">{inside}</bsdf>");
    let shape = |bsdf: &str| format!("<shape type=\"rectangle\">{bsdf}</shape>");
    // `depth` blends, each of the next one and a diffuse.
    let nested = |depth: u32| (0..depth).fold(diffuse.to_string(), |inner, _| blend(&format!("{inner}{diffuse}")));
    let cases = [
        (
            shape(&blend(diffuse)),
            "<bsdf type=\"blendbsdf\">",
            "needs two nested bsdfs",
        ),
        (
            shape(&blend(&[diffuse; 3].concat())),
            "<bsdf type=\"diffuse\">",
            "a third bsdf",
        ),
        (
            shape(&blend(&format!(
                "<float name=\"weight\" value=\"1.5\"/>{diffuse}{diffuse}"
            ))),
            "<float name=\"weight\">",
            "must be in [0, 1], got 1.5",
        ),
        (
            shape(&blend(&format!(
                "<float name=\"weight\" value=\"nan\"/>{diffuse}{diffuse}"
            ))),
            "<float name=\"weight\">",
            "nan is not finite",
        ),
        (
            shape(&blend(&format!(
                "<texture type=\"checkerboard\" name=\"weight\"><rgb name=\"color0\" value=\"2\"/></texture>\
                 {diffuse}{diffuse}"
            ))),
            "<texture type=\"checkerboard\" name=\"weight\">",
            "a blend weight texture's values must be in [0, 1]",
        ),
        (
            shape(&nested(MAX_BLEND_DEPTH + 1)),
            "<bsdf type=\"blendbsdf\">",
            "more than MAX_BLEND_DEPTH = 4",
        ),
    ];
    for (i, (body, element, says)) in cases.iter().enumerate() {
        let e = load_fails(xml_scene(&dir, &format!("b{i}.xml"), body));
        assert!(e.contains(&format!("b{i}.xml:4:")), "located: {e}");
        assert!(e.contains(element) && e.contains(says), "{body}: {e}");
    }
    // At the bound: read, every level a material of its own.
    let path = xml_scene(&dir, "bound.xml", &shape(&nested(MAX_BLEND_DEPTH)));
    let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e:#}"));
    let blends = scene
        .materials
        .iter()
        .filter(|m| matches!(m.surface, ppm_vk_engine::scene::Surface::Blend { .. }))
        .count();
    assert_eq!(blends as u32, MAX_BLEND_DEPTH);
}
