//! The report's figures. Each figure draws through a generic plotters backend once for PNG (the
//! report embeds it) and once for SVG (for papers), so the two never drift apart.

pub(crate) mod arm;
mod lines;
pub(crate) mod policy;
pub(crate) mod prediction;
pub(crate) mod returns;

use crate::atomic::{finish, staging_path};
use crate::ReportError;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};
use vicpilco_env::font::{ensure_font, FAMILY};

pub(crate) use lines::{band, clip, segments, stairs};

pub(crate) type DrawResult = Result<(), Box<dyn std::error::Error>>;
pub(crate) type Cart = Cartesian2d<RangedCoordf64, RangedCoordf64>;

pub(crate) trait Figure {
    fn size(&self) -> (u32, u32);
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static;
}

/// Draws `fig` into DIR/STEM.png and DIR/STEM.svg; returns both paths.
pub(crate) fn save(
    fig: &impl Figure,
    dir: &Path,
    stem: &str,
) -> Result<(PathBuf, PathBuf), ReportError> {
    ensure_font();
    let png = dir.join(format!("{stem}.png"));
    let svg = dir.join(format!("{stem}.svg"));
    let fail = |file: &Path, e: Box<dyn std::error::Error>| ReportError::Plot {
        file: file.to_path_buf(),
        message: e.to_string(),
    };
    // Drawn under a staging name and renamed: a run stopped mid-draw keeps the last whole plot.
    let (png_draft, svg_draft) = (staging_path(&png), staging_path(&svg));
    render(
        &BitMapBackend::new(&png_draft, fig.size()).into_drawing_area(),
        fig,
    )
    .map_err(|e| fail(&png, e))?;
    render(
        &SVGBackend::new(&svg_draft, fig.size()).into_drawing_area(),
        fig,
    )
    .map_err(|e| fail(&svg, e))?;
    for file in [&png, &svg] {
        finish(file).map_err(|e| fail(file, e.into()))?;
    }
    Ok((png, svg))
}

fn render<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, fig: &impl Figure) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    fig.draw(root)?;
    root.present()?;
    Ok(())
}

pub(crate) const OK_GREEN: RGBColor = RGBColor(34, 150, 34);
/// Darker than pure yellow so the markers stay visible on white.
pub(crate) const SOME_YELLOW: RGBColor = RGBColor(235, 185, 0);
pub(crate) const FAIL_RED: RGBColor = RGBColor(210, 35, 35);
pub(crate) const PRED_BLUE: RGBColor = RGBColor(31, 119, 180);
pub(crate) const RECORDED: RGBColor = RGBColor(20, 20, 20);
pub(crate) const GREY: RGBColor = RGBColor(150, 150, 150);

pub(crate) const TITLE_PX: u32 = 22;
const MARGIN: u32 = 14;
/// Room for the last x tick label, which is centred on the plot's right edge.
const MARGIN_RIGHT: u32 = 26;
const X_LABEL_AREA: u32 = 48;
const Y_LABEL_AREA: u32 = 78;
pub(crate) const LABEL_PX: u32 = 18;
pub(crate) const TICK_PX: u32 = 16;

/// Axis range of `vals` padded by `pad` of its span; a flat or empty series still gets a
/// usable range.
pub(crate) fn range(vals: impl IntoIterator<Item = f64>, pad: f64) -> (f64, f64) {
    let (lo, hi) = vals
        .into_iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let span = hi - lo;
    if span <= 1e-12 * lo.abs().max(hi.abs()) || span == 0.0 {
        let half = 0.05 * lo.abs().max(1.0);
        return (lo - half, hi + half);
    }
    let padded = (lo - pad * span, hi + pad * span);
    // Values near f64::MAX would overflow the padding; plotters cannot draw infinite ranges.
    match (
        padded.0.is_finite() && padded.1.is_finite(),
        span.is_finite(),
    ) {
        (true, _) => padded,
        (false, true) => (lo, hi),
        (false, false) => (0.0, 1.0),
    }
}

/// How far past the drawn data (means and recordings) a prediction band may stretch the
/// y-axis, as a fraction of the data's span on each side, so the data keeps at least a third
/// of the axis. A long prediction's ±2σ band can be 20× wider than everything recorded (ẋ to
/// ±4 m/s against 0.3 m/s of data), which would draw the recording and the mean as flat lines;
/// beyond this the band is cut at the axis.
pub(crate) const BAND_REACH: f64 = 1.0;

