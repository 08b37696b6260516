//! The Vulkan context: instance, optional validation, device selection and the logical device.
//!
//! `Gpu` owns every long-lived Vulkan handle of the process (entry, instance, messenger, device, allocator,
//! command pool) and destroys them in one place, its `Drop`. Everything else holds an `Arc<Gpu>`.

use std::ffi::{c_void, CStr, CString};
use std::mem::ManuallyDrop;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Arc, Mutex};

use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};

use crate::error::{CoreError, Result};

/// What the caller wants from the context.
#[derive(Clone, Debug, Default)]
pub struct ContextOptions {
    /// Enable the Khronos validation layer (messages go to the log and are counted).
    pub validation: bool,
    /// Only consider devices whose name contains this (case-insensitive).
    pub device: Option<String>,
    /// Instance extensions needed for presenting (from ash-window), empty for headless use.
    pub surface_extensions: Vec<&'static CStr>,
    /// Refuse allocations past this many bytes of device memory (simulates a small GPU; also
    /// `HRTAO_DEVICE_MEMORY_LIMIT=<MiB>`). None: no limit but the device's own.
    pub memory_limit: Option<u64>,
    /// Leave `multiDrawIndirect` off even where the device has it: the visibility draw then issues one call per
    /// draw, the path of devices without it (for tests).
    pub single_draws: bool,
    /// Trace with this backend (`--ray-backend`); None: the device decides (`RayBackend::choose`).
    pub ray_backend: Option<RayBackend>,
    /// Treat every device as one without ray queries (VK_KHR_ray_query and its feature left off), the situation
    /// of GPUs that trace with pipelines only (for tests). `HRTAO_HIDE_RAY_QUERY=1` sets it for every context of
    /// the process (`ray_query_hidden_by_env`).
    pub mask_ray_query: bool,
}

/// How the passes that trace rays trace them (pass.rs, trace.glsl): ray queries in compute shaders, or
/// ray-tracing pipelines (a ray-generation shader launched over the same work, a miss and a closest-hit shader,
/// a shader binding table: rt_pipeline.rs). Chosen per device: ray queries where the device has them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RayBackend {
    Query,
    Pipeline,
}

impl RayBackend {
    pub fn name(self) -> &'static str {
        match self {
            RayBackend::Query => "query",
            RayBackend::Pipeline => "pipeline",
        }
    }

    /// The backend of a device with ray queries (`query`) or not, ray-tracing pipelines (`pipeline`) or not:
    /// `forced` when given and the device has it, else ray queries where available, pipelines otherwise.
    pub fn choose(
        forced: Option<RayBackend>,
        query: bool,
        pipeline: bool,
    ) -> std::result::Result<RayBackend, String> {
        match forced {
            Some(RayBackend::Query) if !query => {
                Err("ray queries forced but the device lacks rayQuery".into())
            }
            Some(RayBackend::Pipeline) if !pipeline => {
                Err("ray-tracing pipelines forced but the device lacks rayTracingPipeline".into())
            }
            Some(b) => Ok(b),
            None if query => Ok(RayBackend::Query),
            None if pipeline => Ok(RayBackend::Pipeline),
            None => Err("neither rayQuery nor rayTracingPipeline (with indirect traces)".into()),
        }
    }
}

impl std::str::FromStr for RayBackend {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "query" => Ok(RayBackend::Query),
            "pipeline" => Ok(RayBackend::Pipeline),
            _ => Err(format!("unknown ray backend `{s}` (query, pipeline)")),
        }
    }
}

/// The device's ray-tracing pipeline support, where VK_KHR_ray_tracing_pipeline is enabled: its functions and
/// the shader binding table's layout rules.
pub struct RtSupport {
    pub loader: ash::khr::ray_tracing_pipeline::Device,
    pub handle_size: u32,
    pub handle_alignment: u32,
    pub base_alignment: u32,
}

impl ContextOptions {
    /// Headless options, with validation on when `HRTAO_VALIDATION=1`.
    pub fn from_env() -> Self {
        ContextOptions {
            validation: validation_requested_by_env(),
            ..Default::default()
        }
    }
}

/// True when the `HRTAO_VALIDATION` environment variable asks for the validation layer.
pub fn validation_requested_by_env() -> bool {
    matches!(
        std::env::var("HRTAO_VALIDATION").as_deref(),
        Ok("1") | Ok("true") | Ok("yes")
    )
}

