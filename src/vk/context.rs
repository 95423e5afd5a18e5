//! The Vulkan context: loader, instance (with the Khronos validation layer and a debug messenger
//! when asked), device selection, the logical device, its one queue, and the memory allocator.
//!
//! Everything is owned by [`Shared`], which every resource holds through an `Arc`, so the device
//! outlives every object made from it and is destroyed last, in reverse order of creation.

use std::ffi::{c_void, CStr};
use std::sync::{Arc, Mutex};

use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};

use crate::Error;

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// Which physical device to use.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum DeviceChoice {
    /// A real GPU when there is one (discrete, then integrated), lavapipe otherwise.
    #[default]
    Auto,
    /// A CPU implementation (lavapipe).
    Cpu,
    /// The first device whose name contains this text (case-insensitive), or whose index it is.
    Named(String),
}

impl DeviceChoice {
    /// `auto`, `cpu` (or `lavapipe`), a device index, or part of a device name.
    pub fn parse(text: &str) -> DeviceChoice {
        match text.to_ascii_lowercase().as_str() {
            "" | "auto" => DeviceChoice::Auto,
            "cpu" | "lavapipe" | "llvmpipe" => DeviceChoice::Cpu,
            _ => DeviceChoice::Named(text.to_string()),
        }
    }

    /// The choice named by `WEFT_DEVICE`, or `Auto`.
    pub fn from_env() -> DeviceChoice {
        std::env::var("WEFT_DEVICE")
            .map(|v| DeviceChoice::parse(&v))
            .unwrap_or_default()
    }
}

#[derive(Clone, Debug, Default)]
pub struct ContextOptions {
    /// Turn on the Khronos validation layer (with synchronization validation) and collect every
    /// warning and error it reports; see [`Context::take_validation_messages`].
    pub validate: bool,
    pub device: DeviceChoice,
}

/// What was chosen, for messages, goldens and benchmarks.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    pub name: String,
    pub device_type: String,
    pub driver_name: String,
    pub driver_info: String,
    pub api_version: String,
    pub max_image_dimension_2d: u32,
    /// Size of the device's largest DEVICE_LOCAL memory heap, in bytes (on a CPU device such as
    /// lavapipe this is system memory).
    pub device_local_heap_bytes: u64,
    pub timestamp_period_ns: f32,
    pub timestamps: bool,
    /// Whether RGBA32F images can be sampled with linear filtering (optional in Vulkan; the
    /// weave's summed-area table is filtered where it can be, fetched where not).
    pub rgba32f_linear: bool,
    /// Whether D32_SFLOAT_S8_UINT can be a sampled depth-stencil attachment (Vulkan requires it or
    /// D24_UNORM_S8_UINT): the G-buffer's depth then has a stencil that marks each pixel's kind of
    /// material, and the lighting pass shades each kind with a pipeline of its own.
    /// `WEFT_NO_STENCIL=1` makes weft take it as absent.
    pub depth_stencil: bool,
}

impl DeviceInfo {
    pub fn is_cpu(&self) -> bool {
        self.device_type == "cpu"
    }
}

pub(crate) struct Shared {
    pub(crate) entry: ash::Entry,
    pub(crate) instance: ash::Instance,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    pub(crate) device: ash::Device,
    pub(crate) queue: vk::Queue,
    pub(crate) command_pool: vk::CommandPool,
    /// Held while the command pool or the queue is used (Vulkan requires both to be externally
    /// synchronized): `Context` is `Sync`, so two threads may submit at once.
    pub(crate) queue_lock: Mutex<()>,
    /// Queue submissions made so far (`Context::submissions`).
    pub(crate) submissions: std::sync::atomic::AtomicU64,
    /// The fences of submissions in flight ([`InFlight`](super::InFlight): submitted and not yet
    /// waited for). Every resource waits for them before it is destroyed ([`Shared::settle`]),
    /// and so does host access to a buffer's memory: an in-flight submission borrows nothing, so
    /// this is what keeps the resources its commands name alive until the device is done.
    pub(crate) in_flight: Mutex<Vec<vk::Fence>>,
    pub(crate) allocator: Mutex<Option<Allocator>>,
    pub(crate) info: DeviceInfo,
    /// The physical device and the queue's family (a window's surface is checked against them).
    pub(crate) physical: vk::PhysicalDevice,
    pub(crate) queue_family: u32,
    pub(crate) limits: vk::PhysicalDeviceLimits,
    /// Boxed so the debug callback's user pointer stays valid for the instance's whole life.
    messages: Box<Mutex<Vec<String>>>,
    pub(crate) anisotropy: bool,
    /// Whether BC7 textures are enabled and sampled with linear filtering ([`Context::samples_bc7`]).
    pub(crate) bc7: bool,
    /// The driver's pipeline cache (null when the driver refused one), loaded from weft's cache
    /// on disk (crate::cache) and written back when the context ends if it changed.
    pub(crate) pipeline_cache: vk::PipelineCache,
    /// The size of what was loaded, and the entry's key (device, driver, weft).
    pipeline_cache_loaded: usize,
    pipeline_cache_key: Vec<u8>,
}