/// The y-range of a panel showing `data` (means, recordings) and the band `lo..hi`: all of the
/// band when it stays within [`BAND_REACH`] of the data's span, else the data's range widened
/// by that much; and whether the band was cut.
pub(crate) fn band_view(
    data: impl IntoIterator<Item = f64>,
    lo: &[f64],
    hi: &[f64],
    pad: f64,
) -> ((f64, f64), bool) {
    let (d_lo, d_hi) = range(data, 0.0);
    let reach = BAND_REACH * (d_hi - d_lo);
    let (b_lo, b_hi) = range(lo.iter().chain(hi).copied(), 0.0);
    let lowest = b_lo.max(d_lo - reach).min(d_lo);
    let highest = b_hi.min(d_hi + reach).max(d_hi);
    let cut = b_lo < lowest || b_hi > highest;
    (range([lowest, highest], pad), cut)
}

/// What one chart shows along its axes.
pub(crate) struct Axes<'s> {
    pub title: &'s str,
    pub x: (f64, f64),
    pub y: (f64, f64),
    pub x_desc: &'s str,
    pub y_desc: &'s str,
    /// Label only whole numbers on x (episode indices).
    pub integer_x: bool,
}

/// A chart with title, axis descriptions and a light grid.
pub(crate) fn chart<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    axes: &Axes<'_>,
) -> Result<ChartContext<'a, DB, Cart>, Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    let mut c = ChartBuilder::on(area)
        .caption(axes.title, (FAMILY, TITLE_PX))
        .margin(MARGIN)
        .margin_right(MARGIN_RIGHT)
        .x_label_area_size(X_LABEL_AREA)
        .y_label_area_size(Y_LABEL_AREA)
        .build_cartesian_2d(axes.x.0..axes.x.1, axes.y.0..axes.y.1)?;
    let whole = |v: &f64| {
        if (v - v.round()).abs() < 1e-9 {
            format!("{}", v.round() + 0.0)
        } else {
            String::new()
        }
    };
    let x_fmt = tick_formatter(axes.x);
    let y_fmt = tick_formatter(axes.y);
    let mut mesh = c.configure_mesh();
    mesh.x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .x_desc(axes.x_desc)
        .y_desc(axes.y_desc)
        .axis_desc_style((FAMILY, LABEL_PX))
        .label_style((FAMILY, TICK_PX))
        .light_line_style(BLACK.mix(0.05))
        .bold_line_style(BLACK.mix(0.15));
    if axes.integer_x {
        let span = (axes.x.1 - axes.x.0).ceil().max(1.0) as usize;
        mesh.x_labels(span.min(16) + 1).x_label_formatter(&whole);
    }
    mesh.draw()?;
    Ok(c)
}

/// Tick labels with as many decimals as the tick spacing of `range` needs and no float noise
/// (plotters' own labels show `-0.0` and `0.30000000000000004`).
fn tick_formatter(range: (f64, f64)) -> impl Fn(&f64) -> String {
    // plotters spaces at most 10 labels 1, 2 or 5 × 10^k apart, so span / 12 bounds the step
    // from below and never asks for too few decimals.
    let step = ((range.1 - range.0) / 12.0).abs();
    let decimals = if step > 0.0 && step.is_finite() {
        (-step.log10().floor()).clamp(0.0, 12.0) as usize
    } else {
        3
    };
    move |v: &f64| trim_number(&format!("{v:.decimals$}"))
}

/// Drops trailing zeros and a minus sign on zero: "0.500" → "0.5", "-0.00" → "0".
fn trim_number(s: &str) -> String {
    let t = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.')
    } else {
        s
    };
    if t.trim_start_matches('-').chars().all(|c| c == '0') {
        "0".into()
    } else {
        t.into()
    }
}

/// A number for a label: six significant digits at most, so 0.6499999999999999 reads 0.65.
pub(crate) fn short(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let decimals = (5.0 - v.abs().log10().floor()).clamp(0.0, 12.0) as usize;
    trim_number(&format!("{v:.decimals$}"))
}

