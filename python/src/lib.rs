//! `ppm_vk._native`: the engine for Python. The Python package `ppm_vk` (python/ppm_vk/) is the public
//! face: it turns keyword settings into JSON, wraps images and statistics, and defines the exceptions
//! this module raises (ppm_vk/_errors.py), so that they can subclass both `ppm_vk.Error` and the
//! builtin a Python program expects (`OSError`, `ValueError`, `TypeError`).

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray3, PyUntypedArrayMethods};
use ppm_vk_engine::distributed::{self, Job, Method};
use ppm_vk_engine::{
    open_device, CancelToken, Checkpoint, ContextOptions, Error, PassStats, RgbImage, Scene, Settings,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};

/// Settings under the `render` command's flag names, where those differ from the engine's field names.
const FLAG_NAMES: &[(&str, &str)] = &[("radius", "initial_radius"), ("beta", "probe_beta"), ("cone", "cone_k")];

/// The build a checkpoint names (python/build.rs, as the binary's): its kernels and engine must be the ones
/// that continue it.
const BUILD: &str = env!("PPM_VK_GIT_REV");

/// Settings that take `"off"` for none, as their flags do.
const OFF_MEANS_NONE: &[&str] = &["cone_k", "glossy_hits"];

/// The exception `class` of ppm_vk/_errors.py with `message` and the attributes `attrs` sets.
fn raise(
    py: Python<'_>,
    class: &str,
    message: String,
    attrs: impl FnOnce(&Bound<'_, PyDict>) -> PyResult<()>,
) -> PyErr {
    let made = (|| -> PyResult<PyErr> {
        let class = py.import("ppm_vk._errors")?.getattr(class)?;
        let kwargs = PyDict::new(py);
        attrs(&kwargs)?;
        Ok(PyErr::from_value(class.call((message,), Some(&kwargs))?))
    })();
    made.unwrap_or_else(|e| e)
}

/// The engine's error as the `ppm_vk` exception of its case, with the case's fields as attributes.
fn to_py(py: Python<'_>, error: Error) -> PyErr {
    let message = error.to_string();
    match error {
        Error::Scene {
            file,
            line,
            column,
            field,
            ..
        } => raise(py, "SceneError", message, |d| {
            d.set_item("file", file)?;
            d.set_item("line", line)?;
            d.set_item("column", column)?;
            d.set_item("field", field)
        }),
        Error::Settings { field, .. } => raise(py, "SettingsError", message, |d| d.set_item("field", field)),
        Error::Limit {
            what,
            value,
            limit,
            lower,
        } => raise(py, "LimitError", message, |d| {
            d.set_item("what", what)?;
            d.set_item("value", value)?;
            d.set_item("limit", limit)?;
            d.set_item("lower", lower)
        }),
        Error::Device { context, .. } => raise(py, "DeviceError", message, |d| d.set_item("context", context)),
        Error::Io { path, error } => raise(py, "IoError", message, |d| {
            d.set_item("filename", path.display().to_string())?;
            d.set_item("errno", error.raw_os_error())
        }),
        Error::Checkpoint { .. } => raise(py, "CheckpointError", message, |_| Ok(())),
        Error::Cancelled => raise(py, "CancelledError", message, |_| Ok(())),
        _ => raise(py, "Error", message, |_| Ok(())),
    }
}

/// `Result<T, ppm_vk_engine::Error>` into a Python result.
trait OrRaise<T> {
    fn or_raise(self, py: Python<'_>) -> PyResult<T>;
}

impl<T> OrRaise<T> for Result<T, Error> {
    fn or_raise(self, py: Python<'_>) -> PyResult<T> {
        self.map_err(|e| to_py(py, e))
    }
}

/// A settings error (`ppm_vk.SettingsError`, a `ValueError`) naming `field`.
fn settings_error(py: Python<'_>, field: &str, message: String) -> PyErr {
    raise(py, "SettingsError", format!("settings: {field}: {message}"), |d| {
        d.set_item("field", field)
    })
}

/// An unknown keyword (`ppm_vk.UnknownSettingError`, also a `TypeError`, as Python raises for unexpected
/// keywords) naming it and the settings there are.
fn unknown_setting(py: Python<'_>, name: &str, known: &[String]) -> PyErr {
    let message = format!(
        "unknown setting {name:?}; the settings are: {}, and the flag names {}",
        known.join(", "),
        FLAG_NAMES.iter().map(|(f, _)| *f).collect::<Vec<_>>().join(", ")
    );
    raise(py, "UnknownSettingError", message, |d| d.set_item("field", name))
}

/// A checkpoint's load or save failure (the engine reports them through `anyhow`) as the engine's case:
/// [`Error::Io`] where a file could not be read or written, else `otherwise` (refused, damaged).
fn checkpoint_error(path: &Path, e: anyhow::Error, otherwise: fn(String) -> Error) -> Error {
    let message = format!("{e:#}");
    let io_kind = e.chain().find_map(|c| match c.downcast_ref::<Error>() {
        Some(Error::Io { error, .. }) => Some(error.kind()),
        _ => c.downcast_ref::<std::io::Error>().map(|io| io.kind()),
    });
    match io_kind {
        Some(kind) => Error::io(path, std::io::Error::new(kind, message)),
        None => otherwise(message),
    }
}

/// The engine's `Settings` from keyword settings as a JSON object: the engine's defaults (as `render`'s),
/// each given field over them through the engine's own serde mapping, then its range checks. A field
/// whose value does not fit its type is named in the error.
fn settings_from_json(py: Python<'_>, json: &str) -> PyResult<Settings> {
    let given: serde_json::Map<String, serde_json::Value> =
        serde_json::from_str(json).map_err(|e| PyValueError::new_err(format!("settings: {e}")))?;
    let defaults = match serde_json::to_value(Settings::default()) {
        Ok(serde_json::Value::Object(m)) => m,
        _ => return Err(PyValueError::new_err("settings: the defaults are not a JSON object")),
    };
    let known: Vec<String> = defaults.keys().cloned().collect();
    let mut merged = defaults.clone();
    for (name, mut value) in given {
        let field = FLAG_NAMES
            .iter()
            .find(|(flag, _)| *flag == name)
            .map_or(name.as_str(), |(_, field)| *field)
            .to_string();
        if !defaults.contains_key(&field) {
            return Err(unknown_setting(py, &name, &known));
        }
        if OFF_MEANS_NONE.contains(&field.as_str()) && value.as_str().is_some_and(|s| s.eq_ignore_ascii_case("off")) {
            value = serde_json::Value::Null;
        }
        // This field alone over the defaults: a value of the wrong type is named here.
        let mut one = defaults.clone();
        one.insert(field.clone(), value.clone());
        if let Err(e) = serde_json::from_value::<Settings>(serde_json::Value::Object(one)) {
            return Err(settings_error(py, &name, format!("{value}: {e}")));
        }
        merged.insert(field, value);
    }
    let settings: Settings = serde_json::from_value(serde_json::Value::Object(merged))
        .map_err(|e| PyValueError::new_err(format!("settings: {e}")))?;
    settings.validate().or_raise(py)?;
    Ok(settings)
}

/// How to open the device, as `render`'s `--device`, `--validate` and `--pipeline-cache` flags (and
/// their environment variables) say.
fn device_options(device: Option<String>, validation: bool, pipeline_cache: Option<PathBuf>) -> ContextOptions {
    ContextOptions {
        validation,
        device: device.or_else(|| std::env::var("PPM_VK_DEVICE").ok()),
        pipeline_cache: pipeline_cache
            .or_else(|| std::env::var_os("PPM_VK_CACHE_DIR").map(PathBuf::from))
            .or_else(ContextOptions::default_pipeline_cache),
        present: None,
    }
}

/// An image as a float32 array of shape (height, width, 3).
fn to_array<'py>(py: Python<'py>, image: RgbImage) -> PyResult<Bound<'py, PyAny>> {
    let shape = [image.height as usize, image.width as usize, 3];
    let flat: Vec<f32> = image.pixels.into_iter().flatten().collect();
    Ok(PyArray1::from_vec(py, flat).reshape(shape)?.into_any())
}

