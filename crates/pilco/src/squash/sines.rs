//! The engine behind [`SineSat`](super::SineSat), [`PartialSat`](super::PartialSat) and
//! [`TrigAug`](super::TrigAug): exact moments of linear combinations of sinusoids of
//! Gaussian variables.
//!
//! A block is a list of *features* `g_r = sin(k_r x_{i_r} + q_r·π/2)` (a sine, or with
//! `q_r = 1` a cosine), each added with coefficient `a_r` into output `o_r`:
//! `y_j = Σ_{r: o_r = j} a_r g_r`. With `w_r = k_r x_{i_r} + q_r π/2 ~ N(μ_r, v_rr)`,
//! `v_rq = k_r k_q s_{i_r i_q}`, the identities used are (PILCO's `gSin`, `gSat`, `gTrig`)
//!
//! * `E[sin w_r] = exp(−v_rr/2) sin μ_r`, `E[cos w_r] = exp(−v_rr/2) cos μ_r`;
//! * `E[sin w_r sin w_q] = ½ (e⁻ cos(μ_r − μ_q) − e⁺ cos(μ_r + μ_q))`,
//!   `e∓ = exp(−(v_rr + v_qq ∓ 2 v_rq)/2)` (the variances of `w_r ∓ w_q`);
//! * `Cov[x, sin w_r] = Cov[x, w_r] E[cos w_r] = k_r s[:, i_r] E[cos w_r]`, so
//!   `s⁻¹ Cov[x, g_r] = k_r E[cos w_r] · unit_{i_r}`: the input-output term needs no inverse of
//!   `s` and is exact whenever `s` is invertible.
//!
//! Phases are kept as whole quarter turns, so a cosine is computed as `cos`, not as
//! `sin(x + π/2)` rounded.
//!
//! The cost is O(R²) for R features; the backward recomputes the pair terms instead of
//! caching R² of them.

use crate::util::symmetrise;
use crate::{GaussianBar, Moments, MomentsBar};
use faer::{Mat, MatRef};

/// One sinusoidal feature `a · sin(k x_idx + quarter·π/2)` added into output `out`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Feature {
    pub idx: usize,
    pub k: f64,
    pub quarter: i32,
    pub out: usize,
    pub coef: f64,
}

