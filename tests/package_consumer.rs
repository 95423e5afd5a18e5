//! A standalone consumer of weft's SPIR-V package, written as another engine would use it.
//!
//! It runs `weft shaders --out DIR`, then works with nothing but `ash`, `serde_json` and the files
//! in DIR: its own Vulkan instance (Khronos validation layer on; any warning or error it reports
//! fails the test), the lavapipe CPU device, compute pipelines whose descriptor set layouts,
//! push-constant ranges, entry points and workgroup sizes all come from `manifest.json`. With them
//! it
//!
//! 1. builds weave coverage textures (every mip level) with `weave.comp.spv` and reads them back;
//! 2. evaluates the fabric BRDF with `fabric_probe.comp.spv` on the project's probe inputs.
//!
//! weft itself appears only on the CPU side, never on the GPU: its structs make the inputs
//! (`weft::fabric::WeavePush`, `weft::reference::ProbeInput`) and its CPU reference checks the
//! outputs, with the tolerances the project states (`WEAVE_TEXEL_TOLERANCE`, `ProbeBound::GPU`).
//! No `weft::vk` or `weft::render` code runs here.

use std::ffi::{c_void, CStr, CString};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Mutex;

use ash::vk;
use serde_json::Value;
use sha2::{Digest, Sha256};

use weft::fabric::{
    weave_level0_size, weave_level_size, weave_mip_count, weave_texels_cpu, FabricParams,
    WeavePattern, WEAVE_TEXEL_TOLERANCE,
};
use weft::reference::probe::{
    probe_check, probe_cpu_f64, probe_inputs, ProbeBound, ProbeInput, ProbeOutput,
};

// =============================================================================================
// The package on disk.

struct Package {
    dir: PathBuf,
    manifest: Value,
}

/// One binding of a compute module, as manifest.json gives it.
struct ManifestBinding {
    binding: u32,
    ty: vk::DescriptorType,
    count: u32,
    /// Buffers ending in a runtime array: the bytes per element.
    runtime_array_stride: Option<u64>,
    /// Storage images: the declared format (GLSL spelling).
    image_format: Option<String>,
}

/// What an engine needs to make a compute pipeline from the package.
struct ComputeModule {
    name: String,
    words: Vec<u32>,
    entry_point: CString,
    capabilities: Vec<String>,
    /// Set 0: these modules use one descriptor set.
    bindings: Vec<ManifestBinding>,
    push_constant_size: u32,
    workgroup_size: [u32; 3],
}

