//! (b) The final policy's action profiles over time: the predicted action distribution (mean
//! ± 2σ) of the last policy update against the actions actually applied in that update's
//! roll-out and in the initial exploration roll-out (thesis Figs 5-6, 5-12, right). The
//! band is clipped to the action's saturation range when the run recorded it: the moment-matched
//! Gaussian of a squashed action can reach past a bound that no applied action crosses.

use super::{
    axis_label, chart, draw_prediction, grid_size, legend, panels, pretty, range, stairs, std_of,
};
use super::{place_legend, segments, Axes, DrawResult, Figure, Occupied, GREY, RECORDED};
use crate::data::{Prediction, Rollout};
use plotters::coord::Shift;
use plotters::prelude::*;

pub(crate) struct Policy<'a> {
    pub pred: &'a Prediction,
    /// Which of the prediction's start distributions to draw.
    pub start: usize,
    pub last: Option<&'a Rollout>,
    pub initial: Option<&'a Rollout>,
}

const BAND: &str = "predicted ±2σ";
const MEAN: &str = "predicted mean";
const INITIAL: &str = "initial roll-out (exploration)";

/// Actions are held over each step, so every profile is drawn as a staircase.
fn recorded(r: &Rollout, j: usize, dt: f64) -> Option<(Vec<f64>, Vec<f64>)> {
    let v: Option<Vec<f64>> = r.actions.iter().map(|a| a.get(j).copied()).collect();
    v.filter(|v| !v.is_empty()).map(|v| stairs(0.0, dt, &v))
}

/// `mean ± half_width`, clipped to `bounds` (lowest, highest) when given.
fn clipped_band(
    mean: &[f64],
    half_width: &[f64],
    bounds: Option<(f64, f64)>,
) -> (Vec<f64>, Vec<f64>) {
    let (lowest, highest) = bounds.unwrap_or((f64::NEG_INFINITY, f64::INFINITY));
    mean.iter()
        .zip(half_width)
        .map(|(m, h)| ((m - h).max(lowest), (m + h).min(highest)))
        .unzip()
}

impl Figure for Policy<'_> {
    fn size(&self) -> (u32, u32) {
        grid_size(self.pred.action_names.len(), 480)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let p = self.pred;
        let dt = p.dt;
        let steps = p.steps(self.start);
        let t0 = steps.first().map_or(0.0, |s| s.t - dt);
        for (j, area) in panels(root, p.action_names.len()).iter().enumerate() {
            let Some(name) = p.action_names.get(j) else {
                break;
            };
            let mean: Vec<f64> = steps.iter().map(|s| s.action_mean[j]).collect();
            let sd: Vec<f64> = steps
                .iter()
                .map(|s| 2.0 * std_of(s.action_var[j]))
                .collect();
            let bounds = p.action_bounds.as_ref().and_then(|b| b.get(j).copied());
            let (ts, m) = stairs(t0, dt, &mean);
            let (lo, hi) = clipped_band(&m, &stairs(t0, dt, &sd).1, bounds);
            let last = self.last.and_then(|r| recorded(r, j, dt));
            let initial = self.initial.and_then(|r| recorded(r, j, dt));

            let others = [&last, &initial].into_iter().flatten();
            let t_end = others.clone().filter_map(|(t, _)| t.last().copied());
            let x = range(ts.iter().copied().chain(t_end).chain([0.0]), 0.0);
            let y_vals = lo.iter().chain(&hi).copied();
            let y = range(
                y_vals.chain(others.flat_map(|(_, v)| v.iter().copied())),
                0.06,
            );
            let title = format!(
                "{} — final policy (update {}{})",
                pretty(name).0,
                p.episode,
                p.start_label(self.start)
            );
            let y_desc = axis_label(name);
            let mut axes = Axes {
                title: &title,
                x,
                y,
                x_desc: "time [s]",
                y_desc: &y_desc,
                integer_x: false,
            };
            let applied = self
                .last
                .map(|r| format!("applied, roll-out of update {}", r.episode));
            let pos = (j == 0).then(|| {
                let mut occ = Occupied::default();
                occ.band(&ts, &lo, &hi);
                for (t, v) in [&last, &initial].into_iter().flatten() {
                    occ.line(t.iter().copied().zip(v.iter().copied()));
                }
                let mut labels = vec![BAND.to_string(), MEAN.to_string()];
                labels.extend(initial.as_ref().map(|_| INITIAL.to_string()));
                labels.extend(last.as_ref().and(applied.clone()));
                place_legend(&occ, &mut axes, area.dim_in_pixel(), &labels)
            });
            let mut c = chart(area, &axes)?;
            draw_prediction(&mut c, &ts, (&lo, &hi), &m, (BAND, MEAN.to_string()))?;
            if let Some((t, v)) = &initial {
                c.draw_series(segments(
                    t.iter().copied().zip(v.iter().copied()),
                    GREY.stroke_width(1),
                ))?
                .label(INITIAL)
                .legend(|(x, y)| PathElement::new([(x, y), (x + 18, y)], GREY.stroke_width(2)));
            }
            if let (Some((t, v)), Some(applied)) = (&last, applied) {
                c.draw_series(segments(
                    t.iter().copied().zip(v.iter().copied()),
                    RECORDED.stroke_width(2),
                ))?
                .label(applied)
                .legend(|(x, y)| PathElement::new([(x, y), (x + 18, y)], RECORDED.stroke_width(2)));
            }
            if let Some(pos) = pos {
                legend(&mut c, pos)?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::clipped_band;

    #[test]
    fn the_band_stops_at_the_saturation_range() {
        let mean = [6.0, 100.0, 249.0];
        let half = [4.0, 20.0, 3.0];
        let (lo, hi) = clipped_band(&mean, &half, Some((5.0, 250.0)));
        assert_eq!(lo, [5.0, 80.0, 246.0]);
        assert_eq!(hi, [10.0, 120.0, 250.0]);
        let (lo, hi) = clipped_band(&mean, &half, None);
        assert_eq!(lo, [2.0, 80.0, 246.0]);
        assert_eq!(hi, [10.0, 120.0, 252.0]);
    }
}
