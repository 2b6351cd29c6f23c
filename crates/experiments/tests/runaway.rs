//! A roll-out the arm ends early (the VILTA reference driven out of reach, as in vilta-var
//! seed 2's fourth iteration) is recorded, costed over the whole horizon, and kept out of the
//! GP's training set only where its last step was cut short.

use vicpilco_experiments::{arm, config};
use vicpilco_learn::data::training_set;
use vicpilco_learn::outer::rollout;

#[test]
fn a_runaway_rollout_pays_its_last_cost_for_the_steps_it_did_not_run() {
    let (file, text) = config::shipped("vilta-var").unwrap();
    let cfg = config::parse(text, file).unwrap();
    let policy = arm::rbf_policy(&cfg, 1).unwrap();
    let (setup, mut env) = arm::setup(&cfg, policy, 1).unwrap();
    let start = [0.5, 0.2, 0.0, 0.0, 0.0, 0.0];
    // Mid-range gains, the reference pulled down at the largest increment every step.
    let down = |_: usize, _: &[f64]| Ok(vec![127.5, 127.5, 0.0, -cfg.policy.delta_max.unwrap()]);
    let r = rollout(&mut env, &start, 3, down).expect("a runaway ends the roll-out, not the run");
    let h = cfg.horizon;
    let n = r.len();
    assert!(n > 1 && n < h, "ran {n} of {h} steps");
    let last = r.infos.last().unwrap();
    assert!(last.stopped_early.is_some(), "{last:?}");
    assert!(r.infos[..n - 1].iter().all(|i| i.stopped_early.is_none()));
    assert!(!arm::inserted(&r));

    let costs = setup.recorded_costs(&r);
    assert_eq!(costs.len(), h);
    assert!(costs.iter().all(|c| c.is_finite()));
    assert!(costs[n..].iter().all(|&c| c == costs[n - 1]));
    let discounted: f64 = costs
        .iter()
        .enumerate()
        .map(|(t, c)| setup.ret.gamma.powi(t as i32 + 1) * c)
        .sum();
    assert!((setup.recorded_return(&r) - discounted).abs() <= 1e-12 * discounted);

    // Every whole step is a training pair; the cut-short one is not.
    let (inputs, targets) = training_set(&setup.spec, &[r], setup.prior_shift.as_deref());
    assert_eq!((inputs.nrows(), targets.nrows()), (n - 1, n - 1));
}
