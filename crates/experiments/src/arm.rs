//! The thesis's peg-in-hole experiments on the simulated arm, built from an
//! [`ArmExperiment`] config: VIL (§5-4: stiffness (k_x, k_y) along the given min-jerk plan, time
//! as a GP input, the plan's increments as the prior mean of the relative targets) and VILTA
//! (§5-5: stiffness and reference increments (Δx_ref, Δy_ref), no time input, zero prior mean,
//! the scene shifted so the cost target is reachable).
//!
//! Fixed by the thesis and not configurable: the state (x, y, ẋ, ẏ, f_x, f_y), the policy
//! inputs (x, y, ẋ, ẏ), relative targets for the kinematic states and absolute ones for the
//! forces (§4-1-1), the force cost on (f_x, f_y) with target 0.

use crate::config::{ArmExperiment, PolicyKind, PriorMean, Task};
use crate::ExperimentError;
use faer::Mat;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use std::sync::Mutex;
use vicpilco_env::arm::{
    ActionMode, ArmConfig, ArmEnv, OuParams, RefPoint, ReferenceOrigin, ViaPlan,
};
use vicpilco_env::Environment;
use vicpilco_gp::sparse::SparseTrainOptions;
use vicpilco_gp::train::Wolfe;
use vicpilco_gp::{DynamicsOptions, TrainOptions};
use vicpilco_learn::data::Rollout;
use vicpilco_learn::outer::{derive_seed, ExplorePolicy, LoopSetup, OptimiserOptions};
use vicpilco_learn::start::StartDistribution;
use vicpilco_learn::step::{LinearPrior, StepSpec, Target};
use vicpilco_learn::value::ReturnSpec;
use vicpilco_pilco::cost::{CostSum, EnergyCost, SaturatingCost};
use vicpilco_pilco::policy::{LinearPolicy, RbfPolicy};
use vicpilco_pilco::squash::{PartialSat, SatRange};

/// Seed purpose of the policy initialisation (see [`derive_seed`]).
const PURPOSE_POLICY_INIT: u64 = 11;
/// Seed purpose of the final policy's evaluation starts and noise.
pub const PURPOSE_EVALUATION: u64 = 12;
/// Seed purpose of the initial scan's jitter, derived from the explore seed.
const PURPOSE_SCAN_JITTER: u64 = 13;

/// Indices of the reference's lead (x_v − x, y_v − y) in the state with `vilta.lead_state`.
pub const LEAD_INDICES: [usize; 2] = [6, 7];
/// Indices of f_x, f_y in the arm's state (x, y, ẋ, ẏ, f_x, f_y).
pub const FORCE_INDICES: [usize; 2] = [4, 5];
/// The dynamics GP's targets, in output order: position and velocity increments, then the
/// measured contact forces.
pub const GP_TARGET_NAMES: [&str; 6] = ["dx", "dy", "dxd", "dyd", "fx", "fy"];

/// The dynamics GP's input names in column order: the state entries `spec.dyn_inputs` lists
/// (the arm's state, with `t` after it), then the environment's actions.
pub fn gp_input_names(spec: &StepSpec, env: &ArmEnv) -> Vec<String> {
    let state = env.state_names();
    spec.dyn_inputs
        .iter()
        .map(|&i| state.get(i).cloned().unwrap_or_else(|| "t".to_string()))
        .chain(env.action_names())
        .collect()
}

fn diag(v: &[f64]) -> Mat<f64> {
    Mat::from_fn(v.len(), v.len(), |i, j| if i == j { v[i] } else { 0.0 })
}

/// The simulator configuration of an experiment: the default arm (15 % mismatch on) with the
/// experiment's sensor noise, controller, step, horizon and, for VILTA, action layout and
/// shifted scene.
pub fn arm_config(cfg: &ArmExperiment) -> ArmConfig {
    let mut arm = ArmConfig {
        controller: cfg.controller,
        step_dt: cfg.dt,
        horizon: cfg.horizon,
        noise: cfg.sensor_noise,
        ..ArmConfig::default()
    };
    if let (Task::Vilta, Some(v)) = (cfg.task, &cfg.vilta) {
        arm.mode = ActionMode::Vilta {
            delta_max: cfg.policy.delta_max.unwrap_or(0.0),
            delta_tick: v.delta_tick,
            origin: v.reference,
            max_lead: v.max_lead,
            lead_state: v.lead_state.is_some(),
        };
        arm.geometry = arm.geometry.shifted(v.geometry_shift_x, 0.0);
    }
    arm
}

