//! Polylines as the figures draw them: bands, zero-order holds, unjoined segments, and
//! clipping to a chart's box.

use plotters::prelude::{PathElement, ShapeStyle};

/// The outline of the band between `lo` and `hi` over `xs` (upper edge out, lower edge back),
/// to fill as one polygon.
pub(crate) fn band(xs: &[f64], lo: &[f64], hi: &[f64]) -> Vec<(f64, f64)> {
    let upper = xs.iter().zip(hi).map(|(&x, &y)| (x, y));
    let lower = xs.iter().zip(lo).rev().map(|(&x, &y)| (x, y));
    upper.chain(lower).collect()
}

/// Zero-order hold: value `v[k]` from `t0 + k dt` to `t0 + (k + 1) dt`, as a polyline.
pub(crate) fn stairs(t0: f64, dt: f64, v: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let mut ts = Vec::with_capacity(2 * v.len());
    let mut ys = Vec::with_capacity(2 * v.len());
    for (k, &y) in v.iter().enumerate() {
        ts.extend([t0 + k as f64 * dt, t0 + (k + 1) as f64 * dt]);
        ys.extend([y, y]);
    }
    (ts, ys)
}

/// A polyline as separate two-point segments. plotters joins thick polylines with mitres
/// whose inner vertex shoots far off at near-reversals (a jittery path in the hole), drawing
/// long false spikes; unjoined segments cannot.
pub(crate) fn segments(
    pts: impl IntoIterator<Item = (f64, f64)>,
    style: ShapeStyle,
) -> Vec<PathElement<(f64, f64)>> {
    let pts: Vec<(f64, f64)> = pts.into_iter().collect();
    pts.windows(2)
        .map(|w| PathElement::new(vec![w[0], w[1]], style))
        .collect()
}

/// The parts of a polyline inside the box `x` × `y`. plotters clamps points outside a chart
/// onto its border, which would draw false lines along the axes of a zoomed view.
pub(crate) fn clip(pts: &[(f64, f64)], x: (f64, f64), y: (f64, f64)) -> Vec<Vec<(f64, f64)>> {
    let mut pieces: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut current: Vec<(f64, f64)> = Vec::new();
    for w in pts.windows(2) {
        let Some((a, b)) = clip_segment(w[0], w[1], x, y) else {
            if !current.is_empty() {
                pieces.push(std::mem::take(&mut current));
            }
            continue;
        };
        if current.last() != Some(&a) {
            if !current.is_empty() {
                pieces.push(std::mem::take(&mut current));
            }
            current.push(a);
        }
        current.push(b);
        // A segment that leaves the box ends this piece.
        if b != w[1] {
            pieces.push(std::mem::take(&mut current));
        }
    }
    if !current.is_empty() {
        pieces.push(current);
    }
    if let [p] = pts {
        let inside = (x.0..=x.1).contains(&p.0) && (y.0..=y.1).contains(&p.1);
        if inside {
            pieces.push(vec![*p]);
        }
    }
    pieces
}

/// Liang–Barsky: the part of the segment a–b inside the box, if any.
fn clip_segment(
    a: (f64, f64),
    b: (f64, f64),
    x: (f64, f64),
    y: (f64, f64),
) -> Option<((f64, f64), (f64, f64))> {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-dx, a.0 - x.0),
        (dx, x.1 - a.0),
        (-dy, a.1 - y.0),
        (dy, y.1 - a.1),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    if t0 > t1 {
        return None;
    }
    let at = |t: f64| {
        if t == 0.0 {
            a
        } else if t == 1.0 {
            b
        } else {
            (a.0 + t * dx, a.1 + t * dy)
        }
    };
    Some((at(t0), at(t1)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clipping_keeps_only_the_inside() {
        let unit = ((0.0, 1.0), (0.0, 1.0));
        // In, out through the right edge, back in: two pieces, cut at x = 1.
        let pts = [(0.5, 0.5), (1.5, 0.5), (0.5, 0.6)];
        let pieces = clip(&pts, unit.0, unit.1);
        assert_eq!(pieces.len(), 2);
        assert_eq!(pieces[0], [(0.5, 0.5), (1.0, 0.5)]);
        assert_eq!(pieces[1].last(), Some(&(0.5, 0.6)));
        assert!((pieces[1][0].0 - 1.0).abs() < 1e-12);
        // Entirely outside, and a crossing segment with both ends outside.
        assert!(clip(&[(2.0, 2.0), (3.0, 2.0)], unit.0, unit.1).is_empty());
        let through = clip(&[(-1.0, 0.5), (2.0, 0.5)], unit.0, unit.1);
        assert_eq!(through, [vec![(0.0, 0.5), (1.0, 0.5)]]);
        // A path fully inside stays one piece with every point.
        let inside = [(0.1, 0.1), (0.2, 0.3), (0.4, 0.2)];
        assert_eq!(clip(&inside, unit.0, unit.1), [inside.to_vec()]);
    }

    #[test]
    fn stairs_hold_each_value_for_one_step() {
        let (t, y) = stairs(0.0, 0.5, &[1.0, 2.0]);
        assert_eq!(t, [0.0, 0.5, 0.5, 1.0]);
        assert_eq!(y, [1.0, 1.0, 2.0, 2.0]);
    }
}
