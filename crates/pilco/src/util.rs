//! Small dense helpers shared by the blocks.

use crate::error::{PilcoError, Result};
use faer::{Mat, MatRef};

/// Symmetrise in place: `A ← (A + Aᵀ)/2`.
pub(crate) fn symmetrise(a: &mut Mat<f64>) {
    let n = a.nrows();
    debug_assert_eq!(n, a.ncols());
    for i in 0..n {
        for j in 0..i {
            let v = 0.5 * (a[(i, j)] + a[(j, i)]);
            a[(i, j)] = v;
            a[(j, i)] = v;
        }
    }
}

/// The blocks' input check: a mean of length `d` and a `d`×`d` covariance, else
/// [`PilcoError::Shape`] naming `block`.
pub(crate) fn check_input(block: &str, d: usize, m: &[f64], s: MatRef<'_, f64>) -> Result<()> {
    if m.len() == d && s.nrows() == d && s.ncols() == d {
        return Ok(());
    }
    Err(PilcoError::Shape {
        what: format!("{block} input mean and covariance"),
        expected: format!("length {d} and {d}×{d}"),
        got: format!("length {} and {}×{}", m.len(), s.nrows(), s.ncols()),
    })
}

/// [`check_input`] for the blocks whose forward cannot return an error: a wrong shape is a bug
/// in the caller's wiring, stopped with the same message rather than read out of bounds.
#[track_caller]
pub(crate) fn assert_input(block: &str, d: usize, m: &[f64], s: MatRef<'_, f64>) {
    if let Err(e) = check_input(block, d, m, s) {
        panic!("{e}");
    }
}