/// The data a legend should not cover, collected while a figure is prepared.
#[derive(Default)]
pub(crate) struct Occupied {
    lines: Vec<Vec<(f64, f64)>>,
    bands: Vec<(Vec<f64>, Vec<f64>, Vec<f64>)>,
}

impl Occupied {
    pub fn line(&mut self, pts: impl IntoIterator<Item = (f64, f64)>) {
        self.lines.push(pts.into_iter().collect());
    }

    pub fn band(&mut self, xs: &[f64], lo: &[f64], hi: &[f64]) {
        let n = xs.len().min(lo.len()).min(hi.len());
        self.bands
            .push((xs[..n].to_vec(), lo[..n].to_vec(), hi[..n].to_vec()));
    }

    /// Sample points in the unit square of the axes: lines densified along their segments,
    /// bands filled, so a legend box cannot hide between two data points.
    fn samples(&self, x: (f64, f64), y: (f64, f64)) -> Vec<(f64, f64)> {
        let norm = |p: (f64, f64)| ((p.0 - x.0) / (x.1 - x.0), (p.1 - y.0) / (y.1 - y.0));
        let mut out = Vec::new();
        for l in &self.lines {
            out.extend(l.first().map(|&p| norm(p)));
            for w in l.windows(2) {
                let (a, b) = (norm(w[0]), norm(w[1]));
                let n = ((b.0 - a.0).hypot(b.1 - a.1) / 0.01)
                    .ceil()
                    .clamp(1.0, 200.0) as usize;
                out.extend((1..=n).map(|k| {
                    let f = k as f64 / n as f64;
                    (a.0 + f * (b.0 - a.0), a.1 + f * (b.1 - a.1))
                }));
            }
        }
        for (xs, lo, hi) in &self.bands {
            for i in 0..xs.len() {
                let j = (i + 1).min(xs.len() - 1);
                for k in 0..10 {
                    let f = k as f64 / 10.0;
                    let lerp = |v: &[f64]| v[i] + f * (v[j] - v[i]);
                    let (xv, l, h) = (lerp(xs), lerp(lo), lerp(hi));
                    out.extend((0..=6).map(|m| norm((xv, l + (h - l) * m as f64 / 6.0))));
                }
            }
        }
        out
    }
}

/// Picks the corner where a legend with `labels` covers the fewest data samples; if every
/// corner holds data, raises the top of `axes.y` so the legend sits above all of it.
pub(crate) fn place_legend(
    occupied: &Occupied,
    axes: &mut Axes<'_>,
    area_px: (u32, u32),
    labels: &[String],
) -> SeriesLabelPosition {
    let plot_w = area_px
        .0
        .saturating_sub(Y_LABEL_AREA + MARGIN + MARGIN_RIGHT)
        .max(1) as f64;
    let plot_h = area_px
        .1
        .saturating_sub(X_LABEL_AREA + 2 * MARGIN + TITLE_PX + 12)
        .max(1) as f64;
    let longest = labels.iter().map(|l| l.chars().count()).max().unwrap_or(0) as f64;
    // Legend box as plotters draws it (14 px text, sample glyph, padding, offset from corner).
    let fw = ((60.0 + 8.0 * longest) / plot_w).min(1.0);
    let fh = ((24.0 + 21.0 * labels.len() as f64) / plot_h).min(1.0);
    let samples = occupied.samples(axes.x, axes.y);
    let corners = [
        (
            SeriesLabelPosition::UpperRight,
            (1.0 - fw, 1.0),
            (1.0 - fh, 1.0),
        ),
        (SeriesLabelPosition::UpperLeft, (0.0, fw), (1.0 - fh, 1.0)),
        (SeriesLabelPosition::LowerRight, (1.0 - fw, 1.0), (0.0, fh)),
        (SeriesLabelPosition::LowerLeft, (0.0, fw), (0.0, fh)),
    ];
    let inside = |bx: (f64, f64), by: (f64, f64)| {
        let hits = samples.iter().filter(|p| (bx.0..=bx.1).contains(&p.0));
        hits.filter(|p| (by.0..=by.1).contains(&p.1)).count()
    };
    let scored = corners.map(|(pos, bx, by)| (inside(bx, by), pos));
    let best = scored.iter().enumerate().min_by_key(|(i, (n, _))| (*n, *i));
    match best {
        Some((_, (0, pos))) => pos.clone(),
        _ if fh < 0.6 => {
            let (y0, y1) = axes.y;
            axes.y.1 = (y1 - fh * y0) / (1.0 - fh);
            SeriesLabelPosition::UpperRight
        }
        Some((_, (_, pos))) => pos.clone(),
        None => SeriesLabelPosition::UpperRight,
    }
}

