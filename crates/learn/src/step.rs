//! One step of long-term prediction, `x_t ~ N(m, s)` → `x_{t+1}`, forward and backward.
//!
//! The step builds one joint Gaussian (see [`crate::joint`]) over, in this order:
//!
//! 1. the state `x` (D0);
//! 2. `(sin θ, cos θ)` of the angle dimensions (PILCO's `gTrig`), interleaved;
//! 3. time `t·Δt`, if time is an input (a known value: zero variance);
//! 4. the raw policy output `v` from the policy inputs (indices into 1–3);
//! 5. the squashed action `u` (sine saturation, partly non-negative), or `u = v` without
//!    squashing;
//! 6. the GP output `y` from the dynamics inputs (indices into 1–3) followed by `u`.
//!
//! The next state is `x'_k = y_k + x_k + r_k(t)` for relative targets and `x'_k = y_k + r_k(t)`
//! for absolute targets, where `r(t)` is an optional known prior mean (the reference
//! trajectory's increment, thesis §4-1-2) that the GP was trained to predict the residual of.
//! Its covariance `P Σ Pᵀ` includes the cross-covariance of `x` and `y` (thesis eq. 4-6).

use crate::joint::{Joint, JointBar};
use crate::LearnError;
use faer::{Mat, MatRef};
use vicpilco_gp::moments::{self, MmCache, MmModel, MomentsAdjoint};
use vicpilco_pilco::policy::Policy;
use vicpilco_pilco::squash::{PartialSat, TrigAug};
use vicpilco_pilco::{GaussianBar, Moments};

/// How a GP output becomes the next state.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Target {
    /// The GP predicts `x_{t+1} − x_t`.
    Relative,
    /// The GP predicts `x_{t+1}`.
    Absolute,
}

/// A linear term in a target's prior mean: the prior of `x_{t+1}[target]` gains
/// `coefficient · x_t[state]`, so the GP learns what the data add to it and, away from the
/// data, the prediction falls back to the line instead of to zero. Relative targets are the
/// special case `coefficient = 1` on their own state; this adds terms on top of them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinearPrior {
    /// State entry (< D0) whose next value's prior mean gains the term.
    pub target: usize,
    /// State entry (< D0) of `x_t` the term multiplies.
    pub state: usize,
    /// The term's factor on `x_t[state]`; must be finite.
    pub coefficient: f64,
}

/// The shape of a prediction step: which variables feed the policy and the dynamics GP.
#[derive(Clone, Debug)]
pub struct StepSpec {
    /// D0.
    pub state_dim: usize,
    /// State dimensions that are angles (augmented with sin and cos).
    pub angles: Vec<usize>,
    /// Feed time `t·Δt` as a known variable (index `D0 + 2·|angles|`).
    pub time_input: bool,
    /// Policy inputs: indices into `[x; trig; time]`.
    pub policy_inputs: Vec<usize>,
    /// Dynamics-GP inputs before the action: indices into `[x; trig; time]`.
    pub dyn_inputs: Vec<usize>,
    /// One per state dimension.
    pub targets: Vec<Target>,
    /// Linear terms of the targets' prior means in the current state (empty: PILCO's zero
    /// prior, or the previous state for relative targets).
    pub linear_prior: Vec<LinearPrior>,
    /// Seconds per step (for the time input).
    pub dt: f64,
}

impl StepSpec {
    /// Length of `[x; trig; time]`.
    pub fn augmented_dim(&self) -> usize {
        self.state_dim + 2 * self.angles.len() + self.time_input as usize
    }

