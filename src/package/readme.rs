//! `README.md` for the engine developer: how to load, bind and call each module.

use std::fmt::Write as _;

use super::{module_notes, stage_name, Manifest};

impl Manifest {
    /// `README.md`'s text: how to load, bind and call each module, from the manifest and the
    /// hand-written notes.
    pub fn readme(&self) -> String {
        let mut s = String::new();
        let w = &mut s;
        let _ = writeln!(w, "# weft SPIR-V shader package\n");
        let _ = writeln!(
            w,
            "The shaders of weft {} (a deferred Vulkan renderer for woven fabric), compiled to SPIR-V, \
             ready for any Vulkan 1.3 program. Package format {}. Compiler: {}.\n",
            self.weft_version, self.format_version, self.compiler
        );
        let _ = writeln!(w, "## Using a module\n");
        let _ = writeln!(
            w,
            "1. Read `<name>.spv` and check its SHA-256 against `manifest.json`; pass the bytes to \
             `vkCreateShaderModule` (they are little-endian 32-bit words).\n\
             2. Create one `VkDescriptorSetLayout` per set from `descriptor_bindings`: `type` is \
             `VK_DESCRIPTOR_TYPE_<TYPE>` (its value in `vk_descriptor_type`), `count` the \
             descriptor count (0: runtime-sized), stage flags from the modules that use the binding \
             (`vk_shader_stage`). For a graphics pipeline, merge the bindings of its two modules.\n\
             3. Add one `VkPushConstantRange` from `push_constants` (`offset`, `size`) with the stage \
             flags of every module that declares it.\n\
             4. Name `entry_point` in `VkPipelineShaderStageCreateInfo`; give \
             `specialization_constants` by `id` (their defaults apply otherwise).\n\
             5. Compute: dispatch `ceil(n / workgroup_size)` groups along each axis.\n\n\
             The device needs Vulkan 1.3 (SPIR-V {}) and the listed `capabilities`. Buffer bindings \
             give `block_size` (bytes the bound range must hold at least, without a trailing \
             runtime array) and `runtime_array_stride`; image bindings their `image_format` (GLSL \
             spelling). `access` says whether the shader reads or writes the resource. `include/` \
             holds the GLSL the modules were built from, for engines that write their own shaders \
             against weft's G-buffer or BRDF.\n",
            self.modules.first().map(|m| m.spirv_version.as_str()).unwrap_or("1.6")
        );
        let _ = writeln!(w, "## Modules\n");
        let _ = writeln!(w, "| module | stage | size | sha256 |\n|---|---|---|---|");
        for m in &self.modules {
            let _ = writeln!(
                w,
                "| `{}` | {} | {} B | `{}…` |",
                m.file,
                stage_name(m.stage),
                m.size,
                &m.sha256[..16]
            );
        }
        let _ = writeln!(w);
        for m in &self.modules {
            let _ = writeln!(w, "### {}\n", m.name);
            let _ = writeln!(w, "{}\n", module_notes(&m.name).unwrap_or("(no notes)"));
            let _ = write!(
                w,
                "- file `{}`, {} stage, entry point `{}`",
                m.file,
                stage_name(m.stage),
                m.entry_point
            );
            if let Some(g) = m.workgroup_size {
                let _ = write!(
                    w,
                    ", workgroup size {} × {} × {}",
                    g.size[0], g.size[1], g.size[2]
                );
            }
            let _ = writeln!(w);
            match m.push_constants {
                Some(p) => {
                    let _ = writeln!(
                        w,
                        "- push constants: offset {}, size {} bytes",
                        p.offset, p.size
                    );
                }
                None => {
                    let _ = writeln!(w, "- push constants: none");
                }
            }
            if !m.inputs.is_empty() {
                let list: Vec<String> = m
                    .inputs
                    .iter()
                    .map(|v| format!("{}: `{}`", v.location, v.ty))
                    .collect();
                let _ = writeln!(w, "- inputs (location: type): {}", list.join(", "));
            }
            if !m.outputs.is_empty() {
                let list: Vec<String> = m
                    .outputs
                    .iter()
                    .map(|v| format!("{}: `{}`", v.location, v.ty))
                    .collect();
                let _ = writeln!(w, "- outputs (location: type): {}", list.join(", "));
            }
            for c in &m.spec_constants {
                let _ = writeln!(
                    w,
                    "- specialization constant {} (`{}`, default {}): {}",
                    c.constant.id,
                    c.constant.ty,
                    c.constant.default,
                    c.meaning.unwrap_or("(no meaning recorded)")
                );
            }
            if m.bindings.is_empty() {
                let _ = writeln!(w, "- no descriptor bindings");
            } else {
                let _ = writeln!(w, "\n| set | binding | type | count | access | holds |\n|---|---|---|---|---|---|");
                for b in &m.bindings {
                    let mut kind = b.kind.name().to_string();
                    if let Some(f) = b.image_format {
                        let _ = write!(kind, " ({f})");
                    }
                    if let Some(stride) = b.runtime_array_stride {
                        let _ = write!(kind, " ({stride} B per element)");
                    }
                    let _ = writeln!(
                        w,
                        "| {} | {} | {} | {} | {} | {} |",
                        b.set,
                        b.binding,
                        kind,
                        b.count,
                        b.access.name(),
                        b.meaning.as_deref().unwrap_or("")
                    );
                }
            }
            let _ = writeln!(w);
        }
        let _ = writeln!(w, "## Files\n");
        let _ = writeln!(w, "`manifest.json` (everything above, machine-readable), `README.md` (this file), one `.spv` per module, and:\n");
        for f in &self.includes {
            let _ = writeln!(
                w,
                "- `{}` ({} B, sha256 `{}…`)",
                f.file,
                f.size,
                &f.sha256[..16]
            );
        }
        s
    }
}
