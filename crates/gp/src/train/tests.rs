use super::*;
use crate::error::GpError;
use crate::fd;
use faer::Mat;
use rand::rngs::ChaCha8Rng;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;

/// Smooth made-up data: N×D standard-normal inputs, y = sin(Σ x) + 0.1·cos(x_0) + noise.
pub(crate) fn data(n: usize, d: usize, seed: u64) -> (Mat<f64>, Vec<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let x = Mat::from_fn(n, d, |_, _| rng.sample::<f64, _>(StandardNormal));
    let y = smooth_targets(&x, 0, seed);
    (x, y)
}

/// Target k of a smooth made-up function of `x` (k = 0 is the one [`data`] returns), with
/// noise of standard deviation 0.05.
pub(crate) fn smooth_targets(x: &Mat<f64>, k: usize, seed: u64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed_0000 ^ k as u64);
    let (n, d) = (x.nrows(), x.ncols());
    let w = 1.0 + 0.5 * k as f64;
    (0..n)
        .map(|i| {
            let s: f64 = (0..d).map(|c| x[(i, c)]).sum();
            let noise = 0.05 * rng.sample::<f64, _>(StandardNormal);
            if k == 0 {
                s.sin() + 0.1 * x[(i, 0)].cos() + noise
            } else {
                (w * s / d as f64).cos() * (1.0 + 0.2 * k as f64) + 0.3 * x[(i, d - 1)] + noise
            }
        })
        .collect()
}

pub(crate) fn random_hyp(d: usize, rng: &mut ChaCha8Rng) -> Hyper {
    Hyper {
        log_ls: (0..d).map(|_| rng.random_range(-0.5..1.0)).collect(),
        log_sf: rng.random_range(-0.5..0.5),
        log_sn: rng.random_range(-3.0..-1.0),
    }
}

/// A scalar function returning its value and gradient.
pub(crate) type ValueGrad<'a> = dyn FnMut(&[f64]) -> (f64, Vec<f64>) + 'a;

pub(crate) fn check_gradient(f: &mut ValueGrad<'_>, x: &[f64], step: f64, tol: f64) {
    let (_, g) = f(x);
    let mut value = |p: &[f64]| vec![f(p).0];
    let j = fd::jacobian(&mut value, x, step);
    // zip stops at the shorter: a gradient missing entries would pass unchecked.
    assert_eq!(g.len(), x.len(), "analytic gradient length");
    for (k, (a, b)) in g.iter().zip(&j[0]).enumerate() {
        let r = fd::rel_diff(*a, *b, 1e-3);
        assert!(
            r < tol,
            "component {k}: analytic {a}, finite difference {b}, rel {r:e}"
        );
    }
}

#[test]
#[should_panic(expected = "analytic gradient length")]
fn check_gradient_refuses_a_gradient_with_entries_missing() {
    // Right in the entries it has (f = x0² + x1², ∇f = (2x0, 2x1)), but one short.
    let mut f = |p: &[f64]| (p[0] * p[0] + p[1] * p[1], vec![2.0 * p[0]]);
    check_gradient(&mut f, &[0.3, -0.7], 1e-4, 1e-7);
}

#[test]
fn nlml_gradient_matches_finite_differences() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for &(n, d) in &[(5, 1), (30, 3), (100, 7), (30, 7), (100, 1)] {
        let (x, y) = data(n, d, n as u64 * 31 + d as u64);
        let h = random_hyp(d, &mut rng);
        let mut f = |p: &[f64]| {
            let e = nlml(x.as_ref(), &y, &Hyper::from_pilco(p).unwrap()).unwrap();
            (e.value, e.grad)
        };
        check_gradient(&mut f, &h.to_pilco(), 1e-4, 1e-7);
    }
}

