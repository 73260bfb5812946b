//! The `ppm-vk` binary end to end: a render with a report, a trace and per-pass errors, the report's
//! timings, and the errors a user sees for bad input.

mod common;

use std::path::{Path, PathBuf};

use common::{bin, CORNELL, CORNELL_REFERENCE};
use ppm_vk_engine::report::{RunReport, SCHEMA};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ppm-vk-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn render_writes_image_report_and_trace() {
    let dir = scratch("render");
    let (out, report, trace) = (dir.join("img.exr"), dir.join("run.json"), dir.join("run.trace.json"));
    let run = bin()
        .args([
            "render",
            CORNELL,
            "--passes",
            "3",
            "--photons-per-pass",
            "20000",
            "--resolution",
            "32x32",
            "--validate",
        ])
        .args([
            "--reference",
            CORNELL_REFERENCE,
            "--probe",
            "scale-free",
            "--cone",
            "1.1",
            "--region",
            "mine:0,0,256,256",
        ])
        .arg("--out")
        .arg(&out)
        .arg("--report")
        .arg(&report)
        .arg("--trace")
        .arg(&trace)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "render failed:\n{stdout}\n{stderr}");
    assert!(out.exists() && std::fs::metadata(&out).unwrap().len() > 0);
    assert!(stderr.contains("probe:"), "no probe summary in:\n{stderr}");
    assert!(
        stdout.contains("error evaluated after 3 passes"),
        "no overhead line in:\n{stdout}"
    );

    let r = RunReport::load_json(&report).unwrap();
    assert_eq!(r.header.schema, SCHEMA);
    assert_eq!((r.header.width, r.header.height), (32, 32));
    // The hash of the scene as rendered (at the --resolution given), the one checkpoints carry.
    let scene = ppm_vk_engine::Scene::load(CORNELL).unwrap().with_resolution(32, 32);
    assert_eq!(r.header.scene_sha256, scene.content_sha256());
    assert!(r.header.probe.is_some());
    assert_eq!(r.passes.len(), 3);
    let mut last_elapsed = 0.0;
    let mut last_gpu_start = f64::MIN;
    for (k, p) in r.passes.iter().enumerate() {
        assert_eq!(p.pass, k as u64 + 1);
        assert_eq!(p.photons_total, 20_000 * (k as u64 + 1));
        let e = p.error.expect("an error per pass");
        assert!(e.rmse.is_finite() && e.rmse > 0.0 && e.rel_mse > 0.0);
        // A --region replaces the scene's own regions.
        assert!(
            p.region_errors.contains_key("mine") && !p.region_errors.contains_key("caustic"),
            "{:?}",
            p.region_errors.keys()
        );
        // Timings: every stage positive; stages in pipeline order on the GPU clock; passes in order on the
        // wall clock; and the GPU time of a pass fits inside its wall time. 1 ms of slack: the GPU and host
        // clocks agree within ~0.3 ms on lavapipe (../shared/notes/TOOLCHAIN.md), and a pass has three
        // submissions.
        for stage in ["photon", "lookup", "gather", "update"] {
            assert!(
                p.stage_ms[stage] > 0.0,
                "pass {}: {stage} took {} ms",
                p.pass,
                p.stage_ms[stage]
            );
        }
        let order = ["photon", "lookup", "gather", "update"].map(|s| p.stage_start_ms[s]);
        assert!(
            order.windows(2).all(|w| w[0] <= w[1]),
            "pass {}: stage starts out of order {order:?}",
            p.pass
        );
        assert!(
            order[0] >= last_gpu_start,
            "pass {} starts before the previous one on the GPU",
            p.pass
        );
        last_gpu_start = order[0];
        let gpu: f64 = p.stage_ms.values().sum();
        assert!(
            gpu <= p.wall_ms + 1.0,
            "pass {}: {gpu} ms of GPU stages in {} ms of wall time",
            p.pass,
            p.wall_ms
        );
        assert!(
            p.elapsed_s > last_elapsed,
            "pass {} ends before the previous one",
            p.pass
        );
        last_elapsed = p.elapsed_s;
    }

    let t: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&trace).unwrap()).unwrap();
    let spans = t["traceEvents"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| e["ph"] == "X")
        .count();
    assert!(spans >= 3 * 5, "trace has {spans} spans");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn csv_report_has_a_row_per_pass() {
    let dir = scratch("csv");
    let report = dir.join("run.csv");
    let run = bin()
        .args([
            "render",
            CORNELL,
            "--passes",
            "2",
            "--photons-per-pass",
            "10000",
            "--resolution",
            "16x16",
            "--mode",
            "sppm",
        ])
        .arg("--out")
        .arg(dir.join("img.png"))
        .arg("--report")
        .arg(&report)
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let csv = std::fs::read_to_string(&report).unwrap();
    assert_eq!(csv.lines().count(), 3, "{csv}");
    assert!(csv.starts_with("pass,elapsed_s,wall_ms,photons_total,records,"));
    assert!(
        csv.lines().next().unwrap().contains("ray_ms"),
        "SPPM passes time their eye pass: {csv}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bench_writes_cases_with_stages_and_memory() {
    let dir = scratch("bench");
    let json_path = dir.join("bench.json");
    let run = bin()
        .args([
            "bench",
            "--cases",
            "10k@16x16,20k@32x32",
            "--warmup",
            "1",
            "--passes",
            "3",
            "--mode",
            "ppm",
        ])
        .args([
            "--probe",
            "scale-free",
            "--cone",
            "1.1",
            "--validate",
            "--breakdown",
            "--json",
        ])
        .arg(&json_path)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "bench failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(
        stdout.contains("probe scale-free, cone 1.1"),
        "settings line missing:\n{stdout}"
    );
    let doc: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json_path).unwrap()).unwrap();
    // The JSON names enums as the command line does.
    assert_eq!(
        (doc["mode"].as_str(), doc["probe"].as_str()),
        (Some("ppm"), Some("scale-free"))
    );
    assert_eq!(doc["schema"], "ppm-vk-bench/2");
    let cases = doc["cases"].as_array().unwrap();
    assert_eq!(cases.len(), 2);
    for c in cases {
        for stage in ["photon", "lookup", "gather", "update"] {
            let ms = c["stage_ms_median"][stage].as_f64().unwrap();
            assert!(ms > 0.0 && ms.is_finite(), "{stage}: {ms} ms in {c}");
        }
        assert_eq!(c["pass_wall_ms_all"].as_array().unwrap().len(), 3);
        assert!(c["photons_per_second"].as_f64().unwrap() > 0.0);
        // The photon kernel against its variants: every photon path hits the closed box at least once,
        // every record is left at an intersection, and the trace-only ceiling is the fastest per step.
        let variants = c["photon_breakdown"].as_array().unwrap();
        let names: Vec<&str> = variants.iter().map(|v| v["variant"].as_str().unwrap()).collect();
        assert_eq!(names, ["as rendered", "no record stores", "no append", "trace only"]);
        let steps = |i: usize| variants[i]["intersections"].as_u64().unwrap();
        let photons = c["photons_per_pass"].as_u64().unwrap();
        assert!(
            steps(0) >= photons && steps(0) as f64 >= c["records_per_pass"].as_f64().unwrap(),
            "{variants:?}"
        );
        assert_eq!(
            (steps(1), steps(2)),
            (steps(0), steps(0)),
            "removing the append changed the paths: {variants:?}"
        );
        assert!(steps(3) >= photons, "{variants:?}");
        // Memory is bounded: the passes allocate nothing that outlives them.
        let dev = &c["device_memory"];
        assert!(dev["peak_reserved_bytes"].as_u64().unwrap() >= dev["in_use_bytes_after_measured"].as_u64().unwrap());
        assert_eq!(
            dev["in_use_bytes_after_warmup"], dev["in_use_bytes_after_measured"],
            "device memory grew: {dev}"
        );
        if cfg!(target_os = "linux") {
            let rss = &c["host_rss"];
            let (before, after) = (
                rss["bytes_after_warmup"].as_u64().unwrap(),
                rss["bytes_after_measured"].as_u64().unwrap(),
            );
            // Resident memory may move by allocator noise (a few pages), not by a pass's buffers.
            assert!(
                after <= before + (8 << 20),
                "host RSS grew from {before} to {after} over 3 passes"
            );
        }
        // The set-up split by stage and kernel, and the first warm-up pass.
        let setup = &c["setup"];
        let kernels = setup["kernels"].as_array().unwrap();
        assert!(
            kernels.len() >= 8 && setup["kernels_s"].as_f64().unwrap() > 0.0,
            "{setup}"
        );
        assert!(c["first_pass_wall_ms"].as_f64().unwrap() > 0.0, "{c}");
        // The pilot's marks: every pixel counted, some lit (the test scene's light reaches most of it).
        let marks = &c["pilot_marks"];
        let pixels = c["width"].as_u64().unwrap() * c["height"].as_u64().unwrap();
        assert_eq!(marks["pixels"].as_u64(), Some(pixels), "{marks}");
        assert!(marks["lit"].as_u64().unwrap() > 0, "{marks}");
    }
    // The second case compiles nothing: the first left every kernel compiled for the scene in the cache.
    let second = cases[1]["setup"]["kernels"].as_array().unwrap();
    let compiled: Vec<_> = second.iter().filter(|k| !k["spirv_cached"].is_null()).collect();
    assert!(
        !compiled.is_empty() && compiled.iter().all(|k| k["spirv_cached"] == true),
        "{second:?}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// Runs the binary expecting failure; returns stderr.
fn fails(args: &[&str]) -> String {
    let run = bin().args(args).output().unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr).to_string();
    assert!(!run.status.success(), "{args:?} should fail");
    assert!(!stderr.contains("panicked"), "{args:?} panicked:\n{stderr}");
    stderr
}

