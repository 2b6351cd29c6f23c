//! The set-up's check against the system before the first reset.

use super::LoopSetup;
use crate::value::check_starts;
use crate::LearnError;
use vicpilco_env::Environment;
use vicpilco_pilco::policy::Policy;

impl<P: Policy + Clone + Sync> LoopSetup<P>
where
    P::Cache: Send,
{
    /// Checks, before anything runs on the system, that the set-up's parts fit each other and
    /// `env`: the step layout against the policy and squashing, the state, action and horizon
    /// against the system's, the prior shift (H rows of D0 finite numbers), the prediction
    /// starts ([`check_starts`]) and the return's costs ([`crate::value::ReturnSpec::check`]).
    /// Without it a mismatch would surface as a panic deep in a prediction, or after a roll-out
    /// had already moved a real robot. Fails with [`LearnError::Spec`] naming the field.
    pub fn check_against(&self, env: &dyn Environment) -> Result<(), LearnError> {
        let bad = |what: &str, detail: String| Err(LearnError::Spec(format!("{what}: {detail}")));
        let d0 = self.spec.state_dim;
        let actions = self.policy.n_outputs();
        if let Some(sq) = &self.squash {
            if sq.n_inputs() != actions {
                return bad(
                    "squash",
                    format!(
                        "{} inputs for a policy with {actions} outputs",
                        sq.n_inputs()
                    ),
                );
            }
        }
        self.spec.validate(
            self.policy.n_inputs(),
            actions,
            self.spec.dyn_inputs.len() + actions,
            d0,
        )?;
        if env.state_dim() != d0 || env.action_dim() != actions {
            return bad(
                "spec.state_dim",
                format!(
                    "{d0} states and {actions} actions, but the system has {} and {}",
                    env.state_dim(),
                    env.action_dim()
                ),
            );
        }
        let h = self.ret.horizon;
        if env.horizon() != h {
            return bad(
                "ret.horizon",
                format!(
                    "{h} steps, but the system's episodes have {}",
                    env.horizon()
                ),
            );
        }
        if let Some(shift) = &self.prior_shift {
            if shift.len() != h {
                return bad(
                    "prior_shift",
                    format!("{} rows for a horizon of {h} (one per step)", shift.len()),
                );
            }
            crate::step::check_prior_rows(shift, d0)?;
        }
        check_starts("prediction_starts", &self.prediction_starts, d0)?;
        self.ret.check(d0, actions)?;
        Ok(())
    }
}