/// True when `HRTAO_HIDE_RAY_QUERY` asks every context to treat its devices as ones without ray queries (as
/// `ContextOptions::mask_ray_query`): the binary and the whole test suite then run as on a GPU that traces with
/// ray-tracing pipelines only (`hrtao devices` lists no ray queries, the pipeline backend is chosen, forcing ray
/// queries finds no device).
pub fn ray_query_hidden_by_env() -> bool {
    matches!(
        std::env::var("HRTAO_HIDE_RAY_QUERY").as_deref(),
        Ok("1") | Ok("true") | Ok("yes")
    )
}

/// The Khronos validation layer's name.
const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// The message of a context that was asked for validation where the layer is not installed: validation is
/// skipped and the context runs without it (a bare GPU machine has no layer; the suite asks for it everywhere).
pub const VALIDATION_SKIPPED: &str = "validation skipped: VK_LAYER_KHRONOS_validation is not installed \
     (the Vulkan loader lists no such layer; apt-get install vulkan-validationlayers)";

/// `HRTAO_DEVICE_MEMORY_LIMIT` in MiB, if set.
pub fn memory_limit_from_env() -> Option<u64> {
    std::env::var("HRTAO_DEVICE_MEMORY_LIMIT")
        .ok()
        .and_then(|v| v.trim().parse::<u64>().ok())
        .map(|mib| mib << 20)
}

/// Validation messages counted by severity since the context was created.
#[derive(Default, Debug)]
pub struct ValidationCounters {
    pub errors: AtomicU32,
    pub warnings: AtomicU32,
}

impl ValidationCounters {
    pub fn total(&self) -> u32 {
        self.errors.load(Ordering::Relaxed) + self.warnings.load(Ordering::Relaxed)
    }
}

/// Facts about the chosen device, for logs, stats and the UI.
#[derive(Clone, Debug, serde::Serialize)]
pub struct DeviceInfo {
    pub name: String,
    pub kind: String,
    pub driver: String,
    pub api_version: String,
    pub is_software: bool,
    pub timestamp_period_ns: f32,
    pub timestamps: bool,
    /// Valid bits of the queue's timestamps (`timestampValidBits`, 36 to 64): higher bits are undefined and
    /// the counter wraps at 2^bits.
    pub timestamp_valid_bits: u32,
    pub validation: bool,
    /// The device has `geometryShader` (enabled): fragment shaders may read `gl_PrimitiveID`, which the
    /// rasterised primary visibility needs for its indexed draws.
    pub primitive_id_in_fragment: bool,
    /// The device has `multiDrawIndirect` and `drawIndirectFirstInstance` (enabled): the visibility draw issues
    /// one indirect command per pipeline instead of one draw per mesh geometry.
    pub multi_draw_indirect: bool,
    /// The device has `shaderDrawParameters` (enabled): the visibility draw's vertex stage reads gl_DrawID.
    pub draw_parameters: bool,
    /// How the passes trace rays (`RayBackend`).
    pub ray_backend: RayBackend,
}

pub struct Gpu {
    pub device: ash::Device,
    pub instance: ash::Instance,
    pub physical: vk::PhysicalDevice,
    pub queue: vk::Queue,
    pub queue_family: u32,
    pub accel: ash::khr::acceleration_structure::Device,
    /// Ray-tracing pipelines, where the device has them (enabled whenever present).
    pub rt: Option<RtSupport>,
    pub info: DeviceInfo,
    pub limits: vk::PhysicalDeviceLimits,
    pub scratch_alignment: u64,
    pub validation: Arc<ValidationCounters>,
    /// Bytes currently allocated by `Buffer`s (kept by buffer.rs).
    pub(crate) device_bytes: std::sync::atomic::AtomicU64,
    /// `wait_idle` calls so far: every one stalls the CPU and the device together (tests count them).
    idle_waits: std::sync::atomic::AtomicU64,
    pub(crate) memory_limit: Option<u64>,
    allocator: ManuallyDrop<Arc<Mutex<Allocator>>>,
    command_pool: Mutex<vk::CommandPool>,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    /// Kept alive until the very end: the loader library must outlive every Vulkan call.
    pub entry: ash::Entry,
}

/// The extensions every device needs; a ray-tracing backend (`RayBackend`) needs one of VK_KHR_ray_query and
/// VK_KHR_ray_tracing_pipeline besides.
const DEVICE_EXTENSIONS: [&CStr; 2] = [
    ash::khr::acceleration_structure::NAME,
    ash::khr::deferred_host_operations::NAME,
];

unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT,
    user: *mut c_void,
) -> vk::Bool32 {
    let msg = if data.is_null() || (*data).p_message.is_null() {
        "<no message>".to_string()
    } else {
        CStr::from_ptr((*data).p_message).to_string_lossy().into_owned()
    };
    // `user` points into the Arc held by `Gpu::validation`, alive as long as the messenger.
    let counters = if user.is_null() {
        None
    } else {
        Some(&*(user as *const ValidationCounters))
    };
    if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
        log::error!("[vulkan {kind:?}] {msg}");
        if let Some(c) = counters {
            c.errors.fetch_add(1, Ordering::Relaxed);
        }
    } else if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING) {
        log::warn!("[vulkan {kind:?}] {msg}");
        if let Some(c) = counters {
            c.warnings.fetch_add(1, Ordering::Relaxed);
        }
    } else {
        log::debug!("[vulkan {kind:?}] {msg}");
    }
    vk::FALSE
}

/// Why a physical device was not chosen, or that it was.
struct Candidate {
    physical: vk::PhysicalDevice,
    name: String,
    kind: vk::PhysicalDeviceType,
    problem: Option<String>,
    queue_family: u32,
    /// VK_KHR_ray_query with its feature (and not masked).
    ray_query: bool,
    /// VK_KHR_ray_tracing_pipeline with its features (indirect traces included).
    ray_pipeline: bool,
}

fn device_kind_rank(kind: vk::PhysicalDeviceType) -> u32 {
    match kind {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::OTHER => 3,
        _ => 4, // CPU (lavapipe) last
    }
}

fn kind_name(kind: vk::PhysicalDeviceType) -> &'static str {
    match kind {
        vk::PhysicalDeviceType::DISCRETE_GPU => "discrete GPU",
        vk::PhysicalDeviceType::INTEGRATED_GPU => "integrated GPU",
        vk::PhysicalDeviceType::VIRTUAL_GPU => "virtual GPU",
        vk::PhysicalDeviceType::CPU => "CPU (software)",
        _ => "other",
    }
}

const LAVAPIPE_HINT: &str =
    "hrtao needs a Vulkan device with VK_KHR_acceleration_structure and VK_KHR_ray_query or \
VK_KHR_ray_tracing_pipeline. \
Without such a GPU, install Mesa's lavapipe (software Vulkan, Mesa >= 23): on Debian 12 \
`apt-get install -t bookworm-backports mesa-vulkan-drivers`, on Ubuntu `apt-get install mesa-vulkan-drivers` \
(or run scripts/install-deps.sh).";

unsafe fn check_candidate(
    instance: &ash::Instance,
    physical: vk::PhysicalDevice,
    options: &ContextOptions,
) -> Candidate {
    let props = instance.get_physical_device_properties(physical);
    let name = CStr::from_ptr(props.device_name.as_ptr())
        .to_string_lossy()
        .into_owned();
    let mut cand = Candidate {
        physical,
        name,
        kind: props.device_type,
        problem: None,
        queue_family: u32::MAX,
        ray_query: false,
        ray_pipeline: false,
    };
    if vk::api_version_minor(props.api_version) < 2 && vk::api_version_major(props.api_version) == 1 {
        cand.problem = Some("Vulkan 1.2 not supported".into());
        return cand;
    }
    let exts = instance
        .enumerate_device_extension_properties(physical)
        .unwrap_or_default();
    let has = |want: &CStr| {
        exts.iter()
            .any(|e| CStr::from_ptr(e.extension_name.as_ptr()) == want)
    };
    let missing: Vec<String> = DEVICE_EXTENSIONS
        .iter()
        .filter(|e| !has(e))
        .map(|e| e.to_string_lossy().into_owned())
        .collect();
    if !missing.is_empty() {
        cand.problem = Some(format!("missing {}", missing.join(", ")));
        return cand;
    }
    let mut rq = vk::PhysicalDeviceRayQueryFeaturesKHR::default();
    let mut rtp = vk::PhysicalDeviceRayTracingPipelineFeaturesKHR::default();
    let mut asf = vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default();
    let mut v12 = vk::PhysicalDeviceVulkan12Features::default();
    let features = {
        let mut f2 = vk::PhysicalDeviceFeatures2::default()
            .push_next(&mut rq)
            .push_next(&mut rtp)
            .push_next(&mut asf)
            .push_next(&mut v12);
        instance.get_physical_device_features2(physical, &mut f2);
        f2.features
    };
    let hidden = ray_query_hidden_by_env();
    cand.ray_query =
        !options.mask_ray_query && !hidden && has(ash::khr::ray_query::NAME) && rq.ray_query == vk::TRUE;
    cand.ray_pipeline = has(ash::khr::ray_tracing_pipeline::NAME)
        && rtp.ray_tracing_pipeline == vk::TRUE
        && rtp.ray_tracing_pipeline_trace_rays_indirect == vk::TRUE;
    if let Err(e) = RayBackend::choose(options.ray_backend, cand.ray_query, cand.ray_pipeline) {
        cand.problem = Some(if hidden && !cand.ray_query {
            format!("{e} (ray queries hidden by HRTAO_HIDE_RAY_QUERY)")
        } else {
            e
        });
        return cand;
    }
    let required = [
        (asf.acceleration_structure, "accelerationStructure"),
        (v12.buffer_device_address, "bufferDeviceAddress"),
        (v12.scalar_block_layout, "scalarBlockLayout"),
        (features.shader_int64, "shaderInt64"),
        // Section planes clip the rasterised primary visibility.
        (features.shader_clip_distance, "shaderClipDistance"),
        // The hash map claims and stamps a cell with one 64-bit compare-and-swap (hash_map.glsl).
        (v12.shader_buffer_int64_atomics, "shaderBufferInt64Atomics"),
    ];
    let lacking: Vec<&str> = required
        .iter()
        .filter(|(f, _)| *f == 0)
        .map(|(_, name)| *name)
        .collect();
    if !lacking.is_empty() {
        cand.problem = Some(format!("lacks features {}", lacking.join(", ")));
        return cand;
    }
    let families = instance.get_physical_device_queue_family_properties(physical);
    let want = vk::QueueFlags::COMPUTE | vk::QueueFlags::GRAPHICS;
    match families.iter().position(|f| f.queue_flags.contains(want)) {
        Some(i) => cand.queue_family = i as u32,
        None => cand.problem = Some("no graphics+compute queue".into()),
    }
    cand
}

