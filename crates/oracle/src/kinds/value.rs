//! `value`: PILCO's expected long-term cost with its policy gradient, end to end (trigonometric
//! augmentation, RBF or linear policy, sine saturation, full-GP dynamics, saturating cost),
//! plus the Jacobians of one propagation step (`prop1`).

use super::blocks::{cmp, compute_err, jacobian};
use super::congp::rbf_policy;
use crate::{Case, Class, Comparison, KindChecker, OracleError, Tensor};
use faer::Mat;
use vicpilco_gp::moments::MmModel;
use vicpilco_gp::GpModel;
use vicpilco_learn::step::{Predictor, StepSpec, Target};
use vicpilco_learn::value::{value, ReturnSpec};
use vicpilco_pilco::cost::CostSum;
use vicpilco_pilco::policy::{LinearPolicy, Policy};
use vicpilco_pilco::squash::{PartialSat, SatRange};
use vicpilco_pilco::GaussianBar;

pub struct Value;

fn dynamics(case: &Case) -> Result<GpModel, OracleError> {
    GpModel::new(
        case.mat("dyn_inputs")?,
        case.mat("dyn_targets")?,
        case.hypers("dyn_hyp")?,
    )
    .map_err(|e| compute_err(case, e))
}

fn check_with<P: Policy + Sync>(case: &Case, policy: &P) -> Result<Vec<Comparison>, OracleError>
where
    P::Cache: Send,
{
    let d0 = case.usize("D0")?;
    let u = case.usize("U")?;
    let horizon = case.usize("H")?;
    let difi = case.indices_1based("difi_1based")?;
    let spec = StepSpec {
        state_dim: d0,
        angles: case.indices_1based("angi_1based")?,
        time_input: false,
        policy_inputs: case.indices_1based("poli_1based")?,
        dyn_inputs: case.indices_1based("dyni_1based")?,
        targets: (0..d0)
            .map(|k| {
                if difi.contains(&k) {
                    Target::Relative
                } else {
                    Target::Absolute
                }
            })
            .collect(),
        linear_prior: vec![],
        dt: 1.0,
    };
    let max_u = case.vec("maxU")?;
    let ranges: Vec<SatRange> = max_u
        .iter()
        .map(|&a_max| SatRange::Symmetric { a_max })
        .collect();
    let squash = PartialSat::new(u, &(0..u).collect::<Vec<_>>(), &ranges)
        .map_err(|e| compute_err(case, e))?;
    let gp = dynamics(case)?;
    let pred = Predictor::new(
        &spec,
        policy,
        Some(&squash),
        MmModel::with_uncertainty(&gp),
        None,
    )
    .map_err(|e| compute_err(case, e))?;
    let cost = CostSum::loss_sat(case.mat("cost_W")?.as_ref(), &case.vec("cost_z")?)
        .map_err(|e| compute_err(case, e))?;
    let ret = ReturnSpec {
        state_cost: Some(cost),
        cost_angles: vec![],
        w_mean: 1.0,
        w_std: 0.0,
        energy: None,
        gamma: case.scalar("gamma")?,
        horizon,
    };
    let (m0, s0) = case.gaussian("m0", "S0", d0)?;
    let v =
        value(&pred, &ret, &[(m0.clone(), s0.clone())], true).map_err(|e| compute_err(case, e))?;
    let traj = &v.trajectories[0];
    let mut out = Vec::new();
    cmp(
        case,
        &mut out,
        "p_flat",
        Class::Value,
        &Tensor::from_vec(&policy.params()),
    )?;
    cmp(case, &mut out, "J", Class::Value, &Tensor::scalar(v.j))?;
    let grad = v.grad.as_ref().expect("gradient requested");
    cmp(
        case,
        &mut out,
        "dJdp",
        Class::CovOrDerivative,
        &Tensor::from_vec(grad),
    )?;
    let means = Tensor::new(
        vec![horizon, d0],
        traj.iter().flat_map(|s| s.mean.clone()).collect(),
    );
    cmp(case, &mut out, "step_means", Class::Value, &means)?;
    let covs = Tensor::new(
        vec![horizon, d0, d0],
        traj.iter()
            .flat_map(|s| {
                (0..d0 * d0)
                    .map(|k| s.cov[(k / d0, k % d0)])
                    .collect::<Vec<_>>()
            })
            .collect(),
    );
    cmp(case, &mut out, "step_covs", Class::CovOrDerivative, &covs)?;
    cmp(
        case,
        &mut out,
        "step_cost_mean",
        Class::Value,
        &Tensor::from_vec(&traj.iter().map(|s| s.cost_mean).collect::<Vec<_>>()),
    )?;
    cmp(
        case,
        &mut out,
        "step_cost_var",
        Class::CovOrDerivative,
        &Tensor::from_vec(&traj.iter().map(|s| s.cost_var).collect::<Vec<_>>()),
    )?;

    // One step with all Jacobians.
    let prop1 = case.sub("prop1")?;
    let step = pred.step(0, &m0, &s0).map_err(|e| compute_err(case, e))?;
    cmp(
        &prop1,
        &mut out,
        "M",
        Class::Value,
        &Tensor::from_vec(&step.next_mean),
    )?;
    cmp(
        &prop1,
        &mut out,
        "S",
        Class::CovOrDerivative,
        &Tensor::from_mat(&step.next_cov),
    )?;
    let p = policy.n_params();
    let vjp = |bar: GaussianBar| {
        let mut pb = vec![0.0; p];
        let g = pred
            .step_backward(&step.tape, &bar, None, &mut pb)
            .expect("shapes fixed by the forward step");
        (g, pb)
    };
    let jm = jacobian(&[d0], d0, p, |k| {
        let mut bar = GaussianBar::zeros(d0);
        bar.mean[k] = 1.0;
        vjp(bar)
    });
    let js = jacobian(&[d0, d0], d0, p, |k| {
        let mut bar = GaussianBar::zeros(d0);
        bar.cov = Mat::zeros(d0, d0);
        bar.cov[(k / d0, k % d0)] = 1.0;
        vjp(bar)
    });
    for (field, t) in [
        ("dMdm", &jm.dm),
        ("dMds", &jm.ds),
        ("dMdp", &jm.dp),
        ("dSdm", &js.dm),
        ("dSds", &js.ds),
        ("dSdp", &js.dp),
    ] {
        let want = if field.ends_with("ds") {
            prop1.cov_derivative(field)?
        } else {
            prop1.tensor(field)?
        };
        let tol = crate::Tolerance::for_case(&case.kind, &case.name);
        out.push(crate::compare(
            &format!("prop1.{field}"),
            Class::CovOrDerivative,
            t,
            &want,
            tol,
        ));
    }
    Ok(out)
}

impl KindChecker for Value {
    fn kind(&self) -> &'static str {
        "value"
    }

    fn check(&self, case: &Case) -> Result<Vec<Comparison>, OracleError> {
        match case.string("policy_type")?.as_str() {
            t if t.contains("conlin") => {
                let pol = LinearPolicy::new(case.mat("policy_w")?.as_ref(), &case.vec("policy_b")?)
                    .map_err(|e| compute_err(case, e))?;
                check_with(case, &pol)
            }
            _ => {
                let pol = rbf_policy(case, "policy_hyp", "policy_inputs", "policy_targets")?;
                check_with(case, &pol)
            }
        }
    }
}
