//! The `costs` bench's inputs that its checker (`tests/tests/avr_costs.rs`)
//! needs and the bench does not print: this one file is compiled into both
//! (`#[path]`), so that the two cannot drift apart.

use planner_core::escape::{Escape, EscapeConfig};
use planner_core::{Point, Reading};

/// Readings for the free-distance rule with obstacles in sight.
pub const NEAR: [Reading; 5] = [
    Reading::Range(300),
    Reading::Range(180),
    Reading::Clear,
    Reading::Range(420),
    Reading::TooClose,
];

/// Cycles of the drop sequence at most ([`creep`] drops the escape's
/// capacity of virtual obstacles well within them).
pub const CREEP_CYCLES: i16 = 400;

/// Where the virtual obstacles' force is timed from: beside the middle of
/// the row [`creep`] lays, so that all 24 are in reach.
pub const VO_PROBE: Point = Point::new(575, -200);

/// Cycle `k` of the drop sequence: a rover creeping 50 mm every twelve
/// cycles is stuck and drops a virtual obstacle each time (see `escape`).
pub fn creep(escape: &mut Escape, cfg: &EscapeConfig, k: i16) {
    let _ = escape.observe(cfg, Point::new(50 * (k / 12), 0), 5_000);
}
