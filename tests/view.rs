//! `ppm-vk view` in a real window: each test starts its own X server (Xvfb, which scripts/setup.sh
//! installs) and drives the window through the server's XTEST extension, as a user's mouse and keyboard
//! would. The viewer runs under the validation layer (`--validate`): any message fails its exit.

mod common;

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::time::{Duration, Instant};

use ppm_vk_engine::RgbImage;
use x11rb::connection::Connection;
use x11rb::protocol::xproto::{self, ConnectionExt as _};
use x11rb::protocol::xtest::ConnectionExt as _;
use x11rb::rust_connection::RustConnection;

/// Long enough for a cold kernel compilation on lavapipe and a few small passes.
const PATIENCE: Duration = Duration::from_secs(240);

/// A private X server, killed when dropped.
struct Xvfb {
    child: Child,
    display: String,
}

impl Xvfb {
    fn start() -> Xvfb {
        // -displayfd: the server picks a free display and writes its number, so tests can run side by side.
        let mut child = Command::new("Xvfb")
            .args([
                "-displayfd",
                "1",
                "-screen",
                "0",
                "1024x768x24",
                "-nolisten",
                "tcp",
                "-noreset",
            ])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("starting Xvfb (scripts/setup.sh installs the xvfb package)");
        let mut line = String::new();
        BufReader::new(child.stdout.take().unwrap())
            .read_line(&mut line)
            .unwrap();
        let n: u32 = line
            .trim()
            .parse()
            .unwrap_or_else(|_| panic!("Xvfb printed {line:?}, not a display"));
        Xvfb {
            child,
            display: format!(":{n}"),
        }
    }

