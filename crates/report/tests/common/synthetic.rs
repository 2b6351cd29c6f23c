//! Synthetic run directories in the run-directory format, shared by the unit tests (included
//! with `#[path]`) and the integration tests. The trajectories are made up but shaped like
//! real ones (approach the wall, slide to the hole, insert), so the plots can be judged by eye:
//! set VICPILCO_KEEP_TMP=1 to keep the directories.
#![allow(dead_code)]

use serde_json::{json, Value};
use std::f64::consts::PI;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// A directory under the system temp dir, removed on drop unless VICPILCO_KEEP_TMP is set.
pub struct TempDir(PathBuf);

impl TempDir {
    pub fn new(tag: &str) -> TempDir {
        static COUNTER: AtomicUsize = AtomicUsize::new(0);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let dir =
            std::env::temp_dir().join(format!("vicpilco-report-{tag}-{}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("create temp dir");
        TempDir(dir)
    }

    pub fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        if std::env::var_os("VICPILCO_KEEP_TMP").is_none() {
            let _ = std::fs::remove_dir_all(&self.0);
        } else {
            eprintln!("kept {}", self.0.display());
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Stiffness only: 2 actions.
    Vil,
    /// Stiffness and reference increments: 4 actions.
    Vilta,
    /// VILTA from random start heights: 4 roll-outs per update and final_eval.jsonl.
    ViltaVar,
    /// PILCO's pendulum: no geometry, state (dtheta, theta), one torque action.
    Pendulum,
}

const WALL_X: f64 = 0.65;
const HOLE_Y: f64 = 0.20;
const HOLE_R: f64 = 0.005;
const END_X: f64 = 0.75;

/// Min-jerk blend from 0 to 1 over τ ∈ [0, 1].
fn s(tau: f64) -> f64 {
    let t = tau.clamp(0.0, 1.0);
    t * t * t * (10.0 - 15.0 * t + 6.0 * t * t)
}

/// A small deterministic wobble so lines are not perfectly smooth.
fn wobble(k: usize, seed: usize) -> f64 {
    ((k * 7 + seed * 13) as f64 * 0.61).sin() * 0.5 + ((k + seed) as f64 * 1.7).cos() * 0.5
}

struct Traj {
    states: Vec<Vec<f64>>,
    actions: Vec<Vec<f64>>,
    costs: Vec<f64>,
    success: bool,
}

/// One arm roll-out: quality 0 is the exploration roll-out, 1 a good final policy.
fn arm_traj(quality: f64, start_y: f64, n_actions: usize, seed: usize) -> Traj {
    let (steps, dt) = (100, 0.1);
    let success = quality > 0.45;
    let miss = if success {
        0.0
    } else {
        0.02 + 0.03 * (1.0 - quality)
    };
    let y_goal = HOLE_Y + miss;
    let pos = |t: f64| -> (f64, f64) {
        let x_app = 0.5 + (WALL_X - 0.5) * s(t / 2.0);
        let y = start_y + (y_goal - start_y) * s((t - 2.0) / 3.0);
        let x = if success {
            x_app + (END_X - 0.002 - WALL_X) * s((t - 5.0) / 2.0)
        } else {
            x_app
        };
        (x, y)
    };
    let mut states = Vec::new();
    for k in 0..=steps {
        let t = k as f64 * dt;
        let (x, y) = pos(t);
        let (x1, y1) = pos(t + 1e-3);
        let in_contact = t > 1.9 && x < WALL_X + 1e-3;
        let fx = if in_contact { -20.0 } else { 0.0 } + if x > END_X - 0.003 { -15.0 } else { 0.0 };
        let fy = if in_contact {
            2.0 * wobble(k, seed)
        } else {
            0.0
        };
        states.push(vec![
            x + 2e-4 * wobble(k, seed),
            y + 2e-4 * wobble(k + 3, seed),
            (x1 - x) / 1e-3,
            (y1 - y) / 1e-3,
            fx,
            fy,
        ]);
    }
    let mut actions = Vec::new();
    let mut ou = [120.0, 120.0];
    for k in 0..steps {
        let t = k as f64 * dt;
        let a = if quality == 0.0 {
            // A mean-reverting random walk like the exploration's OU stiffness profile.
            for (i, v) in ou.iter_mut().enumerate() {
                *v += 0.3 * (125.0 - *v) + 40.0 * wobble(k, seed + i);
                *v = v.clamp(5.0, 250.0);
            }
            vec![
                ou[0],
                ou[1],
                0.001 * wobble(k, seed),
                0.001 * wobble(k, seed + 1),
            ]
        } else {
            vec![
                230.0 - 170.0 * s((t - 6.0) / 2.0) * quality,
                200.0 - 190.0 * s((t - 5.0) / 2.0) * quality,
                0.002 * (1.0 - s(t / 3.0)),
                0.0015 * (s(t / 2.0) - s((t - 3.0) / 2.0)),
            ]
        };
        actions.push(a[..n_actions].to_vec());
    }
    let costs = states[1..]
        .iter()
        .map(|x| {
            let d2 = (x[0] - END_X).powi(2) + (x[1] - HOLE_Y).powi(2);
            1.0 - (-d2 / (2.0 * 0.06f64.powi(2))).exp() + 0.02
        })
        .collect();
    Traj {
        states,
        actions,
        costs,
        success,
    }
}

/// One pendulum swing-up roll-out (state dtheta, theta; 40 steps of 0.1 s).
fn pendulum_traj(quality: f64, seed: usize) -> Traj {
    let (steps, dt) = (40, 0.1);
    let success = quality > 0.5;
    let target = if success { PI } else { PI * quality };
    let theta = |t: f64| target * s(t / 2.0) + 0.3 * (1.0 - quality) * (3.0 * t).sin();
    let mut states = Vec::new();
    for k in 0..=steps {
        let t = k as f64 * dt;
        let th = theta(t) + 0.01 * wobble(k, seed);
        states.push(vec![(theta(t + 1e-3) - theta(t)) / 1e-3, th]);
    }
    let actions = (0..steps)
        .map(|k| {
            let t = k as f64 * dt;
            vec![if quality == 0.0 {
                2.5 * wobble(k, seed)
            } else {
                2.5 * (2.0 * t).sin() * (1.0 - s((t - 2.0) / 1.0)) * quality
            }]
        })
        .collect();
    let costs = states[1..]
        .iter()
        .map(|x| 1.0 - (-(x[1] - PI).powi(2) / 0.5).exp())
        .collect();
    Traj {
        states,
        actions,
        costs,
        success,
    }
}

fn rollout_json(episode: usize, tr: &Traj) -> Value {
    json!({
        "episode": episode,
        "costs": tr.costs,
        "rollout": {
            "observations": tr.states[1..],
            "actions": tr.actions,
            "true_states": tr.states,
            "infos": [{"true_state": tr.states[1], "flags": {"in_hole": tr.success}}],
            "used_for_training": true
        }
    })
}

/// A prediction close to `tr` with uncertainty growing over the horizon.
fn prediction_json(
    episode: usize,
    tr: &Traj,
    names: (&[&str], &[&str]),
    bounds: &[[f64; 2]],
    dt: f64,
) -> Value {
    let steps: Vec<Value> = (0..tr.actions.len())
        .map(|k| {
            let x = &tr.states[k + 1];
            let grow = 0.2 + k as f64 / tr.actions.len() as f64;
            let scale: Vec<f64> = x
                .iter()
                .map(|v| (v.abs() * 0.03).max(1e-3) * grow)
                .collect();
            json!({
                "t": (k + 1) as f64 * dt,
                "mean": x.iter().zip(&scale).map(|(v, s)| v + 0.4 * s).collect::<Vec<_>>(),
                "var": scale.iter().map(|s| s * s).collect::<Vec<_>>(),
                "action_mean": tr.actions[k].iter().map(|a| a * 1.02).collect::<Vec<_>>(),
                "action_var": tr.actions[k].iter().map(|a| (0.04 * a).powi(2)).collect::<Vec<_>>(),
                "cost_mean": tr.costs[k],
                "cost_var": 0.01,
                "energy_mean": 0.01,
                "weighted_cost_mean": tr.costs[k] * 0.95,
                "weighted_cost_std": 0.05 * grow,
            })
        })
        .collect();
    json!({
        "episode": episode,
        "dt": dt,
        "state_names": names.0,
        "action_names": names.1,
        "action_bounds": bounds,
        "starts": [steps],
    })
}

fn write_lines(path: &Path, lines: &[Value]) {
    let mut f = std::fs::File::create(path).expect("create jsonl");
    for l in lines {
        writeln!(f, "{l}").expect("write jsonl");
    }
}

/// Writes a complete run directory of `kind` into `dir` in the current format.
pub fn write_run(dir: &Path, kind: Kind) {
    let (n_updates, per_update, n_actions) = match kind {
        Kind::Vil => (6, 1, 2),
        Kind::Vilta => (8, 1, 4),
        Kind::ViltaVar => (5, 4, 4),
        Kind::Pendulum => (5, 1, 1),
    };
    let arm = kind != Kind::Pendulum;
    let dt = 0.1;
    let state_names: &[&str] = if arm {
        &["x", "y", "xdot", "ydot", "f_x", "f_y"]
    } else {
        &["dtheta", "theta"]
    };
    let action_names: &[&str] = if arm {
        &["k_x", "k_y", "dx_ref", "dy_ref"][..n_actions]
    } else {
        &["torque"]
    };
    let action_bounds: &[[f64; 2]] = if arm {
        &[
            [5.0, 250.0],
            [5.0, 250.0],
            [-0.0025, 0.0025],
            [-0.0025, 0.0025],
        ][..n_actions]
    } else {
        &[[-2.5, 2.5]]
    };
    let start_y = |update: usize, r: usize| -> f64 {
        if kind == Kind::ViltaVar {
            0.1 + 0.2 * (((update * 4 + r) * 37) % 100) as f64 / 100.0
        } else {
            0.0
        }
    };
    let traj = |quality: f64, update: usize, r: usize| {
        if arm {
            arm_traj(quality, start_y(update, r), n_actions, update * 10 + r)
        } else {
            pendulum_traj(quality, update * 10 + r)
        }
    };

    let mut rollouts = Vec::new();
    let mut predictions = Vec::new();
    let mut episodes = Vec::new();
    let initial = traj(0.0, 0, 0);
    let initial_return: f64 = initial.costs.iter().sum();
    rollouts.push(rollout_json(0, &initial));
    for u in 1..=n_updates {
        // Learning progress with a relapse at update 3, as real runs have.
        let quality = if u == 3 {
            0.3
        } else {
            (u as f64 / n_updates as f64).min(1.0)
        };
        let trs: Vec<Traj> = (0..per_update)
            .map(|r| traj(if r == 1 && u > 2 { 0.4 } else { quality }, u, r))
            .collect();
        predictions.push(prediction_json(
            u,
            &trs[0],
            (state_names, action_names),
            action_bounds,
            dt,
        ));
        let ok = trs.iter().filter(|t| t.success).count();
        let colour = match ok {
            0 => "red",
            n if n == per_update => "green",
            _ => "yellow",
        };
        let recorded: f64 = trs[0].costs.iter().sum();
        let last = trs[0].states.last().cloned().unwrap_or_default();
        episodes.push(json!({
            "index": u,
            "predicted_return_mean": recorded * 0.95 + 1.0,
            "predicted_return_std": 2.0 + 3.0 / u as f64,
            "recorded_return": recorded,
            "success": trs[0].success,
            "success_fraction": ok as f64 / per_update as f64,
            "colour": colour,
            "final_x": if arm { json!(last[0]) } else { Value::Null },
            "max_force": if arm { json!(20.0) } else { Value::Null },
            "start_y": if arm { json!(start_y(u, 0)) } else { Value::Null },
            "interaction_s": 10.0 * per_update as f64,
            "train_s": 1.5 * u as f64,
            "optimise_s": 20.0 + 5.0 * u as f64,
            "evaluations": 40 + u,
            "line_searches": 30,
            "termination": "line-search budget (Length)",
            "objective_start": recorded + 5.0,
            "objective_end": recorded * 0.95 + 1.0,
            "n_train": 100 * u,
            "sparse": u > 4,
        }));
        // Arm runs choose their model on the newest roll-out from the second update on.
        if arm && u >= 2 {
            let kept = u % 2 == 0;
            episodes.last_mut().unwrap()["model_selection"] = json!({
                "refit_score": if kept { 3.0 } else { 1.0 },
                "previous_score": 2.0,
                "kept_previous": kept,
            });
        }
        for tr in &trs {
            rollouts.push(rollout_json(u, tr));
        }
    }

    let mut config = json!({
        "dt": dt,
        "horizon": if arm { 100 } else { 40 },
        "policy_updates": n_updates,
        "cost": {"width": 0.06, "weights": [1.0, 0.0, 0.01]},
        "opt": {"length": 75, "mfepls": 30},
    });
    if arm {
        config["geometry"] = json!({
            "wall_x": WALL_X, "hole_y": HOLE_Y, "hole_r": HOLE_R, "end_x": END_X,
            "spring_catch_x": 0.70
        });
    }
    if kind == Kind::ViltaVar {
        // As a run records it: the setting, and the derived key beside it.
        config["start"] = json!({"y_range": [0.1, 0.3]});
        config["start_y_range"] = json!([0.1, 0.3]);
    }
    let experiment = match kind {
        Kind::Vil => "vil-gic-rbf10",
        Kind::Vilta => "vilta-gic-rbf50",
        Kind::ViltaVar => "vilta-var",
        Kind::Pendulum => "pendulum",
    };
    let summary = json!({
        "experiment": experiment,
        "seed": 1,
        "controller": if arm { json!("gic") } else { Value::Null },
        "policy": "rbf (10 basis functions, 4 inputs)",
        "n_params": 68,
        "initial_return": initial_return,
        "episodes": episodes,
        "solved_at_episode": 4,
        "solved_streak": 3,
        "interaction_s": 10.0 * (1 + n_updates * per_update) as f64,
        "wall_s": 1234.5,
        "config": config,
        "thesis_reference": [
            {"claim": "every roll-out of updates 6-10 inserts", "thesis": "strategy found before 10 episodes",
             "measured": "5/5", "pass": true, "across_seeds": {"passing": 3, "seeds": 5}},
            {"claim": "final return < 25", "thesis": "converges to 20", "measured": "31.2", "pass": false},
            {"claim": "sparse GP from k = 4", "thesis": "Fig. 5-7", "measured": "3 updates", "pass": null},
        ],
    });
    std::fs::write(
        dir.join("summary.json"),
        serde_json::to_string_pretty(&summary).expect("serialise summary"),
    )
    .expect("write summary.json");
    write_lines(&dir.join("rollouts.jsonl"), &rollouts);
    write_lines(&dir.join("predictions.jsonl"), &predictions);

    if kind == Kind::ViltaVar {
        let evals: Vec<Value> = (0..20)
            .map(|i| {
                let y0 = 0.1 + 0.2 * i as f64 / 19.0;
                let tr = arm_traj(if i % 7 == 3 { 0.3 } else { 0.9 }, y0, n_actions, 100 + i);
                json!({"start_y": y0, "success": tr.success, "rollout": {
                    "observations": tr.states[1..], "actions": tr.actions,
                    "true_states": tr.states, "infos": [], "used_for_training": false}})
            })
            .collect();
        write_lines(&dir.join("final_eval.jsonl"), &evals);
    }
}

/// A run as written before predictions.jsonl, costs, colours and thesis_reference existed:
/// summary.json with the old fields and the single-document rollouts.json.
pub fn write_old_run(dir: &Path) {
    let initial = pendulum_traj(0.0, 0);
    let learned: Vec<Traj> = (1..=4).map(|u| pendulum_traj(u as f64 / 4.0, u)).collect();
    let old = |t: &Traj| {
        json!({"actions": t.actions, "observations": t.states[1..], "true_states": t.states,
               "used_for_training": true})
    };
    let doc = json!({
        "initial": [old(&initial)],
        "learned": learned.iter().map(old).collect::<Vec<_>>(),
        "policy_params": [0.1, 0.2],
    });
    std::fs::write(dir.join("rollouts.json"), doc.to_string()).expect("write rollouts.json");
    let episodes: Vec<Value> = learned
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let r: f64 = t.costs.iter().sum();
            json!({"index": i + 1, "predicted_return_mean": r + 0.5, "predicted_return_std": 1.0,
                   "recorded_return": r, "success": t.success, "evaluations": 99,
                   "interaction_s": 4.0, "train_s": 0.01, "optimise_s": 0.9,
                   "line_searches": 75, "n_train": 40, "objective_end": r,
                   "objective_start": r + 1.0, "sparse": false, "termination": "x"})
        })
        .collect();
    let summary = json!({
        "config": {"initial_rollouts": 1, "scenario": "Scenario {\n    dt: 0.1,\n}"},
        "episodes": episodes, "experiment": "pendulum", "interaction_s": 20.0,
        "n_params": 85, "policy": "rbf", "seed": 1, "solved_at_episode": null, "wall_s": 12.0,
    });
    std::fs::write(dir.join("summary.json"), summary.to_string()).expect("write summary.json");
}