/// The path the initial roll-out follows: the VIL plan, or the VILTA scan through its via
/// points starting at `origin` (the start position).
/// A reference path as a function of time.
type Path = Box<dyn Fn(f64) -> RefPoint + Send + Sync>;

fn initial_path(cfg: &ArmExperiment, arm: &ArmConfig, origin: [f64; 2]) -> Path {
    match &cfg.initial.scan {
        Some(scan) => {
            let mut points: Vec<[f64; 3]> = scan.iter().map(|r| [r[1], r[2], 0.0]).collect();
            points[0] = [origin[0], origin[1], 0.0];
            let plan = ViaPlan {
                points,
                times: scan.iter().map(|r| r[0]).collect(),
            };
            Box::new(move |t| plan.eval(t))
        }
        None => {
            let reference = arm.reference.clone();
            Box::new(move |t| reference.eval(t))
        }
    }
}

/// The learning problem's every part except the policy.
struct Problem {
    spec: StepSpec,
    squash: PartialSat,
    ret: ReturnSpec,
    prior_shift: Option<Vec<Vec<f64>>>,
    prediction_starts: Vec<(Vec<f64>, Mat<f64>)>,
    env_start: StartDistribution,
    explore: ExplorePolicy,
}

fn problem(cfg: &ArmExperiment, arm: &ArmConfig) -> Result<Problem, ExperimentError> {
    let m = cfg.n_actions();
    let state_dim = cfg.state_dim();
    let lead = cfg.lead_state();
    let mut policy_inputs = vec![0, 1, 2, 3];
    if lead.is_some() {
        policy_inputs.extend(LEAD_INDICES);
    }
    let mut dyn_inputs = policy_inputs.clone();
    if cfg.gp.force_inputs {
        dyn_inputs.extend(FORCE_INDICES);
    }
    if cfg.gp.time_input {
        // Time follows the state in the augmented vector.
        dyn_inputs.push(state_dim);
    }
    let mut targets = vec![
        Target::Relative,
        Target::Relative,
        Target::Relative,
        Target::Relative,
        Target::Absolute,
        Target::Absolute,
    ];
    // The lead moves by the step's reference increments less the TCP's: an increment, as the
    // position is.
    targets.resize(state_dim, Target::Relative);
    // vilta.lead_state.force_prior_stiffness: each force's prior mean is k₀ times the lead
    // along it.
    let linear_prior = lead
        .and_then(|l| l.force_prior_stiffness)
        .map_or_else(Vec::new, |k0| {
            FORCE_INDICES
                .iter()
                .zip(LEAD_INDICES)
                .map(|(&target, state)| LinearPrior {
                    target,
                    state,
                    coefficient: k0,
                })
                .collect()
        });
    let spec = StepSpec {
        state_dim,
        angles: vec![],
        time_input: cfg.gp.time_input,
        policy_inputs,
        dyn_inputs,
        targets,
        linear_prior,
        dt: cfg.dt,
    };
    let prior_shift = match cfg.gp.prior_mean {
        PriorMean::Zero => None,
        PriorMean::Reference => {
            let r = &arm.reference;
            Some(
                (0..cfg.horizon)
                    .map(|t| {
                        let (a, b) = (r.eval(t as f64 * cfg.dt), r.eval((t + 1) as f64 * cfg.dt));
                        vec![
                            b.x[0] - a.x[0],
                            b.x[1] - a.x[1],
                            b.xd[0] - a.xd[0],
                            b.xd[1] - a.xd[1],
                            0.0,
                            0.0,
                        ]
                    })
                    .collect(),
            )
        }
    };
    let c = &cfg.cost;
    let pos_dims: Vec<usize> = c
        .position_dims
        .iter()
        .map(|d| usize::from(d == "y"))
        .collect();
    let pos_w = 1.0 / (c.position_width * c.position_width);
    let force_cost = |width: f64| {
        let w = 1.0 / (width * width);
        SaturatingCost::new(&[4, 5], diag(&[w, w]).as_ref(), &[0.0, 0.0])
    };
    let mut costs = vec![
        SaturatingCost::new(
            &pos_dims,
            diag(&vec![pos_w; pos_dims.len()]).as_ref(),
            &c.position_target,
        )?,
        force_cost(c.force_width)?,
    ];
    if let Some(far) = c.force_width_far {
        costs.push(force_cost(far)?);
    }
    let k_range = SatRange::Bounded {
        a_min: cfg.policy.k_min,
        a_max: cfg.policy.k_max,
    };
    let (ranges, a_max, penalised) = match cfg.task {
        Task::Vil => (
            vec![k_range; 2],
            vec![cfg.policy.k_max; 2],
            vec![true, true],
        ),
        Task::Vilta => {
            let d = cfg.policy.delta_max.unwrap_or(0.0);
            (
                vec![
                    k_range,
                    k_range,
                    SatRange::Symmetric { a_max: d },
                    SatRange::Symmetric { a_max: d },
                ],
                vec![cfg.policy.k_max, cfg.policy.k_max, d, d],
                vec![true, true, false, false],
            )
        }
    };
    let squash = PartialSat::new(m, &(0..m).collect::<Vec<_>>(), &ranges)?;
    let ret = ReturnSpec {
        state_cost: Some(CostSum::new(state_dim, costs)?),
        cost_angles: vec![],
        w_mean: 1.0,
        w_std: c.w_std,
        energy: Some((EnergyCost::new(&a_max, &penalised)?, c.w_energy)),
        gamma: 1.0,
        horizon: cfg.horizon,
    };
    let s = &cfg.start;
    // The reference starts at the start pose: the lead's mean is 0.
    let start_state: Vec<f64> = s
        .state
        .iter()
        .copied()
        .chain(lead.map(|_| [0.0; 2]).into_iter().flatten())
        .collect();
    let start_var: Vec<f64> = s
        .prediction_std
        .iter()
        .copied()
        .chain(lead.map(|l| [l.prediction_std; 2]).into_iter().flatten())
        .map(|v| v * v)
        .collect();
    let start_cov = diag(&start_var);
    let prediction_starts = match &s.prediction_y {
        Some(ys) => ys
            .iter()
            .map(|&y| {
                let mut mean = start_state.clone();
                mean[1] = y;
                (mean, start_cov.clone())
            })
            .collect(),
        None => vec![(start_state.clone(), start_cov)],
    };
    let env_start = match s.y_range {
        Some([lo, hi]) => {
            let (mut a, mut b) = (start_state.clone(), start_state.clone());
            a[1] = lo;
            b[1] = hi;
            StartDistribution::Uniform { lo: a, hi: b }
        }
        None => StartDistribution::fixed(&start_state),
    };
    let ou = OuParams {
        a_min: cfg.policy.k_min,
        a_max: cfg.policy.k_max,
        theta: cfg.initial.ou_theta,
        dt: cfg.dt,
    };
    ou.validate()?;
    let explore = explore_policy(cfg, arm, ou);
    Ok(Problem {
        spec,
        squash,
        ret,
        prior_shift,
        prediction_starts,
        env_start,
        explore,
    })
}

