//! `plot.png` of one episode: (1) x and y against the reference, (2) stiffness, (3) contact
//! forces (true and measured), (4) the x-y path with the wall, the hole channel and the
//! reference path.
//!
//! Text is rendered with the embedded DejaVu Sans ([`crate::font`]), so no system font library
//! is needed.

use super::params::ArmConfig;
use super::trace::TickRecord;
use crate::font::ensure_font;
use crate::EnvError;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

fn plot_err(path: &Path, e: impl std::fmt::Display) -> EnvError {
    EnvError::Output {
        path: path.display().to_string(),
        message: e.to_string(),
    }
}

const X_COLOR: RGBColor = RGBColor(31, 119, 180);
const Y_COLOR: RGBColor = RGBColor(214, 39, 40);
/// An opaque colour between `c` and white.
fn lighten(c: RGBColor, f: f64) -> RGBColor {
    let l = |v: u8| (v as f64 + (255.0 - v as f64) * f).round() as u8;
    RGBColor(l(c.0), l(c.1), l(c.2))
}

const WALL: RGBColor = RGBColor(90, 90, 90);

/// Every n-th record so at most ~4000 points are drawn per series.
fn thin(trace: &[TickRecord]) -> Vec<&TickRecord> {
    let step = (trace.len() / 4000).max(1);
    trace.iter().step_by(step).collect()
}

fn range(vals: impl Iterator<Item = f64>, pad: f64) -> (f64, f64) {
    let (lo, hi) = vals.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let span = (hi - lo).max(1e-9);
    (lo - pad * span, hi + pad * span)
}

/// Draws the four panels into a 1400×1000 PNG at `path`.
pub fn plot_episode(path: &Path, trace: &[TickRecord], cfg: &ArmConfig) -> Result<(), EnvError> {
    ensure_font();
    let root = BitMapBackend::new(path, (1400, 1000)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
    let panels = root.split_evenly((2, 2));
    let pts = thin(trace);
    let t_end = trace.last().map(|r| r.t).unwrap_or(1.0).max(1e-3);
    draw_positions(&panels[0], &pts, t_end).map_err(|e| plot_err(path, e))?;
    draw_stiffness(&panels[1], &pts, t_end).map_err(|e| plot_err(path, e))?;
    draw_forces(&panels[2], &pts, t_end).map_err(|e| plot_err(path, e))?;
    draw_path(&panels[3], &pts, cfg).map_err(|e| plot_err(path, e))?;
    root.present().map_err(|e| plot_err(path, e))
}

type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;
type Cart = Cartesian2d<RangedCoordf64, RangedCoordf64>;
type Chart<'a, 'b> = ChartContext<'a, BitMapBackend<'b>, Cart>;
type DrawResult = Result<(), Box<dyn std::error::Error>>;

fn chart<'a, 'b>(
    area: &'a Area<'b>,
    title: &str,
    x: (f64, f64),
    y: (f64, f64),
) -> Result<Chart<'a, 'b>, Box<dyn std::error::Error>> {
    Ok(ChartBuilder::on(area)
        .caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(64)
        .build_cartesian_2d(x.0..x.1, y.0..y.1)?)
}

fn legend<'a, 'b: 'a>(c: &mut Chart<'a, 'b>, pos: SeriesLabelPosition) -> DrawResult {
    c.configure_series_labels()
        .position(pos)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.4))
        .label_font(("sans-serif", 15))
        .draw()?;
    Ok(())
}

fn draw_positions(area: &Area, pts: &[&TickRecord], t_end: f64) -> DrawResult {
    let y = range(
        pts.iter()
            .flat_map(|r| [r.x[0], r.x[1], r.x_ref[0], r.x_ref[1]]),
        0.05,
    );
    let mut c = chart(area, "TCP position vs reference", (0.0, t_end), y)?;
    c.configure_mesh()
        .x_desc("t [s]")
        .y_desc("position [m]")
        .label_style(("sans-serif", 15))
        .light_line_style(BLACK.mix(0.05))
        .draw()?;
    for (i, (name, color)) in [("x", X_COLOR), ("y", Y_COLOR)].into_iter().enumerate() {
        c.draw_series(LineSeries::new(
            pts.iter().map(|r| (r.t, r.x[i])),
            color.stroke_width(2),
        ))?
        .label(name)
        .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], color.stroke_width(2)));
        let dashed = DashedLineSeries::new(
            pts.iter().map(|r| (r.t, r.x_ref[i])),
            6,
            4,
            color.mix(0.6).stroke_width(2),
        );
        c.draw_series(dashed)?
            .label(format!("{name}_v (reference)"))
            .legend(move |(x, y)| {
                PathElement::new([(x, y), (x + 20, y)], color.mix(0.6).stroke_width(1))
            });
    }
    legend(&mut c, SeriesLabelPosition::MiddleRight)
}

