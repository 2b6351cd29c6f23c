//! The linear (affine) policy, PILCO's `conlin` (thesis eq. 3-21).
//!
//! `u = w x + b` with `w` E×D and `b` of length E. For `x ~ N(m, s)`:
//! `M = w m + b`, `S = w s wᵀ`, `V = s⁻¹ Cov[x, u] = wᵀ`.
//!
//! Backward, with adjoints `M̄`, `S̄`, `V̄`:
//! `m̄ = wᵀ M̄`, `s̄ = sym(wᵀ S̄ w)`, `b̄ = M̄`, `w̄ = M̄ mᵀ + S̄ w sᵀ + S̄ᵀ w s + V̄ᵀ`.
//! Flat parameters (PILCO's `unwrap` of the struct `{b, w}`): `p = [b (E); w(:) (E·D)]`,
//! `w` column-major, so `w[i][j]` is `p[E + j·E + i]`.

use super::Policy;
use crate::error::{check_finite, check_len, PilcoError, Result};
use crate::util::{check_input, symmetrise};
use crate::{GaussianBar, Moments, MomentsBar};
use faer::{Mat, MatRef};

/// `u = w x + b`.
#[derive(Clone, Debug)]
pub struct LinearPolicy {
    w: Mat<f64>,
    b: Vec<f64>,
}

/// What [`LinearPolicy`]'s backward needs: the input mean and `s wᵀ`.
#[derive(Clone, Debug)]
pub struct LinearCache {
    m: Vec<f64>,
    swt: Mat<f64>,
}

impl LinearPolicy {
    /// `w` is E×D, `b` has length E.
    pub fn new(w: MatRef<'_, f64>, b: &[f64]) -> Result<Self> {
        check_len(
            "linear policy offset b (one per action)",
            w.nrows(),
            b.len(),
        )?;
        check_finite("linear policy offset b", b)?;
        let w = w.to_owned();
        for i in 0..w.nrows() {
            for j in 0..w.ncols() {
                if !w[(i, j)].is_finite() {
                    return Err(PilcoError::Invalid {
                        what: "linear policy weights w".into(),
                        detail: format!("entry ({i}, {j}) is {}", w[(i, j)]),
                    });
                }
            }
        }
        Ok(Self { w, b: b.to_vec() })
    }

    /// All-zero weights and offsets.
    pub fn zeros(d: usize, e: usize) -> Self {
        Self {
            w: Mat::zeros(e, d),
            b: vec![0.0; e],
        }
    }

    /// The weights `w` (E×D), `p[E..]` column-major in [`Policy::params`].
    pub fn w(&self) -> &Mat<f64> {
        &self.w
    }

    /// The offset `b` (E), the action at `x = 0`; `p[..E]` in [`Policy::params`].
    pub fn b(&self) -> &[f64] {
        &self.b
    }
}

impl Policy for LinearPolicy {
    type Cache = LinearCache;

    fn n_inputs(&self) -> usize {
        self.w.ncols()
    }

    fn n_outputs(&self) -> usize {
        self.w.nrows()
    }

    fn n_params(&self) -> usize {
        self.w.nrows() * (1 + self.w.ncols())
    }

    fn params(&self) -> Vec<f64> {
        let (e, d) = (self.w.nrows(), self.w.ncols());
        let mut p = Vec::with_capacity(e * (d + 1));
        p.extend_from_slice(&self.b);
        for j in 0..d {
            for i in 0..e {
                p.push(self.w[(i, j)]);
            }
        }
        p
    }

    fn set_params(&mut self, p: &[f64]) -> Result<()> {
        check_len(
            "linear policy parameters [b; w(:)]",
            self.n_params(),
            p.len(),
        )?;
        check_finite("linear policy parameters", p)?;
        let (e, d) = (self.w.nrows(), self.w.ncols());
        self.b.copy_from_slice(&p[..e]);
        for j in 0..d {
            for i in 0..e {
                self.w[(i, j)] = p[e + j * e + i];
            }
        }
        Ok(())
    }

    fn forward(&self, m: &[f64], s: MatRef<'_, f64>) -> Result<(Moments, LinearCache)> {
        let (e, d) = (self.w.nrows(), self.w.ncols());
        check_input("linear policy", d, m, s)?;
        let w = &self.w;
        let mean = (0..e)
            .map(|i| self.b[i] + (0..d).map(|j| w[(i, j)] * m[j]).sum::<f64>())
            .collect();
        let swt = s * w.transpose();
        let mut cov = w * &swt;
        symmetrise(&mut cov);
        let c = w.transpose().to_owned();
        Ok((
            Moments { mean, cov, v: c },
            LinearCache { m: m.to_vec(), swt },
        ))
    }

    fn backward(&self, cache: &LinearCache, bar: &MomentsBar, p_bar: &mut [f64]) -> GaussianBar {
        let (e, d) = (self.w.nrows(), self.w.ncols());
        assert_eq!(p_bar.len(), self.n_params(), "linear policy: p_bar length");
        let w = &self.w;
        let mut out = GaussianBar::zeros(d);
        for j in 0..d {
            out.mean[j] = (0..e).map(|i| w[(i, j)] * bar.mean[i]).sum();
        }
        let sbar_w = &bar.cov * w; // S̄ w, E×D
        out.cov = w.transpose() * &sbar_w;
        symmetrise(&mut out.cov);

        // w̄ = M̄ mᵀ + S̄ w sᵀ + S̄ᵀ w s + V̄ᵀ = M̄ mᵀ + (S̄ + S̄ᵀ) (s wᵀ)ᵀ + V̄ᵀ  (s symmetric)
        let sym_bar = &bar.cov + bar.cov.transpose();
        let g = &sym_bar * cache.swt.transpose(); // E×D
        for (pb, mb) in p_bar[..e].iter_mut().zip(&bar.mean) {
            *pb += mb;
        }
        for j in 0..d {
            for i in 0..e {
                let mut v = bar.mean[i] * cache.m[j] + g[(i, j)];
                if let Some(vb) = &bar.v {
                    v += vb[(j, i)];
                }
                p_bar[e + j * e + i] += v;
            }
        }
        out
    }

    /// Panics when `x` is not of length [`Policy::n_inputs`], as [`super::RbfPolicy`]'s does:
    /// extra entries would be silently dropped and a short input read out of bounds.
    fn action(&self, x: &[f64]) -> Vec<f64> {
        let (e, d) = (self.w.nrows(), self.w.ncols());
        assert!(
            x.len() == d,
            "linear policy action: input of length {}, expected {d}",
            x.len()
        );
        (0..e)
            .map(|i| self.b[i] + (0..d).map(|j| self.w[(i, j)] * x[j]).sum::<f64>())
            .collect()
    }
}
