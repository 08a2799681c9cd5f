//! Shader compilation and reflection, shared by `build.rs` and the test that
//! proves a broken shader stops the build with its file and line.
//!
//! GLSL is compiled with glslang (Vulkan 1.3 target), then parsed and validated
//! with naga, whose IR is also the source of every reflected number the host
//! uses (bindings, workgroup size, push-constant and struct sizes).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// One descriptor binding as the shader declares it.
#[derive(Debug, Clone, PartialEq)]
pub struct ReflectedBinding {
    pub name: String,
    pub set: u32,
    pub binding: u32,
    /// Variant name of `vista::gpu::BindingKind`.
    pub kind: &'static str,
    /// A storage buffer or image the shader may write (not `readonly`).
    pub writes: bool,
}

/// A named GLSL struct as the SPIR-V lays it out.
#[derive(Debug, Clone, PartialEq)]
pub struct StructLayout {
    pub name: String,
    pub size: u32,
    pub members: Vec<(String, u32, u32)>,
}

/// One `#define NAME VALUEu` of `common/constants.glsl`.
#[derive(Debug, Clone, PartialEq)]
pub struct SharedConstant {
    pub name: String,
    pub value: u32,
    /// The comment lines just above it.
    pub doc: String,
}

/// Parses `common/constants.glsl`: include guards, comments, blank lines and
/// `#define NAME VALUE` with an unsigned decimal or hex literal ending in
/// `u`. Anything else is an error naming the line, so the file stays a plain
/// table both sides can trust.
pub fn parse_constants(text: &str, file: &str) -> Result<Vec<SharedConstant>, String> {
    let mut out: Vec<SharedConstant> = Vec::new();
    // A comment documents the defines right below it, up to a blank line.
    let mut doc = Vec::new();
    let mut after_define = false;
    for (i, line) in text.lines().enumerate() {
        let l = line.trim();
        let at = || format!("{file}:{}", i + 1);
        if let Some(c) = l.strip_prefix("//") {
            if after_define {
                doc.clear();
                after_define = false;
            }
            doc.push(c.trim().to_string());
            continue;
        }
        if l.is_empty() || l.starts_with("#ifndef") || l.starts_with("#endif") {
            doc.clear();
            after_define = false;
            continue;
        }
        let parts: Vec<&str> = l.split_whitespace().collect();
        match parts.as_slice() {
            ["#define", guard] if guard.starts_with("VISTA_") => {}
            ["#define", name, value] => {
                let digits =
                    value.strip_suffix('u').ok_or_else(|| format!("{}: {name}: value needs a `u` suffix", at()))?;
                let parsed = match digits.strip_prefix("0x") {
                    Some(hex) => u32::from_str_radix(hex, 16),
                    None => digits.parse(),
                };
                let value = parsed.map_err(|e| format!("{}: {name}: bad value {value}: {e}", at()))?;
                if !name.chars().all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_') {
                    return Err(format!("{}: {name}: names are UPPER_SNAKE_CASE", at()));
                }
                if out.iter().any(|c| c.name == *name) {
                    return Err(format!("{}: {name} defined twice", at()));
                }
                out.push(SharedConstant { name: name.to_string(), value, doc: doc.join(" ") });
                after_define = true;
            }
            _ => return Err(format!("{}: expected `#define NAME VALUEu`, got `{l}`", at())),
        }
    }
    Ok(out)
}

#[derive(Debug, Clone)]
pub struct CompiledShader {
    /// Rust module name: the file stem for compute shaders (it names the
    /// pass), `stem_vert` / `stem_frag` for graphics stages.
    pub module: String,
    pub file: String,
    /// Variant name of `vista::gpu::ShaderStage`.
    pub stage: &'static str,
    pub words: Vec<u32>,
    pub workgroup_size: [u32; 3],
    pub bindings: Vec<ReflectedBinding>,
    pub push_constant_size: u32,
    /// (name, constant id) of each specialization constant.
    pub spec_constants: Vec<(String, u32)>,
    /// Each named struct type: name, size in bytes, and its members as
    /// (name, byte offset, byte size).
    pub structs: Vec<StructLayout>,
    /// Files pulled in through `#include`, for `rerun-if-changed`.
    pub includes: Vec<PathBuf>,
    /// Variant defines switched on in this compilation (see [`variants_of`]).
    pub defines: Vec<String>,
    /// Bit mask of `defines` within the file's variant list.
    pub variant_mask: u32,
    /// The file's variant list (empty: one compilation).
    pub variant_names: Vec<String>,
}

