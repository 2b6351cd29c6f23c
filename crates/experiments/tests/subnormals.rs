//! Learning runs flush subnormals to zero on their thread and the rayon pool's, and flushing
//! leaves the FITC objective and gradient unchanged where the kernel underflows.
//! (Its own test binary: the check needs a process whose rayon pool nobody else started.)

use faer::Mat;
use rand::rngs::ChaCha8Rng;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal, Uniform};
use vicpilco_experiments::subnormals::{flushing_here, run_flushed};
use vicpilco_gp::sparse::fitc_nlml;
use vicpilco_gp::Hyper;

#[test]
fn a_run_flushes_on_its_thread_and_the_pools_and_restores_the_caller() {
    assert!(!flushing_here());
    let (here, pool) = run_flushed(|| (flushing_here(), rayon::broadcast(|_| flushing_here())));
    assert!(here && pool.iter().all(|&f| f), "{here} {pool:?}");
    assert!(!flushing_here());
}

#[test]
fn flushing_keeps_the_fitc_objective_and_gradient_where_the_kernel_underflows() {
    // Points spread over ±1 with length-scales of 0.02: most kernel values between inducing
    // inputs and data are below 1e-300 or subnormal, as for the arm's force outputs.
    let (n, m, d) = (400, 60, 3);
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let spread = Uniform::new(-1.0, 1.0).unwrap();
    let x: Mat<f64> = Mat::from_fn(n, d, |_, _| spread.sample(&mut rng));
    let y: Vec<f64> = (0..n)
        .map(|i| {
            (3.0 * x[(i, 0)]).sin() + 0.01 * Distribution::<f64>::sample(&StandardNormal, &mut rng)
        })
        .collect();
    let u: Mat<f64> = Mat::from_fn(m, d, |i, c| x[(i * 5, c)] + 0.01);
    let hyp = Hyper {
        log_ls: vec![0.02f64.ln(); d],
        log_sf: 0.0,
        log_sn: 0.1f64.ln(),
    };
    let kernel_min = (0..m)
        .flat_map(|i| (0..n).map(move |j| (i, j)))
        .map(|(i, j)| {
            let r2: f64 = (0..d)
                .map(|c| ((u[(i, c)] - x[(j, c)]) / 0.02).powi(2))
                .sum();
            (-0.5 * r2).exp()
        })
        .filter(|k| *k > 0.0)
        .fold(f64::INFINITY, f64::min);
    assert!(
        kernel_min < f64::MIN_POSITIVE,
        "no subnormal kernel value: {kernel_min}"
    );

    let exact = fitc_nlml(x.as_ref(), &y, &hyp, u.as_ref()).unwrap();
    let flushed = run_flushed(|| fitc_nlml(x.as_ref(), &y, &hyp, u.as_ref()).unwrap());
    assert!((exact.value - flushed.value).abs() <= 1e-12 * exact.value.abs());
    for (a, b) in exact.grad_hyp.iter().zip(&flushed.grad_hyp) {
        assert!(
            (a - b).abs() <= 1e-12 * a.abs().max(1.0),
            "d hyp: {a} vs {b}"
        );
    }
    let scale = (0..m)
        .flat_map(|i| (0..d).map(move |c| (i, c)))
        .map(|(i, c)| exact.grad_inducing[(i, c)].abs())
        .fold(0.0, f64::max);
    for i in 0..m {
        for c in 0..d {
            let (a, b) = (exact.grad_inducing[(i, c)], flushed.grad_inducing[(i, c)]);
            assert!((a - b).abs() <= 1e-12 * scale, "dU[{i},{c}]: {a} vs {b}");
        }
    }
}
