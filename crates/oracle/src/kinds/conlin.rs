//! `conlin`: the linear policy ([`vicpilco_pilco::policy::LinearPolicy`]), including the
//! derivatives w.r.t. the flat parameter vector `p = [b; w(:)]`.

use super::blocks::{check_moment_block, cmp, compute_err};
use crate::{Case, Class, Comparison, KindChecker, OracleError, Tensor};
use vicpilco_pilco::policy::{LinearPolicy, Policy};

pub struct Conlin;

impl KindChecker for Conlin {
    fn kind(&self) -> &'static str {
        "conlin"
    }

    fn check(&self, case: &Case) -> Result<Vec<Comparison>, OracleError> {
        let d = case.usize("D")?;
        let pol = LinearPolicy::new(case.mat("w")?.as_ref(), &case.vec("b")?)
            .map_err(|e| compute_err(case, e))?;
        if pol.n_inputs() != d || pol.n_params() != case.usize("P")? {
            return Err(compute_err(case, "w, D and P disagree"));
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
