//! Pipelines from the generated shader module: the descriptor set layout (one
//! push-descriptor set) and push-constant range come from reflection.

use super::context::{Context, Shared};
use super::resources::{has_stencil, inc, Garbage};
use super::shader::{Binding, ShaderInfo};
use crate::error::{vk_err, Error, Result};
use ash::vk;
use std::sync::Arc;

/// `(constant_id, value)` pairs; ids come from the generated `SPEC_*` constants.
pub type Specialization<'a> = &'a [(u32, u32)];

pub struct Pipeline {
    pub(crate) raw: vk::Pipeline,
    pub(crate) layout: vk::PipelineLayout,
    set_layout: vk::DescriptorSetLayout,
    pub(crate) bind_point: vk::PipelineBindPoint,
    pub(crate) bindings: Vec<Binding>,
    pub(crate) push_stages: vk::ShaderStageFlags,
    pub(crate) push_size: u32,
    pub name: String,
    /// The name with the variant switches of its shaders, e.g.
    /// `cull_patches[CONE_CULL HOLE_CULL]` (reports list pipelines by it).
    pub label: String,
    shared: Arc<Shared>,
}

/// `name[SWITCH ...]` from the variant defines of `shaders`.
fn label_of(name: &str, shaders: &[&ShaderInfo]) -> String {
    let mut defines: Vec<&str> = shaders.iter().flat_map(|s| s.defines.iter().copied()).collect();
    defines.dedup();
    if defines.is_empty() {
        name.to_string()
    } else {
        format!("{name}[{}]", defines.join(" "))
    }
}

pub struct ComputePipelineDesc<'a> {
    pub name: &'a str,
    pub shader: &'static ShaderInfo,
    pub specialization: Specialization<'a>,
}

pub struct GraphicsPipelineDesc<'a> {
    pub name: &'a str,
    pub vertex: &'static ShaderInfo,
    pub fragment: &'static ShaderInfo,
    pub specialization: Specialization<'a>,
    pub color_formats: &'a [vk::Format],
    pub depth_format: Option<vk::Format>,
    /// ALWAYS disables the depth test.
    pub depth_compare: vk::CompareOp,
    pub depth_write: bool,
    /// Stencil test and write of the depth target's stencil aspect.
    pub stencil: Option<StencilDesc>,
    pub cull_mode: vk::CullModeFlags,
    pub topology: vk::PrimitiveTopology,
    /// Blends the colour attachments over what they hold by the fragment's
    /// alpha (0 keeps the target: a full-screen pass that draws only some
    /// pixels, without `discard`, which naga cannot parse).
    pub blend: bool,
}

/// One stencil state for both faces: pass when `reference & compare_mask`
/// relates to the stored value by `compare`; where depth and stencil pass,
/// `write_mask` bits of the stored value become `reference`'s.
#[derive(Debug, Clone, Copy)]
pub struct StencilDesc {
    pub compare: vk::CompareOp,
    pub reference: u32,
    pub compare_mask: u32,
    pub write_mask: u32,
}

struct Layout {
    set_layout: vk::DescriptorSetLayout,
    layout: vk::PipelineLayout,
    bindings: Vec<Binding>,
    push_stages: vk::ShaderStageFlags,
    push_size: u32,
}

fn build_layout(s: &Shared, name: &str, shaders: &[&ShaderInfo]) -> Result<Layout> {
    let mut merged: Vec<(Binding, vk::ShaderStageFlags)> = Vec::new();
    let mut push_stages = vk::ShaderStageFlags::empty();
    let mut push_size = 0;
    for sh in shaders {
        for b in sh.bindings {
            assert_eq!(b.set, 0, "{}: vista shaders use descriptor set 0 only ({})", sh.file, b.name);
            match merged.iter_mut().find(|(m, _)| m.binding == b.binding) {
                Some((m, stages)) => {
                    assert_eq!(m.kind, b.kind, "{}: binding {} differs between stages", sh.file, b.binding);
                    m.writes |= b.writes;
                    *stages |= sh.stage.vk();
                }
                None => merged.push((*b, sh.stage.vk())),
            }
        }
        if sh.push_constant_size > 0 {
            push_stages |= sh.stage.vk();
            push_size = push_size.max(sh.push_constant_size);
        }
    }
    let vk_bindings: Vec<_> = merged
        .iter()
        .map(|(b, stages)| {
            vk::DescriptorSetLayoutBinding::default()
                .binding(b.binding)
                .descriptor_type(b.kind.vk())
                .descriptor_count(1)
                .stage_flags(*stages)
        })
        .collect();
    let info = vk::DescriptorSetLayoutCreateInfo::default()
        .flags(vk::DescriptorSetLayoutCreateFlags::PUSH_DESCRIPTOR_KHR)
        .bindings(&vk_bindings);
    // SAFETY: valid device; bindings reflected from validated SPIR-V.
    let set_layout =
        unsafe { s.device.create_descriptor_set_layout(&info, None) }.map_err(vk_err("vkCreateDescriptorSetLayout"))?;
    let ranges = [vk::PushConstantRange { stage_flags: push_stages, offset: 0, size: push_size }];
    let set_layouts = [set_layout];
    let mut info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
    if push_size > 0 {
        info = info.push_constant_ranges(&ranges);
    }
    // SAFETY: valid device and set layout.
    let layout = match unsafe { s.device.create_pipeline_layout(&info, None) } {
        Ok(l) => l,
        Err(e) => {
            // SAFETY: unused set layout.
            unsafe { s.device.destroy_descriptor_set_layout(set_layout, None) };
            return Err(Error::vk("vkCreatePipelineLayout", e));
        }
    };
    let _ = name;
    Ok(Layout { set_layout, layout, bindings: merged.into_iter().map(|(b, _)| b).collect(), push_stages, push_size })
}

