//! The acceptance table of issue 6: every thesis claim of each experiment, one column per seed,
//! and whether enough seeds pass it (each claim's `across_seeds` rule, written by the run).
//!
//! Only summary.json is read. Claims are matched across runs by their `id` (their text for
//! summaries written before ids existed). The one claim a run cannot decide alone, vil-sic's
//! "mean k_y above the GIC run's", is decided here against a vil-gic run of the same seed, or,
//! when none is given, against every complete vil-gic run.

use crate::data::{Claim, SeedRule, Summary};
use crate::markdown::{cell, header, row};
use crate::ReportError;
use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// Id of the vil-sic claim decided here against the same seed's GIC run; the experiments crate
/// gives its claim this id.
pub const SIC_MEAN_K_Y_ABOVE_GIC: &str = "sic_mean_k_y_above_gic";
/// Id of "final return below the initial roll-out's and constant gains'", made by every VIL run
/// and decided once the run has all its planned updates.
pub const FINAL_BELOW_INITIAL: &str = "final_below_initial_and_constant";

struct RunSummary {
    dir: PathBuf,
    summary: Summary,
}

/// The acceptance verdict of one claim over the runs given.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Verdict {
    Pass,
    Fail,
    Undecided,
}

impl Verdict {
    /// One run's verdict on a claim (`pass` as summary.json records it).
    pub fn of_run(pass: Option<bool>) -> Verdict {
        match pass {
            Some(true) => Verdict::Pass,
            Some(false) => Verdict::Fail,
            None => Verdict::Undecided,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Verdict::Pass => "pass",
            Verdict::Fail => "fail",
            Verdict::Undecided => "undecided",
        }
    }
}

/// Accepted once `rule.passing` runs pass; rejected once so many fail that the remaining
/// seeds of `rule.seeds` could no longer reach it.
pub(crate) fn verdict(rule: SeedRule, passes: u64, fails: u64) -> Verdict {
    if passes >= rule.passing {
        Verdict::Pass
    } else if fails > rule.seeds.saturating_sub(rule.passing) {
        Verdict::Fail
    } else {
        Verdict::Undecided
    }
}

/// Markdown: one section per experiment (sorted by name), runs sorted by seed.
pub fn acceptance_markdown(dirs: &[PathBuf]) -> Result<String, ReportError> {
    let mut by_experiment: BTreeMap<String, Vec<RunSummary>> = BTreeMap::new();
    for dir in dirs {
        let summary = Summary::load(dir)?;
        let runs = by_experiment.entry(summary.experiment.clone()).or_default();
        if let Some(other) = runs.iter().find(|r| r.summary.seed == summary.seed) {
            return Err(ReportError::DuplicateSeed {
                experiment: summary.experiment,
                seed: summary.seed,
                first: other.dir.clone(),
                second: dir.clone(),
            });
        }
        runs.push(RunSummary {
            dir: dir.clone(),
            summary,
        });
    }
    let mut h = String::new();
    for runs in by_experiment.values_mut() {
        runs.sort_by_key(|r| r.summary.seed);
    }
    for (experiment, runs) in &by_experiment {
        section(&mut h, experiment, runs, &by_experiment);
    }
    if h.is_empty() {
        h.push_str("No run directories given.\n");
    }
    Ok(h)
}

fn claim_key(c: &Claim) -> &str {
    c.id.as_deref().unwrap_or(&c.claim)
}

