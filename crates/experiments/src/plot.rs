//! Line plots written as PNG and SVG (plotters, with an embedded DejaVu Sans
//! font so that a fresh machine needs no system fonts).
//!
//! A [`Figure`] is a column of [`Panel`]s; each panel has labelled axes (the
//! caller puts units in the labels) and any number of named [`Series`].

use anyhow::{Context, Result};
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

static FONT: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

/// Registers the embedded DejaVu Sans as `sans-serif` (once; any crate
/// drawing text with plotters calls it first).
pub fn register_font() {
    REGISTER.call_once(|| {
        // The only failure is a malformed font, which is embedded and tested.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// One named curve.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend label.
    pub name: String,
    /// (x, y) points in the panel's units.
    pub points: Vec<(f64, f64)>,
    /// RGB colour.
    pub color: (u8, u8, u8),
    /// Draw dashed (true) or solid.
    pub dashed: bool,
    /// Draw markers instead of a line.
    pub markers: bool,
}

impl Series {
    /// A solid line.
    pub fn line(name: impl Into<String>, points: Vec<(f64, f64)>, color: (u8, u8, u8)) -> Self {
        Self {
            name: name.into(),
            points,
            color,
            dashed: false,
            markers: false,
        }
    }
    /// A dashed line.
    pub fn dashed(mut self) -> Self {
        self.dashed = true;
        self
    }
    /// Markers only.
    pub fn with_markers(mut self) -> Self {
        self.markers = true;
        self
    }
}

/// One set of axes.
#[derive(Debug, Clone, Default)]
pub struct Panel {
    /// Title above the axes.
    pub title: String,
    /// X axis label, with unit.
    pub x_label: String,
    /// Y axis label, with unit.
    pub y_label: String,
    /// Curves.
    pub series: Vec<Series>,
    /// Fixed x range, or `None` to fit the data.
    pub x_range: Option<(f64, f64)>,
    /// Fixed y range, or `None` to fit the data.
    pub y_range: Option<(f64, f64)>,
}

/// A column of panels.
#[derive(Debug, Clone, Default)]
pub struct Figure {
    /// Panels from top to bottom.
    pub panels: Vec<Panel>,
    /// Width in pixels.
    pub width: u32,
    /// Height of each panel in pixels.
    pub panel_height: u32,
}

/// Standard colours for up to six series.
pub const PALETTE: [(u8, u8, u8); 6] = [
    (31, 119, 180),
    (214, 39, 40),
    (44, 160, 44),
    (148, 103, 189),
    (255, 127, 14),
    (23, 190, 207),
];

impl Figure {
    /// A figure of the given panels, 1000 px wide and 360 px per panel.
    pub fn new(panels: Vec<Panel>) -> Self {
        Self {
            panels,
            width: 1000,
            panel_height: 360,
        }
    }

    /// Writes the figure as a PNG.
    pub fn save_png(&self, path: &Path) -> Result<()> {
        register_font();
        let h = self.panel_height * self.panels.len().max(1) as u32;
        let root = BitMapBackend::new(path, (self.width, h)).into_drawing_area();
        self.draw(&root)
            .with_context(|| format!("drawing {}", path.display()))?;
        root.present()
            .with_context(|| format!("writing {}", path.display()))?;
        Ok(())
    }

    /// Writes the figure as an SVG.
    pub fn save_svg(&self, path: &Path) -> Result<()> {
        register_font();
        let h = self.panel_height * self.panels.len().max(1) as u32;
        let root = SVGBackend::new(path, (self.width, h)).into_drawing_area();
        self.draw(&root)
            .with_context(|| format!("drawing {}", path.display()))?;
        root.present()
            .with_context(|| format!("writing {}", path.display()))?;
        Ok(())
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, plotters::coord::Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE).map_err(|e| anyhow::anyhow!("{e:?}"))?;
        let areas = root.split_evenly((self.panels.len().max(1), 1));
        for (panel, area) in self.panels.iter().zip(areas.iter()) {
            draw_panel(panel, area).map_err(|e| anyhow::anyhow!("{e:?}"))?;
        }
        Ok(())
    }
}

fn range_of(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    if hi - lo < 1e-12 {
        return (lo - 0.5, hi + 0.5);
    }
    let pad = 0.05 * (hi - lo);
    (lo - pad, hi + pad)
}

fn draw_panel<DB: DrawingBackend>(
    panel: &Panel,
    area: &DrawingArea<DB, plotters::coord::Shift>,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let xr = panel.x_range.unwrap_or_else(|| {
        range_of(
            panel
                .series
                .iter()
                .flat_map(|s| s.points.iter().map(|p| p.0)),
        )
    });
    let yr = panel.y_range.unwrap_or_else(|| {
        range_of(
            panel
                .series
                .iter()
                .flat_map(|s| s.points.iter().map(|p| p.1)),
        )
    });
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)?;
    chart
        .configure_mesh()
        .x_desc(&panel.x_label)
        .y_desc(&panel.y_label)
        .label_style(("sans-serif", 14))
        .draw()?;
    for s in &panel.series {
        let color = RGBColor(s.color.0, s.color.1, s.color.2);
        let pts = s
            .points
            .iter()
            .copied()
            .filter(|p| p.0.is_finite() && p.1.is_finite());
        let anno = if s.markers {
            chart.draw_series(pts.map(|p| Circle::new(p, 3, color.filled())))?
        } else if s.dashed {
            chart.draw_series(DashedLineSeries::new(pts, 6, 4, color.stroke_width(2)))?
        } else {
            chart.draw_series(LineSeries::new(pts, color.stroke_width(2)))?
        };
        anno.label(s.name.clone()).legend(move |(x, y)| {
            PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
        });
    }
    if panel.series.iter().any(|s| !s.name.is_empty()) {
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()?;
    }
    Ok(())
}

