//! What the firmwares share beside the planner: [`app`] (the rover application
//! over the board's parts), [`calibration`] (each sensor's own, stored on
//! the board), [`drive`] (odometry and the
//! turn-then-advance executor) and [`protocol`] (the serial command lines).

pub mod app;
pub mod calibration;
pub mod drive;
pub mod protocol;
