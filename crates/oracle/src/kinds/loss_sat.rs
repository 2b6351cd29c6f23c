//! `lossSat`: the saturating cost ([`vicpilco_pilco::cost::CostSum::loss_sat`]).

use super::blocks::{cmp, compute_err, jacobian};
use crate::{Case, Class, Comparison, KindChecker, OracleError, Tensor};
use vicpilco_pilco::cost::CostSum;
use vicpilco_pilco::CostBar;

pub struct LossSat;

impl KindChecker for LossSat {
    fn kind(&self) -> &'static str {
        "lossSat"
    }

    fn check(&self, case: &Case) -> Result<Vec<Comparison>, OracleError> {
        let d = case.usize("D")?;
        let cost = CostSum::loss_sat(case.mat("W")?.as_ref(), &case.vec("z")?)
            .map_err(|e| compute_err(case, e))?;
        let (m, s) = (case.vec("m")?, case.mat("s")?);
        if m.len() != d || s.nrows() != d || s.ncols() != d {
            return Err(compute_err(case, "m, s and D disagree"));
        }
        let (mom, cache) = cost.forward(&m, s.as_ref());
        let mut out = Vec::new();
        cmp(case, &mut out, "L", Class::Value, &Tensor::scalar(mom.mean))?;
        cmp(
            case,
            &mut out,
            "S",
            Class::CovOrDerivative,
            &Tensor::scalar(mom.var),
        )?;
        cmp(case, &mut out, "C", Class::Value, &Tensor::from_vec(&mom.v))?;

        let vjp = |bar: CostBar| (cost.backward(&cache, &bar), Vec::new());
        let jl = jacobian(&[], d, 0, |_| {
            vjp(CostBar {
                mean: 1.0,
                ..Default::default()
            })
        });
        let js = jacobian(&[], d, 0, |_| {
            vjp(CostBar {
                var: 1.0,
                ..Default::default()
            })
        });
        let jc = jacobian(&[d], d, 0, |k| {
            let mut c = vec![0.0; d];
            c[k] = 1.0;
            vjp(CostBar {
                v: Some(c),
                ..Default::default()
            })
        });
        for (y, j) in [("L", &jl), ("S", &js), ("C", &jc)] {
            let deriv = Class::CovOrDerivative;
            cmp(case, &mut out, &format!("d{y}dm"), deriv, &j.dm)?;
            cmp(case, &mut out, &format!("d{y}ds"), deriv, &j.ds)?;
        }
        Ok(out)
    }
}