/// The cache entry's key for a device: what a pipeline cache is valid for (the vendor, device,
/// driver version and the driver's cache UUID, as its header says), and this weft.
fn pipeline_cache_key(props: &vk::PhysicalDeviceProperties) -> Vec<u8> {
    let mut key = b"VkPipelineCache v1 ".to_vec();
    key.extend_from_slice(&props.vendor_id.to_le_bytes());
    key.extend_from_slice(&props.device_id.to_le_bytes());
    key.extend_from_slice(&props.driver_version.to_le_bytes());
    key.extend_from_slice(&props.pipeline_cache_uuid);
    key.extend_from_slice(env!("CARGO_PKG_VERSION").as_bytes());
    key
}

/// Whether `data` begins with the header Vulkan defines for a pipeline cache of this device
/// (`VkPipelineCacheHeaderVersionOne`: header size ≥ 32, version 1, vendor, device, UUID); a
/// driver is then the one to judge the rest.
pub(crate) fn pipeline_cache_header_matches(
    data: &[u8],
    props: &vk::PhysicalDeviceProperties,
) -> bool {
    let word = |i: usize| {
        data.get(4 * i..4 * i + 4)
            .map(|b| u32::from_le_bytes(b.try_into().expect("4 bytes")))
    };
    data.len() >= 32
        && word(0).is_some_and(|n| n >= 32 && n as usize <= data.len())
        && word(1) == Some(vk::PipelineCacheHeaderVersion::ONE.as_raw() as u32)
        && word(2) == Some(props.vendor_id)
        && word(3) == Some(props.device_id)
        && data[16..32] == props.pipeline_cache_uuid
}

impl Shared {
    /// Waits for every submission in flight (nothing to wait for, the usual case, costs a lock).
    /// Called before any resource is destroyed and before host access to a buffer's memory, so
    /// that safe code cannot free or touch what a submission that was not waited for still reads
    /// or writes: a resource dropped while a frame is in flight waits for that frame.
    pub(crate) fn settle(&self) {
        let pending = self
            .in_flight
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        if !pending.is_empty() {
            // A failure here is a lost device, after which nothing the device reads matters.
            let _ = unsafe { self.device.wait_for_fences(&pending, true, u64::MAX) };
        }
    }

    /// What a pipeline's creation or destruction holds (issue 23): on a CPU device (lavapipe),
    /// the queue lock, after waiting for the device to go idle, so that no shader is compiled or
    /// freed while lavapipe's queue thread executes one, and no two are compiled at once; `None`
    /// (no lock) on a GPU. Lavapipe 22.3 builds every pipeline's shaders through the gallium
    /// context and draw module its queue thread renders with (`lvp_pipeline.c`: the queue's
    /// `pipe_context::create_*_state`), which are not made for two threads; the reported heap
    /// corruption with 128-bit vectors came from a lavapipe thread, more often the busier the
    /// machine, and weft created pipelines on two threads while a third submitted work. The
    /// environment thread and the variant threads in src/render still run: on lavapipe they take
    /// turns here. docs/regression.md, "Driver configurations".
    pub(crate) fn compile_lock(&self) -> crate::Result<Option<std::sync::MutexGuard<'_, ()>>> {
        if !self.info.is_cpu() {
            return Ok(None);
        }
        let guard = self
            .queue_lock
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        unsafe { self.device.device_wait_idle() }.map_err(vkerr("vkDeviceWaitIdle"))?;
        Ok(Some(guard))
    }
}

