//! Finite-difference checks of the cost VJPs (one saturating cost, sums of saturating costs,
//! the energy cost), Monte-Carlo checks of the sum-of-costs variance and the energy moments.

mod common;

use common::*;
use faer::Mat;
use vicpilco_pilco::cost::{CostSum, EnergyCost, SaturatingCost};
use vicpilco_pilco::{CostBar, CostMoments};

fn flat_cost(o: &CostMoments) -> Vec<f64> {
    let mut v = vec![o.mean, o.var];
    v.extend_from_slice(&o.v);
    v
}

fn cost_bar(yb: &[f64]) -> CostBar {
    CostBar {
        mean: yb[0],
        var: yb[1],
        v: Some(yb[2..].to_vec()),
    }
}

/// A random PSD width matrix on `n` dimensions (rank-deficient when `rank < n`).
fn rand_width(r: &mut rand::rngs::ChaCha8Rng, n: usize, rank: usize, scale: f64) -> Mat<f64> {
    let a = rand_mat(r, n, rank, 1.0);
    let w = &a * a.transpose();
    Mat::from_fn(n, n, |i, j| scale * w[(i, j)] / rank as f64)
}

fn check_sum(r: &mut rand::rngs::ChaCha8Rng, d: usize, sum: &CostSum, s_scale: f64) {
    let m = rand_vec(r, d, 1.0);
    let s = rand_spd(r, d, s_scale);
    let f = |m: &[f64], s: &Mat<f64>| flat_cost(&sum.forward(m, s.as_ref()).0);
    let vjp = |m: &[f64], s: &Mat<f64>, yb: &[f64]| {
        let (_, cache) = sum.forward(m, s.as_ref());
        assert!(
            cache.var_unclamped() > 1e-9,
            "test point too close to the clamp"
        );
        sum.backward(&cache, &cost_bar(yb))
    };
    check_vjp(r, &m, &s, &f, &vjp);
}

#[test]
fn loss_sat_vjp_matches_finite_differences() {
    let mut r = rng(21);
    for d in [1usize, 2, 3, 5, 7] {
        for rank in [d, d.div_ceil(2)] {
            let w = rand_width(&mut r, d, rank, 2.0);
            let z = rand_vec(&mut r, d, 0.5);
            let sum = CostSum::loss_sat(w.as_ref(), &z).unwrap();
            check_sum(&mut r, d, &sum, 0.3);
        }
    }
}

#[test]
fn cost_sum_vjp_matches_finite_differences() {
    let mut r = rng(22);
    // (d, subsets): disjoint, overlapping, nested, unsorted, three costs.
    let cases: Vec<(usize, Vec<Vec<usize>>)> = vec![
        (2, vec![vec![0], vec![1]]),
        (4, vec![vec![0, 1], vec![1, 2, 3]]),
        (5, vec![vec![3, 0], vec![0], vec![4, 2, 1]]),
        (6, vec![vec![5, 1, 2], vec![2, 5], vec![0, 3]]),
    ];
    for (d, subsets) in cases {
        let costs = subsets
            .iter()
            .map(|dims| {
                let w = rand_width(&mut r, dims.len(), dims.len(), 1.5);
                let z = rand_vec(&mut r, dims.len(), 0.5);
                SaturatingCost::new(dims, w.as_ref(), &z).unwrap()
            })
            .collect();
        let sum = CostSum::new(d, costs).unwrap();
        check_sum(&mut r, d, &sum, 0.3);
    }
}

