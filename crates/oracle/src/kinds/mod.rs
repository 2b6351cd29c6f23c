//! One checker per oracle kind.

use crate::KindChecker;

/// Every checker vicpilco has.
pub fn checkers() -> Vec<&'static dyn KindChecker> {
    vec![]
}