impl Package {
    /// Writes the package with the weft binary, as a build script of another engine would.
    fn write_with_weft(dir: &Path) -> Package {
        let out = Command::new(env!("CARGO_BIN_EXE_weft"))
            .args(["shaders", "--out"])
            .arg(dir)
            .output()
            .expect("run the weft binary");
        assert!(
            out.status.success(),
            "`weft shaders --out {}` failed:\n{}{}",
            dir.display(),
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        let text = std::fs::read_to_string(dir.join("manifest.json"))
            .expect("the package has a manifest.json");
        let manifest: Value = serde_json::from_str(&text).expect("manifest.json is JSON");
        assert_eq!(
            manifest["format_version"], 1,
            "this consumer reads package format 1"
        );
        Package {
            dir: dir.to_path_buf(),
            manifest,
        }
    }

    fn module(&self, name: &str) -> &Value {
        let modules = self.manifest["modules"]
            .as_array()
            .expect("manifest.modules");
        modules
            .iter()
            .find(|m| m["name"] == name)
            .unwrap_or_else(|| panic!("the package has no module {name}"))
    }

    /// The module's SPIR-V words, after checking its size and SHA-256 against the manifest.
    fn spirv(&self, name: &str) -> Vec<u32> {
        let m = self.module(name);
        let file = m["file"].as_str().expect("module.file");
        let bytes = std::fs::read(self.dir.join(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert_eq!(Some(bytes.len() as u64), m["size"].as_u64(), "{file}: size");
        assert_eq!(
            Some(format!("{:x}", Sha256::digest(&bytes)).as_str()),
            m["sha256"].as_str(),
            "{file}: sha256"
        );
        ash::util::read_spv(&mut std::io::Cursor::new(bytes))
            .expect("a whole number of SPIR-V words")
    }

    fn compute_module(&self, name: &str) -> ComputeModule {
        let m = self.module(name);
        assert_eq!(m["stage"], "compute", "{name}");
        let u32_of = |v: &Value| {
            v.as_u64()
                .and_then(|x| u32::try_from(x).ok())
                .expect("a u32 in manifest.json")
        };
        let bindings = m["descriptor_bindings"]
            .as_array()
            .expect("module.descriptor_bindings")
            .iter()
            .map(|b| {
                assert_eq!(b["set"], 0, "{name}: this example binds one descriptor set");
                ManifestBinding {
                    binding: u32_of(&b["binding"]),
                    ty: vk::DescriptorType::from_raw(
                        b["vk_descriptor_type"]
                            .as_i64()
                            .expect("vk_descriptor_type") as i32,
                    ),
                    count: u32_of(&b["count"]),
                    runtime_array_stride: b["runtime_array_stride"].as_u64(),
                    image_format: b["image_format"].as_str().map(String::from),
                }
            })
            .collect();
        let push = &m["push_constants"];
        let push_constant_size = if push.is_null() {
            0
        } else {
            assert_eq!(push["offset"], 0, "{name}: push constants start at 0");
            u32_of(&push["size"])
        };
        let size = m["workgroup_size"]
            .as_array()
            .expect("a compute module has workgroup_size");
        ComputeModule {
            name: name.to_string(),
            words: self.spirv(name),
            entry_point: CString::new(m["entry_point"].as_str().expect("entry_point"))
                .expect("no nul in the name"),
            capabilities: m["capabilities"]
                .as_array()
                .unwrap()
                .iter()
                .map(|c| c.as_str().unwrap().to_string())
                .collect(),
            bindings,
            push_constant_size,
            workgroup_size: [u32_of(&size[0]), u32_of(&size[1]), u32_of(&size[2])],
        }
    }
}

impl ComputeModule {
    fn binding(&self, binding: u32) -> &ManifestBinding {
        self.bindings
            .iter()
            .find(|b| b.binding == binding)
            .unwrap_or_else(|| panic!("{} has no binding {binding}", self.name))
    }
}

// =============================================================================================
// A Vulkan device on lavapipe, with the validation layer and a debug messenger.

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

struct Gpu {
    _entry: ash::Entry,
    instance: ash::Instance,
    debug_utils: ash::ext::debug_utils::Instance,
    messenger: vk::DebugUtilsMessengerEXT,
    /// Where the messenger puts every warning and error; boxed so its address outlives the
    /// instance.
    messages: Box<Mutex<Vec<String>>>,
    device: ash::Device,
    queue: vk::Queue,
    command_pool: vk::CommandPool,
    memory_properties: vk::PhysicalDeviceMemoryProperties,
}

unsafe extern "system" fn on_validation_message(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    sink: *mut c_void,
) -> vk::Bool32 {
    if !data.is_null() && !sink.is_null() {
        let text = unsafe { (*data).p_message };
        let text = if text.is_null() {
            "(no text)".into()
        } else {
            unsafe { CStr::from_ptr(text) }.to_string_lossy()
        };
        let sink = unsafe { &*(sink as *const Mutex<Vec<String>>) };
        sink.lock().unwrap().push(format!("[{severity:?}] {text}"));
    }
    vk::FALSE
}

/// A host-visible, coherent buffer, mapped for its whole life.
struct Buffer {
    raw: vk::Buffer,
    memory: vk::DeviceMemory,
    size: u64,
    mapped: *mut u8,
}

impl Buffer {
    fn bytes(&self) -> &[u8] {
        unsafe { std::slice::from_raw_parts(self.mapped, self.size as usize) }
    }
    fn bytes_mut(&mut self) -> &mut [u8] {
        unsafe { std::slice::from_raw_parts_mut(self.mapped, self.size as usize) }
    }
}

impl Gpu {
    fn new() -> Gpu {
        let entry = unsafe { ash::Entry::load() }
            .expect("the Vulkan loader (install libvulkan1; run tools/setup)");
        let layers = unsafe { entry.enumerate_instance_layer_properties() }.unwrap();
        assert!(
            layers.iter().any(|l| l.layer_name_as_c_str() == Ok(VALIDATION_LAYER)),
            "the Khronos validation layer is not installed: run tools/setup (package vulkan-validationlayers)"
        );

        let messages: Box<Mutex<Vec<String>>> = Box::default();
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
            .pfn_user_callback(Some(on_validation_message))
            .user_data(&*messages as *const Mutex<Vec<String>> as *mut c_void);
        let sync_validation = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
        let mut validation_features =
            vk::ValidationFeaturesEXT::default().enabled_validation_features(&sync_validation);
        // The package is SPIR-V 1.6: it needs a Vulkan 1.3 instance and device.
        let app = vk::ApplicationInfo::default()
            .application_name(c"package consumer")
            .api_version(vk::API_VERSION_1_3);
        let layer_names = [VALIDATION_LAYER.as_ptr()];
        let extension_names = [ash::ext::debug_utils::NAME.as_ptr()];
        let instance_info = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layer_names)
            .enabled_extension_names(&extension_names)
            .push_next(&mut validation_features)
            // Chained here too, so instance creation and destruction are validated.
            .push_next(&mut messenger_info);
        let instance =
            unsafe { entry.create_instance(&instance_info, None) }.expect("a Vulkan 1.3 instance");
        let debug_utils = ash::ext::debug_utils::Instance::new(&entry, &instance);
        let messenger_info = vk::DebugUtilsMessengerCreateInfoEXT {
            p_next: std::ptr::null(),
            ..messenger_info
        };
        let messenger =
            unsafe { debug_utils.create_debug_utils_messenger(&messenger_info, None) }.unwrap();

        // lavapipe: the CPU device, Vulkan 1.3, with a compute queue.
        let (physical, family) = unsafe { instance.enumerate_physical_devices() }
            .unwrap()
            .into_iter()
            .find_map(|pd| {
                let props = unsafe { instance.get_physical_device_properties(pd) };
                if props.device_type != vk::PhysicalDeviceType::CPU || props.api_version < vk::API_VERSION_1_3 {
                    return None;
                }
                let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
                let family = families.iter().position(|f| f.queue_flags.contains(vk::QueueFlags::COMPUTE))?;
                Some((pd, family as u32))
            })
            .expect("no Vulkan 1.3 CPU device: install Mesa's lavapipe (mesa-vulkan-drivers; run tools/setup)");
        let priorities = [1.0];
        let queue_info = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(family)
            .queue_priorities(&priorities)];
        let device_info = vk::DeviceCreateInfo::default().queue_create_infos(&queue_info);
        let device = unsafe { instance.create_device(physical, &device_info, None) }
            .expect("a lavapipe device");
        let queue = unsafe { device.get_device_queue(family, 0) };
        let pool_info = vk::CommandPoolCreateInfo::default().queue_family_index(family);
        let command_pool = unsafe { device.create_command_pool(&pool_info, None) }.unwrap();
        let memory_properties = unsafe { instance.get_physical_device_memory_properties(physical) };
        Gpu {
            _entry: entry,
            instance,
            debug_utils,
            messenger,
            messages,
            device,
            queue,
            command_pool,
            memory_properties,
        }
    }

    /// Fails the test if the validation layer reported anything so far.
    fn assert_clean(&self, after: &str) {
        let messages = std::mem::take(&mut *self.messages.lock().unwrap());
        assert!(
            messages.is_empty(),
            "validation reported {} message(s) after {after}:\n{}",
            messages.len(),
            messages.join("\n")
        );
    }

    fn memory_type(&self, allowed: u32, wanted: vk::MemoryPropertyFlags) -> u32 {
        (0..self.memory_properties.memory_type_count)
            .find(|&i| {
                allowed & (1 << i) != 0
                    && self.memory_properties.memory_types[i as usize]
                        .property_flags
                        .contains(wanted)
            })
            .unwrap_or_else(|| panic!("no memory type with {wanted:?}"))
    }

    fn buffer(&self, size: u64, usage: vk::BufferUsageFlags) -> Buffer {
        let d = &self.device;
        let raw = unsafe {
            d.create_buffer(
                &vk::BufferCreateInfo::default().size(size).usage(usage),
                None,
            )
        }
        .unwrap();
        let req = unsafe { d.get_buffer_memory_requirements(raw) };
        let host = vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT;
        let info = vk::MemoryAllocateInfo::default()
            .allocation_size(req.size)
            .memory_type_index(self.memory_type(req.memory_type_bits, host));
        let memory = unsafe { d.allocate_memory(&info, None) }.unwrap();
        unsafe { d.bind_buffer_memory(raw, memory, 0) }.unwrap();
        let mapped = unsafe { d.map_memory(memory, 0, vk::WHOLE_SIZE, vk::MemoryMapFlags::empty()) }
            .unwrap() as *mut u8;
        Buffer {
            raw,
            memory,
            size,
            mapped,
        }
    }

    fn destroy_buffer(&self, b: Buffer) {
        unsafe {
            self.device.destroy_buffer(b.raw, None);
            self.device.free_memory(b.memory, None);
        }
    }

    /// Records commands with `record`, submits them and waits.
    fn run(&self, record: impl FnOnce(vk::CommandBuffer)) {
        let d = &self.device;
        let info = vk::CommandBufferAllocateInfo::default()
            .command_pool(self.command_pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        let cmd = unsafe { d.allocate_command_buffers(&info) }.unwrap()[0];
        let begin = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        unsafe { d.begin_command_buffer(cmd, &begin) }.unwrap();
        record(cmd);
        unsafe { d.end_command_buffer(cmd) }.unwrap();
        let fence = unsafe { d.create_fence(&vk::FenceCreateInfo::default(), None) }.unwrap();
        let cmds = [cmd];
        let submit = vk::SubmitInfo::default().command_buffers(&cmds);
        unsafe {
            d.queue_submit(self.queue, &[submit], fence).unwrap();
            d.wait_for_fences(&[fence], true, u64::MAX).unwrap();
            d.destroy_fence(fence, None);
            d.free_command_buffers(self.command_pool, &cmds);
        }
    }

    /// Tears everything down and fails the test on any validation message, including leaks
    /// reported at device destruction.
    fn destroy(self) {
        unsafe {
            self.device.destroy_command_pool(self.command_pool, None);
            self.device.destroy_device(None);
        }
        self.assert_clean("destroying the device");
        unsafe {
            self.debug_utils
                .destroy_debug_utils_messenger(self.messenger, None);
            self.instance.destroy_instance(None);
        }
    }
}

// =============================================================================================
// A compute pipeline made from a package module and its manifest entry.

struct Kernel {
    set_layout: vk::DescriptorSetLayout,
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
    descriptor_pool: vk::DescriptorPool,
    push_constant_size: u32,
    workgroup_size: [u32; 3],
}

impl Kernel {
    fn new(gpu: &Gpu, module: &ComputeModule, max_sets: u32) -> Kernel {
        let d = &gpu.device;
        // This consumer enables no optional device features, so the module may only need these.
        for c in &module.capabilities {
            assert!(
                c == "Shader",
                "{} needs SPIR-V capability {c}: enable the device feature that provides it",
                module.name
            );
        }
        let bindings: Vec<_> = module
            .bindings
            .iter()
            .map(|b| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b.binding)
                    .descriptor_type(b.ty)
                    .descriptor_count(b.count)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
            })
            .collect();
        let set_layout = unsafe {
            d.create_descriptor_set_layout(
                &vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings),
                None,
            )
        }
        .unwrap();
        let set_layouts = [set_layout];
        let push_ranges = [vk::PushConstantRange {
            stage_flags: vk::ShaderStageFlags::COMPUTE,
            offset: 0,
            size: module.push_constant_size,
        }];
        let mut layout_info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
        if module.push_constant_size > 0 {
            layout_info = layout_info.push_constant_ranges(&push_ranges);
        }
        let layout = unsafe { d.create_pipeline_layout(&layout_info, None) }.unwrap();
        let shader = unsafe {
            d.create_shader_module(
                &vk::ShaderModuleCreateInfo::default().code(&module.words),
                None,
            )
        }
        .unwrap();
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(shader)
            .name(&module.entry_point);
        let info = vk::ComputePipelineCreateInfo::default()
            .stage(stage)
            .layout(layout);
        let pipeline =
            unsafe { d.create_compute_pipelines(vk::PipelineCache::null(), &[info], None) }
                .unwrap_or_else(|(_, e)| panic!("creating the {} pipeline: {e}", module.name))[0];
        unsafe { d.destroy_shader_module(shader, None) };
        let sizes: Vec<_> = module
            .bindings
            .iter()
            .map(|b| vk::DescriptorPoolSize {
                ty: b.ty,
                descriptor_count: b.count * max_sets,
            })
            .collect();
        let pool_info = vk::DescriptorPoolCreateInfo::default()
            .max_sets(max_sets)
            .pool_sizes(&sizes);
        let descriptor_pool = unsafe { d.create_descriptor_pool(&pool_info, None) }.unwrap();
        Kernel {
            set_layout,
            layout,
            pipeline,
            descriptor_pool,
            push_constant_size: module.push_constant_size,
            workgroup_size: module.workgroup_size,
        }
    }

    fn allocate_set(&self, gpu: &Gpu) -> vk::DescriptorSet {
        let layouts = [self.set_layout];
        let info = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(self.descriptor_pool)
            .set_layouts(&layouts);
        unsafe { gpu.device.allocate_descriptor_sets(&info) }.unwrap()[0]
    }

    /// Frees every set allocated so far.
    fn reset_sets(&self, gpu: &Gpu) {
        unsafe {
            gpu.device
                .reset_descriptor_pool(self.descriptor_pool, vk::DescriptorPoolResetFlags::empty())
        }
        .unwrap();
    }

    /// Records one dispatch covering `invocations` (x, y, z), rounded up to whole workgroups.
    fn dispatch(
        &self,
        gpu: &Gpu,
        cmd: vk::CommandBuffer,
        set: vk::DescriptorSet,
        push: &[u8],
        invocations: [u32; 3],
    ) {
        assert_eq!(
            push.len() as u32,
            self.push_constant_size,
            "push constants of the size manifest.json gives"
        );
        let d = &gpu.device;
        let groups = |axis: usize| invocations[axis].div_ceil(self.workgroup_size[axis]);
        unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.pipeline);
            d.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::COMPUTE,
                self.layout,
                0,
                &[set],
                &[],
            );
            if !push.is_empty() {
                d.cmd_push_constants(cmd, self.layout, vk::ShaderStageFlags::COMPUTE, 0, push);
            }
            d.cmd_dispatch(cmd, groups(0), groups(1), groups(2));
        }
    }

    fn destroy(self, gpu: &Gpu) {
        unsafe {
            gpu.device
                .destroy_descriptor_pool(self.descriptor_pool, None);
            gpu.device.destroy_pipeline(self.pipeline, None);
            gpu.device.destroy_pipeline_layout(self.layout, None);
            gpu.device
                .destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}

// =============================================================================================
// 1. The weave texture.

/// The Vulkan format of a storage image's GLSL format qualifier (those this example meets).
fn vk_format(glsl: &str) -> vk::Format {
    match glsl {
        "rgba16f" => vk::Format::R16G16B16A16_SFLOAT,
        "rgba32f" => vk::Format::R32G32B32A32_SFLOAT,
        "rgba8" => vk::Format::R8G8B8A8_UNORM,
        other => panic!("add the VkFormat of {other}"),
    }
}

fn f16_to_f32(h: u16) -> f32 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exponent = ((h >> 10) & 0x1f) as i32;
    let fraction = (h & 0x3ff) as f32;
    match exponent {
        0 => sign * fraction * 2f32.powi(-24),
        31 if fraction == 0.0 => sign * f32::INFINITY,
        31 => f32::NAN,
        e => sign * (1.0 + fraction / 1024.0) * 2f32.powi(e - 15),
    }
}