/// Marks the devices whose name lacks `filter` (case-insensitive) as unusable, then picks the usable device of
/// the best kind (discrete, integrated, virtual GPU, other, CPU), the first one listed among equals.
fn choose(candidates: &mut [Candidate], filter: Option<&str>) -> Option<usize> {
    if let Some(filter) = filter {
        let f = filter.to_lowercase();
        for c in candidates.iter_mut() {
            if c.problem.is_none() && !c.name.to_lowercase().contains(&f) {
                c.problem = Some(format!("name does not contain `{filter}`"));
            }
        }
    }
    candidates
        .iter()
        .enumerate()
        .filter(|(_, c)| c.problem.is_none())
        .min_by_key(|(_, c)| device_kind_rank(c.kind))
        .map(|(i, _)| i)
}

/// The Vulkan loader, or an error that says how to get one.
unsafe fn load_entry() -> Result<ash::Entry> {
    ash::Entry::load().map_err(|e| {
        CoreError::NoDevice(format!(
            "cannot load the Vulkan loader (libvulkan.so.1): {e}. {LAVAPIPE_HINT}"
        ))
    })
}

/// One Vulkan device as `Gpu::new` judges it.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct DeviceListing {
    pub name: String,
    pub kind: &'static str,
    /// Why hrtao cannot use the device (None: usable).
    pub problem: Option<String>,
    /// The device `Gpu::new` opens with the same options.
    pub chosen: bool,
    /// The device offers ray queries (VK_KHR_ray_query with its feature), unless masked (`mask_ray_query`,
    /// `HRTAO_HIDE_RAY_QUERY`). False where the device was refused before its ray tracing was looked at.
    pub ray_query: bool,
    /// The device offers ray-tracing pipelines with indirect traces (VK_KHR_ray_tracing_pipeline).
    pub ray_pipeline: bool,
}

/// Every Vulkan device, judged and chosen as `Gpu::new` would with `options` (only `device` matters here).
pub fn list_devices(options: &ContextOptions) -> Result<Vec<DeviceListing>> {
    unsafe {
        let entry = load_entry()?;
        let app_name = CString::new("hrtao").unwrap();
        let app = vk::ApplicationInfo::default()
            .application_name(&app_name)
            .api_version(vk::API_VERSION_1_2);
        let instance = entry
            .create_instance(&vk::InstanceCreateInfo::default().application_info(&app), None)
            .map_err(|e| CoreError::NoDevice(format!("vkCreateInstance failed: {e}. {LAVAPIPE_HINT}")))?;
        let physicals = instance.enumerate_physical_devices().unwrap_or_default();
        let mut candidates: Vec<Candidate> = physicals
            .iter()
            .map(|&p| check_candidate(&instance, p, options))
            .collect();
        let chosen = choose(&mut candidates, options.device.as_deref());
        instance.destroy_instance(None);
        Ok(candidates
            .into_iter()
            .enumerate()
            .map(|(i, c)| DeviceListing {
                name: c.name,
                kind: kind_name(c.kind),
                problem: c.problem,
                chosen: Some(i) == chosen,
                ray_query: c.ray_query,
                ray_pipeline: c.ray_pipeline,
            })
            .collect())
    }
}

