//! Finite-difference checks of the squashing blocks' VJPs (gSat, partial non-negative
//! saturation, gTrig) and sanity checks of their values.

mod common;

use common::*;
use faer::Mat;
use std::f64::consts::FRAC_PI_2;
use vicpilco_pilco::squash::{PartialSat, SatRange, SineSat, TrigAug};

/// (d, indices) combinations, including a repeated index.
fn layouts() -> Vec<(usize, Vec<usize>)> {
    vec![
        (1, vec![0]),
        (3, vec![1]),
        (3, vec![0, 2]),
        (4, vec![3, 0, 1, 2]),
        (5, vec![4, 1, 4]),
        (7, vec![0, 2, 3, 5, 6]),
    ]
}

#[test]
fn gsat_vjp_matches_finite_differences() {
    let mut r = rng(11);
    for (d, idx) in layouts() {
        for _rep in 0..3 {
            let e: Vec<f64> = idx.iter().map(|_| 0.5 + normal(&mut r).abs()).collect();
            let sat = SineSat::new(d, &idx, &e).unwrap();
            let m = rand_vec(&mut r, d, 1.0);
            let s = rand_spd(&mut r, d, 0.5);
            let i = idx.len();
            let f = |m: &[f64], s: &Mat<f64>| flat_moments(&sat.forward(m, s.as_ref()).0);
            let vjp = |m: &[f64], s: &Mat<f64>, yb: &[f64]| {
                let (_, cache) = sat.forward(m, s.as_ref());
                sat.backward(&cache, &moments_bar(yb, i, d))
            };
            check_vjp(&mut r, &m, &s, &f, &vjp);
        }
    }
}

#[test]
fn gtrig_vjp_matches_finite_differences() {
    let mut r = rng(12);
    for (d, idx) in layouts() {
        for _rep in 0..3 {
            let e: Vec<f64> = idx.iter().map(|_| normal(&mut r)).collect();
            let trig = TrigAug::new(d, &idx, &e).unwrap();
            let m = rand_vec(&mut r, d, 2.0);
            let s = rand_spd(&mut r, d, 0.5);
            let n = 2 * idx.len();
            let f = |m: &[f64], s: &Mat<f64>| flat_moments(&trig.forward(m, s.as_ref()).0);
            let vjp = |m: &[f64], s: &Mat<f64>, yb: &[f64]| {
                let (_, cache) = trig.forward(m, s.as_ref());
                trig.backward(&cache, &moments_bar(yb, n, d))
            };
            check_vjp(&mut r, &m, &s, &f, &vjp);
        }
    }
}

#[test]
fn partial_saturation_vjp_matches_finite_differences() {
    let mut r = rng(13);
    for (d, idx) in layouts() {
        let ranges: Vec<SatRange> = idx
            .iter()
            .enumerate()
            .map(|(j, _)| {
                if j % 2 == 0 {
                    SatRange::Bounded {
                        a_min: 10.0,
                        a_max: 500.0,
                    }
                } else {
                    SatRange::Symmetric { a_max: 0.02 }
                }
            })
            .collect();
        let sat = PartialSat::new(d, &idx, &ranges).unwrap();
        let m = rand_vec(&mut r, d, 1.0);
        let s = rand_spd(&mut r, d, 0.3);
        let i = idx.len();
        let f = |m: &[f64], s: &Mat<f64>| flat_moments(&sat.forward(m, s.as_ref()).0);
        let vjp = |m: &[f64], s: &Mat<f64>, yb: &[f64]| {
            let (_, cache) = sat.forward(m, s.as_ref());
            sat.backward(&cache, &moments_bar(yb, i, d))
        };
        check_vjp(&mut r, &m, &s, &f, &vjp);
    }
}

#[test]
fn partial_saturation_maps_onto_the_intended_intervals() {
    let ranges = [
        SatRange::Bounded {
            a_min: 50.0,
            a_max: 800.0,
        },
        SatRange::Symmetric { a_max: 0.1 },
    ];
    let sat = PartialSat::new(2, &[0, 1], &ranges).unwrap();
    let hi = sat.apply(&[FRAC_PI_2, FRAC_PI_2]);
    let lo = sat.apply(&[-FRAC_PI_2, -FRAC_PI_2]);
    assert!((hi[0] - 800.0).abs() < 1e-10 && (lo[0] - 50.0).abs() < 1e-10);
    assert!((hi[1] - 0.1).abs() < 1e-15 && (lo[1] + 0.1).abs() < 1e-15);
    // Every input stays inside [a_min, a_max] (gains strictly positive).
    for k in -400..=400 {
        let x = k as f64 * 0.01;
        let u = sat.apply(&[x, x]);
        assert!(
            (50.0 - 1e-9..=800.0 + 1e-9).contains(&u[0]),
            "{x} → {}",
            u[0]
        );
        assert!(u[1].abs() <= 0.1 + 1e-15);
    }
    // Moments: the bounded output is the affine image of gSat with e = (a_max − a_min)/2.
    let mut r = rng(14);
    let m = rand_vec(&mut r, 2, 1.0);
    let s = rand_spd(&mut r, 2, 0.4);
    let (p, _) = sat.forward(&m, s.as_ref());
    let (g, _) = SineSat::new(2, &[0, 1], &[375.0, 0.1])
        .unwrap()
        .forward(&m, s.as_ref());
    assert!((p.mean[0] - (425.0 + g.mean[0])).abs() < 1e-12);
    assert!((p.mean[1] - g.mean[1]).abs() < 1e-15);
    assert_eq!(flat(&p.cov), flat(&g.cov));
    assert_eq!(flat(&p.v), flat(&g.v));
    assert!(PartialSat::new(
        1,
        &[0],
        &[SatRange::Bounded {
            a_min: 0.0,
            a_max: 1.0
        }]
    )
    .is_err());
    assert!(PartialSat::new(
        1,
        &[0],
        &[SatRange::Bounded {
            a_min: 2.0,
            a_max: 1.0
        }]
    )
    .is_err());
}