/// Builds every mip level of `params`' weave texture with `weave.comp` and reads them back:
/// per level, its texels (RGBA, rows top to bottom).
fn build_weave_texture(
    gpu: &Gpu,
    kernel: &Kernel,
    module: &ComputeModule,
    params: &FabricParams,
) -> Vec<Vec<[f32; 4]>> {
    let d = &gpu.device;
    let target = module.binding(0);
    assert_eq!(
        target.ty,
        vk::DescriptorType::STORAGE_IMAGE,
        "weave.comp writes a storage image at binding 0"
    );
    let format = vk_format(
        target
            .image_format
            .as_deref()
            .expect("a storage image declares its format"),
    );

    let level0 = weave_level0_size(&params.pattern);
    let levels = weave_mip_count(level0);
    let sizes: Vec<(u32, u32)> = (0..levels).map(|l| weave_level_size(level0, l)).collect();
    let image_info = vk::ImageCreateInfo::default()
        .image_type(vk::ImageType::TYPE_2D)
        .format(format)
        .extent(vk::Extent3D {
            width: level0.0,
            height: level0.1,
            depth: 1,
        })
        .mip_levels(levels)
        .array_layers(1)
        .samples(vk::SampleCountFlags::TYPE_1)
        .tiling(vk::ImageTiling::OPTIMAL)
        // A renderer adds SAMPLED and samples it; this example reads it back.
        .usage(vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC)
        .initial_layout(vk::ImageLayout::UNDEFINED);
    let image = unsafe { d.create_image(&image_info, None) }.unwrap();
    let req = unsafe { d.get_image_memory_requirements(image) };
    let alloc = vk::MemoryAllocateInfo::default()
        .allocation_size(req.size)
        .memory_type_index(
            gpu.memory_type(req.memory_type_bits, vk::MemoryPropertyFlags::DEVICE_LOCAL),
        );
    let memory = unsafe { d.allocate_memory(&alloc, None) }.unwrap();
    unsafe { d.bind_image_memory(image, memory, 0) }.unwrap();
    let range = |level: u32, count: u32| vk::ImageSubresourceRange {
        aspect_mask: vk::ImageAspectFlags::COLOR,
        base_mip_level: level,
        level_count: count,
        base_array_layer: 0,
        layer_count: 1,
    };
    // weave.comp writes one level at a time, through a view of that level alone.
    let views: Vec<vk::ImageView> = (0..levels)
        .map(|l| {
            let info = vk::ImageViewCreateInfo::default()
                .image(image)
                .view_type(vk::ImageViewType::TYPE_2D)
                .format(format)
                .subresource_range(range(l, 1));
            unsafe { d.create_image_view(&info, None) }.unwrap()
        })
        .collect();
    let sets: Vec<vk::DescriptorSet> = views
        .iter()
        .map(|&view| {
            let set = kernel.allocate_set(gpu);
            let image_info = [vk::DescriptorImageInfo {
                sampler: vk::Sampler::null(),
                image_view: view,
                image_layout: vk::ImageLayout::GENERAL,
            }];
            let write = vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(target.binding)
                .descriptor_type(target.ty)
                .image_info(&image_info);
            unsafe { d.update_descriptor_sets(&[write], &[]) };
            set
        })
        .collect();

    const TEXEL_BYTES: u64 = 8; // RGBA16F
    let offsets: Vec<u64> = sizes
        .iter()
        .scan(0, |at, &(w, h)| {
            let here = *at;
            *at += w as u64 * h as u64 * TEXEL_BYTES;
            Some(here)
        })
        .collect();
    let total = offsets.last().unwrap()
        + sizes
            .last()
            .map(|&(w, h)| w as u64 * h as u64 * TEXEL_BYTES)
            .unwrap();
    let readback = gpu.buffer(total, vk::BufferUsageFlags::TRANSFER_DST);

    gpu.run(|cmd| unsafe {
        let to_general = vk::ImageMemoryBarrier::default()
            .dst_access_mask(vk::AccessFlags::SHADER_WRITE)
            .old_layout(vk::ImageLayout::UNDEFINED)
            .new_layout(vk::ImageLayout::GENERAL)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(image)
            .subresource_range(range(0, levels));
        d.cmd_pipeline_barrier(
            cmd,
            vk::PipelineStageFlags::TOP_OF_PIPE,
            vk::PipelineStageFlags::COMPUTE_SHADER,
            vk::DependencyFlags::empty(),
            &[],
            &[],
            &[to_general],
        );
        for (l, &(w, h)) in sizes.iter().enumerate() {
            let push = params.weave_push(w, h).to_bytes();
            kernel.dispatch(gpu, cmd, sets[l], &push, [w, h, 1]);
        }
        let to_transfer = vk::ImageMemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::SHADER_WRITE)
            .dst_access_mask(vk::AccessFlags::TRANSFER_READ)
            .old_layout(vk::ImageLayout::GENERAL)
            .new_layout(vk::ImageLayout::TRANSFER_SRC_OPTIMAL)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(image)
            .subresource_range(range(0, levels));
        d.cmd_pipeline_barrier(
            cmd,
            vk::PipelineStageFlags::COMPUTE_SHADER,
            vk::PipelineStageFlags::TRANSFER,
            vk::DependencyFlags::empty(),
            &[],
            &[],
            &[to_transfer],
        );
        let regions: Vec<vk::BufferImageCopy> = sizes
            .iter()
            .zip(&offsets)
            .enumerate()
            .map(|(l, (&(w, h), &offset))| vk::BufferImageCopy {
                buffer_offset: offset,
                buffer_row_length: 0,
                buffer_image_height: 0,
                image_subresource: vk::ImageSubresourceLayers {
                    aspect_mask: vk::ImageAspectFlags::COLOR,
                    mip_level: l as u32,
                    base_array_layer: 0,
                    layer_count: 1,
                },
                image_offset: vk::Offset3D::default(),
                image_extent: vk::Extent3D {
                    width: w,
                    height: h,
                    depth: 1,
                },
            })
            .collect();
        d.cmd_copy_image_to_buffer(
            cmd,
            image,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            readback.raw,
            &regions,
        );
        let to_host = vk::MemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
            .dst_access_mask(vk::AccessFlags::HOST_READ);
        d.cmd_pipeline_barrier(
            cmd,
            vk::PipelineStageFlags::TRANSFER,
            vk::PipelineStageFlags::HOST,
            vk::DependencyFlags::empty(),
            &[to_host],
            &[],
            &[],
        );
    });

    let halves: Vec<f32> = readback
        .bytes()
        .chunks_exact(2)
        .map(|b| f16_to_f32(u16::from_le_bytes([b[0], b[1]])))
        .collect();
    let texels = sizes
        .iter()
        .zip(&offsets)
        .map(|(&(w, h), &offset)| {
            let start = (offset / 2) as usize;
            halves[start..start + (w * h * 4) as usize]
                .chunks_exact(4)
                .map(|t| [t[0], t[1], t[2], t[3]])
                .collect()
        })
        .collect();

    gpu.destroy_buffer(readback);
    kernel.reset_sets(gpu);
    unsafe {
        for v in views {
            d.destroy_image_view(v, None);
        }
        d.destroy_image(image, None);
        d.free_memory(memory, None);
    }
    texels
}