    /// Checks the spec against the blocks it joins: a policy with `policy_inputs` inputs and
    /// `actions` outputs, and a GP with `gp_inputs` inputs and `gp_outputs` outputs. Fails with
    /// [`LearnError::Spec`] naming the first field at fault: an index out of range, a count
    /// that does not match, a non-finite prior coefficient, or `dt ≤ 0` with a time input.
    pub fn validate(
        &self,
        policy_inputs: usize,
        actions: usize,
        gp_inputs: usize,
        gp_outputs: usize,
    ) -> Result<(), LearnError> {
        let aug = self.augmented_dim();
        let bad = |what: &str, detail: String| Err(LearnError::Spec(format!("{what}: {detail}")));
        if let Some(&i) = self.angles.iter().find(|&&i| i >= self.state_dim) {
            return bad(
                "angles",
                format!("index {i} ≥ state dimension {}", self.state_dim),
            );
        }
        for (name, idx) in [
            ("policy_inputs", &self.policy_inputs),
            ("dyn_inputs", &self.dyn_inputs),
        ] {
            if let Some(&i) = idx.iter().find(|&&i| i >= aug) {
                return bad(name, format!("index {i} ≥ augmented dimension {aug}"));
            }
        }
        if self.policy_inputs.len() != policy_inputs {
            return bad(
                "policy_inputs",
                format!(
                    "{} indices for a policy with {policy_inputs} inputs",
                    self.policy_inputs.len()
                ),
            );
        }
        if self.dyn_inputs.len() + actions != gp_inputs {
            return bad(
                "dyn_inputs",
                format!(
                    "{} indices + {actions} actions for a GP with {gp_inputs} inputs",
                    self.dyn_inputs.len()
                ),
            );
        }
        if self.targets.len() != self.state_dim || gp_outputs != self.state_dim {
            return bad(
                "targets",
                format!(
                    "{} targets and {gp_outputs} GP outputs for {} states",
                    self.targets.len(),
                    self.state_dim
                ),
            );
        }
        for (i, term) in self.linear_prior.iter().enumerate() {
            if term.target >= self.state_dim || term.state >= self.state_dim {
                return bad(
                    "linear_prior",
                    format!(
                        "term {i} links target {} to state {}, beyond the {} states",
                        term.target, term.state, self.state_dim
                    ),
                );
            }
            if !term.coefficient.is_finite() {
                return bad(
                    "linear_prior",
                    format!("term {i} has coefficient {}", term.coefficient),
                );
            }
        }
        if self.time_input && !(self.dt.is_finite() && self.dt > 0.0) {
            return bad("dt", format!("{} must be > 0 with a time input", self.dt));
        }
        Ok(())
    }

    /// `(state, coefficient)` of the linear prior terms of `target`.
    fn prior_terms(&self, target: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.linear_prior
            .iter()
            .filter(move |term| term.target == target)
            .map(|term| (term.state, term.coefficient))
    }

    /// `Σ coefficient · x[state]` over the linear prior terms of `target`.
    pub fn linear_prior_mean(&self, target: usize, x: &[f64]) -> f64 {
        self.prior_terms(target).map(|(j, c)| c * x[j]).sum()
    }
}

/// Each row of a prior shift must be `d0` finite numbers (the row count is the loop's to
/// check against its horizon, [`crate::outer::LoopSetup::check_against`]).
pub(crate) fn check_prior_rows(shift: &[Vec<f64>], d0: usize) -> Result<(), LearnError> {
    match shift
        .iter()
        .enumerate()
        .find(|(_, r)| r.len() != d0 || r.iter().any(|v| !v.is_finite()))
    {
        Some((t, row)) => Err(LearnError::Spec(format!(
            "prior_shift: row {t} ({row:?}) is not {d0} finite numbers"
        ))),
        None => Ok(()),
    }
}

/// A Gaussian over the state, the input of a step or a start of the return: `d0` finite means
/// and a `d0`×`d0` finite covariance. Fails with [`LearnError::Spec`] beginning with `what`.
pub(crate) fn check_state_gaussian(
    what: &str,
    m: &[f64],
    s: MatRef<'_, f64>,
    d0: usize,
) -> Result<(), LearnError> {
    let bad = |detail: String| Err(LearnError::Spec(format!("{what}: {detail}")));
    if m.len() != d0 || s.nrows() != d0 || s.ncols() != d0 {
        return bad(format!(
            "a mean of {} and a {}×{} covariance for {d0} states",
            m.len(),
            s.nrows(),
            s.ncols()
        ));
    }
    if let Some(i) = m.iter().position(|v| !v.is_finite()) {
        return bad(format!("mean entry {i} is {}", m[i]));
    }
    for j in 0..d0 {
        if let Some(i) = (0..d0).find(|&i| !s[(i, j)].is_finite()) {
            return bad(format!("covariance entry ({i}, {j}) is {}", s[(i, j)]));
        }
    }
    Ok(())
}

