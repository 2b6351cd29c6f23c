//! Would another model-selection rule have made a recorded run's choices? Replays the run's
//! model training update by update on its recorded roll-outs and policies, checks that each
//! update reproduces the recorded rule's scores, and asks the other rule (the set-up's) for its
//! verdict, up to the first update where the two rules part.
//!
//! Why: every update of a run is fixed by its data, its model and its policy, and the model is
//! fixed by the chain of choices; so while the other rule chooses as the recorded one did, a
//! run under the other rule *is* the recorded run, update for update. The replay costs the
//! model fits only (no policy optimisation), and its [`LoopState`] at the parting update lets
//! the other rule's run continue from there instead of from the start.

use crate::data::training_set;
use crate::outer::LoopSetup;
use crate::record::{EpisodeRecord, LoopState};
use crate::selection::{verdict_of, ModelSelection, RuleVerdict, SelectionRecord};
use crate::LearnError;
use faer::Mat;
use vicpilco_gp::train::initial_hyper;
use vicpilco_gp::{DynamicsModel, Hyper};
use vicpilco_pilco::policy::Policy;

/// Relative tolerance between a replayed score and the recorded one: the replay must rebuild
/// the recorded models, not similar ones (same binary: equal bit for bit; a build on another
/// CPU may round the last digits of sums differently).
pub const REPLAY_SCORE_TOLERANCE: f64 = 1e-9;

/// One replayed update's verdicts.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ReplayedUpdate {
    /// 1-based policy update.
    pub update: usize,
    /// The recorded rule's scores as replayed (equal to the recorded ones; with
    /// [`ModelSelection::Likelihood`], which always refits, the return scores).
    pub recorded: SelectionRecord,
    /// The set-up's rule on the same two models.
    pub other: SelectionRecord,
    /// Every comparing rule on the same two models ([`ModelSelection::COMPARING`]'s order);
    /// empty in records written before it was kept.
    #[serde(default)]
    pub every_rule: Vec<RuleVerdict>,
}

/// What a replay found.
#[derive(Clone, Debug)]
pub struct Replay {
    /// Updates 1..=`agreed` choose alike under both rules (every update with a choice, and
    /// the first, which has none).
    pub agreed: usize,
    /// Every update with a choice that was replayed, the parting one last if the rules part.
    pub updates: Vec<ReplayedUpdate>,
    /// The loop state after update `agreed` under the set-up's rule: the recorded data, policy
    /// and records of updates 1..=`agreed` (each record's choice scored by the set-up's rule)
    /// and the replayed hyper-parameters and inducing inputs. [`LoopSetup::resume`] continues
    /// it as the set-up's own run.
    pub state: LoopState,
}

/// Where [`LoopSetup::walk_recorded`] stopped: the updates it completed and the model they
/// left.
struct Walked {
    completed: usize,
    hyp: Option<Vec<Hyper>>,
    inducing: Option<Mat<f64>>,
}