fn module(s: &Shared, sh: &ShaderInfo) -> Result<vk::ShaderModule> {
    let info = vk::ShaderModuleCreateInfo::default().code(sh.spirv);
    // SAFETY: SPIR-V validated at build time.
    unsafe { s.device.create_shader_module(&info, None) }.map_err(vk_err("vkCreateShaderModule"))
}

struct Spec {
    entries: Vec<vk::SpecializationMapEntry>,
    data: Vec<u32>,
}

fn spec_for(sh: &ShaderInfo, spec: Specialization) -> Spec {
    let mut out = Spec { entries: Vec::new(), data: Vec::new() };
    for &(id, value) in spec {
        if sh.spec_constants.iter().any(|(_, i)| *i == id) {
            out.entries.push(vk::SpecializationMapEntry {
                constant_id: id,
                offset: 4 * out.data.len() as u32,
                size: 4,
            });
            out.data.push(value);
        }
    }
    out
}

impl Pipeline {
    /// One compute pipeline of pass `name` per variant bit set, each from
    /// `shader` (a bank entry's `variant`), without specialization.
    pub fn compute_variants(
        ctx: &Context,
        name: &str,
        variants: &[u32],
        shader: fn(u32) -> &'static ShaderInfo,
    ) -> Result<Vec<(u32, Pipeline)>> {
        let build = |v: u32| {
            let desc = ComputePipelineDesc { name, shader: shader(v), specialization: &[] };
            Ok((v, Pipeline::compute(ctx, &desc)?))
        };
        variants.iter().map(|&v| build(v)).collect()
    }

    pub fn compute(ctx: &Context, desc: &ComputePipelineDesc) -> Result<Pipeline> {
        let s = &ctx.shared;
        assert_eq!(
            desc.shader.stage,
            super::shader::ShaderStage::Compute,
            "{} is not a compute shader",
            desc.shader.file
        );
        let l = build_layout(s, desc.name, &[desc.shader])?;
        let m = module(s, desc.shader)?;
        let spec = spec_for(desc.shader, desc.specialization);
        let spec_info =
            vk::SpecializationInfo::default().map_entries(&spec.entries).data(bytemuck::cast_slice(&spec.data));
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(m)
            .name(c"main")
            .specialization_info(&spec_info);
        let info = vk::ComputePipelineCreateInfo::default().stage(stage).layout(l.layout);
        // SAFETY: module and layout are live; the module is destroyed after creation.
        let raw = unsafe {
            let r = s.device.create_compute_pipelines(vk::PipelineCache::null(), &[info], None);
            s.device.destroy_shader_module(m, None);
            r
        };
        let label = label_of(desc.name, &[desc.shader]);
        Self::finish(ctx, desc.name, label, raw.map(|p| p[0]).map_err(|(_, e)| e), l, vk::PipelineBindPoint::COMPUTE)
    }

