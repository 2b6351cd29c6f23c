//! 3×3 matrix helpers on plain arrays (row-major `m[row][col]`), all on the stack.

/// A 3-vector.
pub type V3 = [f64; 3];
/// A 3×3 matrix, `m[row][col]`.
pub type M3 = [[f64; 3]; 3];

/// m · v.
#[inline]
pub fn mul_mv(m: &M3, v: &V3) -> V3 {
    [
        m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
        m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
        m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2],
    ]
}

/// mᵀ · v.
#[inline]
pub fn mul_mtv(m: &M3, v: &V3) -> V3 {
    [
        m[0][0] * v[0] + m[1][0] * v[1] + m[2][0] * v[2],
        m[0][1] * v[0] + m[1][1] * v[1] + m[2][1] * v[2],
        m[0][2] * v[0] + m[1][2] * v[1] + m[2][2] * v[2],
    ]
}

/// Determinant.
#[inline]
pub fn det(m: &M3) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// Solves m · x = b by Cramer's rule (fine for the well-conditioned 3×3 systems here).
/// Returns non-finite values when m is singular; callers check `det` first where it matters.
#[inline]
pub fn solve(m: &M3, b: &V3) -> V3 {
    // Cofactors of the first row are reused for the determinant.
    let c00 = m[1][1] * m[2][2] - m[1][2] * m[2][1];
    let c01 = m[1][2] * m[2][0] - m[1][0] * m[2][2];
    let c02 = m[1][0] * m[2][1] - m[1][1] * m[2][0];
    let d = m[0][0] * c00 + m[0][1] * c01 + m[0][2] * c02;
    let inv_d = 1.0 / d;
    let c10 = m[0][2] * m[2][1] - m[0][1] * m[2][2];
    let c11 = m[0][0] * m[2][2] - m[0][2] * m[2][0];
    let c12 = m[0][1] * m[2][0] - m[0][0] * m[2][1];
    let c20 = m[0][1] * m[1][2] - m[0][2] * m[1][1];
    let c21 = m[0][2] * m[1][0] - m[0][0] * m[1][2];
    let c22 = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    // inverse = adjugate / d, adjugate[i][j] = cofactor[j][i]
    [
        (c00 * b[0] + c10 * b[1] + c20 * b[2]) * inv_d,
        (c01 * b[0] + c11 * b[1] + c21 * b[2]) * inv_d,
        (c02 * b[0] + c12 * b[1] + c22 * b[2]) * inv_d,
    ]
}

/// a · b.
#[inline]
pub fn mul_mm(a: &M3, b: &M3) -> M3 {
    let mut r = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            r[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
        }
    }
    r
}

/// Transpose.
#[inline]
pub fn transpose(m: &M3) -> M3 {
    [
        [m[0][0], m[1][0], m[2][0]],
        [m[0][1], m[1][1], m[2][1]],
        [m[0][2], m[1][2], m[2][2]],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solve_inverts() {
        let m = [[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 2.0]];
        let x = [0.3, -1.2, 2.5];
        let b = mul_mv(&m, &x);
        let y = solve(&m, &b);
        for i in 0..3 {
            assert!((x[i] - y[i]).abs() < 1e-14);
        }
        assert!((det(&m) - 4.0 * (6.0 - 0.04) + (2.0 - 0.1) - 0.5 * (0.2 - 1.5)).abs() < 1e-12);
    }
}