/// A pass's statistics as a dict (the Python layer makes a `PassStats` of it).
fn stats_dict<'py>(py: Python<'py>, s: &PassStats) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("index", s.index)?;
    d.set_item("photons", s.photons)?;
    d.set_item("emitted_total", s.emitted_total)?;
    d.set_item("records", s.records)?;
    d.set_item("batches", s.batches)?;
    d.set_item("photon_paths_cut", s.photon_paths_cut)?;
    d.set_item("eye_paths_cut", s.eye_paths_cut)?;
    d.set_item("photons_capped", s.photons_capped)?;
    d.set_item("radius_max", s.radius_max)?;
    d.set_item("cell_size", s.cell_size)?;
    d.set_item("wall_ms", s.wall_ms)?;
    let stages = PyDict::new(py);
    for t in &s.stages {
        let sum = stages.get_item(t.name)?.map_or(Ok(0.0), |v| v.extract::<f64>())?;
        stages.set_item(t.name, sum + t.duration_ms)?;
    }
    d.set_item("stage_ms", stages)?;
    Ok(d)
}

/// A render in progress on one device. Every method that works on the device releases the GIL; `cancel`
/// may be called from any thread while `pass_` runs.
#[pyclass(module = "ppm_vk._native", frozen)]
struct Renderer {
    /// The renderer, locked by whichever method uses it (with the GIL released): `cancel` never takes it.
    inner: Mutex<ppm_vk_engine::Renderer>,
    cancel: CancelToken,
    scene_name: String,
}

