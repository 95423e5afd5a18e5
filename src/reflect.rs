//! A small SPIR-V reader: what a Vulkan program must know to bind and call a module, read from
//! the module's words (OpEntryPoint, OpExecutionMode(Id), OpDecorate/OpMemberDecorate, OpType*,
//! OpConstant*/OpSpecConstant*, OpVariable). It reads the logical-addressing modules glslang
//! emits for Vulkan; it is no validator (`spirv-val` is, and the package tests run it).
//!
//! Opcode, decoration and enumerant numbers come from the `spirv` crate's enums (the SPIR-V
//! grammar, generated), not a hand-written table.

use std::collections::{BTreeSet, HashMap};

const MAGIC: u32 = spirv::MAGIC_NUMBER;

// Opcodes.
const OP_EXTENSION: u32 = spirv::Op::Extension as u32;
const OP_ENTRY_POINT: u32 = spirv::Op::EntryPoint as u32;
const OP_EXECUTION_MODE: u32 = spirv::Op::ExecutionMode as u32;
const OP_CAPABILITY: u32 = spirv::Op::Capability as u32;
const OP_TYPE_VOID: u32 = spirv::Op::TypeVoid as u32;
const OP_TYPE_BOOL: u32 = spirv::Op::TypeBool as u32;
const OP_TYPE_INT: u32 = spirv::Op::TypeInt as u32;
const OP_TYPE_FLOAT: u32 = spirv::Op::TypeFloat as u32;
const OP_TYPE_VECTOR: u32 = spirv::Op::TypeVector as u32;
const OP_TYPE_MATRIX: u32 = spirv::Op::TypeMatrix as u32;
const OP_TYPE_IMAGE: u32 = spirv::Op::TypeImage as u32;
const OP_TYPE_SAMPLER: u32 = spirv::Op::TypeSampler as u32;
const OP_TYPE_SAMPLED_IMAGE: u32 = spirv::Op::TypeSampledImage as u32;
const OP_TYPE_ARRAY: u32 = spirv::Op::TypeArray as u32;
const OP_TYPE_RUNTIME_ARRAY: u32 = spirv::Op::TypeRuntimeArray as u32;
const OP_TYPE_STRUCT: u32 = spirv::Op::TypeStruct as u32;
const OP_TYPE_POINTER: u32 = spirv::Op::TypePointer as u32;
const OP_CONSTANT_TRUE: u32 = spirv::Op::ConstantTrue as u32;
const OP_CONSTANT_FALSE: u32 = spirv::Op::ConstantFalse as u32;
const OP_CONSTANT: u32 = spirv::Op::Constant as u32;
const OP_CONSTANT_COMPOSITE: u32 = spirv::Op::ConstantComposite as u32;
const OP_SPEC_CONSTANT_TRUE: u32 = spirv::Op::SpecConstantTrue as u32;
const OP_SPEC_CONSTANT_FALSE: u32 = spirv::Op::SpecConstantFalse as u32;
const OP_SPEC_CONSTANT: u32 = spirv::Op::SpecConstant as u32;
const OP_SPEC_CONSTANT_COMPOSITE: u32 = spirv::Op::SpecConstantComposite as u32;
const OP_FUNCTION: u32 = spirv::Op::Function as u32;
const OP_VARIABLE: u32 = spirv::Op::Variable as u32;
const OP_DECORATE: u32 = spirv::Op::Decorate as u32;
const OP_MEMBER_DECORATE: u32 = spirv::Op::MemberDecorate as u32;
const OP_EXECUTION_MODE_ID: u32 = spirv::Op::ExecutionModeId as u32;
const OP_TYPE_ACCELERATION_STRUCTURE: u32 = spirv::Op::TypeAccelerationStructureKHR as u32;

// Decorations.
const DEC_SPEC_ID: u32 = spirv::Decoration::SpecId as u32;
const DEC_BLOCK: u32 = spirv::Decoration::Block as u32;
const DEC_BUFFER_BLOCK: u32 = spirv::Decoration::BufferBlock as u32;
const DEC_ARRAY_STRIDE: u32 = spirv::Decoration::ArrayStride as u32;
const DEC_MATRIX_STRIDE: u32 = spirv::Decoration::MatrixStride as u32;
const DEC_BUILT_IN: u32 = spirv::Decoration::BuiltIn as u32;
const DEC_NON_WRITABLE: u32 = spirv::Decoration::NonWritable as u32;
const DEC_NON_READABLE: u32 = spirv::Decoration::NonReadable as u32;
const DEC_LOCATION: u32 = spirv::Decoration::Location as u32;
const DEC_BINDING: u32 = spirv::Decoration::Binding as u32;
const DEC_DESCRIPTOR_SET: u32 = spirv::Decoration::DescriptorSet as u32;
const DEC_OFFSET: u32 = spirv::Decoration::Offset as u32;
const BUILT_IN_WORKGROUP_SIZE: u32 = spirv::BuiltIn::WorkgroupSize as u32;

// Storage classes.
const SC_UNIFORM_CONSTANT: u32 = spirv::StorageClass::UniformConstant as u32;
const SC_INPUT: u32 = spirv::StorageClass::Input as u32;
const SC_UNIFORM: u32 = spirv::StorageClass::Uniform as u32;
const SC_OUTPUT: u32 = spirv::StorageClass::Output as u32;
const SC_PUSH_CONSTANT: u32 = spirv::StorageClass::PushConstant as u32;
const SC_STORAGE_BUFFER: u32 = spirv::StorageClass::StorageBuffer as u32;

// Execution modes.
const MODE_LOCAL_SIZE: u32 = spirv::ExecutionMode::LocalSize as u32;
const MODE_LOCAL_SIZE_ID: u32 = spirv::ExecutionMode::LocalSizeId as u32;

// Image dimensions.
const DIM_BUFFER: u32 = spirv::Dim::DimBuffer as u32;
const DIM_SUBPASS_DATA: u32 = spirv::Dim::DimSubpassData as u32;

/// What a module needs bound and how it is called, for its first entry point.
#[derive(Clone, Debug, PartialEq)]
pub struct Reflection {
    /// SPIR-V version (major, minor).
    pub version: (u32, u32),
    pub entry_point: String,
    /// The SPIR-V execution model of the entry point (0 vertex, 4 fragment, 5 GLCompute, ...).
    pub execution_model: u32,
    pub capabilities: Vec<String>,
    pub extensions: Vec<String>,
    /// Sorted by (set, binding).
    pub bindings: Vec<DescriptorBinding>,
    pub push_constants: Option<PushConstantRange>,
    /// Sorted by id.
    pub spec_constants: Vec<SpecConstant>,
    /// Compute only.
    pub workgroup_size: Option<WorkgroupSize>,
    /// User (non-built-in) inputs and outputs by location, sorted.
    pub inputs: Vec<InterfaceVariable>,
    pub outputs: Vec<InterfaceVariable>,
}

