//! `ppm-vk view SCENE`: a window that shows the render after every pass, and a camera to move.
//!
//! Two threads. The main thread runs the window's event loop and nothing else, so the window answers
//! input at once whatever the device is doing. The render thread owns every Vulkan object: it runs the
//! passes, and presents after each. A camera change is sent to it and cancels the pass in flight
//! ([`CancelToken`]: checked between the pass's submissions), so the new view starts after at most one
//! submission; then [`Renderer::set_camera`] restarts the accumulation without compiling, building or
//! uploading anything again.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, Sender};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{bail, Context as _, Result};
use clap::Args;
use glam::{Quat, Vec3};
use ppm_vk_engine::present::Presenter;
use ppm_vk_engine::scene::Camera;
use ppm_vk_engine::{CancelToken, Error, Renderer, Scene, Settings};
use winit::application::ApplicationHandler;
use winit::dpi::{PhysicalPosition, PhysicalSize};
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop, EventLoopProxy};
use winit::keyboard::{Key, NamedKey};
use winit::raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use winit::window::{Window, WindowId};

use crate::{check_validation, save_pipeline_cache, watch_signals, DeviceArgs, SettingsArgs};

/// Photons per pass when --photons-per-pass is not given: a frame every few tenths of a second on
/// lavapipe at 256x256 (docs/performance.md, "The viewer").
const VIEW_PHOTONS_PER_PASS: u32 = 100_000;

/// The exit code when there is no display to open a window on (as `render` would need none).
pub const EXIT_NO_DISPLAY: i32 = 2;

#[derive(Args)]
pub struct ViewArgs {
    /// Scene file: TOML (see docs/scene-format.md) or Mitsuba 3 XML (.xml, see docs/mitsuba.md).
    scene: PathBuf,
    /// Override a Mitsuba scene's parameter: `-D name=value` sets what `$name` stands for (repeatable).
    #[arg(short = 'D', long = "define", value_name = "NAME=VALUE", value_parser = ppm_vk_engine::scene::parse_define)]
    defines: Vec<(String, String)>,
    #[command(flatten)]
    settings: SettingsArgs,
    /// Stop accumulating after this many passes (the window stays and shows them; a camera change starts
    /// again); default: go on until the window closes.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    passes: Option<u64>,
    /// With --passes: write the frame the window shows after the last pass (read back from the swapchain
    /// image) to this PNG, and exit.
    #[arg(long, requires = "passes", value_name = "FILE.png")]
    screenshot: Option<PathBuf>,
    /// Exposure in stops at the start (the + and - keys change it by half a stop).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true, value_parser = parse_exposure)]
    exposure: f32,
    /// Where the S key saves the image: .exr or .png. Default: `<scene name>.exr` and `<scene name>.png`,
    /// as `render` writes them; where those exist (without --force), `<scene name>-2.exr` and so on.
    #[arg(long, short)]
    out: Option<PathBuf>,
    /// Let the S key overwrite existing images.
    #[arg(long, short)]
    force: bool,
    #[command(flatten)]
    device: DeviceArgs,
}

fn parse_exposure(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(v) if v.is_finite() && v.abs() <= 64.0 => Ok(v),
        Ok(v) => Err(format!("must be a number of stops in [-64, 64], got {v}")),
        Err(e) => Err(format!("{s:?}: {e}")),
    }
}

/// What the keys do, printed at the start and by H.
const HELP: &str = "view: drag to orbit, right-drag (or shift-drag) to pan, wheel to dolly; \
    + / - exposure, space pause, S save, C print the camera, R reset the camera, H help, Q or Esc quit";

/// How the view ended.
pub enum Ended {
    /// The window was closed, or Q pressed, or the screenshot written.
    Done,
    /// By this signal (SIGINT, SIGTERM): exit 128 + signal.
    Signal(i32),
    /// No window could be opened: exit [`EXIT_NO_DISPLAY`].
    NoDisplay(String),
}