#[test]
fn weave_textures_built_from_the_package_match_the_cpu_reference() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let package = Package::write_with_weft(dir.path());
    let module = package.compute_module("weave.comp");
    let gpu = Gpu::new();
    // Up to 8 × 32 texels along a side: at most 9 levels, one set each.
    let kernel = Kernel::new(&gpu, &module, 16);
    gpu.assert_clean("creating the weave.comp pipeline");

    let variants = [
        ("plain (defaults)", FabricParams::default()),
        (
            "twill",
            FabricParams {
                pattern: WeavePattern::twill(),
                gap: 0.008,
                shadow_width: 0.5,
                ..Default::default()
            },
        ),
        (
            "satin",
            FabricParams {
                pattern: WeavePattern::satin(),
                gap: 0.0,
                shadow_strength: 1.0,
                ..Default::default()
            },
        ),
        (
            "custom 3x2",
            FabricParams {
                pattern: WeavePattern::from_rows(&["--|", "|-|"]).unwrap(),
                gap: 0.01,
                ..Default::default()
            },
        ),
    ];
    let mut failures = Vec::new();
    for (name, params) in &variants {
        let levels = build_weave_texture(&gpu, &kernel, &module, params);
        gpu.assert_clean(&format!("building the {name} weave texture"));
        let level0 = weave_level0_size(&params.pattern);
        assert_eq!(levels.len() as u32, weave_mip_count(level0));
        let mut worst = 0f32;
        for (l, gpu_texels) in levels.iter().enumerate() {
            let (w, h) = weave_level_size(level0, l as u32);
            let cpu_texels = weave_texels_cpu(&params.weave_push(w, h));
            assert_eq!(gpu_texels.len(), cpu_texels.len());
            for (i, (g, c)) in gpu_texels.iter().zip(&cpu_texels).enumerate() {
                for k in 0..4 {
                    let diff = (g[k] - c[k]).abs();
                    worst = worst.max(diff);
                    let within = diff <= WEAVE_TEXEL_TOLERANCE; // false for NaN
                    if !within && failures.len() < 20 {
                        failures.push(format!(
                            "{name}, level {l} ({w}x{h}), texel ({}, {}), channel {k}: GPU {} vs CPU {}",
                            i as u32 % w,
                            i as u32 / w,
                            g[k],
                            c[k]
                        ));
                    }
                }
            }
        }
        eprintln!(
            "weave {name}: {} levels, largest |GPU - CPU| {worst:e} (tolerance {WEAVE_TEXEL_TOLERANCE:e})",
            levels.len()
        );
    }
    kernel.destroy(&gpu);
    gpu.destroy();
    assert!(
        failures.is_empty(),
        "weave texels outside WEAVE_TEXEL_TOLERANCE:\n{}",
        failures.join("\n")
    );
}

