//! Instance, physical-device choice, logical device, queue, allocator and the validation messenger.

use std::ffi::{c_void, CStr, CString};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use anyhow::{anyhow, bail, Context as _, Result};
use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};

use crate::pipeline_cache::{CacheKey, DiskCache};

/// How to open a device.
#[derive(Clone, Debug, Default)]
pub struct ContextOptions {
    /// Enable `VK_LAYER_KHRONOS_validation` and collect its messages (see [`Context::validation_messages`]).
    pub validation: bool,
    /// Choose a device by index (as `ppm-vk devices` lists them) or by a case-insensitive substring of its
    /// name. `None` prefers a discrete GPU, then an integrated one, then any (lavapipe).
    pub device: Option<String>,
    /// Directory of the pipeline cache kept between runs (one file per device; see
    /// [`Context::save_pipeline_cache`]). `None`: no cache, every pipeline is compiled from scratch.
    pub pipeline_cache: Option<PathBuf>,
    /// Open the device for presenting to windows of this display too (a viewer): the instance gets the
    /// display's surface extensions and the device VK_KHR_swapchain (see [`crate::Swapchain`]). `None`:
    /// compute only.
    pub present: Option<raw_window_handle::RawDisplayHandle>,
}

impl ContextOptions {
    /// Where the pipeline cache lives by default: `$XDG_CACHE_HOME/ppm-vk`, else `~/.cache/ppm-vk` (the XDG
    /// base directory rules); `None` without either. The binary and the Python package share it.
    pub fn default_pipeline_cache() -> Option<PathBuf> {
        let xdg = std::env::var_os("XDG_CACHE_HOME")
            .map(PathBuf::from)
            .filter(|p| p.is_absolute());
        let home = || {
            std::env::var_os("HOME")
                .map(|h| PathBuf::from(h).join(".cache"))
                .filter(|p| p.is_absolute())
        };
        xdg.or_else(home).map(|d| d.join("ppm-vk"))
    }
}

/// What a physical device is, for listings and run reports.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    pub index: usize,
    pub name: String,
    pub kind: String,
    pub api_version: String,
    pub driver: String,
    /// Loop iterations a SIMD group of a shader may run in all, where the driver ends loops silently past
    /// a limit: lavapipe (llvmpipe) stops every loop after 65535 (gallivm's LP_MAX_TGSI_LOOP_ITERATIONS).
    /// `None`: no such limit is known for this driver.
    pub loop_budget: Option<u32>,
    /// Bytes of its largest device-local memory heap (what buffers can take in all).
    pub memory_bytes: u64,
    /// Whether it has everything the kernels need; if not, what is missing.
    pub missing: Vec<String>,
}

/// Device memory of one context, from its allocator.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MemoryUsage {
    /// Bytes the live buffers occupy.
    pub in_use_bytes: u64,
    /// Bytes of device memory the allocator holds in blocks (what the device has given it).
    pub reserved_bytes: u64,
    /// The most `reserved_bytes` has been since the context opened or the last reset.
    pub peak_reserved_bytes: u64,
}

/// State shared by every object made from a [`Context`], so RAII handles can free themselves.
pub(crate) struct Shared {
    pub(crate) device: ash::Device,
    pub(crate) allocator: Mutex<Option<Allocator>>,
    /// The most device memory the allocator has held in blocks at once, in bytes (since the last reset).
    pub(crate) peak_reserved: std::sync::atomic::AtomicU64,
    pub(crate) push_descriptor: ash::khr::push_descriptor::Device,
    pub(crate) validation: Option<Arc<Mutex<Vec<String>>>>,
}

/// An open Vulkan device with one compute queue. Cheap to clone (shared inside).
#[derive(Clone)]
pub struct Context {
    inner: Arc<Inner>,
}

struct Inner {
    // Field order is drop order: the device-side state goes before the instance.
    shared: Arc<Shared>,
    queue: vk::Queue,
    queue_family: u32,
    physical_device: vk::PhysicalDevice,
    /// Whether the instance and device were made for presenting ([`ContextOptions::present`]).
    presents: bool,
    command_pool: Mutex<vk::CommandPool>,
    info: DeviceInfo,
    limits: vk::PhysicalDeviceLimits,
    timestamp_valid_bits: u32,
    /// Present when VK_EXT_debug_utils is (always with validation; without it when the driver offers it).
    debug_names: Option<ash::ext::debug_utils::Device>,
    pipeline_cache: Option<DiskCache>,
    /// The directory of the pipeline cache ([`ContextOptions::pipeline_cache`]).
    cache_dir: Option<PathBuf>,
    debug: Option<Messenger>,
    instance: ash::Instance,
    _entry: ash::Entry,
}