/// Most variant switches a file may declare (2^N compilations).
const MAX_VARIANT_SWITCHES: usize = 4;

/// A file declares variants with a comment line `// variants: A B` among its
/// first lines: it is compiled once per subset of the names, each defined as
/// 1 (`#ifdef A`). A feature an effect adds becomes a separate pipeline with
/// only the bindings it uses, instead of dead code behind a constant.
pub fn variants_of(text: &str, file: &str) -> Result<Vec<String>, String> {
    let Some(line) = text.lines().take(20).find_map(|l| l.trim().strip_prefix("// variants:")) else {
        return Ok(Vec::new());
    };
    let names: Vec<String> = line.split_whitespace().map(str::to_string).collect();
    if names.is_empty() || names.len() > MAX_VARIANT_SWITCHES {
        return Err(format!("{file}: `// variants:` needs 1..={MAX_VARIANT_SWITCHES} names, got {names:?}"));
    }
    if let Some(bad) = names.iter().find(|n| !n.chars().all(|c| c.is_ascii_uppercase() || c == '_')) {
        return Err(format!("{file}: variant switch {bad:?} is not UPPER_SNAKE_CASE"));
    }
    Ok(names)
}

fn stage_of(path: &Path) -> Result<(glslang::ShaderStage, &'static str, naga::ShaderStage), String> {
    match path.extension().and_then(|e| e.to_str()) {
        Some("comp") => Ok((glslang::ShaderStage::Compute, "Compute", naga::ShaderStage::Compute)),
        Some("vert") => Ok((glslang::ShaderStage::Vertex, "Vertex", naga::ShaderStage::Vertex)),
        Some("frag") => Ok((glslang::ShaderStage::Fragment, "Fragment", naga::ShaderStage::Fragment)),
        other => Err(format!("{}: unknown shader extension {other:?} (expected comp, vert or frag)", path.display())),
    }
}

/// Every shader under `dir` (sorted, `.glsl` headers apart), folders
/// included; each folder is watched too.
pub fn walk(dir: &Path, shaders: &mut Vec<PathBuf>, headers: &mut Vec<PathBuf>) {
    println!("cargo:rerun-if-changed={}", dir.display());
    let mut entries: Vec<PathBuf> =
        std::fs::read_dir(dir).expect("shaders_glsl/ is missing").filter_map(|e| e.ok().map(|e| e.path())).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            walk(&p, shaders, headers);
        } else if p.extension().is_some_and(|e| e == "glsl") {
            headers.push(p);
        } else if p.is_file() {
            shaders.push(p);
        }
    }
}

/// Resolves `#include "x.glsl"` in the including header's folder, the
/// shader's folder, `common/`, then the root (`"grass/grass.glsl"`: an
/// effect's header named from elsewhere).
struct Includer {
    /// The shader's folder, `common/` and the root.
    dirs: [PathBuf; 3],
    seen: Vec<PathBuf>,
}

impl glslang::include::IncludeHandler for Includer {
    fn include(
        &mut self,
        _ty: glslang::include::IncludeType,
        header_name: &str,
        includer_name: &str,
        _depth: usize,
    ) -> Option<glslang::include::IncludeResult> {
        // A header's name is its path (as returned below); the shader's is not.
        let includer = Path::new(includer_name).parent().filter(|d| d.is_dir()).map(Path::to_path_buf);
        let path = includer.iter().chain(&self.dirs).map(|d| d.join(header_name)).find(|p| p.is_file())?;
        let data = std::fs::read_to_string(&path).ok()?;
        let name = path.display().to_string();
        self.seen.push(path);
        Some(glslang::include::IncludeResult { name, data })
    }
}