impl Drop for Shared {
    fn drop(&mut self) {
        // Reverse order of creation. Every resource holding an Arc<Shared> is gone by now.
        unsafe {
            let _ = self.device.device_wait_idle();
            if self.pipeline_cache != vk::PipelineCache::null() {
                // Best effort: a cache that cannot be read back or written is no cache.
                if let Ok(data) = self.device.get_pipeline_cache_data(self.pipeline_cache) {
                    if data.len() != self.pipeline_cache_loaded {
                        crate::cache::write("pipelines", &self.pipeline_cache_key, &data);
                    }
                }
                self.device
                    .destroy_pipeline_cache(self.pipeline_cache, None);
            }
            self.device.destroy_command_pool(self.command_pool, None);
            drop(self.allocator.lock().map(|mut a| a.take()));
            self.device.destroy_device(None);
            if let Some((loader, messenger)) = self.debug.take() {
                loader.destroy_debug_utils_messenger(messenger, None);
            }
            self.instance.destroy_instance(None);
        }
        let _ = &self.entry;
    }
}

/// The handle the rest of the crate uses: cheap to clone.
#[derive(Clone)]
pub struct Context {
    pub(crate) shared: Arc<Shared>,
}

unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _ty: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    if data.is_null() || user.is_null() {
        return vk::FALSE;
    }
    let message = unsafe {
        let data = &*data;
        if data.p_message.is_null() {
            String::from("(no message)")
        } else {
            CStr::from_ptr(data.p_message)
                .to_string_lossy()
                .into_owned()
        }
    };
    let level = if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
        "error"
    } else {
        "warning"
    };
    let sink = unsafe { &*(user as *const Mutex<Vec<String>>) };
    if let Ok(mut v) = sink.lock() {
        v.push(format!("[validation {level}] {message}"));
    }
    vk::FALSE
}

fn no_driver(detail: &str) -> Error {
    Error::NoVulkan(format!(
        "No Vulkan driver found ({detail}): install one, e.g. `sudo apt-get install libvulkan1 mesa-vulkan-drivers` for the lavapipe CPU driver (or run tools/setup), and check that VK_ICD_FILENAMES / VK_DRIVER_FILES, if set, point at an installed driver."
    ))
}

pub(crate) fn vkerr(what: &'static str) -> impl Fn(vk::Result) -> Error {
    move |result| {
        match result {
        vk::Result::ERROR_OUT_OF_DEVICE_MEMORY | vk::Result::ERROR_OUT_OF_HOST_MEMORY => {
            Error::device(format!("{what}: the device ran out of memory ({result}); try a smaller --size or a smaller scene"))
        }
        _ => Error::Vulkan { what, result },
    }
    }
}

/// The vector widths weft lets lavapipe generate code for (`consistent_lavapipe_cpu`): every
/// other width Mesa accepts crashed it.
const LAVAPIPE_VECTOR_BITS: [u32; 2] = [128, 256];

