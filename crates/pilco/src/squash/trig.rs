//! Trigonometric augmentation (PILCO's `gTrig`): angles enter the GP and the policy as
//! `(sin θ, cos θ)`.
//!
//! For `x ~ N(m, s)`, indices `i_1..i_I` and scales `e_1..e_I`, the output has length 2I and is
//! **interleaved**: `y = [e_1 sin x_{i_1}, e_1 cos x_{i_1}, e_2 sin x_{i_2}, …]`. Exact moments:
//!
//! * `E[sin x_i] = exp(−s_ii/2) sin m_i`, `E[cos x_i] = exp(−s_ii/2) cos m_i`;
//! * `E[sin a sin b] = ½(E cos(a−b) − E cos(a+b))`, `E[cos a cos b] = ½(E cos(a−b) + E cos(a+b))`,
//!   `E[sin a cos b] = ½(E sin(a+b) + E sin(a−b))`, with `E cos w = exp(−Var w/2) cos E w`;
//! * `C = s⁻¹Cov[x, y]`: column `2j` is `e_j E[cos x_{i_j}]` and column `2j+1` is
//!   `−e_j E[sin x_{i_j}]`, both on row `i_j` only (`Cov[x, sin x_i] = s[:, i] E[cos x_i]`).

use super::sines::{Feature, Sines, SinesCache};
use crate::error::{check_finite, check_indices, check_len, Result};
use crate::util::assert_input;
use crate::{GaussianBar, Moments, MomentsBar};
use faer::MatRef;

/// PILCO's `gTrig`: `[e_j sin x_{i_j}, e_j cos x_{i_j}]_j`, interleaved.
#[derive(Clone, Debug)]
pub struct TrigAug {
    idx: Vec<usize>,
    engine: Sines,
}

impl TrigAug {
    /// `d` input dimensions; angle j is `x_{idx[j]}`, scaled by `scale[j]` (1 for PILCO's
    /// state augmentation).
    pub fn new(d: usize, idx: &[usize], scale: &[f64]) -> Result<Self> {
        check_indices("gTrig indices", idx, d)?;
        check_len("gTrig scales (one per index)", idx.len(), scale.len())?;
        check_finite("gTrig scales", scale)?;
        let mut feats = Vec::with_capacity(2 * idx.len());
        for (j, (&i, &e)) in idx.iter().zip(scale).enumerate() {
            for (quarter, out) in [(0, 2 * j), (1, 2 * j + 1)] {
                feats.push(Feature {
                    idx: i,
                    k: 1.0,
                    quarter,
                    out,
                    coef: e,
                });
            }
        }
        Ok(Self {
            idx: idx.to_vec(),
            engine: Sines {
                d,
                n_out: 2 * idx.len(),
                feats,
            },
        })
    }

    /// D, the length of the whole input `x`.
    pub fn n_inputs(&self) -> usize {
        self.engine.d
    }

    /// `2 I`.
    pub fn n_outputs(&self) -> usize {
        2 * self.idx.len()
    }

    /// `gTrig`'s `i`, 0-based: outputs `2j`, `2j+1` are `sin`, `cos` of `x_{indices[j]}`.
    pub fn indices(&self) -> &[usize] {
        &self.idx
    }

    /// The deterministic map `x → [e_j sin x_{i_j}, e_j cos x_{i_j}]_j`.
    pub fn apply(&self, x: &[f64]) -> Vec<f64> {
        let mut y = Vec::with_capacity(2 * self.idx.len());
        for (j, &i) in self.idx.iter().enumerate() {
            let e = self.engine.feats[2 * j].coef;
            y.push(e * x[i].sin());
            y.push(e * x[i].cos());
        }
        y
    }

    /// Exact `M` (2I), `S` (2I×2I) and `C` (D×2I) of the interleaved output for `x ~ N(m, s)`.
    pub fn forward(&self, m: &[f64], s: MatRef<'_, f64>) -> (Moments, SinesCache) {
        assert_input("gTrig", self.engine.d, m, s);
        self.engine.forward(m, s)
    }

    /// Adjoints of `(M, S, C)` → adjoints of `(m, s)`; `cache` from this block's `forward`.
    pub fn backward(&self, cache: &SinesCache, bar: &MomentsBar) -> GaussianBar {
        self.engine.backward(cache, bar)
    }
}