/// The Vulkan descriptor type a binding needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum DescriptorKind {
    Sampler,
    CombinedImageSampler,
    SampledImage,
    StorageImage,
    UniformTexelBuffer,
    StorageTexelBuffer,
    UniformBuffer,
    StorageBuffer,
    InputAttachment,
    AccelerationStructure,
}

impl DescriptorKind {
    /// The name used in manifest.json: `VK_DESCRIPTOR_TYPE_<NAME>` in lower case.
    pub fn name(self) -> &'static str {
        match self {
            DescriptorKind::Sampler => "sampler",
            DescriptorKind::CombinedImageSampler => "combined_image_sampler",
            DescriptorKind::SampledImage => "sampled_image",
            DescriptorKind::StorageImage => "storage_image",
            DescriptorKind::UniformTexelBuffer => "uniform_texel_buffer",
            DescriptorKind::StorageTexelBuffer => "storage_texel_buffer",
            DescriptorKind::UniformBuffer => "uniform_buffer",
            DescriptorKind::StorageBuffer => "storage_buffer",
            DescriptorKind::InputAttachment => "input_attachment",
            DescriptorKind::AccelerationStructure => "acceleration_structure",
        }
    }

    /// The `VkDescriptorType` value.
    pub fn vk_value(self) -> i32 {
        match self {
            DescriptorKind::Sampler => 0,
            DescriptorKind::CombinedImageSampler => 1,
            DescriptorKind::SampledImage => 2,
            DescriptorKind::StorageImage => 3,
            DescriptorKind::UniformTexelBuffer => 4,
            DescriptorKind::StorageTexelBuffer => 5,
            DescriptorKind::UniformBuffer => 6,
            DescriptorKind::StorageBuffer => 7,
            DescriptorKind::InputAttachment => 10,
            DescriptorKind::AccelerationStructure => 1_000_150_000,
        }
    }
}

/// Whether the shader reads or writes a storage resource (from NonWritable/NonReadable).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    ReadOnly,
    WriteOnly,
    ReadWrite,
}

impl Access {
    pub fn name(self) -> &'static str {
        match self {
            Access::ReadOnly => "read_only",
            Access::WriteOnly => "write_only",
            Access::ReadWrite => "read_write",
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct DescriptorBinding {
    pub set: u32,
    pub binding: u32,
    pub kind: DescriptorKind,
    /// Array size; 0 for a runtime-sized array.
    pub count: u32,
    pub access: Access,
    /// Storage and sampled images: the declared format, GLSL spelling (`rgba16f`); None = unknown.
    pub image_format: Option<&'static str>,
    /// Buffers: the block's size in bytes without a trailing runtime array (the least a bound
    /// range may hold), and that array's element stride.
    pub block_size: Option<u32>,
    pub runtime_array_stride: Option<u32>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PushConstantRange {
    pub offset: u32,
    pub size: u32,
}

/// A specialization constant's default value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SpecValue {
    Bool(bool),
    Int(i64),
    UInt(u64),
    Float(f64),
}

#[derive(Clone, Debug, PartialEq)]
pub struct SpecConstant {
    pub id: u32,
    /// `bool`, `int32`, `uint32`, `float32`, `float64`, ...
    pub ty: String,
    pub default: SpecValue,
}

/// A compute entry point's local size; an axis set by a specialization constant names its id.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WorkgroupSize {
    pub size: [u32; 3],
    pub spec_ids: [Option<u32>; 3],
}

#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct InterfaceVariable {
    pub location: u32,
    /// GLSL spelling: `vec4`, `uvec2`, `float[2]`, ...
    pub ty: String,
}

#[derive(Clone, Debug)]
enum Type {
    Void,
    Bool,
    Int { width: u32, signed: bool },
    Float { width: u32 },
    Vector { component: u32, count: u32 },
    Matrix { column: u32, count: u32 },
    Image { dim: u32, sampled: u32, format: u32 },
    Sampler,
    SampledImage,
    Array { element: u32, length: u32 },
    RuntimeArray { element: u32 },
    Struct { members: Vec<u32> },
    Pointer { pointee: u32 },
    AccelerationStructure,
}

#[derive(Clone, Debug)]
enum Constant {
    Scalar {
        ty: u32,
        words: Vec<u32>,
        spec: bool,
    },
    Bool {
        value: bool,
        spec: bool,
    },
    Composite {
        parts: Vec<u32>,
    },
}

#[derive(Default)]
struct Decorations {
    /// (id, decoration) -> first literal (0 when the decoration has none).
    on_id: HashMap<(u32, u32), u32>,
    /// (struct id, member, decoration) -> first literal.
    on_member: HashMap<(u32, u32, u32), u32>,
}

impl Decorations {
    fn get(&self, id: u32, decoration: u32) -> Option<u32> {
        self.on_id.get(&(id, decoration)).copied()
    }
    fn has(&self, id: u32, decoration: u32) -> bool {
        self.on_id.contains_key(&(id, decoration))
    }
    fn member(&self, id: u32, member: u32, decoration: u32) -> Option<u32> {
        self.on_member.get(&(id, member, decoration)).copied()
    }
}

struct EntryPoint {
    model: u32,
    function: u32,
    name: String,
    interface: Vec<u32>,
}

/// The module's words, decoded into the tables reflection needs.
struct Module {
    version: (u32, u32),
    capabilities: Vec<u32>,
    extensions: Vec<String>,
    entry_points: Vec<EntryPoint>,
    /// (function, mode) -> operands.
    modes: HashMap<(u32, u32), Vec<u32>>,
    decorations: Decorations,
    types: HashMap<u32, Type>,
    constants: HashMap<u32, Constant>,
    /// (id, pointer type, storage class), in module order.
    variables: Vec<(u32, u32, u32)>,
}

/// How deeply types may nest (arrays of structs of arrays ...): far beyond any shader's, and a
/// bound on the recursion a hostile module's cyclic type ids could cause.
const MAX_TYPE_DEPTH: u32 = 64;