pub(crate) fn legend<'a, DB: DrawingBackend + 'a>(
    c: &mut ChartContext<'a, DB, Cart>,
    pos: SeriesLabelPosition,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    c.configure_series_labels()
        .position(pos)
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK.mix(0.4))
        .label_font((FAMILY, TICK_PX))
        .draw()?;
    Ok(())
}

/// The closed outline between `lo` and `hi` over `xs`, for a filled uncertainty band.
/// The prediction every plot shows: the band `lo..hi` over `ts` labelled `band_label`, and the
/// mean labelled `mean_label`, both in the prediction blue, with their legend entries.
pub(crate) fn draw_prediction<'a, DB: DrawingBackend + 'a>(
    c: &mut ChartContext<'a, DB, Cart>,
    ts: &[f64],
    (lo, hi): (&[f64], &[f64]),
    mean: &[f64],
    (band_label, mean_label): (&str, String),
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    c.draw_series(std::iter::once(Polygon::new(
        band(ts, lo, hi),
        PRED_BLUE.mix(0.2).filled(),
    )))?
    .label(band_label)
    .legend(|(x, y)| Rectangle::new([(x, y - 6), (x + 18, y + 6)], PRED_BLUE.mix(0.2).filled()));
    c.draw_series(segments(
        ts.iter().copied().zip(mean.iter().copied()),
        PRED_BLUE.stroke_width(2),
    ))?
    .label(mean_label)
    .legend(|(x, y)| PathElement::new([(x, y), (x + 18, y)], PRED_BLUE.stroke_width(2)));
    Ok(())
}

/// A standard deviation from a variance that rounding may have made slightly negative.
pub(crate) fn std_of(var: f64) -> f64 {
    var.max(0.0).sqrt()
}

/// How a state or action name is shown, and its unit if known. The run files use both the
/// simulator's short names (`xd`, `fx`) and spelled-out ones (`xdot`, `f_x`); any other name
/// may carry its unit as a trailing ` [unit]` (a system of one's own: `k [N/m]`).
pub(crate) fn pretty(name: &str) -> (String, Option<String>) {
    let known = match name {
        "x" | "y" => Some((name, "m")),
        "xd" | "xdot" => Some(("ẋ", "m/s")),
        "yd" | "ydot" => Some(("ẏ", "m/s")),
        "fx" | "f_x" => Some(("f_x", "N")),
        "fy" | "f_y" => Some(("f_y", "N")),
        "k_x" | "kx" => Some(("k_x", "N/m")),
        "k_y" | "ky" => Some(("k_y", "N/m")),
        // Increments of the reference per controller tick (`vilta.delta_tick`), not per step.
        "dx_ref" => Some(("Δx_ref", "m per tick")),
        "dy_ref" => Some(("Δy_ref", "m per tick")),
        "theta" => Some(("θ", "rad")),
        "dtheta" => Some(("dθ/dt", "rad/s")),
        "v" => Some(("v", "m/s")),
        "torque" => Some(("torque", "N m")),
        "force" => Some(("force", "N")),
        _ => None,
    };
    if let Some((shown, unit)) = known {
        return (shown.to_string(), Some(unit.to_string()));
    }
    match name
        .strip_suffix(']')
        .and_then(|rest| rest.rsplit_once(" ["))
    {
        Some((shown, unit)) if !shown.is_empty() && !unit.is_empty() => {
            (shown.to_string(), Some(unit.to_string()))
        }
        _ => (name.to_string(), None),
    }
}

/// "name [unit]" for an axis description.
pub(crate) fn axis_label(name: &str) -> String {
    match pretty(name) {
        (shown, Some(unit)) => format!("{shown} [{unit}]"),
        (shown, None) => shown,
    }
}