impl Renderer {
    /// `f` on the renderer, with the GIL released while it waits for the lock and works: a pass in flight
    /// on another thread never holds up this interpreter's other threads.
    fn with<T: Send>(
        &self,
        py: Python<'_>,
        f: impl FnOnce(&mut ppm_vk_engine::Renderer) -> Result<T, Error> + Send,
    ) -> PyResult<T> {
        py.detach(|| {
            let mut r = self.inner.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
            f(&mut r)
        })
        .or_raise(py)
    }
}

#[pymethods]
impl Renderer {
    /// Loads `scene` (with `defines` for a Mitsuba scene's `$name`s), opens the device (`device`: its
    /// name or index, validation, the pipeline cache's directory) and sets the render up (kernels, BVH,
    /// first eye pass, probe pass), or continues the checkpoint `resume` of the same scene and settings.
    #[new]
    #[pyo3(signature = (scene, defines, settings_json, resolution, device, resume))]
    fn new(
        py: Python<'_>,
        scene: PathBuf,
        defines: Vec<(String, String)>,
        settings_json: &str,
        resolution: Option<(u32, u32)>,
        device: (Option<String>, bool, Option<PathBuf>),
        resume: Option<PathBuf>,
    ) -> PyResult<Renderer> {
        let settings = settings_from_json(py, settings_json)?;
        if let Some((w, h)) = resolution {
            let max = ppm_vk_engine::scene::MAX_RESOLUTION;
            if w == 0 || h == 0 || w > max || h > max {
                let message = format!("({w}, {h}) out of range: width and height must be in 1..={max}");
                return Err(settings_error(py, "resolution", message));
            }
        }
        let (renderer, scene_name) = py
            .detach(|| -> Result<_, Error> {
                let scene = Scene::load_with(&scene, &defines)?;
                let scene = match resolution {
                    Some((w, h)) => scene.with_resolution(w, h),
                    None => scene,
                };
                // A checkpoint that does not fit is refused before the device opens.
                let resumed = match &resume {
                    Some(path) => Some(
                        Checkpoint::load_for(path, &scene, &settings, BUILD)
                            .map_err(|e| checkpoint_error(path, e, |message| Error::Checkpoint { message }))?,
                    ),
                    None => None,
                };
                // Built here: the options hold a display handle, which may not cross threads.
                let (device, validation, pipeline_cache) = device;
                let ctx = open_device(&device_options(device, validation, pipeline_cache))?;
                let renderer = match &resumed {
                    Some(c) => ppm_vk_engine::Renderer::resume(&ctx, &scene, settings, c, BUILD)?,
                    None => ppm_vk_engine::Renderer::new(&ctx, &scene, settings)?,
                };
                Ok((renderer, scene.name.clone()))
            })
            .or_raise(py)?;
        let cancel = renderer.cancel_token();
        Ok(Renderer {
            inner: Mutex::new(renderer),
            cancel,
            scene_name,
        })
    }