fn draw_stiffness(area: &Area, pts: &[&TickRecord], t_end: f64) -> DrawResult {
    let (_, hi) = range(pts.iter().flat_map(|r| r.k), 0.0);
    let mut c = chart(
        area,
        "stiffness (action)",
        (0.0, t_end),
        (0.0, hi * 1.1 + 1.0),
    )?;
    c.configure_mesh()
        .x_desc("t [s]")
        .y_desc("k [N/m]")
        .label_style(("sans-serif", 15))
        .light_line_style(BLACK.mix(0.05))
        .draw()?;
    for (i, (name, color, w)) in [("k_x", X_COLOR, 4), ("k_y", Y_COLOR, 2)]
        .into_iter()
        .enumerate()
    {
        c.draw_series(LineSeries::new(
            pts.iter().map(|r| (r.t, r.k[i])),
            color.stroke_width(w),
        ))?
        .label(name)
        .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], color.stroke_width(2)));
    }
    legend(&mut c, SeriesLabelPosition::LowerRight)
}

fn draw_forces(area: &Area, pts: &[&TickRecord], t_end: f64) -> DrawResult {
    let y = range(
        pts.iter()
            .flat_map(|r| [r.f_true[0], r.f_true[1], r.f_meas[0], r.f_meas[1]]),
        0.05,
    );
    let mut c = chart(area, "contact force on the environment", (0.0, t_end), y)?;
    c.configure_mesh()
        .x_desc("t [s]")
        .y_desc("force [N]")
        .label_style(("sans-serif", 15))
        .light_line_style(BLACK.mix(0.05))
        .draw()?;
    for (i, (name, color)) in [("f_x", X_COLOR), ("f_y", Y_COLOR)].into_iter().enumerate() {
        c.draw_series(LineSeries::new(
            pts.iter().map(|r| (r.t, r.f_meas[i])),
            lighten(color, 0.65).stroke_width(1),
        ))?
        .label(format!("{name} measured"))
        .legend(move |(x, y)| {
            PathElement::new([(x, y), (x + 20, y)], lighten(color, 0.65).stroke_width(2))
        });
        c.draw_series(LineSeries::new(
            pts.iter().map(|r| (r.t, r.f_true[i])),
            // 1 px: plotters fills wider lines as polygons, which streak out of the panel on
            // near-vertical force spikes.
            color.stroke_width(1),
        ))?
        .label(format!("{name} true"))
        .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], color.stroke_width(2)));
    }
    legend(&mut c, SeriesLabelPosition::UpperRight)
}

fn draw_path(area: &Area, pts: &[&TickRecord], cfg: &ArmConfig) -> DrawResult {
    let g = &cfg.geometry;
    let (wall, end) = (g.wall_x(), g.end_x());
    let (yc, r) = (g.hole_center[1], g.hole_radius);
    let x = range(
        pts.iter()
            .flat_map(|p| [p.x[0], p.x_ref[0]])
            .chain([wall - 0.02, end + 0.02]),
        0.05,
    );
    let y = range(
        pts.iter()
            .flat_map(|p| [p.x[1], p.x_ref[1]])
            .chain([yc - 0.03, yc + 0.03]),
        0.05,
    );
    let mut c = chart(area, "x-y path (wall and hole channel in grey)", x, y)?;
    c.configure_mesh()
        .x_desc("x [m]")
        .y_desc("y [m]")
        .label_style(("sans-serif", 15))
        .light_line_style(BLACK.mix(0.05))
        .draw()?;
    // Solid material: the wall (below and above the channel) up to beyond the end wall.
    let solid = WALL.mix(0.25).filled();
    let far = x.1.max(end + 0.01);
    c.draw_series([
        Rectangle::new([(wall, y.0), (far, yc - r)], solid),
        Rectangle::new([(wall, yc + r), (far, y.1)], solid),
        Rectangle::new([(end, yc - r), (far, yc + r)], solid),
    ])?;
    let edge = WALL.stroke_width(2);
    c.draw_series([PathElement::new(
        [
            (wall, y.0),
            (wall, yc - r),
            (end, yc - r),
            (end, yc + r),
            (wall, yc + r),
            (wall, y.1),
        ],
        edge,
    )])?
    .label("wall face, channel, end wall")
    .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], WALL.stroke_width(2)));
    c.draw_series(DashedLineSeries::new(
        pts.iter().map(|p| (p.x_ref[0], p.x_ref[1])),
        6,
        4,
        BLACK.mix(0.5).stroke_width(1),
    ))?
    .label("reference")
    .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], BLACK.mix(0.5).stroke_width(1)));
    c.draw_series(LineSeries::new(
        pts.iter().map(|p| (p.x[0], p.x[1])),
        X_COLOR.stroke_width(2),
    ))?
    .label("TCP (true)")
    .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], X_COLOR.stroke_width(2)));
    legend(&mut c, SeriesLabelPosition::UpperLeft)
}
