//! (e) Arm experiments only: the x–y path of every roll-out against the wall and the hole, and
//! y(t) of the final policy from fresh starts (vilta-var).

use super::{
    chart, clip, gradient, legend, place_legend, range, short, Axes, DrawResult, Figure, Occupied,
};
use super::{segments, FAIL_RED, GREY, OK_GREEN, RECORDED};
use crate::data::{FinalEval, Geometry, Rollout};
use plotters::coord::Shift;
use plotters::prelude::*;

const WALL_FILL: RGBColor = RGBColor(215, 215, 215);
const WALL_EDGE: RGBColor = RGBColor(90, 90, 90);
const HOLE: &str = "hole channel (y range)";
const WALL: &str = "wall";

pub(crate) struct Paths<'a> {
    pub rollouts: &'a [Rollout],
    pub geometry: &'a Geometry,
    pub start_y_range: Option<(f64, f64)>,
}

/// The roll-out's within-step path when it was recorded, else its states a step apart.
fn xy(r: &Rollout) -> Vec<(f64, f64)> {
    if !r.path.is_empty() {
        return r.path.iter().map(|p| (p.x, p.y)).collect();
    }
    let pts = r.true_states.iter();
    pts.filter_map(|s| Some((*s.first()?, *s.get(1)?)))
        .collect()
}

/// Everything both panels of the paths figure draw.
struct Scene<'a> {
    g: &'a Geometry,
    paths: Vec<(u64, Vec<(f64, f64)>)>,
    /// Legend entries only for the initial, the first and the last update: the colour
    /// gradient orders the ones in between.
    path_labels: Vec<Option<String>>,
    n_updates: usize,
    start: Option<(f64, (f64, f64))>,
    /// A fixed start position (no start interval), marked by a dot.
    start_point: Option<(f64, f64)>,
    /// Where each roll-out the system ended early stopped (a diverged arm), marked by a cross.
    ended_early: Vec<(f64, f64)>,
}

const ENDED_EARLY: &str = "end of a roll-out the system ended early (on the border: beyond it)";
const START: &str = "start";

impl Figure for Paths<'_> {
    fn size(&self) -> (u32, u32) {
        (1600, 760)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let g = self.geometry;
        let paths: Vec<(u64, Vec<(f64, f64)>)> =
            self.rollouts.iter().map(|r| (r.episode, xy(r))).collect();
        let n_updates = paths.iter().map(|p| p.0).max().unwrap_or(0).max(1) as usize;
        let mut labelled = std::collections::BTreeSet::new();
        let first_update = paths.iter().map(|p| p.0).filter(|&e| e > 0).min();
        // The first, middle and last updates label the colour gradient.
        let middle = first_update.map(|f| (f + n_updates as u64) / 2);
        let path_labels = paths
            .iter()
            .map(|(episode, _)| {
                let e = *episode;
                let wanted = e == 0
                    || Some(e) == first_update
                    || Some(e) == middle
                    || e as usize == n_updates;
                if !wanted || !labelled.insert(e) {
                    return None;
                }
                Some(match e {
                    0 => "initial roll-out".to_string(),
                    e => format!("update {e}"),
                })
            })
            .collect();
        let start_x = paths.iter().find_map(|p| p.1.first().map(|q| q.0));
        let first_point = paths.iter().find_map(|p| p.1.first().copied());
        let ended_early: Vec<(f64, f64)> = self
            .rollouts
            .iter()
            .zip(&paths)
            .filter(|(r, _)| r.stopped_early.is_some())
            .filter_map(|(_, p)| p.1.last().copied())
            .collect();
        let scene = Scene {
            g,
            start: start_x.zip(self.start_y_range),
            start_point: first_point.filter(|_| self.start_y_range.is_none()),
            paths,
            path_labels,
            n_updates,
            ended_early,
        };

        let (full, zoom) = root.split_horizontally(900);
        let sy = self.start_y_range.map(|(a, b)| [a, b]).unwrap_or_default();
        let hole = [g.hole_y - g.hole_r, g.hole_y + g.hole_r];
        // The view fits the roll-outs that ran to the end; one that diverged (the arm flung
        // across the workspace) is cut at the border and its end marked, not allowed to
        // shrink the rest into a corner.
        let kept = self.rollouts.iter().zip(&scene.paths);
        let kept: Vec<&Vec<(f64, f64)>> = kept
            .filter(|(r, _)| r.stopped_early.is_none())
            .map(|(_, p)| &p.1)
            .collect();
        let xs = kept.iter().flat_map(|p| p.iter().map(|q| q.0));
        let x = range(xs.chain([g.wall_x, g.end_x]), 0.08);
        let ys = kept.iter().flat_map(|p| p.iter().map(|q| q.1));
        let y = range(ys.chain(hole).chain(sy), 0.08);
        scene.panel(&full, "TCP paths of every roll-out", x, y, true)?;

        // Same metres per pixel on both axes of the 700 × 700 zoom panel, so the channel keeps
        // its shape.
        let depth = (g.end_x - g.wall_x).abs().max(4.0 * g.hole_r).max(1e-3);
        let x = (g.wall_x - 0.3 * depth, g.end_x + 0.1 * depth);
        let half = 0.5 * (x.1 - x.0);
        scene.panel(
            &zoom,
            "near the hole",
            x,
            (g.hole_y - half, g.hole_y + half),
            false,
        )
    }
}

