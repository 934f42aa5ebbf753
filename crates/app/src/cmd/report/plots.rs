//! The report's plots, drawn with plotters into SVG strings (inlined in the
//! page): a case's coverage strip with its truth, its force traces, and the
//! trainee's rates over sessions. Text uses the experiments' embedded font.

use anyhow::{anyhow, Result};
use echothigh_exam::{BinState, CompressionEvent, CoverageBin};
use echothigh_records::{SessionRecord, TruthSegment};
use plotters::prelude::*;

/// The colour of a bin's state (also the page's legend).
pub fn state_colour(state: BinState) -> RGBColor {
    match state {
        BinState::Closed => RGBColor(46, 125, 50),
        BinState::NotClosed => RGBColor(198, 40, 40),
        BinState::InadequatePressure => RGBColor(249, 168, 37),
        BinState::NotExamined => RGBColor(210, 210, 210),
    }
}

/// The colour of a thrombus piece of the truth.
pub fn truth_colour(kind: &str) -> RGBColor {
    if kind == "chronic" {
        RGBColor(106, 27, 154)
    } else {
        RGBColor(40, 40, 40)
    }
}

fn err<E: std::fmt::Display>(e: E) -> anyhow::Error {
    anyhow!("drawing a plot: {e}")
}

/// Per vein, one row of 2 cm bins coloured by state, and above it the
/// truth's thrombus pieces (normal pieces are not drawn). x: cm below the
/// inguinal ligament.
pub fn coverage_strip(bins: &[CoverageBin], truth: &[TruthSegment]) -> Result<String> {
    echothigh_experiments::plot::register_font();
    let mut veins: Vec<&str> = Vec::new();
    for v in bins
        .iter()
        .map(|b| b.vein.as_str())
        .chain(truth.iter().map(|t| t.vein.as_str()))
    {
        if !veins.contains(&v) {
            veins.push(v);
        }
    }
    let s_max = bins
        .iter()
        .map(|b| b.s_end)
        .chain(truth.iter().map(|t| t.s_end))
        .fold(0.02, f64::max)
        * 100.0;
    let rows = veins.len().max(1) as f64;
    let height = 60 + 34 * veins.len().max(1) as u32;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (860, height)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let mut chart = ChartBuilder::on(&root)
            .margin(8)
            .x_label_area_size(36)
            .build_cartesian_2d(-6.0..s_max, rows..0.0)
            .map_err(err)?;
        chart
            .configure_mesh()
            .disable_y_mesh()
            .disable_y_axis()
            .x_desc("s below the inguinal ligament (cm)")
            .x_label_formatter(&|x| {
                if *x < 0.0 {
                    String::new()
                } else {
                    format!("{x:.0}")
                }
            })
            .draw()
            .map_err(err)?;
        for (i, vein) in veins.iter().enumerate() {
            let y = i as f64;
            chart
                .draw_series(std::iter::once(Text::new(
                    vein.to_string(),
                    (-5.5, y + 0.35),
                    ("sans-serif", 15).into_font(),
                )))
                .map_err(err)?;
            chart
                .draw_series(bins.iter().filter(|b| b.vein == *vein).map(|b| {
                    Rectangle::new(
                        [(b.s_start * 100.0, y + 0.35), (b.s_end * 100.0, y + 0.9)],
                        state_colour(b.state).filled(),
                    )
                }))
                .map_err(err)?;
            chart
                .draw_series(
                    truth
                        .iter()
                        .filter(|t| t.vein == *vein && t.kind != "normal")
                        .map(|t| {
                            Rectangle::new(
                                [(t.s_start * 100.0, y + 0.1), (t.s_end * 100.0, y + 0.28)],
                                truth_colour(&t.kind).filled(),
                            )
                        }),
                )
                .map_err(err)?;
        }
        root.present().map_err(err)?;
    }
    Ok(svg)
}

/// Each press's force over time from its start (s, N), one line per press.
pub fn force_traces(events: &[CompressionEvent]) -> Result<String> {
    echothigh_experiments::plot::register_font();
    let t_max = events
        .iter()
        .flat_map(|e| e.force_trace.iter().map(move |p| p[0] - e.t_start))
        .fold(0.1, f64::max);
    let f_max = events
        .iter()
        .flat_map(|e| e.force_trace.iter().map(|p| p[1]))
        .fold(1.0, f64::max)
        * 1.1;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (860, 320)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let mut chart = ChartBuilder::on(&root)
            .margin(10)
            .x_label_area_size(36)
            .y_label_area_size(50)
            .build_cartesian_2d(0.0..t_max, 0.0..f_max)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("time from the start of the press (s)")
            .y_desc("probe force (N)")
            .draw()
            .map_err(err)?;
        for (k, e) in events.iter().enumerate() {
            let colour = Palette99::pick(k).to_rgba();
            let label = format!(
                "{} {} at {:.1} cm",
                k + 1,
                e.vein.as_deref().unwrap_or("no vein"),
                e.s * 100.0
            );
            chart
                .draw_series(LineSeries::new(
                    e.force_trace.iter().map(|p| (p[0] - e.t_start, p[1])),
                    colour.stroke_width(2),
                ))
                .map_err(err)?
                .label(label)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2))
                });
        }
        if !events.is_empty() {
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .draw()
                .map_err(err)?;
        }
        root.present().map_err(err)?;
    }
    Ok(svg)
}

/// One of a session's rates.
type Rate = fn(&SessionRecord) -> Option<f64>;

/// Sensitivity, specificity, coverage and calls correct (%) per session,
/// sessions numbered from 1 (a session without the value has no point).
pub fn trend(sessions: &[SessionRecord]) -> Result<String> {
    echothigh_experiments::plot::register_font();
    let n = sessions.len().max(1) as f64;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (860, 340)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let mut chart = ChartBuilder::on(&root)
            .margin(10)
            .x_label_area_size(36)
            .y_label_area_size(50)
            .build_cartesian_2d(0.5..n + 0.5, 0.0..105.0)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("session")
            .y_desc("%")
            .x_labels(sessions.len().clamp(1, 20))
            .x_label_formatter(&|x| format!("{x:.0}"))
            .draw()
            .map_err(err)?;
        let series: [(&str, RGBColor, Rate); 4] = [
            ("sensitivity", RGBColor(198, 40, 40), |s| {
                s.rates.sensitivity
            }),
            ("specificity", RGBColor(21, 101, 192), |s| {
                s.rates.specificity
            }),
            ("coverage", RGBColor(46, 125, 50), |s| s.rates.mean_coverage),
            ("calls correct", RGBColor(120, 120, 120), |s| {
                s.rates.calls_correct
            }),
        ];
        for (name, colour, value) in series {
            let pts: Vec<(f64, f64)> = sessions
                .iter()
                .enumerate()
                .filter_map(|(i, s)| value(s).map(|v| (i as f64 + 1.0, v * 100.0)))
                .collect();
            chart
                .draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))
                .map_err(err)?
                .label(name)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2))
                });
            chart
                .draw_series(pts.into_iter().map(|p| Circle::new(p, 4, colour.filled())))
                .map_err(err)?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(err)?;
        root.present().map_err(err)?;
    }
    Ok(svg)
}
