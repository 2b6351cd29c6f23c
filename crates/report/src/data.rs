//! The run directory as read from disk (format: the files `crates/experiments` writes, listed
//! in the crate docs and the README). Only summary.json is required; everything else may be
//! absent in runs made before it existed, and its absence becomes a note in the report.

use crate::json::Node;
use crate::ReportError;
use serde_json::Value;
use std::path::Path;

mod run_files;
mod summary_json;
use run_files::{
    parse_final_eval, parse_lines, parse_prediction, parse_rollout_line, read_json, read_lines,
    read_old_rollouts,
};
use summary_json::parse_summary;

/// Outcome of the roll-outs of one policy update, as in the thesis's return plots.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Colour {
    Green,
    Yellow,
    Red,
}

impl Colour {
    pub fn parse(n: Node<'_>) -> Result<Colour, ReportError> {
        match n.v.as_str() {
            Some("green") => Ok(Colour::Green),
            Some("yellow") => Ok(Colour::Yellow),
            Some("red") => Ok(Colour::Red),
            _ => Err(n.malformed("\"green\", \"yellow\" or \"red\"")),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Colour::Green => "green",
            Colour::Yellow => "yellow",
            Colour::Red => "red",
        }
    }
}

pub(crate) struct Episode {
    pub index: u64,
    pub pred_mean: f64,
    pub pred_std: f64,
    pub recorded: f64,
    pub success: Option<bool>,
    pub success_fraction: Option<f64>,
    colour: Option<Colour>,
    pub train_s: Option<f64>,
    pub optimise_s: Option<f64>,
    pub evaluations: Option<u64>,
    /// Arm runs: the peg's x at the end of the first roll-out, metres.
    pub final_x: Option<f64>,
    /// Arm runs: the largest contact force magnitude of the first roll-out, newtons.
    pub max_force: Option<f64>,
    /// Points in the dynamics model's training set, and whether it was the sparse (FITC) GP.
    pub n_train: Option<u64>,
    pub sparse: Option<bool>,
    /// With the model chosen on the newest roll-out: whether the previous update's
    /// hyper-parameters were kept (`None`: no choice was made or recorded).
    pub kept_previous_model: Option<bool>,
}

impl Episode {
    /// The recorded colour, or (older runs) the first roll-out's success as all-or-nothing.
    pub fn colour(&self) -> Option<Colour> {
        self.colour.or(self.success.map(|s| match s {
            true => Colour::Green,
            false => Colour::Red,
        }))
    }
}

