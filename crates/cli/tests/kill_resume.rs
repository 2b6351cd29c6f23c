//! `vicpilco run --resume` after the run was stopped hard, in the middle of a write: nothing
//! the checkpoint covers is lost.
//!
//! The stop is SIGXFSZ from a file-size limit, which ends the process on the spot (no
//! destructor or handler runs) in the middle of the first write that passes the limit,
//! whichever file that is.

#![cfg(unix)]

use std::os::unix::process::ExitStatusExt;
use std::path::Path;
use std::process::{Child, Command, Stdio};

const SEED: &str = "1";
const RECORDS: [&str; 3] = ["rollouts.jsonl", "predictions.jsonl", "policies.jsonl"];

/// `vicpilco`, or with `fsize` (bytes) under that file-size limit: the kernel stops it with
/// SIGXFSZ at its first write past the limit, wherever in a file that falls.
fn vicpilco(fsize: Option<u64>) -> Command {
    let bin = env!("CARGO_BIN_EXE_vicpilco");
    let Some(bytes) = fsize else {
        return Command::new(bin);
    };
    // `ulimit -f` counts 512-byte blocks in a POSIX sh (bash's own mode: 1024, so twice the
    // limit; either way a limit inside the run's writes). No core file for SIGXFSZ.
    let mut cmd = Command::new("sh");
    cmd.arg("-c")
        .arg(format!(
            "ulimit -c 0; ulimit -f {}; exec \"$0\" \"$@\"",
            (bytes / 512).max(1)
        ))
        .arg(bin);
    cmd
}

/// Starts `vicpilco run` in `dir`, its output into `log`.out/.err: a pipe nobody reads could
/// fill and stall the run at a moment of its own rather than the kill's.
fn start(dir: &Path, episodes: usize, resume: bool, log: &Path, fsize: Option<u64>) -> Child {
    let mut cmd = vicpilco(fsize);
    cmd.args(["run", "pendulum", "--seed", SEED, "--episodes"])
        .arg(episodes.to_string())
        .arg("--out")
        .arg(dir);
    if resume {
        cmd.arg("--resume");
    }
    let file = |ext: &str| std::fs::File::create(log.with_extension(ext)).unwrap();
    cmd.stdout(Stdio::from(file("out")))
        .stderr(Stdio::from(file("err")))
        .spawn()
        .expect("vicpilco starts")
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn episodes_of(text: &str, episode: usize) -> usize {
    text.lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .filter(|v| v["episode"].as_u64() == Some(episode as u64))
        .count()
}

/// A resume first trims the records to its checkpoint by writing them anew. Killed during
/// that (by the file-size limit, at the first kilobyte written), it must leave every record
/// the checkpoint covers in place.
#[test]
fn a_resume_killed_while_trimming_the_records_keeps_them() {
    let dir = std::env::temp_dir().join(format!("vicpilco-kill-trim-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let log = std::env::temp_dir().join(format!("vicpilco-kill-trim-{}", std::process::id()));
    let run = |episodes: usize, resume: bool, fsize: Option<u64>| {
        start(&dir, episodes, resume, &log, fsize).wait().unwrap()
    };
    assert!(run(1, false, None).success());
    let before: Vec<String> = RECORDS.iter().map(|f| read(&dir.join(f))).collect();
    let status = run(2, true, Some(1024));
    assert!(
        status.signal().is_some(),
        "not stopped by the limit: {status}"
    );
    for (f, before) in RECORDS.iter().zip(&before) {
        assert!(
            &read(&dir.join(f)) == before,
            "{f} cut short by a resume stopped while rewriting it"
        );
    }
    assert!(run(2, true, None).success());
    let rollouts = read(&dir.join("rollouts.jsonl"));
    let per_update: Vec<usize> = (0..3).map(|e| episodes_of(&rollouts, e)).collect();
    assert_eq!(per_update, [1, 1, 1], "roll-outs per update");
    let _ = std::fs::remove_dir_all(&dir);
    for ext in ["out", "err"] {
        let _ = std::fs::remove_file(log.with_extension(ext));
    }
}
