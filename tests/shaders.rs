//! Every shader validates, Rust twins match the reflected struct sizes, and a
//! broken shader is reported with its file and line.

#[path = "../build/shader_compiler.rs"]
#[allow(dead_code)]
mod shader_compiler;

use vista::shaders;

#[test]
fn every_shader_parses_and_validates_with_naga() {
    assert!(shaders::ALL.len() >= 5);
    for sh in shaders::ALL {
        let bytes: Vec<u8> = sh.spirv.iter().flat_map(|w| w.to_le_bytes()).collect();
        let opts = naga::front::spv::Options {
            adjust_coordinate_space: false,
            strict_capabilities: false,
            block_ctx_dump_prefix: None,
        };
        let module = naga::front::spv::parse_u8_slice(&bytes, &opts).unwrap_or_else(|e| panic!("{}: {e}", sh.file));
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all())
            .validate(&module)
            .unwrap_or_else(|e| panic!("{}: {e}", sh.file));
        assert_eq!(sh.spirv[0], 0x0723_0203, "{}: SPIR-V magic", sh.file);
    }
}

#[test]
fn rust_twins_match_reflected_sizes() {
    use std::mem::size_of;
    use vista::passes::{
        diamond_patch::DiamondPatchPush, prefix_sum::PrefixSumPush, smoke_triangle::SmokeTrianglePush,
    };
    assert_eq!(size_of::<PrefixSumPush>(), shaders::structs::PREFIX_SUM_PUSH);
    assert_eq!(size_of::<SmokeTrianglePush>(), shaders::structs::SMOKE_TRIANGLE_PUSH);
    assert_eq!(size_of::<DiamondPatchPush>(), shaders::structs::DIAMOND_PATCH_PUSH);
    assert_eq!(size_of::<PrefixSumPush>() as u32, shaders::prefix_sum::PUSH_CONSTANT_SIZE);
    use vista::passes::quadtree_update::QuadtreeUpdatePush;
    use vista::passes::traverse::{TraverseHeader, TraversePush};
    use vista::quadtree::QuadtreeUpdate;
    assert_eq!(size_of::<QuadtreeUpdate>(), shaders::structs::QUADTREE_UPDATE);
    assert_eq!(size_of::<QuadtreeUpdatePush>(), shaders::structs::QUADTREE_UPDATE_PUSH);
    assert_eq!(size_of::<TraversePush>(), shaders::structs::TRAVERSE_PUSH);
    assert_eq!(size_of::<TraverseHeader>(), shaders::structs::TRAVERSE_HEADER);
    assert_eq!(size_of::<TraversePush>() as u32, shaders::traverse::PUSH_CONSTANT_SIZE);
    assert_eq!(shaders::traverse::PUSH_CONSTANT_SIZE, shaders::traverse_level::PUSH_CONSTANT_SIZE);
    use vista::passes::cull_patches::{CullPush, PatchListHeader};
    use vista::passes::terrain_geometry::GeometryPush;
    use vista::render::TerrainViewGpu;
    assert_eq!(size_of::<CullPush>(), shaders::structs::CULL_PUSH);
    assert_eq!(size_of::<CullPush>() as u32, shaders::cull_patches::PUSH_CONSTANT_SIZE);
    assert_eq!(size_of::<PatchListHeader>(), shaders::structs::PATCH_LIST_HEADER);
    // The header leads with a VkDrawIndexedIndirectCommand.
    assert_eq!(std::mem::offset_of!(PatchListHeader, first_instance) + 4, 20);
    assert_eq!(size_of::<GeometryPush>(), shaders::structs::GEOMETRY_PUSH);
    assert_eq!(size_of::<GeometryPush>() as u32, shaders::terrain_geometry_vert::PUSH_CONSTANT_SIZE);
    assert_eq!(size_of::<TerrainViewGpu>(), shaders::structs::TERRAIN_VIEW);
}

#[test]
fn reflection_reports_bindings_workgroup_and_spec_constants() {
    let p = &shaders::prefix_sum::SHADER;
    assert_eq!(p.workgroup_size, [256, 1, 1]);
    assert_eq!(p.bindings.len(), 2);
    assert_eq!(shaders::prefix_sum::INPUT_VALUES.kind, vista::gpu::BindingKind::StorageBuffer);
    assert_ne!(shaders::prefix_sum::INPUT_VALUES.binding, shaders::prefix_sum::OUTPUT_SUMS.binding);
    assert_eq!(p.spec_constants, &[("ITEMS_PER_THREAD", shaders::prefix_sum::SPEC_ITEMS_PER_THREAD)]);
}

fn temp_dir(tag: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("vista-shader-test-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(d.join("common")).unwrap();
    d
}

#[test]
fn syntax_error_names_file_and_line() {
    let dir = temp_dir("syntax");
    let file = dir.join("broken.comp");
    std::fs::write(
        &file,
        "#version 460\nlayout(local_size_x = 1) in;\nvoid main() {\n    uint x = undefined_thing;\n}\n",
    )
    .unwrap();
    let err = shader_compiler::compile_file(&file, &dir.join("common")).expect_err("a broken shader must not compile");
    let expect = format!("{}:4:", file.display());
    assert!(err.contains(&expect), "error should name {expect}: {err}");
    assert!(err.contains("undefined_thing"), "{err}");
}

#[test]
fn error_inside_an_include_names_the_include() {
    let dir = temp_dir("include");
    std::fs::write(dir.join("common/bad.glsl"), "// first line\nfloat f() { return nope; }\n").unwrap();
    let file = dir.join("uses_bad.comp");
    std::fs::write(&file, "#version 460\n#extension GL_GOOGLE_include_directive : require\n#include \"bad.glsl\"\nlayout(local_size_x = 1) in;\nvoid main() {}\n").unwrap();
    let err = shader_compiler::compile_file(&file, &dir.join("common")).expect_err("must fail");
    assert!(err.contains("bad.glsl:2"), "error should name bad.glsl:2: {err}");
}

#[test]
fn naga_rejection_stops_the_build_too() {
    let dir = temp_dir("naga");
    let file = dir.join("writeonly.comp");
    std::fs::write(&file, "#version 460\nlayout(local_size_x = 1) in;\nlayout(set = 0, binding = 0) writeonly buffer B { uint v[]; } b;\nvoid main() { b.v[0] = 1u; }\n").unwrap();
    let err = shader_compiler::compile_file(&file, &dir.join("common")).expect_err("naga rejects write-only storage");
    assert!(err.contains("writeonly.comp") && err.contains("naga"), "{err}");
}
