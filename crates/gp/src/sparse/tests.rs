use super::fitc::se_cross;
use super::*;
use crate::error::GpError;
use crate::fd;
use crate::kernel::{Kernel, SquaredExponential};
use crate::linalg::Chol;
use crate::moments::{forward, MmModel};
use crate::train::input_std;
use faer::Mat;
use rand::rngs::ChaCha8Rng;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;

fn normal_mat(r: usize, c: usize, rng: &mut ChaCha8Rng) -> Mat<f64> {
    Mat::from_fn(r, c, |_, _| rng.sample::<f64, _>(StandardNormal))
}

/// Smooth targets of every output, with noise 0.05.
fn smooth(x: &Mat<f64>, e: usize, rng: &mut ChaCha8Rng) -> Mat<f64> {
    let d = x.ncols();
    Mat::from_fn(x.nrows(), e, |i, k| {
        let s: f64 = (0..d).map(|c| x[(i, c)] * (1.0 + 0.3 * c as f64)).sum();
        (s / d as f64 * (1.0 + k as f64)).sin() + 0.2 * x[(i, 0)] * k as f64
    }) + Mat::from_fn(x.nrows(), e, |_, _| {
        0.05 * rng.sample::<f64, _>(StandardNormal)
    })
}

fn hyp_for(x: &Mat<f64>, rng: &mut ChaCha8Rng) -> Hyper {
    Hyper {
        log_ls: input_std(x.as_ref())
            .iter()
            .map(|s| s.ln() + rng.random_range(-0.3..0.5))
            .collect(),
        log_sf: rng.random_range(-0.3..0.3),
        log_sn: rng.random_range(-2.5..-1.0),
    }
}

fn col(m: &Mat<f64>, e: usize) -> Vec<f64> {
    (0..m.nrows()).map(|i| m[(i, e)]).collect()
}

/// The FITC quantities from their definitions with dense N×N algebra (small problems only).
struct Dense {
    nlml: f64,
    beta: Vec<f64>,
    inv_k: Mat<f64>,
}

fn dense(x: &Mat<f64>, y: &[f64], h: &Hyper, u: &Mat<f64>) -> Dense {
    let (n, m) = (x.nrows(), u.nrows());
    let k = SquaredExponential;
    let mut kmm = k.gram(h, u.as_ref());
    for i in 0..m {
        kmm[(i, i)] += FITC_RIDGE;
    }
    let kmn = k.cross(h, u.as_ref(), x.as_ref());
    let lmm = Chol::new(kmm.as_ref(), "kmm").unwrap();
    let q = kmn.transpose() * lmm.solve(kmn.as_ref());
    let gamma: Vec<f64> = (0..n).map(|i| h.sf2() - q[(i, i)] + h.sn2()).collect();
    // C = Q + Γ: Q off the diagonal, σ_f² + σ_n² on it.
    let mut c = q.clone();
    for i in 0..n {
        c[(i, i)] = q[(i, i)] + gamma[i];
    }
    let cc = Chol::new(c.as_ref(), "C").unwrap();
    let a = cc.solve_vec(y);
    let nlml = 0.5 * y.iter().zip(&a).map(|(p, q)| p * q).sum::<f64>()
        + 0.5 * cc.log_det()
        + 0.5 * n as f64 * (2.0 * std::f64::consts::PI).ln();
    let kg = Mat::from_fn(m, n, |i, j| kmn[(i, j)] / gamma[j]);
    let b = &kmm + &kg * kmn.transpose();
    let bc = Chol::new(b.as_ref(), "B").unwrap();
    let beta = bc.solve_vec(&super::fitc::mat_vec(kg.as_ref(), y));
    let inv_k = lmm.inverse() - bc.inverse();
    Dense { nlml, beta, inv_k }
}