impl Gpu {
    /// Creates the instance and the device. Picks a hardware GPU when present, else lavapipe; rays are traced by
    /// `RayBackend::choose`.
    pub fn new(options: &ContextOptions) -> Result<Arc<Gpu>> {
        unsafe { Self::create(options) }
    }

    unsafe fn create(options: &ContextOptions) -> Result<Arc<Gpu>> {
        let entry = load_entry()?;
        let app_name = CString::new("hrtao").unwrap();
        let app = vk::ApplicationInfo::default()
            .application_name(&app_name)
            .application_version(1)
            .engine_name(&app_name)
            .api_version(vk::API_VERSION_1_2);

        let mut layers: Vec<*const i8> = Vec::new();
        let mut extensions: Vec<*const i8> = options.surface_extensions.iter().map(|e| e.as_ptr()).collect();
        let mut validation = false;
        if options.validation {
            let available = entry.enumerate_instance_layer_properties().unwrap_or_default();
            if available
                .iter()
                .any(|l| CStr::from_ptr(l.layer_name.as_ptr()) == VALIDATION_LAYER)
            {
                layers.push(VALIDATION_LAYER.as_ptr());
                validation = true;
            } else {
                // Asked for (`--validation`, HRTAO_VALIDATION=1, the tests) where the layer is not installed, as
                // on a bare GPU machine: run without it, and say so (`DeviceInfo::validation` stays false).
                validation_skipped();
            }
        }
        let have_debug_utils = entry
            .enumerate_instance_extension_properties(None)
            .unwrap_or_default()
            .iter()
            .any(|e| CStr::from_ptr(e.extension_name.as_ptr()) == ash::ext::debug_utils::NAME);
        if have_debug_utils {
            extensions.push(ash::ext::debug_utils::NAME.as_ptr());
        }
        let enabled_features = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
        let mut features =
            vk::ValidationFeaturesEXT::default().enabled_validation_features(&enabled_features);
        let counters = Arc::new(ValidationCounters::default());
        let messenger_info = || {
            vk::DebugUtilsMessengerCreateInfoEXT::default()
                .message_severity(
                    vk::DebugUtilsMessageSeverityFlagsEXT::ERROR
                        | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
                        | vk::DebugUtilsMessageSeverityFlagsEXT::INFO,
                )
                .message_type(
                    vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                        | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                        | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
                )
                .pfn_user_callback(Some(debug_callback))
                .user_data(Arc::as_ptr(&counters) as *mut c_void)
        };
        // One messenger info chained into instance creation (covers vkCreateInstance itself), another for the
        // persistent messenger: a struct chained once has its pNext set and cannot be reused.
        let mut creation_messenger = messenger_info();
        let mut create = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layers)
            .enabled_extension_names(&extensions);
        if validation && have_debug_utils {
            create = create.push_next(&mut features).push_next(&mut creation_messenger);
        }
        let instance = entry
            .create_instance(&create, None)
            .map_err(|e| CoreError::NoDevice(format!("vkCreateInstance failed: {e}. {LAVAPIPE_HINT}")))?;
        let debug = if validation && have_debug_utils {
            let du = ash::ext::debug_utils::Instance::new(&entry, &instance);
            match du.create_debug_utils_messenger(&messenger_info(), None) {
                Ok(m) => Some((du, m)),
                Err(e) => {
                    instance.destroy_instance(None);
                    return Err(CoreError::Vulkan("vkCreateDebugUtilsMessengerEXT", e));
                }
            }
        } else {
            None
        };
        let destroy_instance =
            |debug: &Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>| {
                if let Some((du, m)) = debug {
                    du.destroy_debug_utils_messenger(*m, None);
                }
                instance.destroy_instance(None);
            };

