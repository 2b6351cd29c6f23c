//! One checker per oracle kind.

mod blocks;
mod congp;
mod conlin;
mod gp;
mod gsat;
mod gtrig;
mod loss_sat;
mod nlml;
mod value;

use crate::KindChecker;

/// Every checker vicpilco has.
pub fn checkers() -> Vec<&'static dyn KindChecker> {
    vec![
        &gp::Gp0,
        &gp::Gp1,
        &gp::Gp2,
        &nlml::Nlml,
        &conlin::Conlin,
        &gsat::GSat,
        &gtrig::GTrig,
        &loss_sat::LossSat,
        &congp::Congp,
        &value::Value,
    ]
}
