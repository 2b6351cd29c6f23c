//! Keeping the run directory current while the loop runs, and continuing a stopped run.
//!
//! * every roll-out is appended to `rollouts.jsonl` when it is recorded, with its weighted
//!   cost per step;
//! * every update's long-term prediction is appended to `predictions.jsonl`, and the policy
//!   it rolled out (its parameters) to `policies.jsonl`, so any update's policy can be
//!   replayed or judged under another update's model;
//! * `summary.json` is rewritten after every update, and the plots, `report.html` and
//!   `report.md` with it;
//! * `checkpoint.json` after the initial roll-outs and after every update: the loop state
//!   ([`LoopState`]: data, hyper-parameters, inducing inputs, policy, records), the summary so
//!   far and the config it belongs to. Every random stream is derived from the master seed and
//!   the episode, so no generator state is needed to continue bit for bit.

use crate::summary::{colour, write_json_atomic, EpisodeSummary, Summary};
use crate::{ExperimentError, RunOptions};
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;
use vicpilco_learn::data::Rollout;
use vicpilco_learn::record::{EpisodeRecord, LoopObserver, LoopState, Phase};
use vicpilco_learn::value::ValueOut;
use vicpilco_report::atomic::write_atomic;
use vicpilco_report::difference::first_difference;
use vicpilco_report::jsonl::parse_json_lines;

/// Version of `checkpoint.json`'s layout; a different one is refused.
pub const CHECKPOINT_FORMAT: u32 = 1;

/// What `checkpoint.json` holds.
#[derive(Serialize, Deserialize)]
pub struct Checkpoint {
    /// Layout version, [`CHECKPOINT_FORMAT`] when written; reading refuses any other.
    pub format: u32,
    /// The experiment's name (the one an alias stands for, [`crate::config::canonical`]); a
    /// resume under another is refused.
    pub experiment: String,
    /// The run's master seed; a resume with another is refused.
    pub seed: u64,
    /// The settings that must match to continue (everything but the number of updates).
    pub identity: serde_json::Value,
    /// `summary.json` as of this checkpoint; a resume continues it with its `config` replaced
    /// by the current settings.
    pub summary: Summary,
    /// The loop after `state.completed` updates (0: after the initial roll-outs).
    pub state: LoopState,
}

/// Task-specific numbers of a roll-out for `summary.json`: (final x, largest |f|, start y).
pub type RolloutExtras = fn(&Rollout) -> (f64, f64, f64);

/// The thesis claims a run's summary decides so far: applied after every update, so a run
/// stopped part-way keeps the verdicts its updates already settle.
pub type ClaimsOf<'a> = Box<dyn Fn(&Summary) -> Vec<crate::summary::ThesisCheck> + 'a>;

/// How predictions are labelled and weighted in `predictions.jsonl`.
pub struct PredictionLabels {
    /// Step length Δt (s): step t (from 0) of a prediction is labelled with time (t + 1) Δt.
    pub dt: f64,
    /// The environment's state names, labelling each step's `mean` and `var`.
    pub state_names: Vec<String>,
    /// The environment's action names, labelling each step's `action_mean` and `action_var`.
    pub action_names: Vec<String>,
    /// The range each (squashed) action can take, `None` without squashing: the report
    /// clips the Gaussian summary's band to it, since no applied action lies outside.
    pub action_bounds: Option<Vec<(f64, f64)>>,
    /// w1 of the return: the weighted cost per step is `w1 E[c] + w3 E[c_a]`.
    pub w_mean: f64,
    /// w3, the energy cost's weight in that sum (0 without an energy cost).
    pub w_energy: f64,
}