        let physicals = instance.enumerate_physical_devices().unwrap_or_default();
        let mut candidates: Vec<Candidate> = physicals
            .iter()
            .map(|&p| check_candidate(&instance, p, options))
            .collect();
        let chosen = choose(&mut candidates, options.device.as_deref()).map(|i| {
            let c = &candidates[i];
            (c.physical, c.queue_family, c.ray_query, c.ray_pipeline)
        });
        let Some((physical, queue_family, has_ray_query, has_ray_pipeline)) = chosen else {
            let mut listing = String::new();
            for c in &candidates {
                listing.push_str(&format!(
                    "\n  - {} ({}): {}",
                    c.name,
                    kind_name(c.kind),
                    c.problem.as_deref().unwrap_or("usable")
                ));
            }
            if candidates.is_empty() {
                listing.push_str("\n  (no Vulkan devices at all)");
            }
            destroy_instance(&debug);
            return Err(CoreError::NoDevice(format!(
                "no usable Vulkan device with ray queries or ray-tracing pipelines. Devices found:{listing}\n{LAVAPIPE_HINT}"
            )));
        };

        let props = instance.get_physical_device_properties(physical);
        let ray_backend = RayBackend::choose(options.ray_backend, has_ray_query, has_ray_pipeline)
            .expect("a chosen device has its backend");
        let mut as_props = vk::PhysicalDeviceAccelerationStructurePropertiesKHR::default();
        let mut rt_props = vk::PhysicalDeviceRayTracingPipelinePropertiesKHR::default();
        let mut driver_props = vk::PhysicalDeviceDriverProperties::default();
        let mut props2 = vk::PhysicalDeviceProperties2::default()
            .push_next(&mut as_props)
            .push_next(&mut rt_props)
            .push_next(&mut driver_props);
        instance.get_physical_device_properties2(physical, &mut props2);
        let name = CStr::from_ptr(props.device_name.as_ptr())
            .to_string_lossy()
            .into_owned();
        let driver = format!(
            "{} {}",
            CStr::from_ptr(driver_props.driver_name.as_ptr()).to_string_lossy(),
            CStr::from_ptr(driver_props.driver_info.as_ptr()).to_string_lossy()
        );
        let families = instance.get_physical_device_queue_family_properties(physical);
        let timestamp_valid_bits = families[queue_family as usize].timestamp_valid_bits;
        let timestamps = timestamp_valid_bits > 0;