/// From the window to the render thread.
enum Command {
    /// Show the scene from here, restarting the accumulation; the instant is the input's, for the latency.
    Camera(Camera, Instant),
    Exposure(f32),
    TogglePause,
    Save,
    Resize(u32, u32),
    Redraw,
    Quit,
}

/// From the render thread to the window.
enum Note {
    /// The render thread has ended (its objects are gone: the window may close).
    Ended(Result<Ended>),
}

pub fn run(args: ViewArgs) -> Result<Ended> {
    if let Some(shot) = &args.screenshot {
        let png = shot.extension().is_some_and(|e| e.eq_ignore_ascii_case("png"));
        if !png {
            bail!("--screenshot {}: the extension must be .png", shot.display());
        }
    }
    if let Some(out) = &args.out {
        crate::outputs(&Some(out.clone()), "", true)?; // the extension, before the scene is read
    }
    let scene = args.settings.load_scene(&args.scene, &args.defines)?;
    let settings = Settings {
        // A camera change then waits for one stage of the pass in flight, not for its whole photon batch.
        split_submissions: true,
        ..args.settings.settings(VIEW_PHOTONS_PER_PASS)?
    };
    // Bad input is reported first, then a missing display. Neither variable: winit would fail with a
    // message about connections; say what to do instead.
    if std::env::var_os("DISPLAY").is_none() && std::env::var_os("WAYLAND_DISPLAY").is_none() {
        return Ok(Ended::NoDisplay(
            "no display: neither DISPLAY nor WAYLAND_DISPLAY is set, so no window can open; \
             `ppm-vk render` renders to a file without one"
                .into(),
        ));
    }
    let signal = watch_signals(None)?;
    let event_loop = match EventLoop::<Note>::with_user_event().build() {
        Ok(l) => l,
        Err(e) => {
            return Ok(Ended::NoDisplay(format!(
                "cannot connect to the display ({e}); `ppm-vk render` renders to a file without one"
            )))
        }
    };
    let proxy = event_loop.create_proxy();
    let exposure = args.exposure;
    let mut app = App {
        args: Arc::new(args),
        scene: Arc::new(scene),
        settings,
        proxy,
        signal,
        cancel: CancelToken::new(),
        window: None,
        render: None,
        camera: None,
        drag: None,
        cursor: None,
        shift: false,
        exposure,
        ended: None,
        quitting: false,
    };
    event_loop
        .run_app(&mut app)
        .context("running the window's event loop")?;
    if let Some((_, thread)) = app.render.take() {
        let _ = thread.join();
    }
    app.ended.unwrap_or(Ok(Ended::Done))
}

struct App {
    args: Arc<ViewArgs>,
    scene: Arc<Scene>,
    settings: Settings,
    proxy: EventLoopProxy<Note>,
    signal: Arc<AtomicUsize>,
    /// The renderer's: cancelled to cut the pass in flight short (a camera change, quitting).
    cancel: CancelToken,
    window: Option<Arc<Window>>,
    render: Option<(Sender<Command>, std::thread::JoinHandle<()>)>,
    /// The camera the window asks for (the render thread's may lag by a pass).
    camera: Option<Camera>,
    /// The button held down, if any, and whether it pans.
    drag: Option<bool>,
    cursor: Option<PhysicalPosition<f64>>,
    shift: bool,
    exposure: f32,
    ended: Option<Result<Ended>>,
    quitting: bool,
}

impl App {
    fn send(&self, c: Command) {
        if let Some((tx, _)) = &self.render {
            let _ = tx.send(c);
        }
    }

    /// Asks the render thread to stop; the loop exits when it says it has ([`Note::Ended`]).
    fn quit(&mut self, event_loop: &ActiveEventLoop) {
        if self.quitting {
            return;
        }
        self.quitting = true;
        match &self.render {
            Some(_) => {
                self.send(Command::Quit);
                self.cancel.cancel();
            }
            None => event_loop.exit(),
        }
    }

    fn move_camera(&mut self, camera: Camera) {
        self.camera = Some(camera);
        self.send(Command::Camera(camera, Instant::now()));
        self.cancel.cancel();
    }
}