#[test]
fn penalised_gradient_matches_finite_differences_also_where_the_penalty_is_large() {
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    let curb = HypCurb::default();
    for &(n, d) in &[(5, 1), (30, 3), (100, 7)] {
        let (x, y) = data(n, d, 7 + n as u64);
        let c = input_std(x.as_ref());
        let mut h = random_hyp(d, &mut rng);
        for extreme in [false, true] {
            if extreme {
                // Length-scale 150× the data spread, SNR ≈ e^7.5 ≈ 1800: penalty ≫ 1.
                h.log_ls[0] = c[0].ln() + 5.0;
                h.log_sf = 2.0;
                h.log_sn = -5.5;
            }
            let (pen, _) = curb.penalty(&h, &c).unwrap();
            assert!(!extreme || pen > 10.0, "penalty {pen} should be large");
            // The penalty alone.
            let mut fp = |p: &[f64]| curb.penalty(&Hyper::from_pilco(p).unwrap(), &c).unwrap();
            check_gradient(&mut fp, &h.to_pilco(), 1e-4, 1e-7);
            // nlml + penalty. At the extreme point K + σ_n²I has condition ~1e8, which puts
            // ~1e-8 relative noise on the value (measured: the 5-point difference moves by
            // ~1e-5 between steps 1e-4 and 1e-5), so it is checked more loosely there.
            let mut f = |p: &[f64]| {
                let e = nlml_curb(x.as_ref(), &y, &Hyper::from_pilco(p).unwrap(), &curb).unwrap();
                (e.value, e.grad)
            };
            let (step, tol) = if extreme { (1e-3, 2e-5) } else { (1e-4, 1e-7) };
            check_gradient(&mut f, &h.to_pilco(), step, tol);
        }
    }
}

fn start(x: &Mat<f64>, y: &[f64]) -> Hyper {
    initial_hyper(x.as_ref(), Mat::from_fn(y.len(), 1, |i, _| y[i]).as_ref()).remove(0)
}

#[test]
fn training_decreases_the_objective_and_warm_start_stops_quickly() {
    let (x, y1) = data(80, 3, 5);
    let y2 = smooth_targets(&x, 1, 5);
    let targets = Mat::from_fn(80, 2, |i, e| if e == 0 { y1[i] } else { y2[i] });
    let init = vec![start(&x, &y1), start(&x, &y2)];
    for penalty in [Some(HypCurb::default()), None] {
        let opts = TrainOptions {
            penalty,
            ..Default::default()
        };
        let (hyp, rep) = train(x.as_ref(), targets.as_ref(), &init, &opts).unwrap();
        assert_eq!(rep.outputs.len(), 2);
        for (e, o) in rep.outputs.iter().enumerate() {
            assert!(
                o.objective < o.initial_objective - 1.0,
                "output {e}: {} → {}",
                o.initial_objective,
                o.objective
            );
            assert!(o.termination.converged(), "output {e}: {:?}", o.termination);
            assert!(o.evaluations as u64 > o.iterations);
            assert_eq!(o.jitter, 0.0);
            // The reported objective is the objective at the returned hyper-parameters.
            let y = if e == 0 { &y1 } else { &y2 };
            let plain = nlml(x.as_ref(), y, &hyp[e]).unwrap().value;
            assert!((plain - o.nlml).abs() < 1e-9 * plain.abs().max(1.0));
        }
        // Warm start from the optimum: converged after at most a couple of iterations.
        let (hyp2, rep2) = train(x.as_ref(), targets.as_ref(), &hyp, &opts).unwrap();
        for (o1, o2) in rep.outputs.iter().zip(&rep2.outputs) {
            assert!(
                o2.iterations <= 3,
                "warm start took {} iterations",
                o2.iterations
            );
            assert!(o2.objective <= o1.objective + 1e-9 * o1.objective.abs().max(1.0));
        }
        assert_eq!(hyp2.len(), 2);
    }
}