/// The validation messenger: its loader, its handle, and the messages its callback collects (boxed so the
/// callback's user-data pointer stays put).
type Messenger = (
    ash::ext::debug_utils::Instance,
    vk::DebugUtilsMessengerEXT,
    Box<Arc<Mutex<Vec<String>>>>,
);

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    // Info and verbose messages are the loader chatting; warnings and errors are bugs.
    if severity
        .intersects(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR)
    {
        let text = if data.is_null() || (*data).p_message.is_null() {
            "(no message)".to_string()
        } else {
            CStr::from_ptr((*data).p_message).to_string_lossy().into_owned()
        };
        let sink = &*(user as *const Arc<Mutex<Vec<String>>>);
        if let Ok(mut v) = sink.lock() {
            v.push(format!("{severity:?}: {text}"));
        }
    }
    vk::FALSE
}

fn api_string(v: u32) -> String {
    format!(
        "{}.{}.{}",
        vk::api_version_major(v),
        vk::api_version_minor(v),
        vk::api_version_patch(v)
    )
}

/// What the kernels need from a device, checked before it is chosen.
fn missing_features(instance: &ash::Instance, pd: vk::PhysicalDevice) -> Vec<String> {
    let mut missing = Vec::new();
    let props = unsafe { instance.get_physical_device_properties(pd) };
    if props.api_version < vk::API_VERSION_1_2 {
        missing.push(format!("Vulkan 1.2 (device has {})", api_string(props.api_version)));
    }
    let mut v12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut v12);
    unsafe { instance.get_physical_device_features2(pd, &mut f2) };
    let f = f2.features;
    if f.shader_int64 == vk::FALSE {
        missing.push("shaderInt64 (64-bit photon counts and fixed-point flux sums)".into());
    }
    if f.shader_float64 == vk::FALSE {
        missing.push("shaderFloat64 (per-hit-point statistics N and tau in double)".into());
    }
    if v12.host_query_reset == vk::FALSE {
        missing.push("hostQueryReset".into());
    }
    let exts = unsafe { instance.enumerate_device_extension_properties(pd) }.unwrap_or_default();
    let has_push = exts.iter().any(|e| {
        e.extension_name_as_c_str()
            .map(|n| n == ash::khr::push_descriptor::NAME)
            .unwrap_or(false)
    });
    if !has_push {
        missing.push("VK_KHR_push_descriptor".into());
    }
    let queues = unsafe { instance.get_physical_device_queue_family_properties(pd) };
    if !queues
        .iter()
        .any(|q| q.queue_flags.contains(vk::QueueFlags::COMPUTE) && q.timestamp_valid_bits > 0)
    {
        missing.push("a compute queue with timestamps".into());
    }
    missing
}

/// lavapipe's limit on the loop iterations of one SIMD group (LP_MAX_TGSI_LOOP_ITERATIONS in Mesa's gallivm).
pub const LAVAPIPE_LOOP_BUDGET: u32 = 65535;

fn describe(instance: &ash::Instance, index: usize, pd: vk::PhysicalDevice) -> DeviceInfo {
    let props = unsafe { instance.get_physical_device_properties(pd) };
    let name = props
        .device_name_as_c_str()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut driver_props = vk::PhysicalDeviceDriverProperties::default();
    let mut p2 = vk::PhysicalDeviceProperties2::default().push_next(&mut driver_props);
    unsafe { instance.get_physical_device_properties2(pd, &mut p2) };
    let driver = format!(
        "{} {}",
        driver_props
            .driver_name_as_c_str()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
        driver_props
            .driver_info_as_c_str()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    );
    let kind = match props.device_type {
        vk::PhysicalDeviceType::DISCRETE_GPU => "discrete GPU",
        vk::PhysicalDeviceType::INTEGRATED_GPU => "integrated GPU",
        vk::PhysicalDeviceType::VIRTUAL_GPU => "virtual GPU",
        vk::PhysicalDeviceType::CPU => "CPU",
        _ => "other",
    };
    let loop_budget = (driver_props.driver_id == vk::DriverId::MESA_LLVMPIPE).then_some(LAVAPIPE_LOOP_BUDGET);
    let memory = unsafe { instance.get_physical_device_memory_properties(pd) };
    let memory_bytes = memory.memory_heaps[..memory.memory_heap_count as usize]
        .iter()
        .filter(|h| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL))
        .map(|h| h.size)
        .max()
        .unwrap_or(0);
    DeviceInfo {
        index,
        name,
        kind: kind.into(),
        api_version: api_string(props.api_version),
        driver: driver.trim().to_string(),
        loop_budget,
        memory_bytes,
        missing: missing_features(instance, pd),
    }
}