/// The observer that writes the run directory; forwards to the caller's observer.
pub struct Recorder<'a> {
    /// The caller's observer (progress, logs): every callback is forwarded after the files
    /// are written.
    pub inner: &'a mut dyn LoopObserver,
    /// The summary so far, rewritten to `summary.json` after every update.
    pub summary: Summary,
    /// The run directory all files go to.
    pub dir: PathBuf,
    /// Step length Δt (s): each roll-out adds its steps × Δt to `summary.interaction_s`.
    pub dt: f64,
    /// How `predictions.jsonl`'s lines are labelled and weighted.
    pub labels: PredictionLabels,
    /// Gives `final_x`, `max_force` and `start_y` of each update's first roll-out (arm runs;
    /// `None`: they and the final gains stay null).
    pub extras: Option<RolloutExtras>,
    /// The settings written into every checkpoint ([`Checkpoint::identity`]).
    pub identity: serde_json::Value,
    /// The thesis claims re-decided after every update (arm runs); `None`: no claims.
    pub claims: Option<ClaimsOf<'a>>,
    /// Wall time of earlier sessions of this run (resumed runs).
    pub wall_before: f64,
    /// When this session began; [`Recorder::wall_s`] adds its elapsed time to `wall_before`.
    pub started: Instant,
    /// `rollouts.jsonl`, open for appending ([`open_jsonl`]).
    pub rollouts: std::fs::File,
    /// `predictions.jsonl`, open for appending.
    pub predictions: std::fs::File,
    /// `policies.jsonl`, open for appending.
    pub policies: std::fs::File,
    /// The first roll-out of the update in progress, and the last one of the run.
    pub current: Option<Rollout>,
    /// The first write error. The observer's callbacks cannot fail, so the loop runs on (later
    /// errors are logged only) and the caller returns this one after it.
    pub error: Option<ExperimentError>,
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> ExperimentError + '_ {
    move |e| ExperimentError::Io {
        path: path.to_path_buf(),
        source: e,
    }
}

/// Creates the run directory of a fresh run, first refusing one that holds a run, before
/// anything is written. A resumed run's directory must exist already (its checkpoint says
/// whether there is anything to resume), and [`crate::replay::graft`] makes a replaying run's
/// once its source checks out, so a refused run leaves no folder behind. Returns the
/// directory's lock ([`lock_run_dir`]) whenever the directory exists, to be held for the run.
pub(crate) fn prepare_out(opts: &RunOptions) -> Result<Option<std::fs::File>, ExperimentError> {
    if !opts.resume && opts.replay_from.is_none() {
        refuse_recorded_run(&opts.out)?;
        std::fs::create_dir_all(&opts.out).map_err(io_err(&opts.out))?;
    }
    if opts.out.is_dir() {
        lock_run_dir(&opts.out).map(Some)
    } else {
        Ok(None)
    }
}

/// The file in a run directory whose lock marks it in use.
pub const LOCK_FILE: &str = ".vicpilco.lock";

/// Locks `dir` for this process (an advisory lock on [`LOCK_FILE`], released when the file is
/// dropped or the process ends, however it ends): a `--resume` started while the run is still
/// going would otherwise truncate the records the running process appends to.
pub(crate) fn lock_run_dir(dir: &Path) -> Result<std::fs::File, ExperimentError> {
    let path = dir.join(LOCK_FILE);
    let file = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&path)
        .map_err(io_err(&path))?;
    match file.try_lock() {
        Ok(()) => Ok(file),
        Err(std::fs::TryLockError::WouldBlock) => Err(ExperimentError::RunBusy {
            dir: dir.to_path_buf(),
        }),
        Err(std::fs::TryLockError::Error(e)) => Err(io_err(&path)(e)),
    }
}

/// The JSON-lines files a run directory keeps per update.
pub(crate) const PER_UPDATE_FILES: [&str; 3] =
    ["rollouts.jsonl", "predictions.jsonl", "policies.jsonl"];

/// Fails with [`ExperimentError::RunExists`] when `dir` holds any of a run's record files (a
/// run stopped during its initial roll-out has `rollouts.jsonl` only).
pub(crate) fn refuse_recorded_run(dir: &Path) -> Result<(), ExperimentError> {
    let mut record_files = ["checkpoint.json", "summary.json"]
        .iter()
        .chain(PER_UPDATE_FILES.iter());
    match record_files.find(|f| dir.join(f).exists()) {
        Some(&file) => Err(ExperimentError::RunExists {
            dir: dir.to_path_buf(),
            file,
            held: read_checkpoint_unchecked(dir).map_or("a run".into(), |cp| {
                let done = cp.summary.episodes.len();
                format!(
                    "a run of `{}`, seed {}, {done} update{} done",
                    cp.experiment,
                    cp.seed,
                    if done == 1 { "" } else { "s" }
                )
            }),
        }),
        None => Ok(()),
    }
}