/// `Var[c_1 + c_2] = Var[c_1] + Var[c_2]` when the costs act on independent dimensions, and
/// the mean and `C` are additive in any case.
#[test]
fn cost_sum_of_independent_costs_adds_variances() {
    let mut r = rng(23);
    let s0 = rand_spd(&mut r, 2, 0.5);
    let s1 = rand_spd(&mut r, 2, 0.5);
    let s = Mat::from_fn(4, 4, |i, j| match (i < 2, j < 2) {
        (true, true) => s0[(i, j)],
        (false, false) => s1[(i - 2, j - 2)],
        _ => 0.0,
    });
    let m = rand_vec(&mut r, 4, 1.0);
    let c0 =
        SaturatingCost::new(&[0, 1], rand_width(&mut r, 2, 2, 1.0).as_ref(), &[0.1, 0.2]).unwrap();
    let c1 = SaturatingCost::new(
        &[3, 2],
        rand_width(&mut r, 2, 2, 1.0).as_ref(),
        &[-0.3, 0.0],
    )
    .unwrap();
    let one = |c: &SaturatingCost| {
        CostSum::new(4, vec![c.clone()])
            .unwrap()
            .forward(&m, s.as_ref())
            .0
    };
    let (a, b) = (one(&c0), one(&c1));
    let (both, _) = CostSum::new(4, vec![c0, c1])
        .unwrap()
        .forward(&m, s.as_ref());
    assert!((both.mean - a.mean - b.mean).abs() < 1e-14);
    assert!(
        (both.var - a.var - b.var).abs() < 1e-14,
        "{} vs {}",
        both.var,
        a.var + b.var
    );
    for k in 0..4 {
        assert!((both.v[k] - a.v[k] - b.v[k]).abs() < 1e-14);
    }
}

/// A cost on a subset equals `lossSat` on the sub-distribution.
#[test]
fn subset_cost_equals_loss_sat_on_the_marginal() {
    let mut r = rng(24);
    let m = rand_vec(&mut r, 4, 1.0);
    let s = rand_spd(&mut r, 4, 0.5);
    let w = rand_width(&mut r, 2, 2, 1.0);
    let z = [0.3, -0.1];
    let (sub, _) = CostSum::new(
        4,
        vec![SaturatingCost::new(&[3, 1], w.as_ref(), &z).unwrap()],
    )
    .unwrap()
    .forward(&m, s.as_ref());
    let (mm, sm) = (
        vec![m[3], m[1]],
        Mat::from_fn(2, 2, |i, j| s[([3, 1][i], [3, 1][j])]),
    );
    let (full, _) = CostSum::loss_sat(w.as_ref(), &z)
        .unwrap()
        .forward(&mm, sm.as_ref());
    assert!((sub.mean - full.mean).abs() < 1e-14);
    assert!((sub.var - full.var).abs() < 1e-14);
    assert!(sub.v[0] == 0.0 && sub.v[2] == 0.0);
    // C of the marginal is s_JJ⁻¹ Cov[x_J, c]; C of the full state is s⁻¹ Cov[x, c]: both
    // give the same Cov[x_J, c].
    for (a, &da) in [3usize, 1].iter().enumerate() {
        let cov_full: f64 = (0..4).map(|k| s[(da, k)] * sub.v[k]).sum();
        let cov_sub: f64 = (0..2).map(|k| sm[(a, k)] * full.v[k]).sum();
        assert!((cov_full - cov_sub).abs() < 1e-14);
    }
}

/// Monte Carlo (seeded, 5000 samples) agrees with the exact mean and variance of a sum of
/// three saturating costs on overlapping subsets, where the cross-covariances matter.
#[test]
fn cost_sum_variance_agrees_with_monte_carlo() {
    let mut r = rng(25);
    let d = 3;
    let m = vec![0.4, -0.3, 0.2];
    let s = rand_spd(&mut r, d, 0.6);
    let costs = vec![
        SaturatingCost::new(&[0, 1], rand_width(&mut r, 2, 2, 2.0).as_ref(), &[0.0, 0.1]).unwrap(),
        SaturatingCost::new(&[1], Mat::from_fn(1, 1, |_, _| 3.0).as_ref(), &[-0.2]).unwrap(),
        SaturatingCost::new(&[2, 0], rand_width(&mut r, 2, 1, 1.0).as_ref(), &[0.3, 0.3]).unwrap(),
    ];
    let sum = CostSum::new(d, costs.clone()).unwrap();
    let (mom, _) = sum.forward(&m, s.as_ref());
    let sum_of_vars: f64 = costs
        .iter()
        .map(|c| {
            CostSum::new(d, vec![c.clone()])
                .unwrap()
                .forward(&m, s.as_ref())
                .0
                .var
        })
        .sum();
    let xs = sample_gaussian(&mut r, &m, &s, 5000);
    let cs: Vec<f64> = xs.iter().map(|x| sum.eval(x)).collect();
    let n = cs.len() as f64;
    let mean = cs.iter().sum::<f64>() / n;
    let var = cs.iter().map(|c| (c - mean).powi(2)).sum::<f64>() / (n - 1.0);
    assert!(
        (mean - mom.mean).abs() < 0.03 * mom.mean,
        "mean {mean} vs {}",
        mom.mean
    );
    assert!(
        (var - mom.var).abs() < 0.07 * mom.var,
        "var {var} vs {}",
        mom.var
    );
    eprintln!(
        "MC var {var:.5}, exact {:.5}, Σ Var[c_k] {sum_of_vars:.5}",
        mom.var
    );
    check_cross_cov(&xs, &cs, &s, &mom.v, 0.02);
    // The cross terms are not negligible here, so the check has teeth.
    assert!(
        (mom.var - sum_of_vars).abs() > 0.15 * mom.var,
        "{} vs Σ Var {sum_of_vars}",
        mom.var
    );
}