/// The initial roll-out's actions: OU stiffness, plus for VILTA the scan's increments per
/// controller tick, averaged over each step (the action is held for the step).
fn explore_policy(cfg: &ArmExperiment, arm: &ArmConfig, ou: OuParams) -> ExplorePolicy {
    let horizon = cfg.horizon;
    let dt = cfg.dt;
    match (&cfg.vilta, cfg.initial.scan.is_some()) {
        (Some(v), true) => {
            let ticks_per_step = dt / v.delta_tick;
            let delta_max = cfg.policy.delta_max.unwrap_or(0.0);
            let v = v.clone();
            let cfg = cfg.clone();
            let arm = arm.clone();
            // The scan starts where the arm starts (observed at t = 0).
            let path: Mutex<Option<Path>> = Mutex::new(None);
            // Zero-mean OU offsets of the reference at steps 0..=H (0 at the start), per axis;
            // the stiffness OU's process with its band centred on 0.
            let jitter = cfg.initial.scan_jitter.clone().map(|j| {
                let process = OuParams {
                    a_min: -3.0 * j.std,
                    a_max: 3.0 * j.std,
                    theta: j.theta,
                    dt,
                };
                move |seed: u64| -> [Vec<f64>; 2] {
                    let mut rng = rand::rngs::ChaCha8Rng::seed_from_u64(derive_seed(
                        seed,
                        0,
                        PURPOSE_SCAN_JITTER,
                    ));
                    let x = process.sample(horizon + 1, &mut rng, true);
                    [x, process.sample(horizon + 1, &mut rng, true)]
                }
            });
            Box::new(move |seed, t, obs| {
                let k = ou.profiles(horizon, seed)[t.min(horizon - 1)];
                let mut guard = path.lock().unwrap_or_else(|e| e.into_inner());
                if t == 0 || guard.is_none() {
                    *guard = Some(initial_path(&cfg, &arm, [obs[0], obs[1]]));
                }
                let p = guard.as_ref().expect("set above");
                let (a, b) = (p(t as f64 * dt), p((t + 1) as f64 * dt));
                let offsets = jitter.as_ref().map(|j| j(seed));
                let offset = |i: usize, step: usize| {
                    offsets.as_ref().map_or(0.0, |o| o[i][step.min(horizon)])
                };
                // A reference restarted at the measured position each step aims at the path's
                // next point from there; one integrated from the start follows the path's
                // increments.
                let from = match v.reference {
                    ReferenceOrigin::Start => [a.x[0] + offset(0, t), a.x[1] + offset(1, t)],
                    ReferenceOrigin::Measured => [obs[0], obs[1]],
                };
                let delta = |i: usize| {
                    ((b.x[i] + offset(i, t + 1) - from[i]) / ticks_per_step)
                        .clamp(-delta_max, delta_max)
                };
                vec![k[0], k[1], delta(0), delta(1)]
            })
        }
        _ => Box::new(move |seed, t, _obs| ou.profiles(horizon, seed)[t.min(horizon - 1)].to_vec()),
    }
}

