//! `vicpilco sim`: parses the arguments and hands them to `vicpilco_env::arm::run`.

use anyhow::Context;
use std::path::PathBuf;
use std::process::ExitCode;
use vicpilco_env::arm::run::{run_to_dir, SimOptions, StiffnessSource};
use vicpilco_env::arm::ControllerKind;
use vicpilco_env::EnvError;

#[derive(clap::Args)]
pub struct Args {
    /// Impedance law: gic (general, model-based, uses the F/T sensor), sic (simple,
    /// transposed-Jacobian spring-damper) or off (no torque: the arm coasts).
    #[arg(long, value_parser = parse_controller)]
    controller: ControllerKind,
    /// Stiffness per 0.1 s step: const:KX,KY (N/m), ou:SEED (Ornstein–Uhlenbeck profiles in
    /// [5, 250] N/m), or a CSV file with one k_x,k_y row per step (100 rows).
    #[arg(long, value_parser = parse_stiffness)]
    stiffness: StiffnessSource,
    /// Seed of the sensor noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Control rate in Hz (the thesis used 200; 1000 is the default, see crates/env/README.md):
    /// a whole number of control periods per 0.1 s learning step, at most 1/h = 10 kHz.
    #[arg(long, default_value_t = 1000.0, value_parser = parse_control_hz, allow_negative_numbers = true)]
    control_hz: f64,
    /// Switch the sensor noise off.
    #[arg(long)]
    no_noise: bool,
    /// Switch the 15 % plant/model inertia mismatch off.
    #[arg(long)]
    no_mismatch: bool,
    /// Output folder (created if missing).
    #[arg(long)]
    out: PathBuf,
}

fn parse_controller(s: &str) -> Result<ControllerKind, String> {
    s.parse().map_err(|e: vicpilco_env::EnvError| e.to_string())
}

fn parse_stiffness(s: &str) -> Result<StiffnessSource, String> {
    s.parse().map_err(|e: vicpilco_env::EnvError| e.to_string())
}

/// The rate as the simulator's own check judges it, with the fixed settings it trips over
/// (the learning step and the RK4 step, which `sim` does not expose) spelt out.
fn parse_control_hz(s: &str) -> Result<f64, String> {
    let hz: f64 = s
        .parse()
        .map_err(|_| format!("{s:?} is not a number of Hz"))?;
    let cfg = SimOptions {
        control_hz: hz,
        ..SimOptions::default()
    }
    .config();
    match cfg.validate() {
        Ok(()) => Ok(hz),
        Err(e @ EnvError::InvalidConfig { .. }) if hz.is_finite() && hz > 0.0 => Err(format!(
            "{e}; `sim` keeps the learning step at {} s and the RK4 step h at {} s, so the rate \
             must be a multiple of {} Hz and at most {} Hz",
            cfg.step_dt,
            cfg.h,
            1.0 / cfg.step_dt,
            1.0 / cfg.h
        )),
        Err(e) => Err(e.to_string()),
    }
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let opts = SimOptions {
        controller: args.controller,
        stiffness: args.stiffness,
        seed: args.seed,
        control_hz: args.control_hz,
        noise: !args.no_noise,
        mismatch: !args.no_mismatch,
    };
    let s = run_to_dir(&opts, &args.out)
        .with_context(|| format!("simulating into {}", args.out.display()))?;
    if let Some(why) = &s.stopped_early {
        println!(
            "stopped early after {} of {} steps: {why}",
            s.steps, s.config.horizon
        );
    }
    println!(
        "inserted: {}  final x = {:.4} m  max |f| = {:.1} N  {:.1} s simulated in {:.3} s ({:.0}x real time)  -> {}",
        s.inserted,
        s.final_x,
        s.max_abs_f,
        s.sim_time_s,
        s.wall_time_s,
        s.real_time_factor,
        args.out.display()
    );
    Ok(ExitCode::SUCCESS)
}