impl Scene<'_> {
    fn panel<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        title: &str,
        x: (f64, f64),
        y: (f64, f64),
        with_legend: bool,
    ) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let g = self.g;
        let (y_lo, y_hi) = (g.hole_y - g.hole_r, g.hole_y + g.hole_r);
        let face_label = format!(
            "wall face x = {} m, hole y = {} ± {} m",
            short(g.wall_x),
            short(g.hole_y),
            short(g.hole_r)
        );
        let start_label = self
            .start
            .map(|(_, (a, b))| format!("start interval y ∈ [{}, {}] m", short(a), short(b)));
        let mut axes = Axes {
            title,
            x,
            y,
            x_desc: "x [m]",
            y_desc: "y [m]",
            integer_x: false,
        };
        let pos = with_legend.then(|| {
            let mut labels = vec![WALL.to_string(), face_label.clone()];
            labels.extend(self.path_labels.iter().flatten().cloned());
            labels.extend(start_label.clone());
            labels.extend(self.start_point.map(|_| START.to_string()));
            if !self.ended_early.is_empty() {
                labels.push(ENDED_EARLY.into());
            }
            let mut occ = Occupied::default();
            occ.band(&[g.wall_x, x.1], &[y.0, y.0], &[y.1, y.1]);
            self.paths
                .iter()
                .for_each(|p| occ.line(p.1.iter().copied()));
            if let Some((x0, (a, b))) = self.start {
                occ.line([(x0, a), (x0, b)]);
            }
            place_legend(&occ, &mut axes, area.dim_in_pixel(), &labels)
        });
        let y = axes.y;
        let mut c = chart(area, &axes)?;

        // The wall is solid everywhere right of its face except the channel, which ends at end_x.
        let blocks = [
            [(g.wall_x, y.0), (x.1, y_lo)],
            [(g.wall_x, y_hi), (x.1, y.1)],
            [(g.end_x, y_lo), (x.1, y_hi)],
        ];
        let blocks = blocks.map(|b| Rectangle::new(b, WALL_FILL.filled()));
        c.draw_series(blocks)?
            .label(WALL)
            .legend(|(x, y)| Rectangle::new([(x, y - 6), (x + 18, y + 6)], WALL_FILL.filled()));
        let outline = [
            vec![(g.wall_x, y.0), (g.wall_x, y_lo), (g.end_x, y_lo)],
            vec![(g.end_x, y_lo), (g.end_x, y_hi)],
            vec![(g.end_x, y_hi), (g.wall_x, y_hi), (g.wall_x, y.1)],
        ];
        let outline = outline.map(|l| PathElement::new(l, WALL_EDGE.stroke_width(2)));
        c.draw_series(outline)?
            .label(face_label)
            .legend(|(x, y)| PathElement::new([(x, y), (x + 18, y)], WALL_EDGE.stroke_width(2)));

        for ((episode, pts), label) in self.paths.iter().zip(&self.path_labels) {
            let colour = match *episode {
                0 => GREY,
                e => gradient(e as usize - 1, self.n_updates),
            };
            let pieces = clip(pts, x, y);
            let lines = pieces
                .into_iter()
                .flat_map(|p| segments(p, colour.stroke_width(2)));
            let s = c.draw_series(lines)?;
            if let Some(label) = label {
                s.label(label).legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 18, y)], colour.stroke_width(3))
                });
            }
        }
        if let (Some((x0, (a, b))), Some(label)) = (self.start, start_label) {
            let segment = clip(&[(x0, a), (x0, b)], x, y);
            let segment = segment
                .into_iter()
                .map(|p| PathElement::new(p, RECORDED.stroke_width(4)));
            c.draw_series(segment)?
                .label(label)
                .legend(|(x, y)| PathElement::new([(x, y), (x + 18, y)], RECORDED.stroke_width(4)));
        }
        let inside = |p: &&(f64, f64)| (x.0..=x.1).contains(&p.0) && (y.0..=y.1).contains(&p.1);
        if let Some(p) = self.start_point.filter(|p| inside(&p)) {
            c.draw_series(std::iter::once(Circle::new(p, 6, RECORDED.filled())))?
                .label(START)
                .legend(|(x, y)| Circle::new((x + 9, y), 5, RECORDED.filled()));
        }
        // In the full view an end outside it is marked on the border, where the cut path
        // leaves; the zoom marks only the ends inside it.
        let on_view = |p: &(f64, f64)| (p.0.clamp(x.0, x.1), p.1.clamp(y.0, y.1));
        let crosses: Vec<(f64, f64)> = match with_legend {
            true => self.ended_early.iter().map(on_view).collect(),
            false => self.ended_early.iter().filter(inside).copied().collect(),
        };
        if !crosses.is_empty() {
            c.draw_series(
                crosses
                    .into_iter()
                    .map(|p| Cross::new(p, 8, FAIL_RED.stroke_width(3))),
            )?
            .label(ENDED_EARLY)
            .legend(|(x, y)| Cross::new((x + 9, y), 6, FAIL_RED.stroke_width(3)));
        }
        match pos {
            Some(pos) => legend(&mut c, pos),
            None => Ok(()),
        }
    }
}