/// Reflects a SPIR-V module (little-endian words). Any malformed module is an
/// [`Error::Input`](crate::Error::Input) saying what is wrong, never a panic.
pub fn reflect(bytes: &[u8]) -> crate::Result<Reflection> {
    reflect_words(bytes).map_err(crate::Error::Input)
}

fn reflect_words(bytes: &[u8]) -> Result<Reflection, String> {
    if bytes.len() % 4 != 0 || bytes.len() < 20 {
        return Err(format!(
            "{} bytes is not a SPIR-V module (a multiple of 4, at least 20)",
            bytes.len()
        ));
    }
    let words: Vec<u32> = bytes
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    Module::parse(&words)?.reflect()
}

/// A nul-terminated UTF-8 literal string at the start of `words`; returns it and the words used.
fn literal_string(words: &[u32]) -> Result<(String, usize), String> {
    let mut bytes = Vec::new();
    for (i, w) in words.iter().enumerate() {
        for b in w.to_le_bytes() {
            if b == 0 {
                let s = String::from_utf8(bytes)
                    .map_err(|_| "a literal string is not UTF-8".to_string())?;
                return Ok((s, i + 1));
            }
            bytes.push(b);
        }
    }
    Err("a literal string has no terminating nul".into())
}

impl Module {
    fn parse(words: &[u32]) -> Result<Module, String> {
        if words[0] != MAGIC {
            return Err(format!(
                "bad magic number {:#010x} (a big-endian or non-SPIR-V file?)",
                words[0]
            ));
        }
        let mut m = Module {
            version: ((words[1] >> 16) & 0xff, (words[1] >> 8) & 0xff),
            capabilities: Vec::new(),
            extensions: Vec::new(),
            entry_points: Vec::new(),
            modes: HashMap::new(),
            decorations: Decorations::default(),
            types: HashMap::new(),
            constants: HashMap::new(),
            variables: Vec::new(),
        };
        let mut at = 5;
        while at < words.len() {
            let count = (words[at] >> 16) as usize;
            let opcode = words[at] & 0xffff;
            if count == 0 || at + count > words.len() {
                return Err(format!("instruction at word {at} has a bad length {count}"));
            }
            let ops = &words[at + 1..at + count];
            let need = |n: usize| {
                if ops.len() < n {
                    Err(format!(
                        "opcode {opcode} at word {at} has {} operands, needs {n}",
                        ops.len()
                    ))
                } else {
                    Ok(())
                }
            };
            match opcode {
                OP_CAPABILITY => {
                    need(1)?;
                    m.capabilities.push(ops[0]);
                }
                OP_EXTENSION => m.extensions.push(literal_string(ops)?.0),
                OP_ENTRY_POINT => {
                    need(3)?;
                    let (name, used) = literal_string(&ops[2..])?;
                    m.entry_points.push(EntryPoint {
                        model: ops[0],
                        function: ops[1],
                        name,
                        interface: ops[2 + used..].to_vec(),
                    });
                }
                OP_EXECUTION_MODE | OP_EXECUTION_MODE_ID => {
                    need(2)?;
                    m.modes.insert((ops[0], ops[1]), ops[2..].to_vec());
                }
                OP_DECORATE => {
                    need(2)?;
                    m.decorations
                        .on_id
                        .insert((ops[0], ops[1]), ops.get(2).copied().unwrap_or(0));
                }
                OP_MEMBER_DECORATE => {
                    need(3)?;
                    m.decorations
                        .on_member
                        .insert((ops[0], ops[1], ops[2]), ops.get(3).copied().unwrap_or(0));
                }
                OP_TYPE_VOID | OP_TYPE_BOOL | OP_TYPE_SAMPLER | OP_TYPE_ACCELERATION_STRUCTURE => {
                    need(1)?;
                    let ty = match opcode {
                        OP_TYPE_VOID => Type::Void,
                        OP_TYPE_BOOL => Type::Bool,
                        OP_TYPE_SAMPLER => Type::Sampler,
                        _ => Type::AccelerationStructure,
                    };
                    m.types.insert(ops[0], ty);
                }
                OP_TYPE_INT => {
                    need(3)?;
                    m.types.insert(
                        ops[0],
                        Type::Int {
                            width: ops[1],
                            signed: ops[2] == 1,
                        },
                    );
                }
                OP_TYPE_FLOAT => {
                    need(2)?;
                    m.types.insert(ops[0], Type::Float { width: ops[1] });
                }
                OP_TYPE_VECTOR => {
                    need(3)?;
                    m.types.insert(
                        ops[0],
                        Type::Vector {
                            component: ops[1],
                            count: ops[2],
                        },
                    );
                }
                OP_TYPE_MATRIX => {
                    need(3)?;
                    m.types.insert(
                        ops[0],
                        Type::Matrix {
                            column: ops[1],
                            count: ops[2],
                        },
                    );
                }
                OP_TYPE_IMAGE => {
                    need(8)?;
                    m.types.insert(
                        ops[0],
                        Type::Image {
                            dim: ops[2],
                            sampled: ops[6],
                            format: ops[7],
                        },
                    );
                }
                OP_TYPE_SAMPLED_IMAGE => {
                    need(2)?;
                    m.types.insert(ops[0], Type::SampledImage);
                }
                OP_TYPE_ARRAY => {
                    need(3)?;
                    m.types.insert(
                        ops[0],
                        Type::Array {
                            element: ops[1],
                            length: ops[2],
                        },
                    );
                }
                OP_TYPE_RUNTIME_ARRAY => {
                    need(2)?;
                    m.types
                        .insert(ops[0], Type::RuntimeArray { element: ops[1] });
                }
                OP_TYPE_STRUCT => {
                    need(1)?;
                    m.types.insert(
                        ops[0],
                        Type::Struct {
                            members: ops[1..].to_vec(),
                        },
                    );
                }
                OP_TYPE_POINTER => {
                    need(3)?;
                    m.types.insert(ops[0], Type::Pointer { pointee: ops[2] });
                }
                OP_CONSTANT | OP_SPEC_CONSTANT => {
                    need(3)?;
                    let spec = opcode == OP_SPEC_CONSTANT;
                    m.constants.insert(
                        ops[1],
                        Constant::Scalar {
                            ty: ops[0],
                            words: ops[2..].to_vec(),
                            spec,
                        },
                    );
                }
                OP_CONSTANT_TRUE
                | OP_CONSTANT_FALSE
                | OP_SPEC_CONSTANT_TRUE
                | OP_SPEC_CONSTANT_FALSE => {
                    need(2)?;
                    let value = matches!(opcode, OP_CONSTANT_TRUE | OP_SPEC_CONSTANT_TRUE);
                    let spec = matches!(opcode, OP_SPEC_CONSTANT_TRUE | OP_SPEC_CONSTANT_FALSE);
                    m.constants.insert(ops[1], Constant::Bool { value, spec });
                }
                OP_CONSTANT_COMPOSITE | OP_SPEC_CONSTANT_COMPOSITE => {
                    need(2)?;
                    m.constants.insert(
                        ops[1],
                        Constant::Composite {
                            parts: ops[2..].to_vec(),
                        },
                    );
                }
                OP_VARIABLE => {
                    need(3)?;
                    m.variables.push((ops[1], ops[0], ops[2]));
                }
                // Declarations end where the first function begins.
                OP_FUNCTION => break,
                _ => {}
            }
            at += count;
        }
        Ok(m)
    }

