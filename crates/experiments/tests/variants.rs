//! `vicpilco run NAME --config FILE`: NAME decides which thesis claims judge the run and which
//! runs `acceptance` pools with it, so under a shipped experiment's name the file must be a
//! variant of that experiment; any other name labels a variant of one's own.

use std::path::PathBuf;
use vicpilco_experiments::{planned_updates, ExperimentError, RunOptions};

fn shipped_file(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("../../experiments/{name}.toml"))
}

fn with_config(name: &str, file: &str) -> Result<usize, ExperimentError> {
    let opts = RunOptions {
        config: Some(shipped_file(file)),
        ..Default::default()
    };
    planned_updates(name, &opts)
}

#[test]
fn a_config_runs_under_the_name_of_the_experiment_it_varies_or_a_name_of_its_own() {
    // Same task, law, policy family and kind of start: a variant.
    assert_eq!(with_config("vil-gic", "vil-gic-rbf25").unwrap(), 25);
    assert_eq!(with_config("vilta", "vilta").unwrap(), 20);
    // A name of one's own labels anything.
    assert_eq!(with_config("my-vilta", "vilta").unwrap(), 20);

    for (name, file, key) in [
        ("vilta", "vil-gic-rbf10", "`task`"),
        ("vil-sic", "vil-gic-rbf10", "`controller`"),
        ("vil-gic-lin", "vil-gic-rbf10", "`policy.kind`"),
        ("vilta-var", "vilta", "`start.y_range`"),
        ("vilta", "vilta-var", "`start.y_range`"),
    ] {
        let err = with_config(name, file).unwrap_err().to_string();
        assert!(
            err.contains(&format!("{file}.toml: {key}"))
                && err.contains(&format!("not a variant of `{name}`")),
            "{name} with {file}: {err}"
        );
    }
    // The classic swing-ups are built in code: an arm config under their name is refused.
    for name in ["pendulum", "cartpole"] {
        let err = with_config(name, "vil-gic-rbf10").unwrap_err();
        assert!(
            matches!(
                &err,
                ExperimentError::NotArm {
                    what: "--config",
                    ..
                }
            ),
            "{err}"
        );
    }
}