/// RBF centres spread along the initial roll-out's path (ours), pseudo-targets `init_std ·
/// randn`, the configured length-scales for every output.
pub fn rbf_policy(cfg: &ArmExperiment, seed: u64) -> Result<RbfPolicy, ExperimentError> {
    let arm = arm_config(cfg);
    let n = cfg.policy.n_basis.unwrap_or(0);
    let m = cfg.n_actions();
    let path = initial_path(cfg, &arm, [cfg.start.state[0], cfg.start.state[1]]);
    let t_end = cfg.horizon as f64 * cfg.dt;
    let n_in = cfg.n_policy_inputs();
    // Centres on the scan's path, with the reference leading by nothing (as it starts).
    let centres = Mat::from_fn(n, n_in, |i, k| {
        let r = path(t_end * (i as f64 + 0.5) / n as f64);
        [r.x[0], r.x[1], r.xd[0], r.xd[1]]
            .get(k)
            .copied()
            .unwrap_or(0.0)
    });
    let mut rng = rand::rngs::ChaCha8Rng::seed_from_u64(derive_seed(seed, 0, PURPOSE_POLICY_INIT));
    let mut targets = Mat::from_fn(n, m, |_, _| {
        cfg.policy.init_std * Distribution::<f64>::sample(&StandardNormal, &mut rng)
    });
    if let (true, Some(v)) = (cfg.policy.init_from_scan, &cfg.vilta) {
        // The search roll-out's increment per tick over the step centred on each centre's
        // time, as `explore_policy` sends it, taken back through the actions' saturation.
        let ticks_per_step = cfg.dt / v.delta_tick;
        let range = SatRange::Symmetric {
            a_max: cfg.policy.delta_max.unwrap_or(0.0),
        };
        for i in 0..n {
            let t = t_end * (i as f64 + 0.5) / n as f64;
            let (a, b) = (path(t - 0.5 * cfg.dt), path(t + 0.5 * cfg.dt));
            for axis in 0..2 {
                targets[(i, 2 + axis)] = range.preimage((b.x[axis] - a.x[axis]) / ticks_per_step);
            }
        }
    }
    let ls = cfg.policy.lengthscales.unwrap_or([1.0; 4]);
    let lead_ls = cfg
        .lead_state()
        .and_then(|l| l.policy_lengthscale)
        .unwrap_or(1.0);
    let log_ls = Mat::from_fn(n_in, m, |k, _| ls.get(k).copied().unwrap_or(lead_ls).ln());
    Ok(RbfPolicy::new(
        centres,
        targets,
        log_ls.as_ref(),
        cfg.policy
            .snr
            .unwrap_or(vicpilco_pilco::policy::DEFAULT_SNR),
    )?)
}