    fn ty(&self, id: u32) -> Result<&Type, String> {
        self.types
            .get(&id)
            .ok_or_else(|| format!("type %{id} is not declared"))
    }

    /// The value of an integer constant (a specialization constant's default), for array lengths
    /// and local sizes.
    fn constant_u32(&self, id: u32) -> Result<u32, String> {
        match self.constants.get(&id) {
            Some(Constant::Scalar { words, .. }) if !words.is_empty() => Ok(words[0]),
            _ => Err(format!("%{id} is not an integer constant")),
        }
    }

    fn reflect(&self) -> Result<Reflection, String> {
        let entry = self
            .entry_points
            .first()
            .ok_or("the module has no entry point")?;
        // Since SPIR-V 1.4 the entry point's interface lists every global variable it uses; before
        // that, only inputs and outputs, so every declared resource is taken.
        let listed: BTreeSet<u32> = entry.interface.iter().copied().collect();
        let uses = |id: u32| self.version < (1, 4) || listed.contains(&id);

        let mut bindings = Vec::new();
        let mut push_constants = None;
        let mut inputs = Vec::new();
        let mut outputs = Vec::new();
        for &(id, pointer, storage) in &self.variables {
            let pointee = match self.ty(pointer)? {
                Type::Pointer { pointee, .. } => *pointee,
                _ => return Err(format!("variable %{id} does not have a pointer type")),
            };
            match storage {
                SC_UNIFORM_CONSTANT | SC_UNIFORM | SC_STORAGE_BUFFER if uses(id) => {
                    if let Some(b) = self.binding(id, pointee, storage)? {
                        bindings.push(b);
                    }
                }
                SC_PUSH_CONSTANT if uses(id) => {
                    let (offset, end) = self.struct_extent(pointee)?;
                    push_constants = Some(PushConstantRange {
                        offset,
                        size: end - offset,
                    });
                }
                SC_INPUT | SC_OUTPUT if listed.contains(&id) => {
                    if let Some(location) = self.decorations.get(id, DEC_LOCATION) {
                        let v = InterfaceVariable {
                            location,
                            ty: self.glsl_type(pointee)?,
                        };
                        if storage == SC_INPUT {
                            inputs.push(v)
                        } else {
                            outputs.push(v)
                        }
                    }
                }
                _ => {}
            }
        }
        bindings.sort_by_key(|b| (b.set, b.binding));
        if let Some(w) = bindings
            .windows(2)
            .find(|w| (w[0].set, w[0].binding) == (w[1].set, w[1].binding))
        {
            return Err(format!(
                "two resources share set {} binding {}",
                w[0].set, w[0].binding
            ));
        }
        inputs.sort();
        outputs.sort();

        let mut spec_constants = Vec::new();
        for (&id, c) in &self.constants {
            let Some(spec_id) = self.decorations.get(id, DEC_SPEC_ID) else {
                continue;
            };
            let (ty, default) = match c {
                Constant::Bool { value, spec: true } => {
                    ("bool".to_string(), SpecValue::Bool(*value))
                }
                Constant::Scalar {
                    ty,
                    words,
                    spec: true,
                } => self.scalar_value(*ty, words)?,
                _ => continue,
            };
            spec_constants.push(SpecConstant {
                id: spec_id,
                ty,
                default,
            });
        }
        spec_constants.sort_by_key(|c| c.id);

        Ok(Reflection {
            version: self.version,
            entry_point: entry.name.clone(),
            execution_model: entry.model,
            capabilities: self
                .capabilities
                .iter()
                .map(|&c| capability_name(c))
                .collect(),
            extensions: self.extensions.clone(),
            bindings,
            push_constants,
            spec_constants,
            workgroup_size: self.workgroup_size(entry)?,
            inputs,
            outputs,
        })
    }