impl ApplicationHandler<Note> for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_some() {
            return;
        }
        let c = self.scene.camera;
        let attributes = Window::default_attributes()
            .with_title(format!("ppm-vk view: {}", self.scene.name))
            .with_inner_size(PhysicalSize::new(c.width, c.height));
        let window = match event_loop.create_window(attributes) {
            Ok(w) => Arc::new(w),
            Err(e) => {
                self.ended = Some(Ok(Ended::NoDisplay(format!(
                    "cannot open a window ({e}); `ppm-vk render` renders to a file without one"
                ))));
                event_loop.exit();
                return;
            }
        };
        eprintln!("{HELP}");
        let (tx, rx) = std::sync::mpsc::channel();
        let job = RenderThread {
            window: window.clone(),
            args: self.args.clone(),
            scene: self.scene.clone(),
            settings: self.settings.clone(),
            cancel: self.cancel.clone(),
            exposure: self.exposure,
        };
        let proxy = self.proxy.clone();
        let thread = std::thread::Builder::new().name("render".into()).spawn(move || {
            let ended = job.run(rx);
            let _ = proxy.send_event(Note::Ended(ended));
        });
        match thread {
            Ok(t) => self.render = Some((tx, t)),
            Err(e) => {
                self.ended = Some(Err(anyhow::anyhow!(e).context("starting the render thread")));
                event_loop.exit();
            }
        }
        self.camera = Some(c);
        self.window = Some(window);
    }

    fn user_event(&mut self, event_loop: &ActiveEventLoop, note: Note) {
        match note {
            Note::Ended(ended) => {
                if self.ended.is_none() {
                    self.ended = Some(ended);
                }
                if let Some((_, thread)) = self.render.take() {
                    let _ = thread.join();
                }
                event_loop.exit();
            }
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        // Signals are polled: the handler only stores the number (async-signal-safe).
        let sig = self.signal.load(Ordering::SeqCst);
        if sig != 0 && !self.quitting {
            self.ended = Some(Ok(Ended::Signal(sig as i32)));
            self.quit(event_loop);
        }
        event_loop.set_control_flow(ControlFlow::WaitUntil(Instant::now() + Duration::from_millis(50)));
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => self.quit(event_loop),
            WindowEvent::Resized(size) => self.send(Command::Resize(size.width, size.height)),
            WindowEvent::RedrawRequested => self.send(Command::Redraw),
            WindowEvent::ModifiersChanged(m) => self.shift = m.state().shift_key(),
            WindowEvent::MouseInput { state, button, .. } => {
                self.drag = match (state, button) {
                    (ElementState::Pressed, MouseButton::Left) => Some(self.shift),
                    (ElementState::Pressed, MouseButton::Right | MouseButton::Middle) => Some(true),
                    (ElementState::Released, _) => None,
                    _ => self.drag,
                };
            }
            WindowEvent::CursorMoved { position, .. } => {
                let last = self.cursor.replace(position);
                if let (Some(pan), Some(last), Some(camera)) = (self.drag, last, self.camera) {
                    let (dx, dy) = ((position.x - last.x) as f32, (position.y - last.y) as f32);
                    if dx != 0.0 || dy != 0.0 {
                        let moved = match pan {
                            true => pan_camera(&camera, dx, dy),
                            false => orbit(&camera, dx, dy),
                        };
                        self.move_camera(moved);
                    }
                }
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                if let (Some(camera), true) = (self.camera, steps != 0.0) {
                    self.move_camera(dolly(&camera, steps));
                }
            }
            // Synthetic presses are keys already down when the window got the focus: not the user's now.
            WindowEvent::KeyboardInput {
                event,
                is_synthetic: false,
                ..
            } if event.state == ElementState::Pressed => {
                let once = !event.repeat;
                match event.logical_key.as_ref() {
                    Key::Named(NamedKey::Escape) => self.quit(event_loop),
                    Key::Named(NamedKey::Space) => self.send(Command::TogglePause),
                    Key::Character(c) => match c.to_ascii_lowercase().as_str() {
                        "q" => self.quit(event_loop),
                        "+" | "=" => {
                            self.exposure = (self.exposure + 0.5).min(64.0);
                            self.send(Command::Exposure(self.exposure));
                        }
                        "-" | "_" => {
                            self.exposure = (self.exposure - 0.5).max(-64.0);
                            self.send(Command::Exposure(self.exposure));
                        }
                        "s" if once => self.send(Command::Save),
                        "c" if once => {
                            if let Some(camera) = &self.camera {
                                print_camera(camera, &self.args.scene);
                            }
                        }
                        "r" => self.move_camera(self.scene.camera),
                        "h" => eprintln!("{HELP}"),
                        _ => {}
                    },
                    _ => {}
                }
            }
            _ => {}
        }
    }
}

