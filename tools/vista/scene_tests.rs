//! Tests of the scene file reader (`scene.rs`).

use super::*;

fn parse(text: &str) -> Result<Scene> {
    let dir = std::env::temp_dir().join(format!("vista-scene-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let p = dir.join(format!("s{}.toml", text.len()));
    std::fs::write(&p, text)?;
    Scene::load(&p)
}

#[test]
fn material_rules_override_the_defaults_and_typos_fail() {
    let dir = std::env::temp_dir().join(format!("vista-scene-rules-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("s.toml");
    std::fs::write(&path, "[material_rules]\nsnow_line_m = 1200\nrock_slope_deg = 50\n").unwrap();
    let s = Scene::load(&path).unwrap();
    let expect = MaterialRules { snow_line_m: 1200.0, rock_slope_deg: 50.0, ..MaterialRules::default() };
    assert_eq!(s.material_rules, expect);
    std::fs::write(&path, "[material_rules]\nsnowline_m = 1200\n").unwrap();
    let e = format!("{:#}", Scene::load(&path).unwrap_err());
    assert!(e.contains("unknown field `snowline_m`") && e.lines().count() == 1, "{e}");
    std::fs::write(&path, "[material_rules]\nscree_slope_deg = 60\n").unwrap();
    let e = format!("{:#}", Scene::load(&path).unwrap_err());
    assert!(e.contains("scree_slope_deg (60) must not exceed rock_slope_deg (40)"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_stamp_without_blend_replaces() {
    let s = parse("[[stamps]]\nsource = \"a.png\"\ncenter = [1, 2]\nsize = 10\nheight = 5\n").unwrap();
    assert_eq!(s.stamps().unwrap()[0].placement.blend, StampBlend::Replace);
}

#[test]
fn assets_parse_move_by_the_origin_and_fail_in_one_line() {
    let s = parse("[[assets]]\nkind = \"rock\"\nat = [10, 20]\n[[assets]]\nkind = \"trunk\"\nat = [1, 2]\nscale = 2\nyaw_deg = 30\n")
        .unwrap();
    let a = s.assets([10.0, 0.0]).unwrap();
    assert_eq!((a[0].kind, a[0].at_m, a[0].scale), (AssetKind::Rock, [0.0, 20.0], 1.0));
    assert_eq!((a[1].kind, a[1].scale, a[1].yaw_deg), (AssetKind::Trunk, 2.0, 30.0));
    for (bad, want) in [
        ("[[assets]]\nkind = \"tree\"\nat = [0, 0]\n", "kind \"tree\" is not one of rock, trunk"),
        ("[[assets]]\nkind = \"rock\"\nat = [0, 0]\nscale = 0\n", "scale 0 is outside"),
    ] {
        let e = format!("{:#}", parse(bad).unwrap().assets([0.0; 2]).unwrap_err());
        assert!(e.contains(want) && !e.contains('\n'), "{e}");
    }
    assert!(
        format!("{:#}", parse("[[assets]]\nkind = \"rock\"\nat = [0, 0]\nsize = 2\n").unwrap_err()).contains("size")
    );
}

#[test]
fn decals_parse_share_textures_move_by_the_origin_and_fail_in_one_line() {
    let s = parse(
        "[[decals]]\ntexture = \"a.png\"\nquad = { center = [10, 20], size = [4, 2], rotation_deg = 30 }\n\
         [[decals]]\ntexture = \"b.png\"\nroad = { points = [[0, 0], [5, 5]], width = 2, repeat = 3 }\n\
         opacity = 0.5\nroughness = 0.2\n[[decals]]\ntexture = \"a.png\"\nquad = { center = [1, 1], size = [1, 1] }\n",
    )
    .unwrap();
    let d = s.decals([10.0, 0.0]).unwrap();
    assert_eq!(d.textures.len(), 2);
    assert_eq!(d.decals.iter().map(|d| d.texture).collect::<Vec<_>>(), [0, 1, 0]);
    assert!(matches!(&d.decals[0].shape, DecalShape::Quad { center_m, .. } if center_m.to_array() == [0.0, 20.0]));
    assert_eq!((d.decals[1].opacity, d.decals[1].roughness), (0.5, Some(0.2)));
    for bad in [
        "[[decals]]\ntexture = \"a.png\"\n",
        "[[decals]]\ntexture = \"a.png\"\nquad = { center = [0, 0], size = [0, 1] }\n",
        "[[decals]]\ntexture = \"a.png\"\nroad = { points = [[0, 0]], width = 1, repeat = 1 }\n",
        "[[decals]]\ntexture = \"a.png\"\nquad = { center = [0, 0], size = [1, 1] }\nopacity = 2\n",
    ] {
        let e = format!("{:#}", parse(bad).unwrap().decals([0.0; 2]).unwrap_err());
        assert!(e.contains("decal 1") && e.lines().count() == 1, "{e}");
    }
    let e = format!("{:#}", parse("[[decals]]\ntexture = \"a.png\"\nquad = { centre = [0, 0] }\n").unwrap_err());
    assert!(e.contains("centre") && e.lines().count() == 1, "{e}");
}

#[test]
fn parses_world_holes_effects() {
    let s = parse(
        "[world]\nsource = \"hm.png\"\nextent = [100, 50]\nheight_range = [0, 10]\n\
         [[holes]]\ncircle = [1, 2, 3]\n[[holes]]\npolygon = [[0,0],[1,0],[0,1]]\n[effects]\ncliffs = true\n",
    )
    .unwrap();
    assert!(matches!(&s.world.source, SceneSource::Path(p) if p.is_absolute() && p.ends_with("hm.png")));
    assert_eq!(s.world.extent.unwrap().xy(), [100.0, 50.0]);
    assert_eq!(s.holes().unwrap().len(), 2);
    assert!(s.effects.is_on(vista::render::Effect::Cliffs));
}

#[test]
fn errors_are_one_line() {
    for bad in ["[world\n", "[world]\nextents = 5\n", "[[holes]]\ncircle = [1, 2]\n", "[effects]\nholse = true\n"] {
        let e = format!("{:#}", parse(bad).err().unwrap());
        assert!(!e.contains('\n') && e.contains("scene file"), "{e}");
    }
    let s = parse("[[holes]]\ncircle = [1, 2, -3]\n").unwrap();
    assert!(s.holes().is_err());
}

/// Bad input fuzzing (stability case 9) of scene files: seeded byte
/// mutations and hostile tokens spliced into a valid scene. Each must
/// load (and give its holes or an error) or fail with a one-line error;
/// nothing may panic. `VISTA_FUZZ_CASES` sets the count (nightly runs).
#[test]
fn mutated_scenes_load_or_fail_with_one_line() {
    const VALID: &str = "[world]\nsource = \"procedural\"\nextent = [2048, 1024]\nheight_range = [0, 400]\n\
        spacing = 2\nlods = 4\nseed = 7\n[[holes]]\ncircle = [100, 200, 30]\n[[holes]]\n\
        polygon = [[0, 0], [10, 0], [0, 10]]\n[effects]\ncliffs = { slope_deg = 40, stochastic = false }\n\
        lighting = { sun_azimuth_deg = 200, clay_albedo = 0.5 }\nocclusion = false\n";
    const TOKENS: [&str; 16] = [
        "nan",
        "inf",
        "-1e999",
        "1e308",
        "[",
        "]",
        "{",
        "}",
        "\"",
        "=",
        "\u{e9}",
        "\u{1F4A5}",
        "\n[[holes]]\n",
        "polygon = []",
        "-",
        "\n[effects]\n",
    ];
    let cases = std::env::var("VISTA_FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(2000usize);
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = |n: usize| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state % n.max(1) as u64) as usize
    };
    let (mut loaded, mut rejected) = (0, 0);
    for case in 0..cases {
        let mut bytes = VALID.as_bytes().to_vec();
        for _ in 0..1 + next(3) {
            let at = next(bytes.len() + 1);
            match next(4) {
                0 => bytes.splice(at..at, TOKENS[next(TOKENS.len())].bytes()).for_each(drop),
                1 => bytes.truncate(at),
                2 => {
                    if let Some(b) = bytes.get_mut(at) {
                        *b ^= 1 << next(8);
                    }
                }
                _ => {
                    let end = (at + next(12)).min(bytes.len());
                    bytes.drain(at..end);
                }
            }
        }
        let dir = std::env::temp_dir().join(format!("vista-scene-fuzz-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("scene.toml");
        std::fs::write(&path, &bytes).unwrap();
        let outcome = std::panic::catch_unwind(|| Scene::load(&path).and_then(|s| s.holes().map(|_| ())));
        match outcome {
            Ok(Ok(())) => loaded += 1,
            Ok(Err(e)) => {
                let msg = format!("{e:#}");
                assert!(!msg.contains('\n'), "case {case}: not one line: {msg:?}");
                rejected += 1;
            }
            Err(_) => panic!("case {case} panicked on {:?}", String::from_utf8_lossy(&bytes)),
        }
    }
    assert!(loaded > 0 && rejected > 0, "{loaded} loaded, {rejected} rejected");
}
