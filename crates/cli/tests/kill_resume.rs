//! A learning run killed hard at arbitrary moments and continued with `--resume` ends as the
//! uninterrupted run does: the JSON-lines records and policy.json byte for byte, summary.json
//! and checkpoint.json with timings aside. After every kill nothing the last checkpoint covers
//! is missing from the records, `vicpilco report` reads the directory, and the resume is not
//! refused for the lock the killed process held.
//!
//! The long test is slow (an uninterrupted run, then runs killed 20 times in all and resumed:
//! a minute or two), so ignored by default:
//!
//! ```sh
//! cargo test --release -p vicpilco --test kill_resume -- --ignored --nocapture
//! ```
//!
//! `VICPILCO_KILL_SEED` (default 1) draws another set of kill moments and `VICPILCO_KILLS`
//! (default 20) sets how many; each kill is printed with what it interrupted, as the
//! directory shows it.
//!
//! Kills are SIGKILL after a delay, or SIGXFSZ from a file-size limit: a delay rarely lands
//! inside a write (an update writes for some 30 ms of its seconds), the limit stops the
//! process in the middle of the first write that passes it, whichever file that is. Both end
//! the process on the spot, with no destructor or handler run.

#![cfg(unix)]

use serde_json::Value;
use std::os::unix::process::ExitStatusExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::{Duration, Instant, SystemTime};

use rand::rngs::ChaCha8Rng;
use rand::{RngExt, SeedableRng};

/// Few enough updates for one run to take seconds, enough for the records of several updates
/// to be cut short and resumed from.
const UPDATES: usize = 4;
const SEED: &str = "1";
const RECORDS: [&str; 3] = ["rollouts.jsonl", "predictions.jsonl", "policies.jsonl"];
/// The written fields measured in wall-clock time (or holding it, as `sessions` holds each
/// session's start), which no two runs share.
const TIMINGS: [&str; 4] = ["wall_s", "train_s", "optimise_s", "sessions"];

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

fn env_or<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name)
        .ok()
        .map(|v| {
            v.parse()
                .unwrap_or_else(|_| panic!("{name}={v} does not parse"))
        })
        .unwrap_or(default)
}

/// Kill moments, reproducible from one seed.
struct Moments(ChaCha8Rng);

