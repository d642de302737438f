//! The `sloth` entity kind: a two-toed sloth that hangs under branches and climbs trunks.

pub mod ccd;
pub mod rig;
