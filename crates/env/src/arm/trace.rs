//! Per-tick and per-step records and their CSV files.

use super::contact::Contact;
use crate::{EnvError, Step};
use std::io::Write;
use std::path::Path;

/// The state of one control tick, taken at its start (before the torque is applied).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TickRecord {
    /// Time (s).
    pub t: f64,
    /// True joint angles (rad).
    pub q: [f64; 3],
    /// True joint rates (rad/s).
    pub qd: [f64; 3],
    /// True TCP pose (x, y, φ).
    pub x: [f64; 3],
    /// True TCP velocity (ẋ, ẏ).
    pub xd: [f64; 2],
    /// TCP pose from the noisy encoders.
    pub x_meas: [f64; 3],
    /// TCP velocity from the noisy encoders and tachometers.
    pub xd_meas: [f64; 2],
    /// Reference (x_v, y_v).
    pub x_ref: [f64; 2],
    /// Reference velocity (ẋ_v, ẏ_v).
    pub xd_ref: [f64; 2],
    /// Stiffness (k_x, k_y).
    pub k: [f64; 2],
    /// Commanded joint torque (N·m).
    pub tau: [f64; 3],
    /// True contact force (on the environment).
    pub f_true: [f64; 2],
    /// F/T reading used by the controller.
    pub f_meas: [f64; 2],
    /// True contact state.
    pub contact: Contact,
}

impl TickRecord {
    /// CSV header matching [`TickRecord::csv_row`].
    pub const CSV_HEADER: &'static str = "t,q1,q2,q3,qd1,qd2,qd3,x,y,phi,xd,yd,x_meas,y_meas,xd_meas,yd_meas,x_v,y_v,xd_v,yd_v,k_x,k_y,tau1,tau2,tau3,fx_true,fy_true,fx_meas,fy_meas,contact,face,end,side,spring,in_hole";

    /// One CSV row. Floats use Rust's shortest round-trip formatting.
    pub fn csv_row(&self) -> String {
        let mut v: Vec<f64> = vec![self.t];
        v.extend(self.q);
        v.extend(self.qd);
        v.extend(self.x);
        v.extend(self.xd);
        v.extend(self.x_meas[..2].iter());
        v.extend(self.xd_meas);
        v.extend(self.x_ref);
        v.extend(self.xd_ref);
        v.extend(self.k);
        v.extend(self.tau);
        v.extend(self.f_true);
        v.extend(self.f_meas);
        let c = &self.contact;
        let mut s = v
            .iter()
            .map(|x| x.to_string())
            .collect::<Vec<_>>()
            .join(",");
        for b in [c.any(), c.face, c.end, c.side, c.spring, c.in_hole] {
            s.push(',');
            s.push(if b { '1' } else { '0' });
        }
        s
    }

    /// Bit patterns of every number in the record, for exact comparisons and hashing.
    pub fn bits(&self) -> Vec<u64> {
        let mut v = vec![self.t];
        v.extend(self.q);
        v.extend(self.qd);
        v.extend(self.x);
        v.extend(self.xd);
        v.extend(self.x_meas);
        v.extend(self.xd_meas);
        v.extend(self.x_ref);
        v.extend(self.xd_ref);
        v.extend(self.k);
        v.extend(self.tau);
        v.extend(self.f_true);
        v.extend(self.f_meas);
        v.into_iter().map(f64::to_bits).collect()
    }
}

/// Writes `trace.csv`.
pub fn write_trace_csv(path: &Path, trace: &[TickRecord]) -> Result<(), EnvError> {
    let mut out = String::with_capacity(trace.len() * 400);
    out.push_str(TickRecord::CSV_HEADER);
    out.push('\n');
    for r in trace {
        out.push_str(&r.csv_row());
        out.push('\n');
    }
    write_file(path, out.as_bytes())
}

/// The step flags `steps.csv` carries, 1 or 0 (`singular` and `diverged` mark the step that
/// ended the episode early).
const STEP_FLAG_COLUMNS: [&str; 4] = ["contact", "in_hole", "singular", "diverged"];

/// Writes `steps.csv`: one row per learning step, the action applied during the step, the
/// observation at its end, the true state, the reference and the flags.
pub fn write_steps_csv(
    path: &Path,
    state_names: &[String],
    action_names: &[String],
    first_obs: &[f64],
    steps: &[(Vec<f64>, Step)],
) -> Result<(), EnvError> {
    let mut out = String::new();
    let mut header = vec!["step".to_string(), "t".to_string()];
    header.extend(action_names.iter().cloned());
    header.extend(state_names.iter().cloned());
    header.extend(state_names.iter().map(|n| format!("{n}_true")));
    header.extend(["x_v", "y_v", "xd_v", "yd_v"].map(String::from));
    header.extend(STEP_FLAG_COLUMNS.map(String::from));
    out.push_str(&header.join(","));
    out.push('\n');
    let nan_action = vec![f64::NAN; action_names.len()];
    let row0 = std::iter::once("0".to_string())
        .chain(std::iter::once("0".to_string()))
        .chain(nan_action.iter().map(|_| String::new()))
        .chain(first_obs.iter().map(|v| v.to_string()))
        .chain(state_names.iter().map(|_| String::new()))
        .chain((0..4).map(|_| String::new()))
        .chain(STEP_FLAG_COLUMNS.map(|_| String::new()))
        .collect::<Vec<_>>()
        .join(",");
    out.push_str(&row0);
    out.push('\n');
    for (i, (a, s)) in steps.iter().enumerate() {
        let mut row = vec![(i + 1).to_string(), s.info.t.to_string()];
        row.extend(a.iter().map(|v| v.to_string()));
        row.extend(s.observation.iter().map(|v| v.to_string()));
        row.extend(s.info.true_state.iter().map(|v| v.to_string()));
        let r = s.info.reference.clone().unwrap_or_default();
        row.extend((0..4).map(|k| r.get(k).map(|v| v.to_string()).unwrap_or_default()));
        for f in STEP_FLAG_COLUMNS {
            let b = s.info.flags.get(f).copied().unwrap_or(false);
            row.push(if b { "1" } else { "0" }.to_string());
        }
        out.push_str(&row.join(","));
        out.push('\n');
    }
    write_file(path, out.as_bytes())
}

pub(crate) fn write_file(path: &Path, bytes: &[u8]) -> Result<(), EnvError> {
    let err = |e: std::io::Error| EnvError::Output {
        path: path.display().to_string(),
        message: e.to_string(),
    };
    let mut f = std::fs::File::create(path).map_err(err)?;
    f.write_all(bytes).map_err(err)
}