#[test]
fn zero_iterations_keep_the_given_hyper_parameters_exactly() {
    // The learning loop builds its "previous hyper-parameters" candidate this way.
    let (x, y) = data(60, 2, 9);
    let targets = Mat::from_fn(60, 1, |i, _| y[i]);
    let init = vec![start(&x, &y)];
    let opts = crate::sparse::DynamicsOptions::default()
        .keeping_hyper_parameters()
        .train;
    let (hyp, rep) = train(x.as_ref(), targets.as_ref(), &init, &opts).unwrap();
    assert_eq!(hyp, init);
    assert_eq!(rep.outputs[0].iterations, 0);
    assert_eq!(rep.outputs[0].objective, rep.outputs[0].initial_objective);
}

#[test]
fn training_is_the_same_on_one_thread_and_on_many() {
    let (x, y1) = data(40, 2, 8);
    let y2 = smooth_targets(&x, 1, 8);
    let targets = Mat::from_fn(40, 2, |i, e| if e == 0 { y1[i] } else { y2[i] });
    let init = vec![start(&x, &y1), start(&x, &y2)];
    let opts = TrainOptions::default();
    let (h_many, _) = train(x.as_ref(), targets.as_ref(), &init, &opts).unwrap();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let (h_one, _) = pool
        .install(|| train(x.as_ref(), targets.as_ref(), &init, &opts))
        .unwrap();
    assert_eq!(h_many, h_one);
}

#[test]
fn nan_in_the_data_names_row_and_column() {
    let (mut x, y) = data(10, 3, 1);
    let mut targets = Mat::from_fn(10, 1, |i, _| y[i]);
    let init = vec![start(&x, &y)];
    x[(7, 2)] = f64::NAN;
    let err = train(
        x.as_ref(),
        targets.as_ref(),
        &init,
        &TrainOptions::default(),
    )
    .unwrap_err();
    match &err {
        GpError::NonFinite { row, col, .. } => assert_eq!((*row, *col), (7, 2)),
        other => panic!("expected NonFinite, got {other:?}"),
    }
    assert!(err.to_string().contains("row 7, column 2"), "{err}");
    x[(7, 2)] = 0.0;
    targets[(3, 0)] = f64::INFINITY;
    let err = train(
        x.as_ref(),
        targets.as_ref(),
        &init,
        &TrainOptions::default(),
    )
    .unwrap_err();
    assert!(
        matches!(err, GpError::NonFinite { row: 3, col: 0, .. }),
        "{err:?}"
    );
}

#[test]
fn duplicate_points_with_tiny_noise_report_jitter_instead_of_failing() {
    // Every input appears twice and the noise is ~1e-12 of the signal: K + σ_n² I is singular
    // to working precision at the start point.
    let (x0, y0) = data(15, 2, 3);
    let x = Mat::from_fn(30, 2, |i, c| x0[(i % 15, c)]);
    let y: Vec<f64> = (0..30).map(|i| y0[i % 15]).collect();
    let targets = Mat::from_fn(30, 1, |i, _| y[i]);
    let mut h = start(&x, &y);
    h.log_sn = h.log_sf - 14.0 * std::f64::consts::LN_10 / 2.0 - 8.0;
    let (_, rep) = train(x.as_ref(), targets.as_ref(), &[h], &TrainOptions::default()).unwrap();
    let o = &rep.outputs[0];
    assert!(o.max_jitter > 0.0, "{o:?}");
    assert!(o.objective.is_finite() && o.objective < o.initial_objective);
}

#[test]
fn shape_errors_are_reported() {
    let (x, y) = data(10, 3, 1);
    let targets = Mat::from_fn(10, 1, |i, _| y[i]);
    let bad = Hyper {
        log_ls: vec![0.0; 2],
        log_sf: 0.0,
        log_sn: -1.0,
    };
    assert!(matches!(
        train(
            x.as_ref(),
            targets.as_ref(),
            &[bad],
            &TrainOptions::default()
        ),
        Err(GpError::Shape { .. })
    ));
}