/// glslang names the main file "0" in its log; name it by path instead so a
/// failure reads `shaders_glsl/foo.comp:12: ...`.
fn rewrite_log(log: &str, file: &str) -> String {
    log.lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| l.replacen(" 0:", &format!(" {file}:"), 1))
        .collect::<Vec<_>>()
        .join("\n")
}

/// Compiles one GLSL file, once per variant (the full variant, every switch
/// on, last); `include_dir` resolves `#include "x.glsl"`.
pub fn compile_file(path: &Path, include_dir: &Path) -> Result<Vec<CompiledShader>, String> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| format!("{file}: cannot read: {e}"))?;
    let names = variants_of(&text, &file)?;
    let mut out = Vec::new();
    for mask in 0..1u32 << names.len() {
        let defines: Vec<String> =
            names.iter().enumerate().filter(|(i, _)| mask & (1 << i) != 0).map(|(_, n)| n.clone()).collect();
        let mut sh = compile_variant(path, &text, &defines, include_dir)?;
        sh.variant_mask = mask;
        sh.variant_names = names.clone();
        out.push(sh);
    }
    let full = out.last().expect("at least one compilation");
    for v in &out {
        if let Some(b) = v.bindings.iter().find(|b| !full.bindings.contains(b)) {
            return Err(format!("{file}: binding {} of variant {:?} differs from the full variant", b.name, v.defines));
        }
    }
    Ok(out)
}

fn compile_variant(path: &Path, text: &str, defines: &[String], include_dir: &Path) -> Result<CompiledShader, String> {
    let file = if defines.is_empty() {
        path.display().to_string()
    } else {
        format!("{} [{}]", path.display(), defines.join(" "))
    };
    let (gl_stage, stage_name, naga_stage) = stage_of(path)?;
    let text = text.to_string();
    let compiler = glslang::Compiler::acquire().ok_or("glslang failed to initialise")?;
    let source = glslang::ShaderSource::from(text);
    let options = glslang::CompilerOptions {
        source_language: glslang::SourceLanguage::GLSL,
        target: glslang::Target::Vulkan {
            version: glslang::VulkanVersion::Vulkan1_3,
            spirv_version: glslang::SpirvVersion::SPIRV1_6,
        },
        version_profile: None,
        ..Default::default()
    };
    let own = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    let root = include_dir.parent().unwrap_or(Path::new(".")).to_path_buf();
    let mut includer = Includer { dirs: [own, include_dir.to_path_buf(), root], seen: Vec::new() };
    let words = {
        let macros: Vec<(&str, Option<&str>)> = defines.iter().map(|d| (d.as_str(), Some("1"))).collect();
        let input = glslang::ShaderInput::new(&source, gl_stage, &options, Some(&macros[..]), Some(&mut includer))
            .map_err(|e| format!("{file}: {e}"))?;
        let shader = compiler.create_shader(input).map_err(|e| match e {
            glslang::error::GlslangError::ParseError(log) | glslang::error::GlslangError::PreprocessError(log) => {
                format!("{file}: GLSL error\n{}", rewrite_log(&log.log, &file))
            }
            other => format!("{file}: {other}"),
        })?;
        shader.compile().map_err(|e| format!("{file}: link/codegen failed: {e}"))?
    };
    let stem = path.file_stem().and_then(|s| s.to_str()).ok_or_else(|| format!("{file}: bad file name"))?;
    let module = match stage_name {
        "Compute" => stem.to_string(),
        "Vertex" => format!("{stem}_vert"),
        _ => format!("{stem}_frag"),
    };
    let mut out = reflect(&words, &file, naga_stage)?;
    out.module = module;
    out.stage = stage_name;
    out.words = words;
    out.includes = includer.seen;
    out.file = path.display().to_string();
    out.defines = defines.to_vec();
    Ok(out)
}