/// Open a JSON-lines file for appending, first dropping lines of episodes after `keep_upto`
/// (a resumed run repeats them) or, with `None`, everything. A last line cut off mid-write
/// (the run was stopped while appending it) is dropped too: records are appended before the
/// checkpoint that covers them is written, so it belongs to an update the resume repeats.
pub fn open_jsonl(path: &Path, keep_upto: Option<usize>) -> Result<std::fs::File, ExperimentError> {
    let kept: Vec<String> = match keep_upto {
        Some(last) if path.exists() => {
            let text = std::fs::read_to_string(path).map_err(io_err(path))?;
            let read = parse_json_lines(&text).map_err(|e| ExperimentError::Resume {
                path: path.to_path_buf(),
                message: format!("line {}: {}", e.line, e.error),
            })?;
            if let Some(line) = read.torn {
                tracing::warn!(
                    "{}: dropped the incomplete last line {line}, cut off when the run stopped",
                    path.display()
                );
            }
            let mut kept = Vec::new();
            for line in read.lines {
                let episode =
                    line.value["episode"]
                        .as_u64()
                        .ok_or_else(|| ExperimentError::Resume {
                            path: path.to_path_buf(),
                            message: format!("line {} has no \"episode\"", line.number),
                        })?;
                if episode as usize <= last {
                    kept.push(line.text.to_string());
                }
            }
            kept
        }
        _ => Vec::new(),
    };
    let mut text = kept.join("\n");
    if !text.is_empty() {
        text.push('\n');
    }
    // Not truncated in place: a resume stopped before the kept lines were back would lose
    // records its checkpoint covers, and the next resume would take the cut for a torn line.
    write_atomic(path, text.as_bytes()).map_err(io_err(path))?;
    std::fs::OpenOptions::new()
        .append(true)
        .open(path)
        .map_err(io_err(path))
}

/// Read `DIR/checkpoint.json` and check it belongs to this run.
pub fn read_checkpoint(
    dir: &Path,
    experiment: &str,
    seed: u64,
    identity: &serde_json::Value,
) -> Result<Checkpoint, ExperimentError> {
    let path = dir.join("checkpoint.json");
    let bad = |message: String| ExperimentError::Resume {
        path: path.clone(),
        message,
    };
    let cp = read_checkpoint_unchecked(dir)?;
    // Runs recorded under an alias before runs recorded the name it stands for.
    if crate::config::canonical(&cp.experiment) != crate::config::canonical(experiment) {
        return Err(bad(format!(
            "written by experiment `{}`, not `{experiment}`",
            cp.experiment
        )));
    }
    if cp.seed != seed {
        return Err(bad(format!("written with seed {}, not {seed}", cp.seed)));
    }
    if let Some(diff) = first_difference(&cp.identity, identity, String::new()) {
        return Err(bad(format!(
            "written with different settings: {diff} (only the number of updates may change on \
             resume{})",
            diff.quick_hint("resumes")
        )));
    }
    Ok(cp)
}

/// Read `DIR/checkpoint.json` of any run (format checked, nothing else).
pub fn read_checkpoint_unchecked(dir: &Path) -> Result<Checkpoint, ExperimentError> {
    let path = dir.join("checkpoint.json");
    let bad = |message: String| ExperimentError::Resume {
        path: path.clone(),
        message,
    };
    let text = std::fs::read_to_string(&path).map_err(|e| {
        let archive = dir.join("run.tar.xz");
        bad(if archive.is_file() {
            // A folder of results/ holds the run packed (scripts/archive-run).
            let name = dir
                .file_name()
                .map_or("run".into(), |n| n.to_string_lossy().into_owned());
            // A directory of its own, made by a mkdir that fails rather than unpack over a
            // run there (runs/<name> is a fresh run's default directory).
            format!(
                "no checkpoint ({e}); {} is a stored run, to be unpacked first: mkdir \
                 runs/stored-{name} && tar -C runs/stored-{name} -xJf {}, then give \
                 runs/stored-{name}",
                dir.display(),
                archive.display()
            )
        } else {
            format!(
                "no checkpoint ({e}): not a run directory, or its run stopped during its \
                 initial roll-out"
            )
        })
    })?;
    let format: serde_json::Value = serde_json::from_str(&text).map_err(|e| bad(e.to_string()))?;
    if format["format"].as_u64() != Some(CHECKPOINT_FORMAT as u64) {
        return Err(bad(format!(
            "format {} cannot be read (expected {CHECKPOINT_FORMAT})",
            format["format"]
        )));
    }
    serde_json::from_str(&text).map_err(|e| bad(e.to_string()))
}