#[test]
fn energy_cost_vjp_matches_finite_differences() {
    let mut r = rng(26);
    for u in [1, 2, 3, 5] {
        let a_max: Vec<f64> = (0..u).map(|_| 0.5 + normal(&mut r).abs()).collect();
        let pen: Vec<bool> = (0..u).map(|i| u == 1 || i % 3 != 1).collect();
        let cost = EnergyCost::new(&a_max, &pen).unwrap();
        let mu = rand_vec(&mut r, u, 1.0);
        let sig = rand_spd(&mut r, u, 0.5);
        let f = |m: &[f64], s: &Mat<f64>| flat_cost(&cost.forward(m, s.as_ref()).0);
        let vjp = |m: &[f64], s: &Mat<f64>, yb: &[f64]| {
            let (_, cache) = cost.forward(m, s.as_ref());
            cost.backward(&cache, &cost_bar(yb))
        };
        check_vjp(&mut r, &mu, &sig, &f, &vjp);
    }
}

#[test]
fn energy_cost_moments_agree_with_monte_carlo_and_exclusion_works() {
    let mut r = rng(27);
    let cost = EnergyCost::new(&[2.0, 0.5, 1.0], &[true, false, true]).unwrap();
    assert_eq!(cost.inverse_diag(), &[0.25, 0.0, 1.0]);
    let mu = vec![0.5, 3.0, -0.4];
    let sig = rand_spd(&mut r, 3, 0.5);
    let (mom, _) = cost.forward(&mu, sig.as_ref());
    let xs = sample_gaussian(&mut r, &mu, &sig, 5000);
    let cs: Vec<f64> = xs.iter().map(|a| cost.eval(a)).collect();
    let n = cs.len() as f64;
    let mean = cs.iter().sum::<f64>() / n;
    let var = cs.iter().map(|c| (c - mean).powi(2)).sum::<f64>() / (n - 1.0);
    assert!(
        (mean - mom.mean).abs() < 0.05 * mom.mean,
        "mean {mean} vs {}",
        mom.mean
    );
    assert!(
        (var - mom.var).abs() < 0.15 * mom.var,
        "var {var} vs {}",
        mom.var
    );
    check_cross_cov(&xs, &cs, &sig, &mom.v, 0.05);
    // The excluded action does not enter at all.
    let mut mu2 = mu.clone();
    mu2[1] = -100.0;
    assert_eq!(cost.forward(&mu2, sig.as_ref()).0.mean, mom.mean);
}

/// Sample `Cov[x, c]` against `s · v` (`v = s⁻¹ Cov[x, c]`), absolute tolerance `tol`.
fn check_cross_cov(xs: &[Vec<f64>], cs: &[f64], s: &Mat<f64>, v: &[f64], tol: f64) {
    let n = cs.len() as f64;
    let mc = cs.iter().sum::<f64>() / n;
    for k in 0..v.len() {
        let mk = xs.iter().map(|x| x[k]).sum::<f64>() / n;
        let got = xs
            .iter()
            .zip(cs)
            .map(|(x, c)| (x[k] - mk) * (c - mc))
            .sum::<f64>()
            / n;
        let want: f64 = (0..v.len()).map(|l| s[(k, l)] * v[l]).sum();
        assert!((got - want).abs() < tol, "Cov[x_{k}, c]: {got} vs {want}");
    }
}

