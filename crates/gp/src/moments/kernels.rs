//! The fused N×N loops of moment matching, one column of a pair block at a time.
//!
//! The block `L_ij = exp(r_i + c_j + Σ_k Â_ik B_jk)` (with `Â = 2𝒜T`, `B = ℬ`) is never
//! stored: each column is formed in a length-N buffer that stays in L1 cache, exponentiated,
//! and consumed at once. This keeps memory traffic O(N·D) per pair instead of O(N²), and lets
//! the whole loop be compiled for AVX-512 or AVX2+FMA (chosen at run time) so the D-term
//! inner products, the exponentials and the reductions all vectorise.

use crate::fastexp::exp1;

/// Operands of one pair block. `a_hat` and `a` are column-major N×D (`a_hat[k*N + i]`),
/// `b` is row-major N×D (`b[j*D + k]`).
pub(crate) struct BlockOperands<'a> {
    pub n: usize,
    pub d: usize,
    pub a_hat: &'a [f64],
    pub b: &'a [f64],
    pub row: &'a [f64],
    pub col: &'a [f64],
    pub beta_a: &'a [f64],
    pub beta_b: &'a [f64],
    /// Column-major N×N variance matrix, with its column stride (diagonal model-variance pair
    /// only).
    pub w: Option<(&'a [f64], usize)>,
    /// The block of a diagonal pair (a = b) is symmetric, and so is W: the forward sums then
    /// visit the strict lower triangle and the diagonal only.
    pub symmetric: bool,
}

/// Outputs of the backward sweep of one pair block.
pub(crate) struct BlockBackward {
    /// Row sums of Φ (N).
    pub phi_row: Vec<f64>,
    /// Column sums of Φ (N).
    pub phi_col: Vec<f64>,
    /// Φℬ, column-major N×D.
    pub phi_b: Vec<f64>,
    /// `L β_b` (N).
    pub l_beta_b: Vec<f64>,
    /// `Lᵀ β_a` (N).
    pub lt_beta_a: Vec<f64>,
    /// Φᵀ𝒜, row-major N×D (only with parameter adjoints).
    pub phit_a: Option<Vec<f64>>,
}

/// Sum with eight independent accumulators, so the compiler may vectorise it.
#[inline(always)]
fn sum8(x: &[f64]) -> f64 {
    let mut acc = [0.0; 8];
    let chunks = x.chunks_exact(8);
    let tail = chunks.remainder();
    for c in chunks {
        for l in 0..8 {
            acc[l] += c[l];
        }
    }
    acc.iter().sum::<f64>() + tail.iter().sum::<f64>()
}

/// Dot product with eight independent accumulators.
#[inline(always)]
fn dot8(x: &[f64], y: &[f64]) -> f64 {
    let mut acc = [0.0; 8];
    let (xc, yc) = (x.chunks_exact(8), y.chunks_exact(8));
    let tail: f64 = xc
        .remainder()
        .iter()
        .zip(yc.remainder())
        .map(|(a, b)| a * b)
        .sum();
    for (a, b) in xc.zip(yc) {
        for l in 0..8 {
            acc[l] = a[l].mul_add(b[l], acc[l]);
        }
    }
    acc.iter().sum::<f64>() + tail
}

/// Lanes of the register-blocked loops: rows handled together, kept in registers.
const LANES: usize = 8;

/// Column j of the block into `buf`: D passes of a fused multiply-add over the column, then
/// the exponential (measured faster here than register blocking, which the backward's many
/// consumers of the column do not profit from).
#[inline(always)]
fn fill_column(op: &BlockOperands<'_>, j: usize, buf: &mut [f64]) {
    let n = op.n;
    let cj = op.col[j];
    buf.copy_from_slice(op.row);
    for k in 0..op.d {
        let bjk = op.b[j * op.d + k];
        let ak = &op.a_hat[k * n..(k + 1) * n];
        for (x, a) in buf.iter_mut().zip(ak) {
            *x = a.mul_add(bjk, *x);
        }
    }
    for x in buf.iter_mut() {
        *x = exp1(*x + cj);
    }
}

/// One pass over column j of the block without storing it: returns
/// `(Σ_i β_ai L_ij, Σ_i W_ij L_ij)`. Rows are processed `LANES` at a time with the D-term
/// inner products, the exponential and both reductions fused, so nothing leaves registers.
#[inline(always)]
fn column_sums(op: &BlockOperands<'_>, j: usize, rows: usize, w_col: Option<&[f64]>) -> (f64, f64) {
    let (n, d) = (op.n, op.d);
    let cj = op.col[j];
    let bj = &op.b[j * d..(j + 1) * d];
    let mut acc_beta = [0.0; LANES];
    let mut acc_w = [0.0; LANES];
    let full = rows / LANES * LANES;
    let mut i0 = 0;
    while i0 < full {
        let mut x = [0.0; LANES];
        x.copy_from_slice(&op.row[i0..i0 + LANES]);
        for (k, &bjk) in bj.iter().enumerate() {
            let a = &op.a_hat[k * n + i0..k * n + i0 + LANES];
            for l in 0..LANES {
                x[l] = a[l].mul_add(bjk, x[l]);
            }
        }
        let beta = &op.beta_a[i0..i0 + LANES];
        for l in 0..LANES {
            let v = exp1(x[l] + cj);
            x[l] = v;
            acc_beta[l] = v.mul_add(beta[l], acc_beta[l]);
        }
        if let Some(w) = w_col {
            let w = &w[i0..i0 + LANES];
            for l in 0..LANES {
                acc_w[l] = x[l].mul_add(w[l], acc_w[l]);
            }
        }
        i0 += LANES;
    }
    let mut sb: f64 = acc_beta.iter().sum();
    let mut sw: f64 = acc_w.iter().sum();
    for i in full..rows {
        let mut x = op.row[i];
        for (k, &bjk) in bj.iter().enumerate() {
            x = op.a_hat[k * n + i].mul_add(bjk, x);
        }
        let v = exp1(x + cj);
        sb += v * op.beta_a[i];
        if let Some(w) = w_col {
            sw += v * w[i];
        }
    }
    (sb, sw)
}

