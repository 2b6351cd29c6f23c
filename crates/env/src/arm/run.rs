//! One VIL episode from a stiffness source to files: what `vicpilco sim` does.
//!
//! Writes into the output folder:
//! * `trace.csv`: one row per control tick ([`TickRecord::CSV_HEADER`]).
//! * `steps.csv`: one row per 0.1 s learning step (action, observation, true state, reference,
//!   flags; `singular` or `diverged` marks a step that ended the episode early).
//! * `summary.json`: [`SimSummary`].
//! * `plot.png`: x, y against the reference; stiffness; forces; the x-y path with wall and hole.

use super::ou::OuParams;
use super::params::{ArmConfig, ControllerKind};
use super::trace::{write_file, write_steps_csv, write_trace_csv, TickRecord};
use super::ArmEnv;
use crate::{EnvError, Environment, Step};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::time::Instant;

/// Where the per-step stiffness (k_x, k_y) comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum StiffnessSource {
    /// The same (k_x, k_y) every step: `const:KX,KY`.
    Const([f64; 2]),
    /// An Ornstein–Uhlenbeck profile per axis ([`OuParams::default`]) from a seed: `ou:SEED`.
    Ou(u64),
    /// A CSV file with one `k_x,k_y` row per step (an optional header line is skipped).
    File(PathBuf),
}

impl FromStr for StiffnessSource {
    type Err = EnvError;
    /// Parses `const:KX,KY`, `ou:SEED` or a file path.
    fn from_str(s: &str) -> Result<Self, EnvError> {
        if let Some(rest) = s.strip_prefix("const:") {
            let parts: Vec<&str> = rest.split(',').collect();
            if parts.len() != 2 {
                return Err(EnvError::Input(format!(
                    "stiffness {s:?}: expected const:KX,KY with two numbers"
                )));
            }
            let mut k = [0.0; 2];
            for (i, p) in parts.iter().enumerate() {
                k[i] = p.trim().parse().map_err(|_| {
                    EnvError::Input(format!("stiffness {s:?}: {p:?} is not a number"))
                })?;
            }
            check_stiffness(k, "")?;
            Ok(StiffnessSource::Const(k))
        } else if let Some(rest) = s.strip_prefix("ou:") {
            let seed = rest.trim().parse().map_err(|_| {
                EnvError::Input(format!(
                    "stiffness {s:?}: expected ou:SEED with an integer seed"
                ))
            })?;
            Ok(StiffnessSource::Ou(seed))
        } else if s.is_empty() {
            Err(EnvError::Input(
                "stiffness: expected const:KX,KY, ou:SEED or a CSV file".into(),
            ))
        } else {
            Ok(StiffnessSource::File(PathBuf::from(s)))
        }
    }
}

fn check_stiffness(k: [f64; 2], at: &str) -> Result<(), EnvError> {
    for (name, v) in ["k_x", "k_y"].iter().zip(k) {
        if !(v.is_finite() && v > 0.0) {
            return Err(EnvError::InvalidAction {
                kind: "stiffness",
                field: if at.is_empty() {
                    name.to_string()
                } else {
                    format!("{name} ({at})")
                },
                value: v,
                requirement: "> 0 and finite".into(),
            });
        }
    }
    Ok(())
}

impl StiffnessSource {
    /// The (k_x, k_y) of each of `steps` steps, every value checked.
    pub fn profile(&self, steps: usize) -> Result<Vec<[f64; 2]>, EnvError> {
        match self {
            StiffnessSource::Const(k) => Ok(vec![*k; steps]),
            StiffnessSource::Ou(seed) => Ok(OuParams::default().profiles(steps, *seed)),
            StiffnessSource::File(path) => {
                let text = std::fs::read_to_string(path).map_err(|e| {
                    EnvError::Input(format!("stiffness file {}: {e}", path.display()))
                })?;
                let mut rows = Vec::new();
                for (i, line) in text.lines().enumerate() {
                    let line = line.trim();
                    if line.is_empty() {
                        continue;
                    }
                    let cells: Vec<&str> = line.split(',').map(str::trim).collect();
                    let nums: Option<Vec<f64>> = cells.iter().map(|c| c.parse().ok()).collect();
                    match nums {
                        Some(v) if v.len() == 2 => {
                            let k = [v[0], v[1]];
                            check_stiffness(k, &format!("{} line {}", path.display(), i + 1))?;
                            rows.push(k);
                        }
                        // A header names its columns: a first line whose cells do not all
                        // start with a letter is a malformed row, not a header to skip.
                        None if i == 0
                            && cells.iter().all(|c| c.starts_with(char::is_alphabetic)) =>
                        {
                            continue
                        }
                        _ => {
                            return Err(EnvError::Input(format!(
                            "stiffness file {} line {}: expected two numbers k_x,k_y, got {line:?}",
                            path.display(),
                            i + 1
                        )))
                        }
                    }
                }
                if rows.len() != steps {
                    return Err(EnvError::Input(format!(
                        "stiffness file {} has {} rows, expected one per step ({steps})",
                        path.display(),
                        rows.len()
                    )));
                }
                Ok(rows)
            }
        }
    }
}

