//! Penalty contact of the point peg (TCP) with the wall, the hole channel and the insertion
//! spring (§5-2-1, §5-2-2).
//!
//! Forces are the wrench W_ext the TCP exerts **on the environment** (sign of eq. 2-7: the
//! plant feels −W). Each surface pushes back with K_env·penetration, plus b_env·(speed into
//! the surface) only while the TCP moves into it, plus viscous tangential friction C_f·v_t while
//! touching it. The insertion spring F = k_ins·(x − x_catch) resists +x in the channel from the
//! catch point until the release point (or, with `hold`, keeps its release value to the end).
//!
//! The `in_hole` latch decides whether the face or the channel walls act at x > x_wall: it is
//! set when |y − y_hole| < r (a peg sliding on the face drops in) and cleared when x ≤ x_wall
//! (a peg pressed into the face beside the hole is never pushed sideways into it).
//! [`in_hole`] evaluates it from the latch carried between integrator steps and the current
//! position, so a peg entering mid-step never feels the face.

use super::params::{ContactParams, Geometry};

/// Contact evaluated at one TCP position/velocity.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Contact {
    /// Force (x, y) the TCP exerts on the environment (N).
    pub w: [f64; 2],
    /// Touching the wall face.
    pub face: bool,
    /// Touching the channel's end wall.
    pub end: bool,
    /// Touching a channel side wall.
    pub side: bool,
    /// Compressing the insertion spring.
    pub spring: bool,
    /// The `in_hole` state used.
    pub in_hole: bool,
}

impl Contact {
    /// Any surface touched (face, end wall or side wall; the spring does not count).
    pub fn any(&self) -> bool {
        self.face || self.end || self.side
    }
    /// Per task axis (x, y): is a K_env surface engaged along it? (x: face or end wall;
    /// y: side walls.) Used for B_d = 2ζ·sqrt((K_d + K_e)·M_d).
    pub fn stiff_axes(&self) -> [bool; 2] {
        [self.face || self.end, self.side]
    }
}

/// Effective in-hole state at (x, y) given the latch carried from the last step.
#[inline]
pub fn in_hole(g: &Geometry, latch: bool, x: f64, y: f64) -> bool {
    x > g.wall_x() && (latch || (y - g.hole_center[1]).abs() < g.hole_radius)
}

/// Contact force at TCP position `p` and velocity `v`.
#[inline]
pub fn contact(g: &Geometry, cp: &ContactParams, latch: bool, p: [f64; 2], v: [f64; 2]) -> Contact {
    let mut c = Contact::default();
    let wall = g.wall_x();
    let (x, y) = (p[0], p[1]);
    if x <= wall {
        return c;
    }
    let push =
        |pen: f64, v_in: f64| cp.k_env * pen + if v_in > 0.0 { cp.b_env * v_in } else { 0.0 };
    if !in_hole(g, latch, x, y) {
        c.face = true;
        c.w = [push(x - wall, v[0]), cp.friction * v[1]];
        return c;
    }
    c.in_hole = true;
    let dy = y - g.hole_center[1];
    let r = g.hole_radius;
    if dy > r {
        c.side = true;
        c.w[1] += push(dy - r, v[1]);
        c.w[0] += cp.friction * v[0];
    } else if dy < -r {
        c.side = true;
        c.w[1] -= push(-r - dy, -v[1]);
        c.w[0] += cp.friction * v[0];
    }
    let end = g.end_x();
    if x > end {
        c.end = true;
        c.w[0] += push(x - end, v[0]);
        c.w[1] += cp.friction * v[1];
    }
    let catch = g.spring_catch_x();
    let release = g.spring_release_x();
    if x >= catch && (x < release || g.hold) {
        c.spring = true;
        c.w[0] += g.k_insert * (x.min(release) - catch);
    }
    c
}