/// A new file at `path` (its folder made if need be); refuses to overwrite one, so a result
/// written earlier is never lost.
pub(crate) fn create_new(path: &Path) -> Result<std::fs::File, ExperimentError> {
    let io_err = |e: std::io::Error| ExperimentError::Io {
        path: path.to_path_buf(),
        source: e,
    };
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(io_err)?;
    }
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(path)
        .map_err(|e| match e.kind() {
            std::io::ErrorKind::AlreadyExists => already_exists(path),
            _ => io_err(e),
        })
}

/// The error for an output file that exists: a result written earlier is never overwritten.
pub(crate) fn already_exists(path: &Path) -> ExperimentError {
    ExperimentError::Io {
        path: path.to_path_buf(),
        source: std::io::Error::new(
            std::io::ErrorKind::AlreadyExists,
            "already exists, and a result written earlier is not overwritten: give another \
             --out, or delete it",
        ),
    }
}

impl Recorder<'_> {
    fn keep(&mut self, result: Result<(), ExperimentError>) {
        if let Err(e) = result {
            tracing::error!("{e}");
            self.error.get_or_insert(e);
        }
    }

    fn append(
        file: &mut std::fs::File,
        path: PathBuf,
        line: &serde_json::Value,
    ) -> Result<(), ExperimentError> {
        // One write per record, newline included: `writeln!` issues a write per formatted
        // token, so a stop mid-record would leave a line cut anywhere.
        let mut text = line.to_string();
        text.push('\n');
        file.write_all(text.as_bytes())
            .and_then(|()| file.flush())
            .map_err(|e| ExperimentError::Io { path, source: e })
    }

    /// summary.json with the time and claims so far, then the report: the report follows the
    /// run, so a long run can be watched in a browser.
    fn write_summary_and_report(&mut self) {
        self.summary.wall_s = self.wall_s();
        if let Some(claims) = &self.claims {
            self.summary.thesis_reference = claims(&self.summary);
        }
        let result = self.summary.write(&self.dir).map_err(ExperimentError::from);
        self.keep(result);
        let result = vicpilco_report::write_report(&self.dir)
            .map(|_| ())
            .map_err(Into::into);
        self.keep(result);
    }

    /// `wall_s` of the run so far, earlier sessions included.
    pub fn wall_s(&self) -> f64 {
        self.wall_before + self.started.elapsed().as_secs_f64()
    }

    fn prediction_line(
        &self,
        episode: usize,
        out: &ValueOut,
    ) -> Result<serde_json::Value, ExperimentError> {
        let l = &self.labels;
        let mut starts = Vec::with_capacity(out.trajectories.len());
        for traj in &out.trajectories {
            let mut steps = Vec::with_capacity(traj.len());
            for (t, s) in traj.iter().enumerate() {
                let diag =
                    |m: &faer::Mat<f64>| (0..m.nrows()).map(|i| m[(i, i)]).collect::<Vec<_>>();
                let var = diag(&s.cov);
                let action_var = diag(&s.action_cov);
                let weighted_mean = l.w_mean * s.cost_mean + l.w_energy * s.energy_mean;
                let weighted_std = l.w_mean * s.cost_var.max(0.0).sqrt();
                let all = s
                    .mean
                    .iter()
                    .chain(&var)
                    .chain(&s.action_mean)
                    .chain(&action_var);
                if let Some(v) = all
                    .chain([&weighted_mean, &weighted_std])
                    .find(|v| !v.is_finite())
                {
                    return Err(ExperimentError::Write(
                        crate::summary::WriteError::NonFinite {
                            what: format!("update {episode} prediction at step {t}"),
                            value: *v,
                        },
                    ));
                }
                steps.push(serde_json::json!({
                    "t": (t + 1) as f64 * l.dt,
                    "mean": s.mean,
                    "var": var,
                    "action_mean": s.action_mean,
                    "action_var": action_var,
                    "cost_mean": s.cost_mean,
                    "cost_var": s.cost_var,
                    "energy_mean": s.energy_mean,
                    "weighted_cost_mean": weighted_mean,
                    "weighted_cost_std": weighted_std,
                }));
            }
            starts.push(serde_json::Value::Array(steps));
        }
        Ok(serde_json::json!({
            "episode": episode,
            "dt": l.dt,
            "state_names": l.state_names,
            "action_names": l.action_names,
            "action_bounds": l.action_bounds,
            "starts": starts,
        }))
    }
}

