//! Sine saturation (PILCO's `gSat`, thesis eq. 4-22) and the partial non-negative saturation
//! of impedance gains (thesis eq. 4-23, corrected).
//!
//! ## `gSat`
//!
//! For `x ~ N(m, s)` (D-dimensional), an index list `i_1..i_I` and scales `e_1..e_I`,
//!
//! ```text
//! u_j = e_j · σ(x_{i_j}),   σ(x) = (9 sin x + sin 3x) / 8  ∈ [−1, 1],
//! ```
//!
//! a smooth saturation that reaches ±1 at `x = ±π/2` (the 3rd-order Fourier approximation of
//! a square wave). It is 2π-periodic and monotone only between neighbouring extremes (odd
//! multiples of π/2): a policy whose output moves by more than π along a roll-out can make its
//! saturated output rise and fall again (the linear VIL policy does, EXPERIMENTS.md, eleventh
//! session). The moments are exact: `u` is a linear
//! combination of the 2I sines of `x_{i_j}` and `3 x_{i_j}`, whose means, covariances and
//! cross-covariances with `x` are given by the identities in the engine
//! (`E[sin w] = exp(−Var w/2) sin E w`, …). Outputs: `M` (I), `S` (I×I),
//! `C = s⁻¹Cov[x, u]` (D×I; row `i_j` of column j is
//! `e_j (9 E[cos x] + 3 E[cos 3x]) / 8`, all other rows zero).
//!
//! ## Partial non-negative saturation
//!
//! Impedance gains must stay strictly positive. The thesis (eq. 4-23) prints
//! `π(s) = a_max ([9 sin π̃ + 3 sin π̃]/8 + 1) + a_min`, which has two typos: the second sine
//! must be `sin 3π̃` (as in eq. 4-22), and the affine map as printed sends `[−1, 1]` onto
//! `[a_min, 2 a_max + a_min]`, not onto the interval `[a_min, a_max]` the text asks for.
//! The mapping implemented here is the one the text describes: for a **bounded** dimension
//! (`0 < a_min < a_max`)
//!
//! ```text
//! u = (a_max + a_min)/2 + (a_max − a_min)/2 · σ(x)   ∈ [a_min, a_max],
//! ```
//!
//! and for a **symmetric** dimension (reference actions, still allowed to be negative)
//!
//! ```text
//! u = a_max · σ(x)   ∈ [−a_max, a_max]   (eq. 4-22).
//! ```
//!
//! Both are affine maps `u_j = c_j + h_j σ(x_{i_j})` of `gSat` with scale `e_j = h_j`, so
//! `M = c + M_gSat`, while `S`, `C` and every derivative are those of `gSat` with `e = h`.

use super::sines::{Feature, Sines, SinesCache};
use crate::error::{check_finite, check_indices, check_len, PilcoError, Result};
use crate::util::assert_input;
use crate::{GaussianBar, Moments, MomentsBar};
use faer::MatRef;

/// PILCO's `gSat`: `u_j = e_j (9 sin x_{i_j} + sin 3x_{i_j}) / 8` on a chosen index subset.
#[derive(Clone, Debug)]
pub struct SineSat {
    idx: Vec<usize>,
    scale: Vec<f64>,
    engine: Sines,
}

impl SineSat {
    /// `d` input dimensions; output j saturates `x_{idx[j]}` with amplitude `scale[j]`
    /// (PILCO's `i` 0-based and `e`).
    pub fn new(d: usize, idx: &[usize], scale: &[f64]) -> Result<Self> {
        check_indices("gSat indices", idx, d)?;
        check_len("gSat scales (one per index)", idx.len(), scale.len())?;
        check_finite("gSat scales", scale)?;
        let mut feats = Vec::with_capacity(2 * idx.len());
        for (j, (&i, &e)) in idx.iter().zip(scale).enumerate() {
            feats.push(Feature {
                idx: i,
                k: 1.0,
                quarter: 0,
                out: j,
                coef: 9.0 * e / 8.0,
            });
            feats.push(Feature {
                idx: i,
                k: 3.0,
                quarter: 0,
                out: j,
                coef: e / 8.0,
            });
        }
        Ok(Self {
            idx: idx.to_vec(),
            scale: scale.to_vec(),
            engine: Sines {
                d,
                n_out: idx.len(),
                feats,
            },
        })
    }

    /// D, the length of the whole input `x` (not only of the saturated entries).
    pub fn n_inputs(&self) -> usize {
        self.engine.d
    }

    /// I, one output per index.
    pub fn n_outputs(&self) -> usize {
        self.idx.len()
    }

    /// PILCO's `i`, 0-based: output j saturates `x_{indices[j]}`.
    pub fn indices(&self) -> &[usize] {
        &self.idx
    }

    /// PILCO's `e`: output j lies in `[−|e_j|, |e_j|]`.
    pub fn scales(&self) -> &[f64] {
        &self.scale
    }

    /// The deterministic map `u(x)` (for applying a policy to a known state).
    pub fn apply(&self, x: &[f64]) -> Vec<f64> {
        self.idx
            .iter()
            .zip(&self.scale)
            .map(|(&i, &e)| e * (9.0 * x[i].sin() + (3.0 * x[i]).sin()) / 8.0)
            .collect()
    }

    /// Exact `M`, `S`, `C` of `u` for `x ~ N(m, s)`.
    pub fn forward(&self, m: &[f64], s: MatRef<'_, f64>) -> (Moments, SinesCache) {
        assert_input("gSat", self.engine.d, m, s);
        self.engine.forward(m, s)
    }