/// Options of one simulated episode.
#[derive(Clone, Debug)]
pub struct SimOptions {
    /// Impedance law.
    pub controller: ControllerKind,
    /// Stiffness per step.
    pub stiffness: StiffnessSource,
    /// Sensor-noise seed.
    pub seed: u64,
    /// Control rate (Hz).
    pub control_hz: f64,
    /// Sensor noise on.
    pub noise: bool,
    /// Plant/model mismatch on (1.15) or off (1.0).
    pub mismatch: bool,
}

impl Default for SimOptions {
    fn default() -> Self {
        SimOptions {
            controller: ControllerKind::Gic,
            stiffness: StiffnessSource::Const([250.0, 250.0]),
            seed: 1,
            control_hz: 1000.0,
            noise: true,
            mismatch: true,
        }
    }
}

impl SimOptions {
    /// The environment configuration these options select (thesis VIL set-up otherwise).
    pub fn config(&self) -> ArmConfig {
        let d = ArmConfig::default();
        ArmConfig {
            controller: self.controller,
            control_hz: self.control_hz,
            noise: self.noise,
            mismatch: if self.mismatch { d.mismatch } else { 1.0 },
            record_trace: true,
            ..d
        }
    }
}

/// What `summary.json` holds.
#[derive(Clone, Debug, Serialize)]
pub struct SimSummary {
    /// In the hole and within `insert_tolerance` of the end wall at the end.
    pub inserted: bool,
    /// True TCP x at the end (m).
    pub final_x: f64,
    /// True TCP y at the end (m).
    pub final_y: f64,
    /// Largest true contact force magnitude over all ticks (N).
    pub max_abs_f: f64,
    /// The episode ended early at a singular pose.
    pub singular: bool,
    /// Why the episode ended before its horizon (a singular pose or a runaway arm, with the
    /// time and what ran away), `None` when it ran to the end.
    pub stopped_early: Option<String>,
    /// Learning steps run.
    pub steps: usize,
    /// Simulated seconds.
    pub sim_time_s: f64,
    /// Wall-clock seconds of the simulation (files excluded).
    pub wall_time_s: f64,
    /// sim_time_s / wall_time_s.
    pub real_time_factor: f64,
    /// Controller name.
    pub controller: String,
    /// Control rate (Hz).
    pub control_hz: f64,
    /// RK4 step (s).
    pub h: f64,
    /// Sensor-noise seed.
    pub seed: u64,
    /// Sensor noise on.
    pub noise: bool,
    /// Plant/model inertia ratio.
    pub mismatch: f64,
    /// The full configuration used.
    pub config: ArmConfig,
}

/// Everything one episode produced (before writing files).
pub struct Episode {
    /// Summary.
    pub summary: SimSummary,
    /// The per-tick trace.
    pub trace: Vec<TickRecord>,
    /// The first observation.
    pub first_observation: Vec<f64>,
    /// (action, step) per learning step.
    pub steps: Vec<(Vec<f64>, Step)>,
    /// The configuration.
    pub config: ArmConfig,
}