/// Makes lavapipe's CPU description agree with a vector width forced by `LP_NATIVE_VECTOR_WIDTH`.
///
/// Mesa's lavapipe (seen in 22.3.6) asked for 128-bit vectors on a CPU that has AVX generates a
/// vertex-shader loop eight vertices wide in its draw module while it sizes the vertex buffers for
/// counts rounded to four (plus 512 bytes): a draw of 1 to 4 vertices past a multiple of eight
/// writes up to four vertices past the end of a heap block, and the process aborts later with
/// "corrupted size vs. prev_size" and the like (issue 23; Electric Fence stops at the store:
/// docs/regression.md, "Driver configurations"). A CPU that really lacks 256-bit vectors does not
/// do this, and Mesa can be told to see the CPU as one: `GALLIUM_OVERRIDE_CPU_CAPS=sse4.1`. So
/// when the width is forced to 128 bits or fewer on an AVX CPU and the caps are not already
/// overridden, weft sets that override before the driver reads it (lavapipe reads it once, when
/// the first instance is created): the device still reports 128 bits and runs the code a 128-bit
/// CPU gets. `tests/driver_config.rs` renders the case that overflowed, under glibc's heap checker.
///
/// Asked for more than 256 bits (`LP_NATIVE_VECTOR_WIDTH=512`, which Mesa accepts), the same
/// lavapipe crashes inside LLVM (`LLVMBuildBitCast`, a segmentation fault on its queue thread)
/// at the first `vkCmdBlitImage` it runs: every mip chain weft makes (the environment's radiance
/// cube, a glTF file's textures) is made by blits, so nearly every render died (session 43;
/// docs/regression.md, "Driver configurations"). 512-bit code was no faster where it ran (an
/// AVX-512 EPYC, which splits such vectors in two), so weft caps the width at 256 bits before the
/// driver reads it, and says so once. Mesa accepts any width, and every other one tried crashed
/// every render too (32, 64, 129, 160, 192, 255: a segmentation fault or an abort at the first
/// frame); weft runs a width under 256 at 128 bits, one over it at 256.
fn consistent_lavapipe_cpu() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let asked = std::env::var("LP_NATIVE_VECTOR_WIDTH")
            .ok()
            .and_then(|v| v.trim().parse::<u32>().ok());
        let [lo, hi] = LAVAPIPE_VECTOR_BITS;
        let asked = asked.map(|bits| {
            let kept = if bits >= hi { hi } else { lo };
            if kept != bits {
                eprintln!(
                    "warning: LP_NATIVE_VECTOR_WIDTH={bits}: lavapipe (seen in Mesa 22.3) crashes \
                     at vector widths other than {lo} and {hi} bits (at 512 in its image blits); \
                     weft runs it at {kept} bits (unset the variable, or set it to {lo} or {hi}, \
                     to silence this)"
                );
                // Before any Vulkan library is loaded (see below).
                std::env::set_var("LP_NATIVE_VECTOR_WIDTH", kept.to_string());
            }
            kept
        });
        let narrow = asked == Some(lo);
        if !narrow || std::env::var_os("GALLIUM_OVERRIDE_CPU_CAPS").is_some() {
            return;
        }
        #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
        if std::arch::is_x86_feature_detected!("avx") {
            // Before any Vulkan library is loaded by this call; the Once makes every thread that
            // creates a context wait for it, and Rust's own reads of the environment take the
            // same lock as this write.
            std::env::set_var("GALLIUM_OVERRIDE_CPU_CAPS", "sse4.1");
        }
    });
}

impl Context {
    pub fn new(options: &ContextOptions) -> crate::Result<Context> {
        Context::new_for_display(options, None)
    }

    /// As [`Context::new`], able to present to windows of `display` (`weft view`): the instance
    /// gets the surface extensions the display needs, the device VK_KHR_swapchain.
    pub fn new_for_display(
        options: &ContextOptions,
        display: Option<raw_window_handle::RawDisplayHandle>,
    ) -> crate::Result<Context> {
        consistent_lavapipe_cpu();
        let entry = unsafe { ash::Entry::load() }.map_err(|e| {
            no_driver(&format!(
                "the Vulkan loader libvulkan.so.1 could not be loaded: {e}"
            ))
        })?;

        let mut layers: Vec<*const i8> = Vec::new();
        let mut extensions: Vec<*const i8> = Vec::new();
        if options.validate {
            let available = unsafe { entry.enumerate_instance_layer_properties() }
                .map_err(|e| no_driver(&format!("listing instance layers failed: {e}")))?;
            let found = available
                .iter()
                .any(|l| l.layer_name_as_c_str() == Ok(VALIDATION_LAYER));
            if !found {
                return Err(Error::NoVulkan(
                    "Vulkan validation was asked for but the Khronos validation layer is not installed: run `sudo apt-get install vulkan-validationlayers` (or tools/setup).".into(),
                ));
            }
            layers.push(VALIDATION_LAYER.as_ptr());
            extensions.push(ash::ext::debug_utils::NAME.as_ptr());
        }
        if let Some(display) = display {
            let needed = ash_window::enumerate_required_extensions(display).map_err(|e| {
                Error::device(format!(
                    "this display needs Vulkan surface extensions the driver does not offer ({e}): install a Vulkan driver with window-system support (mesa-vulkan-drivers), or use weft render"
                ))
            })?;
            extensions.extend_from_slice(needed);
        }

        let app = vk::ApplicationInfo::default()
            .application_name(c"weft")
            .engine_name(c"weft")
            .api_version(vk::API_VERSION_1_3);
        let enabled_features = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
        let mut validation_features =
            vk::ValidationFeaturesEXT::default().enabled_validation_features(&enabled_features);
        let messages: Box<Mutex<Vec<String>>> = Box::new(Mutex::new(Vec::new()));
        let mut messenger_info = vk::DebugUtilsMessengerCreateInfoEXT::default()
            .message_severity(
                vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
                    | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
            )
            .message_type(
                vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                    | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                    | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
            )
            .pfn_user_callback(Some(debug_callback))
            .user_data(&*messages as *const Mutex<Vec<String>> as *mut c_void);
        let mut create_info = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layers)
            .enabled_extension_names(&extensions);
        if options.validate {
            create_info = create_info
                .push_next(&mut validation_features)
                .push_next(&mut messenger_info);
        }
        let instance =
            unsafe { entry.create_instance(&create_info, None) }.map_err(|e| match e {
                vk::Result::ERROR_INCOMPATIBLE_DRIVER | vk::Result::ERROR_INITIALIZATION_FAILED => {
                    no_driver(&format!("creating a Vulkan 1.3 instance failed: {e}"))
                }
                other => vkerr("vkCreateInstance")(other),
            })?;
        let debug = if options.validate {
            let loader = ash::ext::debug_utils::Instance::new(&entry, &instance);
            // A fresh copy: the one above was chained into the instance's pNext list.
            let info = vk::DebugUtilsMessengerCreateInfoEXT {
                p_next: std::ptr::null(),
                ..messenger_info
            };
            match unsafe { loader.create_debug_utils_messenger(&info, None) } {
                Ok(m) => Some((loader, m)),
                Err(e) => {
                    unsafe { instance.destroy_instance(None) };
                    return Err(vkerr("vkCreateDebugUtilsMessengerEXT")(e));
                }
            }
        } else {
            None
        };