    /// A descriptor binding, or None for a variable without DescriptorSet/Binding.
    fn binding(
        &self,
        id: u32,
        pointee: u32,
        storage: u32,
    ) -> Result<Option<DescriptorBinding>, String> {
        let d = &self.decorations;
        let (Some(set), Some(binding)) = (d.get(id, DEC_DESCRIPTOR_SET), d.get(id, DEC_BINDING))
        else {
            return Ok(None);
        };
        let (mut ty_id, mut count) = (pointee, 1);
        match self.ty(pointee)? {
            Type::Array { element, length } => {
                (ty_id, count) = (*element, self.constant_u32(*length)?)
            }
            Type::RuntimeArray { element } => (ty_id, count) = (*element, 0),
            _ => {}
        }
        let mut image_format = None;
        let mut block = None;
        let mut non_writable = d.has(id, DEC_NON_WRITABLE);
        let mut non_readable = d.has(id, DEC_NON_READABLE);
        let kind = match (storage, self.ty(ty_id)?) {
            (SC_UNIFORM, Type::Struct { members }) => {
                block = Some(self.block_layout(ty_id)?);
                if d.has(ty_id, DEC_BUFFER_BLOCK) {
                    DescriptorKind::StorageBuffer
                } else if d.has(ty_id, DEC_BLOCK) {
                    non_writable = true;
                    DescriptorKind::UniformBuffer
                } else {
                    return Err(format!(
                        "uniform variable %{id} is neither Block nor BufferBlock ({} members)",
                        members.len()
                    ));
                }
            }
            (SC_STORAGE_BUFFER, Type::Struct { members }) => {
                block = Some(self.block_layout(ty_id)?);
                // glslang puts readonly/writeonly on the block's members.
                let all =
                    |dec| (0..members.len() as u32).all(|k| d.member(ty_id, k, dec).is_some());
                non_writable |= !members.is_empty() && all(DEC_NON_WRITABLE);
                non_readable |= !members.is_empty() && all(DEC_NON_READABLE);
                DescriptorKind::StorageBuffer
            }
            (SC_UNIFORM_CONSTANT, Type::Sampler) => {
                non_writable = true;
                DescriptorKind::Sampler
            }
            (SC_UNIFORM_CONSTANT, Type::SampledImage) => {
                non_writable = true;
                DescriptorKind::CombinedImageSampler
            }
            (SC_UNIFORM_CONSTANT, Type::AccelerationStructure) => {
                non_writable = true;
                DescriptorKind::AccelerationStructure
            }
            (
                SC_UNIFORM_CONSTANT,
                Type::Image {
                    dim,
                    sampled,
                    format,
                },
            ) => {
                image_format = image_format_name(*format);
                let storage_image = *sampled == 2;
                if !storage_image {
                    non_writable = true;
                }
                match (*dim, storage_image) {
                    (DIM_SUBPASS_DATA, _) => DescriptorKind::InputAttachment,
                    (DIM_BUFFER, false) => DescriptorKind::UniformTexelBuffer,
                    (DIM_BUFFER, true) => DescriptorKind::StorageTexelBuffer,
                    (_, false) => DescriptorKind::SampledImage,
                    (_, true) => DescriptorKind::StorageImage,
                }
            }
            (_, other) => {
                return Err(format!(
                "resource %{id} (set {set}, binding {binding}) has an unexpected type {other:?}"
            ))
            }
        };
        let access = match (non_writable, non_readable) {
            (true, _) => Access::ReadOnly,
            (false, true) => Access::WriteOnly,
            (false, false) => Access::ReadWrite,
        };
        let (block_size, runtime_array_stride) = match block {
            Some((size, stride)) => (Some(size), stride),
            None => (None, None),
        };
        Ok(Some(DescriptorBinding {
            set,
            binding,
            kind,
            count,
            access,
            image_format,
            block_size,
            runtime_array_stride,
        }))
    }

    /// A buffer block's size without its trailing runtime array, and that array's stride.
    fn block_layout(&self, id: u32) -> Result<(u32, Option<u32>), String> {
        let Type::Struct { members } = self.ty(id)? else {
            return Err(format!("%{id} is not a struct"));
        };
        if let Some(&last) = members.last() {
            if let Type::RuntimeArray { .. } = self.ty(last)? {
                let k = members.len() as u32 - 1;
                let offset = self
                    .decorations
                    .member(id, k, DEC_OFFSET)
                    .ok_or(format!("member {k} of %{id} has no Offset"))?;
                let stride = self
                    .decorations
                    .get(last, DEC_ARRAY_STRIDE)
                    .ok_or(format!("runtime array %{last} has no ArrayStride"))?;
                return Ok((offset, Some(stride)));
            }
        }
        Ok((self.struct_extent(id)?.1, None))
    }

    /// (lowest member offset, end of the last byte) of an explicitly laid out struct.
    fn struct_extent(&self, id: u32) -> Result<(u32, u32), String> {
        self.struct_extent_at(id, 0)
    }

    fn struct_extent_at(&self, id: u32, depth: u32) -> Result<(u32, u32), String> {
        let Type::Struct { members } = self.ty(id)? else {
            return Err(format!("%{id} is not a struct"));
        };
        let (mut lo, mut hi) = (u32::MAX, 0);
        for (k, &member) in members.iter().enumerate() {
            let k = k as u32;
            let offset = self
                .decorations
                .member(id, k, DEC_OFFSET)
                .ok_or(format!("member {k} of %{id} has no Offset"))?;
            let size = self.size_of_at(
                member,
                self.decorations.member(id, k, DEC_MATRIX_STRIDE),
                depth + 1,
            )?;
            lo = lo.min(offset);
            hi = hi.max(
                offset
                    .checked_add(size)
                    .ok_or(format!("member {k} of %{id} ends beyond 4 GiB"))?,
            );
        }
        Ok((if members.is_empty() { 0 } else { lo }, hi))
    }

    /// Size in bytes of a type in an explicit layout at nesting `depth`; `matrix_stride` from the
    /// enclosing member: types nested deeper than [`MAX_TYPE_DEPTH`] (a
    /// cyclic type, which valid SPIR-V cannot have) and sizes beyond 4 GiB are errors, not a stack
    /// overflow or a wrapped size.
    fn size_of_at(&self, id: u32, matrix_stride: Option<u32>, depth: u32) -> Result<u32, String> {
        if depth > MAX_TYPE_DEPTH {
            return Err(format!(
                "type %{id} nests deeper than {MAX_TYPE_DEPTH} levels (a cyclic type?)"
            ));
        }
        let times = |n: u32, size: u32| {
            n.checked_mul(size)
                .ok_or(format!("type %{id} is larger than 4 GiB"))
        };
        Ok(match self.ty(id)? {
            Type::Bool => 4,
            Type::Int { width, .. } | Type::Float { width } => width / 8,
            Type::Vector { component, count } => {
                times(*count, self.size_of_at(*component, None, depth + 1)?)?
            }
            Type::Matrix { column, count } => match matrix_stride {
                Some(stride) => times(*count, stride)?,
                None => times(*count, self.size_of_at(*column, None, depth + 1)?)?,
            },
            Type::Array { element, length } => {
                let n = self.constant_u32(*length)?;
                match self.decorations.get(id, DEC_ARRAY_STRIDE) {
                    Some(stride) => times(n, stride)?,
                    None => times(n, self.size_of_at(*element, matrix_stride, depth + 1)?)?,
                }
            }
            Type::RuntimeArray { .. } => 0,
            Type::Struct { .. } => self.struct_extent_at(id, depth + 1)?.1,
            other => {
                return Err(format!(
                    "%{id} ({other:?}) has no size in an explicit layout"
                ))
            }
        })
    }