#[test]
fn fitc_value_beta_and_variance_matrix_match_the_dense_definitions() {
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    for &(n, m, d) in &[(6, 3, 1), (30, 8, 3), (50, 12, 5)] {
        let x = normal_mat(n, d, &mut rng);
        let y = smooth(&x, 2, &mut rng);
        let u = normal_mat(m, d, &mut rng);
        let hyp = vec![hyp_for(&x, &mut rng), hyp_for(&x, &mut rng)];
        let model = SparseGpModel::new(x.as_ref(), y.as_ref(), hyp.clone(), u.clone()).unwrap();
        for (e, h) in hyp.iter().enumerate() {
            let want = dense(&x, &col(&y, e), h, &u);
            let got = fitc_nlml(x.as_ref(), &col(&y, e), h, u.as_ref()).unwrap();
            assert!(
                fd::rel_diff(got.value, want.nlml, 1.0) < 1e-10,
                "{} vs {}",
                got.value,
                want.nlml
            );
            assert!(fd::rel_diff(model.nlml()[e], want.nlml, 1.0) < 1e-10);
            let bmax = want.beta.iter().fold(0.0f64, |a, b| a.max(b.abs()));
            for i in 0..m {
                assert!((model.beta()[(i, e)] - want.beta[i]).abs() < 1e-8 * bmax.max(1.0));
            }
            let kmax = (0..m)
                .flat_map(|i| (0..m).map(move |j| (i, j)))
                .fold(0.0f64, |a, (i, j)| a.max(want.inv_k[(i, j)].abs()));
            for i in 0..m {
                for j in 0..m {
                    let diff = (model.inv_k()[e][(i, j)] - want.inv_k[(i, j)]).abs();
                    assert!(
                        diff < 1e-7 * kmax.max(1.0),
                        "inv_k[{i},{j}] off by {diff:e}"
                    );
                }
            }
        }
    }
}

#[test]
fn fitc_gradients_match_finite_differences() {
    let mut rng = ChaCha8Rng::seed_from_u64(22);
    for &(n, m, d) in &[(5, 3, 1), (30, 8, 3), (100, 15, 7)] {
        let x = normal_mat(n, d, &mut rng);
        let y = col(&smooth(&x, 1, &mut rng), 0);
        // Inducing inputs away from each other: keeps K_mm + 1e-6 I well conditioned so the
        // finite differences are not swamped by rounding.
        let u = Mat::from_fn(m, d, |i, c| x[((i * n) / m, c)] + 0.1 * (c as f64 - 0.5));
        let h = hyp_for(&x, &mut rng);
        let g = fitc_nlml(x.as_ref(), &y, &h, u.as_ref()).unwrap();

        // w.r.t. the inducing inputs (row-major flat).
        let u0: Vec<f64> = (0..m)
            .flat_map(|i| (0..d).map(move |c| (i, c)))
            .map(|(i, c)| u[(i, c)])
            .collect();
        let mut fu = |p: &[f64]| {
            let uu = MatRef::from_row_major_slice(p, m, d);
            vec![fitc_nlml(x.as_ref(), &y, &h, uu).unwrap().value]
        };
        let j = fd::jacobian(&mut fu, &u0, 1e-4);
        let scale = j[0].iter().fold(1e-3f64, |a, b| a.max(b.abs()));
        for i in 0..m {
            for c in 0..d {
                let (a, b) = (g.grad_inducing[(i, c)], j[0][i * d + c]);
                assert!(
                    (a - b).abs() < 1e-6 * scale,
                    "N={n} M={m} D={d} u[{i},{c}]: analytic {a}, fd {b}"
                );
            }
        }
        // w.r.t. the log hyper-parameters.
        let mut fh = |p: &[f64]| {
            vec![
                fitc_nlml(x.as_ref(), &y, &Hyper::from_pilco(p).unwrap(), u.as_ref())
                    .unwrap()
                    .value,
            ]
        };
        let j = fd::jacobian(&mut fh, &h.to_pilco(), 1e-4);
        // zip stops at the shorter: a gradient missing entries would pass unchecked.
        assert_eq!(
            g.grad_hyp.len(),
            j[0].len(),
            "hyper-parameter gradient length"
        );
        for (k, (a, b)) in g.grad_hyp.iter().zip(&j[0]).enumerate() {
            assert!(
                fd::rel_diff(*a, *b, 1e-2) < 1e-6,
                "N={n} M={m} D={d} hyp[{k}]: analytic {a}, fd {b}"
            );
        }
    }
}