fn binding_kind(module: &naga::Module, var: &naga::GlobalVariable, file: &str) -> Result<&'static str, String> {
    let inner = &module.types[var.ty].inner;
    let inner = match inner {
        naga::TypeInner::BindingArray { .. } => return Err(format!("{file}: binding arrays are not supported")),
        i => i,
    };
    Ok(match (var.space, inner) {
        (naga::AddressSpace::Storage { .. }, _) => "StorageBuffer",
        (naga::AddressSpace::Uniform, _) => "UniformBuffer",
        (naga::AddressSpace::Handle, naga::TypeInner::Sampler { .. }) => "Sampler",
        (naga::AddressSpace::Handle, naga::TypeInner::Image { class: naga::ImageClass::Storage { .. }, .. }) => {
            "StorageImage"
        }
        (naga::AddressSpace::Handle, naga::TypeInner::Image { .. }) => "SampledImage",
        (space, _) => return Err(format!("{file}: unsupported resource in address space {space:?}")),
    })
}

/// Whether the shader may store through the binding.
fn binding_writes(module: &naga::Module, var: &naga::GlobalVariable) -> bool {
    match (var.space, &module.types[var.ty].inner) {
        (naga::AddressSpace::Storage { access }, _) => access.contains(naga::StorageAccess::STORE),
        (_, naga::TypeInner::Image { class: naga::ImageClass::Storage { access, .. }, .. }) => {
            access.contains(naga::StorageAccess::STORE)
        }
        _ => false,
    }
}

fn error_chain(e: &dyn std::error::Error) -> String {
    let mut out = e.to_string();
    let mut cur = e.source();
    while let Some(inner) = cur {
        out.push_str(": ");
        out.push_str(&inner.to_string());
        cur = inner.source();
    }
    out
}

fn reflect(words: &[u32], file: &str, stage: naga::ShaderStage) -> Result<CompiledShader, String> {
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    let options = naga::front::spv::Options {
        adjust_coordinate_space: false,
        strict_capabilities: false,
        block_ctx_dump_prefix: None,
    };
    let module = naga::front::spv::parse_u8_slice(&bytes, &options)
        .map_err(|e| format!("{file}: naga cannot parse the SPIR-V: {e}"))?;
    naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all())
        .validate(&module)
        .map_err(|e| format!("{file}: naga validation failed: {}", error_chain(e.as_inner())))?;
    let entry = module
        .entry_points
        .iter()
        .find(|e| e.stage == stage)
        .ok_or_else(|| format!("{file}: no {stage:?} entry point"))?;

    let mut bindings = Vec::new();
    let mut push_constant_size = 0;
    for (_, var) in module.global_variables.iter() {
        let type_name = module.types[var.ty].name.clone().unwrap_or_default();
        let name = var.name.clone().filter(|n| !n.is_empty()).unwrap_or(type_name);
        if var.space == naga::AddressSpace::Immediate {
            push_constant_size = module.types[var.ty].inner.size(module.to_ctx());
            continue;
        }
        let Some(rb) = var.binding else { continue };
        if name.is_empty() {
            return Err(format!("{file}: binding (set {}, binding {}) has no name", rb.group, rb.binding));
        }
        bindings.push(ReflectedBinding {
            name,
            set: rb.group,
            binding: rb.binding,
            kind: binding_kind(&module, var, file)?,
            writes: binding_writes(&module, var),
        });
    }
    bindings.sort_by_key(|b| (b.set, b.binding));

    let spec_constants =
        module.overrides.iter().filter_map(|(_, o)| Some((o.name.clone()?, u32::from(o.id?)))).collect();
    let structs = module
        .types
        .iter()
        .filter_map(|(_, t)| match (&t.name, &t.inner) {
            (Some(n), naga::TypeInner::Struct { span, members }) if !n.is_empty() => Some(StructLayout {
                name: n.clone(),
                size: *span,
                members: members
                    .iter()
                    .map(|m| {
                        let size = module.types[m.ty].inner.size(module.to_ctx());
                        (m.name.clone().unwrap_or_default(), m.offset, size)
                    })
                    .collect(),
            }),
            _ => None,
        })
        .collect();
    Ok(CompiledShader {
        module: String::new(),
        file: file.to_string(),
        stage: "",
        words: Vec::new(),
        workgroup_size: entry.workgroup_size,
        bindings,
        push_constant_size,
        spec_constants,
        structs,
        includes: Vec::new(),
        defines: Vec::new(),
        variant_mask: 0,
        variant_names: Vec::new(),
    })
}