    fn scalar_value(&self, ty: u32, words: &[u32]) -> Result<(String, SpecValue), String> {
        let wide = |w: &[u32]| w[0] as u64 | (w.get(1).copied().unwrap_or(0) as u64) << 32;
        Ok(match self.ty(ty)? {
            Type::Int {
                width,
                signed: true,
            } => {
                // Narrower literals are sign-extended to 32 bits by the SPIR-V rules.
                let v = if *width == 64 {
                    wide(words) as i64
                } else {
                    words[0] as i32 as i64
                };
                (format!("int{width}"), SpecValue::Int(v))
            }
            Type::Int {
                width,
                signed: false,
            } => (
                format!("uint{width}"),
                SpecValue::UInt(if *width == 64 {
                    wide(words)
                } else {
                    words[0] as u64
                }),
            ),
            Type::Float { width: 64 } => (
                "float64".into(),
                SpecValue::Float(f64::from_bits(wide(words))),
            ),
            Type::Float { width: 32 } => (
                "float32".into(),
                SpecValue::Float(f32::from_bits(words[0]) as f64),
            ),
            Type::Float { width } => (format!("float{width}"), SpecValue::UInt(words[0] as u64)),
            other => return Err(format!("a specialization constant has type {other:?}")),
        })
    }

    /// The local size: a constant decorated BuiltIn WorkgroupSize wins over LocalSizeId, which
    /// wins over LocalSize. None for a non-compute entry point.
    fn workgroup_size(&self, entry: &EntryPoint) -> Result<Option<WorkgroupSize>, String> {
        let axis = |id: u32| -> Result<(u32, Option<u32>), String> {
            Ok((
                self.constant_u32(id)?,
                self.decorations.get(id, DEC_SPEC_ID),
            ))
        };
        let from_ids = |ids: &[u32]| -> Result<WorkgroupSize, String> {
            if ids.len() < 3 {
                return Err("a workgroup size has fewer than 3 components".into());
            }
            let (x, y, z) = (axis(ids[0])?, axis(ids[1])?, axis(ids[2])?);
            Ok(WorkgroupSize {
                size: [x.0, y.0, z.0],
                spec_ids: [x.1, y.1, z.1],
            })
        };
        let builtin = self.constants.iter().find(|(&id, _)| {
            self.decorations.get(id, DEC_BUILT_IN) == Some(BUILT_IN_WORKGROUP_SIZE)
        });
        if let Some((_, Constant::Composite { parts })) = builtin {
            return from_ids(parts).map(Some);
        }
        if let Some(ids) = self.modes.get(&(entry.function, MODE_LOCAL_SIZE_ID)) {
            return from_ids(ids).map(Some);
        }
        if let Some(s) = self.modes.get(&(entry.function, MODE_LOCAL_SIZE)) {
            if s.len() < 3 {
                return Err("LocalSize has fewer than 3 operands".into());
            }
            return Ok(Some(WorkgroupSize {
                size: [s[0], s[1], s[2]],
                spec_ids: [None; 3],
            }));
        }
        Ok(None)
    }

    /// A GLSL spelling of an interface variable's type.
    fn glsl_type(&self, id: u32) -> Result<String, String> {
        self.glsl_type_at(id, 0)
    }

    fn glsl_type_at(&self, id: u32, depth: u32) -> Result<String, String> {
        if depth > MAX_TYPE_DEPTH {
            return Err(format!(
                "type %{id} nests deeper than {MAX_TYPE_DEPTH} levels (a cyclic type?)"
            ));
        }
        let scalar = |id: u32| -> Result<(&'static str, &'static str), String> {
            Ok(match self.ty(id)? {
                Type::Float { width: 64 } => ("double", "d"),
                Type::Float { width: 16 } => ("float16_t", "f16"),
                Type::Float { .. } => ("float", ""),
                Type::Int { signed: true, .. } => ("int", "i"),
                Type::Int { signed: false, .. } => ("uint", "u"),
                Type::Bool => ("bool", "b"),
                other => return Err(format!("interface type {other:?}")),
            })
        };
        Ok(match self.ty(id)? {
            Type::Vector { component, count } => format!("{}vec{count}", scalar(*component)?.1),
            Type::Matrix { column, count } => match self.ty(*column)? {
                Type::Vector {
                    component,
                    count: rows,
                } => {
                    let p = if scalar(*component)?.0 == "double" {
                        "d"
                    } else {
                        ""
                    };
                    if rows == count {
                        format!("{p}mat{count}")
                    } else {
                        format!("{p}mat{count}x{rows}")
                    }
                }
                other => return Err(format!("matrix column {other:?}")),
            },
            Type::Array { element, length } => {
                format!(
                    "{}[{}]",
                    self.glsl_type_at(*element, depth + 1)?,
                    self.constant_u32(*length)?
                )
            }
            Type::Struct { .. } => "struct".into(),
            _ => scalar(id)?.0.into(),
        })
    }
}

/// The GLSL layout qualifier of a SPIR-V image format; None for Unknown.
fn image_format_name(format: u32) -> Option<&'static str> {
    #[rustfmt::skip]
    const NAMES: [&str; 42] = [
        "unknown", "rgba32f", "rgba16f", "r32f", "rgba8", "rgba8_snorm", "rg32f", "rg16f", "r11f_g11f_b10f", "r16f",
        "rgba16", "rgb10_a2", "rg16", "rg8", "r16", "r8", "rgba16_snorm", "rg16_snorm", "rg8_snorm", "r16_snorm",
        "r8_snorm", "rgba32i", "rgba16i", "rgba8i", "r32i", "rg32i", "rg16i", "rg8i", "r16i", "r8i", "rgba32ui",
        "rgba16ui", "rgba8ui", "r32ui", "rgb10_a2ui", "rg32ui", "rg16ui", "rg8ui", "r16ui", "r8ui", "r64ui", "r64i",
    ];
    match format {
        0 => None,
        f => Some(NAMES.get(f as usize).copied().unwrap_or("other")),
    }
}

