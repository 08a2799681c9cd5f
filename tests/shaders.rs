//! The generated shader bank: it holds every shader file, Rust twins of GPU
//! structs match the reflected layouts member by member, shared constants
//! have one source, and a broken shader is reported with its file and line.

#[path = "../build/shader_compiler.rs"]
#[allow(dead_code)]
mod shader_compiler;

use std::mem::{offset_of, size_of};
use std::path::Path;
use vista::passes::cull_patches::{CullPush, PatchListHeader};
use vista::passes::debug_view::DebugViewPush;
use vista::passes::hiz_build::HizPush;
use vista::passes::prefix_sum::PrefixSumPush;
use vista::passes::quadtree_update::QuadtreeUpdatePush;
use vista::passes::sector_data::SectorDataPush;
use vista::passes::select_patches::{SelectHeader, SelectPush};
use vista::passes::terrain_geometry::TerrainDrawPush;
use vista::passes::terrain_query::{TerrainQueryPush, VistaTerrain};
use vista::passes::traverse::{LevelArgs, TraverseHeader, TraversePush};
use vista::render::TerrainViewGpu;
use vista::shaders::{self, layouts, structs};
use vista::terrain::quadtree::QuadtreeUpdate;

fn shader_dir() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders_glsl")
}

/// Every shader and header, the effects' folders included.
fn files() -> (Vec<std::path::PathBuf>, Vec<std::path::PathBuf>) {
    let (mut shaders, mut headers) = (Vec::new(), Vec::new());
    shader_compiler::walk(&shader_dir(), &mut shaders, &mut headers);
    (shaders, headers)
}

#[test]
fn the_bank_holds_every_shader_file_once() {
    let (shaders, _) = files();
    let mut on_disk: Vec<String> =
        shaders.iter().map(|p| p.file_name().unwrap().to_string_lossy().into_owned()).collect();
    on_disk.sort();
    let mut in_bank: Vec<String> =
        shaders::ALL.iter().map(|s| Path::new(s.file).file_name().unwrap().to_string_lossy().into_owned()).collect();
    in_bank.sort();
    assert_eq!(in_bank, on_disk);
    for s in shaders::ALL {
        // The pass name is the file stem; graphics stages add their stage.
        let stem = Path::new(s.file).file_stem().unwrap().to_str().unwrap();
        let expect = match s.stage {
            vista::gpu::ShaderStage::Compute => stem.to_string(),
            vista::gpu::ShaderStage::Vertex => format!("{stem}_vert"),
            vista::gpu::ShaderStage::Fragment => format!("{stem}_frag"),
        };
        assert_eq!(s.name, expect);
    }
}

/// (field name, byte offset, byte size) of a Rust struct's fields.
macro_rules! fields {
    ($t:ty: $($f:ident),+ $(,)?) => {{
        fn size_of_field<T, F>(_: fn(&T) -> &F) -> usize {
            size_of::<F>()
        }
        (size_of::<$t>(), vec![$((stringify!($f), offset_of!($t, $f), size_of_field(|t: &$t| &t.$f))),+])
    }};
}

/// The GLSL member name a Rust field stands for: `pad0`/`pad1` are the
/// elements of a Rust `pad` array, `dispatch_x/y/z` of `dispatch`.
fn stem(glsl: &str) -> &str {
    let s = glsl.trim_end_matches(|c: char| c.is_ascii_digit());
    s.strip_suffix("_x").or(s.strip_suffix("_y")).or(s.strip_suffix("_z")).unwrap_or(s)
}

/// Every GLSL member lies inside the Rust field of its name, the members of
/// a field tile it exactly, and the sizes agree: a swapped or missing field
/// fails here even when the total size matches.
fn check_layout(what: &str, rust: (usize, Vec<(&str, usize, usize)>), glsl: &[(&str, usize, usize)], size: usize) {
    let (rust_size, fields) = rust;
    assert_eq!(rust_size, size, "{what}: Rust size vs GLSL size");
    for (name, off, len) in &fields {
        let inside: Vec<_> = glsl.iter().filter(|(_, o, _)| (*off..off + len).contains(o)).collect();
        assert!(!inside.is_empty(), "{what}.{name}: no GLSL member at bytes {off}..{}", off + len);
        for (m, _, _) in &inside {
            assert!(*m == *name || stem(m) == *name, "{what}.{name} at {off} holds GLSL member {m}");
        }
        let covered: usize = inside.iter().map(|(_, _, s)| s).sum();
        assert_eq!((inside[0].1, covered), (*off, *len), "{what}.{name}: GLSL members {inside:?} do not tile it");
    }
    for (m, o, _) in glsl {
        assert!(fields.iter().any(|(_, off, len)| (*off..off + len).contains(o)), "{what}: GLSL member {m} unmatched");
    }
}

