//! The oracle README's tolerance rule: compare a whole array against its largest entry.

use crate::case::Tensor;

/// Which tolerance an array gets (oracle README, "Tolerance for a re-implementation").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Class {
    /// Outputs that are neither covariances nor derivatives (M, V, C, L, J, nlml, ...).
    Value,
    /// Covariances and every derivative array.
    CovOrDerivative,
}

/// Tolerances for one case; `*_induceX` cases of gp1 get the looser pair the README gives.
#[derive(Clone, Copy, Debug)]
pub struct Tolerance {
    /// Largest allowed [`Comparison::rel_err`] of a [`Class::Value`] array.
    pub value: f64,
    /// Largest allowed [`Comparison::rel_err`] of a [`Class::CovOrDerivative`] array.
    pub cov_or_derivative: f64,
}

impl Tolerance {
    /// Every case but gp1's `*_induceX`: 1e-9 for values, 1e-8 for covariances and derivatives.
    pub const STANDARD: Self = Self {
        value: 1e-9,
        cov_or_derivative: 1e-8,
    };
    /// gp1's `*_induceX` cases, made ill-conditioned by the 10⁻⁶ ridge on `K_mm`: 1e-8, 1e-7.
    pub const ILL_CONDITIONED: Self = Self {
        value: 1e-8,
        cov_or_derivative: 1e-7,
    };

    /// The tolerances for a case of `kind` (the file's `kind`) named `case` (its `case`):
    /// [`ILL_CONDITIONED`](Self::ILL_CONDITIONED) for gp1's `*_induceX`, else
    /// [`STANDARD`](Self::STANDARD).
    pub fn for_case(kind: &str, case: &str) -> Self {
        if kind == "gp1" && case.ends_with("_induceX") {
            Self::ILL_CONDITIONED
        } else {
            Self::STANDARD
        }
    }
}

/// The comparison of one output array.
#[derive(Clone, Debug)]
pub struct Comparison {
    /// The oracle field compared (e.g. `dSds`, `prop1.dMdp`); on a shape mismatch it also
    /// shows both shapes.
    pub field: String,
    /// Which of the case's two tolerances applied.
    pub class: Class,
    /// `max |ours − oracle|` over the entries; `+∞` on a shape mismatch or a NaN difference.
    pub max_abs_diff: f64,
    /// `max_abs_diff / max(max|oracle|, floor)`, floor 1 for values and 1e-3 otherwise.
    pub rel_err: f64,
    /// The bound `rel_err` must not exceed: the case's [`Tolerance`] for `class`.
    pub tol: f64,
    /// Whether the shapes agree once size-1 axes are dropped (a scalar matches `[1]`).
    pub shape_ok: bool,
}

impl Comparison {
    /// Shapes agree and `rel_err ≤ tol` (NaN in either array fails).
    pub fn passed(&self) -> bool {
        self.shape_ok && self.rel_err <= self.tol
    }
}

/// Compare our array `got` with the oracle's `want` by the README's rule:
/// `max |got − want| / max(max |want|, floor)` against `tol.value` (floor 1) for
/// [`Class::Value`], `tol.cov_or_derivative` (floor 1e-3) otherwise. Covariance derivatives
/// must already be symmetrised on both sides. A shape mismatch gives a failing comparison;
/// `field` is only the label reported.
pub fn compare(
    field: &str,
    class: Class,
    got: &Tensor,
    want: &Tensor,
    tol: Tolerance,
) -> Comparison {
    let tol = match class {
        Class::Value => tol.value,
        Class::CovOrDerivative => tol.cov_or_derivative,
    };
    // Shapes of size-1 axes may legitimately differ in representation (scalar vs [1]).
    let squeeze = |s: &[usize]| s.iter().copied().filter(|&d| d != 1).collect::<Vec<_>>();
    if squeeze(&got.shape) != squeeze(&want.shape) || got.data.len() != want.data.len() {
        return Comparison {
            field: format!("{field} (shape {:?} vs oracle {:?})", got.shape, want.shape),
            class,
            max_abs_diff: f64::INFINITY,
            rel_err: f64::INFINITY,
            tol,
            shape_ok: false,
        };
    }
    let mut max_abs_diff = 0.0f64;
    for (g, w) in got.data.iter().zip(&want.data) {
        let d = (g - w).abs();
        // NaN must fail, so do not let f64::max swallow it.
        max_abs_diff = if d.is_nan() {
            f64::INFINITY
        } else {
            max_abs_diff.max(d)
        };
    }
    let floor = match class {
        Class::Value => 1.0,
        Class::CovOrDerivative => 1e-3,
    };
    let rel_err = max_abs_diff / want.max_abs().max(floor);
    Comparison {
        field: field.to_string(),
        class,
        max_abs_diff,
        rel_err,
        tol,
        shape_ok: true,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_to_the_largest_entry() {
        let want = Tensor::from_vec(&[100.0, 1e-6]);
        let got = Tensor::from_vec(&[100.0 + 5e-8, 1.05e-6]);
        let c = compare("x", Class::Value, &got, &want, Tolerance::STANDARD);
        assert!(c.passed(), "{c:?}");
        let got = Tensor::from_vec(&[100.0 + 5e-6, 1e-6]);
        assert!(!compare("x", Class::Value, &got, &want, Tolerance::STANDARD).passed());
    }

    #[test]
    fn nan_and_shape_mismatch_fail() {
        let want = Tensor::from_vec(&[1.0, 2.0]);
        let got = Tensor::from_vec(&[1.0, f64::NAN]);
        assert!(!compare("x", Class::Value, &got, &want, Tolerance::STANDARD).passed());
        let got = Tensor::from_vec(&[1.0]);
        assert!(!compare("x", Class::Value, &got, &want, Tolerance::STANDARD).passed());
    }
}