fn section(
    h: &mut String,
    experiment: &str,
    runs: &[RunSummary],
    all: &BTreeMap<String, Vec<RunSummary>>,
) {
    let _ = writeln!(h, "## {experiment}\n");
    for r in runs {
        let _ = writeln!(
            h,
            "- seed {}: `{}`, {} policy updates",
            r.summary.seed,
            display(&r.dir),
            r.summary.episodes.len()
        );
    }
    h.push('\n');
    // Claims in the order the runs list them, each once.
    let mut keys: Vec<(&str, &Claim)> = Vec::new();
    for r in runs {
        for c in r.summary.thesis_reference.iter().flatten() {
            if !keys.iter().any(|(k, _)| *k == claim_key(c)) {
                keys.push((claim_key(c), c));
            }
        }
    }
    if keys.is_empty() {
        h.push_str("These runs record no thesis claims (a run writes them when it stops).\n\n");
        return;
    }
    let mut names = vec!["claim".to_string(), "needs".to_string()];
    names.extend(runs.iter().map(|r| format!("seed {}", r.summary.seed)));
    names.extend(["passing".into(), "verdict".into()]);
    header(h, &names.iter().map(String::as_str).collect::<Vec<_>>());
    for (key, first) in keys {
        let rule = runs
            .iter()
            .flat_map(|r| r.summary.thesis_reference.iter().flatten())
            .find(|c| claim_key(c) == key)
            .and_then(|c| c.across_seeds);
        let mut cells = vec![cell(&first.claim), rule_text(rule)];
        let (mut passes, mut fails) = (0, 0);
        for r in runs {
            let claim = r
                .summary
                .thesis_reference
                .iter()
                .flatten()
                .find(|c| claim_key(c) == key);
            let (measured, pass) = match claim {
                None => ("–".to_string(), None),
                Some(_) if key == SIC_MEAN_K_Y_ABOVE_GIC => paired_gic_k_y(&r.summary, all),
                Some(c) => (c.measured.clone(), c.pass),
            };
            match pass {
                Some(true) => passes += 1,
                Some(false) => fails += 1,
                None => {}
            }
            let mark = Verdict::of_run(pass).name();
            cells.push(format!("{} ({mark})", cell(&measured)));
        }
        cells.push(format!("{passes} of {}", runs.len()));
        cells.push(rule.map_or("– (rule not recorded)".into(), |rule| {
            verdict(rule, passes, fails).name().into()
        }));
        row(h, &cells);
    }
    h.push('\n');
}

/// SIC's whole-episode mean k_y against the GIC run of the same seed, decided only when both
/// runs recorded their gains and have all their planned updates: a stopped run's last gains are
/// not its final ones. vil-sic's policy is RBF with N_c = 10, so the GIC run nearest to it in
/// everything but the controller is taken: vil-gic-rbf10 (or its alias), then vil-gic-rbf25,
/// then any other GIC configuration by name.
fn paired_gic_k_y(
    sic: &Summary,
    all: &BTreeMap<String, Vec<RunSummary>>,
) -> (String, Option<bool>) {
    let Some(sic_gains) = sic.final_mean_gains else {
        return ("SIC run has no final_mean_gains".into(), None);
    };
    let nearest_first = ["vil-gic-rbf10", "vil-gic", "vil-gic-rbf25"];
    let mut gic_names: Vec<&String> = all.keys().filter(|k| k.starts_with("vil-gic")).collect();
    gic_names.sort_by_key(|k| {
        let rank = nearest_first.iter().position(|n| n == k);
        (rank.unwrap_or(nearest_first.len()), k.as_str())
    });
    let candidates: Vec<(&String, &Summary, [f64; 2])> = gic_runs(&gic_names, all)
        .filter(|(_, s, _)| s.seed == sic.seed)
        .collect();
    let paired = candidates
        .iter()
        .find(|(_, s, _)| complete(s))
        .or(candidates.first());
    match paired {
        Some((name, gic, gains)) => {
            let text = format!(
                "{:.0} vs {:.0} N/m ({name} seed {})",
                sic_gains[1], gains[1], sic.seed
            );
            let unfinished = [("SIC", sic), ("GIC", *gic)]
                .iter()
                .filter(|(_, s)| !complete(s))
                .map(|(which, s)| format!("{which} run stopped at update {}", s.episodes.len()))
                .collect::<Vec<_>>();
            if unfinished.is_empty() {
                (text, Some(sic_gains[1] > gains[1]))
            } else {
                (format!("{text}; {}", unfinished.join(", ")), None)
            }
        }
        None => against_other_seeds(sic, sic_gains[1], &gic_names, all),
    }
}

/// The GIC runs of `gic_names` (in that order) that recorded their final gains.
fn gic_runs<'a>(
    gic_names: &'a [&'a String],
    all: &'a BTreeMap<String, Vec<RunSummary>>,
) -> impl Iterator<Item = (&'a String, &'a Summary, [f64; 2])> + 'a {
    gic_names.iter().flat_map(move |name| {
        all[*name]
            .iter()
            .filter_map(move |r| r.summary.final_mean_gains.map(|g| (*name, &r.summary, g)))
    })
}