    fn connect(&self) -> X {
        let (conn, screen) = x11rb::connect(Some(&self.display)).expect("connecting to Xvfb");
        let root = conn.setup().roots[screen].root;
        X { conn, root }
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A client of the test's X server that finds the viewer's window and sends it input.
struct X {
    conn: RustConnection,
    root: xproto::Window,
}

impl X {
    /// The top-level window whose title starts with "ppm-vk view".
    fn viewer(&self) -> xproto::Window {
        let deadline = Instant::now() + PATIENCE;
        loop {
            let tree = self.conn.query_tree(self.root).unwrap().reply().unwrap();
            for w in tree.children {
                let name = self
                    .conn
                    .get_property(false, w, xproto::AtomEnum::WM_NAME, xproto::AtomEnum::ANY, 0, 256)
                    .unwrap()
                    .reply()
                    .unwrap();
                if name.value.starts_with(b"ppm-vk view") {
                    return w;
                }
            }
            assert!(Instant::now() < deadline, "no viewer window appeared");
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    /// The window's top-left corner on the screen.
    fn origin(&self, w: xproto::Window) -> (i16, i16) {
        let t = self
            .conn
            .translate_coordinates(w, self.root, 0, 0)
            .unwrap()
            .reply()
            .unwrap();
        (t.dst_x, t.dst_y)
    }

    fn fake(&self, kind: u8, detail: u8, x: i16, y: i16) {
        self.conn.xtest_fake_input(kind, detail, 0, self.root, x, y, 0).unwrap();
        self.conn.flush().unwrap();
        // The server applies fake input in order; a pause lets the viewer see each event on its own.
        std::thread::sleep(Duration::from_millis(30));
    }

    /// Presses `button` at window point `from`, moves to `to` in one motion, releases.
    fn drag(&self, w: xproto::Window, button: u8, from: (i16, i16), to: (i16, i16)) {
        let (ox, oy) = self.origin(w);
        self.fake(xproto::MOTION_NOTIFY_EVENT, 0, ox + from.0, oy + from.1);
        self.fake(xproto::BUTTON_PRESS_EVENT, button, 0, 0);
        self.fake(xproto::MOTION_NOTIFY_EVENT, 0, ox + to.0, oy + to.1);
        self.fake(xproto::BUTTON_RELEASE_EVENT, button, 0, 0);
    }

    /// Types the key whose unshifted keysym is `c` (ASCII letters' keysyms are their codes).
    fn key(&self, w: xproto::Window, c: char) {
        let setup = self.conn.setup();
        let (min, max) = (setup.min_keycode, setup.max_keycode);
        let map = self
            .conn
            .get_keyboard_mapping(min, max - min + 1)
            .unwrap()
            .reply()
            .unwrap();
        let per = map.keysyms_per_keycode as usize;
        let index = map.keysyms.chunks(per).position(|syms| syms[0] == c as u32);
        let code = min + index.unwrap_or_else(|| panic!("no keycode types {c:?}")) as u8;
        // No window manager gives the window the focus: the test does, as a click would.
        self.conn
            .set_input_focus(xproto::InputFocus::PARENT, w, x11rb::CURRENT_TIME)
            .unwrap();
        self.fake(xproto::KEY_PRESS_EVENT, code, 0, 0);
        self.fake(xproto::KEY_RELEASE_EVENT, code, 0, 0);
    }

    /// What a window manager's close button sends: WM_DELETE_WINDOW.
    fn close(&self, w: xproto::Window) {
        let atom = |name: &[u8]| self.conn.intern_atom(false, name).unwrap().reply().unwrap().atom;
        let (protocols, delete) = (atom(b"WM_PROTOCOLS"), atom(b"WM_DELETE_WINDOW"));
        let event = xproto::ClientMessageEvent::new(32, w, protocols, [delete, 0, 0, 0, 0]);
        self.conn
            .send_event(false, w, xproto::EventMask::NO_EVENT, event)
            .unwrap();
        self.conn.flush().unwrap();
    }

    fn resize(&self, w: xproto::Window, width: u32, height: u32) {
        let aux = xproto::ConfigureWindowAux::new().width(width).height(height);
        self.conn.configure_window(w, &aux).unwrap();
        self.conn.flush().unwrap();
    }
}

/// A running viewer with its output read line by line.
struct Viewer {
    child: Child,
    lines: Receiver<(bool, String)>,
    /// Every line so far: (from stdout, text).
    seen: Vec<(bool, String)>,
}

impl Viewer {
    fn start(x: &Xvfb, args: &[&str]) -> Viewer {
        let mut child = common::bin()
            .arg("view")
            .args(args)
            .arg("--validate")
            .env("DISPLAY", &x.display)
            .env_remove("WAYLAND_DISPLAY")
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("starting ppm-vk view");
        let (tx, lines) = std::sync::mpsc::channel();
        let out = child.stdout.take().unwrap();
        let err = child.stderr.take().unwrap();
        let tx2 = tx.clone();
        std::thread::spawn(move || {
            BufReader::new(out)
                .lines()
                .map_while(Result::ok)
                .for_each(|l| drop(tx.send((true, l))))
        });
        std::thread::spawn(move || {
            BufReader::new(err)
                .lines()
                .map_while(Result::ok)
                .for_each(|l| drop(tx2.send((false, l))))
        });
        Viewer {
            child,
            lines,
            seen: Vec::new(),
        }
    }

    /// Waits for a line (after those already waited for) that `want` accepts.
    fn wait_for(&mut self, what: &str, want: impl Fn(&str) -> bool) -> String {
        let deadline = Instant::now() + PATIENCE;
        loop {
            match self
                .lines
                .recv_timeout(deadline.saturating_duration_since(Instant::now()))
            {
                Ok(line) => {
                    self.seen.push(line.clone());
                    if want(&line.1) {
                        return line.1;
                    }
                }
                Err(RecvTimeoutError::Timeout) => panic!("no {what} within {PATIENCE:?}:\n{}", self.log()),
                Err(RecvTimeoutError::Disconnected) => panic!("the viewer ended before {what}:\n{}", self.log()),
            }
        }
    }

    /// Waits for the process to end; returns its exit code and everything it printed.
    fn finish(mut self) -> (Option<i32>, String) {
        let deadline = Instant::now() + PATIENCE;
        let status = loop {
            if let Some(s) = self.child.try_wait().unwrap() {
                break s;
            }
            if Instant::now() > deadline {
                let _ = self.child.kill();
                panic!("the viewer did not exit:\n{}", self.log());
            }
            std::thread::sleep(Duration::from_millis(20));
        };
        // The readers end with the pipes.
        while let Ok(line) = self.lines.recv_timeout(Duration::from_secs(5)) {
            self.seen.push(line);
        }
        use std::os::unix::process::ExitStatusExt;
        let code = status.code().or(status.signal().map(|s| 128 + s));
        (code, self.log())
    }

    fn log(&self) -> String {
        self.seen.iter().map(|(_, l)| l.as_str()).collect::<Vec<_>>().join("\n")
    }

    fn stdout(&self) -> String {
        let lines: Vec<&str> = self.seen.iter().filter(|(o, _)| *o).map(|(_, l)| l.as_str()).collect();
        lines.join("\n")
    }
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ppm-vk-view-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

const SCENE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cornell-spheres.toml");
/// Small and quick: every test renders this.
const SMALL: [&str; 4] = ["--resolution", "64x64", "--photons-per-pass", "20000"];

fn assert_clean_exit(code: Option<i32>, want: i32, log: &str) {
    assert_eq!(code, Some(want), "exit code; output:\n{log}");
    assert!(!log.contains("panicked"), "{log}");
    assert!(!log.contains("validation layer"), "{log}");
}

fn rgba(path: &Path) -> image::RgbaImage {
    image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgba8()
}

#[test]
fn screenshot_after_n_passes_is_renders_png() {
    let x = Xvfb::start();
    let dir = temp_dir("shot");
    let shot = dir.join("shot.png");
    let mut args = vec![
        SCENE,
        "--passes",
        "3",
        "--seed",
        "5",
        "--screenshot",
        shot.to_str().unwrap(),
    ];
    args.extend(SMALL);
    let (code, log) = Viewer::start(&x, &args).finish();
    assert_clean_exit(code, 0, &log);
    let render = common::bin()
        .args(["render", SCENE, "--passes", "3", "--seed", "5", "-f", "--out"])
        .arg(dir.join("render.png"))
        .args(SMALL)
        .output()
        .unwrap();
    assert!(render.status.success(), "{}", String::from_utf8_lossy(&render.stderr));
    let (a, b) = (rgba(&shot), rgba(&dir.join("render.png")));
    assert_eq!(
        a.dimensions(),
        (64, 64),
        "the window is the image's size, and so is the frame"
    );
    assert_eq!(a.dimensions(), b.dimensions());
    // The same image, tone-mapped by the GPU kernel (tonemap.comp) and by the CPU (RgbImage::save_png):
    // within one 8-bit level, since GLSL's pow and Rust's powf may round the last bit differently and so
    // fall on either side of a level's edge. Almost every pixel must match exactly.
    let mut differ = 0;
    for (p, q) in a.pixels().zip(b.pixels()) {
        for c in 0..4 {
            let d = (p[c] as i32 - q[c] as i32).abs();
            assert!(d <= 1, "{p:?} against {q:?}");
            differ += (d > 0) as u32;
        }
    }
    assert!(differ <= 64 * 64 * 3 / 100, "{differ} channels differ by one level");
    let mean: f64 = a.pixels().map(|p| p[0] as f64 + p[1] as f64 + p[2] as f64).sum::<f64>() / (64.0 * 64.0 * 3.0);
    assert!(mean > 30.0, "the frame is not black (mean {mean})");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The scene file with its `[camera]` table replaced by `camera` (the lines the C key printed).
fn with_camera(scene: &str, camera: &str) -> String {
    let mut out = String::new();
    let mut skipping = false;
    for line in scene.lines() {
        if line.trim_start().starts_with('[') {
            skipping = line.trim() == "[camera]";
            if skipping {
                out += camera;
                out += "\n";
            }
        }
        if !skipping {
            out += line;
            out += "\n";
        }
    }
    out
}

#[test]
fn a_drag_moves_the_camera_restarts_and_the_printed_camera_renders_the_same_view() {
    let x = Xvfb::start();
    let dir = temp_dir("drag");
    let saved = dir.join("saved.exr");
    let mut args = vec![SCENE, "--passes", "2", "--out", saved.to_str().unwrap()];
    args.extend(SMALL);
    let mut v = Viewer::start(&x, &args);
    v.wait_for("the first 2 passes", |l| l.starts_with("view: 2 passes"));
    let xc = x.connect();
    let w = xc.viewer();
    xc.drag(w, 1, (20, 30), (45, 22));
    v.wait_for("the camera change", |l| {
        l.contains("camera moved: accumulation restarts")
    });
    v.wait_for("2 passes of the new view", |l| l.starts_with("view: 2 passes"));
    xc.key(w, 'c');
    v.wait_for("the camera's lines", |l| l.starts_with("resolution = "));
    xc.key(w, 's');
    v.wait_for("the saved image", |l| l.starts_with("view: saved"));
    xc.key(w, 'q');
    let stdout = v.stdout();
    let (code, log) = v.finish();
    assert_clean_exit(code, 0, &log);
    assert_eq!(log.matches("camera moved").count(), 1, "one drag, one restart:\n{log}");

    assert_eq!(stdout.matches("[camera]").count(), 1, "one C, one camera:\n{log}");
    assert_eq!(log.matches("view: saved").count(), 1, "one S, one save:\n{log}");
    let camera = stdout[stdout.find("[camera]").expect("a [camera] table")..].to_string();
    let original = std::fs::read_to_string(SCENE).unwrap();
    let moved = with_camera(&original, &camera);
    let scene = dir.join("moved.toml");
    std::fs::write(&scene, &moved).unwrap();
    let before = ppm_vk_engine::Scene::load(Path::new(SCENE)).unwrap().camera;
    let after = ppm_vk_engine::Scene::load(&scene).unwrap().camera;
    assert_ne!(after.eye, before.eye, "the drag moved the eye:\n{camera}");
    assert_eq!(after.look_at, before.look_at, "an orbit keeps the look-at point");
    let render = common::bin()
        .args(["render", "--passes", "2", "--photons-per-pass", "20000", "-f", "--out"])
        .arg(dir.join("render.exr"))
        .arg(&scene)
        .output()
        .unwrap();
    assert!(render.status.success(), "{}", String::from_utf8_lossy(&render.stderr));
    // Renderer::set_camera gives a new renderer's image bit for bit; the printed numbers round-trip.
    let a = RgbImage::load_exr(&saved).unwrap();
    let b = RgbImage::load_exr(dir.join("render.exr")).unwrap();
    assert_eq!(
        a, b,
        "the view saved after the drag and `render` of the printed camera differ"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_resize_makes_the_swapchain_again() {
    let x = Xvfb::start();
    let mut args = vec![SCENE, "--passes", "1"];
    args.extend(SMALL);
    let mut v = Viewer::start(&x, &args);
    v.wait_for("the first pass", |l| l.starts_with("view: 1 passes"));
    let xc = x.connect();
    let w = xc.viewer();
    xc.resize(w, 150, 90);
    v.wait_for("the new swapchain", |l| l == "view: window 150x90");
    xc.resize(w, 40, 300);
    v.wait_for("the new swapchain", |l| l == "view: window 40x300");
    xc.key(w, 'q');
    let (code, log) = v.finish();
    assert_clean_exit(code, 0, &log);
}

/// Passes long enough that the close lands in one (half a second each on lavapipe).
const SLOW: [&str; 4] = ["--resolution", "128x128", "--photons-per-pass", "1000000"];

#[test]
fn closing_the_window_mid_pass_ends_cleanly() {
    let x = Xvfb::start();
    let mut args = vec![SCENE];
    args.extend(SLOW);
    let mut v = Viewer::start(&x, &args);
    v.wait_for("the render to start", |l| l.starts_with("view: rendering"));
    let xc = x.connect();
    let w = xc.viewer();
    std::thread::sleep(Duration::from_millis(300));
    xc.close(w);
    let (code, log) = v.finish();
    assert_clean_exit(code, 0, &log);
}

#[test]
fn sigterm_and_sigint_end_cleanly() {
    for (sig, name) in [(libc::SIGTERM, "SIGTERM"), (libc::SIGINT, "SIGINT")] {
        let x = Xvfb::start();
        let mut args = vec![SCENE];
        args.extend(SLOW);
        let mut v = Viewer::start(&x, &args);
        v.wait_for("the render to start", |l| l.starts_with("view: rendering"));
        std::thread::sleep(Duration::from_millis(300));
        unsafe { libc::kill(v.child.id() as i32, sig) };
        let (code, log) = v.finish();
        assert_clean_exit(code, 128 + sig, &format!("{name}:\n{log}"));
    }
}

#[test]
fn without_a_display_it_says_to_use_render_and_exits_2() {
    for display in [None, Some(":231")] {
        let mut c = common::bin();
        c.args(["view", SCENE]).env_remove("WAYLAND_DISPLAY");
        match display {
            Some(d) => c.env("DISPLAY", d),
            None => c.env_remove("DISPLAY"),
        };
        let out = c.output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "DISPLAY {display:?}: {stderr}");
        assert!(
            stderr.starts_with("error: ") && stderr.contains("ppm-vk render"),
            "{stderr}"
        );
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
    // A bad scene is reported as such (exit 1) before the missing display.
    let out = common::bin()
        .args(["view", "no-such-scene.toml"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("no-such-scene.toml"), "{stderr}");
}

/// A measurement, not a test (run it with `--ignored --nocapture`; docs/performance.md, "The viewer"):
/// frames per second while accumulating, and the time from a camera change (a drag, a pan, the wheel) to
/// the first frame of the new view, as the viewer measures them, at 256x256 and 512x512 with 100k photons
/// per pass.
#[test]
#[ignore]
fn measure_frame_rate_and_camera_latency() {
    for resolution in ["256x256", "512x512"] {
        let x = Xvfb::start();
        let args = [
            SCENE,
            "--resolution",
            resolution,
            "--photons-per-pass",
            "100000",
            "--passes",
            "40",
        ];
        let mut v = Viewer::start(&x, &args);
        v.wait_for("40 passes", |l| l.starts_with("view: 40 passes"));
        let xc = x.connect();
        let w = xc.viewer();
        xc.key(w, 'q');
        let (code, log) = v.finish();
        assert_clean_exit(code, 0, &log);
        let rate = log
            .lines()
            .find(|l| l.contains("frames/s"))
            .unwrap_or("no summary")
            .to_string();

        let args = [SCENE, "--resolution", resolution, "--photons-per-pass", "100000"];
        let mut v = Viewer::start(&x, &args);
        v.wait_for("the render to start", |l| l.starts_with("view: rendering"));
        std::thread::sleep(Duration::from_secs(2));
        for i in 0..12i16 {
            match i % 3 {
                0 => xc.drag(w, 1, (100, 100), (100 + 8 + i, 96)),
                1 => xc.drag(w, 3, (100, 100), (104, 100 + i)),
                _ => {
                    let (ox, oy) = xc.origin(w);
                    xc.fake(xproto::MOTION_NOTIFY_EVENT, 0, ox + 100, oy + 100);
                    xc.fake(xproto::BUTTON_PRESS_EVENT, 4 + (i % 2) as u8, 0, 0);
                    xc.fake(xproto::BUTTON_RELEASE_EVENT, 4 + (i % 2) as u8, 0, 0);
                }
            }
            std::thread::sleep(Duration::from_millis(1000));
        }
        let w = xc.viewer();
        xc.key(w, 'q');
        let (code, log) = v.finish();
        assert_clean_exit(code, 0, &log);
        let latency = log
            .lines()
            .find(|l| l.contains("camera changes"))
            .unwrap_or("no summary")
            .to_string();
        println!("{resolution}, 100000 photons per pass:\n  {rate}\n  {latency}");
    }
}