/// Runs one VIL episode from the start pose P0 = (0.5, 0).
pub fn simulate(opts: &SimOptions) -> Result<Episode, EnvError> {
    let cfg = opts.config();
    let profile = opts.stiffness.profile(cfg.horizon)?;
    let mut env = ArmEnv::new(cfg.clone())?;
    let clock = Instant::now();
    let p0 = super::plan::ViaPlan::thesis().points[0];
    let first = env.reset(&[p0[0], p0[1], 0.0, 0.0, 0.0, 0.0], opts.seed)?;
    let mut steps = Vec::with_capacity(cfg.horizon);
    for k in &profile {
        let s = env.step(k)?;
        let done = s.done;
        steps.push((k.to_vec(), s));
        if done {
            break;
        }
    }
    let wall = clock.elapsed().as_secs_f64();
    let inserted = env.inserted();
    let trace = env.take_trace();
    let last = &steps.last().expect("horizon ≥ 1").1;
    let sim_time = last.info.t;
    let max_abs_f = trace
        .iter()
        .map(|r| r.f_true[0].hypot(r.f_true[1]))
        .fold(0.0, f64::max);
    let summary = SimSummary {
        inserted,
        final_x: last.info.true_state[0],
        final_y: last.info.true_state[1],
        max_abs_f,
        singular: last.info.flags.get("singular").copied().unwrap_or(false),
        stopped_early: last.info.stopped_early.clone(),
        steps: steps.len(),
        sim_time_s: sim_time,
        wall_time_s: wall,
        real_time_factor: sim_time / wall.max(1e-12),
        controller: cfg.controller.to_string(),
        control_hz: cfg.control_hz,
        h: 1.0 / cfg.control_hz / cfg.substeps() as f64,
        seed: opts.seed,
        noise: cfg.noise,
        mismatch: cfg.mismatch,
        config: cfg.clone(),
    };
    Ok(Episode {
        summary,
        trace,
        first_observation: first,
        steps,
        config: cfg,
    })
}

/// Runs [`simulate`] and writes trace.csv, steps.csv, summary.json and plot.png into `out`
/// (created if missing).
pub fn run_to_dir(opts: &SimOptions, out: &Path) -> Result<SimSummary, EnvError> {
    let ep = simulate(opts)?;
    std::fs::create_dir_all(out).map_err(|e| EnvError::Output {
        path: out.display().to_string(),
        message: e.to_string(),
    })?;
    write_trace_csv(&out.join("trace.csv"), &ep.trace)?;
    let state_names: Vec<String> = super::STATE_NAMES.iter().map(|s| s.to_string()).collect();
    let action_names = vec!["k_x".to_string(), "k_y".to_string()];
    write_steps_csv(
        &out.join("steps.csv"),
        &state_names,
        &action_names,
        &ep.first_observation,
        &ep.steps,
    )?;
    let json = serde_json::to_string_pretty(&ep.summary).map_err(|e| EnvError::Output {
        path: "summary.json".into(),
        message: e.to_string(),
    })?;
    write_file(&out.join("summary.json"), json.as_bytes())?;
    super::plot::plot_episode(&out.join("plot.png"), &ep.trace, &ep.config)?;
    Ok(ep.summary)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_stiffness_sources() {
        assert_eq!(
            "const:250,5".parse::<StiffnessSource>().unwrap(),
            StiffnessSource::Const([250.0, 5.0])
        );
        assert_eq!(
            "ou:7".parse::<StiffnessSource>().unwrap(),
            StiffnessSource::Ou(7)
        );
        let e = "const:-5,100"
            .parse::<StiffnessSource>()
            .unwrap_err()
            .to_string();
        assert!(e.contains("stiffness") && e.contains("-5"), "{e}");
        assert!("const:5".parse::<StiffnessSource>().is_err());
        assert!("ou:x".parse::<StiffnessSource>().is_err());
        let p = StiffnessSource::Ou(3).profile(100).unwrap();
        assert_eq!(p.len(), 100);
        let dir = std::env::temp_dir().join(format!("vicpilco-stiff-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("k.csv");
        std::fs::write(&f, "k_x,k_y\n100,200\n150,250\n").unwrap();
        let src: StiffnessSource = f.to_str().unwrap().parse().unwrap();
        assert_eq!(
            src.profile(2).unwrap(),
            vec![[100.0, 200.0], [150.0, 250.0]]
        );
        assert!(src.profile(3).unwrap_err().to_string().contains("2 rows"));
        std::fs::write(&f, "100,0\n").unwrap();
        assert!(src
            .profile(1)
            .unwrap_err()
            .to_string()
            .contains("stiffness k_y"));
        // A first line with a number in it is a row gone wrong, not a header.
        std::fs::write(&f, "100;200\n150,250\n").unwrap();
        let e = src.profile(1).unwrap_err().to_string();
        assert!(e.contains("line 1: expected two numbers"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