#[test]
fn invalid_costs_are_rejected() {
    let w = Mat::<f64>::identity(2, 2);
    assert!(SaturatingCost::new(&[0], w.as_ref(), &[0.0]).is_err());
    assert!(SaturatingCost::new(&[0, 0], w.as_ref(), &[0.0, 0.0]).is_err());
    let c = SaturatingCost::new(&[0, 3], w.as_ref(), &[0.0, 0.0]).unwrap();
    assert!(CostSum::new(3, vec![c]).is_err());
    assert!(CostSum::new(3, vec![]).is_err());
    assert!(EnergyCost::new(&[0.0], &[true]).is_err());
}

#[test]
fn a_width_matrix_that_is_not_symmetric_psd_is_refused_naming_w() {
    // Eigenvalues 3 and −1: E[exp(−½ xᵀWx)] diverges, yet |I + sW|^(−1/2) with s = 2I would
    // give the finite expected cost 0.622.
    let indefinite = Mat::from_fn(2, 2, |i, j| if i == j { 1.0 } else { 2.0 });
    let err = SaturatingCost::new(&[0, 1], indefinite.as_ref(), &[0.0, 0.0]).unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("width matrix W") && msg.contains("positive semi-definite"),
        "{msg}"
    );
    let asymmetric = Mat::from_fn(2, 2, |i, j| match (i, j) {
        (0, 1) => 0.5,
        (1, 0) => -0.5,
        _ => 1.0,
    });
    let err = SaturatingCost::new(&[0, 1], asymmetric.as_ref(), &[0.0, 0.0]).unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("width matrix W") && msg.contains("not symmetric"),
        "{msg}"
    );
    // Rank-deficient PSD widths (and their rounding) stay accepted.
    let mut r = rng(31);
    for n in [1, 2, 4] {
        let w = rand_width(&mut r, n, 1, 3.0);
        let dims: Vec<usize> = (0..n).collect();
        SaturatingCost::new(&dims, w.as_ref(), &vec![0.0; n]).unwrap();
    }
    let zero = Mat::<f64>::zeros(2, 2);
    SaturatingCost::new(&[0, 1], zero.as_ref(), &[0.0, 0.0]).unwrap();
    // The cart-pole's tip-distance width: [[1, l], [l, l²]]/width² has a zero eigenvalue.
    let (l, width) = (0.6, 0.25);
    let tip = Mat::from_fn(2, 2, |i, j| [[1.0, l], [l, l * l]][i][j] / (width * width));
    SaturatingCost::new(&[0, 1], tip.as_ref(), &[0.0, 0.0]).unwrap();
}

#[test]
fn an_indefinite_state_covariance_gives_nan_not_a_plausible_cost() {
    // |I + sW| = −5 for W = I and s with eigenvalues 4 and −2: the Gaussian integral does not
    // exist, and taking |det| would have returned a finite cost.
    let sum = CostSum::loss_sat(Mat::<f64>::identity(2, 2).as_ref(), &[0.0, 0.0]).unwrap();
    let s = Mat::from_fn(2, 2, |i, j| if i == j { 1.0 } else { 3.0 });
    let (o, _) = sum.forward(&[0.0, 0.0], s.as_ref());
    assert!(o.mean.is_nan(), "{}", o.mean);
    // A PSD s still gives the closed form 1 − |I + s|^(−1/2) at m = z.
    let s = Mat::from_fn(2, 2, |i, j| if i == j { 1.0 } else { 0.5 });
    let (o, _) = sum.forward(&[0.0, 0.0], s.as_ref());
    assert!(
        (o.mean - (1.0 - 3.75f64.powf(-0.5))).abs() < 1e-14,
        "{}",
        o.mean
    );
}