/// SPIR-V capability names, for those a Vulkan shader is likely to declare.
#[rustfmt::skip]
const CAPABILITIES: &[(u32, &str)] = &[
    (0, "Matrix"), (1, "Shader"), (2, "Geometry"), (3, "Tessellation"), (9, "Float16"), (10, "Float64"),
    (11, "Int64"), (12, "Int64Atomics"), (22, "Int16"), (25, "ImageGatherExtended"),
    (27, "StorageImageMultisample"), (28, "UniformBufferArrayDynamicIndexing"),
    (29, "SampledImageArrayDynamicIndexing"), (30, "StorageBufferArrayDynamicIndexing"),
    (31, "StorageImageArrayDynamicIndexing"), (32, "ClipDistance"), (33, "CullDistance"), (34, "ImageCubeArray"),
    (35, "SampleRateShading"), (39, "Int8"), (40, "InputAttachment"), (41, "SparseResidency"), (42, "MinLod"),
    (43, "Sampled1D"), (44, "Image1D"), (45, "SampledCubeArray"), (46, "SampledBuffer"), (47, "ImageBuffer"),
    (48, "ImageMSArray"), (49, "StorageImageExtendedFormats"), (50, "ImageQuery"), (51, "DerivativeControl"),
    (52, "InterpolationFunction"), (53, "TransformFeedback"), (54, "GeometryStreams"),
    (55, "StorageImageReadWithoutFormat"), (56, "StorageImageWriteWithoutFormat"), (57, "MultiViewport"),
    (61, "GroupNonUniform"), (62, "GroupNonUniformVote"), (63, "GroupNonUniformArithmetic"),
    (64, "GroupNonUniformBallot"), (65, "GroupNonUniformShuffle"), (66, "GroupNonUniformShuffleRelative"),
    (67, "GroupNonUniformClustered"), (68, "GroupNonUniformQuad"), (69, "ShaderLayer"), (70, "ShaderViewportIndex"),
    (4427, "DrawParameters"), (4433, "StorageBuffer16BitAccess"), (4434, "UniformAndStorageBuffer16BitAccess"),
    (4435, "StoragePushConstant16"), (4436, "StorageInputOutput16"), (4439, "MultiView"),
    (4441, "VariablePointersStorageBuffer"), (4442, "VariablePointers"), (4448, "StorageBuffer8BitAccess"),
    (4449, "UniformAndStorageBuffer8BitAccess"), (4450, "StoragePushConstant8"), (4464, "DenormPreserve"),
    (4465, "DenormFlushToZero"), (4466, "SignedZeroInfNanPreserve"), (4467, "RoundingModeRTE"),
    (4468, "RoundingModeRTZ"), (4472, "RayQueryKHR"), (4479, "RayTracingKHR"), (5301, "ShaderNonUniform"),
    (5302, "RuntimeDescriptorArray"), (5345, "VulkanMemoryModel"), (5346, "VulkanMemoryModelDeviceScope"),
    (5347, "PhysicalStorageBufferAddresses"), (5379, "DemoteToHelperInvocation"),
];

/// The SPIR-V name of a capability (`Capability<N>` for one not in [`CAPABILITIES`]).
fn capability_name(c: u32) -> String {
    CAPABILITIES
        .iter()
        .find(|(n, _)| *n == c)
        .map(|(_, s)| s.to_string())
        .unwrap_or_else(|| format!("Capability{c}"))
}

