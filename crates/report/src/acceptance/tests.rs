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
    assert!(
        md.contains("| claim | needs | seed 1 | seed 2 | seed 3 | seed 4 | passing | verdict |")
    );
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

#[test]
fn seeds_beyond_the_rules_are_shown_but_not_counted() {
    let tmp = TempDir::new("acceptance-extra-seeds");
    // Seeds 1, 2 and 4 fail, seed 3 passes; seeds 6-8 pass. Counting every run would give
    // 4 passes and a "3 of 5" pass that the acceptance seeds do not support.
    let dirs: Vec<PathBuf> = [1, 2, 3, 4, 6, 7, 8]
        .into_iter()
        .map(|seed| {
            let pass = !matches!(seed, 1 | 2 | 4);
            let final_return = if pass { 20.0 } else { 90.0 };
            let claims = vec![claim(
                "vilta_final_return",
                "final return <= 25",
                &format!("{final_return:.1}"),
                Some(pass),
                false,
            )];
            write_summary(tmp.path(), &format!("s{seed}"), "vilta", seed, 1.0, claims)
        })
        .collect();
    let md = acceptance_markdown(&dirs).unwrap();
    let row = row_of(&md, "final return <= 25");
    assert_eq!(
        row[2..6],
        ["90.0 (fail)", "90.0 (fail)", "20.0 (pass)", "90.0 (fail)"]
    );
    assert_eq!(row[6..9], ["20.0 (pass, not counted)"; 3]);
    assert_eq!(row[9..], ["1 of 4; 3 of 3 other seeds", "fail"]);
    assert!(md.contains("- seed 3: "), "{md}");
    assert!(!md
        .lines()
        .any(|l| l.starts_with("- seed 3:") && l.contains("not counted")));
    assert!(md.lines().any(|l| l.starts_with("- seed 6:")
        && l.ends_with("(beyond the acceptance seeds 1–5: shown, not counted)")));
}

#[test]
fn runs_pooled_under_one_name_with_other_settings_are_pointed_out() {
    let tmp = TempDir::new("acceptance-settings");
    let run = |seed: u64, episodes: u64, length: u64| {
        let dir = write_summary(tmp.path(), &format!("s{seed}"), "vilta", seed, 1.0, vec![]);
        let file = dir.join("summary.json");
        let mut summary: Value =
            serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
        summary["config"] = json!({"episodes": episodes, "optimiser": {"length": length}});
        std::fs::write(&file, summary.to_string()).unwrap();
        dir
    };
    // The number of updates is not a setting that makes another experiment.
    let same = [run(1, 20, 50), run(2, 25, 50)];
    let md = acceptance_markdown(&same).unwrap();
    assert!(!md.contains("differ in their settings"), "{md}");
    // A --quick run among them is.
    let mixed = [same[0].clone(), same[1].clone(), run(3, 3, 5)];
    let md = acceptance_markdown(&mixed).unwrap();
    assert!(
        md.contains("`optimiser.length` is 50 in seed 1 and 5 in seed 3"),
        "{md}"
    );
}

/// Parts of one bullet that pass on different seeds do not make the bullet pass: its row counts
/// a seed only when every part holds there.
#[test]
fn a_bullets_parts_must_hold_on_the_same_seed() {
    let tmp = TempDir::new("acceptance-bundle");
    let part = |id: &str, pass: Option<bool>| claim(id, id, "x", pass, false);
    // Seeds 1-3 pass the first insertion, seeds 3-5 the final return, seeds 1-5 the three in a
    // row: each part passes on 3 of 5 seeds, the bullet on seed 3 only.
    let dirs: Vec<PathBuf> = (1..=5)
        .map(|seed: u64| {
            let claims = vec![
                part("vilta_first_insertion", Some(seed <= 3)),
                part("vilta_three_after_first", Some(true)),
                part("vilta_final_return", Some(seed >= 3)),
            ];
            write_summary(tmp.path(), &format!("s{seed}"), "vilta", seed, 1.0, claims)
        })
        .collect();
    let md = acceptance_markdown(&dirs).unwrap();
    assert_eq!(
        row_of(&md, "vilta_first_insertion")[7..],
        ["3 of 5", "pass"]
    );
    assert_eq!(row_of(&md, "vilta_final_return")[7..], ["3 of 5", "pass"]);
    let bundle = row_of(&md, SAME_SEED_BUNDLES[2].0);
    assert_eq!(
        bundle[2..7],
        [
            "2 of 3 parts (fail)",
            "2 of 3 parts (fail)",
            "3 of 3 parts (pass)",
            "2 of 3 parts (fail)",
            "2 of 3 parts (fail)"
        ]
    );
    assert_eq!(bundle[7..], ["1 of 5", "fail"]);
    // An undecided part leaves a seed undecided, unless another part already failed there.
    let undecided = [
        write_summary(
            tmp.path(),
            "u1",
            "vilta",
            1,
            1.0,
            vec![
                part("vilta_first_insertion", Some(true)),
                part("vilta_three_after_first", None),
                part("vilta_final_return", Some(true)),
            ],
        ),
        write_summary(
            tmp.path(),
            "u2",
            "vilta",
            2,
            1.0,
            vec![
                part("vilta_first_insertion", Some(false)),
                part("vilta_three_after_first", None),
                part("vilta_final_return", Some(true)),
            ],
        ),
    ];
    let md = acceptance_markdown(&undecided).unwrap();
    let bundle = row_of(&md, SAME_SEED_BUNDLES[2].0);
    assert_eq!(
        bundle[2..4],
        ["2 of 3 parts (undecided)", "1 of 3 parts (fail)"]
    );
    // Without all its parts among the claims, no bundle row.
    assert!(!md.contains(SAME_SEED_BUNDLES[0].0));
}

#[test]
fn a_reported_claim_shows_each_seeds_numbers_and_no_verdict() {
    let tmp = TempDir::new("acceptance-reported");
    let gains = |seed: u64, measured: &str| {
        let mut c = claim(
            VILTA_GAINS_LOWERED,
            "final gains lowered",
            measured,
            None,
            false,
        );
        c["across_seeds"] = Value::Null;
        write_summary(
            tmp.path(),
            &format!("vilta-{seed}"),
            "vilta",
            seed,
            10.0,
            vec![c],
        )
    };
    let dirs = [gains(1, "(60, 150) -> (5, 20) N/m"), gains(2, "n.a.")];
    let md = acceptance_markdown(&dirs).unwrap();
    let row = row_of(&md, "final gains lowered");
    assert_eq!(
        row,
        [
            "final gains lowered",
            "reported only",
            "(60, 150) -> (5, 20) N/m",
            "n.a.",
            "–",
            "reported"
        ]
    );
    assert_eq!(
        Verdict::of_claim(&crate::data::Claim {
            id: Some(VILTA_GAINS_LOWERED.into()),
            claim: "c".into(),
            thesis: "t".into(),
            measured: "m".into(),
            pass: None,
            across_seeds: None,
        }),
        Verdict::Reported
    );
}
