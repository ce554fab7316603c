//! The demo's SVG: four panels (node 1 position, node 2 position in its
//! own units, node 1 velocity, node 1 following error) against time, each
//! panel's node's phases (homing, move, sine) shaded and named, and each
//! panel's legend in a column of its own, clear of the data. A demand is
//! drawn dashed and first, so the actual value stays visible over it; tick
//! labels carry no useless ".0".

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

/// A named stretch of the run of one node.
#[derive(Clone, Copy, Debug)]
pub struct Phase {
    /// Label.
    pub name: &'static str,
    /// The node (or slave) it is a phase of.
    pub node: u8,
    /// Start \[s\].
    pub start: f64,
    /// End \[s\].
    pub end: f64,
}

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Style {
    /// A measured value: a solid line, drawn over the demands.
    Actual,
    /// A set-point: dashed, drawn first.
    Demand,
}

/// One value of a sample to draw: legend, colour, style, value.
pub type Series = (&'static str, RGBColor, Style, fn(&Sample) -> f64);

/// One panel: the values of one node against time.
#[derive(Clone, Copy, Debug)]
pub struct Panel {
    /// Title.
    pub title: &'static str,
    /// Unit of the y axis.
    pub unit: &'static str,
    /// Whose phases are shaded.
    pub node: u8,
    /// The values drawn.
    pub series: &'static [Series],
}

const PANELS: [Panel; 4] = [
    Panel {
        title: "Node 1 (AKD) position",
        unit: "degrees",
        node: 1,
        series: &[
            ("demand (6064h + 60F4h)", RED, Style::Demand, |x| x.demand / 1000.0),
            ("actual 6064h", BLUE, Style::Actual, |x| x.position / 1000.0),
        ],
    },
    Panel {
        title: "Node 2 (DDS6) position",
        unit: "position units",
        node: 2,
        series: &[("actual 6064h", GREEN, Style::Actual, |x| x.position2)],
    },
    Panel {
        title: "Node 1 velocity",
        unit: "degrees/s",
        node: 1,
        series: &[("actual 606Ch", BLUE, Style::Actual, |x| x.velocity / 1000.0)],
    },
    Panel {
        title: "Node 1 following error",
        unit: "degrees",
        node: 1,
        series: &[("actual 60F4h", MAGENTA, Style::Actual, |x| x.following / 1000.0)],
    },
];

/// A tick label: as few digits as the value needs (`500`, `0.5`, `-1.25`),
/// never a trailing `.0`.
pub fn tick(v: f64) -> String {
    if !v.is_finite() {
        return v.to_string();
    }
    // Ticks are round numbers; 6 decimals hide float noise (0.30000000000000004).
    let s = format!("{v:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".to_owned() } else { s.to_owned() }
}

/// Demands first, then actual values: the later line is drawn on top.
fn draw_order(series: &[Series]) -> Vec<&Series> {
    let mut v: Vec<&Series> = series.iter().collect();
    v.sort_by_key(|s| s.2 != Style::Demand);
    v
}

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
    for (area, panel) in root.split_evenly((panels.len(), 1)).iter().zip(panels) {
        let (title, unit, series) = (panel.title, panel.unit, panel.series);
        // The legend column on the right: never over the data.
        let (chart_area, legend_area) = area.split_horizontally(900);
        let (lo, hi) = series.iter().fold((f64::MAX, f64::MIN), |(lo, hi), (_, _, _, f)| {
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
        // This node's phases first, under the curves; a phase keeps its
        // colour in every panel.
        for (k, p) in phases.iter().filter(|p| p.node == panel.node).enumerate() {
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
        chart
            .configure_mesh()
            .x_desc("time [s]")
            .y_desc(unit)
            .x_label_formatter(&|v| tick(*v))
            .y_label_formatter(&|v| tick(*v))
            .draw()
            .map_err(err)?;
        for (_, c, style, f) in draw_order(series) {
            let points = s.iter().map(|x| (x.t, f(x)));
            match style {
                Style::Demand => chart.draw_series(DashedLineSeries::new(points, 6, 4, c.stroke_width(1))),
                Style::Actual => chart.draw_series(LineSeries::new(points, c.stroke_width(2))),
            }
            .map_err(err)?;
        }
        for (k, (name, c, style, _)) in series.iter().enumerate() {
            let y = 40 + 22 * k as i32;
            let line = match style {
                Style::Demand => vec![(10, y), (20, y), (30, y), (40, y)],
                Style::Actual => vec![(10, y), (40, y)],
            };
            let width = if *style == Style::Demand { 1 } else { 2 };
            if *style == Style::Demand {
                for seg in line.chunks(2) {
                    legend_area
                        .draw(&PathElement::new(seg.to_vec(), ShapeStyle::from(c).stroke_width(width)))
                        .map_err(err)?;
                }
            } else {
                legend_area
                    .draw(&PathElement::new(line, ShapeStyle::from(c).stroke_width(width)))
                    .map_err(err)?;
            }
            legend_area.draw(&Text::new(*name, (48, y - 7), ("sans-serif", 14))).map_err(err)?;
        }
    }
    root.present().map_err(err)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_without_point_zero() {
        assert_eq!(tick(500.0), "500");
        assert_eq!(tick(0.0), "0");
        assert_eq!(tick(-0.0), "0");
        assert_eq!(tick(0.5), "0.5");
        assert_eq!(tick(-1.25), "-1.25");
        assert_eq!(tick(0.1 + 0.2), "0.3");
        assert_eq!(tick(14000.0), "14000");
    }

    /// The SVG of a small run: (panel's polylines in drawing order, text).
    fn svg(phases: &[Phase]) -> String {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.svg");
        let s: Vec<Sample> = (0..200)
            .map(|k| {
                let t = f64::from(k) / 100.0;
                Sample {
                    t,
                    demand: 1000.0 * t,
                    position: 990.0 * t,
                    position2: 500.0 * t,
                    ..Sample::default()
                }
            })
            .collect();
        plot(&path, &s, phases).unwrap();
        std::fs::read_to_string(path).unwrap()
    }

    #[test]
    fn demand_dashed_under_the_actual_value_and_round_ticks() {
        let text = svg(&[]);
        // The demand (red) is dashed: many short segments, all drawn before
        // the actual value's (blue) one polyline of the first panel.
        let red = "stroke=\"#FF0000\"";
        let blue = "stroke=\"#0000FF\"";
        let first_blue = text.find(blue).unwrap();
        let reds: Vec<usize> = text.match_indices(red).map(|(i, _)| i).collect();
        assert!(reds.len() > 10, "dashed demand: {} red paths", reds.len());
        // The legend's sample strokes come after the data.
        assert!(
            reds.iter().filter(|&&i| i < first_blue).count() > 10,
            "demand drawn before the actual value"
        );
        // No tick label ends in ".0".
        for label in text.split("</text>").filter_map(|t| t.rsplit('>').next()) {
            let label = label.trim();
            assert!(!(label.ends_with(".0") && label.parse::<f64>().is_ok()), "tick label `{label}`");
        }
    }

    #[test]
    fn each_panel_shades_its_own_nodes_phases() {
        let phases = [
            Phase { name: "homing", node: 1, start: 0.0, end: 1.0 },
            Phase { name: "homing", node: 2, start: 0.0, end: 0.1 },
            Phase { name: "move", node: 2, start: 0.1, end: 0.5 },
        ];
        let text = svg(&phases);
        let homing = PHASE_COLORS[0];
        let fill = |c: RGBColor| format!("fill=\"#{:02X}{:02X}{:02X}\"", c.0, c.1, c.2);
        // Node 1's three panels and node 2's one: four homing rectangles,
        // one "move" (node 2 only).
        assert_eq!(text.matches(&fill(homing)).count(), 4, "homing shaded once per panel");
        assert_eq!(text.matches(&fill(PHASE_COLORS[1])).count(), 1, "node 2's move only in its panel");
        assert_eq!(text.matches(">\nmove\n</text>").count(), 1);
    }
}
