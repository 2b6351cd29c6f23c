//! The linear policy: VJP for the input and the parameters against finite differences, the
//! flat parameter order, and accumulation into the parameter adjoint buffer.

mod common;

use common::*;
use faer::Mat;
use vicpilco_gp::fd;
use vicpilco_pilco::policy::{LinearPolicy, Policy};

#[test]
fn linear_policy_input_vjp_matches_finite_differences() {
    let mut r = rng(31);
    for (d, e) in [(1, 1), (2, 1), (3, 2), (5, 3), (7, 2)] {
        let pol = LinearPolicy::new(
            rand_mat(&mut r, e, d, 1.0).as_ref(),
            &rand_vec(&mut r, e, 1.0),
        )
        .unwrap();
        let m = rand_vec(&mut r, d, 1.0);
        let s = rand_spd(&mut r, d, 0.5);
        let f = |m: &[f64], s: &Mat<f64>| flat_moments(&pol.forward(m, s.as_ref()).unwrap().0);
        let vjp = |m: &[f64], s: &Mat<f64>, yb: &[f64]| {
            let (_, cache) = pol.forward(m, s.as_ref()).unwrap();
            let mut pb = vec![0.0; pol.n_params()];
            pol.backward(&cache, &moments_bar(yb, e, d), &mut pb)
        };
        check_vjp(&mut r, &m, &s, &f, &vjp);
    }
}

#[test]
fn linear_policy_parameter_vjp_matches_finite_differences() {
    let mut r = rng(32);
    for (d, e) in [(1, 1), (3, 2), (5, 3)] {
        let mut pol = LinearPolicy::zeros(d, e);
        let p0 = rand_vec(&mut r, pol.n_params(), 1.0);
        pol.set_params(&p0).unwrap();
        let m = rand_vec(&mut r, d, 1.0);
        let s = rand_spd(&mut r, d, 0.5);
        let ny = e + e * e + d * e;
        let ybar = rand_vec(&mut r, ny, 1.0);
        let (_, cache) = pol.forward(&m, s.as_ref()).unwrap();
        // Accumulates: start from a non-zero buffer.
        let mut pb = vec![1.0; pol.n_params()];
        pol.backward(&cache, &moments_bar(&ybar, e, d), &mut pb);
        pb.iter_mut().for_each(|v| *v -= 1.0);
        for _ in 0..3 {
            let dir = rand_vec(&mut r, p0.len(), 1.0);
            let mut g = |p: &[f64]| {
                let mut q = pol.clone();
                q.set_params(p).unwrap();
                dot(&ybar, &flat_moments(&q.forward(&m, s.as_ref()).unwrap().0))
            };
            let numeric = fd::directional(&mut g, &p0, &dir, 1e-4);
            let analytic = dot(&pb, &dir);
            let err = fd::rel_diff(analytic, numeric, 1e-6);
            assert!(err < 1e-8, "{analytic} vs {numeric}");
        }
    }
}

#[test]
fn linear_policy_moments_and_flat_order() {
    // w = [[1, 2, 3], [4, 5, 6]], b = [7, 8]: p = [b; w(:)] = [7, 8, 1, 4, 2, 5, 3, 6].
    let w = Mat::from_fn(2, 3, |i, j| (3 * i + j + 1) as f64);
    let pol = LinearPolicy::new(w.as_ref(), &[7.0, 8.0]).unwrap();
    assert_eq!(pol.params(), vec![7.0, 8.0, 1.0, 4.0, 2.0, 5.0, 3.0, 6.0]);
    let mut q = LinearPolicy::zeros(3, 2);
    q.set_params(&pol.params()).unwrap();
    assert_eq!(flat(q.w()), flat(&w));
    assert_eq!(q.b(), &[7.0, 8.0]);
    assert!(q.set_params(&[1.0]).is_err());

    let m = [1.0, -1.0, 0.5];
    let s = Mat::from_fn(3, 3, |i, j| if i == j { 2.0 } else { 0.5 });
    let (o, _) = pol.forward(&m, s.as_ref()).unwrap();
    assert_eq!(o.mean, pol.action(&m));
    assert_eq!(o.mean, vec![7.0 + 1.0 - 2.0 + 1.5, 8.0 + 4.0 - 5.0 + 3.0]);
    let want = &w * &s * w.transpose();
    assert_eq!(flat(&o.cov), flat(&want));
    assert_eq!(flat(&o.v), flat(&w.transpose().to_owned()));
}

