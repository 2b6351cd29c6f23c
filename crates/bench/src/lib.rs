//! Fixed benchmark workloads from `../shared/bench` (see its README), so vicpilco's timings
//! are comparable with other PILCO implementations run on the same numbers.

use faer::Mat;
use serde::Deserialize;
use std::path::{Path, PathBuf};
use vicpilco_gp::{GpModel, Hyper};

#[derive(Debug, thiserror::Error)]
pub enum WorkloadError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: not a valid workload: {detail}")]
    Parse { path: PathBuf, detail: String },
}

/// Workload W1: a VIL-sized PILCO problem (D = 6 states, U = 2 actions, N = 300, 50 basis
/// functions, H = 100). Field names follow `w1.json`; matrices are arrays of rows.
#[derive(Clone, Debug, Deserialize)]
#[allow(non_snake_case)]
pub struct W1 {
    pub state_dim: usize,
    pub action_dim: usize,
    pub n_train: usize,
    pub n_basis: usize,
    pub horizon: usize,
    pub X: Vec<Vec<f64>>,
    pub Y: Vec<Vec<f64>>,
    pub dyn_log_lengthscales: Vec<Vec<f64>>,
    pub dyn_log_signal_std: Vec<f64>,
    pub dyn_log_noise_std: Vec<f64>,
    pub train_init_log_lengthscales: Vec<Vec<f64>>,
    pub train_init_log_signal_std: Vec<f64>,
    pub train_init_log_noise_std: Vec<f64>,
    pub policy_inputs: Vec<Vec<f64>>,
    pub policy_targets: Vec<Vec<f64>>,
    pub policy_log_lengthscales: Vec<Vec<f64>>,
    pub policy_signal_std: f64,
    pub policy_noise_std: f64,
    pub max_action: Vec<f64>,
    pub m0: Vec<f64>,
    pub S0: Vec<Vec<f64>>,
    pub cost_target: Vec<f64>,
    pub cost_width: f64,
    pub cost_dims: Vec<usize>,
    pub cost_W: Vec<Vec<f64>>,
    pub gamma: f64,
}

/// `../shared/bench` beside the repository (or `VICPILCO_BENCH_DIR`).
pub fn default_dir() -> PathBuf {
    if let Some(d) = std::env::var_os("VICPILCO_BENCH_DIR") {
        return PathBuf::from(d);
    }
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/bench")
}

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
    pub fn load(path: &Path) -> Result<Self, WorkloadError> {
        let text = std::fs::read_to_string(path).map_err(|e| WorkloadError::Io {
            path: path.to_path_buf(),
            source: e,
        })?;
        serde_json::from_str(&text).map_err(|e| WorkloadError::Parse {
            path: path.to_path_buf(),
            detail: e.to_string(),
        })
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
