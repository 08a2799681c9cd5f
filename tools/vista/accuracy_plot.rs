//! The Pareto plot of `vista bench accuracy`: one panel per view, GPU time
//! against the measured LOD error (p99 of the drawn surface's projected
//! vertical distance to the finest surface, px: what the target bounds), a
//! curve per setting family with its points labelled by target (px), the
//! shading settings as labelled marks.

use anyhow::{anyhow, Result};
use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};
use std::path::Path;
use vista::bench::{AccuracyBench, AccuracyPoint};

const SIZE: (u32, u32) = (1400, 1000);

/// The geometry rows' families, a curve each: both rules, culling on and off.
const FAMILIES: &[(&str, RGBColor)] = &[
    ("culling on", BLUE),
    ("culling off", RED),
    ("culling on per triangle", RGBColor(230, 140, 0)),
    ("culling off per triangle", RGBColor(150, 60, 170)),
];

/// Short marks for the shading settings, in the bench's order.
fn shading_mark(setting: &str) -> &'static str {
    match setting {
        "tiled, stochastic cliffs" => "T",
        "tiled, blended cliffs" => "TB",
        "tiled, near/far thresholds x0.5" => "T/2",
        "tiled, near/far thresholds x2" => "Tx2",
        "every flavour, stochastic cliffs" => "E",
        "every flavour, blended cliffs" => "EB",
        _ => "?",
    }
}

pub fn pareto_plot(b: &AccuracyBench, title: &str, path: &Path) -> Result<()> {
    // Registering twice (a second plot in one process) only replaces the font.
    register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular())
        .map_err(|_| anyhow!("the embedded plot font did not load"))?;
    let (w, h) = SIZE;
    let mut buf = vec![255u8; (w * h * 3) as usize];
    draw(b, title, &mut buf).map_err(|e| anyhow!("drawing the plot: {e}"))?;
    Ok(vista::output::write_png(path, &buf, [w, h], image::ExtendedColorType::Rgb8)?)
}

/// A view's points that the panel draws. Only these set the axes: a
/// family left out would leave an empty stretch of the panel.
fn drawn_points<'a>(b: &'a AccuracyBench, view: &str) -> Vec<&'a AccuracyPoint> {
    let drawn = |family: &str| family == "shading" || FAMILIES.iter().any(|f| f.0 == family);
    b.points.iter().filter(|p| p.view == view && drawn(&p.family)).collect()
}

fn draw(b: &AccuracyBench, title: &str, buf: &mut [u8]) -> Result<(), Box<dyn std::error::Error>> {
    let root = BitMapBackend::with_buffer(buf, SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    let root =
        root.titled(&format!("{title}: GPU time vs measured LOD error (labels: target px)"), ("sans-serif", 22))?;
    let views: Vec<&str> = b.references.iter().map(|r| r.view.as_str()).collect();
    let cols = if views.len() > 1 { 2 } else { 1 };
    let rows = views.len().div_ceil(cols).max(1);
    let panels = root.split_evenly((rows, cols));
    for (panel, view) in panels.iter().zip(&views) {
        let pts = drawn_points(b, view);
        let xs = pts.iter().map(|p| p.gpu_ms);
        let ys = pts.iter().map(|p| p.error.lod_px_p99);
        let (x0, x1) = (xs.clone().fold(f64::MAX, f64::min), xs.fold(0.0, f64::max));
        let (y0, y1) = (ys.clone().fold(f64::MAX, f64::min), ys.fold(0.0, f64::max));
        let (dx, dy) = (((x1 - x0) * 0.1).max(1e-3), ((y1 - y0) * 0.15).max(1e-4));
        // Room above the points for the legend.
        let top = y1 + 3.0 * dy;
        let mut chart = ChartBuilder::on(panel)
            .caption(format!("view \"{view}\""), ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d((x0 - dx).max(0.0)..x1 + dx, (y0 - dy).max(0.0)..top)?;
        chart
            .configure_mesh()
            .x_desc("GPU ms per frame (sum of pass medians)")
            .y_desc("LOD error p99 (px)")
            .label_style(("sans-serif", 13))
            .max_light_lines(1)
            .draw()?;
        for &(family, colour) in FAMILIES {
            let mut line: Vec<(f64, f64, f32)> = pts
                .iter()
                .filter(|p| p.family == family)
                .map(|p| (p.gpu_ms, p.error.lod_px_p99, p.target_error_px))
                .collect();
            line.sort_by(|a, b| a.2.total_cmp(&b.2));
            if line.is_empty() {
                continue;
            }
            chart
                .draw_series(LineSeries::new(line.iter().map(|&(x, y, _)| (x, y)), colour.stroke_width(2)))?
                .label(family)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)));
            chart.draw_series(line.iter().map(|&(x, y, t)| {
                EmptyElement::at((x, y))
                    + Circle::new((0, 0), 4, colour.filled())
                    + Text::new(format!("{t}"), (6, -16), ("sans-serif", 14).into_font())
            }))?;
        }
        let shading: Vec<&&AccuracyPoint> = pts.iter().filter(|p| p.family == "shading").collect();
        if !shading.is_empty() {
            let t = shading[0].target_error_px;
            chart
                .draw_series(
                    shading.iter().map(|p| TriangleMarker::new((p.gpu_ms, p.error.lod_px_p99), 6, GREEN.filled())),
                )?
                .label(format!("shading at {t} px: T tiled, B blended cliffs, E every flavour, /2 x2 thresholds"))
                .legend(|(x, y)| TriangleMarker::new((x + 10, y), 6, GREEN.filled()));
            chart.draw_series(shading.iter().map(|p| {
                EmptyElement::at((p.gpu_ms, p.error.lod_px_p99))
                    + Text::new(shading_mark(&p.setting), (7, 4), ("sans-serif", 13).into_font())
            }))?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()?;
    }
    root.present()?;
    Ok(())
}