impl LoopObserver for Recorder<'_> {
    fn phase(&mut self, episode: usize, phase: Phase) {
        self.inner.phase(episode, phase)
    }
    fn objective(&mut self, episode: usize, j: f64) {
        self.inner.objective(episode, j)
    }
    fn rollout_done(&mut self, episode: usize, rollout: &Rollout, costs: &[f64]) {
        self.summary.interaction_s += rollout.len() as f64 * self.dt;
        if episode == 0 && self.summary.initial_return.is_none() {
            self.summary.initial_return = Some(costs.iter().sum());
        }
        if rollout.used_for_training {
            self.current = Some(rollout.clone());
        }
        let line = serde_json::json!({ "episode": episode, "costs": costs, "rollout": rollout });
        let path = self.dir.join("rollouts.jsonl");
        let result = Self::append(&mut self.rollouts, path, &line);
        self.keep(result);
        self.inner.rollout_done(episode, rollout, costs)
    }
    fn predicted(&mut self, episode: usize, prediction: &ValueOut) {
        let path = self.dir.join("predictions.jsonl");
        let result = self
            .prediction_line(episode, prediction)
            .and_then(|line| Self::append(&mut self.predictions, path, &line));
        self.keep(result);
        self.inner.predicted(episode, prediction)
    }
    fn episode_done(&mut self, record: &EpisodeRecord) {
        let extras = match (self.extras, &self.current) {
            (Some(f), Some(r)) => Some(f(r)),
            _ => None,
        };
        if let (Some(_), Some(r)) = (self.extras, &self.current) {
            self.summary.final_gains = Some(crate::checks::gains_first_last(r, self.dt));
            self.summary.final_mean_gains = Some(crate::checks::mean_gains(&r.actions));
        }
        self.summary.episodes.push(EpisodeSummary {
            record: record.clone(),
            colour: colour(record.success_fraction).to_string(),
            final_x: extras.map(|e| e.0),
            max_force: extras.map(|e| e.1),
            start_y: extras.map(|e| e.2),
        });
        self.summary.update_solved();
        self.write_summary_and_report();
        self.inner.episode_done(record)
    }
    fn checkpoint(&mut self, state: &LoopState) {
        // Episode 0's line is the untrained policy the first update starts from.
        let line = serde_json::json!({ "episode": state.completed, "params": state.policy_params });
        let path = self.dir.join("policies.jsonl");
        let result = Self::append(&mut self.policies, path, &line);
        self.keep(result);
        // The checkpoint says these records exist: they reach the disk before it does, so a
        // power cut (not only a killed process) cannot leave a checkpoint ahead of its records.
        let synced: Vec<_> = [
            (&self.rollouts, "rollouts.jsonl"),
            (&self.predictions, "predictions.jsonl"),
            (&self.policies, "policies.jsonl"),
        ]
        .into_iter()
        .map(|(file, name)| {
            file.sync_data().map_err(|e| ExperimentError::Io {
                path: self.dir.join(name),
                source: e,
            })
        })
        .collect();
        for result in synced {
            self.keep(result);
        }
        self.summary.wall_s = self.wall_s();
        let cp = Checkpoint {
            format: CHECKPOINT_FORMAT,
            experiment: self.summary.experiment.clone(),
            seed: self.summary.seed,
            identity: self.identity.clone(),
            summary: self.summary.clone(),
            state: state.clone(),
        };
        let result = serde_json::to_value(&cp)
            .map_err(|e| ExperimentError::Write(e.into()))
            .and_then(|v| {
                write_json_atomic(&self.dir.join("checkpoint.json"), &v).map_err(Into::into)
            });
        self.keep(result);
        if state.completed == 0 && self.summary.episodes.is_empty() {
            // The first update can take minutes (vilta-var's about eight): the initial roll-out
            // is summarised and reported now, so `vicpilco report` and a browser show it meanwhile.
            self.write_summary_and_report();
        }
        self.inner.checkpoint(state)
    }
}