#[test]
fn rust_twins_match_reflected_layouts() {
    selection_twins_match();
    culling_and_drawing_twins_match();
    push_constant_blocks_are_the_pipelines();
}

/// The twins of the quadtree, traversal and terrain data passes.
fn selection_twins_match() {
    check_layout("PrefixSumPush", fields!(PrefixSumPush: count), layouts::PREFIX_SUM_PUSH, structs::PREFIX_SUM_PUSH);
    check_layout(
        "QuadtreeUpdate",
        fields!(QuadtreeUpdate: target, coords, word0, word1),
        layouts::QUADTREE_UPDATE,
        structs::QUADTREE_UPDATE,
    );
    check_layout(
        "QuadtreeUpdatePush",
        fields!(QuadtreeUpdatePush: count),
        layouts::QUADTREE_UPDATE_PUSH,
        structs::QUADTREE_UPDATE_PUSH,
    );
    check_layout(
        "TraversePush",
        fields!(TraversePush: cameras, forwards, camera_count, target_error_px, sector_size_m, lod_count, root_grid_x,
            root_grid_y, height_lo, height_scale, list_capacity, final_capacity, current_lod, box_pad),
        layouts::TRAVERSE_PUSH,
        structs::TRAVERSE_PUSH,
    );
    check_layout(
        "TraverseHeader",
        fields!(TraverseHeader: dispatch, node_count, overflow, missing_roots, pad, lod_counts),
        layouts::TRAVERSE_HEADER,
        structs::TRAVERSE_HEADER,
    );
    check_layout("LevelArgs", fields!(LevelArgs: x, y, z, count), layouts::LEVEL_ARGS, structs::LEVEL_ARGS);
    check_layout(
        "SectorDataPush",
        fields!(SectorDataPush: sectors_x, sectors_y, lod_count, pad),
        layouts::SECTOR_DATA_PUSH,
        structs::SECTOR_DATA_PUSH,
    );
    check_layout(
        "VistaTerrain",
        fields!(VistaTerrain: sector_size_m, spacing_m, sectors_x, sectors_y, lod_count, height_lo, height_range,
            extent_x_m, extent_y_m, grid_origin_x_m, grid_origin_y_m, pad),
        layouts::VISTA_TERRAIN,
        structs::VISTA_TERRAIN,
    );
    check_layout(
        "TerrainQueryPush",
        fields!(TerrainQueryPush: terrain, count, pad),
        layouts::TERRAIN_QUERY_PUSH,
        structs::TERRAIN_QUERY_PUSH,
    );
}

/// The twins of culling, drawing, the view and the materials.
fn culling_and_drawing_twins_match() {
    check_layout(
        "CullPush",
        fields!(CullPush: stages, capacity, depth_w, depth_h),
        layouts::CULL_PUSH,
        structs::CULL_PUSH,
    );
    check_layout(
        "PatchListHeader",
        fields!(PatchListHeader: index_count, instance_count, first_index, vertex_offset, first_instance, patches_in,
            after_frustum, after_cone, after_hole, after_occlusion, bound_bits, seam_overflow),
        layouts::PATCH_LIST_HEADER,
        structs::PATCH_LIST_HEADER,
    );
    // The header leads with a VkDrawIndexedIndirectCommand.
    assert_eq!(offset_of!(PatchListHeader, first_instance) + 4, 20);
    check_layout(
        "SelectHeader",
        fields!(SelectHeader: conflicts, refined, refine_capped, coarsened),
        layouts::SELECT_HEADER,
        structs::SELECT_HEADER,
    );
    check_layout(
        "SelectPush",
        fields!(SelectPush: phase, lod_count, budget, buckets_at, reversed, pad),
        layouts::SELECT_PUSH,
        structs::SELECT_PUSH,
    );
    check_layout(
        "TerrainDrawPush",
        fields!(TerrainDrawPush: nan_bits, phase, pad),
        layouts::TERRAIN_DRAW_PUSH,
        structs::TERRAIN_DRAW_PUSH,
    );
    check_layout(
        "DebugViewPush",
        fields!(DebugViewPush: colours, mode, pad),
        layouts::DEBUG_VIEW_PUSH,
        structs::DEBUG_VIEW_PUSH,
    );
    check_layout("HizPush", fields!(HizPush: src_size, dst_size, level, pad), layouts::HIZ_PUSH, structs::HIZ_PUSH);
    check_layout(
        "TerrainViewGpu",
        fields!(TerrainViewGpu: view_proj, frustum, sun_dir, sun_color, sky_color, camera_sample, camera_frac,
            camera_z, spacing_m, height_lo, height_scale, height_range, lod_map_w, lod_map_h, pad, inv_view_proj,
            viewport, camera_world, shade_bands, shade_slope, shade_flags, lod_forward, lod_params, lod_right, lod_up,
            image, control),
        layouts::TERRAIN_VIEW,
        structs::TERRAIN_VIEW,
    );
    check_layout(
        "ControlGpu",
        fields!(vista::effects::materials::ControlGpu: layers, tiling_m, threshold, sharpness, slope_damp, normal_damp,
            pad),
        layouts::CONTROL_TEXTURE,
        structs::CONTROL_TEXTURE,
    );
    check_layout(
        "MaterialGpu",
        fields!(vista::effects::materials::MaterialGpu: layers, tiling_m, cos_rot, sin_rot),
        layouts::TERRAIN_MATERIAL,
        structs::TERRAIN_MATERIAL,
    );
}