/// Monte Carlo agrees with the exact moments (a check of the formulas, not of derivatives).
#[test]
fn gsat_and_gtrig_moments_agree_with_sampling() {
    let mut r = rng(15);
    let (d, idx) = (3, vec![0, 2]);
    let m = vec![0.3, -0.2, 1.1];
    let s = rand_spd(&mut r, d, 0.5);
    let sat = SineSat::new(d, &idx, &[1.0, 2.0]).unwrap();
    let trig = TrigAug::new(d, &idx, &[1.0, 1.0]).unwrap();
    let x = [0.7, 9.0, -2.0];
    assert_eq!(
        trig.apply(&x),
        vec![x[0].sin(), x[0].cos(), x[2].sin(), x[2].cos()]
    );
    assert_eq!(
        sat.apply(&x)[1],
        2.0 * (9.0 * x[2].sin() + (3.0 * x[2]).sin()) / 8.0
    );
    let xs = sample_gaussian(&mut r, &m, &s, 20000);
    for (mom, fx) in [
        (
            sat.forward(&m, s.as_ref()).0,
            Box::new(|x: &[f64]| sat.apply(x)) as Box<dyn Fn(&[f64]) -> Vec<f64>>,
        ),
        (
            trig.forward(&m, s.as_ref()).0,
            Box::new(|x: &[f64]| trig.apply(x)),
        ),
    ] {
        let ys: Vec<Vec<f64>> = xs.iter().map(|x| fx(x)).collect();
        let n = ys.len() as f64;
        let e = mom.mean.len();
        for a in 0..e {
            let ma = ys.iter().map(|y| y[a]).sum::<f64>() / n;
            assert!(
                (ma - mom.mean[a]).abs() < 0.03,
                "mean {a}: {ma} vs {}",
                mom.mean[a]
            );
            for b in 0..e {
                let mb = ys.iter().map(|y| y[b]).sum::<f64>() / n;
                let cab = ys.iter().map(|y| (y[a] - ma) * (y[b] - mb)).sum::<f64>() / n;
                assert!((cab - mom.cov[(a, b)]).abs() < 0.03, "cov {a}{b}");
            }
            // Cov[x, y] = s C
            for k in 0..d {
                let mk = xs.iter().map(|x| x[k]).sum::<f64>() / n;
                let cxy = xs
                    .iter()
                    .zip(&ys)
                    .map(|(x, y)| (x[k] - mk) * (y[a] - ma))
                    .sum::<f64>()
                    / n;
                let want: f64 = (0..d).map(|l| s[(k, l)] * mom.v[(l, a)]).sum();
                assert!((cxy - want).abs() < 0.03, "cross {k}{a}: {cxy} vs {want}");
            }
        }
    }
}

#[test]
fn invalid_definitions_are_rejected() {
    assert!(SineSat::new(2, &[2], &[1.0]).is_err());
    assert!(SineSat::new(2, &[0, 1], &[1.0]).is_err());
    assert!(TrigAug::new(2, &[0], &[f64::NAN]).is_err());
}

#[test]
fn the_preimage_inverts_each_range_on_the_branch_through_zero() {
    let ranges = [
        SatRange::Symmetric { a_max: 0.0025 },
        SatRange::Bounded {
            a_min: 5.0,
            a_max: 250.0,
        },
    ];
    for r in ranges {
        let sat = PartialSat::new(1, &[0], &[r]).unwrap();
        let (lo, hi) = r.bounds();
        for k in 0..=40 {
            let u = lo + (hi - lo) * k as f64 / 40.0;
            let x = r.preimage(u);
            assert!(x.abs() <= FRAC_PI_2 + 1e-12, "{r:?}: {u} -> {x}");
            let back = sat.apply(&[x])[0];
            assert!(
                (back - u).abs() <= 1e-9 * (hi - lo),
                "{r:?}: {u} -> {x} -> {back}"
            );
        }
        // Outside the range: the nearest bound's preimage.
        assert_eq!(r.preimage(hi + 1.0), r.preimage(hi));
        assert_eq!(r.preimage(lo - 1.0), r.preimage(lo));
    }
    assert!(SatRange::Symmetric { a_max: 1.0 }.preimage(0.0).abs() < 1e-15);
}