/// Radians the camera turns per pixel dragged.
const ORBIT_PER_PIXEL: f32 = 0.008;
/// Closest the view direction comes to `up` (radians), so orbiting never flips over the pole.
const POLE_MARGIN: f32 = 0.02;

/// Turns the eye about the look-at point: `dx` about `up`, `dy` about the camera's right axis.
pub fn orbit(c: &Camera, dx: f32, dy: f32) -> Camera {
    let up = c.up.normalize();
    let offset = c.eye - c.look_at;
    let yawed = Quat::from_axis_angle(up, -dx * ORBIT_PER_PIXEL) * offset;
    // The angle from `up`, kept inside (margin, pi - margin).
    let polar = yawed.normalize().dot(up).clamp(-1.0, 1.0).acos();
    let pitch = (-dy * ORBIT_PER_PIXEL).clamp(POLE_MARGIN - polar, std::f32::consts::PI - POLE_MARGIN - polar);
    let right = up.cross(yawed).normalize_or_zero();
    let turned = match right == Vec3::ZERO {
        true => yawed,
        false => Quat::from_axis_angle(right, -pitch) * yawed,
    };
    Camera {
        eye: c.look_at + turned,
        ..*c
    }
}

/// Moves eye and look-at together in the image plane so that the look-at point follows the cursor.
pub fn pan_camera(c: &Camera, dx: f32, dy: f32) -> Camera {
    let forward = c.look_at - c.eye;
    let distance = forward.length();
    let right = forward.cross(c.up).normalize_or_zero();
    let up = right.cross(forward).normalize_or_zero();
    // Scene units per pixel at the look-at point's depth.
    let per_pixel = 2.0 * distance * (0.5 * c.vfov_deg.to_radians()).tan() / c.height as f32;
    let shift = (-dx * right + dy * up) * per_pixel;
    Camera {
        eye: c.eye + shift,
        look_at: c.look_at + shift,
        ..*c
    }
}

/// Moves the eye toward the look-at point (`steps` > 0) or away, 10% of the distance per wheel step; never
/// onto it.
pub fn dolly(c: &Camera, steps: f32) -> Camera {
    let offset = c.eye - c.look_at;
    let factor = 0.9f32.powf(steps.clamp(-20.0, 20.0));
    let scaled = offset * factor;
    let eye = match scaled.length() > 1e-4 * offset.length().max(f32::MIN_POSITIVE) && scaled.is_finite() {
        true => c.look_at + scaled,
        false => c.eye,
    };
    Camera { eye, ..*c }
}

/// Prints the camera as the scene file's lines: TOML's `[camera]` table, or an XML scene's `<sensor>`
/// (its fov, to_world and film: replace those of the file's sensor).
fn print_camera(c: &Camera, scene_path: &Path) {
    println!("{}", camera_lines(c, scene_path));
}

