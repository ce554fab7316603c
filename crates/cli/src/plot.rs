//! The demo's SVG: four panels (node 1 position, node 2 position in its
//! own units, node 1 velocity, node 1 following error) against time, the
//! phases (homing, move, sine) shaded and named in every panel, and each
//! panel's legend in a column of its own, clear of the data.

use anyhow::{anyhow, bail};
use plotters::prelude::*;

/// One 1 ms sample, from the TPDOs.
#[derive(Clone, Copy, Debug, Default)]
pub struct Sample {
    /// Seconds since the nodes were started.
    pub t: f64,
    /// Node 1 position demand \[m°\]: 6064h + 60F4h (the AKD has no 6062h).
    pub demand: f64,
    /// Node 1 6064h position actual value \[m°\].
    pub position: f64,
    /// Node 1 606Ch velocity actual value \[m°/s\].
    pub velocity: f64,
    /// Node 1 60F4h following error actual value \[m°\].
    pub following: f64,
    /// Node 2 6064h position actual value \[its position units\].
    pub position2: f64,
}

/// A named stretch of the run.
#[derive(Clone, Copy, Debug)]
pub struct Phase {
    /// Label.
    pub name: &'static str,
    /// Start \[s\].
    pub start: f64,
    /// End \[s\].
    pub end: f64,
}

/// One value of a sample to draw: legend, colour, value.
pub type Series = (&'static str, RGBColor, fn(&Sample) -> f64);

/// One panel: title, unit of the y axis, the values drawn.
pub type Panel = (&'static str, &'static str, &'static [Series]);

const PANELS: [Panel; 4] = [
    (
        "Node 1 (AKD) position",
        "degrees",
        &[
            ("actual 6064h", BLUE, |x| x.position / 1000.0),
            ("demand (6064h + 60F4h)", RED, |x| x.demand / 1000.0),
        ],
    ),
    ("Node 2 (DDS6) position", "position units", &[("actual 6064h", GREEN, |x| x.position2)]),
    ("Node 1 velocity", "degrees/s", &[("actual 606Ch", BLUE, |x| x.velocity / 1000.0)]),
    ("Node 1 following error", "degrees", &[("actual 60F4h", MAGENTA, |x| x.following / 1000.0)]),
];

const PHASE_COLORS: [RGBColor; 3] =
    [RGBColor(255, 236, 179), RGBColor(200, 230, 201), RGBColor(187, 222, 251)];

fn err(e: impl std::fmt::Display) -> anyhow::Error {
    anyhow!("{e}")
}

/// Writes the CAN demo's SVG to `path`.
pub fn plot(path: &std::path::Path, s: &[Sample], phases: &[Phase]) -> anyhow::Result<()> {
    plot_panels(path, s, phases, &PANELS)
}

/// Writes an SVG of `panels`, one above the other, to `path`.
pub fn plot_panels(
    path: &std::path::Path,
    s: &[Sample],
    phases: &[Phase],
    panels: &[Panel],
) -> anyhow::Result<()> {
    if s.is_empty() {
        bail!("no samples to plot");
    }
    let root = SVGBackend::new(path, (1100, 275 * panels.len().max(1) as u32)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let t_end = s.last().map_or(1.0, |x| x.t).max(0.001);
    for (area, &(title, unit, series)) in root.split_evenly((panels.len(), 1)).iter().zip(panels) {
        // The legend column on the right: never over the data.
        let (chart_area, legend_area) = area.split_horizontally(900);
        let (lo, hi) = series.iter().fold((f64::MAX, f64::MIN), |(lo, hi), (_, _, f)| {
            s.iter().map(f).fold((lo, hi), |(a, b), v| (a.min(v), b.max(v)))
        });
        let pad = ((hi - lo) * 0.08).max(1e-3);
        let (lo, hi) = (lo - pad, hi + pad * 2.0);
        let mut chart = ChartBuilder::on(&chart_area)
            .caption(title, ("sans-serif", 18))
            .margin(8)
            .x_label_area_size(30)
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..t_end, lo..hi)
            .map_err(err)?;
        // Phases first, under the curves.
        for (k, p) in phases.iter().enumerate() {
            let c = PHASE_COLORS[k % PHASE_COLORS.len()];
            chart
                .draw_series(std::iter::once(Rectangle::new([(p.start, lo), (p.end, hi)], c.filled())))
                .map_err(err)?;
            chart
                .draw_series(std::iter::once(Text::new(
                    p.name.to_owned(),
                    (p.start, hi - pad * 0.2),
                    ("sans-serif", 13).into_font().color(&BLACK),
                )))
                .map_err(err)?;
        }
        chart.configure_mesh().x_desc("time [s]").y_desc(unit).draw().map_err(err)?;
        for (_, c, f) in series {
            chart.draw_series(LineSeries::new(s.iter().map(|x| (x.t, f(x))), *c)).map_err(err)?;
        }
        for (k, (name, c, _)) in series.iter().enumerate() {
            let y = 40 + 22 * k as i32;
            legend_area
                .draw(&PathElement::new(vec![(10, y), (40, y)], ShapeStyle::from(c).stroke_width(2)))
                .map_err(err)?;
            legend_area.draw(&Text::new(*name, (48, y - 7), ("sans-serif", 14))).map_err(err)?;
        }
    }
    root.present().map_err(err)?;
    Ok(())
}