#[test]
fn inducing_inputs_at_the_training_inputs_reproduce_the_full_gp() {
    let mut rng = ChaCha8Rng::seed_from_u64(23);
    let (n, d) = (40, 3);
    let x = normal_mat(n, d, &mut rng);
    let y = smooth(&x, 2, &mut rng);
    let mut hyp = vec![hyp_for(&x, &mut rng), hyp_for(&x, &mut rng)];
    // Noise σ_n ≈ 0.3: the 1e-6 ridge on K_mm then changes predictions by ~1e-6 (oracle
    // README, gp1 notes: the effect grows to 1e-4…1e-3 at σ_n ≈ 0.01).
    for h in &mut hyp {
        h.log_sn = (0.3f64).ln();
    }
    let full = GpModel::new(x.clone(), y.clone(), hyp.clone()).unwrap();
    let sparse = SparseGpModel::new(x.as_ref(), y.as_ref(), hyp, x.clone()).unwrap();
    for t in 0..10 {
        let xs: Vec<f64> = (0..d).map(|c| 0.7 * ((t * 3 + c) as f64).sin()).collect();
        let (mf, vf) = full.predict(&xs).unwrap();
        let (ms, vs) = sparse.predict(&xs).unwrap();
        for e in 0..2 {
            assert!((mf[e] - ms[e]).abs() < 1e-5, "mean {} vs {}", mf[e], ms[e]);
            assert!((vf[e] - vs[e]).abs() < 1e-5, "var {} vs {}", vf[e], vs[e]);
        }
    }
    // Moment matching integrates the same predictive mean and variance over the input
    // Gaussian, so the sparse model's moments (its β and W = K_mm⁻¹ − B⁻¹) must agree with the
    // full GP's (β and (K + σ_n²I)⁻¹) as the point predictions above do: M and S to the same
    // 1e-5 (measured: ≤ 2.6e-6). V = s⁻¹Cov[x, f] is a slope of the mean (∂m/∂x as s → 0),
    // and the slope of the ridge's ~1e-6 change of the mean comes out larger (measured:
    // ≤ 6.5e-6, at the smallest s), hence 2e-5 for V. A wrong β or W would be off by the
    // size of the moments themselves (0.1–1).
    let max_diff = |a: &Mat<f64>, b: &Mat<f64>| {
        (0..a.nrows())
            .flat_map(|i| (0..a.ncols()).map(move |j| (i, j)))
            .fold(0.0f64, |w, ij| w.max((a[ij] - b[ij]).abs()))
    };
    let (full_mm, sparse_mm) = (MmModel::with_uncertainty(&full), MmModel::sparse(&sparse));
    for t in 0..5 {
        let m: Vec<f64> = (0..d).map(|c| 0.5 * ((t * 5 + c) as f64).cos()).collect();
        let s = Mat::from_fn(d, d, |i, j| {
            0.05 * (1.0 + t as f64) * if i == j { 1.0 } else { 0.3 }
        });
        let (mf, _) = forward(&full_mm, &m, s.as_ref()).unwrap();
        let (ms, _) = forward(&sparse_mm, &m, s.as_ref()).unwrap();
        for (a, b) in mf.mean.iter().zip(&ms.mean) {
            assert!((a - b).abs() < 1e-5, "input {t}: M {a} vs {b}");
        }
        let (cov, v) = (max_diff(&mf.cov, &ms.cov), max_diff(&mf.v, &ms.v));
        assert!(cov < 1e-5, "input {t}: S differs by {cov:e}");
        assert!(v < 2e-5, "input {t}: V differs by {v:e}");
    }
}

#[test]
fn se_cross_matches_the_kernel() {
    let mut rng = ChaCha8Rng::seed_from_u64(24);
    let a = normal_mat(7, 3, &mut rng);
    let b = normal_mat(5, 3, &mut rng);
    let h = hyp_for(&a, &mut rng);
    let got = se_cross(&h, a.as_ref(), b.as_ref());
    let want = SquaredExponential.cross(&h, a.as_ref(), b.as_ref());
    for i in 0..7 {
        for j in 0..5 {
            assert!((got[(i, j)] - want[(i, j)]).abs() < 1e-14);
        }
    }
}