pub fn camera_lines(c: &Camera, scene_path: &Path) -> String {
    let v = |p: Vec3| format!("{:?}, {:?}, {:?}", p.x, p.y, p.z);
    let xml = scene_path.extension().is_some_and(|e| e.eq_ignore_ascii_case("xml"));
    match xml {
        false => format!(
            "[camera]\neye = [{}]\nlook_at = [{}]\nup = [{}]\nvfov = {:?}\nresolution = [{}, {}]",
            v(c.eye),
            v(c.look_at),
            v(c.up),
            c.vfov_deg,
            c.width,
            c.height
        ),
        true => format!(
            "<sensor type=\"perspective\">\n    <float name=\"fov\" value=\"{:?}\"/>\n    \
             <string name=\"fov_axis\" value=\"y\"/>\n    <transform name=\"to_world\">\n        \
             <lookat origin=\"{}\" target=\"{}\" up=\"{}\"/>\n    </transform>\n    \
             <film type=\"hdrfilm\">\n        <integer name=\"width\" value=\"{}\"/>\n        \
             <integer name=\"height\" value=\"{}\"/>\n    </film>\n</sensor>",
            c.vfov_deg,
            v(c.eye),
            v(c.look_at),
            v(c.up),
            c.width,
            c.height
        ),
    }
}

/// What the render thread needs; it owns every Vulkan object, so they are made and dropped on it, before
/// the window goes.
struct RenderThread {
    window: Arc<Window>,
    args: Arc<ViewArgs>,
    scene: Arc<Scene>,
    settings: Settings,
    cancel: CancelToken,
    exposure: f32,
}

/// Frame and latency figures of one view, printed when it ends.
#[derive(Default)]
struct Timings {
    frames: u32,
    /// When the first and the latest frame were shown.
    span: Option<(Instant, Instant)>,
    /// From a camera change's input to the first frame of the new view, in ms.
    latencies: Vec<f64>,
}

impl Timings {
    fn frame(&mut self) {
        let now = Instant::now();
        self.frames += 1;
        let first = self.span.map_or(now, |s| s.0);
        self.span = Some((first, now));
    }

    fn summary(&self) -> String {
        let mut s = match self.span {
            Some((first, last)) if self.frames > 1 => {
                let t = (last - first).as_secs_f64();
                format!(
                    "view: {} frames in {t:.1} s ({:.2} frames/s)",
                    self.frames,
                    (self.frames - 1) as f64 / t
                )
            }
            _ => format!("view: {} frames", self.frames),
        };
        if !self.latencies.is_empty() {
            let mut l = self.latencies.clone();
            l.sort_by(f64::total_cmp);
            s += &format!(
                "; {} camera changes, from the input to the new view's first frame: median {:.0} ms, max {:.0} ms",
                l.len(),
                l[l.len() / 2],
                l[l.len() - 1]
            );
        }
        s
    }
}

impl RenderThread {
    fn run(self, rx: Receiver<Command>) -> Result<Ended> {
        let window = self.window.clone();
        let display = window.display_handle().context("the window's display handle")?.as_raw();
        let handle = window.window_handle().context("the window's handle")?.as_raw();
        let ctx = match self.args.device.open_for(Some(display)) {
            Ok(ctx) => ctx,
            Err(e) => {
                return Ok(Ended::NoDisplay(format!(
                    "{e:#}; `ppm-vk render` renders to a file without a window"
                )))
            }
        };
        let info = ctx.info().clone();
        eprintln!("device: {} ({}, {})", info.name, info.kind, info.driver);
        window.set_title(&format!("ppm-vk view: {}: compiling kernels", self.scene.name));
        let mut renderer = Renderer::new(&ctx, &self.scene, self.settings.clone())?;
        save_pipeline_cache(&ctx);
        renderer.set_cancel(self.cancel.clone());
        let c = self.scene.camera;
        let photons = renderer.settings().photons_per_pass;
        eprintln!("view: rendering {}x{}, {photons} photons per pass", c.width, c.height);
        let size = window.inner_size();
        // SAFETY: the window outlives the presenter: this thread holds it, and drops the presenter first.
        let presenter = unsafe { Presenter::new(&ctx, display, handle, (size.width, size.height)) };
        let mut presenter = match presenter {
            Ok(p) => p,
            Err(e) => {
                return Ok(Ended::NoDisplay(format!(
                    "{e}; `ppm-vk render` renders to a file without a window"
                )))
            }
        };
        let ended = self.frames(&rx, &mut renderer, &mut presenter);
        drop(presenter);
        ended.and_then(|e| {
            check_validation(&ctx)?;
            Ok(e)
        })
    }

