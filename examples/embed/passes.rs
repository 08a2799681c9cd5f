//! The engine's own passes around vista: its occluder (a building drawn
//! before vista, into the depth vista then loads), its deferred lighting
//! of the G-buffer vista wrote (`--output gbuffer`: sun and sky ambient,
//! then the same ACES tonemap vista's lit output uses), its tonemap of the
//! HDR radiance vista wrote (`--output hdr`), and its marker. Plain GLSL
//! compiled at start, one descriptor set, the engine's objects only.

use crate::targets::{gbuffer_layout, Mode, Targets, DEPTH, HDR_FORMAT};
use ash::vk;
use std::ffi::CStr;
use vista::passes::terrain_geometry::COLOR_FORMAT;
use vista::render::{Lighting, View};

/// Sun, sky and exposure of the engine's lighting (vista's scene's, so the
/// engine's picture and vista's own agree), and the background colour.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct LightPush {
    sun_dir: [f32; 4],
    sun_colour: [f32; 4],
    /// w: the exposure's factor.
    sky_colour: [f32; 4],
    background: [f32; 4],
}

impl LightPush {
    pub fn new(l: &Lighting, background: [f32; 4]) -> Self {
        let s = l.sun_dir().as_vec3();
        let [r, g, b] = l.sky_color;
        LightPush {
            sun_dir: [s.x, s.y, s.z, 0.0],
            sun_colour: [l.sun_color[0], l.sun_color[1], l.sun_color[2], 0.0],
            sky_colour: [r, g, b, 2f32.powf(l.exposure_ev())],
            background,
        }
    }

    pub fn background(&self) -> [f32; 4] {
        self.background
    }
}

/// The building: its unit cube to clip space (the view's camera-relative
/// view-projection of the box's centre and half size, made in f64).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BoxPush {
    cube_to_clip: [[f32; 4]; 4],
}

impl BoxPush {
    pub fn new(view: &View, centre_m: glam::DVec3, half_m: glam::DVec3) -> Self {
        let rel = centre_m - glam::DVec3::from_array(view.camera.position_m);
        let cube = glam::DMat4::from_translation(rel) * glam::DMat4::from_scale(half_m);
        BoxPush { cube_to_clip: (view.view_proj() * cube).as_mat4().to_cols_array_2d() }
    }
}

/// Push constants of the marker: its clip-space centre and half size (NDC).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Marker {
    clip: [f32; 4],
    half: [f32; 2],
    pad: [f32; 2],
}

impl Marker {
    pub fn new(view: &View, world_m: glam::DVec3) -> Self {
        let rel = world_m - glam::DVec3::from_array(view.camera.position_m);
        let clip = view.view_proj() * rel.extend(1.0);
        let aspect = f64::from(view.size[0]) / f64::from(view.size[1]);
        Marker { clip: clip.as_vec4().to_array(), half: [0.03, (0.03 * aspect) as f32], pad: [0.0; 2] }
    }
}

const ACES: &str = "
vec3 aces(vec3 c) {
    const mat3 to_rrt = mat3(0.59719, 0.35458, 0.04823, 0.07600, 0.90834, 0.01566, 0.02840, 0.13383, 0.83777);
    const mat3 from_odt = mat3(1.60475, -0.53108, -0.07367, -0.10208, 1.10813, -0.00605, -0.00327, -0.07276, 1.07602);
    vec3 v = c * to_rrt;
    vec3 fit = (v * (v + 0.0245786) - 0.000090537) / (v * (0.983729 * v + 0.4329510) + 0.238081);
    c = clamp(fit * from_odt, 0.0, 1.0);
    return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, greaterThan(c, vec3(0.0031308)));
}
layout(push_constant) uniform Light { vec4 sun_dir; vec4 sun_colour; vec4 sky_colour; vec4 background; } light;
vec3 lit(vec3 base, vec3 n) {
    return base * (light.sun_colour.rgb * max(dot(n, light.sun_dir.xyz), 0.0) + light.sky_colour.rgb * (0.5 + 0.5 * n.z));
}
";

const FULLSCREEN_VERT: &str = "#version 450
void main() {
    vec2 p = vec2((gl_VertexIndex << 1) & 2, gl_VertexIndex & 2);
    gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}";