    /// One photon pass; its statistics as a dict. A `cancel()` during it raises `CancelledError` and
    /// leaves the render as the passes before it left it (the next call goes on).
    fn pass_<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let result = self.with(py, |r| r.pass());
        if result.is_err() {
            // A cancel ends this pass, not the render.
            self.cancel.reset();
        }
        stats_dict(py, &result?)
    }

    /// Cancels the pass in flight (or the next one) from any thread, without waiting for it.
    fn cancel(&self) {
        self.cancel.cancel();
    }

    /// The current image: float32, shape (height, width, 3), linear RGB.
    fn image<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let image = self.with(py, |r| r.image())?;
        to_array(py, image)
    }

    /// Writes the current image: .exr (linear) or .png (tone-mapped sRGB), as `render --out` does.
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        self.with(py, |r| r.image()?.save(&path))
    }

    /// Saves the whole state of the render to `path`, for `Renderer(..., resume=path)` (or `ppm-vk render
    /// --resume` of the same build) to continue bit for bit.
    fn checkpoint(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        self.with(py, |r| {
            let saved = r.checkpoint(BUILD)?.save(&path);
            saved.map_err(|e| checkpoint_error(&path, e, |message| Error::Checkpoint { message }))
        })
    }

    /// Moves the camera (the fields given; the others stay) and starts the render again from its first pass.
    #[pyo3(signature = (eye=None, look_at=None, up=None, vfov=None))]
    fn set_camera(
        &self,
        py: Python<'_>,
        eye: Option<[f32; 3]>,
        look_at: Option<[f32; 3]>,
        up: Option<[f32; 3]>,
        vfov: Option<f32>,
    ) -> PyResult<()> {
        self.with(py, |r| {
            let mut camera = *r.camera();
            camera.eye = eye.map_or(camera.eye, Into::into);
            camera.look_at = look_at.map_or(camera.look_at, Into::into);
            camera.up = up.map_or(camera.up, Into::into);
            camera.vfov_deg = vfov.unwrap_or(camera.vfov_deg);
            r.set_camera(&camera)
        })
    }

    /// The camera as a dict: eye, look_at, up, vfov (degrees), width, height.
    fn camera<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let c = self.with(py, |r| Ok(*r.camera()))?;
        let d = PyDict::new(py);
        d.set_item("eye", c.eye.to_array())?;
        d.set_item("look_at", c.look_at.to_array())?;
        d.set_item("up", c.up.to_array())?;
        d.set_item("vfov", c.vfov_deg)?;
        d.set_item("width", c.width)?;
        d.set_item("height", c.height)?;
        Ok(d)
    }

    /// Photon passes done.
    #[getter]
    fn passes(&self, py: Python<'_>) -> PyResult<u64> {
        self.with(py, |r| Ok(r.passes()))
    }

    /// The settings in force, as JSON (the engine's field names).
    fn settings_json(&self, py: Python<'_>) -> PyResult<String> {
        let settings = self.with(py, |r| Ok(r.settings().clone()))?;
        serde_json::to_string(&settings).map_err(|e| PyValueError::new_err(e.to_string()))
    }

    /// The scene's name.
    #[getter]
    fn scene_name(&self) -> &str {
        &self.scene_name
    }

    /// The device's name and kind.
    #[getter]
    fn device(&self, py: Python<'_>) -> PyResult<String> {
        self.with(py, |r| {
            let info = r.context().info();
            Ok(format!("{} ({}, {})", info.name, info.kind, info.driver))
        })
    }

    /// The validation layer's messages so far (empty unless opened with `validation=True`).
    fn validation_messages(&self, py: Python<'_>) -> PyResult<Vec<String>> {
        self.with(py, |r| Ok(r.context().validation_messages()))
    }
}