pub(crate) struct FinalEvalPlot<'a> {
    pub evals: &'a [FinalEval],
    /// The update whose policy this is, when the summary names it.
    pub update: Option<u64>,
    pub geometry: Option<&'a Geometry>,
    /// Without a time step the x axis counts steps.
    pub dt: Option<f64>,
}

/// A start's success and its curve of (time, value) points.
type Curve = (bool, Vec<(f64, f64)>);

/// The contact force magnitude |f| at each step end, from a true state's (f_x, f_y) at
/// entries 4 and 5 (the arm's state layout); `None` for states without them.
fn force_curve(e: &FinalEval, dt: f64) -> Option<Vec<(f64, f64)>> {
    let pts = e.true_states.iter().enumerate();
    pts.map(|(k, s)| Some((k as f64 * dt, s.get(4)?.hypot(*s.get(5)?))))
        .collect()
}

impl FinalEvalPlot<'_> {
    /// Every start's |f|(t) with its success, when every start recorded forces.
    fn force_curves(&self) -> Option<Vec<Curve>> {
        let dt = self.dt.unwrap_or(1.0);
        let curves: Option<Vec<_>> = self
            .evals
            .iter()
            .map(|e| Some((e.success, force_curve(e, dt)?)))
            .collect();
        curves.filter(|c| !c.is_empty() && c.iter().all(|(_, f)| !f.is_empty()))
    }

    /// |f|(t) of every start, coloured as in the y(t) panel: a start that inserts by ramming
    /// the end wall looks like any other in y(t).
    fn draw_forces<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        forces: &[Curve],
    ) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let mut peaks: Vec<f64> = forces
            .iter()
            .map(|(_, c)| c.iter().map(|p| p.1).fold(0.0, f64::max))
            .collect();
        peaks.sort_by(f64::total_cmp);
        let median = peaks[peaks.len() / 2];
        let highest = peaks[peaks.len() - 1];
        let title = format!(
            "Contact force |f| from the same starts: largest per start median {median:.0} N, \
             at most {highest:.0} N"
        );
        let x = range(forces.iter().flat_map(|c| c.1.iter().map(|q| q.0)), 0.0);
        let y = range(
            forces
                .iter()
                .flat_map(|c| c.1.iter().map(|q| q.1))
                .chain([0.0]),
            0.08,
        );
        let axes = Axes {
            title: &title,
            x,
            y,
            x_desc: if self.dt.is_some() {
                "time [s]"
            } else {
                "step"
            },
            y_desc: "|f| [N]",
            integer_x: false,
        };
        let mut c = chart(area, &axes)?;
        for (success, curve) in forces {
            let colour = if *success { OK_GREEN } else { FAIL_RED };
            c.draw_series(segments(curve.iter().copied(), colour.stroke_width(2)))?;
        }
        Ok(())
    }
}

