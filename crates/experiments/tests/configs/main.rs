//! The shipped configs (`experiments/*.toml`): every file parses, is shipped, and its key
//! numbers are the thesis's (issue 6's tables); bad keys and values are errors naming them.

mod options;

use vicpilco_env::arm::ControllerKind;
use vicpilco_experiments::arm;
use vicpilco_experiments::config::{self, ArmExperiment, PolicyKind, PriorMean, Task, CONFIGS};
use vicpilco_learn::selection::ModelSelection;

fn shipped(name: &str) -> ArmExperiment {
    let (file, text) = config::shipped(name).unwrap_or_else(|| panic!("{name} not shipped"));
    config::parse(text, file).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn every_toml_in_the_experiments_directory_is_shipped_and_parses() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../experiments");
    let mut on_disk: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| {
            let p = e.unwrap().path();
            (p.extension()? == "toml").then(|| p.file_stem().unwrap().to_string_lossy().into())
        })
        .collect();
    on_disk.sort();
    let mut names: Vec<String> = CONFIGS.iter().map(|(n, _)| n.to_string()).collect();
    names.sort();
    assert_eq!(on_disk, names);
    for name in &names {
        let from_file = config::load(&dir.join(format!("{name}.toml"))).unwrap();
        assert_eq!(from_file, shipped(name), "{name}");
    }
    assert_eq!(shipped("vil-gic"), shipped("vil-gic-rbf10"));
}

/// Each probe (`probes/<probe>/<experiment>.toml`, see probes/README.md) is a shipped config
/// with settings changed: it must still load under the current keys and rules, and be named
/// after the experiment it changes, so `vicpilco run <experiment> --config` can take it.
#[test]
fn every_probe_config_loads_and_is_named_after_a_shipped_experiment() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../probes");
    let mut probes = 0;
    for probe in std::fs::read_dir(&dir).unwrap() {
        let probe = probe.unwrap().path();
        if !probe.is_dir() {
            continue;
        }
        for file in std::fs::read_dir(&probe).unwrap() {
            let file = file.unwrap().path();
            if file.extension().is_none_or(|e| e != "toml") {
                continue;
            }
            let stem = file.file_stem().unwrap().to_string_lossy();
            let base = shipped(&stem);
            let changed = config::load(&file).unwrap_or_else(|e| panic!("{e}"));
            changed
                .check_variant_of(&stem, &base, &file.display().to_string())
                .unwrap_or_else(|e| panic!("{e}"));
            assert_ne!(changed, base, "{} changes nothing", file.display());
            probes += 1;
        }
    }
    assert!(probes > 0, "no probe config under {}", dir.display());
}

/// The VIL table (issue 6, item 2).
fn assert_vil_common(c: &ArmExperiment) {
    assert_eq!(c.task, Task::Vil);
    assert_eq!((c.horizon, c.dt, c.episodes), (100, 0.1, 25));
    assert!(c.gp.time_input);
    assert_eq!(c.gp.prior_mean, PriorMean::Reference);
    assert_eq!(
        (c.gp.sparse_threshold, c.gp.n_inducing, c.gp.line_searches),
        (300, 300, 300)
    );
    assert!(c.gp.cold_restart);
    assert_eq!(c.gp.hyper_points, 300);
    assert_eq!(c.policy.k_min, 5.0);
    assert_eq!(c.cost.position_dims, ["x", "y"]);
    assert_eq!(c.cost.position_target, [0.75, 0.20]);
    assert_eq!((c.cost.position_width, c.cost.force_width), (0.05, 20.0));
    assert_eq!((c.cost.w_std, c.cost.w_energy), (-0.25, 0.01));
    assert_eq!((c.optimiser.length, c.optimiser.mfepls), (50, 25));
    assert_eq!(c.start.state, [0.5, 0.0, 0.0, 0.0, 0.0, 0.0]);
    assert_eq!(
        c.start.prediction_std,
        [0.002, 0.002, 0.005, 0.005, 0.1, 0.1]
    );
    assert!(c.vilta.is_none() && c.initial.scan.is_none());
}

#[test]
fn vil_configs_match_the_thesis_tables() {
    let lin = shipped("vil-gic-lin");
    assert_vil_common(&lin);
    assert_eq!(
        (lin.policy.kind, lin.controller, lin.policy.k_max),
        (PolicyKind::Linear, ControllerKind::Gic, 250.0)
    );
    assert_eq!(lin.n_params(), 10);
    for (name, n_c, n_psi) in [("vil-gic-rbf10", 10, 68), ("vil-gic-rbf25", 25, 158)] {
        let c = shipped(name);
        assert_vil_common(&c);
        assert_eq!(
            (c.policy.kind, c.controller),
            (PolicyKind::Rbf, ControllerKind::Gic)
        );
        assert_eq!((c.policy.n_basis, c.policy.k_max), (Some(n_c), 250.0));
        assert_eq!(c.policy.snr, Some(100.0));
        assert_eq!(c.n_params(), n_psi, "{name}");
    }
    let sic = shipped("vil-sic");
    assert_vil_common(&sic);
    assert_eq!(sic.controller, ControllerKind::Sic);
    assert_eq!((sic.policy.n_basis, sic.policy.k_max), (Some(10), 500.0));
}