/// Everything a step needs: its shape, the policy (with optional squashing), the dynamics GP
/// and the optional prior mean.
pub struct Predictor<'a, P: Policy> {
    /// Which variables feed the policy and the GP, and how GP outputs become the next state.
    pub spec: &'a StepSpec,
    /// Sine and cosine (unit amplitude) of `spec.angles`; `None` without angles.
    pub trig: Option<TrigAug>,
    /// The policy; [`Predictor::step_backward`] adds the adjoints of its parameters.
    pub policy: &'a P,
    /// Squashing of the raw policy output (input dimension = number of actions).
    pub squash: Option<&'a PartialSat>,
    /// The dynamics GP as moment matching uses it: inputs `[aug(x)[dyn_inputs]; u]`, one
    /// output per state entry (`x_{t+1}` less its prior mean).
    pub dynamics: MmModel<'a>,
    /// `r(t)` per step (H rows of D0), added to the predicted mean.
    pub prior_shift: Option<&'a [Vec<f64>]>,
}

impl<'a, P: Policy> Predictor<'a, P> {
    /// Checks that policy, squashing, GP and prior shift fit `spec` ([`StepSpec::validate`];
    /// squashing as wide as the policy's output; `prior_shift` rows of D0 finite numbers) and
    /// builds the angle augmentation. Fails with [`LearnError::Spec`], or
    /// [`LearnError::Pilco`] for invalid angles.
    pub fn new(
        spec: &'a StepSpec,
        policy: &'a P,
        squash: Option<&'a PartialSat>,
        dynamics: MmModel<'a>,
        prior_shift: Option<&'a [Vec<f64>]>,
    ) -> Result<Self, LearnError> {
        let actions = policy.n_outputs();
        if let Some(sq) = squash {
            if sq.n_inputs() != actions || sq.n_outputs() != actions {
                return Err(LearnError::Spec(format!(
                    "squashing maps {} inputs to {} outputs, the policy has {actions} actions",
                    sq.n_inputs(),
                    sq.n_outputs()
                )));
            }
        }
        spec.validate(
            policy.n_inputs(),
            actions,
            dynamics.input_dim(),
            dynamics.output_dim(),
        )?;
        if let Some(shift) = prior_shift {
            check_prior_rows(shift, spec.state_dim)?;
        }
        let trig = if spec.angles.is_empty() {
            None
        } else {
            Some(TrigAug::new(
                spec.state_dim,
                &spec.angles,
                &vec![1.0; spec.angles.len()],
            )?)
        };
        Ok(Self {
            spec,
            trig,
            policy,
            squash,
            dynamics,
            prior_shift,
        })
    }

    /// Action dimension: the policy's outputs (squashing keeps the width).
    pub fn n_actions(&self) -> usize {
        self.policy.n_outputs()
    }

    /// What each next-state entry sums from the step's joint.
    fn output_terms(&self, y_idx: &[usize]) -> Vec<OutputTerms> {
        (0..self.spec.state_dim)
            .map(|k| {
                let mut base = vec![y_idx[k]];
                if self.spec.targets[k] == Target::Relative {
                    base.push(k);
                }
                OutputTerms {
                    base,
                    prior: self.spec.prior_terms(k).collect(),
                }
            })
            .collect()
    }

    fn shift(&self, t: usize) -> Option<&[f64]> {
        self.prior_shift.map(|s| {
            s.get(t)
                .map(Vec::as_slice)
                .unwrap_or_else(|| s.last().map(Vec::as_slice).unwrap_or(&[]))
        })
    }
}

/// One next-state entry as a sum of joint entries: `base` with weight 1 (the GP output, and
/// the previous state for a relative target), then the linear prior terms
/// `(state, coefficient)`.
struct OutputTerms {
    base: Vec<usize>,
    prior: Vec<(usize, f64)>,
}

/// What the backward pass of a step needs.
pub struct StepTape<C> {
    joint: Joint,
    trig: Option<(Mat<f64>, vicpilco_pilco::squash::SinesCache)>,
    policy_idx: Vec<usize>,
    policy: (Mat<f64>, C),
    v_idx: Vec<usize>,
    squash: Option<(Mat<f64>, vicpilco_pilco::squash::SinesCache)>,
    u_idx: Vec<usize>,
    gp_idx: Vec<usize>,
    gp: (Mat<f64>, MmCache),
    y_idx: Vec<usize>,
}

impl<C> StepTape<C> {
    /// Indices of the actions in the step's joint.
    pub fn action_idx(&self) -> &[usize] {
        &self.u_idx
    }
}

