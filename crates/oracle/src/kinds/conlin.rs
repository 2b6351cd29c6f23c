//! `conlin`: the linear policy ([`vicpilco_pilco::policy::LinearPolicy`]), including the
//! derivatives w.r.t. the flat parameter vector `p = [b; w(:)]`.

use super::blocks::{check_policy, compute_err};
use crate::{Case, Comparison, KindChecker, OracleError};
use vicpilco_pilco::policy::LinearPolicy;

pub struct Conlin;

impl KindChecker for Conlin {
    fn kind(&self) -> &'static str {
        "conlin"
    }

    fn check(&self, case: &Case) -> Result<Vec<Comparison>, OracleError> {
        let pol = LinearPolicy::new(case.mat("w")?.as_ref(), &case.vec("b")?)
            .map_err(|e| compute_err(case, e))?;
        check_policy(case, &pol)
    }
}