fn load_entry() -> Result<ash::Entry> {
    unsafe { ash::Entry::load() }.map_err(|e| {
        anyhow!(
            "cannot load the Vulkan loader (libvulkan.so.1): {e}. On Debian/Ubuntu: \
             `sudo apt-get install libvulkan1 mesa-vulkan-drivers` (or run scripts/setup.sh)"
        )
    })
}

/// An instance, with the validation layer if asked for, and with VK_EXT_debug_utils (object names, the
/// validation messenger) whenever the layer or the driver offers it. Returns whether debug_utils is on.
/// With `present`, also the surface extensions that display needs.
fn create_instance(
    entry: &ash::Entry,
    validation: bool,
    present: Option<raw_window_handle::RawDisplayHandle>,
) -> Result<(ash::Instance, bool)> {
    let app = vk::ApplicationInfo::default()
        .application_name(c"ppm-vk")
        .engine_name(c"ppm-vk")
        .api_version(vk::API_VERSION_1_2);
    let mut layers = Vec::new();
    let mut exts = Vec::new();
    if validation {
        let available = unsafe { entry.enumerate_instance_layer_properties() }.context("listing Vulkan layers")?;
        let found = available
            .iter()
            .any(|l| l.layer_name_as_c_str().map(|n| n == VALIDATION_LAYER).unwrap_or(false));
        if !found {
            bail!(
                "validation was requested but VK_LAYER_KHRONOS_validation is not installed. On Debian/Ubuntu: \
                 `sudo apt-get install vulkan-validationlayers` (or run scripts/setup.sh)"
            );
        }
        layers.push(VALIDATION_LAYER.as_ptr());
    }
    // The validation layer provides debug_utils itself; the loader lists what the driver and implicit layers
    // offer (Mesa's drivers, lavapipe included, do).
    let offered =
        unsafe { entry.enumerate_instance_extension_properties(None) }.context("listing Vulkan instance extensions")?;
    let debug_utils = validation
        || offered.iter().any(|e| {
            e.extension_name_as_c_str()
                .map(|n| n == ash::ext::debug_utils::NAME)
                .unwrap_or(false)
        });
    if debug_utils {
        exts.push(ash::ext::debug_utils::NAME.as_ptr());
    }
    if let Some(display) = present {
        let needed = ash_window::enumerate_required_extensions(display)
            .context("this display has no Vulkan surface extension (only X11 and Wayland are supported)")?;
        for &name in needed {
            let name_c = unsafe { CStr::from_ptr(name) };
            if !offered
                .iter()
                .any(|e| e.extension_name_as_c_str().is_ok_and(|n| n == name_c))
            {
                bail!(
                    "the Vulkan loader offers no {} here, so nothing can be shown in a window",
                    name_c.to_string_lossy()
                );
            }
        }
        exts.extend_from_slice(needed);
    }
    let info = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_layer_names(&layers)
        .enabled_extension_names(&exts);
    let instance = unsafe { entry.create_instance(&info, None) }
        .context("vkCreateInstance failed (is a Vulkan driver installed?)")?;
    Ok((instance, debug_utils))
}

impl Context {
    /// Every physical device the loader sees, with what each lacks for ppm-vk.
    pub fn list_devices() -> Result<Vec<DeviceInfo>> {
        let entry = load_entry()?;
        let (instance, _) = create_instance(&entry, false, None)?;
        let pds = unsafe { instance.enumerate_physical_devices() }.context("enumerating Vulkan devices");
        let out = pds.map(|pds| {
            pds.iter()
                .enumerate()
                .map(|(i, &pd)| describe(&instance, i, pd))
                .collect()
        });
        unsafe { instance.destroy_instance(None) };
        out
    }

