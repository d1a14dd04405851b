//! What every rule reports: a located violation. Its own module because the rules
//! ([`crate::rules`]) report it and the validator collects it; neither owns it.

use std::fmt;

/// One rule violation: where and what.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Problem {
    /// A path such as `objects[2].triangles[517]` or `sections[4]`.
    pub location: String,
    pub message: String,
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.location, self.message)
    }
}