#[test]
fn cold_restart_keeps_the_better_of_the_warm_start_and_the_first_guess() {
    let (x, y1) = data(80, 3, 9);
    let y2 = smooth_targets(&x, 1, 9);
    let targets = Mat::from_fn(80, 2, |i, e| if e == 0 { y1[i] } else { y2[i] });
    // Output 0 starts on the white-noise plateau (length-scales far below the input spread,
    // where the gradient vanishes); output 1 from a sensible start.
    let plateau = Hyper {
        log_ls: vec![(1e-4f64).ln(); 3],
        log_sf: -3.0,
        log_sn: 0.0,
    };
    let warm = vec![plateau, start(&x, &y2)];
    let plain = TrainOptions::default();
    let (h_warm, r_warm) = train(x.as_ref(), targets.as_ref(), &warm, &plain).unwrap();
    let guess = initial_hyper(x.as_ref(), targets.as_ref());
    let (h_cold, r_cold) = train(x.as_ref(), targets.as_ref(), &guess, &plain).unwrap();
    let both = TrainOptions {
        cold_restart: true,
        ..plain
    };
    let (h, r) = train(x.as_ref(), targets.as_ref(), &warm, &both).unwrap();
    for e in 0..2 {
        let (w, c) = (r_warm.outputs[e].objective, r_cold.outputs[e].objective);
        let picked_cold = c < w;
        assert_eq!(r.outputs[e].from_cold_restart, picked_cold, "output {e}");
        assert_eq!(r.outputs[e].objective, w.min(c), "output {e}");
        assert_eq!(
            h[e],
            if picked_cold { &h_cold[e] } else { &h_warm[e] }.clone()
        );
    }
    assert!(
        r.outputs[0].from_cold_restart,
        "the plateau start must lose: warm {} vs cold {}",
        r_warm.outputs[0].objective, r_cold.outputs[0].objective
    );
}

#[test]
fn initial_hyper_is_pilcos_first_guess() {
    let x = Mat::from_fn(4, 2, |i, j| (i * (j + 1)) as f64);
    let y = Mat::from_fn(4, 1, |i, _| 2.0 * i as f64);
    let h = initial_hyper(x.as_ref(), y.as_ref());
    // Sample std (n − 1) of 0,1,2,3 is √(5/3); of 0,2,4,6 twice that.
    let s = (5.0f64 / 3.0).sqrt();
    assert!((h[0].log_ls[0] - s.ln()).abs() < 1e-12);
    assert!((h[0].log_ls[1] - (2.0 * s).ln()).abs() < 1e-12);
    assert!((h[0].log_sf - (2.0 * s).ln()).abs() < 1e-12);
    assert!((h[0].log_sn - (0.2 * s).ln()).abs() < 1e-12);
}

#[test]
fn floor_penalty_gradient_matches_finite_differences_and_leaves_free_inputs_alone() {
    let mut rng = ChaCha8Rng::seed_from_u64(31);
    let mut h = random_hyp(4, &mut rng);
    // Input 0 at 0.45 of its floor, 1 at half of it, 2 above it, 3 unfloored.
    let floor = [0.3, 0.2, 0.05, 0.0];
    h.log_ls[0] = (0.45f64 * 0.3).ln();
    h.log_ls[1] = (0.1f64).ln();
    h.log_ls[2] = (0.4f64).ln();
    h.log_ls[3] = (1e-6f64).ln();
    let (value, grad) = floor_penalty(&h, &floor);
    let z0 = (1.0f64 / 0.45).ln() / std::f64::consts::LN_2;
    assert!((value - z0.powi(30) - 1.0).abs() <= 1e-12 * value);
    assert!(grad[0] < 0.0 && grad[1] < 0.0);
    assert_eq!(&grad[2..], &[0.0; 4]);
    let mut f = |p: &[f64]| floor_penalty(&Hyper::from_pilco(p).unwrap(), &floor);
    check_gradient(&mut f, &h.to_pilco(), 1e-4, 1e-6);
    // A third of the floor is a wall.
    h.log_ls[0] = (0.1f64).ln();
    assert!(floor_penalty(&h, &floor).0 > 1e5);
}