    /// Opens a device: by `options.device`, else the first suitable discrete GPU,
    /// then integrated, then any (lavapipe).
    pub fn new(options: &ContextOptions) -> Result<Context> {
        let entry = load_entry()?;
        let (instance, debug_utils) = create_instance(&entry, options.validation, options.present)?;
        // From here on, failure must destroy the instance: wrap the rest.
        match Self::open(entry.clone(), instance.clone(), debug_utils, options) {
            Ok(ctx) => Ok(ctx),
            Err(e) => {
                unsafe { instance.destroy_instance(None) };
                Err(e)
            }
        }
    }

    fn open(
        entry: ash::Entry,
        instance: ash::Instance,
        debug_utils: bool,
        options: &ContextOptions,
    ) -> Result<Context> {
        let sink = Arc::new(Mutex::new(Vec::<String>::new()));
        let debug = if options.validation {
            let loader = ash::ext::debug_utils::Instance::new(&entry, &instance);
            let user = Box::new(sink.clone());
            let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
                .message_severity(
                    vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
                )
                .message_type(
                    vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                        | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                        | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
                )
                .pfn_user_callback(Some(debug_callback))
                .user_data(&*user as *const Arc<Mutex<Vec<String>>> as *mut c_void);
            let messenger = unsafe { loader.create_debug_utils_messenger(&info, None) }
                .context("creating the validation messenger")?;
            Some((loader, messenger, user))
        } else {
            None
        };

        let pds = unsafe { instance.enumerate_physical_devices() }.context("enumerating Vulkan devices")?;
        if pds.is_empty() {
            bail!("no Vulkan device found. On Debian/Ubuntu: `sudo apt-get install mesa-vulkan-drivers` for lavapipe (CPU)");
        }
        let infos: Vec<DeviceInfo> = pds
            .iter()
            .enumerate()
            .map(|(i, &pd)| describe(&instance, i, pd))
            .collect();
        let wanted = options.device.clone().filter(|s| !s.is_empty());
        let chosen = match wanted {
            Some(w) => {
                let hit = match w.parse::<usize>() {
                    Ok(i) => infos.get(i),
                    Err(_) => infos.iter().find(|d| d.name.to_lowercase().contains(&w.to_lowercase())),
                };
                let d =
                    hit.ok_or_else(|| anyhow!("no Vulkan device matches {w:?}; devices: {}", list_names(&infos)))?;
                if !d.missing.is_empty() {
                    bail!(
                        "device {} ({}) lacks what ppm-vk needs: {}",
                        d.index,
                        d.name,
                        d.missing.join(", ")
                    );
                }
                d.clone()
            }
            None => {
                let rank = |d: &DeviceInfo| match d.kind.as_str() {
                    "discrete GPU" => 0,
                    "integrated GPU" => 1,
                    "virtual GPU" => 2,
                    _ => 3,
                };
                let mut ok: Vec<&DeviceInfo> = infos.iter().filter(|d| d.missing.is_empty()).collect();
                ok.sort_by_key(|d| (rank(d), d.index));
                match ok.first() {
                    Some(d) => (*d).clone(),
                    None => bail!(
                        "no Vulkan device has what ppm-vk needs: {}",
                        infos
                            .iter()
                            .map(|d| format!("{} lacks {}", d.name, d.missing.join(", ")))
                            .collect::<Vec<_>>()
                            .join("; ")
                    ),
                }
            }
        };
        let pd = pds[chosen.index];
        let props = unsafe { instance.get_physical_device_properties(pd) };
        let queues = unsafe { instance.get_physical_device_queue_family_properties(pd) };
        let (queue_family, qprops) = queues
            .iter()
            .enumerate()
            .find(|(_, q)| q.queue_flags.contains(vk::QueueFlags::COMPUTE) && q.timestamp_valid_bits > 0)
            .map(|(i, q)| (i as u32, *q))
            .ok_or_else(|| anyhow!("device {} has no compute queue with timestamps", chosen.name))?;

        let priorities = [1.0f32];
        let queue_info = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(queue_family)
            .queue_priorities(&priorities)];
        let features = vk::PhysicalDeviceFeatures::default()
            .shader_int64(true)
            .shader_float64(true);
        let mut v12 = vk::PhysicalDeviceVulkan12Features::default().host_query_reset(true);
        let mut exts = vec![ash::khr::push_descriptor::NAME.as_ptr()];
        if options.present.is_some() {
            let offered = unsafe { instance.enumerate_device_extension_properties(pd) }
                .context("listing the device's extensions")?;
            let has = offered.iter().any(|e| {
                e.extension_name_as_c_str()
                    .is_ok_and(|n| n == ash::khr::swapchain::NAME)
            });
            if !has {
                bail!(
                    "device {} cannot present to a window (no VK_KHR_swapchain)",
                    chosen.name
                );
            }
            exts.push(ash::khr::swapchain::NAME.as_ptr());
        }
        let info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queue_info)
            .enabled_features(&features)
            .enabled_extension_names(&exts)
            .push_next(&mut v12);
        let device = unsafe { instance.create_device(pd, &info, None) }
            .with_context(|| format!("creating a logical device on {}", chosen.name))?;
        let queue = unsafe { device.get_device_queue(queue_family, 0) };
        let pipeline_cache = match &options.pipeline_cache {
            Some(dir) => match DiskCache::open(&device, dir, CacheKey::of(&props)) {
                Ok(c) => Some(c),
                Err(e) => {
                    unsafe { device.destroy_device(None) };
                    return Err(e);
                }
            },
            None => None,
        };
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device: pd,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        })
        .context("creating the GPU memory allocator")?;
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        let command_pool =
            unsafe { device.create_command_pool(&pool_info, None) }.context("creating a command pool")?;
        let push_descriptor = ash::khr::push_descriptor::Device::new(&instance, &device);
        let debug_names = debug_utils.then(|| ash::ext::debug_utils::Device::new(&instance, &device));
        let shared = Arc::new(Shared {
            device,
            allocator: Mutex::new(Some(allocator)),
            peak_reserved: Default::default(),
            push_descriptor,
            validation: options.validation.then(|| sink.clone()),
        });
        let ctx = Context {
            inner: Arc::new(Inner {
                shared,
                queue,
                queue_family,
                physical_device: pd,
                presents: options.present.is_some(),
                command_pool: Mutex::new(command_pool),
                info: chosen,
                limits: props.limits,
                timestamp_valid_bits: qprops.timestamp_valid_bits,
                debug_names,
                pipeline_cache,
                cache_dir: options.pipeline_cache.clone(),
                debug,
                instance,
                _entry: entry,
            }),
        };
        ctx.name_object(command_pool, "ppm-vk command pool");
        if let Some(c) = &ctx.inner.pipeline_cache {
            ctx.name_object(c.raw, "ppm-vk pipeline cache");
        }
        Ok(ctx)
    }

    /// Gives a Vulkan object a name that validation messages and debuggers (RenderDoc, Nsight) show. Does
    /// nothing when VK_EXT_debug_utils is not on. A NUL inside `name` (which C strings cannot hold) becomes
    /// U+FFFD. Naming can fail only for want of host memory, and a missing name harms nothing: that is
    /// ignored.
    pub fn name_object<H: vk::Handle>(&self, handle: H, name: &str) {
        let Some(names) = &self.inner.debug_names else { return };
        let name = debug_name(name);
        let info = vk::DebugUtilsObjectNameInfoEXT::default()
            .object_handle(handle)
            .object_name(&name);
        let _ = unsafe { names.set_debug_utils_object_name(&info) };
    }

    /// Whether [`Context::name_object`] reaches Vulkan (VK_EXT_debug_utils is on).
    pub fn names_objects(&self) -> bool {
        self.inner.debug_names.is_some()
    }

    /// The pipeline cache every pipeline of this context is created with (null when the cache is off).
    pub(crate) fn pipeline_cache(&self) -> vk::PipelineCache {
        self.inner
            .pipeline_cache
            .as_ref()
            .map_or(vk::PipelineCache::null(), |c| c.raw)
    }

    /// Why the pipeline cache file was not used (damaged, another driver, unreadable), in one line; `None`
    /// when it was used, was absent, or the cache is off.
    pub fn pipeline_cache_note(&self) -> Option<&str> {
        self.inner.pipeline_cache.as_ref().and_then(|c| c.note.as_deref())
    }

    /// The directory this context keeps its pipeline cache in (`None`: the cache is off). Other caches of
    /// compiled kernels (the run-time specialised SPIR-V) live beside it and are off with it.
    pub fn cache_dir(&self) -> Option<&Path> {
        self.inner.cache_dir.as_deref()
    }

    /// Bytes of pipeline data the cache file gave this context (0 when the cache is off, the file absent or
    /// not used).
    pub fn pipeline_cache_loaded_bytes(&self) -> usize {
        self.inner.pipeline_cache.as_ref().map_or(0, |c| c.loaded)
    }

    /// Writes the pipeline cache to its file (atomically) if it holds pipelines the file lacks; returns the
    /// file written. Dropping the context does this too, but ignores a failure; call this to see one.
    pub fn save_pipeline_cache(&self) -> Result<Option<&Path>> {
        match &self.inner.pipeline_cache {
            Some(c) => c.save(self.device()),
            None => Ok(None),
        }
    }

    pub(crate) fn shared(&self) -> &Arc<Shared> {
        &self.inner.shared
    }

    /// The raw ash device, for recording commands.
    pub fn device(&self) -> &ash::Device {
        &self.inner.shared.device
    }

    pub fn info(&self) -> &DeviceInfo {
        &self.inner.info
    }

    /// Device memory held by this context's buffers now, and the most its allocator has held at once.
    pub fn memory_usage(&self) -> MemoryUsage {
        let shared = self.shared();
        let (in_use, reserved) = match shared.allocator.lock().ok().as_deref().and_then(|a| a.as_ref()) {
            Some(a) => {
                let r = a.generate_report();
                (r.total_allocated_bytes, r.total_capacity_bytes)
            }
            None => (0, 0),
        };
        let peak = shared
            .peak_reserved
            .load(std::sync::atomic::Ordering::Relaxed)
            .max(reserved);
        MemoryUsage {
            in_use_bytes: in_use,
            reserved_bytes: reserved,
            peak_reserved_bytes: peak,
        }
    }

    /// Starts a new peak: [`MemoryUsage::peak_reserved_bytes`] counts from what is held now.
    pub fn reset_memory_peak(&self) {
        let now = self.memory_usage().reserved_bytes;
        self.shared()
            .peak_reserved
            .store(now, std::sync::atomic::Ordering::Relaxed);
    }

    pub fn limits(&self) -> &vk::PhysicalDeviceLimits {
        &self.inner.limits
    }

    pub fn queue_family(&self) -> u32 {
        self.inner.queue_family
    }

    /// Nanoseconds per timestamp tick.
    pub fn timestamp_period(&self) -> f64 {
        self.inner.limits.timestamp_period as f64
    }

    pub fn timestamp_valid_bits(&self) -> u32 {
        self.inner.timestamp_valid_bits
    }

    /// Warnings and errors the validation layer has reported so far (empty without validation).
    pub fn validation_messages(&self) -> Vec<String> {
        match &self.inner.shared.validation {
            Some(sink) => sink.lock().map(|v| v.clone()).unwrap_or_default(),
            None => Vec::new(),
        }
    }

    pub(crate) fn entry(&self) -> &ash::Entry {
        &self.inner._entry
    }

    pub(crate) fn instance(&self) -> &ash::Instance {
        &self.inner.instance
    }

    pub(crate) fn physical_device(&self) -> vk::PhysicalDevice {
        self.inner.physical_device
    }

    /// Whether the context was opened for presenting ([`ContextOptions::present`]).
    pub fn presents(&self) -> bool {
        self.inner.presents
    }

    /// Runs `f` with the queue, which nothing else submits to meanwhile (queue access must be externally
    /// synchronised: [`Context::run`] holds the same lock).
    pub(crate) fn with_queue<T>(&self, f: impl FnOnce(vk::Queue) -> T) -> Result<T> {
        let _pool = self
            .inner
            .command_pool
            .lock()
            .map_err(|_| anyhow!("command pool lock poisoned"))?;
        Ok(f(self.inner.queue))
    }

    /// Records commands into a fresh command buffer, submits it and waits for the queue.
    pub fn run<T>(&self, record: impl FnOnce(vk::CommandBuffer) -> Result<T>) -> Result<T> {
        let device = self.device();
        let pool = self
            .inner
            .command_pool
            .lock()
            .map_err(|_| anyhow!("command pool lock poisoned"))?;
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(*pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        let cmd = unsafe { device.allocate_command_buffers(&alloc) }.context("allocating a command buffer")?[0];
        self.name_object(cmd, "Context::run");
        let fence = unsafe { device.create_fence(&vk::FenceCreateInfo::default(), None) }.context("creating a fence");
        let result = fence.and_then(|fence| {
            let r = (|| {
                let begin = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
                unsafe { device.begin_command_buffer(cmd, &begin) }.context("vkBeginCommandBuffer")?;
                let value = record(cmd)?;
                unsafe { device.end_command_buffer(cmd) }.context("vkEndCommandBuffer")?;
                let cmds = [cmd];
                let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
                unsafe { device.queue_submit(self.inner.queue, &submit, fence) }.context("vkQueueSubmit")?;
                unsafe { device.wait_for_fences(&[fence], true, u64::MAX) }
                    .context("waiting for the GPU (device lost or hung?)")?;
                Ok(value)
            })();
            unsafe { device.destroy_fence(fence, None) };
            r
        });
        unsafe { device.free_command_buffers(*pool, &[cmd]) };
        result
    }
}