        // Features: ray queries, acceleration structures, buffer device address, scalar layout, int64 (+ atomics).
        let mut supported_v11 = vk::PhysicalDeviceVulkan11Features::default();
        let mut supported_v12 = vk::PhysicalDeviceVulkan12Features::default();
        let supported = {
            let mut f2 = vk::PhysicalDeviceFeatures2::default()
                .push_next(&mut supported_v11)
                .push_next(&mut supported_v12);
            instance.get_physical_device_features2(physical, &mut f2);
            f2.features
        };
        let mut rq = vk::PhysicalDeviceRayQueryFeaturesKHR::default().ray_query(true);
        let mut rtp = vk::PhysicalDeviceRayTracingPipelineFeaturesKHR::default()
            .ray_tracing_pipeline(true)
            .ray_tracing_pipeline_trace_rays_indirect(true);
        let mut asf =
            vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default().acceleration_structure(true);
        let mut v12 = vk::PhysicalDeviceVulkan12Features::default()
            .buffer_device_address(true)
            .scalar_block_layout(true)
            .host_query_reset(supported_v12.host_query_reset == vk::TRUE)
            .shader_buffer_int64_atomics(true);
        let primitive_id_in_fragment = supported.geometry_shader == vk::TRUE;
        let draw_parameters = supported_v11.shader_draw_parameters == vk::TRUE;
        let mut v11 = vk::PhysicalDeviceVulkan11Features::default().shader_draw_parameters(draw_parameters);
        let multi_draw_indirect = !options.single_draws
            && supported.multi_draw_indirect == vk::TRUE
            && supported.draw_indirect_first_instance == vk::TRUE;
        let base = vk::PhysicalDeviceFeatures::default()
            .shader_int64(true)
            .shader_clip_distance(true)
            .geometry_shader(primitive_id_in_fragment)
            .multi_draw_indirect(multi_draw_indirect)
            .draw_indirect_first_instance(multi_draw_indirect);
        let mut features2 = vk::PhysicalDeviceFeatures2::default()
            .features(base)
            .push_next(&mut asf)
            .push_next(&mut v12)
            .push_next(&mut v11);
        // Each ray-tracing extension, with its feature, where the device has it (a masked ray query stays off).
        if has_ray_query {
            features2 = features2.push_next(&mut rq);
        }
        if has_ray_pipeline {
            features2 = features2.push_next(&mut rtp);
        }
        let priorities = [1.0f32];
        let queue_info = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(queue_family)
            .queue_priorities(&priorities)];
        let mut dev_exts: Vec<*const i8> = DEVICE_EXTENSIONS.iter().map(|e| e.as_ptr()).collect();
        if has_ray_query {
            dev_exts.push(ash::khr::ray_query::NAME.as_ptr());
        }
        if has_ray_pipeline {
            dev_exts.push(ash::khr::ray_tracing_pipeline::NAME.as_ptr());
        }
        if !options.surface_extensions.is_empty() {
            dev_exts.push(ash::khr::swapchain::NAME.as_ptr());
        }
        let device_info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queue_info)
            .enabled_extension_names(&dev_exts)
            .push_next(&mut features2);
        let device = match instance.create_device(physical, &device_info, None) {
            Ok(d) => d,
            Err(e) => {
                destroy_instance(&debug);
                return Err(CoreError::Vulkan("vkCreateDevice", e));
            }
        };
        let queue = device.get_device_queue(queue_family, 0);
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device: physical,
            debug_settings: Default::default(),
            buffer_device_address: true,
            allocation_sizes: Default::default(),
        })
        .map_err(|e| CoreError::Memory(format!("creating the allocator: {e}")))?;
        let pool = device
            .create_command_pool(
                &vk::CommandPoolCreateInfo::default()
                    .queue_family_index(queue_family)
                    .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER),
                None,
            )
            .map_err(|e| CoreError::Vulkan("vkCreateCommandPool", e))?;
        let accel = ash::khr::acceleration_structure::Device::new(&instance, &device);
        let rt = has_ray_pipeline.then(|| RtSupport {
            loader: ash::khr::ray_tracing_pipeline::Device::new(&instance, &device),
            handle_size: rt_props.shader_group_handle_size,
            handle_alignment: rt_props.shader_group_handle_alignment.max(1),
            base_alignment: rt_props.shader_group_base_alignment.max(1),
        });
        let is_software = props.device_type == vk::PhysicalDeviceType::CPU;
        if is_software {
            keep_freed_memory();
        }
        let info = DeviceInfo {
            name,
            kind: kind_name(props.device_type).into(),
            driver,
            api_version: format!(
                "{}.{}.{}",
                vk::api_version_major(props.api_version),
                vk::api_version_minor(props.api_version),
                vk::api_version_patch(props.api_version)
            ),
            is_software,
            timestamp_period_ns: props.limits.timestamp_period,
            timestamps,
            timestamp_valid_bits,
            validation,
            primitive_id_in_fragment,
            multi_draw_indirect,
            draw_parameters,
            ray_backend,
        };
        log::info!(
            "Vulkan device: {} ({}, {}), rays traced by {}, validation {}",
            info.name,
            info.kind,
            info.driver,
            ray_backend.name(),
            validation
        );
        Ok(Arc::new(Gpu {
            device,
            instance,
            physical,
            queue,
            queue_family,
            accel,
            rt,
            info,
            limits: props.limits,
            scratch_alignment: as_props
                .min_acceleration_structure_scratch_offset_alignment
                .max(1) as u64,
            validation: counters,
            device_bytes: Default::default(),
            idle_waits: Default::default(),
            memory_limit: options.memory_limit.or_else(memory_limit_from_env),
            allocator: ManuallyDrop::new(Arc::new(Mutex::new(allocator))),
            command_pool: Mutex::new(pool),
            debug,
            entry,
        }))
    }

    pub fn allocator(&self) -> std::sync::MutexGuard<'_, Allocator> {
        self.allocator.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// The shared allocator, for libraries that allocate on our device (egui-ash). Every clone must be
    /// dropped before the `Gpu`; a clone still alive then is leaked rather than freed on a destroyed device.
    pub fn allocator_arc(&self) -> Arc<Mutex<Allocator>> {
        Arc::clone(&self.allocator)
    }

    /// Records commands with `record`, submits them and waits for completion.
    pub fn run_commands<R>(&self, record: impl FnOnce(vk::CommandBuffer) -> R) -> Result<R> {
        unsafe {
            let pool = self.command_pool.lock().unwrap_or_else(|p| p.into_inner());
            let cmd = self
                .device
                .allocate_command_buffers(
                    &vk::CommandBufferAllocateInfo::default()
                        .command_pool(*pool)
                        .command_buffer_count(1),
                )
                .map_err(|e| CoreError::Vulkan("vkAllocateCommandBuffers", e))?[0];
            let result = (|| {
                self.device
                    .begin_command_buffer(
                        cmd,
                        &vk::CommandBufferBeginInfo::default()
                            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
                    )
                    .map_err(|e| CoreError::Vulkan("vkBeginCommandBuffer", e))?;
                let r = record(cmd);
                self.device
                    .end_command_buffer(cmd)
                    .map_err(|e| CoreError::Vulkan("vkEndCommandBuffer", e))?;
                self.submit_and_wait(cmd)?;
                Ok(r)
            })();
            self.device.free_command_buffers(*pool, &[cmd]);
            result
        }
    }

    /// Bytes of device memory allocated through the allocator (all our buffers and acceleration structures).
    pub fn device_memory_bytes(&self) -> u64 {
        self.device_bytes.load(Ordering::Relaxed)
    }

    /// Submits one command buffer and waits for it with a fence (bounded wait: a hung device is an error).
    pub fn submit_and_wait(&self, cmd: vk::CommandBuffer) -> Result<()> {
        unsafe {
            let fence = self
                .device
                .create_fence(&vk::FenceCreateInfo::default(), None)
                .map_err(|e| CoreError::Vulkan("vkCreateFence", e))?;
            let cmds = [cmd];
            let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
            let result = self
                .device
                .queue_submit(self.queue, &submit, fence)
                .map_err(|e| CoreError::from_vk("vkQueueSubmit", e))
                .and_then(|_| {
                    // 10 minutes: lavapipe is slow, but a frame never legitimately takes that long.
                    self.device
                        .wait_for_fences(&[fence], true, 600_000_000_000)
                        .map_err(|e| CoreError::from_vk("vkWaitForFences", e))
                });
            self.device.destroy_fence(fence, None);
            result
        }
    }

    pub fn wait_idle(&self) {
        self.idle_waits.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        unsafe {
            let _ = self.device.device_wait_idle();
        }
    }

    /// `wait_idle` calls so far.
    pub fn idle_waits(&self) -> u64 {
        self.idle_waits.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// Errors and warnings reported by the validation layer so far.
    pub fn validation_messages(&self) -> u32 {
        self.validation.total()
    }
}