#[test]
fn subset_selection_is_deterministic_distinct_and_seeded() {
    let a = select_subset(1000, 50, 7);
    assert_eq!(a, select_subset(1000, 50, 7));
    assert_ne!(a, select_subset(1000, 50, 8));
    assert_eq!(a.len(), 50);
    assert!(a.windows(2).all(|w| w[0] < w[1]) && a[49] < 1000);
    assert_eq!(select_subset(5, 10, 1), vec![0, 1, 2, 3, 4]);
}

/// Training data, hyper-parameters and starting inducing inputs for `train_inducing`.
struct InducingProblem {
    x: Mat<f64>,
    y: Mat<f64>,
    hyp: Vec<Hyper>,
    u0: Mat<f64>,
}

/// `n` random inputs of dimension `d`, smooth targets of `outputs` outputs with their
/// hyper-parameters, and `m` of the inputs (subset seed `subset_seed`) as the starting inducing
/// inputs.
fn inducing_problem(
    seed: u64,
    (n, d, m): (usize, usize, usize),
    outputs: usize,
    subset_seed: u64,
) -> InducingProblem {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let x = normal_mat(n, d, &mut rng);
    let y = smooth(&x, outputs, &mut rng);
    let hyp = (0..outputs).map(|_| hyp_for(&x, &mut rng)).collect();
    let sub = select_subset(n, m, subset_seed);
    let u0 = Mat::from_fn(m, d, |i, c| x[(sub[i], c)]);
    InducingProblem { x, y, hyp, u0 }
}

#[test]
fn training_inducing_inputs_decreases_the_summed_fitc_nlml() {
    let InducingProblem { x, y, hyp, u0 } = inducing_problem(25, (120, 2, 10), 2, 3);
    let opts = InducingOptions {
        max_iters: 30,
        ..Default::default()
    };
    let (u, rep) = train_inducing(x.as_ref(), y.as_ref(), &hyp, u0.as_ref(), &opts).unwrap();
    assert!(rep.nlml < rep.initial_nlml - 1.0, "{rep:?}");
    let sum: f64 = (0..2)
        .map(|e| {
            fitc_nlml(x.as_ref(), &col(&y, e), &hyp[e], u.as_ref())
                .unwrap()
                .value
        })
        .sum();
    assert!((sum - rep.nlml).abs() < 1e-9 * sum.abs());
    assert!((rep.output_nlml.iter().sum::<f64>() - rep.nlml).abs() < 1e-9 * sum.abs());
}

#[test]
fn inducing_inputs_train_the_same_on_one_thread_and_on_many() {
    let InducingProblem { x, y, hyp, u0 } = inducing_problem(26, (80, 3, 8), 3, 5);
    let opts = InducingOptions {
        max_iters: 10,
        ..Default::default()
    };
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let (u, rep) = pool
            .install(|| train_inducing(x.as_ref(), y.as_ref(), &hyp, u0.as_ref(), &opts))
            .unwrap();
        (u, rep.nlml, rep.output_nlml)
    };
    assert_eq!(on(1), on(3));
}

#[test]
fn dynamics_model_switches_to_sparse_above_the_threshold() {
    let mut rng = ChaCha8Rng::seed_from_u64(26);
    let (n, d) = (60, 2);
    let x = normal_mat(n, d, &mut rng);
    let y = smooth(&x, 2, &mut rng);
    let init = vec![hyp_for(&x, &mut rng), hyp_for(&x, &mut rng)];
    let mut opts = DynamicsOptions {
        sparse_threshold: 60,
        ..Default::default()
    };
    opts.sparse.num_inducing = 12;
    opts.sparse.inducing.max_iters = 10;
    let (full, rep) = DynamicsModel::fit(x.clone(), y.clone(), &init, None, &opts).unwrap();
    assert!(!full.is_sparse() && matches!(rep, DynamicsReport::Full(_)));
    assert_eq!(full.inputs().nrows(), n);

    opts.sparse_threshold = 59;
    let (sp, rep) = DynamicsModel::fit(x.clone(), y.clone(), &init, None, &opts).unwrap();
    assert!(sp.is_sparse());
    assert_eq!(sp.inputs().nrows(), 12);
    assert_eq!(sp.beta().nrows(), 12);
    assert_eq!(sp.inv_k()[1].nrows(), 12);
    let DynamicsReport::Sparse(r) = rep else {
        panic!("expected a sparse report")
    };
    let ind = r.inducing.expect("inducing inputs were optimised");
    assert!(ind.nlml <= ind.initial_nlml);
    // Sparse predictions are close to the full GP on this smooth function.
    let (mf, _) = full.predict(&[0.2, -0.3]).unwrap();
    let (ms, _) = sp.predict(&[0.2, -0.3]).unwrap();
    for e in 0..2 {
        assert!((mf[e] - ms[e]).abs() < 0.1, "{mf:?} vs {ms:?}");
    }
}

