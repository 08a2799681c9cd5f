//! The command line reads a GeoTIFF's extent and origin from its tags.

#[path = "../../../tests/geotiff_files/mod.rs"]
mod geotiff_files;
mod vista_cmd;

use geotiff_files::{heights, temp_dir, write_tiff, TAGS};
use tiff::encoder::colortype;

#[test]
fn the_command_line_takes_extent_and_origin_from_the_tags() {
    let dir = temp_dir("cli");
    let tif = dir.join("dem.tif");
    write_tiff::<colortype::Gray16>(&tif, 64, 48, &heights(64, 48), &TAGS);
    let out =
        vista_cmd::vista_cmd().args(["bake", "--dry-run", "--spacing", "5", "--heightmap"]).arg(&tif).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(text.contains("(1920 x 960 m, heights"), "{text}");
    // A hole given in map coordinates lands in the world (no "outside" note).
    let out = vista_cmd::vista_cmd()
        .args(["bake", "--dry-run", "--spacing", "5", "--hole-circle", "340100,5080500,20", "--heightmap"])
        .arg(&tif)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success() && !err.contains("outside the world"), "{err}");
    // No --spacing: the pixel size (30 x 20 m; the finer), which puts the
    // vertices on the posts, not the procedural world's 0.5 m; halved
    // twice, as the map's 960 m are under 128 quads of 20 m.
    let out = vista_cmd::vista_cmd().args(["bake", "--dry-run", "--heightmap"]).arg(&tif).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success() && text.contains("spacing 5 m"), "{text}{}", String::from_utf8_lossy(&out.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}