#[test]
fn bad_input_is_a_clear_error() {
    let e = fails(&["render", "no/such/scene.toml", "--out", "x.png"]);
    assert!(e.contains("no/such/scene.toml"), "{e}");
    let e = fails(&["render", CORNELL, "--out", "x.jpg"]);
    assert!(e.contains("x.jpg") && e.contains(".exr"), "{e}");
    let e = fails(&["render", CORNELL, "--cone", "0.5"]);
    assert!(e.contains("cone"), "{e}");
    let e = fails(&["render", CORNELL, "--alpha", "1.5", "--out", "/tmp/ppm-vk-never.png"]);
    assert!(e.contains("alpha"), "{e}");
    let e = fails(&["render", CORNELL, "--time=-3"]);
    assert!(e.contains("--time"), "{e}");
    let e = fails(&["render", CORNELL, "--region", "a:1,2,3"]);
    assert!(e.contains("NAME:X0,Y0,W,H"), "{e}");
    let e = fails(&["render", CORNELL, "--resolution", "0x10"]);
    assert!(e.contains("resolution"), "{e}");
    let e = fails(&[
        "render",
        CORNELL,
        "--report",
        "/tmp/r.txt",
        "--passes",
        "1",
        "--photons-per-pass",
        "1000",
        "--resolution",
        "8x8",
        "--out",
        "/tmp/ppm-vk-never.png",
    ]);
    assert!(e.contains(".json or .csv"), "{e}");
}