#[test]
fn vilta_configs_match_the_thesis_tables() {
    let v = shipped("vilta");
    assert_eq!(v.task, Task::Vilta);
    assert!(!v.gp.time_input);
    assert_eq!(v.gp.prior_mean, PriorMean::Zero);
    assert_eq!(v.gp.n_inducing, 300);
    assert_eq!((v.gp.hyper_points, v.gp.cold_restart), (300, true));
    assert_eq!((v.policy.n_basis, v.n_params()), (Some(50), 416));
    assert_eq!(
        (v.policy.k_min, v.policy.k_max, v.policy.delta_max),
        (5.0, 250.0, Some(0.0025))
    );
    assert_eq!(v.cost.position_dims, ["x"]);
    assert_eq!(v.cost.position_target, [0.80]);
    assert_eq!((v.cost.position_width, v.cost.force_width), (0.05, 20.0));
    assert_eq!((v.cost.w_std, v.cost.w_energy), (-0.25, 0.01));
    assert_eq!((v.optimiser.length, v.optimiser.mfepls), (50, 25));
    assert_eq!(v.episodes, 20);
    let vt = v.vilta.as_ref().unwrap();
    assert_eq!((vt.geometry_shift_x, vt.delta_tick), (0.05, 0.005));
    assert_eq!((vt.rollouts_per_iteration, vt.evaluation_starts), (1, 0));
    assert_eq!(
        v.initial.scan.as_deref().unwrap(),
        [[0.0, 0.5, 0.0], [3.0, 0.75, 0.10], [10.0, 0.75, 0.30]]
    );

    let var = shipped("vilta-var");
    assert_eq!((var.policy.n_basis, var.n_params()), (Some(75), 616));
    assert_eq!(var.start.y_range, Some([0.1, 0.3]));
    assert_eq!(var.start.prediction_y.as_deref().unwrap(), [0.1, 0.2, 0.3]);
    let vt = var.vilta.as_ref().unwrap();
    assert_eq!((vt.rollouts_per_iteration, vt.evaluation_starts), (4, 20));
    assert_eq!(var.episodes, 15);
}

/// A shipped config's text with `line` begun on a new line right after `anchor` (a comment
/// that followed `anchor` on its line then follows `line`).
fn with_line_after(text: &str, anchor: &str, line: &str) -> String {
    assert!(text.contains(anchor), "no {anchor:?} in the config");
    text.replace(anchor, &format!("{anchor}\n{line}"))
}

/// The shipped `vilta.toml` with `line` added to its `[vilta]` table.
fn vilta_with_vilta_line(line: &str) -> String {
    with_line_after(
        config::shipped("vilta").unwrap().1,
        "rollouts_per_iteration = 1",
        line,
    )
}

fn error_of(text: &str) -> String {
    config::parse(text, "test.toml").unwrap_err().to_string()
}

#[test]
fn unknown_keys_are_errors_naming_the_key_and_file() {
    let text = config::shipped("vil-gic").unwrap().1;
    let e = error_of(&text.replace("mfepls = 25", "mfepls = 25\nmfpels = 3"));
    assert!(e.contains("test.toml") && e.contains("mfpels"), "{e}");
    let e = error_of(&format!("{text}\n[extra]\nx = 1\n"));
    assert!(e.contains("extra"), "{e}");
}

#[test]
fn out_of_range_values_are_errors_naming_the_key() {
    let text = config::shipped("vil-gic").unwrap().1;
    for (from, to, key) in [
        ("k_min = 5.0", "k_min = 300.0", "policy.k_min"),
        (
            "position_width = 0.05",
            "position_width = -1.0",
            "cost.position_width",
        ),
        ("length = 50", "length = 0", "optimiser.length"),
        ("n_basis = 10", "n_basis = 0", "policy.n_basis"),
        ("horizon = 100", "horizon = 0", "horizon"),
        (
            "position_target = [0.75, 0.20]",
            "position_target = [0.75]",
            "cost.position_target",
        ),
        ("w_energy = 0.01", "w_energy = -0.01", "cost.w_energy"),
        // Sizes that would make the run allocate without bound or never end.
        (
            "horizon = 100",
            "horizon = 1000000000",
            "`horizon` must be ≤",
        ),
        (
            "n_basis = 10",
            "n_basis = 100000000",
            "`policy.n_basis` must be ≤",
        ),
        (
            "memory = 10",
            "memory = 1000000000000",
            "`optimiser.memory` must be ≤",
        ),
        // The simulator's rule, named by this file's key (the simulator calls it step_dt).
        (
            "dt = 0.1",
            "dt = 0.0123",
            "`dt` must be a whole number of control periods",
        ),
    ] {
        assert!(text.contains(from), "{from}");
        let e = error_of(&text.replace(from, to));
        assert!(e.contains(key), "{to}: {e}");
    }
    let vilta = config::shipped("vilta").unwrap().1;
    let e = error_of(&vilta.replace("prior_mean = \"zero\"", "prior_mean = \"reference\""));
    assert!(e.contains("gp.prior_mean"), "{e}");
    let e = error_of(&vilta.replace("delta_max = 0.0025 ", "# "));
    assert!(e.contains("policy.delta_max"), "{e}");
}
