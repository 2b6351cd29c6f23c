//! (a) Expected return per policy update with its 95 % interval against the recorded return,
//! markers coloured by how many roll-outs succeeded (thesis Figs 5-6, 5-7, 5-12).

use super::{band, chart, legend, place_legend, range, Axes, DrawResult, Figure, Occupied};
use super::{segments, FAIL_RED, GREY, OK_GREEN, PRED_BLUE, RECORDED, SOME_YELLOW};
use crate::data::{Colour, Episode};
use plotters::coord::Shift;
use plotters::prelude::*;

pub(crate) struct Returns<'a> {
    pub episodes: &'a [Episode],
    /// Each update's predicted return (mean, std), in `episodes`' order
    /// ([`crate::data::Run::predicted_return`]).
    pub predicted: Vec<(f64, f64)>,
    pub initial_return: Option<f64>,
    /// (update, recorded return) of each roll-out after an update's first: runs with several
    /// roll-outs per update (`vilta-var`) show what the colour summarises.
    pub other_rollouts: Vec<(f64, f64)>,
    /// The update whose policy the run hands over when it is not the last one
    /// (`vilta.final_policy`), marked by a vertical line.
    pub final_policy: Option<u64>,
}

/// The thesis's 95 % confidence intervals.
const Z95: f64 = 1.96;
const MARKER: i32 = 6;
const BAND: &str = "predicted ±1.96σ (95 %)";
const MEAN: &str = "predicted mean";
const INITIAL: &str = "initial roll-out";
const OTHERS: &str = "recorded: the update's other roll-outs";
const OTHER_MARKER: i32 = 3;