/// The engine's deferred lighting: its G-buffer (base colour, normal) and
/// depth (0: background) into the display image.
fn light_frag() -> String {
    format!(
        "#version 450
{ACES}
layout(set = 0, binding = 0) uniform sampler2D base;
layout(set = 0, binding = 1) uniform sampler2D normal;
layout(set = 0, binding = 2) uniform sampler2D depth;
layout(location = 0) out vec4 colour;
void main() {{
    ivec2 p = ivec2(gl_FragCoord.xy);
    if (texelFetch(depth, p, 0).r == 0.0) {{
        colour = light.background;
        return;
    }}
    vec3 n = normalize(texelFetch(normal, p, 0).xyz * 2.0 - 1.0);
    colour = vec4(aces(lit(texelFetch(base, p, 0).rgb, n) * light.sky_colour.w), 1.0);
}}"
    )
}

/// The engine's tonemap of the linear radiance vista wrote (depth 0: the
/// background colour).
fn tonemap_frag() -> String {
    format!(
        "#version 450
{ACES}
layout(set = 0, binding = 0) uniform sampler2D radiance;
layout(set = 0, binding = 2) uniform sampler2D depth;
layout(location = 0) out vec4 colour;
void main() {{
    ivec2 p = ivec2(gl_FragCoord.xy);
    bool background = texelFetch(depth, p, 0).r == 0.0;
    colour = background ? light.background : vec4(aces(texelFetch(radiance, p, 0).rgb * light.sky_colour.w), 1.0);
}}"
    )
}

const BOX_VERT: &str = "#version 450
layout(push_constant) uniform Box { layout(offset = 64) mat4 cube_to_clip; } b;
layout(location = 0) flat out vec3 normal;
void main() {
    // 6 faces x 2 triangles, outward winding seen from outside.
    const ivec3 axes[6] = ivec3[](ivec3(0, 1, 2), ivec3(0, 2, 1), ivec3(1, 2, 0), ivec3(1, 0, 2), ivec3(2, 0, 1), ivec3(2, 1, 0));
    const vec2 corners[6] = vec2[](vec2(-1, -1), vec2(1, -1), vec2(1, 1), vec2(-1, -1), vec2(1, 1), vec2(-1, 1));
    int face = gl_VertexIndex / 6;
    ivec3 a = axes[face];
    float side = (face & 1) == 0 ? 1.0 : -1.0;
    vec2 c = corners[gl_VertexIndex % 6];
    vec3 p = vec3(0.0);
    p[a.x] = c.x;
    p[a.y] = c.y * side;
    p[a.z] = side;
    vec3 n = vec3(0.0);
    n[a.z] = side;
    normal = n;
    gl_Position = b.cube_to_clip * vec4(p, 1.0);
}";

/// The building's colour: lit by the engine (display-encoded for `lit`,
/// radiance for `hdr`: spec constant 0).
fn box_colour_frag() -> String {
    format!(
        "#version 450
layout(constant_id = 0) const uint RADIANCE = 0u;
{ACES}
layout(location = 0) flat in vec3 normal;
layout(location = 0) out vec4 colour;
void main() {{
    vec3 radiance = lit(vec3(0.45, 0.42, 0.40), normal);
    colour = vec4(RADIANCE != 0u ? radiance : aces(radiance * light.sky_colour.w), 1.0);
}}"
    )
}

/// The building into the engine's G-buffer (the layout vista writes too).
const BOX_GBUFFER_FRAG: &str = "#version 450
layout(location = 0) flat in vec3 normal;
layout(location = 0) out vec4 base_roughness;
layout(location = 1) out vec4 packed_normal;
void main() {
    base_roughness = vec4(0.45, 0.42, 0.40, 0.7);
    packed_normal = vec4(normal * 0.5 + 0.5, 0.0);
}";

