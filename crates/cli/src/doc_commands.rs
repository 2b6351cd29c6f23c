//! The shell commands the docs give must work with the CLI as built: every `vicpilco …` (or
//! `cargo run --release -- …`) line in a fenced block of the top-level docs parses, names an
//! experiment that exists and, where it names a config file, one that loads; every
//! `--example` named exists. Placeholders (`<name>`, `S`, `N`, `FILE`, …) stand for valid
//! values, and each optional `[a | b]` group is tried absent and with each alternative.

use super::{Cli, Command};
use clap::Parser;
use std::path::{Path, PathBuf};

/// The documents whose shell blocks a newcomer copies from.
const DOCS: &[&str] = &[
    "README.md",
    "EXPERIMENTS.md",
    "BENCHMARKS.md",
    "ARCHITECTURE.md",
    "THESIS.md",
    "probes/README.md",
    "results/README.md",
    "crates/env/README.md",
];

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// One command as written: where, and its words after the program.
#[derive(Debug)]
struct DocCommand {
    place: String,
    words: Vec<String>,
}

/// What a documented line runs.
enum Invocation {
    Cli(Vec<String>),
    Example { name: String },
}

/// The lines of fenced code blocks, continuation lines (`\`) joined, comments dropped.
fn fenced_lines(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut in_block = false;
    let mut pending: Option<(usize, String)> = None;
    for (i, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            in_block = !in_block;
            continue;
        }
        if !in_block {
            continue;
        }
        let code = match line.find(" #") {
            Some(k) => &line[..k],
            None => line,
        };
        let (start, mut joined) = pending.take().unwrap_or((i + 1, String::new()));
        joined.push_str(code.trim());
        match joined.strip_suffix('\\') {
            Some(head) => pending = Some((start, format!("{} ", head.trim_end()))),
            None => out.push((start, joined)),
        }
    }
    out
}

/// The CLI's words, or the example's name, of a line that runs vicpilco.
fn invocation(line: &str) -> Option<Invocation> {
    // Leading `VAR=value` words set the environment, as in `RAYON_NUM_THREADS=1 vicpilco …`.
    let words: Vec<&str> = line
        .split_whitespace()
        .skip_while(|w| w.contains('=') && !w.starts_with('-'))
        .collect();
    let cargo_run = ["cargo", "run", "--release"];
    if words.starts_with(&cargo_run) {
        let rest = &words[cargo_run.len()..];
        if let Some(k) = rest.iter().position(|w| *w == "--example") {
            return Some(Invocation::Example {
                name: rest.get(k + 1)?.to_string(),
            });
        }
        if rest.first() == Some(&"--") {
            return Some(Invocation::Cli(
                rest[1..].iter().map(|w| w.to_string()).collect(),
            ));
        }
        return None;
    }
    let program = words.first()?;
    (*program == "vicpilco" || program.ends_with("/vicpilco"))
        .then(|| Invocation::Cli(words[1..].iter().map(|w| w.to_string()).collect()))
}

/// Every concrete reading of a line with optional groups: each group absent, or present as
/// one of its `|`-separated alternatives.
fn expand_optionals(line: &str) -> Vec<String> {
    let Some(open) = line.find('[') else {
        return vec![line.to_string()];
    };
    let Some(len) = line[open..].find(']') else {
        return vec![line.to_string()];
    };
    let (head, group, tail) = (
        &line[..open],
        &line[open + 1..open + len],
        &line[open + len + 1..],
    );
    let mut readings = vec![String::new()];
    readings.extend(group.split('|').map(|alt| alt.trim().to_string()));
    readings
        .iter()
        .flat_map(|choice| {
            expand_optionals(tail)
                .into_iter()
                .map(move |rest| format!("{head} {choice} {rest}"))
        })
        .collect()
}

/// A placeholder word as a value the CLI accepts.
fn concrete(word: &str) -> String {
    match word {
        "S" | "<S>" => "1".into(),
        "N" => "3".into(),
        "LIST" => "5,10".into(),
        _ => word
            .replace("<name>", "vilta")
            .replace("<experiment>", "vilta")
            .replace("NAME", "vilta"),
    }
}

/// Whether a word is a placeholder rather than a real path.
fn is_placeholder(word: &str) -> bool {
    word.contains('<') || word.chars().all(|c| c.is_ascii_uppercase() || c == '_')
}

fn doc_commands() -> (Vec<DocCommand>, Vec<(String, String)>) {
    let mut commands = Vec::new();
    let mut examples = Vec::new();
    for doc in DOCS {
        let text =
            std::fs::read_to_string(repo_root().join(doc)).unwrap_or_else(|e| panic!("{doc}: {e}"));
        for (line_no, line) in fenced_lines(&text) {
            let place = format!("{doc}:{line_no}");
            match invocation(&line) {
                Some(Invocation::Cli(_)) => {
                    for reading in expand_optionals(&line) {
                        let Some(Invocation::Cli(words)) = invocation(&reading) else {
                            unreachable!("{place}: an optional group hid the program");
                        };
                        commands.push(DocCommand {
                            place: place.clone(),
                            words: words.iter().map(|w| concrete(w)).collect(),
                        });
                    }
                }
                Some(Invocation::Example { name }) => examples.push((place, name)),
                None => {}
            }
        }
    }
    (commands, examples)
}