/// Push-constant blocks are exactly what the pipelines were built with.
fn push_constant_blocks_are_the_pipelines() {
    assert_eq!(size_of::<TraversePush>() as u32, shaders::traverse::PUSH_CONSTANT_SIZE);
    assert_eq!(shaders::traverse::PUSH_CONSTANT_SIZE, shaders::traverse_level::PUSH_CONSTANT_SIZE);
    assert_eq!(size_of::<CullPush>() as u32, shaders::cull_patches::PUSH_CONSTANT_SIZE);
    assert_eq!(size_of::<SelectPush>() as u32, shaders::select_patches::PUSH_CONSTANT_SIZE);
    assert_eq!(size_of::<TerrainDrawPush>() as u32, shaders::terrain_holes_vert::PUSH_CONSTANT_SIZE);
    assert_eq!(size_of::<TerrainDrawPush>() as u32, shaders::terrain_geometry_vert::PUSH_CONSTANT_SIZE);
    assert_eq!(size_of::<DebugViewPush>() as u32, shaders::debug_view_frag::PUSH_CONSTANT_SIZE);
    assert_eq!(size_of::<SectorDataPush>() as u32, shaders::sector_data::PUSH_CONSTANT_SIZE);
    assert_eq!(size_of::<TerrainQueryPush>() as u32, shaders::terrain_query::PUSH_CONSTANT_SIZE);
}

#[test]
fn a_swapped_field_fails_the_layout_check() {
    #[repr(C)]
    struct Swapped {
        capacity: u32,
        stages: u32,
        pad: [u32; 2],
    }
    let r = std::panic::catch_unwind(|| {
        check_layout("Swapped", fields!(Swapped: capacity, stages, pad), layouts::CULL_PUSH, structs::CULL_PUSH)
    });
    assert!(r.is_err(), "same size, swapped fields: must fail");
}

#[test]
fn shared_constants_have_one_source() {
    // No shader redeclares a name of constants.glsl (a second copy could
    // drift); the table itself parses to what the bank exports.
    let dir = shader_dir();
    let text = std::fs::read_to_string(dir.join("common/constants.glsl")).unwrap();
    let parsed = shader_compiler::parse_constants(&text, "constants.glsl").unwrap();
    let exported: Vec<(String, u32)> = shaders::consts::ALL.iter().map(|(n, v)| (n.to_string(), *v)).collect();
    assert_eq!(parsed.iter().map(|c| (c.name.clone(), c.value)).collect::<Vec<_>>(), exported);
    let (shaders, headers) = files();
    for path in shaders.iter().chain(&headers).filter(|p| !p.ends_with("constants.glsl")) {
        let src = std::fs::read_to_string(path).unwrap();
        for (name, _) in shaders::consts::ALL {
            for decl in [format!("const uint {name} "), format!("#define {name} ")] {
                assert!(!src.contains(&decl), "{}: redeclares {name}; include constants.glsl", path.display());
            }
        }
    }
    // Values the host relies on, derived independently of the table.
    use shaders::consts as k;
    assert_eq!(k::MAX_SLOTS, (1 << k::SLOT_BITS) - 1, "slots fill their fields");
    const { assert!(k::SHARED_LIST_CAPACITY > k::MAX_SLOTS, "a shared list holds every resident node") };
    assert_eq!(k::NODE_EMPTY, u32::from(u16::MAX), "R16 node texture");
    assert_eq!(
        k::SECTOR_DATA_WORDS,
        k::MAX_NODE_LODS.div_ceil(k::SECTOR_LODS_PER_WORD),
        "sector data holds every LOD a world can have, in as few words as fit"
    );
    const { assert!(k::SECTOR_LODS_PER_WORD * k::SLOT_BITS <= 32) };
    const { assert!(k::PATCH_DELTA_SHIFT + 4 * k::PATCH_DELTA_BITS <= 32, "four deltas fit the word") };
    const { assert!(k::PATCH_INDEX_SHIFT + k::PATCH_INDEX_MASK.count_ones() <= k::PATCH_DELTA_SHIFT) };
    const { assert!(k::MAX_LOD_DELTA < 1 << k::PATCH_DELTA_BITS, "a delta fits its bits") };
    // Stitching snaps in node coordinates: the coarsest grid divides the node.
    assert_eq!(vista::world::NODE_QUADS % (1u32 << k::MAX_LOD_DELTA), 0);
}

