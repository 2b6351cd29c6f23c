//! Shared helpers of the block tests: random inputs and a VJP-vs-finite-difference check
//! built on the project's one checker, `vicpilco_gp::fd`.

#![allow(dead_code)]

use faer::Mat;
use rand::rngs::ChaCha8Rng;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;
use vicpilco_gp::fd;
use vicpilco_pilco::{GaussianBar, Moments, MomentsBar};

pub fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

pub fn normal(rng: &mut ChaCha8Rng) -> f64 {
    rng.sample(StandardNormal)
}

pub fn rand_vec(rng: &mut ChaCha8Rng, n: usize, scale: f64) -> Vec<f64> {
    (0..n).map(|_| scale * normal(rng)).collect()
}

pub fn rand_mat(rng: &mut ChaCha8Rng, r: usize, c: usize, scale: f64) -> Mat<f64> {
    Mat::from_fn(r, c, |_, _| scale * normal(rng))
}

/// A random symmetric positive-definite matrix with eigenvalues of order `scale`.
pub fn rand_spd(rng: &mut ChaCha8Rng, n: usize, scale: f64) -> Mat<f64> {
    let a = rand_mat(rng, n, n, 1.0);
    let mut s = &a * a.transpose();
    for i in 0..n {
        for j in 0..n {
            s[(i, j)] *= scale / n as f64;
        }
        s[(i, i)] += 0.1 * scale;
    }
    sym(&s)
}

/// A random symmetric matrix (a perturbation direction for a covariance).
pub fn rand_sym(rng: &mut ChaCha8Rng, n: usize) -> Mat<f64> {
    sym(&rand_mat(rng, n, n, 1.0))
}

pub fn sym(a: &Mat<f64>) -> Mat<f64> {
    Mat::from_fn(a.nrows(), a.ncols(), |i, j| 0.5 * (a[(i, j)] + a[(j, i)]))
}

pub fn flat(a: &Mat<f64>) -> Vec<f64> {
    let mut v = Vec::with_capacity(a.nrows() * a.ncols());
    for i in 0..a.nrows() {
        for j in 0..a.ncols() {
            v.push(a[(i, j)]);
        }
    }
    v
}

pub fn unflat(v: &[f64], r: usize, c: usize) -> Mat<f64> {
    Mat::from_fn(r, c, |i, j| v[i * c + j])
}

/// `[M; S(:); C(:)]` (row-major) of a block's outputs.
pub fn flat_moments(o: &Moments) -> Vec<f64> {
    let mut v = o.mean.clone();
    v.extend(flat(&o.cov));
    v.extend(flat(&o.v));
    v
}

/// The adjoint of `flat_moments` split back into `(M̄, S̄, C̄)`.
pub fn moments_bar(ybar: &[f64], e: usize, d: usize) -> MomentsBar {
    MomentsBar {
        mean: ybar[..e].to_vec(),
        cov: unflat(&ybar[e..e + e * e], e, e),
        v: Some(unflat(&ybar[e + e * e..], d, e)),
    }
}

pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// A block's forward, flattened: `(m, s) → outputs`.
pub type BlockFn<'a> = dyn Fn(&[f64], &Mat<f64>) -> Vec<f64> + 'a;
/// A block's VJP: `(m, s, ȳ) → (m̄, s̄)`.
pub type BlockVjp<'a> = dyn Fn(&[f64], &Mat<f64>, &[f64]) -> GaussianBar + 'a;

/// Check a VJP against central finite differences of `ȳ·f` along random directions.
///
/// `f(m, s)` returns the flattened outputs; `vjp(m, s, ȳ)` the input adjoints. Three random
/// directions are tried: mean only, covariance only (symmetric), and both. Returns the largest
/// relative discrepancy.
pub fn check_vjp(
    rng: &mut ChaCha8Rng,
    m: &[f64],
    s: &Mat<f64>,
    f: &BlockFn,
    vjp: &BlockVjp,
) -> f64 {
    let d = m.len();
    let ny = f(m, s).len();
    let mut worst = 0.0f64;
    for mode in 0..3 {
        let ybar = rand_vec(rng, ny, 1.0);
        let dm = if mode == 1 {
            vec![0.0; d]
        } else {
            rand_vec(rng, d, 1.0)
        };
        let ds = if mode == 0 {
            Mat::zeros(d, d)
        } else {
            rand_sym(rng, d)
        };
        let bar = vjp(m, s, &ybar);
        assert_symmetric(&bar.cov);
        let analytic = dot(&bar.mean, &dm) + dot(&flat(&bar.cov), &flat(&ds));
        let mut x0 = m.to_vec();
        x0.extend(flat(s));
        let mut dir = dm.clone();
        dir.extend(flat(&ds));
        let mut g = |x: &[f64]| -> f64 {
            let sm = unflat(&x[d..], d, d);
            dot(&ybar, &f(&x[..d], &sm))
        };
        let numeric = fd::directional(&mut g, &x0, &dir, 1e-4);
        let err = fd::rel_diff(analytic, numeric, 1e-6);
        assert!(
            err < 1e-7,
            "mode {mode}: VJP {analytic:.12e} vs FD {numeric:.12e} (rel {err:.2e})"
        );
        worst = worst.max(err);
    }
    worst
}

pub fn assert_symmetric(a: &Mat<f64>) {
    for i in 0..a.nrows() {
        for j in 0..i {
            assert_eq!(
                a[(i, j)],
                a[(j, i)],
                "adjoint of a covariance is not symmetric"
            );
        }
    }
}

/// Draw `n` samples of `N(m, s)` (Cholesky of `s`).
pub fn sample_gaussian(rng: &mut ChaCha8Rng, m: &[f64], s: &Mat<f64>, n: usize) -> Vec<Vec<f64>> {
    let d = m.len();
    let chol = vicpilco_gp::linalg::Chol::new(s.as_ref(), "sample covariance").unwrap();
    let l = chol.l();
    (0..n)
        .map(|_| {
            let z = rand_vec(rng, d, 1.0);
            (0..d)
                .map(|i| m[i] + (0..=i).map(|j| l[(i, j)] * z[j]).sum::<f64>())
                .collect()
        })
        .collect()
}