/// `name` as a C string: interior NULs become U+FFFD rather than cut the name short or fail.
fn debug_name(name: &str) -> CString {
    CString::new(name.replace('\0', "\u{fffd}")).unwrap_or_default()
}

fn list_names(infos: &[DeviceInfo]) -> String {
    infos
        .iter()
        .map(|d| format!("[{}] {}", d.index, d.name))
        .collect::<Vec<_>>()
        .join(", ")
}

impl Drop for Inner {
    fn drop(&mut self) {
        unsafe {
            let device = &self.shared.device;
            let _ = device.device_wait_idle();
            if let Some(cache) = self.pipeline_cache.take() {
                // Best effort: a run that cannot save its cache has still done its work.
                let _ = cache.save(device);
                device.destroy_pipeline_cache(cache.raw, None);
            }
            if let Ok(pool) = self.command_pool.lock() {
                device.destroy_command_pool(*pool, None);
            }
            // The allocator frees its memory blocks; buffers made from this context hold `shared`, so by
            // the time the last Context handle drops, every Buffer should be gone. If one is not (a leak in
            // the caller), leave the device alive rather than destroy memory under it.
            if Arc::strong_count(&self.shared) == 1 {
                if let Ok(mut a) = self.shared.allocator.lock() {
                    a.take();
                }
                device.destroy_device(None);
            }
            if let Some((loader, messenger, _)) = self.debug.take() {
                loader.destroy_debug_utils_messenger(messenger, None);
            }
            if Arc::strong_count(&self.shared) == 1 {
                self.instance.destroy_instance(None);
            }
        }
    }
}