        // From here on, a failure must still destroy the instance: keep it in a guard.
        struct InstanceGuard(
            Option<(
                ash::Instance,
                Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
            )>,
        );
        impl Drop for InstanceGuard {
            fn drop(&mut self) {
                if let Some((instance, debug)) = self.0.take() {
                    unsafe {
                        if let Some((l, m)) = debug {
                            l.destroy_debug_utils_messenger(m, None);
                        }
                        instance.destroy_instance(None);
                    }
                }
            }
        }
        let mut guard = InstanceGuard(Some((instance.clone(), debug)));

        let physical_devices = unsafe { instance.enumerate_physical_devices() }
            .map_err(|e| no_driver(&format!("listing physical devices failed: {e}")))?;
        if physical_devices.is_empty() {
            return Err(no_driver("the loader found no physical device"));
        }
        let (physical, queue_family, info, limits) =
            choose_device(&instance, &physical_devices, &options.device)?;

        let mut supported13 = vk::PhysicalDeviceVulkan13Features::default();
        let mut supported = vk::PhysicalDeviceFeatures2::default().push_next(&mut supported13);
        unsafe { instance.get_physical_device_features2(physical, &mut supported) };
        // Anisotropic filtering on lavapipe (Mesa 22.3) makes a close-up render take minutes
        // instead of a second, so CPU devices filter trilinearly; real GPUs get up to 16x.
        let anisotropy = supported.features.sampler_anisotropy == vk::TRUE && !info.is_cpu();
        let float64 = supported.features.shader_float64 == vk::TRUE;
        // BC7 textures (KTX2 files in a universal format with their full mip chain, transcoded
        // on load) are uploaded as BC7 where the device samples both BC7 formats with linear
        // filtering; elsewhere as RGBA8.
        let bc7 = supported.features.texture_compression_bc == vk::TRUE
            && [vk::Format::BC7_SRGB_BLOCK, vk::Format::BC7_UNORM_BLOCK]
                .iter()
                .all(|&format| {
                    let props =
                        unsafe { instance.get_physical_device_format_properties(physical, format) };
                    props.optimal_tiling_features.contains(
                        vk::FormatFeatureFlags::SAMPLED_IMAGE
                            | vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR
                            | vk::FormatFeatureFlags::TRANSFER_DST,
                    )
                });
        let (dr, s2, m4) = (
            supported13.dynamic_rendering,
            supported13.synchronization2,
            supported13.maintenance4,
        );
        if dr != vk::TRUE || s2 != vk::TRUE || m4 != vk::TRUE {
            return Err(Error::NoVulkan(format!(
                "The Vulkan device '{}' lacks dynamic rendering, synchronization2 or maintenance4, which weft needs: update the driver (Mesa >= 22) or choose another device with --device / WEFT_DEVICE.",
                info.name
            )));
        }