pub(crate) struct Claim {
    /// Stable name of the claim (absent in summaries written before it existed).
    pub id: Option<String>,
    pub claim: String,
    pub thesis: String,
    pub measured: String,
    pub pass: Option<bool>,
    /// Acceptance rule: at least `passing` of the runs on seeds 1 to `seeds` pass the claim.
    pub across_seeds: Option<SeedRule>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct SeedRule {
    pub passing: u64,
    pub seeds: u64,
}

/// Peg-in-hole geometry of the arm experiments, metres.
pub(crate) struct Geometry {
    pub wall_x: f64,
    pub hole_y: f64,
    pub hole_r: f64,
    pub end_x: f64,
}

pub(crate) struct Summary {
    pub experiment: String,
    pub seed: u64,
    pub controller: Option<String>,
    pub policy: Option<String>,
    pub n_params: Option<u64>,
    pub initial_return: Option<f64>,
    /// Arm runs: the return of constant gains on the same simulator, and whether they insert.
    pub constant_gain_return: Option<f64>,
    pub constant_gain_inserted: Option<bool>,
    pub episodes: Vec<Episode>,
    pub solved_at_episode: Option<u64>,
    /// Successive successful updates that count as "solved" (absent in older summaries).
    pub solved_streak: Option<u64>,
    pub interaction_s: Option<f64>,
    pub wall_s: Option<f64>,
    pub config: Option<Value>,
    pub geometry: Option<Geometry>,
    pub start_y_range: Option<(f64, f64)>,
    /// `config.dt`, the fallback time step when there is no predictions.jsonl.
    pub config_dt: Option<f64>,
    /// `config.episodes`, the policy updates the run was asked for (absent in runs whose
    /// config does not record it): a run with fewer has not ended.
    pub config_episodes: Option<u64>,
    pub thesis_reference: Option<Vec<Claim>>,
    /// Arm runs: mean (k_x, k_y) of the last roll-out over the whole episode.
    pub final_mean_gains: Option<[f64; 2]>,
    /// The update whose policy `final_eval.jsonl` rolled out (absent in summaries written
    /// before `vilta.final_policy`, whose final evaluation is the last update's).
    pub final_eval_update: Option<u64>,
    /// Each invocation of the run (empty in summaries written before they were recorded).
    pub sessions: Vec<Session>,
    /// A run started with `--replay-from`: the recorded run its first updates are.
    pub replayed_from: Option<ReplaySource>,
}

/// `summary.json`'s `replayed_from`.
pub(crate) struct ReplaySource {
    pub run: String,
    /// The recorded run's last return (absent in summaries written before it was kept),
    /// which matches it to a stored run where the path `run` names nothing.
    pub recorded_final: Option<f64>,
    pub recorded_rule: String,
    pub recorded_updates: u64,
    pub agreed: u64,
}

/// One invocation of a run: the first update it computed and the build that ran it.
pub(crate) struct Session {
    pub first_update: u64,
    pub commit: String,
    pub subnormals: String,
}

impl Summary {
    /// DIR/summary.json, the one file a run directory must have.
    pub fn load(dir: &Path) -> Result<Summary, ReportError> {
        let file = dir.join("summary.json");
        let v = read_json(&file)?;
        parse_summary(Node::root(&file, "", &v))
    }

    /// "update k", "not solved", or a dash before the first update; with the streak known,
    /// what "solved" means: the updates whose first roll-outs all succeeded.
    pub fn solved_text(&self) -> String {
        let streak = self.solved_streak.filter(|&n| n > 0);
        match (self.solved_at_episode, self.episodes.is_empty(), streak) {
            (Some(k), _, Some(1)) => format!("update {k} (its first roll-out succeeds)"),
            (Some(k), _, Some(n)) => format!(
                "update {k} (first roll-outs of updates {}–{k} all succeed)",
                (k + 1).saturating_sub(n)
            ),
            (Some(k), _, None) => format!("update {k}"),
            (None, false, Some(n)) if self.config_episodes > Some(self.episodes.len() as u64) => {
                format!("not yet ({n} successive updates whose first roll-out succeeds)")
            }
            (None, false, Some(n)) => {
                format!("not solved (never {n} successive updates whose first roll-out succeeds)")
            }
            (None, false, None) => "not solved".into(),
            (None, true, _) => "–".into(),
        }
    }

    /// Which build computed which updates: "updates 1–14: abc (gradual underflow); 15–25:
    /// def (flushed to zero)", with a leading "not recorded" range for older sessions.
    pub fn sessions_text(&self) -> String {
        let range = |a: u64, b: u64| {
            if a == b {
                format!("update {a}")
            } else {
                format!("updates {a}–{b}")
            }
        };
        let Some(first) = self.sessions.first() else {
            return "not recorded".into();
        };
        let mut parts = Vec::new();
        if first.first_update > 1 {
            parts.push(format!(
                "{}: not recorded",
                range(1, first.first_update - 1)
            ));
        }
        for (i, s) in self.sessions.iter().enumerate() {
            let end = self
                .sessions
                .get(i + 1)
                .map_or(self.episodes.len() as u64, |next| {
                    next.first_update.saturating_sub(1)
                });
            // A session stopped (or resumed with nothing left) before it finished an update.
            if end >= s.first_update {
                let what = format!("{} ({})", s.commit, s.subnormals);
                parts.push(format!("{}: {what}", range(s.first_update, end)));
            }
        }
        parts.join("; ")
    }