/// The predicted action and next state of one step.
pub struct StepOut<C> {
    /// Mean of `x_{t+1}` (D0), prior terms and shift included.
    pub next_mean: Vec<f64>,
    /// Covariance of `x_{t+1}` (D0×D0, symmetrised).
    pub next_cov: Mat<f64>,
    /// Mean and covariance of the (squashed) action.
    pub action_mean: Vec<f64>,
    /// The action's covariance (A×A, A = [`Predictor::n_actions`]).
    pub action_cov: Mat<f64>,
    /// What [`Predictor::step_backward`] needs to differentiate this step.
    pub tape: StepTape<C>,
}

fn store_c(mo: &Moments) -> Mat<f64> {
    mo.v.clone()
}

impl<P: Policy> Predictor<'_, P> {
    /// Predict `x_{t+1}` from `x_t ~ N(m, s)` at step index `t` (time `t·Δt`). An `m` or `s`
    /// that is not D0 finite numbers is [`LearnError::Spec`].
    pub fn step(&self, t: usize, m: &[f64], s: &Mat<f64>) -> Result<StepOut<P::Cache>, LearnError> {
        check_state_gaussian("step input", m, s.as_ref(), self.spec.state_dim)?;
        self.step_checked(t, m, s)
    }

    /// [`Self::step`] on an input known to fit: a start [`crate::value::value`] has checked,
    /// or the output of the step before, so a horizon's steps are not checked again.
    pub(crate) fn step_checked(
        &self,
        t: usize,
        m: &[f64],
        s: &Mat<f64>,
    ) -> Result<StepOut<P::Cache>, LearnError> {
        let d0 = self.spec.state_dim;
        let mut joint = Joint::new(m.to_vec(), s.clone());
        let trig = match &self.trig {
            Some(tr) => {
                let (mo, cache) = tr.forward(m, s.as_ref());
                let all: Vec<usize> = (0..d0).collect();
                joint.append(&all, &mo);
                Some((store_c(&mo), cache))
            }
            None => None,
        };
        if self.spec.time_input {
            joint.append_constant(&[t as f64 * self.spec.dt]);
        }
        let (pm, ps) = joint.marginal(&self.spec.policy_inputs);
        let (pmo, pcache) = self.policy.forward(&pm, ps.as_ref())?;
        let v_idx = joint.append(&self.spec.policy_inputs, &pmo);
        let (squash, u_idx) = match self.squash {
            Some(sq) => {
                let (vm, vs) = joint.marginal(&v_idx);
                let (mo, cache) = sq.forward(&vm, vs.as_ref());
                let u = joint.append(&v_idx, &mo);
                (Some((store_c(&mo), cache)), u)
            }
            None => (None, v_idx.clone()),
        };
        let gp_idx: Vec<usize> = self.spec.dyn_inputs.iter().chain(&u_idx).copied().collect();
        let (gm, gs) = joint.marginal(&gp_idx);
        let (gp_out, gcache) = moments::forward(&self.dynamics, &gm, gs.as_ref())?;
        let y_idx = joint.append(&gp_idx, &gp_out);

        let rel = |k: usize| self.spec.targets[k] == Target::Relative;
        let shift = self.shift(t);
        let next_mean: Vec<f64> = (0..d0)
            .map(|k| {
                joint.mean[y_idx[k]]
                    + if rel(k) { joint.mean[k] } else { 0.0 }
                    + self.spec.linear_prior_mean(k, &joint.mean)
                    + shift.map_or(0.0, |s| s[k])
            })
            .collect();
        let terms = self.output_terms(&y_idx);
        let next_cov = Mat::from_fn(d0, d0, |k, l| {
            let c = &joint.cov;
            let mut v = c[(y_idx[k], y_idx[l])];
            if rel(l) {
                v += 0.5 * (c[(y_idx[k], l)] + c[(l, y_idx[k])]);
            }
            if rel(k) {
                v += 0.5 * (c[(k, y_idx[l])] + c[(y_idx[l], k)]);
            }
            if rel(k) && rel(l) {
                v += c[(k, l)];
            }
            // The prior terms' covariances with the GP output, with the previous state
            // (relative targets) and with each other.
            let (tk, tl) = (&terms[k], &terms[l]);
            for &(j, cj) in &tl.prior {
                for &r in &tk.base {
                    v += cj * 0.5 * (c[(r, j)] + c[(j, r)]);
                }
            }
            for &(i, ci) in &tk.prior {
                for &r in &tl.base {
                    v += ci * 0.5 * (c[(i, r)] + c[(r, i)]);
                }
                for &(j, cj) in &tl.prior {
                    v += ci * cj * c[(i, j)];
                }
            }
            v
        });
        let next_cov = Mat::from_fn(d0, d0, |k, l| 0.5 * (next_cov[(k, l)] + next_cov[(l, k)]));
        let (action_mean, action_cov) = joint.marginal(&u_idx);
        Ok(StepOut {
            next_mean,
            next_cov,
            action_mean,
            action_cov,
            tape: StepTape {
                joint,
                trig,
                policy_idx: self.spec.policy_inputs.clone(),
                policy: (store_c(&pmo), pcache),
                v_idx,
                squash,
                u_idx,
                gp_idx,
                gp: (gp_out.v.clone(), gcache),
                y_idx,
            },
        })
    }

    /// Reverse of [`Predictor::step`]: from the adjoints of the next state (and optionally
    /// of the action distribution) to the adjoints of `(m, s)`; policy-parameter adjoints
    /// are added to `p_bar`.
    pub fn step_backward(
        &self,
        tape: &StepTape<P::Cache>,
        next_bar: &GaussianBar,
        action_bar: Option<&GaussianBar>,
        p_bar: &mut [f64],
    ) -> Result<GaussianBar, LearnError> {
        let d0 = self.spec.state_dim;
        let mut zbar = JointBar::zeros(tape.joint.dim());
        // Each next-state entry is a weighted sum of joint entries.
        let terms: Vec<Vec<(usize, f64)>> = self
            .output_terms(&tape.y_idx)
            .into_iter()
            .map(|t| {
                t.base
                    .into_iter()
                    .map(|r| (r, 1.0))
                    .chain(t.prior)
                    .collect()
            })
            .collect();
        for (k, tk) in terms.iter().enumerate() {
            for &(r, w) in tk {
                zbar.mean[r] += w * next_bar.mean[k];
            }
        }
        for (k, tk) in terms.iter().enumerate() {
            for (l, tl) in terms.iter().enumerate() {
                let g = next_bar.cov[(k, l)];
                for &(r, wr) in tk {
                    for &(c, wc) in tl {
                        zbar.cov[(r, c)] += wr * wc * g;
                    }
                }
            }
        }
        if let Some(ab) = action_bar {
            zbar.add_marginal(&tape.u_idx, ab);
        }
        // Dynamics GP.
        let mb = zbar.pop_append(&tape.joint, &tape.gp_idx, tape.gp.0.as_ref());
        let cov_bar = mb.cov;
        let v_bar = mb.v.expect("pop_append returns C̄");
        let ia = moments::backward(
            &self.dynamics,
            &tape.gp.1,
            MomentsAdjoint {
                mean: &mb.mean,
                cov: cov_bar.as_ref(),
                v: v_bar.as_ref(),
            },
            false,
        )?;
        zbar.add_marginal(
            &tape.gp_idx,
            &GaussianBar {
                mean: ia.m,
                cov: ia.s,
            },
        );
        // Squashing.
        if let (Some(sq), Some((c, cache))) = (self.squash, &tape.squash) {
            let mb = zbar.pop_append(&tape.joint, &tape.v_idx, c.as_ref());
            let gb = sq.backward(cache, &mb);
            zbar.add_marginal(&tape.v_idx, &gb);
        }
        // Policy.
        let mb = zbar.pop_append(&tape.joint, &tape.policy_idx, tape.policy.0.as_ref());
        let gb = self.policy.backward(&tape.policy.1, &mb, p_bar);
        zbar.add_marginal(&tape.policy_idx, &gb);
        // Time is a constant: nothing flows back through it.
        if self.spec.time_input {
            let n = zbar.dim() - 1;
            zbar.mean.truncate(n);
            zbar.cov = Mat::from_fn(n, n, |i, j| zbar.cov[(i, j)]);
        }
        // Trigonometric augmentation.
        if let (Some(tr), Some((c, cache))) = (&self.trig, &tape.trig) {
            let all: Vec<usize> = (0..d0).collect();
            let mb = zbar.pop_append(&tape.joint, &all, c.as_ref());
            let gb = tr.backward(cache, &mb);
            zbar.add_marginal(&all, &gb);
        }
        debug_assert_eq!(zbar.dim(), d0);
        Ok(zbar.into_gaussian_bar())
    }
}