impl Figure for FinalEvalPlot<'_> {
    fn size(&self) -> (u32, u32) {
        match self.force_curves() {
            Some(_) => (1000, 960),
            None => (1000, 600),
        }
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let dt = self.dt.unwrap_or(1.0);
        let root = &match self.force_curves() {
            Some(f) => {
                let (top, bottom) = root.split_vertically(root.dim_in_pixel().1 * 3 / 5);
                self.draw_forces(&bottom, &f)?;
                top
            }
            None => root.clone(),
        };
        let curves: Vec<Curve> = self
            .evals
            .iter()
            .map(|e| {
                if !e.path.is_empty() {
                    return (
                        e.success,
                        e.path.iter().map(|p| (p.step * dt, p.y)).collect(),
                    );
                }
                let pts = e.true_states.iter().enumerate();
                let pts = pts.filter_map(|(k, s)| Some((k as f64 * dt, *s.get(1)?)));
                (e.success, pts.collect())
            })
            .collect();
        let hole = self
            .geometry
            .map(|g| (g.hole_y - g.hole_r, g.hole_y + g.hole_r));
        let x = range(curves.iter().flat_map(|c| c.1.iter().map(|q| q.0)), 0.0);
        let ys = curves.iter().flat_map(|c| c.1.iter().map(|q| q.1));
        let y = range(ys.chain(hole.map(|h| [h.0, h.1]).unwrap_or_default()), 0.08);
        let n = curves.len();
        let ok = curves.iter().filter(|c| c.0).count();
        let title = match self.update {
            Some(u) => {
                format!("Final policy (update {u}) from {n} fresh starts: {ok} of {n} insert")
            }
            None => format!("Final policy from {n} fresh starts: {ok} of {n} insert"),
        };
        let mut axes = Axes {
            title: &title,
            x,
            y,
            x_desc: if self.dt.is_some() {
                "time [s]"
            } else {
                "step"
            },
            y_desc: "y [m]",
            integer_x: false,
        };
        let groups = [(true, OK_GREEN, "inserts"), (false, FAIL_RED, "fails")].map(
            |(success, colour, word)| {
                let count = curves.iter().filter(|c| c.0 == success).count();
                (success, colour, format!("{word} ({count} of {n})"), count)
            },
        );
        let mut occ = Occupied::default();
        curves.iter().for_each(|c| occ.line(c.1.iter().copied()));
        let mut labels: Vec<String> = hole.iter().map(|_| HOLE.to_string()).collect();
        labels.extend(groups.iter().filter(|g| g.3 > 0).map(|g| g.2.clone()));
        let pos = place_legend(&occ, &mut axes, root.dim_in_pixel(), &labels);
        let mut c = chart(root, &axes)?;
        if let Some((lo, hi)) = hole {
            c.draw_series(std::iter::once(Rectangle::new(
                [(x.0, lo), (x.1, hi)],
                WALL_EDGE.mix(0.35).filled(),
            )))?
            .label(HOLE)
            .legend(|(x, y)| {
                Rectangle::new([(x, y - 6), (x + 18, y + 6)], WALL_EDGE.mix(0.35).filled())
            });
        }
        for (success, colour, label, _) in groups {
            let mut group = curves.iter().filter(|c| c.0 == success);
            if let Some(first) = group.next() {
                c.draw_series(segments(first.1.iter().copied(), colour.stroke_width(2)))?
                    .label(label)
                    .legend(move |(x, y)| {
                        PathElement::new([(x, y), (x + 18, y)], colour.stroke_width(3))
                    });
            }
            for curve in group {
                c.draw_series(segments(curve.1.iter().copied(), colour.stroke_width(2)))?;
            }
        }
        legend(&mut c, pos)
    }
}