/// Paths ended at a depth backstop are a warning once they are more than a rounding accident: a camera
/// between two parallel perfect mirrors (its centre pixel looks along the corridor for ever) gets one,
/// and the run report counts the cut paths; cornell-spheres gets none.
#[test]
fn render_warns_when_light_is_trapped() {
    let dir = scratch("trapped");
    let scene = dir.join("corridor.toml");
    std::fs::write(
        &scene,
        "[camera]\neye = [0.0, 0.0, 0.0]\nlook_at = [0.0, 0.0, -1.0]\nup = [0.0, 1.0, 0.0]\nvfov = 40.0\n\
         resolution = [9, 9]\n[materials.mirror]\nmirror = [1.0, 1.0, 1.0]\n[materials.light]\nemission = [5.0, 5.0, 5.0]\n\
         [[quad]]\norigin = [-5.0, -5.0, -1.0]\nedge_u = [10.0, 0.0, 0.0]\nedge_v = [0.0, 10.0, 0.0]\nmaterial = \"mirror\"\n\
         [[quad]]\norigin = [-5.0, -5.0, 1.0]\nedge_u = [0.0, 10.0, 0.0]\nedge_v = [10.0, 0.0, 0.0]\nmaterial = \"mirror\"\n\
         [[quad]]\norigin = [-0.2, 0.9, -0.2]\nedge_u = [0.4, 0.0, 0.0]\nedge_v = [0.0, 0.0, 0.4]\nmaterial = \"light\"\n",
    )
    .unwrap();
    let report = dir.join("run.json");
    let run = bin()
        .args([
            "render",
            "--passes",
            "1",
            "--photons-per-pass",
            "10000",
            "--mode",
            "ppm",
            "--emission-samples",
            "0",
            "--out",
        ])
        .arg(dir.join("img.exr"))
        .arg("--report")
        .arg(&report)
        .arg(&scene)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(
        stderr.contains("warning:") && stderr.contains("specular bounces"),
        "{stderr}"
    );
    let report: RunReport = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    assert!(report.passes[0].eye_paths_cut >= 1);
    let quiet = bin()
        .args([
            "render",
            CORNELL,
            "--passes",
            "2",
            "--photons-per-pass",
            "20000",
            "--resolution",
            "32x32",
            "--out",
        ])
        .arg(dir.join("cornell.png"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&quiet.stderr);
    assert!(quiet.status.success() && !stderr.contains("warning:"), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--checkpoint` + `--resume` from the command line: 2 passes, then resumed to 4, give the file of 4
/// uninterrupted passes byte for byte; the same command with another setting is refused naming it; the
/// old `--checkpoint SECONDS` says what replaced it.
#[test]
fn resume_continues_a_render_from_its_checkpoint() {
    let dir = scratch("resume");
    let (whole, resumed, ckpt) = (dir.join("whole.exr"), dir.join("resumed.exr"), dir.join("state.ckpt"));
    let render = |passes: &str, out: &PathBuf, extra: &[&std::ffi::OsStr]| {
        let run = bin()
            .args([
                "render",
                CORNELL,
                "--mode",
                "ppm",
                "--probe",
                "scale-free",
                "--passes",
                passes,
            ])
            .args([
                "--photons-per-pass",
                "10000",
                "--resolution",
                "32x32",
                "--validate",
                "--out",
            ])
            .arg(out)
            .args(extra)
            .output()
            .unwrap();
        (run.status.success(), String::from_utf8_lossy(&run.stderr).to_string())
    };
    let (ok, e) = render("4", &whole, &[]);
    assert!(ok, "{e}");
    let (ok, e) = render("2", &resumed, &["--checkpoint".as_ref(), ckpt.as_os_str()]);
    assert!(ok && ckpt.exists(), "{e}");
    let (ok, e) = render("4", &resumed, &["--resume".as_ref(), ckpt.as_os_str()]);
    assert!(ok && e.contains("resumed after pass 2"), "{e}");
    assert!(
        std::fs::read(&whole).unwrap() == std::fs::read(&resumed).unwrap(),
        "the resumed image differs"
    );
    let (ok, e) = render(
        "4",
        &resumed,
        &[
            "--resume".as_ref(),
            ckpt.as_os_str(),
            "--alpha".as_ref(),
            "0.5".as_ref(),
        ],
    );
    assert!(
        !ok && e.contains("other settings") && e.contains("alpha: 0.7 in the checkpoint, 0.5 now"),
        "{e}"
    );
    let e = fails(&["render", CORNELL, "--checkpoint", "60"]);
    assert!(e.contains("--checkpoint-every 60"), "{e}");
}

/// Starts a render and returns it with its stderr, line by line, once a line contains `ready`.
fn spawn_until(
    args: &[&str],
    dir: &std::path::Path,
    ready: &str,
) -> (std::process::Child, std::sync::mpsc::Receiver<String>) {
    use std::io::BufRead;
    let mut child = bin()
        .args([
            "render",
            CORNELL,
            "--photons-per-pass",
            "10000",
            "--passes",
            "100000000",
        ])
        .args(args)
        .current_dir(dir)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let (send, lines) = std::sync::mpsc::channel();
    let stderr = std::io::BufReader::new(child.stderr.take().unwrap());
    std::thread::spawn(move || stderr.lines().map_while(Result::ok).for_each(|l| drop(send.send(l))));
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(120);
    loop {
        let line = lines.recv_timeout(deadline.saturating_duration_since(std::time::Instant::now()));
        match line {
            Ok(l) if l.contains(ready) => return (child, lines),
            Ok(_) => {}
            Err(e) => panic!("no line with {ready:?} from the render: {e}"),
        }
    }
}

fn signal(child: &std::process::Child, sig: i32) {
    // SAFETY: kill(2) on our own child's pid.
    assert_eq!(unsafe { libc::kill(child.id() as i32, sig) }, 0);
}

/// The rest of a child's stderr, after it exited.
fn rest(lines: std::sync::mpsc::Receiver<String>) -> String {
    lines.iter().collect::<Vec<_>>().join("\n")
}

/// SIGTERM in the middle of a render: the pass in flight ends, the image, the report and the checkpoint
/// are written, all of the same passes, and the exit status is 143 (128 + SIGTERM).
#[test]
fn sigterm_finishes_the_pass_and_writes_everything() {
    let dir = scratch("sigterm");
    let args = [
        "--resolution",
        "32x32",
        "--out",
        "img.exr",
        "--report",
        "run.json",
        "--checkpoint",
        "state.ckpt",
    ];
    let (mut child, lines) = spawn_until(
        &[&args[..], &["--checkpoint-every", "0.001"]].concat(),
        &dir,
        "scene cornell-spheres",
    );
    // The checkpoint appears after the first pass: the render is under way.
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(120);
    while !dir.join("state.ckpt").exists() {
        assert!(std::time::Instant::now() < deadline, "no checkpoint after 120 s");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    signal(&child, libc::SIGTERM);
    let status = child.wait().unwrap();
    let stderr = rest(lines);
    assert_eq!(status.code(), Some(143), "{stderr}");
    assert!(stderr.contains("interrupted by signal 15"), "{stderr}");
    let report = RunReport::load_json(&dir.join("run.json")).unwrap();
    let passes = report.passes.last().expect("a pass in the report").pass;
    let checkpoint = ppm_vk_engine::Checkpoint::load(&dir.join("state.ckpt")).unwrap();
    assert_eq!(
        checkpoint.header.passes, passes,
        "the checkpoint and the report tell different passes"
    );
    assert!(dir.join("img.exr").exists());
}

/// Set-up at 512x512 with the probe takes seconds on lavapipe; a SIGINT during it stops the render
/// before its first pass, writing nothing (no 0-pass image), with status 130. A second SIGINT exits at
/// once, without waiting for the set-up to end.
#[test]
fn signals_during_set_up_write_nothing() {
    for second in [false, true] {
        let dir = scratch(&format!("sigint-{second}"));
        let args = [
            "--resolution",
            "512x512",
            "--probe",
            "scale-free",
            "--out",
            "img.exr",
            "--report",
            "run.json",
        ];
        let (mut child, lines) = spawn_until(&args, &dir, "device:");
        signal(&child, libc::SIGINT);
        if second {
            std::thread::sleep(std::time::Duration::from_millis(100));
            signal(&child, libc::SIGINT);
        }
        let status = child.wait().unwrap();
        let stderr = rest(lines);
        assert_eq!(status.code(), Some(130), "{stderr}");
        assert!(
            !dir.join("img.exr").exists() && !dir.join("run.json").exists(),
            "wrote output:\n{stderr}"
        );
        // The first signal alone waits for the set-up and says so; the second does not wait.
        assert_eq!(
            stderr.contains("interrupted during set-up"),
            !second,
            "second signal: {second}\n{stderr}"
        );
    }
}

/// Limits are checked before any pass: an image whose hit points exceed the device's largest buffer
/// (lavapipe: 128 MiB, 48 bytes a hit point: 4096x4096 needs 768 MiB a slot, 4 slots a pixel where
/// cornell-spheres' glass splits) says what to lower and writes nothing; an unknown device lists the ones
/// there are.
#[test]
fn device_limits_are_checked_before_work() {
    let dir = scratch("limits");
    let out = dir.join("never.exr");
    let out = out.to_str().unwrap();
    let e = fails(&[
        "render",
        CORNELL,
        "--resolution",
        "4096x4096",
        "--passes",
        "1",
        "--out",
        out,
    ]);
    // lavapipe's 2048 MiB: per-pixel buffers are bound in tiles (any of them may pass one binding), but
    // all of them must fit the device's memory.
    assert!(
        e.contains("the render's device memory (")
            && e.contains("the hit points 3072 MiB")
            && e.contains("lower the resolution (4096x4096) or the hit points per pixel (4, --glass-splits)"),
        "{e}"
    );
    assert!(!dir.join("never.exr").exists());
    let e = fails(&["render", CORNELL, "--device", "nosuch", "--out", out]);
    assert!(e.contains("no Vulkan device matches \"nosuch\"; devices:"), "{e}");
    let e = fails(&["render", CORNELL, "--photons-per-pass", "0", "--out", out]);
    assert!(e.contains("--photons-per-pass"), "{e}");
    let e = fails(&["render", CORNELL, "--beta", "1", "--out", out]);
    assert!(e.contains("must be in (0, 1)"), "{e}");
}

#[test]
fn render_names_its_output_after_the_scene_and_never_overwrites_silently() {
    let dir = scratch("default-out");
    let run = || {
        let mut c = bin();
        c.current_dir(&dir).args([
            "render",
            CORNELL,
            "--passes",
            "1",
            "--photons-per-pass",
            "2000",
            "--resolution",
            "8x8",
        ]);
        c
    };
    let first = run().output().unwrap();
    assert!(first.status.success(), "{}", String::from_utf8_lossy(&first.stderr));
    let (exr, png) = (dir.join("cornell-spheres.exr"), dir.join("cornell-spheres.png"));
    assert!(
        exr.exists() && png.exists(),
        "the scene's name, .exr and a .png preview"
    );
    let written = std::fs::read(&exr).unwrap();
    // Again: refused before rendering, the file untouched.
    let second = run().output().unwrap();
    let stderr = String::from_utf8_lossy(&second.stderr);
    assert!(
        !second.status.success() && stderr.contains("exists") && stderr.contains("--force"),
        "{stderr}"
    );
    assert_eq!(std::fs::read(&exr).unwrap(), written);
    // With --force it overwrites.
    let third = run().arg("--force").output().unwrap();
    assert!(third.status.success(), "{}", String::from_utf8_lossy(&third.stderr));
}

/// `render` saves the pipeline cache, and the SPIR-V of the kernels it compiled for the scene, where
/// PPM_VK_CACHE_DIR says (the next run reads it without a note), `--no-pipeline-cache` keeps none, and a
/// damaged cache file is a note, never an error.
#[test]
fn render_keeps_the_pipeline_cache_where_asked() {
    let dir = scratch("pipeline-cache");
    let cache = dir.join("cache");
    let render = |extra: &[&str]| {
        let run = bin()
            .env("PPM_VK_CACHE_DIR", &cache)
            .args([
                "render",
                CORNELL,
                "--passes",
                "1",
                "--photons-per-pass",
                "1000",
                "--resolution",
                "8x8",
                "--force",
            ])
            .arg("--out")
            .arg(dir.join("img.exr"))
            .args(extra)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&run.stderr).into_owned();
        assert!(run.status.success(), "render {extra:?} failed:\n{stderr}");
        stderr
    };
    let entries = |dir: &Path| {
        std::fs::read_dir(dir)
            .map(|d| d.map(|e| e.unwrap().path()).collect::<Vec<_>>())
            .unwrap_or_default()
    };
    let files = || entries(&cache).into_iter().filter(|p| p.is_file()).collect::<Vec<_>>();

    render(&["--no-pipeline-cache"]);
    assert!(
        entries(&cache).is_empty(),
        "--no-pipeline-cache wrote {:?}",
        entries(&cache)
    );
    let first = render(&["--validate"]);
    assert!(!first.contains("pipeline cache"), "{first}");
    assert!(
        !entries(&cache.join("spirv")).is_empty(),
        "no compiled kernel was cached"
    );
    let written = files();
    assert_eq!(written.len(), 1, "{written:?}");
    assert!(
        std::fs::metadata(&written[0]).unwrap().len() > 28,
        "an empty cache file"
    );
    assert!(
        !render(&[]).contains("pipeline cache"),
        "the second run did not take the first run's cache"
    );

    std::fs::write(&written[0], b"not a cache").unwrap();
    let damaged = render(&["--validate"]);
    assert!(
        damaged.contains("note: pipeline cache") && damaged.contains("ignored"),
        "{damaged}"
    );
    assert!(
        !render(&[]).contains("pipeline cache"),
        "the damaged file was not replaced"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `compare` end to end on a tiny render: the table, the JSON (typed, schema ppm-vk-compare/1) and the
/// plot, an SVG with log-scale tick labels, one line per variant and the peer's points.
#[test]
fn compare_writes_table_json_and_a_readable_plot() {
    let dir = scratch("compare");
    let peer = dir.join("peer.csv");
    std::fs::write(&peer, "# seconds,rel_mse,label\n0.5,0.2,other\n2,0.05,other\n").unwrap();
    let run = bin()
        .args([
            "compare",
            CORNELL,
            "--reference",
            CORNELL_REFERENCE,
            "--time",
            "0.5",
            "--resolution",
            "16x16",
        ])
        .args([
            "--photons-per-pass",
            "5000",
            "--variants",
            "ppm; sppm+alpha=0.7",
            "--validate",
            "--peer",
        ])
        .arg(&peer)
        .arg("--out")
        .arg(&dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "compare failed:\n{stderr}");
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("compare.json")).unwrap()).unwrap();
    assert_eq!(doc["schema"], "ppm-vk-compare/1");
    let variants = doc["variants"].as_array().unwrap();
    assert_eq!(
        variants
            .iter()
            .map(|v| v["variant"].as_str().unwrap())
            .collect::<Vec<_>>(),
        ["ppm", "sppm+alpha=0.7"]
    );
    // Each variant's image, named after it whole (a dot in a number does not start its extension).
    for name in ["ppm", "sppm_alpha_0.7"] {
        for ext in ["exr", "png"] {
            assert!(dir.join(format!("{name}.{ext}")).is_file(), "no {name}.{ext}");
        }
    }
    for v in variants {
        // Equal time: each variant's clock (set-up excluded) reaches --time and stops after one more pass.
        let (wall, setup) = (v["wall_s"].as_f64().unwrap(), v["setup_s"].as_f64().unwrap());
        assert!(wall >= 0.5 && setup > 0.0, "{v}");
        assert!(
            v["passes"].as_u64().unwrap() >= 1 && v["whole"]["rel_mse"].as_f64().unwrap() > 0.0,
            "{v}"
        );
        // The scene file's regions are scored.
        assert!(v["regions"]["caustic"]["pixels"].as_u64().unwrap() > 0, "{v}");
        assert!(!v["rel_mse_curve"].as_array().unwrap().is_empty(), "{v}");
    }
    let table = std::fs::read_to_string(dir.join("compare.md")).unwrap();
    assert!(
        table.contains("| ppm |") && table.contains("| sppm+alpha=0.7 |") && table.contains("caustic relMSE"),
        "{table}"
    );

    let svg = std::fs::read_to_string(dir.join("error-vs-time.svg")).unwrap();
    let texts: Vec<&str> = svg
        .split("<text")
        .skip(1)
        .map(|t| t.split_once('>').unwrap().1.split("</text>").next().unwrap().trim())
        .collect();
    // Tick labels on the log time axis (0.5 s to 2 s: 0.5, 1, 2) and on the error axis (from the peer's 0.2).
    for label in ["0.5", "1", "2", "0.2"] {
        assert!(texts.contains(&label), "no tick label {label} in {texts:?}");
    }
    for label in ["ppm", "sppm+alpha=0.7", "other"] {
        assert!(texts.contains(&label), "no legend entry {label} in {texts:?}");
    }
    // One polyline per variant (the axes and ticks are 1 px wide, the variants' lines 2 px).
    let lines = svg
        .split("<polyline")
        .skip(1)
        .filter(|p| p.split_once("/>").unwrap().0.contains("stroke-width=\"2\""))
        .count();
    assert_eq!(lines, 2, "{svg}");
    // The peer's two points and its legend marker are triangles.
    assert_eq!(svg.matches("<polygon").count(), 3, "{svg}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Every subcommand has --version and says what each of its options does; sizes out of range are refused
/// by the parser, naming the bound.
#[test]
fn every_option_has_help_and_sizes_are_checked() {
    for cmd in ["render", "devices", "bench", "compare"] {
        let run = bin().args([cmd, "--help"]).output().unwrap();
        assert!(run.status.success(), "{cmd} --help failed");
        let help = String::from_utf8_lossy(&run.stdout).to_string();
        let lines: Vec<&str> = help.lines().collect();
        let mut options = 0;
        for (i, line) in lines.iter().enumerate() {
            let trimmed = line.trim_start();
            // An option starts with - or --; "- name: ..." is an item of clap's "Possible values" list.
            if !trimmed.starts_with('-') || trimmed.starts_with("- ") {
                continue;
            }
            options += 1;
            // Help text on the same line (after two spaces) or on the next, indented deeper.
            let indent = line.len() - trimmed.len();
            let same_line = trimmed
                .split_once("  ")
                .is_some_and(|(_, rest)| !rest.trim().is_empty());
            let next = lines.get(i + 1).copied().unwrap_or("");
            let next_line = next.len() - next.trim_start().len() > indent && !next.trim().is_empty();
            assert!(same_line || next_line, "{cmd}: option without help: {line:?}\n{help}");
        }
        assert!(options >= 2, "{cmd}: no options found in\n{help}");
        let version = bin().args([cmd, "--version"]).output().unwrap();
        assert!(
            version.status.success() && String::from_utf8_lossy(&version.stdout).starts_with("ppm-vk"),
            "{cmd} --version"
        );
    }
    let e = fails(&["bench", "--cases", "10k@16x16384,10k@16x16385"]);
    assert!(e.contains("16x16385") && e.contains("1..=16384"), "{e}");
    let e = fails(&["bench", "--cases", "10k@16"]);
    assert!(e.contains("WIDTHxHEIGHT"), "{e}");
    let e = fails(&[
        "compare",
        CORNELL,
        "--reference",
        CORNELL_REFERENCE,
        "--resolution",
        "16385x16",
    ]);
    assert!(e.contains("1..=16384"), "{e}");
    let e = fails(&["render", CORNELL, "--resolution", "16x0"]);
    assert!(e.contains("1..=16384"), "{e}");
    let peer = scratch("bad-peer").join("peer.csv");
    std::fs::write(&peer, "# s,e\n10,0.1\n30,-2\n").unwrap();
    let e = fails(&[
        "compare",
        CORNELL,
        "--reference",
        CORNELL_REFERENCE,
        "--peer",
        peer.to_str().unwrap(),
    ]);
    assert!(e.contains("peer.csv:3") && e.contains("positive"), "{e}");
    std::fs::remove_dir_all(peer.parent().unwrap()).ok();
}

/// Runs the binary with `args` in `dir` under a 2 GiB address-space limit, expecting it to fail within
/// `secs` seconds (it is killed and the test fails otherwise); returns its stderr.
fn fails_within(args: &[&str], dir: &std::path::Path, secs: u64) -> String {
    use std::io::Read as _;
    use std::os::unix::process::CommandExt as _;
    let mut cmd = bin();
    cmd.args(args)
        .current_dir(dir)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped());
    // SAFETY: setrlimit is async-signal-safe; the closure allocates nothing.
    unsafe {
        cmd.pre_exec(|| {
            let limit = libc::rlimit {
                rlim_cur: 2 << 30,
                rlim_max: 2 << 30,
            };
            match libc::setrlimit(libc::RLIMIT_AS, &limit) {
                0 => Ok(()),
                _ => Err(std::io::Error::last_os_error()),
            }
        });
    }
    let mut child = cmd.spawn().unwrap();
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(secs);
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if std::time::Instant::now() > deadline {
            child.kill().ok();
            child.wait().ok();
            panic!("{args:?} did not end within {secs} s");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    };
    let mut stderr = String::new();
    child.stderr.take().unwrap().read_to_string(&mut stderr).unwrap();
    assert!(!status.success(), "{args:?} should fail");
    assert!(!stderr.contains("panicked"), "{args:?} panicked:\n{stderr}");
    stderr
}

/// A FIFO at `path`, which no writer opens.
fn mkfifo(path: &std::path::Path) {
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

/// A scene whose floor is textured with `texture` (a path relative to the scene), in `dir`.
fn textured_scene(dir: &std::path::Path, texture: &str) -> PathBuf {
    let text = std::fs::read_to_string(CORNELL).unwrap().replacen(
        "[materials.white]\ndiffuse = [0.725, 0.71, 0.68]",
        &format!("[materials.white]\ndiffuse = {{ texture = \"{texture}\" }}"),
        1,
    );
    assert!(text.contains(texture), "the white material was not found");
    let path = dir.join("textured.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// A FIFO or a device given as a texture, `--resume` or `--reference` ends the render within 10 s, under a 2 GiB
/// address-space limit, with an error naming it (the FIFO blocked in open() for ever, SIGINT and SIGTERM
/// could not end it; `--resume /dev/zero` read until memory ran out); `--photons-per-pass 2147483648`
/// (a pass of days that no signal ended) is refused, saying the limit.
#[test]
fn fifos_devices_and_endless_passes_are_refused_at_once() {
    let dir = scratch("fifos");
    let fifo = dir.join("fifo");
    mkfifo(&fifo);
    let scene = textured_scene(&dir, "fifo");
    let scene = scene.to_str().unwrap();
    let e = fails_within(&["render", scene, "--out", "x.exr"], &dir, 10);
    assert!(e.contains("fifo") && e.contains("not a regular file"), "{e}");
    for (flag, file) in [("--resume", "fifo"), ("--resume", "/dev/zero"), ("--reference", "fifo")] {
        let e = fails_within(&["render", CORNELL, flag, file, "--out", "x.exr"], &dir, 10);
        assert!(
            e.contains(file) && e.contains("not a regular file"),
            "{flag} {file}: {e}"
        );
    }
    let e = fails_within(&["render", CORNELL, "--photons-per-pass", "2147483648"], &dir, 10);
    assert!(e.contains("--photons-per-pass") && e.contains("16777216"), "{e}");
    assert!(!dir.join("x.exr").exists());
}

/// A checkpoint whose header was edited (`"passes": 18446744073709551615` resumed "after pass
/// 18446744073709551615" and rendered another image) is refused: the checksum covers the header.
#[test]
fn an_edited_checkpoint_header_is_refused() {
    let dir = scratch("edited-ckpt");
    let base = [
        "--resolution",
        "8x8",
        "--photons-per-pass",
        "1000",
        "--out",
        "img.exr",
        "--force",
    ];
    let run = bin()
        .args(["render", CORNELL, "--passes", "1", "--checkpoint", "state.ckpt"])
        .args(base)
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let mut bytes = std::fs::read(dir.join("state.ckpt")).unwrap();
    let at = bytes
        .windows(10)
        .position(|w| w == b"\"passes\":1")
        .expect("the header's passes");
    bytes.splice(at + 9..at + 10, *b"18446744073709551615");
    // The header's length as the editor would fix it (19 bytes more), so the header still parses.
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) + 19;
    bytes[12..16].copy_from_slice(&len.to_le_bytes());
    std::fs::write(dir.join("edited.ckpt"), &bytes).unwrap();
    let args = [
        &["render", CORNELL, "--passes", "2", "--resume", "edited.ckpt"][..],
        &base,
    ]
    .concat();
    let e = fails_within(&args, &dir, 30);
    assert!(
        e.contains("edited.ckpt") && e.contains("passes 18446744073709551615 is more than a render may have"),
        "{e}"
    );
    // The same edit within the counters' range (1 pass to 2, and its photons) is caught by the checksum.
    let mut bytes = std::fs::read(dir.join("state.ckpt")).unwrap();
    let at = bytes.windows(10).position(|w| w == b"\"passes\":1").unwrap();
    bytes[at + 9] = b'2';
    let at = bytes
        .windows(15)
        .position(|w| w == b"\"emitted\":1000,")
        .expect("the header's photons");
    bytes[at + 10] = b'2';
    std::fs::write(dir.join("edited.ckpt"), &bytes).unwrap();
    let e = fails_within(&args, &dir, 30);
    assert!(e.contains("edited.ckpt") && e.contains("checksum"), "{e}");
}

/// SIGTERM ends a long pass within seconds: a pass of 2^24 photons at 128x128 (about 50 s on a
/// two-core lavapipe, in one submission before) is cancelled between its batches of 2^20 photons; the
/// render exits 143 without writing a 0-pass image.
#[test]
fn sigterm_ends_a_long_pass_within_seconds() {
    use std::io::BufRead as _;
    let dir = scratch("long-pass");
    let mut child = bin()
        .args([
            "render",
            CORNELL,
            "--resolution",
            "128x128",
            "--photons-per-pass",
            "16777216",
        ])
        .args(["--passes", "1000", "--out", "img.exr"])
        .current_dir(&dir)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut stderr = std::io::BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    // The set-up ends with the scene line; the first pass starts right after it.
    while !line.starts_with("scene ") {
        line.clear();
        assert!(
            stderr.read_line(&mut line).unwrap() > 0,
            "the render ended before its scene line"
        );
    }
    std::thread::sleep(std::time::Duration::from_millis(1500));
    let sent = std::time::Instant::now();
    signal(&child, libc::SIGTERM);
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if sent.elapsed() > std::time::Duration::from_secs(20) {
            child.kill().ok();
            panic!("SIGTERM did not end the pass within 20 s");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    };
    let elapsed = sent.elapsed();
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut stderr, &mut rest).unwrap();
    assert_eq!(status.code(), Some(143), "{rest}");
    assert!(
        rest.contains("nothing written") && !dir.join("img.exr").exists(),
        "{rest}"
    );
    println!("SIGTERM ended the pass after {elapsed:?}");
}

/// A camera that sees nothing lit renders an image of zeros: it is written (it is what the scene gives),
/// with a warning saying so; cornell-spheres gets none.
#[test]
fn a_black_image_is_warned_about() {
    let dir = scratch("black");
    let away = std::fs::read_to_string(CORNELL)
        .unwrap()
        .replace("eye = [0.0, 1.0, 2.9]", "eye = [0.0, 1.0, 10.0]")
        .replace("look_at = [0.0, 0.8, 0.0]", "look_at = [0.0, 1.0, 20.0]");
    std::fs::write(dir.join("away.toml"), away).unwrap();
    let warned = |scene: &str| {
        let run = bin()
            .args([
                "render",
                scene,
                "--resolution",
                "8x8",
                "--passes",
                "1",
                "--photons-per-pass",
                "1000",
            ])
            .args(["--out", "img.exr", "--force"])
            .current_dir(&dir)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&run.stderr).to_string();
        assert!(run.status.success(), "{stderr}");
        stderr.contains("warning: every pixel is 0 after 1 passes: the camera sees nothing lit")
    };
    assert!(warned("away.toml"));
    assert!(!warned(CORNELL));
}

/// A texture larger than the device's storage buffer is named as the cause, not "the resolution or
/// photons per pass": a 3000 x 3000 image (144 MB of texels; lavapipe binds 128 MiB). A device that
/// binds it renders.
#[test]
fn a_texture_too_large_for_the_device_is_named() {
    let dir = scratch("big-texture");
    image::RgbImage::from_pixel(3000, 3000, image::Rgb([128, 128, 128]))
        .save(dir.join("big.png"))
        .unwrap();
    let scene = textured_scene(&dir, "big.png");
    let run = bin()
        .args([
            "render",
            scene.to_str().unwrap(),
            "--resolution",
            "8x8",
            "--passes",
            "1",
        ])
        .args(["--photons-per-pass", "1000", "--out", "img.exr"])
        .current_dir(&dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!stderr.contains("photons per pass"), "{stderr}");
    if !run.status.success() {
        assert!(
            stderr.contains("the textures") && stderr.contains("big.png\", has 9000000 pixels"),
            "{stderr}"
        );
    }
}

/// `check` reads scenes without a device: a line saying what each holds, its warnings under it, and
/// for a file it cannot read the reader's located error and a failing exit.
#[test]
fn check_reads_scenes_and_names_what_it_cannot() {
    let dir = scratch("check");
    let bad = dir.join("bad.xml");
    std::fs::write(
        &bad,
        "<scene version=\"3.0.0\">\n  <shape type=\"teapot\"/>\n</scene>\n",
    )
    .unwrap();
    let run = bin().args(["check", CORNELL]).output().unwrap();
    let out = String::from_utf8_lossy(&run.stdout).to_string();
    assert!(run.status.success(), "{out}");
    assert!(out.starts_with("ok: ") && out.contains("3 spheres, 7 quads"), "{out}");

    let run = bin().args(["check", CORNELL, bad.to_str().unwrap()]).output().unwrap();
    let out = String::from_utf8_lossy(&run.stdout).to_string();
    let err = String::from_utf8_lossy(&run.stderr).to_string();
    assert!(!run.status.success());
    assert!(out.contains("bad.xml:2:3: <shape type=\"teapot\">"), "{out}");
    assert!(err.contains("1 of 2 scene file(s) could not be read"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}
