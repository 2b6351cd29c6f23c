//! Running one episode on the system, and the per-(episode, purpose) seeds that make each
//! episode reproducible alone.

use crate::data::Rollout;
use crate::LearnError;
use vicpilco_env::Environment;

/// SplitMix64 of (master seed, episode, purpose): independent streams without stored state.
pub fn derive_seed(master: u64, episode: u64, purpose: u64) -> u64 {
    let mut z = master
        ^ episode.wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ purpose.wrapping_mul(0xD1B5_4A32_D192_ED03);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

pub(super) const PURPOSE_START: u64 = 1;
pub(super) const PURPOSE_NOISE: u64 = 2;
pub(super) const PURPOSE_EXPLORE: u64 = 3;
/// Roll-out j ≥ 1 of an update uses purpose `PURPOSE_EXTRA_ROLLOUT + j` for its sub-seed.
pub(super) const PURPOSE_EXTRA_ROLLOUT: u64 = 100;

/// Run one episode on the system with `act(t, observation) → action`, until the horizon or
/// until the system ends it (logged as a warning with the system's reason). Fails with
/// [`LearnError::Env`] when the system refuses a reset or step, or returns an observation or
/// true state that is not `state_dim` finite numbers.
pub fn rollout(
    env: &mut dyn Environment,
    start: &[f64],
    seed: u64,
    mut act: impl FnMut(usize, &[f64]) -> Result<Vec<f64>, LearnError>,
) -> Result<Rollout, LearnError> {
    // A NaN or a state of the wrong length from the system would travel silently into the
    // recorded return, the model selection's scores and the summary, or panic in the cost or
    // the training set after the roll-out; it is the system's error, named where it happened.
    let d = env.state_dim();
    let state = |at: &str, what: &str, v: &[f64]| {
        if v.len() != d {
            return Err(LearnError::Env(format!(
                "{at}: the {what} has {} entries, the system's state_dim is {d}",
                v.len()
            )));
        }
        match v.iter().position(|x| !x.is_finite()) {
            Some(i) => Err(LearnError::Env(format!(
                "{at}: the {what} has a non-finite entry {i} ({})",
                v[i]
            ))),
            None => Ok(()),
        }
    };
    let first = env
        .reset(start, seed)
        .map_err(|e| LearnError::Env(e.to_string()))?;
    state("reset", "observation", &first)?;
    let mut r = Rollout {
        observations: vec![first],
        actions: Vec::new(),
        true_states: vec![start.to_vec()],
        infos: Vec::new(),
        used_for_training: true,
    };
    for t in 0..env.horizon() {
        let a = act(t, r.observations.last().expect("non-empty"))?;
        let step = env
            .step(&a)
            .map_err(|e| LearnError::Env(format!("step {t}: {e}")))?;
        let at = format!("step {t}");
        state(&at, "observation", &step.observation)?;
        // `StepInfo` documents the true state in the observation's layout (a system without
        // a noise-free one copies the observation), and the recorded costs read it.
        state(&at, "true state", &step.info.true_state)?;
        r.actions.push(a);
        r.observations.push(step.observation);
        r.true_states.push(step.info.true_state.clone());
        r.infos.push(step.info);
        if step.done {
            break;
        }
    }
    if let Some(why) = r.infos.last().and_then(|i| i.stopped_early.as_deref()) {
        tracing::warn!(
            steps = r.len(),
            horizon = env.horizon(),
            "the system ended the roll-out early; the steps it did not run pay its last cost: {why}"
        );
    }
    Ok(r)
}