impl Moments {
    fn new(seed: u64) -> Self {
        Moments(ChaCha8Rng::seed_from_u64(seed))
    }
    fn unit(&mut self) -> f64 {
        self.0.random()
    }
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

fn json(path: &Path) -> Value {
    serde_json::from_str(&read(path))
        .unwrap_or_else(|e| panic!("{} is not whole JSON: {e}", path.display()))
}

/// Updates the checkpoint in `dir` covers; `None` without one.
fn completed(dir: &Path) -> Option<usize> {
    let path = dir.join("checkpoint.json");
    path.exists()
        .then(|| json(&path)["state"]["completed"].as_u64().unwrap() as usize)
}

fn without_timings(v: &mut Value) {
    match v {
        Value::Object(map) => {
            for key in TIMINGS {
                map.remove(key);
            }
            map.values_mut().for_each(without_timings);
        }
        Value::Array(items) => items.iter_mut().for_each(without_timings),
        _ => {}
    }
}

fn json_without_timings(path: &Path) -> Value {
    let mut v = json(path);
    without_timings(&mut v);
    v
}

/// Bytes of `text`'s leading lines whose record belongs to an update up to `upto`.
fn covered_len(text: &str, upto: usize) -> usize {
    let mut len = 0;
    for line in text.split_inclusive('\n') {
        let v: Value = serde_json::from_str(line).unwrap();
        if v["episode"].as_u64().unwrap() as usize > upto {
            break;
        }
        len += line.len();
    }
    len
}

fn episodes_of(text: &str, episode: usize) -> usize {
    text.lines()
        .filter_map(|l| serde_json::from_str::<Value>(l).ok())
        .filter(|v| v["episode"].as_u64() == Some(episode as u64))
        .count()
}

fn modified(path: &Path) -> Option<SystemTime> {
    std::fs::metadata(path).and_then(|m| m.modified()).ok()
}

/// A resume first trims the records to its checkpoint by writing them anew. Killed during
/// that (by the file-size limit, at the first kilobyte written), it must leave every record
/// the checkpoint covers in place.
#[test]
fn a_resume_killed_while_trimming_the_records_keeps_them() {
    // Removed when the test ends, however it ends.
    let scratch = tempfile::tempdir().unwrap();
    let (dir, log) = (scratch.path().join("run"), scratch.path().join("log"));
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
}

/// The uninterrupted run, and when (from its start) each checkpoint appeared.
fn reference_run(dir: &Path, logs: &Path) -> (Duration, Vec<Duration>) {
    let t0 = Instant::now();
    let mut child = start(dir, UPDATES, false, &logs.join("reference"), None);
    let mut seen = Vec::new();
    let mut last = None;
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            assert!(status.success(), "the uninterrupted run failed: {status}");
            break;
        }
        let now = modified(&dir.join("checkpoint.json"));
        if now.is_some() && now != last {
            last = now;
            // Renamed into place whole, so never read half-written.
            if seen.len() == completed(dir).unwrap() {
                seen.push(t0.elapsed());
            }
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    assert_eq!(seen.len(), UPDATES + 1, "checkpoints 0..={UPDATES} seen");
    (t0.elapsed(), seen)
}

/// Where in an update's writing `name` comes, to order files written within one tick of the
/// file system's clock (a few milliseconds, in which the report and the checkpoint are written).
fn write_order(name: &str) -> u8 {
    let name = name.trim_end_matches(".tmp");
    match name {
        "predictions.jsonl" => 1,
        "rollouts.jsonl" => 2,
        "summary.json" => 3,
        "report.html" => 5,
        "report.md" => 6,
        "policies.jsonl" => 7,
        "checkpoint.json" => 8,
        "policy.json" => 9,
        _ if name.ends_with(".jsonl") => 0,
        _ => 4,
    }
}

/// What the stopped process was doing, as its directory shows it: the checkpoint and the file
/// it wrote last (of those written after `since`, when it started).
fn landing(dir: &Path, since: SystemTime) -> String {
    let done = completed(dir);
    // The update in progress, 0 for the initial roll-out.
    let next = done.map_or(0, |c| c + 1);
    let newest = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .filter_map(|e| {
            let e = e.ok()?;
            let meta = e.metadata().ok()?;
            let name = e.file_name().to_string_lossy().into_owned();
            Some((meta.modified().ok()?, write_order(&name), name, meta.len()))
        })
        .filter(|(t, _, name, _)| *t > since && name != ".vicpilco.lock")
        .max();
    let Some((_, _, name, len)) = newest else {
        return format!("checkpoint {done:?}, start-up: nothing written yet");
    };
    // Only this process's: a cut an earlier one left stays until a resume trims it.
    let cut = RECORDS.into_iter().find(|f| {
        let text = std::fs::read_to_string(dir.join(f)).unwrap_or_default();
        modified(&dir.join(f)).is_some_and(|t| t > since)
            && !text.is_empty()
            && !text.ends_with('\n')
    });
    let doing = if let Some(f) = cut {
        format!("appending to {f}, its last line cut off")
    } else if name.ends_with(".jsonl.tmp") {
        "trimming the records to the checkpoint".to_string()
    } else if name.ends_with(".jsonl") {
        match (done, episodes_of(&read(&dir.join(&name)), next) > 0) {
            (None, _) => "initial roll-out".to_string(),
            (Some(_), true) => format!("update {next}: {name} appended"),
            (Some(_), false) => format!("training or optimising update {next}, records trimmed"),
        }
    } else if name == "checkpoint.json" && done != Some(UPDATES) {
        format!("training or optimising update {next}")
    } else {
        format!("writing {name}")
    };
    format!("checkpoint {done:?}, {doing}; last written {name} ({len} bytes)")
}

/// What must hold however the run was stopped: every record is the uninterrupted run's (a
/// cut-off last line a beginning of one), none the checkpoint covers is missing, the whole
/// JSON files parse, the summary's updates are the reference's, and `vicpilco report` reads
/// the directory.
fn check_killed(dir: &Path, reference: &Path, logs: &Path) {
    let done = completed(dir);
    for f in RECORDS {
        let got = std::fs::read_to_string(dir.join(f)).unwrap_or_default();
        let want = read(&reference.join(f));
        assert!(
            want.starts_with(&got),
            "{f} after a kill is not the uninterrupted run's records (or a beginning of them)"
        );
        if let Some(c) = done {
            assert!(
                got.len() >= covered_len(&want, c),
                "{f} after a kill lost records of updates up to {c}, which the checkpoint covers"
            );
        }
    }
    let Some(c) = done else {
        return;
    };
    if !dir.join("summary.json").exists() {
        // Written first when update 1 ends: before, there is nothing to report.
        assert_eq!(c, 0, "checkpoint {c} without summary.json");
        return;
    }
    let mut summary = json_without_timings(&dir.join("summary.json"));
    let summarised = summary["episodes"].as_array().unwrap().len();
    assert!(
        summarised == c || summarised == c + 1,
        "summary.json has {summarised} updates, the checkpoint {c}"
    );
    let mut want = json_without_timings(&reference.join("summary.json"));
    let want = want["episodes"].as_array_mut().unwrap();
    want.truncate(summarised);
    assert_eq!(summary["episodes"].take(), Value::Array(want.clone()));
    let out = vicpilco(None)
        .arg("report")
        .arg(dir)
        .stdout(Stdio::null())
        .output()
        .unwrap();
    std::fs::write(logs.join("last-report.err"), &out.stderr).unwrap();
    assert!(
        out.status.success(),
        "vicpilco report fails on a killed run: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The killed process's lock on the directory died with it, though its lock file stays.
fn assert_lock_free(dir: &Path) {
    let path = dir.join(".vicpilco.lock");
    let Ok(file) = std::fs::OpenOptions::new().write(true).open(&path) else {
        return;
    };
    assert!(
        file.try_lock().is_ok(),
        "{} is still locked after its process was killed",
        path.display()
    );
}

/// A run killed before its first checkpoint has nothing to resume: `--resume` must say so, and
/// a fresh run must refuse the directory rather than discard its roll-outs.
fn check_nothing_to_resume(dir: &Path, logs: &Path) {
    let log = logs.join("resume-refused");
    let status = start(dir, UPDATES, true, &log, None).wait().unwrap();
    let err = read(&log.with_extension("err"));
    assert_eq!(status.code(), Some(2), "{err}");
    assert!(
        err.contains("no checkpoint") && err.contains("stopped during its initial roll-out"),
        "{err}"
    );
    if dir.join("rollouts.jsonl").exists() {
        let log = logs.join("fresh-refused");
        let status = start(dir, UPDATES, false, &log, None).wait().unwrap();
        let err = read(&log.with_extension("err"));
        assert_eq!(status.code(), Some(2), "{err}");
        assert!(err.contains("already holds"), "{err}");
    }
}

/// Where a kill is aimed.
#[derive(Clone, Copy, Debug)]
enum Aim {
    /// SIGKILL within the first 20 ms of a fresh run (start-up, the initial roll-out and its
    /// checkpoint take some 10 ms), or the first 0.3 s of a resume, most very early (start-up
    /// and the trimming of the records to its checkpoint take a few).
    Early,
    /// SIGKILL anywhere in what is left of the run, as the uninterrupted one timed it (mostly
    /// training and optimising, where the run spends its time).
    Anywhere,
    /// SIGKILL up to 40 ms after the process next appends a prediction: its roll-out and the
    /// writing that ends an update (rollouts.jsonl, summary.json, the report's plots and
    /// pages, policies.jsonl, checkpoint.json), some 30 ms of the update's seconds.
    Writing,
    /// SIGXFSZ at the first write past a file-size limit between 4 KiB and 2 MiB (spread
    /// evenly in its logarithm): in the middle of a record, a plot, the report page, a
    /// checkpoint or the resume's trimming of the records.
    MidWrite,
}

/// Waits until the moment `aim` (for a `fresh` run or a resume) and `u` in [0, 1) choose, or
/// the process ends first (its exit status).
fn wait_for_moment(
    child: &mut Child,
    dir: &Path,
    (aim, fresh): (Aim, bool),
    u: f64,
    left: Duration,
) -> Option<ExitStatus> {
    let began = Instant::now();
    let mut deadline = match aim {
        Aim::Early if fresh => Some(began + Duration::from_secs_f64(0.02 * u)),
        Aim::Early => Some(began + Duration::from_secs_f64(0.3 * u.powi(4))),
        Aim::Anywhere => Some(began + left.mul_f64(u)),
        Aim::Writing | Aim::MidWrite => None,
    };
    if let Aim::MidWrite = aim {
        return Some(child.wait().unwrap());
    }
    // Taken once start-up has trimmed the records, so that trimming is not taken for a
    // prediction appended.
    let mut before: Option<Option<SystemTime>> = None;
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            return Some(status);
        }
        let now = Instant::now();
        match deadline {
            Some(d) if now >= d => return None,
            Some(d) => std::thread::sleep((d - now).min(Duration::from_millis(2))),
            None => {
                let predictions = modified(&dir.join("predictions.jsonl"));
                match before {
                    None if now >= began + Duration::from_millis(100) => before = Some(predictions),
                    Some(m) if m != predictions => {
                        deadline = Some(now + Duration::from_secs_f64(0.04 * u))
                    }
                    _ => {}
                }
                std::thread::sleep(Duration::from_millis(1));
            }
        }
    }
}

/// One run in `dir` stopped `kills` times (fewer if it ends first), then resumed to its end;
/// returns the kills made and the fresh restarts they forced.
fn killed_run(
    dir: &Path,
    logs: &Path,
    reference: &Path,
    (whole, checkpoints_at): (Duration, &[Duration]),
    moments: &mut Moments,
    kills: usize,
) -> (usize, usize) {
    let mut made = 0;
    let mut restarts = 0;
    for attempt in 1.. {
        let done = completed(dir);
        if done.is_none() && dir.exists() {
            // Stopped during the initial roll-out: nothing to resume, so the test starts the
            // run afresh, as a user told so would.
            check_nothing_to_resume(dir, logs);
            std::fs::remove_dir_all(dir).unwrap();
            restarts += 1;
        }
        let log = logs.join(format!("attempt-{attempt}"));
        let began = Instant::now();
        // On the file system's clock, which may tick coarser than `SystemTime::now`.
        let marker = logs.join("started");
        std::fs::write(&marker, "").unwrap();
        let since = modified(&marker).unwrap();
        if made == kills {
            let mut child = start(dir, UPDATES, done.is_some(), &log, None);
            let status = child.wait().unwrap();
            assert!(
                status.success(),
                "last resume: {}",
                read(&log.with_extension("err"))
            );
            eprintln!(
                "  attempt {attempt}: from checkpoint {done:?}, ran to the end ({:.1} s)",
                began.elapsed().as_secs_f64()
            );
            break;
        }
        // A fresh run is stopped early more often: its initial roll-out is over in milliseconds.
        let early = if done.is_none() { 0.4 } else { 0.2 };
        let aim = match moments.unit() {
            p if p < early => Aim::Early,
            p if p < early + 0.2 => Aim::Writing,
            p if p < early + 0.4 => Aim::MidWrite,
            _ => Aim::Anywhere,
        };
        let u = moments.unit();
        let fsize = matches!(aim, Aim::MidWrite).then(|| (4096.0 * 512f64.powf(u)) as u64);
        let mut child = start(dir, UPDATES, done.is_some(), &log, fsize);
        let left = whole.saturating_sub(done.map_or(Duration::ZERO, |c| checkpoints_at[c]));
        let how = match wait_for_moment(&mut child, dir, (aim, done.is_none()), u, left) {
            Some(status) if status.success() => {
                eprintln!(
                    "  attempt {attempt}: from checkpoint {done:?}, ended by itself before its \
                     kill ({aim:?})"
                );
                break;
            }
            Some(status) => {
                let err = read(&log.with_extension("err"));
                assert!(
                    fsize.is_some() && status.signal().is_some(),
                    "attempt {attempt} failed by itself: {status}\n{err}"
                );
                format!("limit {} KiB", fsize.unwrap() / 1024)
            }
            None => {
                child.kill().unwrap();
                child.wait().unwrap();
                format!("after {:.3} s", began.elapsed().as_secs_f64())
            }
        };
        made += 1;
        eprintln!(
            "  kill {made} ({aim:?}, attempt {attempt}, from checkpoint {done:?}) {how}: {}",
            landing(dir, since)
        );
        assert_lock_free(dir);
        check_killed(dir, reference, logs);
    }
    (made, restarts)
}

/// The killed run's directory holds what the uninterrupted run's does, timings aside.
fn check_same_result(killed: &Path, reference: &Path) {
    for f in RECORDS.into_iter().chain(["policy.json"]) {
        assert!(
            read(&killed.join(f)) == read(&reference.join(f)),
            "{f} differs from the uninterrupted run's"
        );
    }
    for f in ["summary.json", "checkpoint.json"] {
        assert_eq!(
            json_without_timings(&killed.join(f)),
            json_without_timings(&reference.join(f)),
            "{f} differs from the uninterrupted run's, timings aside"
        );
    }
    // Killed sessions whose work was redone are not listed; the rest, from update 1 on, are.
    let sessions: Vec<u64> = json(&killed.join("summary.json"))["sessions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["first_update"].as_u64().unwrap())
        .collect();
    eprintln!("  same result; sessions' first updates: {sessions:?}");
    assert_eq!(sessions.first(), Some(&1));
    assert!(sessions.windows(2).all(|w| w[0] <= w[1]), "{sessions:?}");
    let leftovers: Vec<PathBuf> = std::fs::read_dir(killed)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "tmp"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
    let out = vicpilco(None).arg("report").arg(killed).output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
#[ignore = "a minute or two: an uninterrupted pendulum run, then runs killed 20 times in all \
            and resumed (cargo test --release -p vicpilco --test kill_resume -- --ignored \
            --nocapture)"]
fn a_run_killed_anywhere_resumes_to_the_uninterrupted_result() {
    let kills_wanted: usize = env_or("VICPILCO_KILLS", 20);
    let mut moments = Moments::new(env_or("VICPILCO_KILL_SEED", 1));
    let scratch = tempfile::tempdir().unwrap();
    let base = scratch.path();
    let (reference, logs) = (base.join("full"), base.join("logs"));
    std::fs::create_dir_all(&logs).unwrap();
    let test_start = Instant::now();
    let (whole, checkpoints_at) = reference_run(&reference, &logs);
    eprintln!(
        "uninterrupted: {:.1} s, checkpoints at {:?} s",
        whole.as_secs_f64(),
        checkpoints_at
            .iter()
            .map(|t| (t.as_secs_f64() * 100.0).round() / 100.0)
            .collect::<Vec<_>>()
    );
    // Several runs, each stopped until it has had its share or ends between kills, so that a
    // kill late in one run does not end the test with few kills made.
    let (mut kills, mut restarts) = (0, 0);
    for round in 1.. {
        if kills == kills_wanted {
            break;
        }
        assert!(
            round <= 2 * kills_wanted,
            "runs keep ending before their kills"
        );
        let share = (kills_wanted - kills).min(6);
        eprintln!("run {round}:");
        let dir = base.join(format!("killed-{round}"));
        let run_logs = logs.join(format!("run-{round}"));
        std::fs::create_dir_all(&run_logs).unwrap();
        let (made, fresh) = killed_run(
            &dir,
            &run_logs,
            &reference,
            (whole, &checkpoints_at),
            &mut moments,
            share,
        );
        check_same_result(&dir, &reference);
        kills += made;
        restarts += fresh;
    }
    eprintln!(
        "{kills} kills, {restarts} fresh restarts after a kill before the first checkpoint; \
         {:.1} s in all",
        test_start.elapsed().as_secs_f64()
    );
}