    /// "updates 1–k: the recorded run RUN (rule R, N updates, final return F); the rules part
    /// at k+1", or "–" for a run of its own from the start.
    pub fn replayed_text(&self) -> String {
        let Some(r) = &self.replayed_from else {
            return "–".into();
        };
        let parting = if r.agreed < r.recorded_updates {
            format!("; this run's rule parts from it at update {}", r.agreed + 1)
        } else {
            "; this run's rule chooses alike on all of them".into()
        };
        let last = r
            .recorded_final
            .map_or_else(String::new, |f| format!(", final return {f:.1}"));
        format!(
            "updates 1–{}: the recorded run {} (rule {}, {} updates{last}){parting}",
            r.agreed, r.run, r.recorded_rule, r.recorded_updates
        )
    }

    /// Wall time over policy updates (initial roll-outs included in the wall time).
    pub fn wall_per_update(&self) -> Option<f64> {
        let n = self.episodes.len();
        self.wall_s.filter(|_| n > 0).map(|w| w / n as f64)
    }
}

/// A number with `decimals` decimals, or a dash when absent.
pub(crate) fn num(v: Option<f64>, decimals: usize) -> String {
    v.map_or_else(|| "–".into(), |v| format!("{v:.decimals$}"))
}

/// Rows of numbers, one per step: actions or states.
type Rows = Vec<Vec<f64>>;

pub(crate) struct Rollout {
    pub episode: u64,
    pub costs: Option<Vec<f64>>,
    pub actions: Rows,
    pub true_states: Rows,
    /// Why the system ended the roll-out before the horizon (its last step's
    /// `stopped_early`), if it did.
    pub stopped_early: Option<String>,
    /// The true (x, y) from the start through every within-step sample the system recorded
    /// (`infos[].path`); empty when a step has none.
    pub path: Vec<PathPoint>,
}

/// One sample of a roll-out's within-step path. `step` counts steps from the roll-out's
/// start: the record gives no sample times, but the system samples at regular instants with
/// the last at the step's end, so sample j of n within step k lies at k + j/n. (A step the
/// system ended early spans less than `dt`; its samples are spread over the whole step.)
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PathPoint {
    pub step: f64,
    pub x: f64,
    pub y: f64,
}

impl Rollout {
    /// The true y at the roll-out's end (arm runs), `None` without true states.
    pub fn final_y(&self) -> Option<f64> {
        self.true_states.last().and_then(|s| s.get(1)).copied()
    }

    /// Mean and population std of action component `j` over the roll-out; `None` without
    /// actions or when the rows are shorter than `j + 1`.
    pub fn action_mean_std(&self, j: usize) -> Option<(f64, f64)> {
        let v: Vec<f64> = self
            .actions
            .iter()
            .map(|a| a.get(j).copied())
            .collect::<Option<_>>()?;
        if v.is_empty() {
            return None;
        }
        let n = v.len() as f64;
        let mean = v.iter().sum::<f64>() / n;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n;
        Some((mean, var.sqrt()))
    }
}

/// One predicted step; `t` is the time at the end of the step and `mean`/`var` describe the
/// state there, while the action fields describe the action applied during the step.
pub(crate) struct PredStep {
    pub t: f64,
    pub mean: Vec<f64>,
    pub var: Vec<f64>,
    pub action_mean: Vec<f64>,
    pub action_var: Vec<f64>,
    pub weighted_cost: Option<(f64, f64)>,
}

pub(crate) struct Prediction {
    pub episode: u64,
    pub dt: f64,
    pub state_names: Vec<String>,
    pub action_names: Vec<String>,
    /// The range of each squashed action (absent in runs without squashing and in files
    /// written before it was recorded).
    pub action_bounds: Option<Vec<(f64, f64)>>,
    /// Each start distribution's steps (a run optimising over K start distributions, as
    /// `vilta-var` does, records K predictions; every one has at least one step).
    pub starts: Vec<Vec<PredStep>>,
}

impl Prediction {
    /// Start distribution `k`'s steps.
    pub fn steps(&self, k: usize) -> &[PredStep] {
        &self.starts[k]
    }