/// The value after `flag` in `words`.
fn flag_value<'a>(words: &'a [String], flag: &str) -> Option<&'a str> {
    let k = words.iter().position(|w| w == flag)?;
    words.get(k + 1).map(String::as_str)
}

fn check(cmd: &DocCommand) -> Result<(), String> {
    let argv = std::iter::once("vicpilco".to_string()).chain(cmd.words.iter().cloned());
    let cli = Cli::try_parse_from(argv).map_err(|e| e.to_string())?;
    let name = match &cli.command {
        Command::Run(_) | Command::Rescore(_) | Command::Evaluate(_) => cmd.words.get(1),
        _ => None,
    };
    if let Some(name) = name {
        let known = vicpilco_experiments::CLASSIC.contains(&name.as_str())
            || vicpilco_experiments::config::shipped(name).is_some();
        if !known {
            return Err(format!("no experiment named {name}"));
        }
    }
    if let Some(file) = flag_value(&cmd.words, "--config").filter(|f| !is_placeholder(f)) {
        vicpilco_experiments::config::load(&repo_root().join(file)).map_err(|e| e.to_string())?;
    }
    Ok(())
}

#[test]
fn every_documented_command_parses_and_names_what_exists() {
    let (commands, _) = doc_commands();
    let failures: Vec<String> = commands
        .iter()
        .filter_map(|c| {
            check(c)
                .err()
                .map(|e| format!("{}: `{}`: {e}", c.place, c.words.join(" ")))
        })
        .collect();
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
    // The README alone gives the main job, the other commands and three synopses.
    let in_readme = commands
        .iter()
        .filter(|c| c.place.starts_with("README.md:"))
        .count();
    assert!(
        in_readme >= 15,
        "only {in_readme} commands read from README.md"
    );
    for sub in [
        "run",
        "oracle",
        "bench",
        "sim",
        "report",
        "acceptance",
        "rescore",
        "evaluate",
    ] {
        assert!(
            commands
                .iter()
                .any(|c| c.words.first().is_some_and(|w| w == sub)),
            "no documented `vicpilco {sub}` command"
        );
    }
}

/// The README's test command is the one CI runs, word for word.
#[test]
fn the_readme_test_command_is_the_one_ci_runs() {
    let readme = std::fs::read_to_string(repo_root().join("README.md")).unwrap();
    let (_, after) = readme
        .split_once("Run the tests")
        .expect("README.md has a \"Run the tests\" paragraph");
    let command = fenced_lines(after)
        .into_iter()
        .map(|(_, line)| line)
        .next()
        .expect("a command block after \"Run the tests\"");
    assert!(command.starts_with("cargo test"), "{command}");
    let ci = std::fs::read_to_string(repo_root().join(".ci/run")).unwrap();
    assert!(
        ci.lines().any(|l| l.trim() == command),
        ".ci/run does not run the README's test command `{command}`"
    );
}

#[test]
fn every_documented_example_exists() {
    let (_, examples) = doc_commands();
    assert!(!examples.is_empty(), "no `--example` command read");
    let crates = std::fs::read_dir(repo_root().join("crates")).unwrap();
    let sources: Vec<PathBuf> = crates
        .filter_map(|c| c.ok())
        .map(|c| c.path().join("examples"))
        .collect();
    for (place, name) in examples {
        assert!(
            sources
                .iter()
                .any(|dir| dir.join(format!("{name}.rs")).is_file()),
            "{place}: no example named {name}"
        );
    }
}

#[test]
fn the_checks_catch_a_wrong_command() {
    let cases = [
        ("run vil-gic --seed one", "invalid value"),
        ("run vil-gic --frobnicate", "unexpected argument"),
        ("run vil-gci --seed 1", "no experiment named vil-gci"),
        ("run vilta --config experiments/none.toml", "none.toml"),
        (
            "run vilta --resume --replay-from RUN",
            "cannot be used with",
        ),
    ];
    for (line, expected) in cases {
        let cmd = DocCommand {
            place: "test".into(),
            words: line.split_whitespace().map(String::from).collect(),
        };
        let err = check(&cmd).expect_err(line);
        assert!(err.contains(expected), "{line}: {err}");
    }
}

#[test]
fn optional_groups_expand_to_every_reading() {
    let readings: Vec<String> = expand_optionals("run x [--a | --b B] [--c]")
        .iter()
        .map(|r| r.split_whitespace().collect::<Vec<_>>().join(" "))
        .collect();
    assert_eq!(
        readings,
        [
            "run x",
            "run x --c",
            "run x --a",
            "run x --a --c",
            "run x --b B",
            "run x --b B --c"
        ]
    );
    let lines = fenced_lines("text\n```sh\na \\\n  b # note\nc\n```\nvicpilco run x\n");
    assert_eq!(lines, [(3, "a b".to_string()), (5, "c".to_string())]);
}