const MARKER_VERT: &str = "#version 450
layout(push_constant) uniform Marker { vec4 clip; vec2 half_size; } m;
void main() {
    vec2 c[6] = vec2[](vec2(-1, -1), vec2(1, -1), vec2(1, 1), vec2(-1, -1), vec2(1, 1), vec2(-1, 1));
    gl_Position = m.clip + vec4(c[gl_VertexIndex] * m.half_size * m.clip.w, 0.0, 0.0);
}";
const MARKER_FRAG: &str = "#version 450
layout(location = 0) out vec4 colour;
void main() { colour = vec4(1.0, 0.0, 1.0, 1.0); }";

fn spirv(text: &str, stage: glslang::ShaderStage) -> Result<Vec<u32>, String> {
    let compiler = glslang::Compiler::acquire().ok_or("glslang")?;
    let source = glslang::ShaderSource::from(text.to_string());
    let options = glslang::CompilerOptions {
        source_language: glslang::SourceLanguage::GLSL,
        target: glslang::Target::Vulkan {
            version: glslang::VulkanVersion::Vulkan1_3,
            spirv_version: glslang::SpirvVersion::SPIRV1_6,
        },
        ..Default::default()
    };
    let input = glslang::ShaderInput::new(&source, stage, &options, None, None).map_err(|e| e.to_string())?;
    compiler.create_shader(input).map_err(|e| e.to_string())?.compile().map_err(|e| e.to_string())
}

/// How a pipeline tests and writes depth.
#[derive(Clone, Copy)]
enum Depth {
    /// No depth attachment.
    None,
    /// Reversed-Z, GREATER, written (the building).
    Write,
    /// Read-only, GREATER_OR_EQUAL, not written (the marker).
    Test,
}

struct Desc<'a> {
    vertex: &'a str,
    fragment: &'a str,
    formats: &'a [vk::Format],
    depth: Depth,
    layout: vk::PipelineLayout,
    spec: Option<u32>,
    cull: vk::CullModeFlags,
}

/// # Safety
/// `d` is the engine's device; `desc.layout` fits the shaders.
unsafe fn pipeline(d: &ash::Device, desc: &Desc) -> Result<vk::Pipeline, String> {
    let (vs, fs) =
        (spirv(desc.vertex, glslang::ShaderStage::Vertex)?, spirv(desc.fragment, glslang::ShaderStage::Fragment)?);
    // SAFETY: plain creation of the engine's pipeline objects.
    unsafe {
        let module = |w: &[u32]| d.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(w), None);
        let (vm, fm) = (module(&vs).map_err(|x| x.to_string())?, module(&fs).map_err(|x| x.to_string())?);
        let main: &CStr = c"main";
        let entries = [vk::SpecializationMapEntry::default().constant_id(0).offset(0).size(4)];
        let data = desc.spec.unwrap_or(0).to_ne_bytes();
        let spec = vk::SpecializationInfo::default().map_entries(&entries).data(&data);
        let mut fragment_stage =
            vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::FRAGMENT).module(fm).name(main);
        if desc.spec.is_some() {
            fragment_stage = fragment_stage.specialization_info(&spec);
        }
        let stages = [
            vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::VERTEX).module(vm).name(main),
            fragment_stage,
        ];
        let vertex = vk::PipelineVertexInputStateCreateInfo::default();
        let assembly =
            vk::PipelineInputAssemblyStateCreateInfo::default().topology(vk::PrimitiveTopology::TRIANGLE_LIST);
        let viewport = vk::PipelineViewportStateCreateInfo::default().viewport_count(1).scissor_count(1);
        let raster = vk::PipelineRasterizationStateCreateInfo::default()
            .line_width(1.0)
            .cull_mode(desc.cull)
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE);
        let ms = vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let depth = match desc.depth {
            Depth::None => vk::PipelineDepthStencilStateCreateInfo::default(),
            Depth::Write => vk::PipelineDepthStencilStateCreateInfo::default()
                .depth_test_enable(true)
                .depth_write_enable(true)
                .depth_compare_op(vk::CompareOp::GREATER),
            Depth::Test => vk::PipelineDepthStencilStateCreateInfo::default()
                .depth_test_enable(true)
                .depth_compare_op(vk::CompareOp::GREATER_OR_EQUAL),
        };
        let blend: Vec<_> = desc
            .formats
            .iter()
            .map(|_| vk::PipelineColorBlendAttachmentState::default().color_write_mask(vk::ColorComponentFlags::RGBA))
            .collect();
        let blending = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend);
        let dynamic = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic);
        let with_depth = !matches!(desc.depth, Depth::None);
        let depth_format = if with_depth { DEPTH.format } else { vk::Format::UNDEFINED };
        let mut rendering = vk::PipelineRenderingCreateInfo::default()
            .color_attachment_formats(desc.formats)
            .depth_attachment_format(depth_format)
            .stencil_attachment_format(depth_format);
        let info = vk::GraphicsPipelineCreateInfo::default()
            .stages(&stages)
            .vertex_input_state(&vertex)
            .input_assembly_state(&assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&ms)
            .depth_stencil_state(&depth)
            .color_blend_state(&blending)
            .dynamic_state(&dynamic)
            .layout(desc.layout)
            .push_next(&mut rendering);
        let made = d.create_graphics_pipelines(vk::PipelineCache::null(), &[info], None);
        d.destroy_shader_module(vm, None);
        d.destroy_shader_module(fm, None);
        Ok(made.map_err(|(_, x)| x.to_string())?[0])
    }
}