#[inline(always)]
fn forward_generic(op: &BlockOperands<'_>) -> (f64, f64) {
    let n = op.n;
    let mut total = 0.0;
    let mut trace = 0.0;
    for j in 0..n {
        let w_col = op.w.map(|(w, stride)| &w[j * stride..j * stride + n]);
        if op.symmetric {
            let (sb, sw) = column_sums(op, j, j, w_col);
            let mut x = op.row[j] + op.col[j];
            for k in 0..op.d {
                x = op.a_hat[k * n + j].mul_add(op.b[j * op.d + k], x);
            }
            let ljj = exp1(x);
            total += (2.0 * sb + op.beta_a[j] * ljj) * op.beta_b[j];
            trace += 2.0 * sw + w_col.map_or(0.0, |w| w[j] * ljj);
        } else {
            let (sb, sw) = column_sums(op, j, n, w_col);
            total += sb * op.beta_b[j];
            trace += sw;
        }
    }
    (total, trace)
}

/// `Φ = t L ∘ (G β_a β_bᵀ − δ S̄_aa W)`: `scale_beta = tG`, `scale_w = tS̄_aa` (0 without W).
#[inline(always)]
fn backward_generic(
    op: &BlockOperands<'_>,
    scale_beta: f64,
    scale_w: f64,
    a: Option<&[f64]>,
) -> BlockBackward {
    let (n, d) = (op.n, op.d);
    let mut buf = vec![0.0; n];
    let mut phi = vec![0.0; n];
    let mut out = BlockBackward {
        phi_row: vec![0.0; n],
        phi_col: vec![0.0; n],
        phi_b: vec![0.0; n * d],
        l_beta_b: vec![0.0; n],
        lt_beta_a: vec![0.0; n],
        phit_a: a.map(|_| vec![0.0; n * d]),
    };
    for j in 0..n {
        fill_column(op, j, &mut buf);
        let gb = scale_beta * op.beta_b[j];
        match op.w {
            Some((w, stride)) => {
                let wc = &w[j * stride..j * stride + n];
                for i in 0..n {
                    phi[i] = buf[i] * (gb * op.beta_a[i] - scale_w * wc[i]);
                }
            }
            None => {
                for i in 0..n {
                    phi[i] = buf[i] * gb * op.beta_a[i];
                }
            }
        }
        let bj = op.beta_b[j];
        for i in 0..n {
            out.phi_row[i] += phi[i];
            out.l_beta_b[i] = buf[i].mul_add(bj, out.l_beta_b[i]);
        }
        out.phi_col[j] = sum8(&phi);
        out.lt_beta_a[j] = dot8(&buf, op.beta_a);
        for k in 0..d {
            let bjk = op.b[j * d + k];
            let dst = &mut out.phi_b[k * n..(k + 1) * n];
            for (o, p) in dst.iter_mut().zip(&phi) {
                *o = p.mul_add(bjk, *o);
            }
        }
        if let (Some(a), Some(pa)) = (a, out.phit_a.as_mut()) {
            for k in 0..d {
                let ak = &a[k * n..(k + 1) * n];
                pa[j * d + k] = dot8(&phi, ak);
            }
        }
    }
    out
}

macro_rules! dispatch {
    ($generic:ident, $avx512:ident, $avx2:ident, ($($arg:ident : $ty:ty),*) -> $ret:ty) => {
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx512f,avx512dq,avx2,fma")]
        unsafe fn $avx512($($arg: $ty),*) -> $ret {
            $generic($($arg),*)
        }
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2,fma")]
        unsafe fn $avx2($($arg: $ty),*) -> $ret {
            $generic($($arg),*)
        }
    };
}

dispatch!(forward_generic, forward_avx512, forward_avx2, (op: &BlockOperands<'_>) -> (f64, f64));
dispatch!(backward_generic, backward_avx512, backward_avx2,
    (op: &BlockOperands<'_>, scale_beta: f64, scale_w: f64, a: Option<&[f64]>) -> BlockBackward);

/// `(Σ_ij β_ai L_ij β_bj, Σ_ij W_ij L_ij)` of one pair block.
pub(crate) fn block_forward(op: &BlockOperands<'_>) -> (f64, f64) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::is_x86_feature_detected!("avx512f") && std::is_x86_feature_detected!("avx512dq") {
            // SAFETY: the CPU has the features the function was compiled for.
            return unsafe { forward_avx512(op) };
        }
        if std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma") {
            // SAFETY: as above.
            return unsafe { forward_avx2(op) };
        }
    }
    forward_generic(op)
}

/// The backward sweep of one pair block; `a` (column-major 𝒜) only when parameter adjoints
/// are wanted.
pub(crate) fn block_backward(
    op: &BlockOperands<'_>,
    scale_beta: f64,
    scale_w: f64,
    a: Option<&[f64]>,
) -> BlockBackward {
    #[cfg(target_arch = "x86_64")]
    {
        if std::is_x86_feature_detected!("avx512f") && std::is_x86_feature_detected!("avx512dq") {
            // SAFETY: the CPU has the features the function was compiled for.
            return unsafe { backward_avx512(op, scale_beta, scale_w, a) };
        }
        if std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma") {
            // SAFETY: as above.
            return unsafe { backward_avx2(op, scale_beta, scale_w, a) };
        }
    }
    backward_generic(op, scale_beta, scale_w, a)
}