        let priorities = [1.0f32];
        let queue_infos = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(queue_family)
            .queue_priorities(&priorities)];
        // Demote-to-helper: what `discard` compiles to in SPIR-V 1.6 (alphaMode MASK cut-outs in
        // gbuffer.frag and shadow_mask.frag); required of every Vulkan 1.3 device.
        let mut features13 = vk::PhysicalDeviceVulkan13Features::default()
            .dynamic_rendering(true)
            .synchronization2(true)
            .maintenance4(true)
            .shader_demote_to_helper_invocation(
                supported13.shader_demote_to_helper_invocation == vk::TRUE,
            );
        let base_features = vk::PhysicalDeviceFeatures::default()
            .sampler_anisotropy(anisotropy)
            .shader_float64(float64)
            .texture_compression_bc(bc7);
        let mut features = vk::PhysicalDeviceFeatures2::default()
            .features(base_features)
            .push_next(&mut features13);
        let device_extensions = [ash::khr::swapchain::NAME.as_ptr()];
        let mut device_info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queue_infos)
            .push_next(&mut features);
        if display.is_some() {
            device_info = device_info.enabled_extension_names(&device_extensions);
        }
        let device = unsafe { instance.create_device(physical, &device_info, None) }
            .map_err(vkerr("vkCreateDevice"))?;
        let queue = unsafe { device.get_device_queue(queue_family, 0) };

        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        let command_pool = match unsafe { device.create_command_pool(&pool_info, None) } {
            Ok(p) => p,
            Err(e) => {
                unsafe { device.destroy_device(None) };
                return Err(vkerr("vkCreateCommandPool")(e));
            }
        };
        let allocator = match Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device: physical,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        }) {
            Ok(a) => a,
            Err(e) => {
                unsafe {
                    device.destroy_command_pool(command_pool, None);
                    device.destroy_device(None);
                }
                return Err(Error::device(format!(
                    "creating the memory allocator failed: {e}"
                )));
            }
        };

        // The pipeline cache: what an earlier run compiled for this device and driver, if weft's
        // cache holds it and its header is this device's; empty otherwise, none if the driver
        // refuses even that.
        let props = unsafe { instance.get_physical_device_properties(physical) };
        let pipeline_cache_key = pipeline_cache_key(&props);
        let initial = crate::cache::read("pipelines", &pipeline_cache_key)
            .filter(|d| pipeline_cache_header_matches(d, &props))
            .unwrap_or_default();
        let create = |data: &[u8]| unsafe {
            device.create_pipeline_cache(
                &vk::PipelineCacheCreateInfo::default().initial_data(data),
                None,
            )
        };
        let (pipeline_cache, pipeline_cache_loaded) = match create(&initial) {
            Ok(c) => (c, initial.len()),
            Err(_) => (create(&[]).unwrap_or(vk::PipelineCache::null()), 0),
        };

        let (instance, debug) = guard.0.take().expect("guard holds the instance until here");
        Ok(Context {
            shared: Arc::new(Shared {
                entry,
                instance,
                debug,
                device,
                queue,
                command_pool,
                queue_lock: Mutex::new(()),
                submissions: std::sync::atomic::AtomicU64::new(0),
                in_flight: Mutex::new(Vec::new()),
                allocator: Mutex::new(Some(allocator)),
                info,
                physical,
                queue_family,
                limits,
                messages,
                anisotropy,
                bc7,
                pipeline_cache,
                pipeline_cache_loaded,
                pipeline_cache_key,
            }),
        })
    }

    pub fn info(&self) -> &DeviceInfo {
        &self.shared.info
    }

    /// Whether textures that carry a BC7 mip chain are uploaded as BC7 (the device enables
    /// `textureCompressionBC` and samples BC7 with linear filtering); `WEFT_NO_BC7=1` turns it off
    /// (the RGBA8 path, for comparison).
    pub fn samples_bc7(&self) -> bool {
        self.shared.bc7 && std::env::var_os("WEFT_NO_BC7").is_none_or(|v| v.is_empty() || v == "0")
    }

    pub fn validating(&self) -> bool {
        self.shared.debug.is_some()
    }

    /// Every validation warning and error reported since the last call.
    pub fn take_validation_messages(&self) -> Vec<String> {
        self.shared
            .messages
            .lock()
            .map(|mut v| std::mem::take(&mut *v))
            .unwrap_or_default()
    }

    /// `Err(Error::Validation)` if the validation layer reported anything since the last call.
    pub fn check_validation(&self) -> crate::Result<()> {
        let messages = self.take_validation_messages();
        if messages.is_empty() {
            Ok(())
        } else {
            Err(Error::Validation(messages))
        }
    }

    /// Makes one deliberately invalid call (a buffer with no usage flags, destroyed at once), so a
    /// test can prove that validation messages are caught.
    ///
    /// # Safety
    /// It breaks a valid-usage rule of `vkCreateBuffer` on purpose: call it only with the
    /// validation layer on (which reports it instead of letting it reach the driver), in tests.
    #[doc(hidden)]
    pub unsafe fn provoke_validation_error(&self) {
        let info = vk::BufferCreateInfo::default()
            .size(16)
            .usage(vk::BufferUsageFlags::empty());
        if let Ok(b) = unsafe { self.shared.device.create_buffer(&info, None) } {
            unsafe { self.shared.device.destroy_buffer(b, None) };
        }
    }

    /// How many queue submissions this context (and its clones) has made: `weft render --stats`
    /// reports a frame's.
    pub fn submissions(&self) -> u64 {
        self.shared
            .submissions
            .load(std::sync::atomic::Ordering::Relaxed)
    }

    pub fn wait_idle(&self) -> crate::Result<()> {
        let _queue = self
            .shared
            .queue_lock
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        unsafe { self.shared.device.device_wait_idle() }.map_err(vkerr("vkDeviceWaitIdle"))
    }
}

