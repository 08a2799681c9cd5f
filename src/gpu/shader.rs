//! Types the generated `shaders` module is written in (see build.rs).

use ash::vk;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShaderStage {
    Compute,
    Vertex,
    Fragment,
}

impl ShaderStage {
    pub fn vk(self) -> vk::ShaderStageFlags {
        match self {
            ShaderStage::Compute => vk::ShaderStageFlags::COMPUTE,
            ShaderStage::Vertex => vk::ShaderStageFlags::VERTEX,
            ShaderStage::Fragment => vk::ShaderStageFlags::FRAGMENT,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BindingKind {
    StorageBuffer,
    UniformBuffer,
    SampledImage,
    StorageImage,
    Sampler,
}

impl BindingKind {
    pub fn vk(self) -> vk::DescriptorType {
        match self {
            BindingKind::StorageBuffer => vk::DescriptorType::STORAGE_BUFFER,
            BindingKind::UniformBuffer => vk::DescriptorType::UNIFORM_BUFFER,
            BindingKind::SampledImage => vk::DescriptorType::SAMPLED_IMAGE,
            BindingKind::StorageImage => vk::DescriptorType::STORAGE_IMAGE,
            BindingKind::Sampler => vk::DescriptorType::SAMPLER,
        }
    }
}

/// One descriptor binding, reflected from the SPIR-V. Host code names
/// bindings through these constants, never through literal numbers.
#[derive(Debug, Clone, Copy)]
pub struct Binding {
    pub name: &'static str,
    pub set: u32,
    pub binding: u32,
    pub kind: BindingKind,
    /// This shader may store through it (a storage buffer or image not
    /// declared `readonly`): the access logs count it as a write.
    pub writes: bool,
}

/// The same binding, whichever stage's view of its access (a vertex shader
/// may read what the fragment shader of the pipeline writes).
impl PartialEq for Binding {
    fn eq(&self, other: &Self) -> bool {
        (self.name, self.set, self.binding, self.kind) == (other.name, other.set, other.binding, other.kind)
    }
}

impl Eq for Binding {}

/// A compiled, validated and reflected shader.
#[derive(Debug)]
pub struct ShaderInfo {
    pub name: &'static str,
    pub file: &'static str,
    pub stage: ShaderStage,
    /// Variant switches on in this compilation (`// variants:` in the file).
    pub defines: &'static [&'static str],
    pub spirv: &'static [u32],
    pub workgroup_size: [u32; 3],
    pub bindings: &'static [Binding],
    pub push_constant_size: u32,
    /// (name, constant_id) of each specialization constant.
    pub spec_constants: &'static [(&'static str, u32)],
}
