//! One checker per oracle kind.

mod gp;

use crate::KindChecker;

/// Every checker vicpilco has.
pub fn checkers() -> Vec<&'static dyn KindChecker> {
    vec![&gp::Gp0, &gp::Gp2]
}
