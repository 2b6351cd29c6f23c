//! One checker per oracle kind.

mod gp;
mod nlml;

use crate::KindChecker;

/// Every checker vicpilco has.
pub fn checkers() -> Vec<&'static dyn KindChecker> {
    vec![&gp::Gp0, &gp::Gp2, &nlml::Nlml]
}