/// Reads an EXR image: float32, shape (height, width, 3).
#[pyfunction]
fn read_exr<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyAny>> {
    let image = py.detach(|| RgbImage::load_exr(&path)).or_raise(py)?;
    to_array(py, image)
}

/// `image` (float32, shape (height, width, 3), linear) as the PNG `render` writes: scaled by 2^exposure,
/// clamped, sRGB-encoded to 8 bits.
#[pyfunction]
#[pyo3(signature = (image, exposure=0.0))]
fn encode_png<'py>(py: Python<'py>, image: PyReadonlyArray3<'py, f32>, exposure: f32) -> PyResult<Bound<'py, PyBytes>> {
    let shape = image.shape();
    if shape[2] != 3 {
        return Err(PyValueError::new_err(format!(
            "expected an array of shape (height, width, 3), got {shape:?}"
        )));
    }
    let (height, width) = (shape[0] as u32, shape[1] as u32);
    let data = image.as_array();
    let pixels = data.rows().into_iter().map(|p| [p[0], p[1], p[2]]).collect();
    let rgb = RgbImage { width, height, pixels };
    let png = py.detach(|| rgb.encode_png(exposure)).or_raise(py)?;
    Ok(PyBytes::new(py, &png))
}

/// The names of the settings (the engine's fields) and their defaults, as JSON.
#[pyfunction]
fn default_settings_json() -> PyResult<String> {
    serde_json::to_string(&Settings::default()).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// A part that cannot be merged (refused, or damaged): `ppm_vk.MergeError` with the engine's message.
fn merge_error(py: Python<'_>, e: anyhow::Error) -> PyErr {
    raise(py, "MergeError", format!("{e:#}"), |_| Ok(()))
}

/// A part's load or save failure: `IoError` where the file could not be read or written, else (damaged,
/// not a part) `MergeError`.
fn part_file_error(py: Python<'_>, path: &Path, e: anyhow::Error) -> PyErr {
    match checkpoint_error(path, e, |message| Error::Checkpoint { message }) {
        Error::Checkpoint { message } => raise(py, "MergeError", message, |_| Ok(())),
        other => to_py(py, other),
    }
}

/// One worker's share of a render (`ppm_vk.render_part`): per pixel sums that `merge` combines. Pickles
/// as its file's bytes, so it travels between processes (Ray tasks) as it would in a file.
#[pyclass(module = "ppm_vk._native", frozen)]
struct Part {
    inner: distributed::Part,
}

#[pymethods]
impl Part {
    /// The part as the bytes of its file (`ppm-vk merge` reads them as a `.part`).
    fn to_bytes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        let bytes = py.detach(|| self.inner.to_bytes()).map_err(|e| merge_error(py, e))?;
        Ok(PyBytes::new(py, &bytes))
    }

    /// Writes the part atomically to `path`.
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        py.detach(|| self.inner.save(&path))
            .map_err(|e| part_file_error(py, &path, e))
    }

    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyBytes>,))> {
        let parse = py.import("ppm_vk._native")?.getattr("part_from_bytes")?;
        Ok((parse, (self.to_bytes(py)?,)))
    }

    /// Worker (from 0), workers, this worker's passes, method, scene name, build.
    #[getter]
    fn worker(&self) -> u32 {
        self.inner.header.job.worker
    }
    #[getter]
    fn of(&self) -> u32 {
        self.inner.header.job.of
    }
    #[getter]
    fn passes(&self) -> u64 {
        self.inner.header.job.passes
    }
    #[getter]
    fn method(&self) -> &'static str {
        method_name(self.inner.header.job.method)
    }
    #[getter]
    fn scene_name(&self) -> &str {
        &self.inner.header.scene_name
    }
    #[getter]
    fn build(&self) -> &str {
        &self.inner.header.build
    }
}

fn method_name(method: Method) -> &'static str {
    match method {
        Method::Probabilistic => "probabilistic",
        Method::Independent => "independent",
    }
}

