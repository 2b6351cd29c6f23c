//! `congp`: the RBF policy ([`vicpilco_pilco::policy::RbfPolicy`]), including derivatives
//! w.r.t. the flat parameter vector `p = [hyp(:); inputs(:); targets(:)]`.

use super::blocks::{check_moment_block, cmp, compute_err};
use crate::{Case, Class, Comparison, KindChecker, OracleError, Tensor};
use vicpilco_pilco::policy::{Policy, RbfPolicy};

pub struct Congp;

/// The RBF policy a congp or value case describes (σ_f = 1, σ_n = 0.01 forced as in PILCO).
pub(crate) fn rbf_policy(
    case: &Case,
    hyp: &str,
    inputs: &str,
    targets: &str,
) -> Result<RbfPolicy, OracleError> {
    let hyp = case.mat(hyp)?;
    let d = hyp.nrows() - 2;
    let log_ls = faer::Mat::from_fn(d, hyp.ncols(), |r, c| hyp[(r, c)]);
    RbfPolicy::new(
        case.mat(inputs)?,
        case.mat(targets)?,
        log_ls.as_ref(),
        100.0,
    )
    .map_err(|e| compute_err(case, e))
}

impl KindChecker for Congp {
    fn kind(&self) -> &'static str {
        "congp"
    }

    fn check(&self, case: &Case) -> Result<Vec<Comparison>, OracleError> {
        let d = case.usize("D")?;
        let pol = rbf_policy(case, "hyp", "inputs", "targets")?;
        if pol.n_inputs() != d || pol.n_params() != case.usize("P")? {
            return Err(compute_err(case, "hyp, D and P disagree"));
        }
        let (m, s) = (case.vec("m")?, case.mat("s")?);
        let (outputs, cache) = pol
            .forward(&m, s.as_ref())
            .map_err(|e| compute_err(case, e))?;
        let p = pol.n_params();
        let mut out = check_moment_block(case, d, p, "V", &outputs, |bar| {
            let mut pb = vec![0.0; p];
            let g = pol.backward(&cache, bar, &mut pb);
            (g, pb)
        })?;
        cmp(
            case,
            &mut out,
            "p_flat",
            Class::Value,
            &Tensor::from_vec(&pol.params()),
        )?;
        Ok(out)
    }
}
