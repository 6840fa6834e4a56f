//! What the firmwares share beside the planner: [`drive`] (odometry and the
//! turn-then-advance executor) and [`protocol`] (the serial command lines).

pub mod drive;
pub mod protocol;