fn device_type_name(t: vk::PhysicalDeviceType) -> &'static str {
    match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => "discrete GPU",
        vk::PhysicalDeviceType::INTEGRATED_GPU => "integrated GPU",
        vk::PhysicalDeviceType::VIRTUAL_GPU => "virtual GPU",
        vk::PhysicalDeviceType::CPU => "cpu",
        _ => "other",
    }
}

fn choose_device(
    instance: &ash::Instance,
    devices: &[vk::PhysicalDevice],
    choice: &DeviceChoice,
) -> crate::Result<(
    vk::PhysicalDevice,
    u32,
    DeviceInfo,
    vk::PhysicalDeviceLimits,
)> {
    let mut candidates = Vec::new();
    for (index, &pd) in devices.iter().enumerate() {
        let mut driver = vk::PhysicalDeviceDriverProperties::default();
        let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut driver);
        unsafe { instance.get_physical_device_properties2(pd, &mut props2) };
        let props = props2.properties;
        // ash's bounded accessors: a name without its NUL within the array reads as "?".
        let text = |r: Result<&CStr, std::ffi::FromBytesUntilNulError>| {
            r.map(|c| c.to_string_lossy().into_owned())
                .unwrap_or_else(|_| "?".into())
        };
        let name = text(props.device_name_as_c_str());
        let driver_name = text(driver.driver_name_as_c_str());
        let driver_info = text(driver.driver_info_as_c_str());
        let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
        let family = families.iter().position(|f| {
            f.queue_flags
                .contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE)
        });
        let v = props.api_version;
        let info = DeviceInfo {
            name,
            device_type: device_type_name(props.device_type).into(),
            driver_name,
            driver_info,
            api_version: format!(
                "{}.{}.{}",
                vk::api_version_major(v),
                vk::api_version_minor(v),
                vk::api_version_patch(v)
            ),
            max_image_dimension_2d: props.limits.max_image_dimension2_d,
            device_local_heap_bytes: {
                let memory = unsafe { instance.get_physical_device_memory_properties(pd) };
                memory
                    .memory_heaps_as_slice()
                    .iter()
                    .filter(|h| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL))
                    .map(|h| h.size)
                    .max()
                    .unwrap_or(0)
            },
            timestamp_period_ns: props.limits.timestamp_period,
            timestamps: props.limits.timestamp_compute_and_graphics == vk::TRUE
                && family.is_some_and(|f| families[f].timestamp_valid_bits > 0),
            rgba32f_linear: {
                let f = unsafe {
                    instance
                        .get_physical_device_format_properties(pd, vk::Format::R32G32B32A32_SFLOAT)
                };
                f.optimal_tiling_features
                    .contains(vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR)
            },
            depth_stencil: {
                let f = unsafe {
                    instance
                        .get_physical_device_format_properties(pd, vk::Format::D32_SFLOAT_S8_UINT)
                };
                // `WEFT_NO_STENCIL=1`: as a device without it (the one-pipeline path, to compare).
                f.optimal_tiling_features.contains(
                    vk::FormatFeatureFlags::DEPTH_STENCIL_ATTACHMENT
                        | vk::FormatFeatureFlags::SAMPLED_IMAGE
                        | vk::FormatFeatureFlags::TRANSFER_SRC,
                ) && std::env::var_os("WEFT_NO_STENCIL").is_none_or(|v| v.is_empty() || v == "0")
            },
        };
        let usable = family.is_some() && v >= vk::API_VERSION_1_3;
        candidates.push((
            index,
            pd,
            family.unwrap_or(0) as u32,
            info,
            props.limits,
            props.device_type,
            usable,
        ));
    }
    let rank = |t: vk::PhysicalDeviceType| match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 3,
        _ => 4,
    };
    let list = || {
        candidates
            .iter()
            .map(|c| {
                format!(
                    "{}: {} ({}, Vulkan {})",
                    c.0, c.3.name, c.3.device_type, c.3.api_version
                )
            })
            .collect::<Vec<_>>()
            .join("; ")
    };
    let chosen = match choice {
        DeviceChoice::Auto => candidates
            .iter()
            .filter(|c| c.6)
            .min_by_key(|c| (rank(c.5), c.0)),
        DeviceChoice::Cpu => candidates
            .iter()
            .find(|c| c.6 && c.5 == vk::PhysicalDeviceType::CPU),
        DeviceChoice::Named(n) => {
            let lower = n.to_ascii_lowercase();
            candidates.iter().find(|c| {
                c.6 && (n.parse::<usize>().ok() == Some(c.0)
                    || c.3.name.to_ascii_lowercase().contains(&lower))
            })
        }
    };
    match chosen {
        Some(c) => Ok((c.1, c.2, c.3.clone(), c.4)),
        None => Err(Error::NoVulkan(format!(
            "No usable Vulkan 1.3 device matches '{}' (devices: {}): install mesa-vulkan-drivers for lavapipe, or pick another with --device / WEFT_DEVICE (auto, cpu, an index, or part of a name).",
            match choice {
                DeviceChoice::Auto => "auto".to_string(),
                DeviceChoice::Cpu => "cpu".to_string(),
                DeviceChoice::Named(n) => n.clone(),
            },
            list()
        ))),
    }
}