/// The engine's pipelines for one mode, their layouts and the one
/// descriptor set its full-screen pass reads.
pub struct Passes {
    mode: Mode,
    set_layout: vk::DescriptorSetLayout,
    pool: vk::DescriptorPool,
    set: vk::DescriptorSet,
    sampler: vk::Sampler,
    /// Push constants: `LightPush` (fragment), then `BoxPush` (vertex) from
    /// offset 64: 128 bytes, what every device offers.
    layout: vk::PipelineLayout,
    marker_layout: vk::PipelineLayout,
    building: vk::Pipeline,
    /// The lighting (gbuffer) or tonemap (hdr) pass; none for `lit`.
    resolve: Option<vk::Pipeline>,
    marker: vk::Pipeline,
}

impl Passes {
    /// # Safety
    /// `d` is the engine's device; `targets` outlive the passes.
    pub unsafe fn new(d: &ash::Device, mode: Mode, targets: &Targets) -> Result<Passes, String> {
        unsafe {
            let (set_layout, pool, set, sampler) = descriptors(d, mode)?;
            let (layout, marker_layout) = pipeline_layouts(d, set_layout)?;
            let building = building_pipeline(d, mode, layout)?;
            let resolve = resolve_pipeline(d, mode, layout)?;
            let ldr = [COLOR_FORMAT];
            let marker = pipeline(
                d,
                &Desc {
                    vertex: MARKER_VERT,
                    fragment: MARKER_FRAG,
                    formats: &ldr,
                    depth: Depth::Test,
                    layout: marker_layout,
                    spec: None,
                    cull: vk::CullModeFlags::NONE,
                },
            )?;
            let passes =
                Passes { mode, set_layout, pool, set, sampler, layout, marker_layout, building, resolve, marker };
            passes.write_set(d, targets);
            Ok(passes)
        }
    }

    /// Points the full-screen pass at its inputs.
    unsafe fn write_set(&self, d: &ash::Device, t: &Targets) {
        let read = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        let views: Vec<(vk::ImageView, vk::ImageLayout)> = match self.mode {
            Mode::Lit => return,
            // (Binding 1 is the lighting's normal: the tonemap reads none.)
            Mode::Hdr => {
                let hdr = t.hdr.as_ref().expect("made for hdr").view;
                vec![(hdr, read), (hdr, read), (t.depth.sampled, vk::ImageLayout::DEPTH_STENCIL_READ_ONLY_OPTIMAL)]
            }
            Mode::Gbuffer => vec![
                (t.gbuffer[0].view, read),
                (t.gbuffer[1].view, read),
                (t.depth.sampled, vk::ImageLayout::DEPTH_STENCIL_READ_ONLY_OPTIMAL),
            ],
        };
        let infos: Vec<[vk::DescriptorImageInfo; 1]> = views
            .iter()
            .map(|&(image_view, image_layout)| {
                [vk::DescriptorImageInfo { sampler: self.sampler, image_view, image_layout }]
            })
            .collect();
        let writes: Vec<_> = infos
            .iter()
            .enumerate()
            .map(|(i, info)| {
                vk::WriteDescriptorSet::default()
                    .dst_set(self.set)
                    .dst_binding(i as u32)
                    .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                    .image_info(info)
            })
            .collect();
        // SAFETY: the set is not in use (made above, before any frame).
        unsafe { d.update_descriptor_sets(&writes, &[]) };
    }