impl Drop for Gpu {
    fn drop(&mut self) {
        unsafe {
            let _ = self.device.device_wait_idle();
            let allocator = ManuallyDrop::take(&mut self.allocator);
            match Arc::try_unwrap(allocator) {
                Ok(a) => drop(a),
                Err(still_shared) => {
                    log::error!("GPU allocator still shared at device destruction: leaking it");
                    std::mem::forget(still_shared);
                }
            }
            self.device.destroy_command_pool(
                *self.command_pool.get_mut().unwrap_or_else(|p| p.into_inner()),
                None,
            );
            self.device.destroy_device(None);
            if let Some((du, m)) = self.debug.take() {
                du.destroy_debug_utils_messenger(m, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}

/// Says once per process that validation was asked for but is skipped (`VALIDATION_SKIPPED`): in the log, and
/// on stderr as well where the log does not show warnings (a test's logger), so a run's output always says it.
fn validation_skipped() {
    static SAID: std::sync::Once = std::sync::Once::new();
    SAID.call_once(|| {
        log::warn!("{VALIDATION_SKIPPED}");
        if !log::log_enabled!(log::Level::Warn) {
            eprintln!("hrtao: {VALIDATION_SKIPPED}");
        }
    });
}

/// A CPU device (lavapipe) runs in this process and allocates its per-draw and per-dispatch working memory
/// (rasteriser bins, vertex buffers) with malloc every frame. glibc hands large freed blocks back to the kernel
/// (munmap, trimming the heap), so the next frame page-faults them in again: up to a fifth of a moving frame's
/// CPU time went to the kernel. Keep freed memory in the process instead: blocks up to 32 MiB come from the
/// heap, and the heap is never trimmed. Harmless elsewhere (GPU drivers allocate little per frame), and only
/// applied for CPU devices.
fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        // SAFETY: mallopt only sets allocator parameters; it takes the allocator's own lock.
        let ok = unsafe {
            libc::mallopt(libc::M_MMAP_THRESHOLD, 32 << 20) == 1
                && libc::mallopt(libc::M_TRIM_THRESHOLD, i32::MAX) == 1
        };
        if !ok {
            log::debug!("mallopt refused the CPU device's allocation settings");
        }
    }
}