#[cfg(test)]
mod pipeline_cache_tests {
    use super::*;

    #[test]
    fn only_this_devices_header_is_handed_to_the_driver() {
        let mut props = vk::PhysicalDeviceProperties {
            vendor_id: 0x10de,
            device_id: 0x2330,
            ..Default::default()
        };
        props.pipeline_cache_uuid = [7; 16];
        let mut good = Vec::new();
        for w in [32u32, 1, 0x10de, 0x2330] {
            good.extend_from_slice(&w.to_le_bytes());
        }
        good.extend_from_slice(&[7; 16]);
        good.extend_from_slice(b"driver data");
        assert!(pipeline_cache_header_matches(&good, &props));
        let changed = |at: usize| {
            let mut d = good.clone();
            d[at] ^= 1;
            d
        };
        // A header smaller than Vulkan's, another version, vendor, device or UUID: not for this
        // device.
        let mut small = good.clone();
        small[0..4].copy_from_slice(&16u32.to_le_bytes());
        assert!(!pipeline_cache_header_matches(&small, &props));
        for at in [4, 8, 12, 16, 31] {
            assert!(
                !pipeline_cache_header_matches(&changed(at), &props),
                "byte {at}"
            );
        }
        // Too short, or a header size past the end.
        assert!(!pipeline_cache_header_matches(&good[..31], &props));
        let mut big = good.clone();
        big[0..4].copy_from_slice(&1000u32.to_le_bytes());
        assert!(!pipeline_cache_header_matches(&big, &props));
        assert!(!pipeline_cache_header_matches(&[], &props));
    }
}