    /// The building into the engine's targets (inside their rendering scope).
    ///
    /// # Safety
    /// `cmd` is recording inside a scope of this mode's building targets.
    pub unsafe fn draw_building(&self, d: &ash::Device, cmd: vk::CommandBuffer, light: &LightPush, b: &BoxPush) {
        unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, self.building);
            d.cmd_push_constants(cmd, self.layout, vk::ShaderStageFlags::FRAGMENT, 0, bytemuck::bytes_of(light));
            d.cmd_push_constants(cmd, self.layout, vk::ShaderStageFlags::VERTEX, 64, bytemuck::bytes_of(b));
            d.cmd_draw(cmd, 36, 1, 0, 0);
        }
    }

    /// The full-screen lighting or tonemap into the display image (inside
    /// its scope); nothing for `lit`.
    ///
    /// # Safety
    /// `cmd` is recording inside a scope of the display image, the inputs in
    /// the layouts `write_set` named.
    pub unsafe fn resolve(&self, d: &ash::Device, cmd: vk::CommandBuffer, light: &LightPush) {
        let Some(p) = self.resolve else { return };
        unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, p);
            d.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::GRAPHICS, self.layout, 0, &[self.set], &[]);
            d.cmd_push_constants(cmd, self.layout, vk::ShaderStageFlags::FRAGMENT, 0, bytemuck::bytes_of(light));
            d.cmd_draw(cmd, 3, 1, 0, 0);
        }
    }

    /// # Safety
    /// `cmd` is recording inside a scope of the display image and the depth.
    pub unsafe fn draw_markers(&self, d: &ash::Device, cmd: vk::CommandBuffer, markers: &[Marker]) {
        unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, self.marker);
            for m in markers {
                d.cmd_push_constants(cmd, self.marker_layout, vk::ShaderStageFlags::VERTEX, 0, bytemuck::bytes_of(m));
                d.cmd_draw(cmd, 6, 1, 0, 0);
            }
        }
    }

    /// # Safety
    /// The device is idle.
    pub unsafe fn destroy(&self, d: &ash::Device) {
        unsafe {
            for p in [self.building, self.marker].into_iter().chain(self.resolve) {
                d.destroy_pipeline(p, None);
            }
            d.destroy_pipeline_layout(self.layout, None);
            d.destroy_pipeline_layout(self.marker_layout, None);
            d.destroy_sampler(self.sampler, None);
            d.destroy_descriptor_pool(self.pool, None);
            d.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}

/// The one descriptor set of the full-screen pass, its layout and pool,
/// and the sampler it reads with.
///
/// # Safety
/// `d` is the engine's device.
unsafe fn descriptors(
    d: &ash::Device,
    mode: Mode,
) -> Result<(vk::DescriptorSetLayout, vk::DescriptorPool, vk::DescriptorSet, vk::Sampler), String> {
    let e = |x: vk::Result| x.to_string();
    // SAFETY: as the caller promises; the create infos are locals.
    unsafe {
        // Exactly what the mode's full-screen pass reads (a binding left
        // unwritten is not something every driver tolerates).
        let inputs = if mode == Mode::Lit { 0 } else { 3 };
        let bindings: Vec<_> = (0..inputs)
            .map(|i| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(i)
                    .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::FRAGMENT)
            })
            .collect();
        let set_layout = d
            .create_descriptor_set_layout(&vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings), None)
            .map_err(e)?;
        let sizes = [vk::DescriptorPoolSize { ty: vk::DescriptorType::COMBINED_IMAGE_SAMPLER, descriptor_count: 3 }];
        let pool = d
            .create_descriptor_pool(&vk::DescriptorPoolCreateInfo::default().max_sets(1).pool_sizes(&sizes), None)
            .map_err(e)?;
        let layouts = [set_layout];
        let set = d
            .allocate_descriptor_sets(
                &vk::DescriptorSetAllocateInfo::default().descriptor_pool(pool).set_layouts(&layouts),
            )
            .map_err(e)?[0];
        let sampler = d.create_sampler(&vk::SamplerCreateInfo::default(), None).map_err(e)?;
        Ok((set_layout, pool, set, sampler))
    }
}

