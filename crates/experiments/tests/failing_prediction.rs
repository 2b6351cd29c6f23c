//! When the policy optimisation cannot even start because the predicted return fails at the
//! current policy, the run's error is the cause the prediction gave (which quantity is not
//! finite, and where), not just that the optimisation failed.

use vicpilco_env::classic::PendulumScenario;

#[test]
fn a_prediction_failing_at_the_start_policy_names_its_cause() {
    let (mut setup, mut env) =
        vicpilco_experiments::classic::setup(PendulumScenario::default(), 1).unwrap();
    setup.episodes = 1;
    // A start covariance with a negative variance passes the loop's checks (sizes and
    // finiteness; telling a covariance from an indefinite matrix is the prediction's
    // business) and fails the first moment-matching step.
    for (_, cov) in &mut setup.prediction_starts {
        cov[(0, 0)] = -1.0;
    }
    let err = setup
        .run(&mut env, &mut ())
        .err()
        .expect("the optimisation cannot start")
        .to_string();
    assert!(
        err.contains("moment-matching input covariance") && err.contains("negative variance"),
        "the error should name the prediction's own failure: {err}"
    );
}
