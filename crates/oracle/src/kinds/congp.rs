//! `congp`: the RBF policy ([`vicpilco_pilco::policy::RbfPolicy`]), including derivatives
//! w.r.t. the flat parameter vector `p = [hyp(:); inputs(:); targets(:)]`.

use super::blocks::{check_policy, compute_err};
use crate::{Case, Comparison, KindChecker, OracleError};
use vicpilco_pilco::policy::RbfPolicy;

pub struct Congp;

/// The RBF policy a congp or value case describes (σ_f = 1, σ_n = 0.01 forced as in PILCO).
pub(crate) fn rbf_policy(
    case: &Case,
    hyp: &str,
    inputs: &str,
    targets: &str,
) -> Result<RbfPolicy, OracleError> {
    let hyp = case.pilco_hyp(hyp)?;
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
        check_policy(case, &rbf_policy(case, "hyp", "inputs", "targets")?)
    }
}