    pub fn graphics(ctx: &Context, desc: &GraphicsPipelineDesc) -> Result<Pipeline> {
        let s = &ctx.shared;
        let l = build_layout(s, desc.name, &[desc.vertex, desc.fragment])?;
        let vm = module(s, desc.vertex)?;
        let fm = match module(s, desc.fragment) {
            Ok(m) => m,
            Err(e) => {
                // SAFETY: unused objects created above.
                unsafe {
                    s.device.destroy_shader_module(vm, None);
                    s.device.destroy_pipeline_layout(l.layout, None);
                    s.device.destroy_descriptor_set_layout(l.set_layout, None);
                }
                return Err(e);
            }
        };
        let (vs, fs) = (spec_for(desc.vertex, desc.specialization), spec_for(desc.fragment, desc.specialization));
        let vsi = vk::SpecializationInfo::default().map_entries(&vs.entries).data(bytemuck::cast_slice(&vs.data));
        let fsi = vk::SpecializationInfo::default().map_entries(&fs.entries).data(bytemuck::cast_slice(&fs.data));
        let stages = [
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::VERTEX)
                .module(vm)
                .name(c"main")
                .specialization_info(&vsi),
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::FRAGMENT)
                .module(fm)
                .name(c"main")
                .specialization_info(&fsi),
        ];
        let vertex_input = vk::PipelineVertexInputStateCreateInfo::default();
        let input_assembly = vk::PipelineInputAssemblyStateCreateInfo::default().topology(desc.topology);
        let viewport = vk::PipelineViewportStateCreateInfo::default().viewport_count(1).scissor_count(1);
        let raster = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(desc.cull_mode)
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0);
        let multisample =
            vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let depth = depth_stencil(desc);
        let attachments = blend_attachments(desc);
        let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&attachments);
        let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
        let mut rendering = vk::PipelineRenderingCreateInfo::default()
            .color_attachment_formats(desc.color_formats)
            .depth_attachment_format(desc.depth_format.unwrap_or(vk::Format::UNDEFINED))
            .stencil_attachment_format(desc.depth_format.filter(|f| has_stencil(*f)).unwrap_or(vk::Format::UNDEFINED));
        let info = vk::GraphicsPipelineCreateInfo::default()
            .stages(&stages)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&input_assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&multisample)
            .depth_stencil_state(&depth)
            .color_blend_state(&blend)
            .dynamic_state(&dynamic)
            .layout(l.layout)
            .push_next(&mut rendering);
        // SAFETY: every pointer refers to locals; modules are destroyed after creation.
        let raw = unsafe {
            let r = s.device.create_graphics_pipelines(vk::PipelineCache::null(), &[info], None);
            s.device.destroy_shader_module(vm, None);
            s.device.destroy_shader_module(fm, None);
            r
        };
        let label = label_of(desc.name, &[desc.vertex, desc.fragment]);
        Self::finish(ctx, desc.name, label, raw.map(|p| p[0]).map_err(|(_, e)| e), l, vk::PipelineBindPoint::GRAPHICS)
    }

    fn finish(
        ctx: &Context,
        name: &str,
        label: String,
        raw: Result<vk::Pipeline, vk::Result>,
        l: Layout,
        bind_point: vk::PipelineBindPoint,
    ) -> Result<Pipeline> {
        let s = &ctx.shared;
        let raw = match raw {
            Ok(p) => p,
            Err(e) => {
                // SAFETY: unused layout objects.
                unsafe {
                    s.device.destroy_pipeline_layout(l.layout, None);
                    s.device.destroy_descriptor_set_layout(l.set_layout, None);
                }
                return Err(Error::vk("vkCreate*Pipelines", e));
            }
        };
        inc(&s.live.pipelines);
        ctx.set_name(raw, name);
        ctx.set_name(l.layout, name);
        Ok(Pipeline {
            raw,
            layout: l.layout,
            set_layout: l.set_layout,
            bind_point,
            bindings: l.bindings,
            push_stages: l.push_stages,
            push_size: l.push_size,
            name: name.to_string(),
            label,
            shared: s.clone(),
        })
    }
}

impl Drop for Pipeline {
    fn drop(&mut self) {
        self.shared.retire(Garbage::Pipeline(self.raw, self.layout, self.set_layout));
    }
}

/// Depth test and write, and the stencil test, of a graphics pipeline.
fn depth_stencil(desc: &GraphicsPipelineDesc) -> vk::PipelineDepthStencilStateCreateInfo<'static> {
    let has_depth = desc.depth_format.is_some();
    let stencil_op = desc.stencil.map(|st| {
        let pass = if st.write_mask != 0 { vk::StencilOp::REPLACE } else { vk::StencilOp::KEEP };
        vk::StencilOpState::default()
            .fail_op(vk::StencilOp::KEEP)
            .pass_op(pass)
            .depth_fail_op(vk::StencilOp::KEEP)
            .compare_op(st.compare)
            .compare_mask(st.compare_mask)
            .write_mask(st.write_mask)
            .reference(st.reference)
    });
    vk::PipelineDepthStencilStateCreateInfo::default()
        .depth_test_enable(has_depth && desc.depth_compare != vk::CompareOp::ALWAYS)
        .depth_write_enable(has_depth && desc.depth_write)
        .depth_compare_op(desc.depth_compare)
        .stencil_test_enable(stencil_op.is_some())
        .front(stencil_op.unwrap_or_default())
        .back(stencil_op.unwrap_or_default())
}

/// One colour blend state per attachment: written whole, alpha-blended
/// when the pipeline blends.
fn blend_attachments(desc: &GraphicsPipelineDesc) -> Vec<vk::PipelineColorBlendAttachmentState> {
    let attachment = |_| {
        let a = vk::PipelineColorBlendAttachmentState::default().color_write_mask(vk::ColorComponentFlags::RGBA);
        if !desc.blend {
            return a;
        }
        a.blend_enable(true)
            .src_color_blend_factor(vk::BlendFactor::SRC_ALPHA)
            .dst_color_blend_factor(vk::BlendFactor::ONE_MINUS_SRC_ALPHA)
            .color_blend_op(vk::BlendOp::ADD)
            .src_alpha_blend_factor(vk::BlendFactor::ZERO)
            .dst_alpha_blend_factor(vk::BlendFactor::ONE)
            .alpha_blend_op(vk::BlendOp::ADD)
    };
    desc.color_formats.iter().map(attachment).collect()
}
