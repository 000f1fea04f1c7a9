//! Every emulated-board case: the core, guard and force cases ([`crate::case`]) and the
//! hazards of parts that fail ([`crate::hazards`]).

use crate::case::{self, Case};

/// Every case, the full protocol run first.
pub fn all() -> Vec<Case> {
    let mut all = case::core_set();
    all.extend(crate::hazards::cases());
    all
}

/// The case called `name`.
pub fn by_name(name: &str) -> Option<Case> {
    all().into_iter().find(|c| c.name == name)
}
