//! One checker per oracle kind.

mod blocks;
mod conlin;
mod gp;
mod gsat;
mod gtrig;
mod loss_sat;

use crate::KindChecker;

/// Every checker vicpilco has.
pub fn checkers() -> Vec<&'static dyn KindChecker> {
    vec![
        &gp::Gp0,
        &gp::Gp2,
        &conlin::Conlin,
        &gsat::GSat,
        &gtrig::GTrig,
        &loss_sat::LossSat,
    ]
}