impl Figure for Returns<'_> {
    fn size(&self) -> (u32, u32) {
        (1000, 600)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let eps = self.episodes;
        let xs: Vec<f64> = eps.iter().map(|e| e.index as f64).collect();
        let means: Vec<(f64, f64)> = xs
            .iter()
            .zip(&self.predicted)
            .map(|(&x, p)| (x, p.0))
            .collect();
        let lo: Vec<f64> = self.predicted.iter().map(|(m, s)| m - Z95 * s).collect();
        let hi: Vec<f64> = self.predicted.iter().map(|(m, s)| m + Z95 * s).collect();
        let x = range(xs.iter().copied().chain([1.0]), 0.0);
        let x = (x.0 - 0.5, x.1 + 0.5);
        let y_vals = lo.iter().chain(&hi).copied();
        let y_vals = y_vals.chain(eps.iter().map(|e| e.recorded));
        let y_vals = y_vals.chain(self.other_rollouts.iter().map(|p| p.1));
        let y = range(y_vals.chain(self.initial_return), 0.08);
        let group = |want: Option<Colour>| -> Vec<(f64, f64)> {
            eps.iter()
                .filter(|e| e.colour() == want)
                .map(|e| (e.index as f64, e.recorded))
                .collect()
        };
        let groups = [
            (
                group(Some(Colour::Green)),
                "recorded: all roll-outs succeed",
            ),
            (group(Some(Colour::Yellow)), "recorded: some succeed"),
            (group(Some(Colour::Red)), "recorded: none succeed"),
            (group(None), "recorded (no success flag)"),
        ];

        let mut occ = Occupied::default();
        occ.band(&xs, &lo, &hi);
        occ.line(means.iter().copied());
        let mut labels = vec![BAND.to_string(), MEAN.to_string()];
        if let Some(r0) = self.initial_return {
            occ.line([(x.0, r0), (x.1, r0)]);
            labels.push(INITIAL.into());
        }
        for (pts, label) in &groups {
            pts.iter().for_each(|&p| occ.line([p]));
            if !pts.is_empty() {
                labels.push(label.to_string());
            }
        }
        self.other_rollouts.iter().for_each(|&p| occ.line([p]));
        if !self.other_rollouts.is_empty() {
            labels.push(OTHERS.into());
        }
        let final_label = self
            .final_policy
            .map(|u| format!("final policy (update {u})"));
        // The final policy's line spans the whole height wherever the legend goes; the legend
        // may cover a stretch of it.
        labels.extend(final_label.clone());
        let mut axes = Axes {
            title: "Expected and recorded return per policy update",
            x,
            y,
            x_desc: "policy update (episode)",
            y_desc: "return (sum of immediate costs)",
            integer_x: true,
        };
        let pos = place_legend(&occ, &mut axes, root.dim_in_pixel(), &labels);
        let mut c = chart(root, &axes)?;

        c.draw_series(std::iter::once(Polygon::new(
            band(&xs, &lo, &hi),
            PRED_BLUE.mix(0.2).filled(),
        )))?
        .label(BAND)
        .legend(|(x, y)| {
            Rectangle::new([(x, y - 6), (x + 18, y + 6)], PRED_BLUE.mix(0.2).filled())
        });
        if eps.len() == 1 {
            // A one-point band has no width; an error bar shows the same interval.
            c.draw_series(xs.iter().zip(&lo).zip(&hi).map(|((&x, &lo), &hi)| {
                PathElement::new([(x, lo), (x, hi)], PRED_BLUE.mix(0.5).stroke_width(8))
            }))?;
        }
        c.draw_series(segments(means.iter().copied(), PRED_BLUE.stroke_width(2)))?
            .label(MEAN)
            .legend(|(x, y)| PathElement::new([(x, y), (x + 18, y)], PRED_BLUE.stroke_width(2)));
        // Dots mark the updates on the line, and are all there is of it with one update.
        c.draw_series(means.iter().map(|&p| Circle::new(p, 3, PRED_BLUE.filled())))?;

        if let Some(r0) = self.initial_return {
            c.draw_series(DashedLineSeries::new(
                [(x.0, r0), (x.1, r0)],
                8,
                5,
                GREY.stroke_width(2),
            ))?
            .label(INITIAL)
            .legend(|(x, y)| PathElement::new([(x, y), (x + 18, y)], GREY.stroke_width(2)));
        }

        if let (Some(u), Some(label)) = (self.final_policy, final_label) {
            let (u, y) = (u as f64, axes.y);
            c.draw_series(DashedLineSeries::new(
                [(u, y.0), (u, y.1)],
                6,
                4,
                RECORDED.mix(0.6).stroke_width(2),
            ))?
            .label(label)
            .legend(|(x, y)| {
                PathElement::new([(x + 9, y - 7), (x + 9, y + 7)], RECORDED.stroke_width(2))
            });
        }
        if !self.other_rollouts.is_empty() {
            c.draw_series(
                self.other_rollouts
                    .iter()
                    .map(|&p| Circle::new(p, OTHER_MARKER, RECORDED.stroke_width(1))),
            )?
            .label(OTHERS)
            .legend(|(x, y)| Circle::new((x + 6, y), OTHER_MARKER, RECORDED.stroke_width(1)));
        }

        let edge = RECORDED.stroke_width(1);
        let [(green, green_label), (yellow, yellow_label), (red, red_label), (unknown, unknown_label)] =
            &groups;
        if !green.is_empty() {
            c.draw_series(green.iter().map(|&p| {
                EmptyElement::at(p)
                    + Circle::new((0, 0), MARKER, OK_GREEN.filled())
                    + Circle::new((0, 0), MARKER, edge)
            }))?
            .label(*green_label)
            .legend(move |p| {
                EmptyElement::at(p)
                    + Circle::new((6, 0), MARKER, OK_GREEN.filled())
                    + Circle::new((6, 0), MARKER, edge)
            });
        }
        let diamond = |dx: i32| {
            let m = MARKER + 1;
            vec![(dx, -m), (dx + m, 0), (dx, m), (dx - m, 0)]
        };
        if !yellow.is_empty() {
            c.draw_series(yellow.iter().map(|&p| {
                EmptyElement::at(p)
                    + Polygon::new(diamond(0), SOME_YELLOW.filled())
                    + PathElement::new(closed(diamond(0)), edge)
            }))?
            .label(*yellow_label)
            .legend(move |p| {
                EmptyElement::at(p)
                    + Polygon::new(diamond(6), SOME_YELLOW.filled())
                    + PathElement::new(closed(diamond(6)), edge)
            });
        }
        let square = |dx: i32| {
            [
                (dx - MARKER + 1, -MARKER + 1),
                (dx + MARKER - 1, MARKER - 1),
            ]
        };
        if !red.is_empty() {
            c.draw_series(red.iter().map(|&p| {
                EmptyElement::at(p)
                    + Rectangle::new(square(0), FAIL_RED.filled())
                    + Rectangle::new(square(0), edge)
            }))?
            .label(*red_label)
            .legend(move |p| {
                EmptyElement::at(p)
                    + Rectangle::new(square(6), FAIL_RED.filled())
                    + Rectangle::new(square(6), edge)
            });
        }
        if !unknown.is_empty() {
            c.draw_series(
                unknown
                    .iter()
                    .map(|&p| Cross::new(p, MARKER, RECORDED.stroke_width(2))),
            )?
            .label(*unknown_label)
            .legend(|(x, y)| Cross::new((x + 6, y), MARKER, RECORDED.stroke_width(2)));
        }
        legend(&mut c, pos)
    }
}

fn closed(mut pts: Vec<(i32, i32)>) -> Vec<(i32, i32)> {
    if let Some(&first) = pts.first() {
        pts.push(first);
    }
    pts
}