/// The passes' layout (`LightPush`, then `BoxPush`) and the marker's.
///
/// # Safety
/// `d` is the engine's device; `set_layout` is its.
unsafe fn pipeline_layouts(
    d: &ash::Device,
    set_layout: vk::DescriptorSetLayout,
) -> Result<(vk::PipelineLayout, vk::PipelineLayout), String> {
    let e = |x: vk::Result| x.to_string();
    let layouts = [set_layout];
    // SAFETY: as the caller promises; the create infos are locals.
    unsafe {
        let ranges = [
            vk::PushConstantRange::default().stage_flags(vk::ShaderStageFlags::FRAGMENT).size(64),
            vk::PushConstantRange::default().stage_flags(vk::ShaderStageFlags::VERTEX).offset(64).size(64),
        ];
        let layout = d
            .create_pipeline_layout(
                &vk::PipelineLayoutCreateInfo::default().set_layouts(&layouts).push_constant_ranges(&ranges),
                None,
            )
            .map_err(e)?;
        let marker_range = [vk::PushConstantRange::default().stage_flags(vk::ShaderStageFlags::VERTEX).size(32)];
        let marker_layout = d
            .create_pipeline_layout(&vk::PipelineLayoutCreateInfo::default().push_constant_ranges(&marker_range), None)
            .map_err(e)?;
        Ok((layout, marker_layout))
    }
}

/// The building's pipeline, into the mode's colour target or G-buffer.
///
/// # Safety
/// `d` is the engine's device; `layout` is `pipeline_layouts`'s first.
unsafe fn building_pipeline(d: &ash::Device, mode: Mode, layout: vk::PipelineLayout) -> Result<vk::Pipeline, String> {
    let vert = BOX_VERT;
    // SAFETY: as the caller promises.
    unsafe {
        let building = match mode {
            Mode::Lit | Mode::Hdr => {
                let formats = if mode == Mode::Lit { [COLOR_FORMAT] } else { [HDR_FORMAT] };
                let spec = Some(u32::from(mode == Mode::Hdr));
                let frag = box_colour_frag();
                let desc = Desc {
                    vertex: vert,
                    fragment: &frag,
                    formats: &formats,
                    depth: Depth::Write,
                    layout,
                    spec,
                    cull: vk::CullModeFlags::NONE,
                };
                pipeline(d, &desc)?
            }
            Mode::Gbuffer => {
                let formats = gbuffer_layout().formats();
                let desc = Desc {
                    vertex: vert,
                    fragment: BOX_GBUFFER_FRAG,
                    formats: &formats,
                    depth: Depth::Write,
                    layout,
                    spec: None,
                    cull: vk::CullModeFlags::NONE,
                };
                pipeline(d, &desc)?
            }
        };
        Ok(building)
    }
}

/// The full-screen lighting (gbuffer) or tonemap (hdr); none for `lit`.
///
/// # Safety
/// `d` is the engine's device; `layout` is `pipeline_layouts`'s first.
unsafe fn resolve_pipeline(
    d: &ash::Device,
    mode: Mode,
    layout: vk::PipelineLayout,
) -> Result<Option<vk::Pipeline>, String> {
    let ldr = [COLOR_FORMAT];
    // SAFETY: as the caller promises.
    unsafe {
        let resolve_frag = match mode {
            Mode::Lit => None,
            Mode::Hdr => Some(tonemap_frag()),
            Mode::Gbuffer => Some(light_frag()),
        };
        let resolve = match resolve_frag {
            Some(f) => Some(pipeline(
                d,
                &Desc {
                    vertex: FULLSCREEN_VERT,
                    fragment: &f,
                    formats: &ldr,
                    depth: Depth::None,
                    layout,
                    spec: None,
                    cull: vk::CullModeFlags::NONE,
                },
            )?),
            None => None,
        };
        Ok(resolve)
    }
}