/// Output 0's reported objective is its plain nlml plus PILCO's `hypCurb` plus `extra`.
fn assert_objective_is_penalised_nlml(
    x: &Mat<f64>,
    y: &[f64],
    held: &Hyper,
    rep: &TrainReport,
    extra: f64,
) {
    let plain = nlml(x.as_ref(), y, held).unwrap().value;
    let curb = HypCurb::default()
        .penalty(held, &input_std(x.as_ref()))
        .unwrap()
        .0;
    let o = &rep.outputs[0];
    assert!((o.objective - (plain + curb + extra)).abs() < 1e-9 * o.objective.abs().max(1.0));
}

#[test]
fn a_lengthscale_floor_keeps_training_off_the_noise_scale() {
    // A floor 4× above a length-scale's free optimum holds it at the penalty's wall, between
    // a third of the floor (penalty 1e6) and the floor.
    let (x, y) = data(60, 2, 3);
    let init = vec![start(&x, &y)];
    let targets = Mat::from_fn(60, 1, |i, _| y[i]);
    let free = train(
        x.as_ref(),
        targets.as_ref(),
        &init,
        &TrainOptions::default(),
    )
    .unwrap()
    .0;
    let l_free = free[0].log_ls[0].exp();
    let floor = vec![4.0 * l_free, 0.0];
    let opts = TrainOptions {
        lengthscale_floor: floor.clone(),
        ..Default::default()
    };
    let (held, rep) = train(x.as_ref(), targets.as_ref(), &init, &opts).unwrap();
    let l_held = held[0].log_ls[0].exp();
    assert!(
        l_held > floor[0] / 3.0 && l_held < floor[0],
        "{l_free} → {l_held}"
    );
    // The reported objective includes the floor penalty.
    let extra = floor_penalty(&held[0], &floor).0;
    assert_objective_is_penalised_nlml(&x, &y, &held[0], &rep, extra);
}

#[test]
fn ceiling_penalty_mirrors_the_floor_and_matches_finite_differences() {
    let mut rng = ChaCha8Rng::seed_from_u64(37);
    let mut h = random_hyp(4, &mut rng);
    // Input 0 at 2.2 times its ceiling, 1 at twice it, 2 below it, 3 free.
    let ceiling = [0.3, 0.2, 0.5, 0.0];
    h.log_ls[0] = (2.2f64 * 0.3).ln();
    h.log_ls[1] = (0.4f64).ln();
    h.log_ls[2] = (0.1f64).ln();
    h.log_ls[3] = (1e6f64).ln();
    let (value, grad) = ceiling_penalty(&h, &ceiling);
    let z0 = 2.2f64.ln() / std::f64::consts::LN_2;
    assert!((value - z0.powi(30) - 1.0).abs() <= 1e-12 * value);
    assert!(grad[0] > 0.0 && grad[1] > 0.0);
    assert_eq!(&grad[2..], &[0.0; 4]);
    let mut f = |p: &[f64]| ceiling_penalty(&Hyper::from_pilco(p).unwrap(), &ceiling);
    check_gradient(&mut f, &h.to_pilco(), 1e-4, 1e-6);
    // The ceiling is the floor reflected through the bound: ℓ = c·r costs what ℓ = c/r does.
    let mut below = h.clone();
    below.log_ls[0] = (0.3f64 / 2.2).ln();
    let floored = floor_penalty(&below, &[0.3]).0;
    assert!((ceiling_penalty(&h, &[0.3]).0 - floored).abs() <= 1e-12 * floored);
    // Three times the ceiling is a wall.
    h.log_ls[0] = (0.9f64).ln();
    assert!(ceiling_penalty(&h, &ceiling).0 > 1e5);
}