fn const_ident(name: &str) -> String {
    let mut out = String::new();
    let mut prev_lower = false;
    for c in name.chars() {
        if c.is_ascii_uppercase() && prev_lower {
            out.push('_');
        }
        prev_lower = c.is_ascii_lowercase() || c.is_ascii_digit();
        out.push(if c.is_ascii_alphanumeric() { c.to_ascii_uppercase() } else { '_' });
    }
    out
}

/// The constants of constants.glsl, and their table by name.
fn write_constants(s: &mut String, constants: &[SharedConstant]) {
    s.push_str(
        "/// The constants of `shaders_glsl/common/constants.glsl`, shared by host and shaders.\npub mod consts {\n",
    );
    for c in constants {
        let _ = writeln!(s, "    /// {}\n    pub const {}: u32 = {};", c.doc, c.name, c.value);
    }
    let all: Vec<String> = constants.iter().map(|c| format!("({:?}, {})", c.name, c.name)).collect();
    let _ =
        writeln!(s, "    /// Every constant by name.\n    pub const ALL: &[(&str, u32)] = &[{}];\n}}", all.join(", "));
}

/// One shader file's module: its pass name, bindings, spec constants,
/// sizes, variant switches and every compilation.
fn write_shader_module(s: &mut String, group: &[CompiledShader]) {
    let sh = group.last().expect("non-empty group");
    let _ = writeln!(s, "/// `{}`\npub mod {} {{\n    use crate::gpu::shader::*;", sh.file, sh.module);
    let pass = sh.module.trim_end_matches("_vert").trim_end_matches("_frag");
    let _ = writeln!(s, "    /// The pass (and timer label) this shader belongs to: its file stem.\n    pub const PASS: &str = {pass:?};");
    for b in &sh.bindings {
        let _ = writeln!(
            s,
            "    pub const {}: Binding = Binding {{ name: {:?}, set: {}, binding: {}, kind: BindingKind::{}, writes: {} }};",
            const_ident(&b.name),
            b.name,
            b.set,
            b.binding,
            b.kind,
            b.writes
        );
    }
    for (name, id) in &sh.spec_constants {
        let _ = writeln!(s, "    pub const SPEC_{}: u32 = {id};", const_ident(name));
    }
    let _ = writeln!(s, "    pub const WORKGROUP_SIZE: [u32; 3] = {:?};", sh.workgroup_size);
    let _ = writeln!(s, "    pub const PUSH_CONSTANT_SIZE: u32 = {};", sh.push_constant_size);
    for (i, name) in sh.variant_names.iter().enumerate() {
        let _ = writeln!(
            s,
            "    /// Variant switch `{name}` (a bit of [`variant`]'s mask).\n    pub const VARIANT_{name}: u32 = {};",
            1u32 << i
        );
    }
    for v in group.iter() {
        let list: Vec<String> = v.bindings.iter().map(|b| const_ident(&b.name)).collect();
        let specs: Vec<String> = v.spec_constants.iter().map(|(n, id)| format!("({n:?}, {id})")).collect();
        let full = std::ptr::eq(v, sh);
        let ident = if full { "SHADER".to_string() } else { format!("SHADER_V{}", v.variant_mask) };
        let _ = writeln!(s, "    static SPIRV_V{}: [u32; {}] = {:?};", v.variant_mask, v.words.len(), v.words);
        let _ = writeln!(
            s,
            "    {}static {ident}: ShaderInfo = ShaderInfo {{ name: {:?}, file: {:?}, stage: ShaderStage::{}, defines: &{:?}, spirv: &SPIRV_V{}, workgroup_size: {:?}, bindings: &[{}], push_constant_size: {}, spec_constants: &[{}] }};",
            if full { "pub " } else { "" },
            v.module,
            v.file,
            v.stage,
            v.defines,
            v.variant_mask,
            v.workgroup_size,
            list.join(", "),
            v.push_constant_size,
            specs.join(", ")
        );
    }
    let idents: Vec<String> = group
        .iter()
        .map(|v| if std::ptr::eq(v, sh) { "&SHADER".to_string() } else { format!("&SHADER_V{}", v.variant_mask) })
        .collect();
    let _ = writeln!(
        s,
        "    /// Every compilation of the file, indexed by variant mask.\n    pub static VARIANTS: [&ShaderInfo; {}] = [{}];",
        group.len(),
        idents.join(", ")
    );
    if !sh.variant_names.is_empty() {
        let _ = writeln!(s, "    /// The compilation with the switches of `mask` on.\n    pub fn variant(mask: u32) -> &'static ShaderInfo {{\n        VARIANTS[mask as usize]\n    }}");
    }
    s.push_str("}\n");
}