#[test]
fn the_constants_table_rejects_anything_but_defines() {
    let ok = "// doc\n#define A 1u\n#define B 0x10u\n";
    let c = shader_compiler::parse_constants(ok, "t").unwrap();
    assert_eq!(c.iter().map(|c| (c.name.as_str(), c.value)).collect::<Vec<_>>(), [("A", 1), ("B", 16)]);
    assert_eq!(c[1].doc, "doc", "a comment documents the defines below it");
    for (bad, why) in [
        ("#define A 1\n", "needs a `u` suffix"),
        ("#define A 1u\n#define A 2u\n", "defined twice"),
        ("const uint A = 1u;\n", "expected `#define"),
        ("#define a 1u\n", "UPPER_SNAKE_CASE"),
        ("#define A 0xZZu\n", "bad value"),
    ] {
        let err = shader_compiler::parse_constants(bad, "t.glsl").expect_err(bad);
        assert!(err.contains(why) && err.contains("t.glsl:"), "{bad:?}: {err}");
    }
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

#[test]
fn variants_leave_out_what_their_switches_add() {
    use shaders::{cull_patches as cull, gbuffer_tiles_frag as tiles};
    let names = |s: &vista::gpu::ShaderInfo| s.bindings.iter().map(|b| b.name).collect::<Vec<_>>();
    for material in ["splat_atlas", "materials", "detail_albedo", "detail_normal", "detail_height"] {
        assert!(!names(tiles::variant(0)).contains(&material), "far atlas only: no {material}");
        assert!(names(tiles::variant(tiles::VARIANT_MATERIALS)).contains(&material));
    }
    // The control-map flavour: its atlas and table and the detail textures,
    // none of the splat map's.
    let control = names(tiles::variant(tiles::VARIANT_CONTROL_MAP));
    for name in ["control_atlas", "control", "detail_albedo", "detail_normal", "detail_height"] {
        assert!(control.contains(&name) && !names(tiles::variant(tiles::VARIANT_MATERIALS)).contains(&"control_atlas"));
        assert!(!names(tiles::variant(0)).contains(&name), "far atlas only: no {name}");
    }
    assert!(!control.contains(&"splat_atlas") && !control.contains(&"materials"));
    // The virtual-texture flavour: its state buffer and cache images only
    // where its switch is on.
    let vt = names(tiles::variant(tiles::VARIANT_MATERIALS | tiles::VARIANT_VIRTUAL_TEXTURE));
    for name in ["vt_state", "vt_albedo", "vt_detail"] {
        assert!(vt.contains(&name) && !names(tiles::variant(tiles::VARIANT_MATERIALS)).contains(&name), "{name}");
    }
    let full = tiles::VARIANT_MATERIALS
        | tiles::VARIANT_CONTROL_MAP
        | tiles::VARIANT_VIRTUAL_TEXTURE
        | tiles::VARIANT_ENGINE_GBUFFER;
    assert!(std::ptr::eq(tiles::variant(full), &tiles::SHADER), "SHADER is the full variant");
    // Output `gbuffer`'s layout arrives as specialization constants, only
    // where its switch is on.
    let specs = |v| tiles::variant(v).spec_constants.iter().map(|(n, _)| *n).collect::<Vec<_>>();
    assert!(specs(tiles::VARIANT_ENGINE_GBUFFER).contains(&"GB_CHANNELS3"));
    assert!(!specs(0).contains(&"GB_FLAGS"));
    let bare = names(cull::variant(0));
    for gone in ["patch_cones", "patch_holes", "hole_list"] {
        assert!(!bare.contains(&gone), "{gone} in the bare cull variant");
    }
    assert!(names(cull::variant(cull::VARIANT_CONE_CULL)).contains(&"patch_cones"));
    assert!(!names(cull::variant(cull::VARIANT_CONE_CULL)).contains(&"patch_holes"));
    assert_eq!(cull::variant(cull::VARIANT_HOLE_CULL).defines, &["HOLE_CULL"]);
    assert_eq!(cull::VARIANTS.len(), 8);
    assert!(!bare.contains(&"visibility") && names(cull::variant(cull::VARIANT_OCCLUSION)).contains(&"visibility"));
    // A file's switch list is checked.
    assert!(shader_compiler::variants_of("// variants: lower_case\n", "f").is_err());
    assert!(shader_compiler::variants_of("// variants: A B C D E\n", "f").is_err());
    assert_eq!(shader_compiler::variants_of("// variants: A B\n", "f").unwrap(), ["A", "B"]);
    assert!(shader_compiler::variants_of("void main() {}\n", "f").unwrap().is_empty());
}