#[test]
fn hyper_parameters_are_fitted_on_all_points_or_on_the_requested_subset() {
    let mut rng = ChaCha8Rng::seed_from_u64(27);
    let (n, d, m) = (50, 2, 8);
    let x = normal_mat(n, d, &mut rng);
    let y = smooth(&x, 1, &mut rng);
    let init = vec![hyp_for(&x, &mut rng)];
    let hyper = crate::TrainOptions {
        max_iters: 20,
        ..Default::default()
    };
    let mut opts = SparseTrainOptions {
        num_inducing: m,
        seed: 5,
        hyper: hyper.clone(),
        hyper_points: None,
        inducing: InducingOptions {
            max_iters: 2,
            ..Default::default()
        },
    };
    let (all, rep) = train_sparse(x.as_ref(), y.as_ref(), &init, None, &opts).unwrap();
    assert_eq!(rep.hyper_points, n);
    let (expect, _) = crate::train::train(x.as_ref(), y.as_ref(), &init, &hyper).unwrap();
    assert_eq!(all.hyp(), &expect[..]);

    opts.hyper_points = Some(20);
    let (sub, rep) = train_sparse(x.as_ref(), y.as_ref(), &init, None, &opts).unwrap();
    assert_eq!(rep.hyper_points, 20);
    let rows = select_subset(n, 20, 5);
    let xs = Mat::from_fn(20, d, |i, c| x[(rows[i], c)]);
    let ys = Mat::from_fn(20, 1, |i, _| y[(rows[i], 0)]);
    let (expect, _) = crate::train::train(xs.as_ref(), ys.as_ref(), &init, &hyper).unwrap();
    assert_eq!(sub.hyp(), &expect[..]);
    assert_ne!(sub.hyp(), all.hyp());

    // A cold start (no previous inducing inputs) gets `cold_start_factor` times the budget.
    opts.inducing.cold_start_factor = 3;
    let (cold, rep) = train_sparse(x.as_ref(), y.as_ref(), &init, None, &opts).unwrap();
    let cold_iters = rep.inducing.unwrap().iterations;
    assert!(cold_iters > 2 && cold_iters <= 6, "{cold_iters}");
    let (_, rep) = train_sparse(x.as_ref(), y.as_ref(), &init, Some(cold.inputs()), &opts).unwrap();
    assert!(rep.inducing.unwrap().iterations <= 2);
}

#[test]
fn bad_inducing_inputs_are_rejected_with_their_position() {
    let mut rng = ChaCha8Rng::seed_from_u64(27);
    let x = normal_mat(10, 2, &mut rng);
    let y = smooth(&x, 1, &mut rng);
    let hyp = vec![hyp_for(&x, &mut rng)];
    let mut u = normal_mat(4, 2, &mut rng);
    u[(2, 1)] = f64::NAN;
    let err = SparseGpModel::new(x.as_ref(), y.as_ref(), hyp.clone(), u).unwrap_err();
    assert!(
        matches!(err, GpError::NonFinite { row: 2, col: 1, .. }),
        "{err:?}"
    );
    let u = normal_mat(4, 3, &mut rng);
    assert!(matches!(
        SparseGpModel::new(x.as_ref(), y.as_ref(), hyp, u),
        Err(GpError::Shape { .. })
    ));
}

