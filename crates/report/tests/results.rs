//! The runs stored in `results/` (see results/README.md), and those of each probe in
//! `probes/<probe>/` (runs with a changed setting, same layout): each folder's summary must
//! parse, be named after its experiment and seed, and appear in the acceptance table over its
//! group, so that `vicpilco acceptance results/*/` reproduces what EXPERIMENTS.md quotes.

use std::path::PathBuf;
use vicpilco_report::acceptance_markdown;

#[path = "common/stored_runs.rs"]
mod stored_runs;

use stored_runs::{every_run, folders, probe_groups, repo_dir, result_runs};

#[test]
fn every_stored_run_is_named_after_its_experiment_and_seed_and_is_complete() {
    for dir in &every_run() {
        let text = std::fs::read_to_string(dir.join("summary.json"))
            .unwrap_or_else(|e| panic!("{}: {e}", dir.join("summary.json").display()));
        let summary: serde_json::Value = serde_json::from_str(&text)
            .unwrap_or_else(|e| panic!("{}: {e}", dir.join("summary.json").display()));
        let experiment = summary["experiment"].as_str().expect("experiment");
        let seed = summary["seed"].as_u64().expect("seed");
        let name = dir.file_name().unwrap().to_string_lossy();
        assert_eq!(
            name,
            format!("{experiment}-seed{seed}"),
            "{}",
            dir.display()
        );
        // The archive is what lets a later session redraw or resume the run.
        let archive = dir.join("run.tar.xz");
        let bytes =
            std::fs::read(&archive).unwrap_or_else(|e| panic!("{}: {e}", archive.display()));
        assert!(
            bytes.starts_with(&[0xfd, b'7', b'z', b'X', b'Z', 0x00]),
            "{} is not an xz file",
            archive.display()
        );
        assert!(
            dir.join("report.md").is_file(),
            "{} lacks report.md",
            dir.display()
        );
    }
}

/// probes/README.md is where a reader learns what a probe changed and what it found, so a
/// probe folder without its row there cannot be read.
#[test]
fn every_probe_has_a_row_in_the_probes_readme() {
    let readme_path = repo_dir("probes").join("README.md");
    let readme = std::fs::read_to_string(&readme_path)
        .unwrap_or_else(|e| panic!("{}: {e}", readme_path.display()));
    let probes = folders(&repo_dir("probes"));
    assert!(!probes.is_empty(), "probes/ holds no probe");
    for probe in probes {
        let name = probe.file_name().unwrap().to_string_lossy();
        assert!(
            readme.contains(&format!("\n| `{name}` |")),
            "probe {name} has no row in {}",
            readme_path.display()
        );
    }
}

#[test]
fn the_acceptance_table_covers_every_stored_run() {
    let results = result_runs();
    assert!(!results.is_empty(), "results/ holds no stored run");
    for dirs in std::iter::once(results).chain(probe_groups()) {
        covers_every_run(&dirs);
    }
}

fn covers_every_run(dirs: &[PathBuf]) {
    let table = acceptance_markdown(dirs).expect("acceptance table over a group of stored runs");
    for dir in dirs {
        let text = std::fs::read_to_string(dir.join("summary.json")).unwrap();
        let summary: serde_json::Value = serde_json::from_str(&text).unwrap();
        let seed = summary["seed"].as_u64().unwrap();
        let experiment = summary["experiment"].as_str().unwrap();
        let heading = format!("## {experiment}\n");
        let start = table
            .find(&heading)
            .unwrap_or_else(|| panic!("no section for {experiment}"));
        let section = &table[start + heading.len()..];
        let section = &section[..section.find("\n## ").unwrap_or(section.len())];
        assert!(
            section.contains(&format!("- seed {seed}: `")),
            "seed {seed} missing from the {experiment} section"
        );
    }
}

/// A stored `evaluate.jsonl` (results/README.md) must be of the run beside it: one line per
/// update from 0 to the last, each over the final evaluation's number of starts, the evaluated
/// update's line (`final_eval.update`, else the last) repeating the final evaluation's count
/// (when the run got that far); and `evaluate.md` must have a row for each line.
#[test]
fn a_stored_evaluation_covers_every_update_and_repeats_the_final_one() {
    let dirs: Vec<PathBuf> = every_run()
        .into_iter()
        .filter(|d| d.join("evaluate.jsonl").exists())
        .collect();
    for dir in result_runs() {
        let name = dir.file_name().unwrap().to_string_lossy().into_owned();
        assert!(
            !name.starts_with("vilta-var-") || dirs.contains(&dir),
            "{name}: results/README.md promises a stored evaluation of every vilta-var run"
        );
    }
    for dir in &dirs {
        let read = |name: &str| {
            std::fs::read_to_string(dir.join(name))
                .unwrap_or_else(|e| panic!("{}: {e}", dir.join(name).display()))
        };
        let summary: serde_json::Value = serde_json::from_str(&read("summary.json")).unwrap();
        // A run stopped before its last update has no final evaluation yet; its starts are
        // then the config's.
        let final_eval = &summary["final_eval"];
        let starts = final_eval["starts"]
            .as_u64()
            .or_else(|| summary["config"]["vilta"]["evaluation_starts"].as_u64())
            .expect("final_eval.starts or config.vilta.evaluation_starts");
        let lines: Vec<serde_json::Value> = read("evaluate.jsonl")
            .lines()
            .map(|l| serde_json::from_str(l).expect("an evaluate.jsonl line"))
            .collect();
        let updates = summary["episodes"].as_array().expect("episodes").len();
        assert_eq!(
            lines.len(),
            updates + 1,
            "{}: updates 0..={updates}",
            dir.display()
        );
        for (u, line) in lines.iter().enumerate() {
            assert_eq!(line["update"].as_u64(), Some(u as u64), "{}", dir.display());
            assert_eq!(
                line["starts"].as_array().map(|s| s.len() as u64),
                Some(starts),
                "{} update {u}",
                dir.display()
            );
        }
        if !final_eval.is_null() {
            // Summaries before `vilta.final_policy` evaluated the last update's policy.
            let evaluated = final_eval["update"]
                .as_u64()
                .map_or(updates, |u| u as usize);
            assert_eq!(
                lines[evaluated]["successes"],
                final_eval["successes"],
                "{}: update {evaluated} is the final policy",
                dir.display()
            );
        }
        let table = read("evaluate.md");
        assert_eq!(table.lines().count(), 2 + lines.len(), "{}", dir.display());
    }
}