/// Potential energy stored in the surfaces and the insertion spring, the integral of
/// [`contact`]'s position-dependent forces. The spring's force depends on x alone (with or
/// without `hold`), so it is conservative too: past the release point its energy stays at
/// ½k(r − c)² (no force) or, held, grows linearly with the constant force k(r − c).
pub fn potential(g: &Geometry, cp: &ContactParams, latch: bool, p: [f64; 2]) -> f64 {
    let (x, y) = (p[0], p[1]);
    let wall = g.wall_x();
    if x <= wall {
        return 0.0;
    }
    let half_k = 0.5 * cp.k_env;
    if !in_hole(g, latch, x, y) {
        return half_k * (x - wall).powi(2);
    }
    let mut e = 0.0;
    let over = (y - g.hole_center[1]).abs() - g.hole_radius;
    if over > 0.0 {
        e += half_k * over * over;
    }
    if x > g.end_x() {
        e += half_k * (x - g.end_x()).powi(2);
    }
    let catch = g.spring_catch_x();
    let release = g.spring_release_x();
    if x >= catch {
        let engaged = x.min(release) - catch;
        e += 0.5 * g.k_insert * engaged * engaged;
        if g.hold && x > release {
            e += g.k_insert * engaged * (x - release);
        }
    }
    e
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn surfaces_and_latch() {
        let g = Geometry::default();
        let cp = ContactParams::default();
        // free space
        assert_eq!(
            contact(&g, &cp, false, [0.6, 0.0], [1.0, 1.0]).w,
            [0.0, 0.0]
        );
        // face, moving in and sliding: spring + damping + friction
        let c = contact(&g, &cp, false, [0.651, 0.0], [0.1, 0.2]);
        assert!(c.face && !c.in_hole);
        assert!((c.w[0] - (100.0 + 5.0)).abs() < 1e-9 && (c.w[1] - 0.1).abs() < 1e-12);
        // moving out: no damping, force stays ≥ 0
        let c = contact(&g, &cp, false, [0.651, 0.0], [-0.1, 0.0]);
        assert!((c.w[0] - 100.0).abs() < 1e-9);
        // pressed into the face just outside the channel: face, not pushed sideways
        let c = contact(&g, &cp, false, [0.651, 0.2052], [0.0, 0.0]);
        assert!(c.face && !c.side && c.w[1] == 0.0);
        // inside the channel (by position or latch): side wall pushes back towards the centre
        let c = contact(&g, &cp, true, [0.68, 0.2052], [0.0, 0.0]);
        assert!(c.side && c.in_hole && (c.w[1] - 1e5 * 0.0002).abs() < 1e-6);
        let c = contact(&g, &cp, true, [0.68, 0.1948], [0.0, 0.0]);
        assert!(c.side && (c.w[1] + 1e5 * 0.0002).abs() < 1e-6);
        // spring: 300 (x − 0.70) until 0.73, then 0 (or 9 N held), end wall at 0.75
        let f = |x: f64, g: &Geometry| contact(g, &cp, true, [x, 0.2], [0.0, 0.0]).w[0];
        assert_eq!(f(0.69, &g), 0.0);
        assert!((f(0.72, &g) - 6.0).abs() < 1e-9);
        assert_eq!(f(0.74, &g), 0.0);
        assert!((f(0.7501, &g) - 10.0).abs() < 1e-6);
        let held = Geometry {
            hold: true,
            ..g.clone()
        };
        assert!((f(0.74, &held) - 9.0).abs() < 1e-9);
        // leaving through the face clears the effective state
        assert!(!in_hole(&g, true, g.wall_x(), 0.2));
        // shifting moves everything
        let s = g.shifted(0.05, 0.0);
        assert!((s.wall_x() - 0.70).abs() < 1e-15 && (s.end_x() - 0.80).abs() < 1e-15);
    }

    /// At rest every contact force is the gradient of `potential` (the force the arm exerts
    /// is ∂U/∂p), the insertion spring's beyond its release point included, held or not.
    #[test]
    fn potential_is_the_integral_of_the_resting_forces() {
        let cp = ContactParams::default();
        let free = Geometry::default();
        let held = Geometry {
            hold: true,
            ..free.clone()
        };
        let h = 1e-7;
        for g in [&free, &held] {
            for (latch, p) in [
                (false, [0.66, 0.0]),
                (true, [0.69, 0.2]),
                (true, [0.72, 0.2]),
                (true, [0.74, 0.2]),
                (true, [0.7503, 0.2]),
                (true, [0.72, 0.2053]),
                (true, [0.74, 0.1946]),
            ] {
                let w = contact(g, &cp, latch, p, [0.0, 0.0]).w;
                for axis in 0..2 {
                    let at = |d: f64| {
                        let mut q = p;
                        q[axis] += d;
                        potential(g, &cp, latch, q)
                    };
                    let slope = (at(h) - at(-h)) / (2.0 * h);
                    assert!(
                        (slope - w[axis]).abs() <= 1e-5 * (1.0 + w[axis].abs()),
                        "hold {} at {p:?}, axis {axis}: ∂U = {slope}, force {}",
                        g.hold,
                        w[axis]
                    );
                }
            }
        }
    }
}
