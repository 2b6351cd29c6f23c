use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;
use vicpilco_learn::record::{EpisodeRecord, LoopObserver, Phase};
use vicpilco_learn::value::ValueOut;

#[derive(clap::Args)]
pub struct Args {
    /// Experiment: pendulum, cartpole, or a thesis run: vil-gic (= vil-gic-rbf10),
    /// vil-gic-lin, vil-gic-rbf25, vil-sic, vilta, vilta-var (settings in experiments/*.toml).
    name: String,
    /// Master seed: the same seed reproduces the run.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Run directory (summary.json, the JSON-lines records, checkpoint, policy, report);
    /// default runs/<name>-seed<S>, or runs/<name>-quick-seed<S> with --quick (a smoke run
    /// then never meets a full run's directory).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Number of policy updates (default: the experiment's).
    #[arg(long)]
    episodes: Option<usize>,
    /// Smoke test: 3 policy updates with 5 line searches each.
    #[arg(long)]
    quick: bool,
    /// Read the thesis run's settings from this TOML file instead of the shipped one. Under a
    /// shipped NAME the file must be a variant of it (same task, controller, policy.kind and
    /// fixed or variable start); any other NAME labels a variant of one's own.
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// Continue the run in DIR from its checkpoint.json (same name, seed and settings; the
    /// number of updates may grow). The continued run equals an uninterrupted one bit for bit.
    #[arg(long)]
    resume: bool,
    /// Start from the recorded run in DIR (same experiment, seed and settings but
    /// gp.model_selection, e.g. a shipped run and a probe's rule): its model fits are replayed,
    /// its updates kept while this run's rule chooses the same models, and the run continues
    /// from the first update where the rules part. Writes to --out, never to DIR.
    #[arg(long, value_name = "DIR", conflicts_with = "resume")]
    replay_from: Option<PathBuf>,
}

/// A progress bar over policy updates showing the phase, the current objective J and ETA.
struct Progress {
    bar: ProgressBar,
    last_j: f64,
    /// Start distributions of the latest prediction: with K > 1 (vilta-var) the record's
    /// predicted return is the first start's, and the line must say so (the report sets the
    /// start nearest the roll-out beside it instead).
    prediction_starts: usize,
}

impl LoopObserver for Progress {
    fn phase(&mut self, episode: usize, phase: Phase) {
        let what = match phase {
            Phase::InitialRollout => "initial roll-out",
            Phase::Train => "train GP",
            Phase::Optimise => "optimise policy",
            Phase::Rollout => "roll-out",
        };
        self.bar
            .set_message(format!("episode {episode}: {what}, J = {:.3}", self.last_j));
    }
    fn objective(&mut self, episode: usize, j: f64) {
        self.last_j = j;
        self.bar
            .set_message(format!("episode {episode}: optimise policy, J = {j:.3}"));
    }
    fn predicted(&mut self, _episode: usize, prediction: &ValueOut) {
        self.prediction_starts = prediction.trajectories.len();
    }
    fn episode_done(&mut self, r: &EpisodeRecord) {
        self.bar.set_position(r.index as u64);
        let outcome = if r.rollouts > 1 {
            format!(
                "{:.0} % of {} roll-outs succeed",
                100.0 * r.success_fraction,
                r.rollouts
            )
        } else if r.success {
            "success".to_string()
        } else {
            "no success".to_string()
        };
        let which_start = match self.prediction_starts {
            k if k > 1 => format!(" (start 1 of {k})"),
            _ => String::new(),
        };
        let line = format!(
            "episode {:>2}: predicted{which_start} {:.2} ± {:.2}, recorded {:.2}, {} (train {:.1} s, {} cold restarts kept, optimise {:.1} s, {} evaluations)",
            r.index,
            r.predicted_return_mean,
            r.predicted_return_std,
            r.recorded_return,
            outcome,
            r.train_s,
            r.cold_restarts,
            r.optimise_s,
            r.evaluations
        );
        // A hidden bar (stderr not a terminal) drops println; the log line must not be lost.
        if self.bar.is_hidden() {
            eprintln!("{line}");
        } else {
            self.bar.println(line);
        }
    }
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let out = args.out.unwrap_or_else(|| {
        PathBuf::from("runs").join(crate::recorded::default_run_name(
            &args.name, args.seed, args.quick,
        ))
    });
    let opts = vicpilco_experiments::RunOptions {
        seed: args.seed,
        out: out.clone(),
        episodes: args.episodes,
        quick: args.quick,
        config: args.config,
        resume: args.resume,
        replay_from: args.replay_from,
    };
    let total = vicpilco_experiments::planned_updates(&args.name, &opts)
        .with_context(|| format!("running `{}`", args.name))?;
    let bar = ProgressBar::new(total as u64);
    bar.set_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} updates, ETA {eta}  {msg}")
            .expect("valid template"),
    );
    if args.resume {
        // Said before the first new update, which may be minutes away. Only for this run's own
        // checkpoint: one that cannot be read, or another run's, is refused next with the reason.
        let canonical = vicpilco_experiments::config::canonical;
        let ours = vicpilco_experiments::record::read_checkpoint_unchecked(&out)
            .ok()
            .filter(|cp| {
                canonical(&cp.experiment) == canonical(&args.name) && cp.seed == args.seed
            });
        if let Some(cp) = ours {
            let done = cp.summary.episodes.len();
            println!("resuming {}: {done} of {total} updates done", out.display());
            bar.set_position(done as u64);
            // The jump from 0 is not progress made in no time.
            bar.reset_eta();
        }
    }
    let mut progress = Progress {
        bar,
        last_j: f64::NAN,
        prediction_starts: 1,
    };
    let summary = vicpilco_experiments::run(&args.name, &opts, &mut progress)
        .with_context(|| format!("running `{}`", args.name))?;
    progress.bar.finish_and_clear();
    println!(
        "{}: seed {}, {} update{}, {}, {:.1} s of interaction, {:.0} s wall; wrote {}",
        summary.experiment,
        summary.seed,
        summary.episodes.len(),
        if summary.episodes.len() == 1 { "" } else { "s" },
        summary
            .solved_at_episode
            .map_or("never solved".to_string(), |e| format!(
                "solved at update {e}"
            )),
        summary.interaction_s,
        summary.wall_s,
        out.join("summary.json").display()
    );
    Ok(())
}