    /// The pass loop: commands between passes, a frame after each.
    fn frames(&self, rx: &Receiver<Command>, renderer: &mut Renderer, presenter: &mut Presenter) -> Result<Ended> {
        let (mut exposure, mut paused, mut dirty) = (self.exposure, false, false);
        let mut size = presenter.extent();
        let mut started = Instant::now();
        let mut moved: Option<Instant> = None;
        let mut timings = Timings::default();
        let mut announced = false;
        let target = self.args.passes.unwrap_or(u64::MAX);
        loop {
            // Every command waiting; only the last camera counts.
            let mut camera = None;
            let idle = paused || renderer.passes() >= target;
            let first = match idle && !dirty {
                true => match rx.recv_timeout(Duration::from_millis(100)) {
                    Ok(c) => Some(c),
                    Err(RecvTimeoutError::Timeout) => None,
                    Err(RecvTimeoutError::Disconnected) => return Ok(Ended::Done),
                },
                false => None,
            };
            for command in first.into_iter().chain(rx.try_iter()) {
                match command {
                    Command::Quit => {
                        eprintln!("{}", timings.summary());
                        return Ok(Ended::Done);
                    }
                    Command::Camera(c, at) => camera = Some((c, moved.unwrap_or(at))),
                    Command::Exposure(e) => (exposure, dirty) = (e, true),
                    Command::TogglePause => {
                        paused = !paused;
                        dirty = true;
                    }
                    Command::Save => self.save(renderer, exposure)?,
                    Command::Resize(w, h) => {
                        size = (w, h);
                        if w > 0 && h > 0 {
                            presenter.resize(size)?;
                            eprintln!("view: window {}x{}", presenter.extent().0, presenter.extent().1);
                            dirty = true;
                        }
                    }
                    Command::Redraw => dirty = true,
                }
            }
            if let Some((c, at)) = camera {
                self.cancel.reset();
                renderer.set_camera(&c)?;
                eprintln!("view: camera moved: accumulation restarts");
                (started, moved, announced) = (Instant::now(), Some(at), false);
            }
            if !paused && renderer.passes() < target {
                match renderer.pass() {
                    Ok(_) => dirty = true,
                    Err(Error::Cancelled) => {
                        self.cancel.reset();
                        continue;
                    }
                    Err(e) => return Err(e.into()),
                }
            }
            if !dirty || size.0 == 0 || size.1 == 0 {
                continue;
            }
            dirty = false;
            let done = renderer.passes() >= target;
            let shoot = done && self.args.screenshot.is_some();
            let frame = presenter.present(renderer, exposure, shoot, size)?;
            timings.frame();
            if let (Some(at), true) = (moved, renderer.passes() > 0) {
                timings.latencies.push(at.elapsed().as_secs_f64() * 1e3);
                moved = None;
            }
            self.title(renderer, started, exposure, paused);
            if done && !announced {
                announced = true;
                eprintln!(
                    "view: {} passes: accumulation stopped (the window stays; Q quits)",
                    renderer.passes()
                );
            }
            if let (Some(path), Some(frame)) = (&self.args.screenshot, frame) {
                frame.save_png(path)?;
                eprintln!("view: wrote {} ({}x{})", path.display(), frame.width, frame.height);
                eprintln!("{}", timings.summary());
                return Ok(Ended::Done);
            }
        }
    }

    fn title(&self, renderer: &Renderer, started: Instant, exposure: f32, paused: bool) {
        let elapsed = started.elapsed().as_secs_f64();
        let rate = renderer.emitted() as f64 / elapsed.max(1e-9) / 1e6;
        let mut title = format!(
            "ppm-vk view: {} | pass {} | {:.2} M photons/s | {:.1} s | exposure {:+.1}",
            self.scene.name,
            renderer.passes(),
            rate,
            elapsed,
            exposure
        );
        if paused {
            title += " | paused";
        }
        self.window.set_title(&title);
    }

