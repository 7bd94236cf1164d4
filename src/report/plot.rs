//! The report's plot: relMSE against wall time, both axes logarithmic, one curve per engine and
//! Accel (Embree solid with dots, the BVH lighter with crosses).

use std::path::Path;

use plotters::prelude::*;
use plotters::style::FontStyle;

use super::Report;
use crate::engines::EngineKind;
use crate::output::{write_atomically, OutputError};

const SIZE: (u32, u32) = (900, 600);

/// Fonts tried, in order, for the plot's labels (plotters draws text with a font it is
/// given; Debian's `fonts-dejavu-core` provides the first).
const FONT_FILES: [&str; 3] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/usr/share/fonts/truetype/freefont/FreeSans.ttf",
];

/// Registers the first font found as plotters' "sans-serif", once.
fn register_font() -> Result<(), String> {
    static REGISTERED: std::sync::OnceLock<Result<(), String>> = std::sync::OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            let bytes = FONT_FILES
                .iter()
                .find_map(|f| std::fs::read(f).ok())
                .ok_or_else(|| {
                    format!(
                        "no font for the plot's labels (looked for {}); install fonts-dejavu-core",
                        FONT_FILES.join(", ")
                    )
                })?;
            // plotters keeps the font for the life of the program.
            let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
            plotters::style::register_font("sans-serif", FontStyle::Normal, bytes)
                .map_err(|_| "the plot's font could not be read".to_string())
        })
        .clone()
}

fn colour(engine: EngineKind) -> RGBColor {
    let (r, g, b) = crate::engines::engine(engine).colour();
    RGBColor(r, g, b)
}

/// Writes the plot as PNG (atomically).
pub fn write(path: &Path, report: &Report) -> Result<(), String> {
    register_font()?;
    let mut buffer = vec![255u8; (SIZE.0 * SIZE.1 * 3) as usize];
    draw(&mut buffer, report).map_err(|e| format!("{}: drawing the plot: {e}", path.display()))?;
    let image = image::RgbImage::from_raw(SIZE.0, SIZE.1, buffer)
        .ok_or("the plot's buffer has the wrong size")?;
    write_atomically(path, |w| {
        image
            .write_to(w, image::ImageFormat::Png)
            .map_err(|e| OutputError::Io {
                path: path.to_path_buf(),
                source: std::io::Error::other(e),
            })
    })
    .map_err(|e| e.to_string())
}

fn draw<'a>(buffer: &'a mut [u8], report: &Report) -> Result<(), Box<dyn std::error::Error + 'a>> {
    let root = BitMapBackend::with_buffer(buffer, SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    let points = report.series.iter().flat_map(|s| s.points.iter());
    let (mut t0, mut t1, mut e0, mut e1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for p in points.filter(|p| p.1 > 0.0 && p.2 > 0.0) {
        (t0, t1, e0, e1) = (t0.min(p.1), t1.max(p.1), e0.min(p.2), e1.max(p.2));
    }
    if t0 > t1 {
        (t0, t1, e0, e1) = (0.01, 1.0, 1e-3, 1.0);
    }
    let name = report
        .scene
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!("{name}: error against time"),
            ("sans-serif", 24).into_font(),
        )
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(
            (t0 / 1.5..t1 * 1.5).log_scale(),
            (e0 / 1.5..e1 * 1.5).log_scale(),
        )?;
    chart
        .configure_mesh()
        .x_desc("wall time (s)")
        .y_desc("relMSE against the reference")
        .x_label_formatter(&|v| format!("{v:.0e}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()?;
    for s in &report.series {
        let bvh = s.accel == crate::accel::AccelKind::Bvh;
        let base = colour(s.engine);
        let c = if bvh { base.mix(0.45) } else { base.mix(1.0) };
        let xy: Vec<(f64, f64)> = s
            .points
            .iter()
            .filter(|p| p.1 > 0.0 && p.2 > 0.0)
            .map(|p| (p.1, p.2))
            .collect();
        let slope = s.slope.map_or(String::new(), |v| format!(", slope {v:.2}"));
        chart
            .draw_series(LineSeries::new(xy.clone(), c.stroke_width(2)))?
            .label(format!("{} ({}){slope}", s.engine.name(), s.accel))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2)));
        if bvh {
            chart.draw_series(xy.iter().map(|&p| Cross::new(p, 5, c.stroke_width(2))))?;
        } else {
            chart.draw_series(xy.iter().map(|&p| Circle::new(p, 4, c.filled())))?;
        }
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 15))
        .draw()?;
    root.present()?;
    Ok(())
}