    /// The start distribution to compare with roll-out `r`: the one whose first predicted
    /// state gives `r`'s first recorded state the highest likelihood (per-dimension Gaussian).
    /// A roll-out from a random start (`vilta-var`) is then shown beside the prediction from
    /// the start nearest its own, not beside whichever start happens to be first.
    pub fn start_nearest(&self, r: Option<&Rollout>) -> usize {
        let Some(x1) = r.and_then(|r| r.true_states.get(1)) else {
            return 0;
        };
        let misfit = |steps: &[PredStep]| -> f64 {
            let s = &steps[0];
            let terms = s.mean.iter().zip(&s.var).zip(x1);
            terms
                .map(|((m, v), x)| (x - m).powi(2) / v.max(1e-300) + v.max(1e-300).ln())
                .sum()
        };
        let scores = self.starts.iter().map(|s| misfit(s));
        let best = scores.enumerate().min_by(|a, b| a.1.total_cmp(&b.1));
        best.map_or(0, |(k, _)| k)
    }

    /// ", start k of K" for a prediction over several start distributions, else "".
    pub fn start_label(&self, k: usize) -> String {
        match self.starts.len() {
            1 => String::new(),
            n => format!(", start {} of {n}", k + 1),
        }
    }
}

pub(crate) struct FinalEval {
    pub success: bool,
    pub true_states: Vec<Vec<f64>>,
    /// As [`Rollout::path`].
    pub path: Vec<PathPoint>,
}

pub(crate) struct Run {
    pub summary: Summary,
    pub rollouts: Option<Vec<Rollout>>,
    pub predictions: Option<Vec<Prediction>>,
    pub final_eval: Option<Vec<FinalEval>>,
    /// What was absent or ignored while reading; shown in the report.
    pub notes: Vec<String>,
}

impl Run {
    pub fn load(dir: &Path) -> Result<Run, ReportError> {
        let mut notes = Vec::new();
        let summary = Summary::load(dir)?;

        let rollouts = match read_lines(&dir.join("rollouts.jsonl"), &mut notes)? {
            Some(lines) => Some(parse_lines(&lines, parse_rollout_line)?),
            None => read_old_rollouts(&dir.join("rollouts.json"), &mut notes)?,
        };
        if rollouts.is_none() {
            notes.push("no rollouts.jsonl: recorded trajectories are not plotted".into());
        }
        let predictions = read_lines(&dir.join("predictions.jsonl"), &mut notes)?
            .map(|lines| parse_lines(&lines, parse_prediction))
            .transpose()?;
        if predictions.is_none() {
            notes.push("no predictions.jsonl: predicted trajectories are not plotted".into());
        }
        let final_eval = read_lines(&dir.join("final_eval.jsonl"), &mut notes)?
            .map(|lines| parse_lines(&lines, parse_final_eval))
            .transpose()?;
        Ok(Run {
            summary,
            rollouts,
            predictions,
            final_eval,
            notes,
        })
    }

    /// Every roll-out the system ended before the horizon, as "update k, roll-out j: why"
    /// (update 0 is the initial roll-outs); "none", or "–" without rollouts.jsonl.
    pub fn ended_early_text(&self) -> String {
        let Some(rollouts) = &self.rollouts else {
            return "–".into();
        };
        let mut per_update: std::collections::BTreeMap<u64, usize> = Default::default();
        let ended: Vec<String> = rollouts
            .iter()
            .filter_map(|r| {
                let j = per_update.entry(r.episode).or_default();
                *j += 1;
                let why = r.stopped_early.as_ref()?;
                Some(format!("update {}, roll-out {j}: {why}", r.episode))
            })
            .collect();
        if ended.is_empty() {
            "none".into()
        } else {
            ended.join("; ")
        }
    }