    /// Adjoints of `(M, S, C)` → adjoints of `(m, s)`.
    pub fn backward(&self, cache: &SinesCache, bar: &MomentsBar) -> GaussianBar {
        self.engine.backward(cache, bar)
    }
}

/// The output range of one saturated dimension of [`PartialSat`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SatRange {
    /// `u = a_max σ(x) ∈ [−a_max, a_max]`.
    Symmetric {
        /// Amplitude, `> 0` (checked by [`PartialSat::new`]).
        a_max: f64,
    },
    /// `u = (a_max + a_min)/2 + (a_max − a_min)/2 · σ(x) ∈ [a_min, a_max]`, `0 < a_min < a_max`.
    Bounded {
        /// Lowest output, `> 0` so a gain stays positive (checked by [`PartialSat::new`]).
        a_min: f64,
        /// Highest output, `> a_min`.
        a_max: f64,
    },
}

impl SatRange {
    /// The closed interval `(lowest, highest)` the saturated output can take.
    pub fn bounds(self) -> (f64, f64) {
        match self {
            SatRange::Symmetric { a_max } => (-a_max, a_max),
            SatRange::Bounded { a_min, a_max } => (a_min, a_max),
        }
    }

    /// The pre-saturation value `x ∈ [−π/2, π/2]` that this range maps onto `u`, with `u`
    /// clamped into the range: the inverse of `u = c + h σ(x)` on the branch through 0
    /// (for setting a policy's initial outputs to chosen actions).
    pub fn preimage(self, u: f64) -> f64 {
        let (c, h) = self.affine();
        let v = ((u - c) / h).clamp(-1.0, 1.0);
        // σ(x) = (3s − s³)/2 with s = sin x (sin 3x = 3s − 4s³). The cubic s³ − 3s + 2v = 0
        // has, with s = 2 cos φ, cos 3φ = −v; its root in [−1, 1] is the branch below.
        let s = 2.0 * ((((-v).acos()) + 4.0 * std::f64::consts::PI) / 3.0).cos();
        s.clamp(-1.0, 1.0).asin()
    }

    /// `(offset c, half-width h)` of the affine map `u = c + h σ(x)`.
    fn affine(self) -> (f64, f64) {
        match self {
            SatRange::Symmetric { a_max } => (0.0, a_max),
            SatRange::Bounded { a_min, a_max } => (0.5 * (a_max + a_min), 0.5 * (a_max - a_min)),
        }
    }
}

/// Partial non-negative saturation (thesis eq. 4-23, corrected; see the module docs): each
/// chosen dimension is squashed either symmetrically onto `[−a_max, a_max]` or, for gains,
/// onto `[a_min, a_max]` with `a_min > 0`.
#[derive(Clone, Debug)]
pub struct PartialSat {
    ranges: Vec<SatRange>,
    offset: Vec<f64>,
    sat: SineSat,
}

impl PartialSat {
    /// `d` input dimensions; output j saturates `x_{idx[j]}` onto `ranges[j]`.
    pub fn new(d: usize, idx: &[usize], ranges: &[SatRange]) -> Result<Self> {
        check_len("saturation ranges (one per index)", idx.len(), ranges.len())?;
        let mut offset = Vec::with_capacity(ranges.len());
        let mut half = Vec::with_capacity(ranges.len());
        for (j, r) in ranges.iter().enumerate() {
            let ok = match *r {
                SatRange::Symmetric { a_max } => a_max.is_finite() && a_max > 0.0,
                SatRange::Bounded { a_min, a_max } => {
                    a_min.is_finite() && a_max.is_finite() && 0.0 < a_min && a_min < a_max
                }
            };
            if !ok {
                return Err(PilcoError::Invalid {
                    what: format!("saturation range {j}"),
                    detail: format!(
                        "{r:?}: need 0 < a_max (symmetric) or 0 < a_min < a_max (bounded)"
                    ),
                });
            }
            let (c, h) = r.affine();
            offset.push(c);
            half.push(h);
        }
        Ok(Self {
            ranges: ranges.to_vec(),
            offset,
            sat: SineSat::new(d, idx, &half)?,
        })
    }

    /// D, the length of the whole input `x`.
    pub fn n_inputs(&self) -> usize {
        self.sat.n_inputs()
    }

    /// I, one output per index.
    pub fn n_outputs(&self) -> usize {
        self.sat.n_outputs()
    }

    /// The range of each output j, in the order of the indices given to [`PartialSat::new`].
    pub fn ranges(&self) -> &[SatRange] {
        &self.ranges
    }

    /// The deterministic map `u(x)` (for applying a policy to a known state).
    pub fn apply(&self, x: &[f64]) -> Vec<f64> {
        let mut u = self.sat.apply(x);
        for (uj, c) in u.iter_mut().zip(&self.offset) {
            *uj += c;
        }
        u
    }

    /// Exact `M` (I), `S` (I×I), `C` (D×I) of `u` for `x ~ N(m, s)`: those of `gSat` with `e_j`
    /// the half-width of range j, and `M_j` shifted by the range's centre.
    pub fn forward(&self, m: &[f64], s: MatRef<'_, f64>) -> (Moments, SinesCache) {
        let (mut out, cache) = self.sat.forward(m, s);
        for (mj, c) in out.mean.iter_mut().zip(&self.offset) {
            *mj += c;
        }
        (out, cache)
    }

    /// The offsets are constants, so the backward is `gSat`'s with `e_j` the half-width of
    /// range j: `(a_max − a_min)/2` for a bounded range, `a_max` for a symmetric one.
    pub fn backward(&self, cache: &SinesCache, bar: &MomentsBar) -> GaussianBar {
        self.sat.backward(cache, bar)
    }
}