// =============================================================================================
// 2. The BRDF probe.

#[test]
fn the_brdf_evaluated_from_the_package_matches_the_cpu_reference() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let package = Package::write_with_weft(dir.path());
    let module = package.compute_module("fabric_probe.comp");
    let gpu = Gpu::new();
    let kernel = Kernel::new(&gpu, &module, 1);
    gpu.assert_clean("creating the fabric_probe.comp pipeline");

    // The project's probe batch: every hard case, then seeded random inputs.
    let cases = probe_inputs(0x5eed, 4000);
    let count = cases.len() as u64;
    let (inputs, outputs) = (module.binding(0), module.binding(1));
    let in_stride = inputs
        .runtime_array_stride
        .expect("the inputs are a runtime array");
    let out_stride = outputs
        .runtime_array_stride
        .expect("the outputs are a runtime array");
    assert_eq!(
        in_stride,
        std::mem::size_of::<ProbeInput>() as u64,
        "ProbeInput's size"
    );
    assert_eq!(
        out_stride,
        std::mem::size_of::<ProbeOutput>() as u64,
        "ProbeOutput's size"
    );

    let mut input_buffer = gpu.buffer(count * in_stride, vk::BufferUsageFlags::STORAGE_BUFFER);
    for (slot, case) in input_buffer
        .bytes_mut()
        .chunks_exact_mut(in_stride as usize)
        .zip(&cases)
    {
        slot.copy_from_slice(&case.input.to_bytes());
    }
    let mut output_buffer = gpu.buffer(count * out_stride, vk::BufferUsageFlags::STORAGE_BUFFER);
    // NaN everywhere, so an output the shader never wrote fails the comparison.
    output_buffer.bytes_mut().fill(0xff);

    let set = kernel.allocate_set(&gpu);
    let infos = [
        [vk::DescriptorBufferInfo {
            buffer: input_buffer.raw,
            offset: 0,
            range: vk::WHOLE_SIZE,
        }],
        [vk::DescriptorBufferInfo {
            buffer: output_buffer.raw,
            offset: 0,
            range: vk::WHOLE_SIZE,
        }],
    ];
    let writes: Vec<_> = [inputs, outputs]
        .into_iter()
        .zip(&infos)
        .map(|(b, info)| {
            vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(b.binding)
                .descriptor_type(b.ty)
                .buffer_info(info)
        })
        .collect();
    unsafe { gpu.device.update_descriptor_sets(&writes, &[]) };

    gpu.run(|cmd| {
        let push = (count as u32).to_le_bytes(); // `uint count`
        kernel.dispatch(&gpu, cmd, set, &push, [count as u32, 1, 1]);
        let to_host = vk::MemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::SHADER_WRITE)
            .dst_access_mask(vk::AccessFlags::HOST_READ);
        unsafe {
            gpu.device.cmd_pipeline_barrier(
                cmd,
                vk::PipelineStageFlags::COMPUTE_SHADER,
                vk::PipelineStageFlags::HOST,
                vk::DependencyFlags::empty(),
                &[to_host],
                &[],
                &[],
            )
        };
    });
    gpu.assert_clean("running the probe");

    let mut failures = Vec::new();
    for (case, bytes) in cases
        .iter()
        .zip(output_buffer.bytes().chunks_exact(out_stride as usize))
    {
        let got = ProbeOutput::from_bytes(bytes);
        let reference = probe_cpu_f64(&case.input);
        let messages = probe_check(&case.input, &reference, &got, &ProbeBound::GPU);
        if !messages.is_empty() {
            failures.push(format!("{}:\n    {}", case.name, messages.join("\n    ")));
        }
    }
    eprintln!(
        "probe: {count} inputs through fabric_probe.comp.spv, {} outside ProbeBound::GPU",
        failures.len()
    );

    gpu.destroy_buffer(input_buffer);
    gpu.destroy_buffer(output_buffer);
    kernel.destroy(&gpu);
    gpu.destroy();
    assert!(
        failures.is_empty(),
        "{} of {count} probe inputs differ from the CPU reference by more than ProbeBound::GPU:\n{}",
        failures.len(),
        failures.iter().take(20).cloned().collect::<Vec<_>>().join("\n")
    );
}