/// A part from its file's bytes, refusing damaged ones (`MergeError`).
#[pyfunction]
fn part_from_bytes(py: Python<'_>, bytes: &[u8]) -> PyResult<Part> {
    let inner = py
        .detach(|| distributed::Part::parse(bytes))
        .map_err(|e| merge_error(py, e))?;
    Ok(Part { inner })
}

/// A part from its file (`render --worker K --of N` writes them); `IoError` if unreadable, `MergeError`
/// if damaged.
#[pyfunction]
fn load_part(py: Python<'_>, path: PathBuf) -> PyResult<Part> {
    let inner = py
        .detach(|| distributed::Part::load(&path))
        .map_err(|e| part_file_error(py, &path, e))?;
    Ok(Part { inner })
}

/// Renders a worker's share of the scene (`job`: method, worker, workers, passes of its own), on the
/// device `device` opens, with the GIL released.
#[pyfunction]
#[pyo3(signature = (scene, defines, settings_json, resolution, device, job))]
fn render_part(
    py: Python<'_>,
    scene: PathBuf,
    defines: Vec<(String, String)>,
    settings_json: &str,
    resolution: Option<(u32, u32)>,
    device: (Option<String>, bool, Option<PathBuf>),
    job: (String, u32, u32, u64),
) -> PyResult<Part> {
    let (method, worker, of, passes) = job;
    let settings = settings_from_json(py, settings_json)?;
    let method = match method.as_str() {
        "probabilistic" => Method::Probabilistic,
        "independent" => Method::Independent,
        _ => {
            let message = format!("{method:?}: expected \"probabilistic\" or \"independent\"");
            return Err(settings_error(py, "method", message));
        }
    };
    let job = Job {
        method,
        worker,
        of,
        passes,
    };
    // Refused before the scene loads and the device opens.
    job.validate().or_raise(py)?;
    let inner = py
        .detach(|| -> Result<_, Error> {
            let scene = Scene::load_with(&scene, &defines)?;
            let scene = match resolution {
                Some((w, h)) => scene.with_resolution(w, h),
                None => scene,
            };
            let (device, validation, pipeline_cache) = device;
            let ctx = open_device(&device_options(device, validation, pipeline_cache))?;
            distributed::render_part(&ctx, &scene, &settings, &job, BUILD, None, |_| {})
        })
        .or_raise(py)?;
    Ok(Part { inner })
}

/// Merges parts of one render (in any order) into its image; also what was merged, as a dict. Refused
/// parts (of other scenes, settings, builds, shares; a worker twice) are a `MergeError`.
#[pyfunction]
fn merge<'py>(py: Python<'py>, parts: Vec<PyRef<'py, Part>>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyDict>)> {
    // The sums are cloned once so that the merge runs without the GIL (a part may be large).
    let owned: Vec<distributed::Part> = parts.iter().map(|p| p.inner.clone()).collect();
    let (image, info) = py
        .detach(|| distributed::merge(&owned))
        .map_err(|e| merge_error(py, e))?;
    let d = PyDict::new(py);
    d.set_item("scene_name", info.scene_name)?;
    d.set_item("method", method_name(info.method))?;
    d.set_item("of", info.of)?;
    d.set_item("workers", info.workers)?;
    d.set_item("missing", info.missing)?;
    d.set_item("passes", info.passes)?;
    d.set_item("photons", info.photons)?;
    Ok((to_array(py, image)?, d))
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Renderer>()?;
    m.add_class::<Part>()?;
    m.add_function(wrap_pyfunction!(part_from_bytes, m)?)?;
    m.add_function(wrap_pyfunction!(load_part, m)?)?;
    m.add_function(wrap_pyfunction!(render_part, m)?)?;
    m.add_function(wrap_pyfunction!(merge, m)?)?;
    m.add_function(wrap_pyfunction!(read_exr, m)?)?;
    m.add_function(wrap_pyfunction!(encode_png, m)?)?;
    m.add_function(wrap_pyfunction!(default_settings_json, m)?)?;
    Ok(())
}
