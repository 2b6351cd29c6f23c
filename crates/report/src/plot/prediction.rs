//! (c) Long-term state predictions (mean ± 2σ per dimension) against the states recorded when
//! the same policy was rolled out, and (d) the predicted immediate cost against the recorded
//! one. A prediction far off the recording shows where the GP model was wrong.

use super::{axis_label, band_view, chart, draw_prediction, grid_size, legend, panels, pretty};
use super::{place_legend, segments, Axes, DrawResult, Figure, Occupied, RECORDED};
use super::{range, std_of};
use crate::data::{Prediction, Rollout};
use plotters::coord::Shift;
use plotters::prelude::*;

const BAND: &str = "predicted ±2σ";
const MEAN: &str = "predicted mean";

pub(crate) struct StatePrediction<'a> {
    pub pred: &'a Prediction,
    /// Which of the prediction's start distributions to draw.
    pub start: usize,
    pub rollout: Option<&'a Rollout>,
}

impl Figure for StatePrediction<'_> {
    fn size(&self) -> (u32, u32) {
        grid_size(self.pred.state_names.len(), 400)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let p = self.pred;
        let steps = p.steps(self.start);
        let ts: Vec<f64> = steps.iter().map(|s| s.t).collect();
        for (i, area) in panels(root, p.state_names.len()).iter().enumerate() {
            let Some(name) = p.state_names.get(i) else {
                break;
            };
            let mean: Vec<f64> = steps.iter().map(|s| s.mean[i]).collect();
            let sd: Vec<f64> = steps.iter().map(|s| 2.0 * std_of(s.var[i])).collect();
            let lo: Vec<f64> = mean.iter().zip(&sd).map(|(m, s)| m - s).collect();
            let hi: Vec<f64> = mean.iter().zip(&sd).map(|(m, s)| m + s).collect();
            // true_states[0] is the start, true_states[k] the state k steps later.
            let truth: Vec<(f64, f64)> = self
                .rollout
                .map(|r| {
                    let states = r.true_states.iter().enumerate();
                    let pts = states.filter_map(|(k, x)| Some((k as f64 * p.dt, *x.get(i)?)));
                    pts.collect()
                })
                .unwrap_or_default();

            let x = range(
                ts.iter()
                    .copied()
                    .chain([0.0])
                    .chain(truth.iter().map(|q| q.0)),
                0.0,
            );
            let data = mean.iter().copied().chain(truth.iter().map(|q| q.1));
            let (y, cut) = band_view(data, &lo, &hi, 0.06);
            let title = format!(
                "{} — update {}{}{}",
                pretty(name).0,
                p.episode,
                p.start_label(self.start),
                if cut { " (band cut at the axis)" } else { "" }
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
            let recorded = match (truth.is_empty(), self.rollout) {
                (false, Some(r)) => Some(format!("recorded, roll-out of update {}", r.episode)),
                _ => None,
            };
            let pos = (i == 0).then(|| {
                let mut occ = Occupied::default();
                occ.band(&ts, &lo, &hi);
                occ.line(truth.iter().copied());
                let mut labels = vec![BAND.to_string(), MEAN.to_string()];
                labels.extend(recorded.clone());
                place_legend(&occ, &mut axes, area.dim_in_pixel(), &labels)
            });
            let mut c = chart(area, &axes)?;
            draw_prediction(&mut c, &ts, (&lo, &hi), &mean, (BAND, MEAN.to_string()))?;
            if let Some(recorded) = recorded {
                c.draw_series(segments(truth.iter().copied(), RECORDED.stroke_width(2)))?
                    .label(recorded)
                    .legend(|(x, y)| {
                        PathElement::new([(x, y), (x + 18, y)], RECORDED.stroke_width(2))
                    });
            }
            if let Some(pos) = pos {
                legend(&mut c, pos)?;
            }
        }
        Ok(())
    }
}

pub(crate) struct CostPrediction<'a> {
    pub pred: &'a Prediction,
    /// Which of the prediction's start distributions to draw.
    pub start: usize,
    /// The recorded weighted cost per step and the roll-out's update index.
    pub recorded: Option<(&'a [f64], u64)>,
}

impl Figure for CostPrediction<'_> {
    fn size(&self) -> (u32, u32) {
        (1000, 520)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let p = self.pred;
        let (mut ts, mut mean, mut sd) = (Vec::new(), Vec::new(), Vec::new());
        for s in p.steps(self.start) {
            if let Some((m, sdev)) = s.weighted_cost {
                ts.push(s.t);
                mean.push(m);
                sd.push(2.0 * sdev.max(0.0));
            }
        }
        let lo: Vec<f64> = mean.iter().zip(&sd).map(|(m, s)| m - s).collect();
        let hi: Vec<f64> = mean.iter().zip(&sd).map(|(m, s)| m + s).collect();
        // costs[k] is the cost of step k, i.e. of the state at its end, like the prediction's t.
        let rec: Vec<(f64, f64)> = self
            .recorded
            .map(|(c, _)| {
                let pts = c.iter().enumerate();
                pts.map(|(k, &v)| ((k + 1) as f64 * p.dt, v)).collect()
            })
            .unwrap_or_default();
        let x = range(
            ts.iter()
                .copied()
                .chain([0.0])
                .chain(rec.iter().map(|q| q.0)),
            0.0,
        );
        let y_vals = lo.iter().chain(&hi).copied().chain([0.0]);
        let y = range(y_vals.chain(rec.iter().map(|q| q.1)), 0.06);
        let title = format!(
            "Immediate cost — update {}{}",
            p.episode,
            p.start_label(self.start)
        );
        let mut axes = Axes {
            title: &title,
            x,
            y,
            x_desc: "time [s]",
            y_desc: "weighted immediate cost",
            integer_x: false,
        };
        let mean_label = format!("predicted mean (sum {:.2})", mean.iter().sum::<f64>());
        let rec_label = self.recorded.map(|(costs, episode)| {
            let sum = costs.iter().sum::<f64>();
            format!("recorded, roll-out of update {episode} (sum {sum:.2})")
        });
        let mut occ = Occupied::default();
        occ.band(&ts, &lo, &hi);
        occ.line(rec.iter().copied());
        let mut labels = vec![BAND.to_string(), mean_label.clone()];
        labels.extend(rec_label.clone());
        let pos = place_legend(&occ, &mut axes, root.dim_in_pixel(), &labels);
        let mut c = chart(root, &axes)?;
        draw_prediction(&mut c, &ts, (&lo, &hi), &mean, (BAND, mean_label))?;
        if let Some(rec_label) = rec_label {
            c.draw_series(segments(rec.iter().copied(), RECORDED.stroke_width(2)))?
                .label(rec_label)
                .legend(|(x, y)| PathElement::new([(x, y), (x + 18, y)], RECORDED.stroke_width(2)));
        }
        legend(&mut c, pos)
    }
}
