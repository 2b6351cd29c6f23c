//! The acceptance table of issue 6: every thesis claim of each experiment, one column per seed,
//! and whether enough seeds pass it (each claim's `across_seeds` rule, written by the run).
//! The rule is over seeds 1 to its `seeds` (issue 6: 1–5); runs on further seeds get their
//! columns, marked "not counted", and a separate count beside the verdict's.
//!
//! Only summary.json is read. Claims are matched across runs by their `id` (their text for
//! summaries written before ids existed). The one claim a run cannot decide alone, vil-sic's
//! "mean k_y above the GIC run's", is decided here against a vil-gic run of the same seed, or,
//! when none is given, against every complete vil-gic run.

use crate::data::{Claim, SeedRule, Summary};
use crate::difference::first_difference;
use crate::markdown::{cell, header, row};
use crate::ReportError;
use serde_json::Value;
use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// Id of the vil-sic claim decided here against the same seed's GIC run; the experiments crate
/// gives its claim this id.
pub const SIC_MEAN_K_Y_ABOVE_GIC: &str = "sic_mean_k_y_above_gic";
/// Issue 6's bullets whose parts must all hold on one seed for that seed to count ("... for
/// ≥ 3 of 5 seeds"): the row label and the ids of the parts, as the experiments crate names its
/// claims. The acceptance table adds a row per bundle whose parts it shows.
pub const SAME_SEED_BUNDLES: &[(&str, &[&str])] = &[
    (
        "all four parts above on the same seed (updates 6-10 insert, both means, prediction at 10)",
        &[
            "updates_6_10_insert",
            "mean_return_6_10",
            "mean_return_21_25",
            "prediction_at_10",
        ],
    ),
    (
        "final return <= 90 and the last 5 updates inserting, on the same seed",
        &["sic_final_return", "sic_last_5_insert"],
    ),
    (
        "all three parts above on the same seed (first insertion, 3 consecutive, final <= 25)",
        &[
            "vilta_first_insertion",
            "vilta_three_after_first",
            "vilta_final_return",
        ],
    ),
];
/// Id of vilta's "final gains lowered after insertion", which issue 6 asks to report (the mean
/// gains over the first and last 2 s), not to pass or fail: a run records it with no verdict
/// and no acceptance rule, and the tables show it as reported.
pub const VILTA_GAINS_LOWERED: &str = "vilta_gains_lowered";
/// Claims that are reported, never judged.
pub const REPORTED_ONLY: &[&str] = &[VILTA_GAINS_LOWERED];

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
    /// A claim the issue asks to report, not to judge ([`REPORTED_ONLY`]).
    Reported,
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

    /// One run's verdict on claim `c`: reported for a [`REPORTED_ONLY`] claim, else
    /// [`Self::of_run`].
    pub fn of_claim(c: &Claim) -> Verdict {
        match c.id.as_deref() {
            Some(id) if REPORTED_ONLY.contains(&id) => Verdict::Reported,
            _ => Verdict::of_run(c.pass),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Verdict::Pass => "pass",
            Verdict::Fail => "fail",
            Verdict::Undecided => "undecided",
            Verdict::Reported => "reported",
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
    let rules: Vec<SeedRule> = runs
        .iter()
        .flat_map(|r| r.summary.thesis_reference.iter().flatten())
        .filter_map(|c| c.across_seeds)
        .collect();
    for r in runs {
        let seed = r.summary.seed;
        let beyond = rules
            .iter()
            .find(|rule| !is_acceptance_seed(Some(**rule), seed));
        let note = beyond.map_or(String::new(), |rule| {
            format!(
                " (beyond the acceptance seeds 1–{}: shown, not counted)",
                rule.seeds
            )
        });
        let _ = writeln!(
            h,
            "- seed {seed}: `{}`, {} policy updates{note}",
            display(&r.dir),
            r.summary.episodes.len()
        );
    }
    h.push('\n');
    settings_note(h, runs);
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
    // Each run's (measured, pass) of one claim.
    let of_claim = |r: &RunSummary, key: &str| -> (String, Option<bool>) {
        let claim = r
            .summary
            .thesis_reference
            .iter()
            .flatten()
            .find(|c| claim_key(c) == key);
        match claim {
            None => ("–".to_string(), None),
            Some(_) if key == SIC_MEAN_K_Y_ABOVE_GIC => paired_gic_k_y(&r.summary, all),
            Some(c) => (c.measured.clone(), c.pass),
        }
    };
    let rule_of = |key: &str| {
        runs.iter()
            .flat_map(|r| r.summary.thesis_reference.iter().flatten())
            .find(|c| claim_key(c) == key)
            .and_then(|c| c.across_seeds)
    };
    for (key, first) in &keys {
        if REPORTED_ONLY.contains(key) {
            reported_row(h, runs, &first.claim, |r| of_claim(r, key).0);
        } else {
            seed_row(h, runs, &first.claim, rule_of(key), |r| of_claim(r, key));
        }
    }
    // A bullet of the issue whose parts must hold on the same seed: one row more, so that
    // parts passing on different seeds do not read as the bullet passing.
    for (label, ids) in SAME_SEED_BUNDLES {
        if !ids.iter().all(|id| keys.iter().any(|(k, _)| k == id)) {
            continue;
        }
        seed_row(h, runs, label, rule_of(ids[0]), |r| {
            let parts: Vec<Option<bool>> = ids.iter().map(|id| of_claim(r, id).1).collect();
            let pass = if parts.contains(&Some(false)) {
                Some(false)
            } else if parts.iter().all(|p| *p == Some(true)) {
                Some(true)
            } else {
                None
            };
            let held = parts.iter().filter(|p| **p == Some(true)).count();
            (format!("{held} of {} parts", ids.len()), pass)
        });
    }
    h.push('\n');
}

/// One table row: `label`, the seed rule, each run's measured value and mark (seeds beyond the
/// rule shown but not counted), the passing count and the verdict.
/// A claim that is reported, not judged: each seed's numbers, no count and no verdict.
fn reported_row(
    h: &mut String,
    runs: &[RunSummary],
    label: &str,
    value: impl Fn(&RunSummary) -> String,
) {
    let mut cells = vec![cell(label), "reported only".into()];
    cells.extend(runs.iter().map(|r| cell(&value(r))));
    cells.extend(["–".into(), Verdict::Reported.name().into()]);
    row(h, &cells);
}

fn seed_row(
    h: &mut String,
    runs: &[RunSummary],
    label: &str,
    rule: Option<SeedRule>,
    value: impl Fn(&RunSummary) -> (String, Option<bool>),
) {
    let mut cells = vec![cell(label), rule_text(rule)];
    let (mut passes, mut fails, mut counted) = (0, 0, 0);
    let (mut extra_passes, mut extra) = (0, 0);
    for r in runs {
        let (measured, pass) = value(r);
        let mark = Verdict::of_run(pass).name();
        if is_acceptance_seed(rule, r.summary.seed) {
            counted += 1;
            match pass {
                Some(true) => passes += 1,
                Some(false) => fails += 1,
                None => {}
            }
            cells.push(format!("{} ({mark})", cell(&measured)));
        } else {
            extra += 1;
            extra_passes += u64::from(pass == Some(true));
            cells.push(format!("{} ({mark}, not counted)", cell(&measured)));
        }
    }
    let mut passing = format!("{passes} of {counted}");
    if extra > 0 {
        let _ = write!(passing, "; {extra_passes} of {extra} other seeds");
    }
    cells.push(passing);
    cells.push(rule.map_or("– (rule not recorded)".into(), |rule| {
        verdict(rule, passes, fails).name().into()
    }));
    row(h, &cells);
}

/// Runs pooled under one name should share their settings (the number of updates aside):
/// says where the first run that does not differs from the lowest seed's, so a verdict over
/// a shipped run and a probe's, or a `--quick` one, is not read as one experiment's.
fn settings_note(h: &mut String, runs: &[RunSummary]) {
    let settings = |r: &RunSummary| {
        let mut c = r.summary.config.clone().unwrap_or(Value::Null);
        if let Some(map) = c.as_object_mut() {
            map.remove("episodes");
        }
        c
    };
    let Some((first, rest)) = runs.split_first() else {
        return;
    };
    let base = settings(first);
    let differing = rest
        .iter()
        .find_map(|r| first_difference(&base, &settings(r), String::new()).map(|d| (r, d)));
    if let Some((r, d)) = differing {
        let _ = writeln!(
            h,
            "**These runs differ in their settings**, so the verdicts below pool different \
             experiments: `{}` is {} in seed {} and {} in seed {}.\n",
            d.key, d.recorded, first.summary.seed, d.now, r.summary.seed
        );
    }
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

/// Whether a run of `seed` counts towards `rule`: issue 6 judges its claims on seeds 1 to
/// `rule.seeds`, so a run on another seed is evidence shown beside them, never a vote (seven
/// seeds must not pass a "3 of 5" rule that seeds 1–5 fail). Without a recorded rule every run
/// counts, as before the rules existed.
fn is_acceptance_seed(rule: Option<SeedRule>, seed: u64) -> bool {
    rule.is_none_or(|r| (1..=r.seeds).contains(&seed))
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
mod tests;