/// Without a GIC run of the SIC run's seed, the SIC run must be above every complete GIC run
/// given (the strictest reading of "the GIC run's" when the seeds do not pair) to pass, and
/// fails only when it is below all of them; in between, or with none complete, it is open.
fn against_other_seeds(
    sic: &Summary,
    sic_k_y: f64,
    gic_names: &[&String],
    all: &BTreeMap<String, Vec<RunSummary>>,
) -> (String, Option<bool>) {
    let no_pair = format!("no vil-gic run of seed {}", sic.seed);
    let others: Vec<(&String, u64, f64)> = gic_runs(gic_names, all)
        .filter(|(_, s, _)| complete(s))
        .map(|(name, s, g)| (name, s.seed, g[1]))
        .collect();
    if others.is_empty() {
        return (format!("{sic_k_y:.0} N/m; {no_pair} given"), None);
    }
    let by_k_y = |a: &&(&String, u64, f64), b: &&(&String, u64, f64)| a.2.total_cmp(&b.2);
    let highest = others.iter().max_by(by_k_y).expect("not empty");
    let lowest = others.iter().min_by(by_k_y).expect("not empty");
    let pass = if sic_k_y > highest.2 {
        Some(true)
    } else if sic_k_y <= lowest.2 {
        Some(false)
    } else {
        None
    };
    let text = format!(
        "{sic_k_y:.0} N/m; {no_pair}, the {} complete ones: {:.0} ({} seed {}) to {:.0} ({} seed {})",
        others.len(),
        lowest.2,
        lowest.0,
        lowest.1,
        highest.2,
        highest.0,
        highest.1
    );
    (text, pass)
}

/// Whether a VIL run has all its planned updates: its "final return below the initial" claim,
/// which every VIL run makes, is decided only then.
fn complete(s: &Summary) -> bool {
    s.thesis_reference
        .iter()
        .flatten()
        .any(|c| claim_key(c) == FINAL_BELOW_INITIAL && c.pass.is_some())
}

/// "3 of 5 seeds", "every run (5 seeds)", or a dash for summaries that predate the rules.
pub(crate) fn rule_text(rule: Option<SeedRule>) -> String {
    match rule {
        Some(r) if r.passing == r.seeds => format!("every run ({} seeds)", r.seeds),
        Some(r) => format!("{} of {} seeds", r.passing, r.seeds),
        None => "–".into(),
    }
}

