//! Fixed benchmark workloads from `../shared/bench` (see its README), so vicpilco's timings
//! are comparable with other PILCO implementations run on the same numbers.

#![warn(missing_docs)]

use faer::Mat;
use serde::Deserialize;
use std::path::{Path, PathBuf};
use vicpilco_gp::moments::MmModel;
use vicpilco_gp::{GpModel, Hyper};
use vicpilco_learn::step::{Predictor, StepSpec, Target};
use vicpilco_learn::value::ReturnSpec;
use vicpilco_pilco::cost::CostSum;
use vicpilco_pilco::policy::RbfPolicy;
use vicpilco_pilco::squash::{PartialSat, SatRange};

/// Why [`W1::load`] failed.
#[derive(Debug, thiserror::Error)]
pub enum WorkloadError {
    /// The path only: the I/O error is the source, which `{:#}` prints after it.
    #[error("{}", path.display())]
    Io {
        /// The workload file.
        path: PathBuf,
        /// The read error.
        source: std::io::Error,
    },
    /// The file is not JSON, or a field of [`W1`] is missing or has the wrong type.
    #[error("{path}: not a valid workload: {detail}")]
    Parse {
        /// The workload file.
        path: PathBuf,
        /// `serde_json`'s message (names the field, line and column).
        detail: String,
    },
    /// A field's size disagrees with the declared sizes, or `cost_dims` names no state.
    #[error("{path}: field `{field}`: {detail}")]
    Invalid {
        /// The workload file.
        path: PathBuf,
        /// The JSON field at fault.
        field: &'static str,
        /// The size expected and the size found, or the index out of range.
        detail: String,
    },
}

/// Workload W1: a VIL-sized PILCO problem (D = 6 states, U = 2 actions, N = 300, 50 basis
/// functions, H = 100). Field names follow `w1.json`; matrices are arrays of rows.
#[derive(Clone, Debug, Deserialize)]
#[allow(non_snake_case)]
pub struct W1 {
    /// D = 6 states; the first D columns of `X`.
    pub state_dim: usize,
    /// U = 2 actions; the last U columns of `X`.
    pub action_dim: usize,
    /// N = 300, the rows of `X` and `Y` (as stated in the file; not checked against them).
    pub n_train: usize,
    /// 50, the rows of `policy_inputs` and `policy_targets`.
    pub n_basis: usize,
    /// H = 100 predicted steps in `J`.
    pub horizon: usize,
    /// Dynamics-GP training inputs, N×(D+U): state, then action.
    pub X: Vec<Vec<f64>>,
    /// Dynamics-GP training targets, N×D: state differences `x_{t+1} − x_t`.
    pub Y: Vec<Vec<f64>>,
    /// Dynamics-GP log length-scales, (D+U)×D, column e for output e.
    pub dyn_log_lengthscales: Vec<Vec<f64>>,
    /// Dynamics-GP `log σ_f` (signal std), one per output.
    pub dyn_log_signal_std: Vec<f64>,
    /// Dynamics-GP `log σ_n` (noise std), one per output.
    pub dyn_log_noise_std: Vec<f64>,
    /// Training start, (D+U)×D: the log sample std of each input column (pilco-matlab's init).
    pub train_init_log_lengthscales: Vec<Vec<f64>>,
    /// Training start: the log sample std of each target column.
    pub train_init_log_signal_std: Vec<f64>,
    /// Training start: `log(std/10)` of each target column.
    pub train_init_log_noise_std: Vec<f64>,
    /// RBF policy centres, `n_basis`×D, on all states.
    pub policy_inputs: Vec<Vec<f64>>,
    /// RBF policy pseudo-targets, `n_basis`×U, column u for action u.
    pub policy_targets: Vec<Vec<f64>>,
    /// RBF policy log length-scales, D×U, column u for action u.
    pub policy_log_lengthscales: Vec<Vec<f64>>,
    /// Policy σ_f, not a log (1, fixed); only the ratio to `policy_noise_std` is used.
    pub policy_signal_std: f64,
    /// Policy σ_n, not a log (0.01, fixed): SNR `policy_signal_std / policy_noise_std`.
    pub policy_noise_std: f64,
    /// `gSat`'s `e` per action: action u is squashed onto `[−max_action[u], max_action[u]]`.
    pub max_action: Vec<f64>,
    /// Mean of the Gaussian start state (D).
    pub m0: Vec<f64>,
    /// Covariance of the start state, D×D (1e-3 I).
    pub S0: Vec<Vec<f64>>,
    /// Cost target `z` (D); only the entries on `cost_dims` matter.
    pub cost_target: Vec<f64>,
    /// Cost width w = 0.25; informational, `cost_W` already holds `1/w²`.
    pub cost_width: f64,
    /// State dims the cost sees (`[0, 2]`); informational, encoded in the zeros of `cost_W`.
    pub cost_dims: Vec<usize>,
    /// `lossSat`'s `W`, D×D: `diag(1/w²)` on `cost_dims`, 0 elsewhere.
    pub cost_W: Vec<Vec<f64>>,
    /// Discount γ (1.0) in `J = Σ_{t=1..H} γ^t E[c(x_t)]`.
    pub gamma: f64,
}