/// A perceptually ordered colour for update `i` of `n` (viridis, sampled at five stops), so
/// early and late roll-outs are told apart at a glance.
pub(crate) fn gradient(i: usize, n: usize) -> RGBColor {
    const STOPS: [(f64, f64, f64); 5] = [
        (68.0, 1.0, 84.0),
        (59.0, 82.0, 139.0),
        (33.0, 145.0, 140.0),
        (94.0, 201.0, 98.0),
        (223.0, 200.0, 30.0),
    ];
    let f = if n <= 1 {
        1.0
    } else {
        i as f64 / (n - 1) as f64
    };
    let pos = f.clamp(0.0, 1.0) * (STOPS.len() - 1) as f64;
    let k = (pos.floor() as usize).min(STOPS.len() - 2);
    let w = pos - k as f64;
    let (a, b) = (STOPS[k], STOPS[k + 1]);
    let mix = |x: f64, y: f64| (x + (y - x) * w).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Pixel size of the grid [`panels`] lays out: `n` panels of height `panel_height`, two per
/// row when there is more than one.
pub(crate) fn grid_size(n: usize, panel_height: u32) -> (u32, u32) {
    let n = n.max(1);
    let w = if n > 1 { 1400 } else { 1000 };
    (w, panel_height * n.div_ceil(2) as u32)
}

/// Splits `root` into a grid of `n` panels, two per row when there is more than one.
pub(crate) fn panels<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    n: usize,
) -> Vec<DrawingArea<DB, Shift>> {
    let cols = if n > 1 { 2 } else { 1 };
    let rows = n.div_ceil(cols).max(1);
    root.split_evenly((rows, cols))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_band_far_wider_than_the_data_is_cut_and_a_narrow_one_is_not() {
        let data = [0.0, 1.0];
        // Within the data's span on each side: all of the band shows.
        let (y, cut) = band_view(data, &[-0.9], &[1.3], 0.0);
        assert_eq!((y, cut), ((-0.9, 1.3), false));
        // A band 20× the data's span is cut at that span past the data.
        let (y, cut) = band_view(data, &[-10.0], &[10.0], 0.0);
        assert_eq!((y, cut), ((-1.0, 2.0), true));
        // Cut on one side only.
        let (y, cut) = band_view(data, &[0.2], &[10.0], 0.0);
        assert_eq!((y, cut), ((0.0, 2.0), true));
    }

    #[test]
    fn range_survives_flat_empty_and_nan() {
        assert_eq!(range([], 0.1), (0.0, 1.0));
        let (lo, hi) = range([2.0, 2.0], 0.0);
        assert!(lo < 2.0 && hi > 2.0);
        let (lo, hi) = range([f64::NAN, 1.0, 3.0], 0.0);
        assert_eq!((lo, hi), (1.0, 3.0));
        let (lo, hi) = range([-f64::MAX, f64::MAX], 0.1);
        assert!(lo.is_finite() && hi.is_finite() && lo < hi);
    }

    #[test]
    fn labels_have_no_float_noise() {
        assert_eq!(short(0.6499999999999999), "0.65");
        assert_eq!(short(0.005), "0.005");
        assert_eq!(short(250.0), "250");
        assert_eq!(short(-1.5e-7), "-0.00000015");
        let f = tick_formatter((-0.1, 0.15));
        assert_eq!(f(&-1e-17), "0");
        assert_eq!(f(&0.15000000000000002), "0.15");
        assert_eq!(f(&0.05), "0.05");
        let f = tick_formatter((0.0, 300.0));
        assert_eq!(f(&250.0), "250");
    }

    #[test]
    fn axis_labels_know_the_arms_names_and_read_a_units_suffix() {
        assert_eq!(axis_label("xd"), "ẋ [m/s]");
        assert_eq!(axis_label("k [N/m]"), "k [N/m]");
        assert_eq!(
            pretty("k [N/m]"),
            ("k".to_string(), Some("N/m".to_string()))
        );
        for bare in ["k", "[N/m]", "k []", "k [N/m"] {
            assert_eq!(pretty(bare), (bare.to_string(), None), "{bare}");
        }
    }

    #[test]
    fn gradient_ends_are_the_viridis_ends() {
        assert_eq!(gradient(0, 5), RGBColor(68, 1, 84));
        assert_eq!(gradient(4, 5), RGBColor(223, 200, 30));
        assert_eq!(gradient(0, 1), RGBColor(223, 200, 30));
    }
}