#[test]
fn rbf_param_scales_put_centres_in_length_scale_units() {
    use vicpilco_pilco::policy::{CentreScale, RbfPolicy};
    let (n, d, e) = (3, 2, 2);
    let centres = Mat::from_fn(n, d, |i, c| 10.0 + (i * d + c) as f64);
    let targets = Mat::from_fn(n, e, |i, a| 0.1 * (i + a) as f64);
    // ℓ for input 0: 0.1 and 0.4 (geometric mean 0.2, smallest 0.1); input 1: 2 and 2.
    let log_ls = Mat::from_fn(d, e, |c, a| match (c, a) {
        (0, 0) => 0.1f64.ln(),
        (0, _) => 0.4f64.ln(),
        _ => 2.0f64.ln(),
    });
    let pol = RbfPolicy::new(centres.clone(), targets, log_ls.as_ref(), 100.0).unwrap();
    let p = pol.params();
    for (rule, input0) in [
        (CentreScale::GeometricMean, 0.2),
        (CentreScale::Smallest, 0.1),
    ] {
        let scales = pol.param_scales(rule);
        assert_eq!(scales.len(), pol.n_params());
        for (k, (&pk, &sk)) in p.iter().zip(&scales).enumerate() {
            // Exactly the centre entries (values ≥ 10 here) are scaled, each by its input's ℓ.
            let centre = (0..n)
                .flat_map(|i| (0..d).map(move |c| (i, c)))
                .find(|&(i, c)| centres[(i, c)] == pk);
            match centre {
                Some((_, 0)) => assert!((sk - input0).abs() < 1e-12, "{rule:?} {k}: {sk}"),
                Some((_, _)) => assert!((sk - 2.0).abs() < 1e-12, "{rule:?} {k}: {sk}"),
                None => assert_eq!(sk, 1.0, "{rule:?} entry {k}"),
            }
        }
    }
}

#[test]
fn rbf_log_lengthscales_of_the_wrong_shape_are_refused_naming_log_ls() {
    use vicpilco_pilco::policy::RbfPolicy;
    let (n, d, e) = (3, 2, 2);
    let centres = Mat::from_fn(n, d, |i, c| (i * d + c) as f64);
    let targets = Mat::from_fn(n, e, |i, a| 0.1 * (i + a) as f64);
    // Too few columns used to panic on an index, too many were silently ignored, and a wrong
    // row count was reported as another output's length-scales.
    for (rows, cols) in [(d, e - 1), (d, e + 1), (d + 1, e)] {
        let log_ls = Mat::<f64>::zeros(rows, cols);
        let err = RbfPolicy::new(centres.clone(), targets.clone(), log_ls.as_ref(), 100.0)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("log_ls") && err.contains(&format!("got {rows}×{cols}")),
            "{err}"
        );
    }
    let log_ls = Mat::<f64>::zeros(d, e);
    assert!(RbfPolicy::new(centres, targets, log_ls.as_ref(), 100.0).is_ok());
}

/// The forward pass returns a `Result`, so an input of the wrong size is an error naming the
/// block (it used to panic), for the linear policy as for the RBF policy.
#[test]
fn policy_forward_refuses_an_input_of_the_wrong_size_with_an_error() {
    use vicpilco_pilco::policy::RbfPolicy;
    let linear = LinearPolicy::zeros(2, 1);
    let centres = Mat::from_fn(3, 2, |i, c| (i + c) as f64);
    let rbf = RbfPolicy::new(
        centres,
        Mat::zeros(3, 1),
        Mat::<f64>::zeros(2, 1).as_ref(),
        100.0,
    )
    .unwrap();
    let s1 = Mat::from_fn(1, 1, |_, _| 0.1);
    let s2 = Mat::from_fn(2, 2, |i, j| if i == j { 0.1 } else { 0.0 });
    let s3 = Mat::from_fn(3, 3, |i, j| if i == j { 0.1 } else { 0.0 });
    for (m, s) in [
        (&[0.0][..], s1.as_ref()),
        (&[0.0, 0.0, 0.0][..], s3.as_ref()),
        (&[0.0, 0.0][..], s1.as_ref()),
    ] {
        let err = linear.forward(m, s).expect_err("refused").to_string();
        assert!(err.contains("linear policy input"), "{err}");
        assert!(rbf.forward(m, s).is_err());
    }
    assert!(linear.forward(&[0.0, 0.0], s2.as_ref()).is_ok());
}

/// `action` cannot return an error; an input of the wrong length stops it with a message
/// instead of dropping the extra entries (as the RBF policy's does).
#[test]
#[should_panic(expected = "linear policy action: input of length 3, expected 2")]
fn linear_policy_action_refuses_extra_entries() {
    LinearPolicy::zeros(2, 1).action(&[0.0, 0.0, 5.0]);
}

#[test]
#[should_panic(expected = "linear policy action: input of length 1, expected 2")]
fn linear_policy_action_refuses_a_short_input() {
    LinearPolicy::zeros(2, 1).action(&[0.0]);
}
