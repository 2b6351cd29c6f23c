//! `gTrig`: sine/cosine augmentation ([`vicpilco_pilco::squash::TrigAug`]).

use super::blocks::{check_moment_block, compute_err};
use crate::{Case, Comparison, KindChecker, OracleError};
use vicpilco_pilco::squash::TrigAug;

pub struct GTrig;

impl KindChecker for GTrig {
    fn kind(&self) -> &'static str {
        "gTrig"
    }

    fn check(&self, case: &Case) -> Result<Vec<Comparison>, OracleError> {
        let d = case.usize("d")?;
        let idx = case.indices_1based("i_1based")?;
        let trig = TrigAug::new(d, &idx, &case.vec("e")?).map_err(|e| compute_err(case, e))?;
        let (m, s) = case.gaussian_input(d)?;
        let (outputs, cache) = trig.forward(&m, s.as_ref());
        check_moment_block(case, d, 0, "C", &outputs, |bar| {
            (trig.backward(&cache, bar), Vec::new())
        })
    }
}