/// `../shared/bench` beside the repository (or `VICPILCO_BENCH_DIR`).
pub fn default_dir() -> PathBuf {
    if let Some(d) = std::env::var_os("VICPILCO_BENCH_DIR") {
        return PathBuf::from(d);
    }
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/bench")
}

/// A matrix stored as an array of rows (the workload's format); the column count is the first
/// row's length (0×0 when empty). Panics if a later row is shorter ([`W1::load`] refuses such
/// a workload).
pub fn rows_to_mat(rows: &[Vec<f64>]) -> Mat<f64> {
    let c = rows.first().map_or(0, Vec::len);
    Mat::from_fn(rows.len(), c, |i, j| rows[i][j])
}

/// Hyper-parameters from a D×E array of log length-scales plus per-output log stds.
pub fn hypers(log_ls: &[Vec<f64>], log_sf: &[f64], log_sn: &[f64]) -> Vec<Hyper> {
    (0..log_sf.len())
        .map(|e| Hyper {
            log_ls: log_ls.iter().map(|r| r[e]).collect(),
            log_sf: log_sf[e],
            log_sn: log_sn[e],
        })
        .collect()
}

impl W1 {
    /// Read and deserialise `w1.json`, and check every array against the declared sizes
    /// (`state_dim`, `action_dim`, `n_train`, `n_basis`), so that a malformed workload is an
    /// error naming its field, never a panic later on. Every number is finite: JSON has no
    /// NaN or infinity, and `serde_json` refuses one out of the f64 range (a `Parse` error).
    pub fn load(path: &Path) -> Result<Self, WorkloadError> {
        let text = std::fs::read_to_string(path).map_err(|e| WorkloadError::Io {
            path: path.to_path_buf(),
            source: e,
        })?;
        let w1: W1 = serde_json::from_str(&text).map_err(|e| WorkloadError::Parse {
            path: path.to_path_buf(),
            detail: e.to_string(),
        })?;
        w1.check()
            .map_err(|(field, detail)| WorkloadError::Invalid {
                path: path.to_path_buf(),
                field,
                detail,
            })?;
        Ok(w1)
    }

