//! What the firmwares share beside the planner: [`app`] (the rover application
//! over the board's parts), [`drive`] (odometry and the
//! turn-then-advance executor) and [`protocol`] (the serial command lines).

pub mod app;
pub mod drive;
pub mod protocol;