fn display(p: &Path) -> String {
    p.display().to_string().replace('`', "'")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synthetic::TempDir;
    use serde_json::{json, Value};

    const THREE_OF_FIVE: SeedRule = SeedRule {
        passing: 3,
        seeds: 5,
    };
    const EVERY_RUN: SeedRule = SeedRule {
        passing: 5,
        seeds: 5,
    };

    #[test]
    fn verdicts_follow_the_seed_rules() {
        assert_eq!(verdict(THREE_OF_FIVE, 3, 0), Verdict::Pass);
        assert_eq!(verdict(THREE_OF_FIVE, 3, 2), Verdict::Pass);
        assert_eq!(verdict(THREE_OF_FIVE, 2, 2), Verdict::Undecided);
        assert_eq!(verdict(THREE_OF_FIVE, 2, 3), Verdict::Fail);
        assert_eq!(verdict(THREE_OF_FIVE, 0, 0), Verdict::Undecided);
        assert_eq!(verdict(EVERY_RUN, 4, 0), Verdict::Undecided);
        assert_eq!(verdict(EVERY_RUN, 4, 1), Verdict::Fail);
        assert_eq!(verdict(EVERY_RUN, 5, 0), Verdict::Pass);
    }

    fn claim(id: &str, text: &str, measured: &str, pass: Option<bool>, every: bool) -> Value {
        let seeds = 5;
        let passing = if every { 5 } else { 3 };
        json!({"id": id, "claim": text, "thesis": "t", "measured": measured, "pass": pass,
               "across_seeds": {"passing": passing, "seeds": seeds}})
    }

    fn write_summary(
        root: &Path,
        name: &str,
        experiment: &str,
        seed: u64,
        k_y: f64,
        claims: Vec<Value>,
    ) -> PathBuf {
        let dir = root.join(name);
        std::fs::create_dir_all(&dir).unwrap();
        let summary = json!({"experiment": experiment, "seed": seed, "episodes": [],
                             "final_mean_gains": [150.0, k_y], "thesis_reference": claims});
        std::fs::write(dir.join("summary.json"), summary.to_string()).unwrap();
        dir
    }

    fn sic_claims(final_return: f64) -> Vec<Value> {
        vec![
            claim(
                "sic_final_return",
                "final return <= 90",
                &format!("{final_return:.1}"),
                Some(final_return <= 90.0),
                false,
            ),
            claim(
                SIC_MEAN_K_Y_ABOVE_GIC,
                "mean k_y above GIC's",
                "n/a",
                None,
                false,
            ),
            finished(true),
        ]
    }

    /// The every-VIL-run claim, decided (`done`) only once a run has all its planned updates.
    fn finished(done: bool) -> Value {
        let pass = done.then_some(true);
        claim(FINAL_BELOW_INITIAL, "final below initial", "x", pass, true)
    }

    /// The table row whose first cell is `claim`, split into its cells.
    fn row_of(md: &str, claim: &str) -> Vec<String> {
        let line = md
            .lines()
            .find(|l| l.starts_with(&format!("| {claim} |")))
            .unwrap_or_else(|| panic!("no row {claim} in\n{md}"));
        line.trim_matches('|')
            .split(" | ")
            .map(|c| c.trim().to_string())
            .collect()
    }

    #[test]
    fn table_counts_seeds_and_pairs_sic_with_the_same_seeds_gic_run() {
        let tmp = TempDir::new("acceptance");
        let root = tmp.path();
        let dirs = vec![
            write_summary(root, "sic3", "vil-sic", 3, 240.0, sic_claims(95.0)),
            write_summary(root, "sic1", "vil-sic", 1, 270.0, sic_claims(72.5)),
            write_summary(root, "sic2", "vil-sic", 2, 120.0, sic_claims(80.0)),
            write_summary(root, "sic4", "vil-sic", 4, 240.0, sic_claims(70.0)),
            // Seed 1 has two GIC runs: rbf10 is the comparison, not rbf25.
            write_summary(
                root,
                "rbf25-1",
                "vil-gic-rbf25",
                1,
                300.0,
                vec![finished(true)],
            ),
            write_summary(
                root,
                "rbf10-1",
                "vil-gic-rbf10",
                1,
                200.0,
                vec![finished(true)],
            ),
            write_summary(
                root,
                "rbf25-2",
                "vil-gic-rbf25",
                2,
                130.0,
                vec![finished(true)],
            ),
            // Seed 2 also has a linear-policy GIC run: RBF N_c = 25 is nearer to SIC's policy.
            write_summary(root, "lin-2", "vil-gic-lin", 2, 50.0, vec![finished(true)]),
            // A run from before the claims were recorded.
            write_summary(root, "lin-1", "vil-gic-lin", 1, 50.0, vec![]),
            // Seed 4's GIC run was stopped early: its last gains are not its final ones.
            write_summary(
                root,
                "rbf10-4",
                "vil-gic-rbf10",
                4,
                100.0,
                vec![finished(false)],
            ),
        ];
        let md = acceptance_markdown(&dirs).unwrap();
        assert!(md.contains("## vil-sic"), "{md}");
        assert!(md
            .contains("| claim | needs | seed 1 | seed 2 | seed 3 | seed 4 | passing | verdict |"));
        assert_eq!(
            row_of(&md, "final return <= 90"),
            [
                "final return <= 90",
                "3 of 5 seeds",
                "72.5 (pass)",
                "80.0 (pass)",
                "95.0 (fail)",
                "70.0 (pass)",
                "3 of 4",
                "pass"
            ]
        );
        assert_eq!(
            row_of(&md, "mean k_y above GIC's"),
            [
                "mean k_y above GIC's",
                "3 of 5 seeds",
                "270 vs 200 N/m (vil-gic-rbf10 seed 1) (pass)",
                "120 vs 130 N/m (vil-gic-rbf25 seed 2) (fail)",
                "240 N/m; no vil-gic run of seed 3, the 4 complete ones: 50 (vil-gic-lin seed 2) to 300 (vil-gic-rbf25 seed 1) (undecided)",
                "240 vs 100 N/m (vil-gic-rbf10 seed 4); GIC run stopped at update 0 (undecided)",
                "1 of 4",
                "undecided"
            ]
        );
        let sic_section = &md[md.find("## vil-sic").unwrap()..];
        let every = row_of(sic_section, "final below initial");
        assert_eq!(every[1], "every run (5 seeds)");
        assert_eq!(every[6..], ["4 of 4", "undecided"]);
        // The stopped GIC run counts as neither pass nor fail.
        let gic = row_of(
            &md[md.find("## vil-gic-rbf10").unwrap()..],
            "final below initial",
        );
        assert_eq!(
            gic[2..],
            ["x (pass)", "x (undecided)", "1 of 2", "undecided"]
        );
    }

    #[test]
    fn without_its_seeds_gic_run_sic_must_beat_every_complete_one() {
        let tmp = TempDir::new("acceptance-unpaired");
        let root = tmp.path();
        let gic = |name: &str, seed: u64, k_y: f64, done: bool| {
            write_summary(root, name, "vil-gic-rbf10", seed, k_y, vec![finished(done)])
        };
        let dirs = vec![
            write_summary(root, "sic1", "vil-sic", 1, 185.0, sic_claims(60.0)),
            write_summary(root, "sic2", "vil-sic", 2, 50.0, sic_claims(60.0)),
            write_summary(root, "sic3", "vil-sic", 3, 5.0, sic_claims(60.0)),
            gic("gic4", 4, 132.5, true),
            gic("gic5", 5, 7.1, true),
            // A stopped run's gains are not its final ones: not a comparison.
            gic("gic6", 6, 400.0, false),
        ];
        let md = acceptance_markdown(&dirs).unwrap();
        let cells = row_of(&md, "mean k_y above GIC's");
        let range = "the 2 complete ones: 7 (vil-gic-rbf10 seed 5) to 132 (vil-gic-rbf10 seed 4)";
        assert_eq!(
            cells[2..],
            [
                format!("185 N/m; no vil-gic run of seed 1, {range} (pass)"),
                format!("50 N/m; no vil-gic run of seed 2, {range} (undecided)"),
                format!("5 N/m; no vil-gic run of seed 3, {range} (fail)"),
                "1 of 3".to_string(),
                "undecided".to_string(),
            ]
        );
    }

    #[test]
    fn an_impossible_seed_rule_is_an_error_naming_the_field() {
        let tmp = TempDir::new("acceptance-rule");
        let mut bad = claim("x", "x", "1", Some(true), false);
        bad["across_seeds"]["passing"] = json!(6);
        let dir = write_summary(tmp.path(), "a", "vil-sic", 1, 1.0, vec![bad]);
        let err = acceptance_markdown(&[dir]).unwrap_err();
        assert!(matches!(err, ReportError::Malformed { .. }), "{err}");
        assert!(err.to_string().contains("across_seeds"), "{err}");
    }

    #[test]
    fn two_runs_of_one_seed_are_refused() {
        let tmp = TempDir::new("acceptance-dup");
        let a = write_summary(tmp.path(), "a", "vil-sic", 1, 1.0, vec![]);
        let b = write_summary(tmp.path(), "b", "vil-sic", 1, 1.0, vec![]);
        let err = acceptance_markdown(&[a, b]).unwrap_err();
        assert!(
            matches!(err, ReportError::DuplicateSeed { seed: 1, .. }),
            "{err}"
        );
        assert!(err.to_string().contains("vil-sic seed 1"), "{err}");
    }

    #[test]
    fn old_summaries_match_by_text_and_leave_the_verdict_open() {
        let tmp = TempDir::new("acceptance-old");
        let old = vec![
            json!({"claim": "every roll-out of updates 6-10 inserts", "thesis": "t",
                              "measured": "5/5", "pass": true}),
        ];
        let dirs: Vec<PathBuf> = (1..=3)
            .map(|s| {
                write_summary(
                    tmp.path(),
                    &format!("r{s}"),
                    "vil-gic-rbf10",
                    s,
                    1.0,
                    old.clone(),
                )
            })
            .collect();
        let md = acceptance_markdown(&dirs).unwrap();
        let row = row_of(&md, "every roll-out of updates 6-10 inserts");
        assert_eq!(row[1], "–");
        assert_eq!(row[5..], ["3 of 3", "– (rule not recorded)"]);
    }
}