    /// The first roll-out recorded after `episode` updates (the one summary.json describes).
    pub fn rollout_of(&self, episode: u64) -> Option<&Rollout> {
        self.rollouts
            .as_ref()?
            .iter()
            .find(|r| r.episode == episode)
    }

    /// The predicted return (mean, std) to set beside update `e`'s recorded first roll-out.
    /// A policy optimised over K > 1 start distributions has K predictions, and summary.json
    /// records the first's; the roll-out started from one state, so this is the prediction
    /// from the start nearest it ([`Prediction::start_nearest`]), summed from
    /// predictions.jsonl's weighted step costs, with which start it is (k of K, from 0). Without
    /// a recorded roll-out to compare, or without that start's step costs (older files), it is
    /// the first start's, summary.json's, and says so. Runs with one start, or without that
    /// prediction, get summary.json's numbers and no start.
    pub fn predicted_return(&self, e: &Episode) -> (f64, f64, Option<(usize, usize)>) {
        let recorded = (e.pred_mean, e.pred_std, None);
        let Some(p) = self
            .predictions
            .as_ref()
            .and_then(|ps| ps.iter().find(|p| p.episode == e.index))
            .filter(|p| p.starts.len() > 1)
        else {
            return recorded;
        };
        let k = p.start_nearest(self.rollout_of(e.index));
        let which = Some((k, p.starts.len()));
        let costs: Option<Vec<(f64, f64)>> = p.steps(k).iter().map(|s| s.weighted_cost).collect();
        match costs {
            Some(c) => (
                c.iter().map(|c| c.0).sum(),
                c.iter().map(|c| c.1).sum(),
                which,
            ),
            None => (e.pred_mean, e.pred_std, Some((0, p.starts.len()))),
        }
    }

    /// The time step: the predictions' if any, else `config.dt`.
    pub fn dt(&self) -> Option<f64> {
        self.predictions
            .as_ref()
            .and_then(|p| p.first())
            .map(|p| p.dt)
            .or(self.summary.config_dt)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn step(mean: &[f64], var: &[f64]) -> PredStep {
        PredStep {
            t: 0.1,
            mean: mean.to_vec(),
            var: var.to_vec(),
            action_mean: vec![],
            action_var: vec![],
            weighted_cost: None,
        }
    }

    fn rollout(first_states: &[&[f64]]) -> Rollout {
        Rollout {
            episode: 1,
            costs: None,
            actions: vec![],
            true_states: first_states.iter().map(|s| s.to_vec()).collect(),
            stopped_early: None,
            path: vec![],
        }
    }

    #[test]
    fn a_roll_out_is_compared_with_the_start_nearest_its_own() {
        let pred = Prediction {
            episode: 1,
            dt: 0.1,
            state_names: vec!["x".into(), "y".into()],
            action_names: vec![],
            action_bounds: None,
            starts: [0.1, 0.2, 0.3]
                .iter()
                .map(|&y| vec![step(&[0.5, y], &[1e-4, 1e-4])])
                .collect(),
        };
        let r = rollout(&[&[0.5, 0.27], &[0.5, 0.28]]);
        assert_eq!(pred.start_nearest(Some(&r)), 2);
        let r = rollout(&[&[0.5, 0.12], &[0.5, 0.13]]);
        assert_eq!(pred.start_nearest(Some(&r)), 0);
        // Without a recorded step to compare, the first.
        assert_eq!(pred.start_nearest(Some(&rollout(&[&[0.5, 0.3]]))), 0);
        assert_eq!(pred.start_nearest(None), 0);
        assert_eq!(pred.start_label(2), ", start 3 of 3");
    }
}
