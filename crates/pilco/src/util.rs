//! Small dense helpers shared by the blocks.

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

/// Panic with a clear message when a forward input has the wrong shape.
#[track_caller]
pub(crate) fn assert_input(block: &str, d: usize, m: &[f64], s: MatRef<'_, f64>) {
    assert!(
        m.len() == d && s.nrows() == d && s.ncols() == d,
        "{block}: input mean has length {} and covariance {}×{}, expected {d} and {d}×{d}",
        m.len(),
        s.nrows(),
        s.ncols()
    );
}