    /// The first field whose size (or, for `cost_dims`, an index) is wrong, and what is wrong.
    fn check(&self) -> Result<(), (&'static str, String)> {
        let (d, u, n, b) = (self.state_dim, self.action_dim, self.n_train, self.n_basis);
        let matrices: [(&'static str, &[Vec<f64>], usize, usize); 9] = [
            ("X", &self.X, n, d + u),
            ("Y", &self.Y, n, d),
            ("dyn_log_lengthscales", &self.dyn_log_lengthscales, d + u, d),
            (
                "train_init_log_lengthscales",
                &self.train_init_log_lengthscales,
                d + u,
                d,
            ),
            ("policy_inputs", &self.policy_inputs, b, d),
            ("policy_targets", &self.policy_targets, b, u),
            (
                "policy_log_lengthscales",
                &self.policy_log_lengthscales,
                d,
                u,
            ),
            ("S0", &self.S0, d, d),
            ("cost_W", &self.cost_W, d, d),
        ];
        for (field, rows, n_rows, n_cols) in matrices {
            let ragged = rows.iter().position(|r| r.len() != n_cols);
            if rows.len() != n_rows || ragged.is_some() {
                let got = match ragged {
                    Some(i) => format!("row {i} has {} entries", rows[i].len()),
                    None => format!("{} rows", rows.len()),
                };
                return Err((field, format!("expected {n_rows}×{n_cols}, got {got}")));
            }
        }
        let vectors: [(&'static str, &[f64], usize); 7] = [
            ("dyn_log_signal_std", &self.dyn_log_signal_std, d),
            ("dyn_log_noise_std", &self.dyn_log_noise_std, d),
            (
                "train_init_log_signal_std",
                &self.train_init_log_signal_std,
                d,
            ),
            (
                "train_init_log_noise_std",
                &self.train_init_log_noise_std,
                d,
            ),
            ("max_action", &self.max_action, u),
            ("m0", &self.m0, d),
            ("cost_target", &self.cost_target, d),
        ];
        for (field, values, len) in vectors {
            if values.len() != len {
                return Err((
                    field,
                    format!("expected {len} entries, got {}", values.len()),
                ));
            }
        }
        if let Some(k) = self.cost_dims.iter().find(|&&k| k >= d) {
            return Err((
                "cost_dims",
                format!("state index {k} is not below state_dim {d}"),
            ));
        }
        Ok(())
    }

    /// The dynamics GP with the workload's given hyper-parameters.
    pub fn dynamics_gp(&self) -> vicpilco_gp::Result<GpModel> {
        GpModel::new(
            rows_to_mat(&self.X),
            rows_to_mat(&self.Y),
            hypers(
                &self.dyn_log_lengthscales,
                &self.dyn_log_signal_std,
                &self.dyn_log_noise_std,
            ),
        )
    }

    /// Initial hyper-parameters for the training benchmark.
    pub fn train_init(&self) -> Vec<Hyper> {
        hypers(
            &self.train_init_log_lengthscales,
            &self.train_init_log_signal_std,
            &self.train_init_log_noise_std,
        )
    }
}

/// The W1 prediction problem, ready for [`vicpilco_learn::value::value`].
pub struct W1Problem {
    /// One step: the policy and the GP see all D states (no angles, no time input), every
    /// target is a state difference.
    pub spec: StepSpec,
    /// PILCO's `congp` from the `policy_*` fields, SNR `policy_signal_std / policy_noise_std`.
    pub policy: RbfPolicy,
    /// `gSat` on every action with amplitude `max_action` (symmetric ranges).
    pub squash: PartialSat,
    /// The full GP on `[x; u]` with the workload's `dyn_*` hyper-parameters.
    pub dynamics: GpModel,
    /// `lossSat(cost_W, cost_target)` on the whole state, weight 1 on `E[c]`, no energy cost.
    pub ret: ReturnSpec,
    /// The start distribution `(m0, S0)`.
    pub start: (Vec<f64>, Mat<f64>),
}

impl W1Problem {
    /// The step predictor over these parts, with model uncertainty (PILCO's `gp0`) and no
    /// prior shift; fails if the sizes of spec, policy, squashing and GP disagree.
    pub fn predictor(&self) -> Result<Predictor<'_, RbfPolicy>, vicpilco_learn::LearnError> {
        Predictor::new(
            &self.spec,
            &self.policy,
            Some(&self.squash),
            MmModel::with_uncertainty(&self.dynamics),
            None,
        )
    }
}

impl W1 {
    /// State → RBF policy on all states → sine saturation → full GP on (state, action) with
    /// difference targets → saturating cost on `cost_dims`, as the bench README specifies.
    pub fn problem(&self) -> Result<W1Problem, Box<dyn std::error::Error + Send + Sync>> {
        let (d, u) = (self.state_dim, self.action_dim);
        let spec = StepSpec {
            state_dim: d,
            angles: vec![],
            time_input: false,
            policy_inputs: (0..d).collect(),
            dyn_inputs: (0..d).collect(),
            targets: vec![Target::Relative; d],
            linear_prior: vec![],
            dt: 1.0,
        };
        let log_ls = rows_to_mat(&self.policy_log_lengthscales);
        let snr = self.policy_signal_std / self.policy_noise_std;
        let policy = RbfPolicy::new(
            rows_to_mat(&self.policy_inputs),
            rows_to_mat(&self.policy_targets),
            log_ls.as_ref(),
            snr,
        )?;
        let ranges: Vec<SatRange> = self
            .max_action
            .iter()
            .map(|&a_max| SatRange::Symmetric { a_max })
            .collect();
        let squash = PartialSat::new(u, &(0..u).collect::<Vec<_>>(), &ranges)?;
        let ret = ReturnSpec {
            state_cost: Some(CostSum::loss_sat(
                rows_to_mat(&self.cost_W).as_ref(),
                &self.cost_target,
            )?),
            cost_angles: vec![],
            w_mean: 1.0,
            w_std: 0.0,
            energy: None,
            gamma: self.gamma,
            horizon: self.horizon,
        };
        Ok(W1Problem {
            spec,
            policy,
            squash,
            dynamics: self.dynamics_gp()?,
            ret,
            start: (self.m0.clone(), rows_to_mat(&self.S0)),
        })
    }
}

/// Median wall times of the W1 operations (bench README, "Timed operations").
#[derive(Clone, Debug, serde::Serialize)]
pub struct W1Timings {
    /// Seconds for `J` over the horizon, without gradient.
    pub forward_s: f64,
    /// Seconds for `J` and `dJ/dψ` over all policy parameters in one call.
    pub value_grad_s: f64,
    /// Seconds to train the D dynamics GPs from `train_init_*` (see [`W1::time`]).
    pub train_s: f64,
    /// `J` of the last forward repetition, serialised as `J` (reference 92.6720698716).
    #[serde(rename = "J")]
    pub j: f64,
    /// `‖dJ/d(policy inputs, targets)‖₂` (reference 149.55171269).
    pub grad_norm_inputs_targets: f64,
    /// Final penalised negative log marginal likelihood per output after training.
    pub train_nlml: Vec<f64>,
    /// Timed repetitions per operation (at least 1), warm-up not counted.
    pub repetitions: usize,
    /// `RAYON_NUM_THREADS` when a positive number, else the available parallelism.
    pub threads: usize,
    /// Peak resident memory of the process (VmHWM), MB, when the OS reports it.
    pub peak_memory_mb: Option<f64>,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Peak resident set size from `/proc/self/status` (Linux), MB.
pub fn peak_memory_mb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

impl W1 {
    /// Time forward, value+gradient and training: one warm-up call each, then the median of
    /// `reps` repetitions. Training uses PILCO's hypCurb penalty, at most 100 L-BFGS
    /// iterations per output, gradient-norm and relative-change tolerances 1e-6.
    pub fn time(&self, reps: usize) -> Result<W1Timings, Box<dyn std::error::Error + Send + Sync>> {
        use std::time::Instant;
        use vicpilco_learn::value::value;
        let reps = reps.max(1);
        let pb = self.problem()?;
        let pred = pb.predictor()?;
        let starts = std::slice::from_ref(&pb.start);
        let warm = value(&pred, &pb.ret, starts, true)?;
        let grad = warm.grad.as_ref().expect("gradient requested");
        let n_hyp = (self.state_dim + 2) * self.action_dim;
        let grad_norm = grad[n_hyp..].iter().map(|g| g * g).sum::<f64>().sqrt();
        let mut fwd = Vec::with_capacity(reps);
        let mut vg = Vec::with_capacity(reps);
        let mut j = warm.j;
        for _ in 0..reps {
            let t = Instant::now();
            j = value(&pred, &pb.ret, starts, false)?.j;
            fwd.push(t.elapsed().as_secs_f64());
            let t = Instant::now();
            value(&pred, &pb.ret, starts, true)?;
            vg.push(t.elapsed().as_secs_f64());
        }
        let (x, y) = (rows_to_mat(&self.X), rows_to_mat(&self.Y));
        let opts = vicpilco_gp::TrainOptions::default();
        let init = self.train_init();
        let (_, report) = vicpilco_gp::train(x.as_ref(), y.as_ref(), &init, &opts)?;
        let mut tr = Vec::with_capacity(reps);
        for _ in 0..reps {
            let t = Instant::now();
            vicpilco_gp::train(x.as_ref(), y.as_ref(), &init, &opts)?;
            tr.push(t.elapsed().as_secs_f64());
        }
        Ok(W1Timings {
            forward_s: median(fwd),
            value_grad_s: median(vg),
            train_s: median(tr),
            j,
            grad_norm_inputs_targets: grad_norm,
            train_nlml: report.objectives(),
            repetitions: reps,
            threads: rayon_threads(),
            peak_memory_mb: peak_memory_mb(),
        })
    }
}

fn rayon_threads() -> usize {
    std::env::var("RAYON_NUM_THREADS")
        .ok()
        .and_then(|v| v.parse().ok())
        .filter(|&n: &usize| n > 0)
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
}