/// Records a full memory barrier between commands: every earlier compute or transfer write becomes
/// visible to every later compute, transfer, indirect-dispatch or host access. Kernels here run strictly one after another,
/// so one kind of barrier serves all.
pub fn barrier(ctx: &Context, cmd: vk::CommandBuffer) {
    let mb = [vk::MemoryBarrier::default()
        .src_access_mask(vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::TRANSFER_WRITE)
        .dst_access_mask(
            vk::AccessFlags::SHADER_READ
                | vk::AccessFlags::SHADER_WRITE
                | vk::AccessFlags::TRANSFER_READ
                | vk::AccessFlags::TRANSFER_WRITE
                | vk::AccessFlags::HOST_READ
                | vk::AccessFlags::INDIRECT_COMMAND_READ,
        )];
    unsafe {
        ctx.device().cmd_pipeline_barrier(
            cmd,
            vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::TRANSFER,
            vk::PipelineStageFlags::COMPUTE_SHADER
                | vk::PipelineStageFlags::TRANSFER
                | vk::PipelineStageFlags::HOST
                | vk::PipelineStageFlags::DRAW_INDIRECT,
            vk::DependencyFlags::empty(),
            &mb,
            &[],
            &[],
        )
    };
}

#[cfg(test)]
mod tests {
    use super::debug_name;

    #[test]
    fn debug_names_keep_interior_nuls_visible() {
        assert_eq!(debug_name("photon records").as_bytes(), b"photon records");
        assert_eq!(debug_name("a\0b").to_str(), Ok("a\u{fffd}b"));
        assert_eq!(debug_name("\0").to_str(), Ok("\u{fffd}"));
        assert_eq!(debug_name("").as_bytes(), b"");
    }
}