impl<P: Policy + Clone + Sync> LoopSetup<P>
where
    P::Cache: Send,
{
    /// Replay the run that `recorded` (its final checkpoint state) and `policies` (the policy
    /// parameters after each update `u`, `policies[u]`, 0 for the untrained one) describe,
    /// made with `recorded_rule` and this set-up otherwise, and find where this set-up's rule
    /// would have chosen differently. `on_update` sees each replayed update as it completes.
    /// Errors if a replayed score differs from the recorded one by more than
    /// [`REPLAY_SCORE_TOLERANCE`] (the models are not the recorded ones), or if the record is
    /// incomplete.
    pub fn replay_selection(
        &self,
        recorded_rule: ModelSelection,
        recorded: &LoopState,
        policies: &[Vec<f64>],
        on_update: &mut dyn FnMut(&ReplayedUpdate),
    ) -> Result<Replay, LearnError> {
        let mut updates = Vec::new();
        let mut episodes: Vec<EpisodeRecord> = Vec::new();
        let walked = self.walk_recorded(recorded_rule, recorded, policies, &mut |ep, u| {
            let Some(u) = u else {
                episodes.push(recorded.episodes[ep - 1].clone());
                return true;
            };
            on_update(u);
            updates.push(u.clone());
            if u.other.kept_previous != u.recorded.kept_previous {
                return false;
            }
            episodes.push(EpisodeRecord {
                model_selection: self.model_selection.compares().then_some(u.other),
                ..recorded.episodes[ep - 1].clone()
            });
            true
        })?;
        let agreed = walked.completed;
        Ok(Replay {
            agreed,
            updates,
            state: LoopState {
                completed: agreed,
                data: recorded.data[..self.initial_rollouts + agreed].to_vec(),
                hyp: walked.hyp,
                inducing: walked.inducing.as_ref().map(crate::outer::mat_rows),
                policy_params: policies[agreed].clone(),
                episodes,
            },
        })
    }

    /// Replay the recorded run (as [`Self::replay_selection`]) through all its updates, along
    /// its own choices, and return every comparing rule's verdict at each update with a
    /// choice (`on_update` sees each as it completes, and stops the replay by returning
    /// false, e.g. when the verdict could not be written). Past the first update where a rule
    /// parts from the recorded one, its verdicts are on the recorded run's models, not on those
    /// its own run would have had: they say how it judges the recorded models, not what its run
    /// would have done.
    pub fn rescore_run(
        &self,
        recorded_rule: ModelSelection,
        recorded: &LoopState,
        policies: &[Vec<f64>],
        on_update: &mut dyn FnMut(&ReplayedUpdate) -> bool,
    ) -> Result<Vec<ReplayedUpdate>, LearnError> {
        let mut updates = Vec::new();
        self.walk_recorded(recorded_rule, recorded, policies, &mut |_, u| match u {
            Some(u) => {
                updates.push(u.clone());
                on_update(u)
            }
            None => true,
        })?;
        Ok(updates)
    }

    /// Rebuild the recorded run's models update by update along its recorded choices, and
    /// hand each update to `visit` (with its verdicts when it chose a model) until `visit`
    /// says stop (that update then does not count as completed).
    fn walk_recorded(
        &self,
        recorded_rule: ModelSelection,
        recorded: &LoopState,
        policies: &[Vec<f64>],
        visit: &mut dyn FnMut(usize, Option<&ReplayedUpdate>) -> bool,
    ) -> Result<Walked, LearnError> {
        let bad = |what: String| Err(LearnError::Spec(format!("replay: {what}")));
        let done = recorded.completed;
        if recorded.data.len() != self.initial_rollouts + done {
            return bad(format!(
                "{} training roll-outs for {} initial roll-outs and {done} updates",
                recorded.data.len(),
                self.initial_rollouts
            ));
        }
        if recorded.episodes.len() != done || policies.len() != done + 1 {
            return bad(format!(
                "{} update records and {} policies for {done} updates",
                recorded.episodes.len(),
                policies.len()
            ));
        }
        let missing = |rule: ModelSelection| {
            LearnError::Spec(format!("replay: no verdict of the rule `{rule}`"))
        };
        let mut policy = self.policy.clone();
        let mut walked = Walked {
            completed: 0,
            hyp: None,
            inducing: None,
        };
        for ep in 1..=done {
            let data = &recorded.data[..self.initial_rollouts + ep - 1];
            let (inputs, targets) = training_set(&self.spec, data, self.prior_shift.as_deref());
            let recorded_choice = recorded.episodes[ep - 1].model_selection;
            let inducing = walked.inducing.as_ref().map(|m| m.as_ref());
            let (model, go_on) = match walked.hyp.as_deref() {
                Some(prev_hyp) if ep >= 2 => {
                    let refit = DynamicsModel::fit(
                        inputs.clone(),
                        targets.clone(),
                        prev_hyp,
                        inducing,
                        &self.dynamics,
                    )?
                    .0;
                    let kept =
                        self.fit_keeping(inputs, targets, prev_hyp, walked.inducing.as_ref())?;
                    let newest = data
                        .last()
                        .ok_or_else(|| LearnError::Spec("replay: an update without data".into()))?;
                    policy.set_params(&policies[ep - 1])?;
                    let every_rule = self.judge_every_rule(&policy, &refit, &kept, newest)?;
                    let replayed =
                        verdict_of(recorded_rule, &every_rule).ok_or(missing(recorded_rule))?;
                    if recorded_rule.compares() {
                        let Some(rec) = recorded_choice else {
                            return bad(format!("update {ep} has no recorded model choice"));
                        };
                        check_scores(ep, &rec, &replayed)?;
                    }
                    let other = verdict_of(self.model_selection, &every_rule)
                        .ok_or(missing(self.model_selection))?;
                    let update = ReplayedUpdate {
                        update: ep,
                        recorded: replayed,
                        other,
                        every_rule,
                    };
                    let go_on = visit(ep, Some(&update));
                    (if replayed.kept_previous { kept } else { refit }, go_on)
                }
                _ => {
                    let init = walked
                        .hyp
                        .clone()
                        .unwrap_or_else(|| initial_hyper(inputs.as_ref(), targets.as_ref()));
                    let (refit, _) =
                        DynamicsModel::fit(inputs, targets, &init, inducing, &self.dynamics)?;
                    (refit, visit(ep, None))
                }
            };
            if !go_on {
                break;
            }
            walked.completed = ep;
            walked.hyp = Some(model.hyp().to_vec());
            if model.is_sparse() {
                walked.inducing = Some(model.inputs().to_owned());
            }
        }
        Ok(walked)
    }
}

/// Are the replayed scores the recorded ones?
fn check_scores(
    ep: usize,
    recorded: &SelectionRecord,
    replayed: &SelectionRecord,
) -> Result<(), LearnError> {
    let close = |a: f64, b: f64| (a - b).abs() <= REPLAY_SCORE_TOLERANCE * a.abs().max(b.abs());
    if close(recorded.refit_score, replayed.refit_score)
        && close(recorded.previous_score, replayed.previous_score)
        && recorded.kept_previous == replayed.kept_previous
    {
        return Ok(());
    }
    Err(LearnError::Spec(format!(
        "replay: update {ep} scores the refit {} and the previous hyper-parameters {} where the \
         run recorded {} and {}: the replay does not rebuild the run's models (other settings \
         or code?)",
        replayed.refit_score,
        replayed.previous_score,
        recorded.refit_score,
        recorded.previous_score
    )))
}