/// The SPIR-V name of an execution model.
pub fn execution_model_name(model: u32) -> String {
    match model {
        0 => "Vertex".into(),
        1 => "TessellationControl".into(),
        2 => "TessellationEvaluation".into(),
        3 => "Geometry".into(),
        4 => "Fragment".into(),
        5 => "GLCompute".into(),
        5364 => "TaskEXT".into(),
        5365 => "MeshEXT".into(),
        m => format!("ExecutionModel{m}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Assembles a module from (opcode, operands).
    fn module(instructions: &[(u32, Vec<u32>)]) -> Vec<u8> {
        let mut words = vec![MAGIC, 0x0001_0600, 0, 100, 0];
        for (op, ops) in instructions {
            words.push(((ops.len() as u32 + 1) << 16) | op);
            words.extend(ops);
        }
        words.iter().flat_map(|w| w.to_le_bytes()).collect()
    }

    fn name(s: &str) -> Vec<u32> {
        let mut b = s.as_bytes().to_vec();
        b.resize((b.len() / 4 + 1) * 4, 0);
        b.chunks(4)
            .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect()
    }

    #[test]
    fn local_size_id_with_spec_constants_and_a_uniform_array() {
        // %1 uint, %2 = spec 16 (SpecId 3), %3 = 4, %4 = 1, entry %10 "main" with LocalSizeId %2 %4 %4,
        // a uniform block array[4] at set 1 binding 2, a float spec constant id 0 = 0.5.
        let mut entry = vec![5, 10];
        entry.extend(name("main"));
        entry.push(30);
        let m = module(&[
            (OP_CAPABILITY, vec![1]),
            (OP_ENTRY_POINT, entry),
            (OP_EXECUTION_MODE_ID, vec![10, MODE_LOCAL_SIZE_ID, 2, 4, 4]),
            (OP_DECORATE, vec![2, DEC_SPEC_ID, 3]),
            (OP_DECORATE, vec![6, DEC_SPEC_ID, 0]),
            (OP_DECORATE, vec![20, DEC_BLOCK]),
            (OP_MEMBER_DECORATE, vec![20, 0, DEC_OFFSET, 0]),
            (OP_MEMBER_DECORATE, vec![20, 1, DEC_OFFSET, 16]),
            (OP_DECORATE, vec![30, DEC_DESCRIPTOR_SET, 1]),
            (OP_DECORATE, vec![30, DEC_BINDING, 2]),
            (OP_TYPE_INT, vec![1, 32, 0]),
            (OP_TYPE_FLOAT, vec![5, 32]),
            (OP_TYPE_VECTOR, vec![7, 5, 3]),
            (OP_SPEC_CONSTANT, vec![1, 2, 16]),
            (OP_CONSTANT, vec![1, 3, 4]),
            (OP_CONSTANT, vec![1, 4, 1]),
            (OP_SPEC_CONSTANT, vec![5, 6, 0.5f32.to_bits()]),
            (OP_TYPE_STRUCT, vec![20, 7, 5]),
            (OP_TYPE_ARRAY, vec![21, 20, 3]),
            (OP_TYPE_POINTER, vec![22, SC_UNIFORM, 21]),
            (OP_VARIABLE, vec![22, 30, SC_UNIFORM]),
        ]);
        let r = reflect(&m).unwrap();
        assert_eq!(r.entry_point, "main");
        assert_eq!(r.capabilities, vec!["Shader"]);
        assert_eq!(
            r.workgroup_size,
            Some(WorkgroupSize {
                size: [16, 1, 1],
                spec_ids: [Some(3), None, None]
            })
        );
        assert_eq!(r.bindings.len(), 1);
        let b = &r.bindings[0];
        assert_eq!(
            (b.set, b.binding, b.kind, b.count, b.access),
            (1, 2, DescriptorKind::UniformBuffer, 4, Access::ReadOnly)
        );
        assert_eq!(b.block_size, Some(20));
        assert_eq!(r.spec_constants.len(), 2);
        assert_eq!(
            r.spec_constants[0],
            SpecConstant {
                id: 0,
                ty: "float32".into(),
                default: SpecValue::Float(0.5)
            }
        );
        assert_eq!(
            r.spec_constants[1],
            SpecConstant {
                id: 3,
                ty: "uint32".into(),
                default: SpecValue::UInt(16)
            }
        );
    }

    /// A uniform block whose member type is an array of the block itself (ids %20 and %21 refer
    /// to each other: invalid SPIR-V, hostile input), or whose size passes 4 GiB.
    fn block_module(array_element: u32, length: u32, stride: Option<u32>) -> Vec<u8> {
        let mut entry = vec![5, 10];
        entry.extend(name("main"));
        entry.push(30);
        let mut ops = vec![
            (OP_CAPABILITY, vec![1]),
            (OP_ENTRY_POINT, entry),
            (OP_DECORATE, vec![20, DEC_BLOCK]),
            (OP_MEMBER_DECORATE, vec![20, 0, DEC_OFFSET, 0]),
            (OP_DECORATE, vec![30, DEC_DESCRIPTOR_SET, 0]),
            (OP_DECORATE, vec![30, DEC_BINDING, 0]),
            (OP_TYPE_INT, vec![1, 32, 0]),
            (OP_CONSTANT, vec![1, 3, length]),
            (OP_TYPE_STRUCT, vec![20, 21]),
            (OP_TYPE_ARRAY, vec![21, array_element, 3]),
            (OP_TYPE_POINTER, vec![22, SC_UNIFORM, 20]),
            (OP_VARIABLE, vec![22, 30, SC_UNIFORM]),
        ];
        if let Some(st) = stride {
            ops.insert(4, (OP_DECORATE, vec![21, DEC_ARRAY_STRIDE, st]));
        }
        module(&ops)
    }

    #[test]
    fn cyclic_and_huge_types_are_errors_not_crashes() {
        let e = reflect(&block_module(20, 4, None)).unwrap_err().to_string();
        assert!(e.contains("nests deeper") && e.contains("cyclic"), "{e}");
        // uint[2^30] with stride 16: 16 GiB, beyond u32.
        let e = reflect(&block_module(1, 1 << 30, Some(16)))
            .unwrap_err()
            .to_string();
        assert!(e.contains("larger than 4 GiB"), "{e}");
        // The same array of 4 is fine: 64 bytes.
        let r = reflect(&block_module(1, 4, Some(16))).unwrap();
        assert_eq!(r.bindings[0].block_size, Some(64));
    }

    /// The numbers taken from the `spirv` crate are those of the SPIR-V specification (the hand
    /// table they replaced).
    #[test]
    fn numbers_are_the_specifications() {
        assert_eq!(MAGIC, 119734787);
        assert_eq!(OP_EXTENSION, 10);
        assert_eq!(OP_ENTRY_POINT, 15);
        assert_eq!(OP_EXECUTION_MODE, 16);
        assert_eq!(OP_CAPABILITY, 17);
        assert_eq!(OP_TYPE_VOID, 19);
        assert_eq!(OP_TYPE_BOOL, 20);
        assert_eq!(OP_TYPE_INT, 21);
        assert_eq!(OP_TYPE_FLOAT, 22);
        assert_eq!(OP_TYPE_VECTOR, 23);
        assert_eq!(OP_TYPE_MATRIX, 24);
        assert_eq!(OP_TYPE_IMAGE, 25);
        assert_eq!(OP_TYPE_SAMPLER, 26);
        assert_eq!(OP_TYPE_SAMPLED_IMAGE, 27);
        assert_eq!(OP_TYPE_ARRAY, 28);
        assert_eq!(OP_TYPE_RUNTIME_ARRAY, 29);
        assert_eq!(OP_TYPE_STRUCT, 30);
        assert_eq!(OP_TYPE_POINTER, 32);
        assert_eq!(OP_CONSTANT_TRUE, 41);
        assert_eq!(OP_CONSTANT_FALSE, 42);
        assert_eq!(OP_CONSTANT, 43);
        assert_eq!(OP_CONSTANT_COMPOSITE, 44);
        assert_eq!(OP_SPEC_CONSTANT_TRUE, 48);
        assert_eq!(OP_SPEC_CONSTANT_FALSE, 49);
        assert_eq!(OP_SPEC_CONSTANT, 50);
        assert_eq!(OP_SPEC_CONSTANT_COMPOSITE, 51);
        assert_eq!(OP_FUNCTION, 54);
        assert_eq!(OP_VARIABLE, 59);
        assert_eq!(OP_DECORATE, 71);
        assert_eq!(OP_MEMBER_DECORATE, 72);
        assert_eq!(OP_EXECUTION_MODE_ID, 331);
        assert_eq!(OP_TYPE_ACCELERATION_STRUCTURE, 5341);
        assert_eq!(DEC_SPEC_ID, 1);
        assert_eq!(DEC_BLOCK, 2);
        assert_eq!(DEC_BUFFER_BLOCK, 3);
        assert_eq!(DEC_ARRAY_STRIDE, 6);
        assert_eq!(DEC_MATRIX_STRIDE, 7);
        assert_eq!(DEC_BUILT_IN, 11);
        assert_eq!(DEC_NON_WRITABLE, 24);
        assert_eq!(DEC_NON_READABLE, 25);
        assert_eq!(DEC_LOCATION, 30);
        assert_eq!(DEC_BINDING, 33);
        assert_eq!(DEC_DESCRIPTOR_SET, 34);
        assert_eq!(DEC_OFFSET, 35);
        assert_eq!(BUILT_IN_WORKGROUP_SIZE, 25);
        assert_eq!(SC_UNIFORM_CONSTANT, 0);
        assert_eq!(SC_INPUT, 1);
        assert_eq!(SC_UNIFORM, 2);
        assert_eq!(SC_OUTPUT, 3);
        assert_eq!(SC_PUSH_CONSTANT, 9);
        assert_eq!(SC_STORAGE_BUFFER, 12);
        assert_eq!(MODE_LOCAL_SIZE, 17);
        assert_eq!(MODE_LOCAL_SIZE_ID, 38);
        assert_eq!(DIM_BUFFER, 5);
        assert_eq!(DIM_SUBPASS_DATA, 6);
    }

    #[test]
    fn rejects_what_is_not_spir_v() {
        assert!(reflect(b"not a module at all!").is_err());
        assert!(reflect(&[0u8; 6]).is_err());
    }
}