/// Weights `init_std · randn`, offsets 0 (mid-range gains after the saturation).
pub fn linear_policy(cfg: &ArmExperiment, seed: u64) -> Result<LinearPolicy, ExperimentError> {
    let m = cfg.n_actions();
    let mut rng = rand::rngs::ChaCha8Rng::seed_from_u64(derive_seed(seed, 0, PURPOSE_POLICY_INIT));
    let w = Mat::from_fn(m, cfg.n_policy_inputs(), |_, _| {
        cfg.policy.init_std * Distribution::<f64>::sample(&StandardNormal, &mut rng)
    });
    Ok(LinearPolicy::new(w.as_ref(), &vec![0.0; m])?)
}

/// The largest contact force |f| (N) at the end of any step of a roll-out: `summary.json`'s
/// `max_force` and `vicpilco evaluate`'s, one definition for both.
pub fn largest_force(r: &Rollout) -> f64 {
    r.true_states
        .iter()
        .map(|s| s[4].hypot(s[5]))
        .fold(0.0, f64::max)
}

/// Whether the peg ended fully inserted at the end of the episode (the simulator's
/// `inserted` flag after the last step: in the hole within the insertion tolerance of the end
/// wall). An episode the simulator stopped early (singular Jacobian, runaway joint) never
/// succeeds.
pub fn inserted(r: &Rollout) -> bool {
    // Records written before `stopped_early` existed mark a singular stop by its flag alone.
    let stopped_early = r
        .infos
        .iter()
        .any(|i| i.stopped_early.is_some() || i.flags.get("singular") == Some(&true));
    !stopped_early
        && r.infos
            .last()
            .and_then(|i| i.flags.get("inserted"))
            .copied()
            .unwrap_or(false)
}

/// The environment of the initial search roll-out when it differs from the updates' one:
/// VILTA with `vilta.max_lead_in_search = false` (ours) records the search without the lead
/// bound. `None`: the search runs on the updates' environment.
pub fn search_env(cfg: &ArmExperiment) -> Result<Option<ArmEnv>, ExperimentError> {
    if cfg.vilta.as_ref().is_none_or(|v| v.max_lead_in_search) {
        return Ok(None);
    }
    let mut arm = arm_config(cfg);
    if let ActionMode::Vilta { max_lead, .. } = &mut arm.mode {
        *max_lead = None;
    }
    Ok(Some(ArmEnv::new(arm)?))
}

/// The learning problem with `policy` and its arm environment.
pub fn setup<P>(
    cfg: &ArmExperiment,
    policy: P,
    seed: u64,
) -> Result<(LoopSetup<P>, ArmEnv), ExperimentError> {
    let arm = arm_config(cfg);
    let p = problem(cfg, &arm)?;
    let env = ArmEnv::new(arm)?;
    let setup = LoopSetup {
        spec: p.spec,
        squash: Some(p.squash),
        ret: p.ret,
        prediction_starts: p.prediction_starts,
        env_start: p.env_start,
        prior_shift: p.prior_shift,
        dynamics: DynamicsOptions {
            sparse_threshold: cfg.gp.sparse_threshold,
            train: TrainOptions {
                max_iters: cfg.gp.line_searches,
                cold_restart: cfg.gp.cold_restart,
                lengthscale_floor: cfg.gp.lengthscale_floor.clone().unwrap_or_default(),
                lengthscale_ceiling: cfg.gp.lengthscale_ceiling.clone().unwrap_or_default(),
                ..TrainOptions::default()
            },
            sparse: SparseTrainOptions {
                num_inducing: cfg.gp.n_inducing,
                seed,
                hyper_points: Some(cfg.gp.hyper_points),
                ..SparseTrainOptions::default()
            },
        },
        model_selection: cfg.gp.model_selection,
        optimiser: OptimiserOptions {
            length: cfg.optimiser.length,
            mfepls: cfg.optimiser.mfepls,
            memory: cfg.optimiser.memory,
            wolfe: Wolfe::PILCO,
            scale_params: cfg
                .optimiser
                .scale_params
                .then(|| cfg.optimiser.centre_scale.unwrap_or_default()),
            max_slope_ratio: cfg.optimiser.msr,
        },
        initial_rollouts: 1,
        episodes: cfg.episodes,
        rollouts_per_episode: cfg.vilta.as_ref().map_or(1, |v| v.rollouts_per_iteration),
        policy,
        explore: p.explore,
        success: Box::new(inserted),
        seed,
    };
    Ok((setup, env))
}

/// Whether the config's policy is linear (the caller picks the policy type).
pub fn is_linear(cfg: &ArmExperiment) -> bool {
    cfg.policy.kind == PolicyKind::Linear
}

#[cfg(test)]
mod tests;
