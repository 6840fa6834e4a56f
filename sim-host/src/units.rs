//! The simulator's metres and radians against the core's millimetres and
//! binary angles.

use crate::geom::V2;
use planner_core::{Angle, Point};

/// Metres to the core's millimetres.
pub fn to_point(p: V2) -> Point {
    Point::saturating((p.x * 1000.0).round() as i32, (p.y * 1000.0).round() as i32)
}

/// Metres to the core's whole millimetres, saturating at 0 and `u16::MAX`.
pub fn to_mm(m: f64) -> u16 {
    (m * 1000.0).round().clamp(0.0, u16::MAX as f64) as u16
}

/// The core's millimetres to metres.
pub fn to_v2(p: Point) -> V2 {
    V2::new(p.x as f64 / 1000.0, p.y as f64 / 1000.0)
}

/// Radians to the core's binary angle.
pub fn to_angle(rad: f64) -> Angle {
    let turns = rad / std::f64::consts::TAU;
    Angle(((turns.rem_euclid(1.0) * 65_536.0).round() as u32 & 0xFFFF) as u16)
}

/// The core's binary angle to radians in (−π, π].
pub fn to_rad(a: Angle) -> f64 {
    a.signed() as f64 * std::f64::consts::TAU / 65_536.0
}