#[test]
fn an_empty_training_set_is_refused_by_every_entry_point() {
    let (x, y) = (Mat::<f64>::zeros(0, 2), Mat::<f64>::zeros(0, 1));
    let hyp = vec![Hyper {
        log_ls: vec![0.0; 2],
        log_sf: 0.0,
        log_sn: -2.0,
    }];
    let names_the_inputs = |err: GpError| {
        assert!(
            matches!(&err, GpError::Shape { what, got, .. }
                if what == "GP training inputs" && got == "0 rows"),
            "{err:?}"
        );
        assert!(err.to_string().contains("at least 1 row"), "{err}");
    };
    names_the_inputs(GpModel::new(x.clone(), y.clone(), hyp.clone()).unwrap_err());
    let u = Mat::<f64>::zeros(3, 2);
    names_the_inputs(SparseGpModel::new(x.as_ref(), y.as_ref(), hyp.clone(), u).unwrap_err());
    names_the_inputs(
        DynamicsModel::fit(
            x.clone(),
            y.clone(),
            &hyp,
            None,
            &DynamicsOptions::default(),
        )
        .unwrap_err(),
    );
    let sparse = SparseTrainOptions::default();
    names_the_inputs(train_sparse(x.as_ref(), y.as_ref(), &hyp, None, &sparse).unwrap_err());
}

#[test]
fn a_prediction_input_of_the_wrong_length_is_a_shape_error() {
    let mut rng = ChaCha8Rng::seed_from_u64(28);
    let x = normal_mat(12, 2, &mut rng);
    let y = smooth(&x, 1, &mut rng);
    let hyp = vec![hyp_for(&x, &mut rng)];
    let full = GpModel::new(x.clone(), y.clone(), hyp.clone()).unwrap();
    let sparse =
        SparseGpModel::new(x.as_ref(), y.as_ref(), hyp, normal_mat(4, 2, &mut rng)).unwrap();
    for bad in [&[0.1][..], &[0.1, 0.2, 0.3][..]] {
        for (name, err) in [
            ("full", full.predict(bad).unwrap_err()),
            ("sparse", sparse.predict(bad).unwrap_err()),
            (
                "dynamics",
                DynamicsModel::Full(full.clone()).predict(bad).unwrap_err(),
            ),
        ] {
            assert!(
                matches!(&err, GpError::Shape { what, .. } if what == "GP prediction input x"),
                "{name}: {err:?}"
            );
            let want = format!("got length {}", bad.len());
            assert!(err.to_string().contains(&want), "{name}: {err}");
        }
    }
    assert!(full.predict(&[0.1, 0.2]).is_ok() && sparse.predict(&[0.1, 0.2]).is_ok());
}

#[test]
fn fitc_nlml_names_a_nan_in_its_data_as_training_does() {
    let mut rng = ChaCha8Rng::seed_from_u64(29);
    let mut x = normal_mat(10, 2, &mut rng);
    let mut y = col(&smooth(&x, 1, &mut rng), 0);
    let h = hyp_for(&x, &mut rng);
    let mut u = normal_mat(4, 2, &mut rng);
    x[(3, 0)] = f64::NAN;
    let err = fitc_nlml(x.as_ref(), &y, &h, u.as_ref()).unwrap_err();
    assert!(
        matches!(&err, GpError::NonFinite { what, row: 3, col: 0, .. } if what == "GP training inputs"),
        "{err:?}"
    );
    x[(3, 0)] = 0.0;
    y[8] = f64::NAN;
    let err = fitc_nlml(x.as_ref(), &y, &h, u.as_ref()).unwrap_err();
    assert!(
        matches!(&err, GpError::NonFinite { what, row: 8, col: 0, .. } if what == "GP training targets"),
        "{err:?}"
    );
    y[8] = 0.0;
    u[(1, 1)] = f64::INFINITY;
    let err = fitc_nlml(x.as_ref(), &y, &h, u.as_ref()).unwrap_err();
    assert!(
        matches!(&err, GpError::NonFinite { what, row: 1, col: 1, .. } if what == "inducing inputs"),
        "{err:?}"
    );
    assert!(fitc_nlml(x.as_ref(), &y, &h, normal_mat(4, 2, &mut rng).as_ref()).is_ok());
}