/// Writes the force magnitude over time as a PNG: the rendered force and the
/// physics' own contact force.
pub fn plot_force(
    path: &std::path::Path,
    mode: &str,
    ticks: &[echothigh_runtime::trace::TickRecord],
    physics: &[echothigh_runtime::trace::PhysicsRecord],
) -> Result<()> {
    let f = echothigh_runtime::trace::force_magnitudes(ticks);
    let rendered: Vec<(f64, f64)> = ticks.iter().zip(&f).map(|(r, f)| (r.t, *f)).collect();
    let phys: Vec<(f64, f64)> = physics
        .iter()
        .map(|r| {
            (
                r.t,
                (r.force[0].powi(2) + r.force[1].powi(2) + r.force[2].powi(2)).sqrt(),
            )
        })
        .collect();
    let fig = Figure::new(vec![Panel {
        title: format!("Force magnitude ({mode} coupling)"),
        x_label: "time (s)".into(),
        y_label: "force (N, tissue)".into(),
        series: vec![
            Series::line("rendered (1 kHz)", rendered, PALETTE[0]),
            Series::line("physics contact force", phys, PALETTE[1]).dashed(),
        ],
        ..Default::default()
    }]);
    fig.save_png(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The embedded font renders text: a figure with a title and labels
    /// produces a PNG whose pixels are not all white.
    #[test]
    fn png_has_ink() {
        let dir = std::env::temp_dir().join(format!("echothigh-plot-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("t.png");
        let pts: Vec<(f64, f64)> = (0..100)
            .map(|i| (i as f64, (i as f64 * 0.1).sin()))
            .collect();
        let fig = Figure::new(vec![Panel {
            title: "sine".into(),
            x_label: "t (s)".into(),
            y_label: "f (N)".into(),
            series: vec![Series::line("sin", pts, PALETTE[0])],
            ..Default::default()
        }]);
        fig.save_png(&path).unwrap();
        let decoder = png::Decoder::new(std::fs::File::open(&path).unwrap());
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).unwrap();
        let dark = buf[..info.buffer_size()]
            .iter()
            .filter(|&&b| b < 128)
            .count();
        assert!(dark > 1000, "only {dark} dark bytes");
        std::fs::remove_dir_all(&dir).ok();
    }
}
