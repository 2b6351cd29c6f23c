//! Central finite differences: the one checker every analytic-derivative test in vicpilco
//! uses.
//!
//! Reverse-mode code is checked through directional derivatives: for a function
//! `f: Rⁿ → Rᵐ` with VJP `x̄ = Jᵀ ȳ`, pick random `ȳ` and direction `v`, and compare
//! `ȳᵀ J v` (from the VJP: `x̄ · v`) with the 4th-order central difference of `ȳ · f` along `v`.

/// 5-point central difference of a scalar function along `dir` at `x`, step `h`.
pub fn directional(f: &mut dyn FnMut(&[f64]) -> f64, x: &[f64], dir: &[f64], h: f64) -> f64 {
    let at = |t: f64| -> Vec<f64> { x.iter().zip(dir).map(|(a, d)| a + t * d).collect() };
    let (f2p, f1p, f1m, f2m) = (f(&at(2.0 * h)), f(&at(h)), f(&at(-h)), f(&at(-2.0 * h)));
    (-f2p + 8.0 * f1p - 8.0 * f1m + f2m) / (12.0 * h)
}

/// Full Jacobian by 5-point central differences (row i = output i), for small problems.
pub fn jacobian(f: &mut dyn FnMut(&[f64]) -> Vec<f64>, x: &[f64], h: f64) -> Vec<Vec<f64>> {
    let n = x.len();
    let m = f(x).len();
    let mut jac = vec![vec![0.0; n]; m];
    let mut xp = x.to_vec();
    for j in 0..n {
        let mut eval = |t: f64| {
            xp[j] = x[j] + t;
            let y = f(&xp);
            xp[j] = x[j];
            y
        };
        let (a, b, c, d) = (eval(2.0 * h), eval(h), eval(-h), eval(-2.0 * h));
        for i in 0..m {
            jac[i][j] = (-a[i] + 8.0 * b[i] - 8.0 * c[i] + d[i]) / (12.0 * h);
        }
    }
    jac
}

/// Relative agreement of an analytic and a finite-difference number:
/// `|a − b| / max(|a|, |b|, floor)`.
pub fn rel_diff(analytic: f64, numeric: f64, floor: f64) -> f64 {
    (analytic - numeric).abs() / analytic.abs().max(numeric.abs()).max(floor)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directional_derivative_of_a_cubic_is_exact() {
        let mut f = |x: &[f64]| x[0].powi(3) + 2.0 * x[0] * x[1];
        let d = directional(&mut f, &[1.5, -0.5], &[1.0, 2.0], 1e-3);
        // ∇f = (3x² + 2y, 2x) = (5.75, 3); · (1, 2) = 11.75
        assert!((d - 11.75).abs() < 1e-9, "{d}");
    }

    #[test]
    fn jacobian_of_a_linear_map() {
        let mut f = |x: &[f64]| vec![x[0] + 2.0 * x[1], -x[1]];
        let j = jacobian(&mut f, &[0.3, 0.7], 1e-3);
        assert!((j[0][0] - 1.0).abs() < 1e-10 && (j[0][1] - 2.0).abs() < 1e-10);
        assert!((j[1][0]).abs() < 1e-10 && (j[1][1] + 1.0).abs() < 1e-10);
    }
}