    /// The S key: the image as `render` writes it, the PNG at the exposure shown.
    fn save(&self, renderer: &mut Renderer, exposure: f32) -> Result<()> {
        let image = renderer.image()?;
        let paths = save_paths(&self.args.out, &self.scene.name, self.args.force);
        for p in &paths {
            match p
                .extension()
                .and_then(|e| e.to_str())
                .map(|e| e.to_ascii_lowercase())
                .as_deref()
            {
                Some("png") => image.save_png(p, exposure)?,
                _ => image.save(p)?,
            }
        }
        let names: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
        eprintln!("view: saved {} after {} passes", names.join(" and "), renderer.passes());
        Ok(())
    }
}

/// `render`'s names (`--out`, else `<scene>.exr` and `<scene>.png`); where one exists and `force` is off,
/// the first `-2`, `-3`, ... suffix that is free for all of them.
fn save_paths(out: &Option<PathBuf>, scene_name: &str, force: bool) -> Vec<PathBuf> {
    let base: Vec<PathBuf> = match out {
        Some(p) => vec![p.clone()],
        None => vec![
            PathBuf::from(format!("{scene_name}.exr")),
            PathBuf::from(format!("{scene_name}.png")),
        ],
    };
    if force || base.iter().all(|p| !p.exists()) {
        return base;
    }
    let numbered = |n: u32| -> Vec<PathBuf> {
        base.iter()
            .map(|p| {
                let stem = p
                    .file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default();
                let ext = p
                    .extension()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default();
                p.with_file_name(format!("{stem}-{n}.{ext}"))
            })
            .collect()
    };
    (2..)
        .map(numbered)
        .find(|paths| paths.iter().all(|p| !p.exists()))
        .unwrap_or(base)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera {
            eye: Vec3::new(0.0, 1.0, 2.9),
            look_at: Vec3::new(0.0, 0.8, 0.0),
            up: Vec3::Y,
            vfov_deg: 50.0,
            width: 256,
            height: 256,
        }
    }

    #[test]
    fn orbit_keeps_the_distance_and_the_look_at_point() {
        let c = camera();
        let d = (c.eye - c.look_at).length();
        for (dx, dy) in [(10.0, 0.0), (0.0, 25.0), (-300.0, 180.0), (0.0, -5000.0), (0.0, 5000.0)] {
            let o = orbit(&c, dx, dy);
            assert!(((o.eye - o.look_at).length() - d).abs() < 1e-5 * d, "{dx},{dy}");
            assert_eq!(o.look_at, c.look_at);
            let polar = (o.eye - o.look_at).normalize().dot(Vec3::Y).acos();
            assert!(
                (POLE_MARGIN * 0.99..=std::f32::consts::PI - POLE_MARGIN * 0.99).contains(&polar),
                "{polar}"
            );
            o.validate("t").unwrap();
        }
        // A horizontal drag keeps the height; a drag right turns the eye to the left (-x).
        let o = orbit(&c, 40.0, 0.0);
        assert!((o.eye.y - c.eye.y).abs() < 1e-6);
        assert!(o.eye.x < 0.0);
    }

    #[test]
    fn pan_moves_eye_and_look_at_together_in_the_image_plane() {
        let c = camera();
        let p = pan_camera(&c, 20.0, -10.0);
        assert!(((p.eye - c.eye) - (p.look_at - c.look_at)).length() < 1e-6);
        let shift = p.look_at - c.look_at;
        assert!(shift.dot(c.look_at - c.eye).abs() < 1e-5, "in the image plane");
        // 20 pixels of 256 at distance d move the look-at point by 20/256 of the view's height there.
        let d = (c.look_at - c.eye).length();
        let expected = (20f32.powi(2) + 10f32.powi(2)).sqrt() / 256.0 * 2.0 * d * 25f32.to_radians().tan();
        assert!((shift.length() - expected).abs() < 1e-5);
    }

    #[test]
    fn dolly_scales_the_distance_and_never_reaches_the_look_at_point() {
        let c = camera();
        let d = (c.eye - c.look_at).length();
        let closer = dolly(&c, 1.0);
        assert!(((closer.eye - closer.look_at).length() - 0.9 * d).abs() < 1e-5);
        let back = dolly(&closer, -1.0);
        assert!((back.eye - c.eye).length() < 1e-5);
        let mut near = c;
        for _ in 0..1000 {
            near = dolly(&near, 20.0);
        }
        assert!((near.eye - near.look_at).length() > 0.0);
        near.validate("t").unwrap();
    }

    #[test]
    fn camera_lines_are_the_scene_files_own() {
        let c = camera();
        let toml = camera_lines(&c, Path::new("a.toml"));
        assert!(
            toml.starts_with("[camera]\neye = [0.0, 1.0, 2.9]\nlook_at = [0.0, 0.8, 0.0]"),
            "{toml}"
        );
        assert!(toml.contains("vfov = 50.0\nresolution = [256, 256]"), "{toml}");
        let xml = camera_lines(&c, Path::new("a.XML"));
        assert!(
            xml.contains(r#"<lookat origin="0.0, 1.0, 2.9" target="0.0, 0.8, 0.0" up="0.0, 1.0, 0.0"/>"#),
            "{xml}"
        );
        assert!(xml.contains(r#"<float name="fov" value="50.0"/>"#), "{xml}");
    }

    /// The printed `<sensor>` in an XML scene gives back the camera (the loader goes through Mitsuba's
    /// to_world matrix and a y field of view, so to within f32 rounding, not bit for bit).
    #[test]
    fn an_xml_scenes_printed_sensor_loads_as_the_same_camera() {
        let c = Camera {
            eye: Vec3::new(0.3, 1.2, 4.1),
            look_at: Vec3::new(-0.2, 0.4, 0.1),
            width: 48,
            height: 32,
            ..camera()
        };
        let sensor = camera_lines(&c, Path::new("s.xml"));
        let xml = format!(
            r#"<scene version="3.0.0">{sensor}
            <shape type="rectangle"><bsdf type="diffuse"/><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>
            </scene>"#
        );
        let path = std::env::temp_dir().join(format!("ppm-vk-sensor-{}.xml", std::process::id()));
        std::fs::write(&path, xml).unwrap();
        let loaded = Scene::load(&path).map(|s| s.camera);
        std::fs::remove_file(&path).unwrap();
        let l = loaded.unwrap();
        assert_eq!((l.width, l.height), (48, 32));
        assert!(
            (l.vfov_deg - c.vfov_deg).abs() < 1e-4,
            "{} against {}",
            l.vfov_deg,
            c.vfov_deg
        );
        assert!((l.eye - c.eye).length() < 1e-5, "{:?}", l.eye);
        let (a, b) = ((l.look_at - l.eye).normalize(), (c.look_at - c.eye).normalize());
        assert!((a - b).length() < 1e-5, "{a:?} against {b:?}");
        assert!(l.up.normalize().dot(a).abs() < 1.0 - 1e-3);
    }

    #[test]
    fn save_paths_never_overwrite_without_force() {
        let dir = std::env::temp_dir().join(format!("ppm-vk-save-paths-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let name = dir.join("s").display().to_string();
        assert_eq!(
            save_paths(&None, &name, false),
            [format!("{name}.exr"), format!("{name}.png")].map(PathBuf::from)
        );
        std::fs::write(format!("{name}.png"), b"x").unwrap();
        assert_eq!(
            save_paths(&None, &name, false),
            [format!("{name}-2.exr"), format!("{name}-2.png")].map(PathBuf::from)
        );
        assert_eq!(save_paths(&None, &name, true)[1], PathBuf::from(format!("{name}.png")));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