/// Every named GLSL struct's layout, checked the same across shaders
/// (with the file it was first seen in).
fn struct_layouts(shaders: &[CompiledShader]) -> Result<BTreeMap<String, (StructLayout, String)>, String> {
    let mut structs: BTreeMap<String, (StructLayout, String)> = BTreeMap::new();
    for sh in shaders {
        for st in &sh.structs {
            match structs.get(&st.name) {
                Some((old, where_)) if old != st => {
                    return Err(format!(
                        "struct {} differs between {where_} ({} bytes, {:?}) and {} ({} bytes, {:?})",
                        st.name, old.size, old.members, sh.file, st.size, st.members
                    ))
                }
                _ => {
                    structs.insert(st.name.clone(), (st.clone(), sh.file.clone()));
                }
            }
        }
    }
    Ok(structs)
}

/// Rust source of the generated `shaders` module. Struct layouts are
/// collected across all shaders; two shaders disagreeing on a struct's size
/// or member offsets is an error.
pub fn generate_module(shaders: &[CompiledShader], constants: &[SharedConstant]) -> Result<String, String> {
    let mut s = String::from("// @generated by build.rs from shaders_glsl/: do not edit.\n");
    write_constants(&mut s, constants);
    // Variants of one file are consecutive, the full one (every switch on) last.
    let mut groups: Vec<&[CompiledShader]> = Vec::new();
    let mut rest = shaders;
    while let Some(first) = rest.first() {
        let n = rest.iter().take_while(|v| v.module == first.module).count();
        groups.push(&rest[..n]);
        rest = &rest[n..];
    }
    for group in &groups {
        write_shader_module(&mut s, group);
    }
    let structs = struct_layouts(shaders)?;
    s.push_str("/// Byte size of every named GLSL struct, as the SPIR-V lays it out.\npub mod structs {\n");
    for (name, (st, _)) in &structs {
        let _ = writeln!(s, "    pub const {}: usize = {};", const_ident(name), st.size);
    }
    s.push_str("}\n/// Members of every named GLSL struct: (name, byte offset, byte size).\npub mod layouts {\n");
    for (name, (st, _)) in &structs {
        let _ = writeln!(s, "    pub const {}: &[(&str, usize, usize)] = &{:?};", const_ident(name), st.members);
    }
    s.push_str("}\n/// Every shader of the crate (one per file: its full variant).\npub static ALL: &[&crate::gpu::shader::ShaderInfo] = &[");
    for g in &groups {
        let _ = write!(s, "&{}::SHADER, ", g[0].module);
    }
    s.push_str("];\n");
    Ok(s)
}
