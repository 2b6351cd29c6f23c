//! `gSat`: sine saturation ([`vicpilco_pilco::squash::SineSat`]).

use super::blocks::{check_moment_block, compute_err};
use crate::{Case, Comparison, KindChecker, OracleError};
use vicpilco_pilco::squash::SineSat;

pub struct GSat;

impl KindChecker for GSat {
    fn kind(&self) -> &'static str {
        "gSat"
    }

    fn check(&self, case: &Case) -> Result<Vec<Comparison>, OracleError> {
        let d = case.usize("d")?;
        let idx = case.indices_1based("i_1based")?;
        let sat = SineSat::new(d, &idx, &case.vec("e")?).map_err(|e| compute_err(case, e))?;
        let (m, s) = case.gaussian_input(d)?;
        let (outputs, cache) = sat.forward(&m, s.as_ref());
        check_moment_block(case, d, 0, "C", &outputs, |bar| {
            (sat.backward(&cache, bar), Vec::new())
        })
    }
}