/// `(sin(x + q π/2), cos(x + q π/2))` from `(sin x, cos x)`.
#[inline]
fn rot(sc: (f64, f64), q: i32) -> (f64, f64) {
    let (s, c) = sc;
    match q.rem_euclid(4) {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// A linear combination of sinusoidal features of a D-dimensional Gaussian input.
#[derive(Clone, Debug)]
pub(crate) struct Sines {
    pub d: usize,
    pub n_out: usize,
    pub feats: Vec<Feature>,
}

/// What the backward of a sine block (gSat, gTrig, partial saturation) needs from the forward pass: feature means (without the phase)
/// and the feature covariance `v` (R×R), and `exp(−v_rr/2)`.
#[derive(Clone, Debug)]
pub struct SinesCache {
    mu: Vec<f64>,
    v: Mat<f64>,
    h: Vec<f64>,
}

impl Sines {
    pub fn forward(&self, m: &[f64], s: MatRef<'_, f64>) -> (Moments, SinesCache) {
        let f = &self.feats;
        let r_n = f.len();
        let mu: Vec<f64> = f.iter().map(|ft| ft.k * m[ft.idx]).collect();
        let v = Mat::from_fn(r_n, r_n, |r, q| f[r].k * f[q].k * s[(f[r].idx, f[q].idx)]);
        let h: Vec<f64> = (0..r_n).map(|r| (-0.5 * v[(r, r)]).exp()).collect();
        // E[sin w_r], E[cos w_r]
        let (es, ec): (Vec<f64>, Vec<f64>) = (0..r_n)
            .map(|r| {
                let (sn, cs) = rot(mu[r].sin_cos(), f[r].quarter);
                (h[r] * sn, h[r] * cs)
            })
            .unzip();

        let mut mean = vec![0.0; self.n_out];
        let mut cov = Mat::zeros(self.n_out, self.n_out);
        let mut c = Mat::zeros(self.d, self.n_out);
        for r in 0..r_n {
            mean[f[r].out] += f[r].coef * es[r];
            c[(f[r].idx, f[r].out)] += f[r].coef * f[r].k * ec[r];
            for q in 0..=r {
                let p = self.pair(&mu, &v, r, q).p;
                let g = f[r].coef * f[q].coef * (p - es[r] * es[q]);
                cov[(f[r].out, f[q].out)] += g;
                if q != r {
                    cov[(f[q].out, f[r].out)] += g;
                }
            }
        }
        symmetrise(&mut cov);
        (Moments { mean, cov, v: c }, SinesCache { mu, v, h })
    }

    /// `E[sin w_r sin w_q]` and its partial derivatives.
    #[inline]
    fn pair(&self, mu: &[f64], v: &Mat<f64>, r: usize, q: usize) -> Pair {
        let (fr, fq) = (&self.feats[r], &self.feats[q]);
        let (vr, vq, vrq) = (v[(r, r)], v[(q, q)], v[(r, q)]);
        let em = (-0.5 * (vr + vq - 2.0 * vrq)).exp();
        let ep = (-0.5 * (vr + vq + 2.0 * vrq)).exp();
        let (sd, cd) = rot((mu[r] - mu[q]).sin_cos(), fr.quarter - fq.quarter);
        let (ss, cs) = rot((mu[r] + mu[q]).sin_cos(), fr.quarter + fq.quarter);
        let p = 0.5 * (em * cd - ep * cs);
        Pair {
            p,
            dmu_r: 0.5 * (-em * sd + ep * ss),
            dmu_q: 0.5 * (em * sd + ep * ss),
            dv_diag: -0.5 * p,
            dv_rq: 0.5 * (em * cd + ep * cs),
        }
    }

    /// Vector-Jacobian product: adjoints of `(M, S, C)` → adjoints of `(m, s)`.
    pub fn backward(&self, cache: &SinesCache, bar: &MomentsBar) -> GaussianBar {
        let f = &self.feats;
        let r_n = f.len();
        let SinesCache { mu, v, h } = cache;
        let sc: Vec<(f64, f64)> = (0..r_n)
            .map(|r| rot(mu[r].sin_cos(), f[r].quarter))
            .collect();
        let es: Vec<f64> = (0..r_n).map(|r| h[r] * sc[r].0).collect();

        // Adjoints of E[sin w_r] and E[cos w_r], of μ_r and of v_rq (lower triangle + diag).
        let mut es_bar: Vec<f64> = (0..r_n).map(|r| f[r].coef * bar.mean[f[r].out]).collect();
        let mut ec_bar = vec![0.0; r_n];
        if let Some(cb) = &bar.v {
            for r in 0..r_n {
                ec_bar[r] = f[r].coef * f[r].k * cb[(f[r].idx, f[r].out)];
            }
        }
        let mut mu_bar = vec![0.0; r_n];
        let mut v_bar = Mat::<f64>::zeros(r_n, r_n);
        for r in 0..r_n {
            for q in 0..=r {
                let (or, oq) = (f[r].out, f[q].out);
                let mut g = bar.cov[(or, oq)];
                if q != r {
                    g += bar.cov[(oq, or)];
                }
                g *= f[r].coef * f[q].coef;
                if g == 0.0 {
                    continue;
                }
                let pr = self.pair(mu, v, r, q);
                es_bar[r] -= g * es[q];
                es_bar[q] -= g * es[r];
                mu_bar[r] += g * pr.dmu_r;
                mu_bar[q] += g * pr.dmu_q;
                v_bar[(r, r)] += g * pr.dv_diag;
                v_bar[(q, q)] += g * pr.dv_diag;
                v_bar[(r, q)] += g * pr.dv_rq;
            }
        }
        for r in 0..r_n {
            let (sn, cs) = sc[r];
            // E[sin] = h sin μ, E[cos] = h cos μ, h = exp(−v_rr/2)
            mu_bar[r] += es_bar[r] * h[r] * cs - ec_bar[r] * h[r] * sn;
            v_bar[(r, r)] -= 0.5 * h[r] * (es_bar[r] * sn + ec_bar[r] * cs);
        }

        let mut out = GaussianBar::zeros(self.d);
        for r in 0..r_n {
            out.mean[f[r].idx] += f[r].k * mu_bar[r];
            for q in 0..=r {
                let vb = v_bar[(r, q)];
                if vb != 0.0 {
                    out.cov[(f[r].idx, f[q].idx)] += f[r].k * f[q].k * vb;
                }
            }
        }
        symmetrise(&mut out.cov);
        out
    }
}

struct Pair {
    p: f64,
    dmu_r: f64,
    dmu_q: f64,
    /// ∂p/∂v_rr = ∂p/∂v_qq (as separate entries).
    dv_diag: f64,
    dv_rq: f64,
}