#[test]
fn a_lengthscale_ceiling_keeps_an_ignored_input_in_play() {
    // The targets do not depend on input 2, so its free length-scale runs long; a ceiling a
    // quarter of that holds it between the ceiling and three times it (penalty 1e6), and the
    // other inputs' length-scales stay free.
    let (x2, y) = data(60, 2, 3);
    let mut rng = ChaCha8Rng::seed_from_u64(41);
    let x = Mat::from_fn(60, 3, |i, j| {
        if j < 2 {
            x2[(i, j)]
        } else {
            rng.sample::<f64, _>(StandardNormal)
        }
    });
    let init = vec![start(&x, &y)];
    let targets = Mat::from_fn(60, 1, |i, _| y[i]);
    let fit = |opts: &TrainOptions| train(x.as_ref(), targets.as_ref(), &init, opts).unwrap();
    let free = fit(&TrainOptions::default()).0;
    let l_free = free[0].log_ls[2].exp();
    assert!(l_free > 4.0, "input 2 should be all but ignored: {l_free}");
    let ceiling = vec![0.0, 0.0, l_free / 4.0];
    let opts = TrainOptions {
        lengthscale_ceiling: ceiling.clone(),
        ..Default::default()
    };
    let (held, rep) = fit(&opts);
    let l_held = held[0].log_ls[2].exp();
    assert!(
        l_held > ceiling[2] && l_held < 3.0 * ceiling[2],
        "{l_free} → {l_held}"
    );
    // The reported objective includes the ceiling penalty.
    let extra = ceiling_penalty(&held[0], &ceiling).0;
    assert_objective_is_penalised_nlml(&x, &y, &held[0], &rep, extra);
}

#[test]
fn nlml_names_a_nan_in_its_data_as_train_does() {
    let (mut x, mut y) = data(10, 3, 1);
    let h = start(&x, &y);
    x[(4, 1)] = f64::NAN;
    let err = nlml(x.as_ref(), &y, &h).unwrap_err();
    assert!(
        matches!(&err, GpError::NonFinite { what, row: 4, col: 1, .. } if what == "GP training inputs"),
        "{err:?}"
    );
    x[(4, 1)] = 0.0;
    y[6] = f64::NAN;
    let err = nlml_curb(x.as_ref(), &y, &h, &HypCurb::default()).unwrap_err();
    assert!(
        matches!(&err, GpError::NonFinite { what, row: 6, col: 0, .. } if what == "GP training targets"),
        "{err:?}"
    );
}

/// `Hyper::from_pilco` of fewer than 2 entries used to underflow `len − 2` and index out of
/// bounds; `HypCurb::penalty` with fewer c_d than length-scales indexed out of bounds. Both
/// are public and take the caller's numbers, so both are errors naming what is wrong.
#[test]
fn hyper_columns_and_penalty_scales_of_the_wrong_length_are_errors() {
    for col in [&[][..], &[0.5][..]] {
        let msg = Hyper::from_pilco(col).unwrap_err().to_string();
        assert!(msg.contains("PILCO hyper-parameter column"), "{msg}");
        assert!(msg.contains(&format!("got {} entries", col.len())), "{msg}");
    }
    let h = Hyper::from_pilco(&[0.1, 0.2, 0.3, -2.0]).unwrap();
    assert_eq!((h.log_ls, h.log_sf, h.log_sn), (vec![0.1, 0.2], 0.3, -2.0));

    let h = Hyper::from_pilco(&[0.1, 0.2, 0.3, -2.0]).unwrap();
    let curb = HypCurb::default();
    for c in [&[1.0][..], &[1.0, 1.0, 1.0][..]] {
        let msg = curb.penalty(&h, c).unwrap_err().to_string();
        assert!(
            msg.starts_with("hypCurb input_std (c_d): expected length 2"),
            "{msg}"
        );
    }
    assert!(curb.penalty(&h, &[1.0, 2.0]).is_ok());
}
