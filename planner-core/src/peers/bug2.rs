//! Bug2 (Lumelsky & Stepanov 1987, "Path-planning strategies for a point
//! mobile automaton moving amidst unknown obstacles of arbitrary shape").
//!
//! - **Motion to goal** along the m-line, the segment from the start to the
//!   goal, while the way along it is free.
//! - **Hit**: where the way is blocked is the hit point H; follow the
//!   boundary, always on the same side (the right: the rover goes round
//!   counter-clockwise, "left-turning").
//! - **Leave** at the first point L on the m-line, between the start and
//!   the goal, with d(L, goal) < d(H, goal) from which the way towards the
//!   goal is free. With five forward beams "the way is free" is asked by
//!   turning to face the goal (a look, on the spot); a look that finds the
//!   way blocked is not asked again until `PROGRESS_MM` nearer.
//! - **Unreachable** on coming back to H ([`HitLoop`]) on the m-line: the
//!   boundary has no point on the m-line nearer the goal, so it encloses
//!   the start or the goal. Near H but off the m-line is not back at H:
//!   among small obstacles the five beams lose the boundary and the rover
//!   can come round another one beside H. Ours: after
//!   [`HitLoop::BUDGET_CYCLES`] of following from one hit point too.
//!
//! Its path is at most D + ½Σ nᵢpᵢ (D the start–goal distance, pᵢ the
//! perimeters of the obstacles the m-line crosses nᵢ times).

use super::{begin, hug, HitLoop, Senses, Side, FREE_STEP_MM, HUG_FREE_MM};
use crate::eapf::command::{Output, Status};
use crate::eapf::config::Config;
use crate::eapf::sensors::{RawCounts, Reading};
use crate::fixed::{Angle, Point};
use crate::Pose;

/// The rover is on the m-line within this, mm (its steps along a boundary
/// are at most 200 mm, so a crossing is also caught by the side changing).
const ON_LINE_MM: i32 = 30;
/// A leave point is this much nearer the goal than the hit point, mm (and a
/// second look this much nearer than a look that failed).
const PROGRESS_MM: u16 = 50;

/// What Bug2 is doing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Along the m-line towards the goal.
    ToGoal,
    /// Following the boundary met at the hit point.
    Follow {
        /// The hit point and whether the rover is back at it.
        hit: HitLoop,
        /// The goal's distance at the hit point, mm.
        hit_mm: u16,
        /// The goal's distance at the last look that found the way
        /// blocked, mm.
        looked_mm: u16,
        /// This cycle turned to face the goal: the next asks the way.
        looking: bool,
    },
    /// Back at the hit point: the goal cannot be reached.
    Unreachable,
}

/// The Bug2 planner.
#[derive(Clone, Debug)]
pub struct Bug2 {
    pub(super) senses: Senses,
    goal: Point,
    /// The m-line's start: where the rover stood at the first cycle.
    start: Option<Point>,
    /// The rover's side of the m-line last cycle (sign of the cross
    /// product), to catch a crossing between two cycles.
    last_side: i8,
    mode: Mode,
    /// A look was asked again (see the leave in [`Bug2::step_raw`]).
    rechecked: bool,
}

impl Bug2 {
    /// Bug2 heading for `goal` with the rover's `config`.
    pub fn new(config: Config, goal: Point) -> Bug2 {
        Bug2 {
            senses: Senses::new(config),
            goal,
            start: None,
            last_side: 0,
            mode: Mode::ToGoal,
            rechecked: false,
        }
    }

    /// What it is doing.
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// One cycle from raw counts.
    pub fn step_raw(&mut self, pose: Pose, raw: &RawCounts) -> Output {
        if let Err(out) = begin(&mut self.senses, pose, raw, self.goal) {
            return out;
        }
        let start = *self.start.get_or_insert(pose.position);
        let on_line = self.crossed_m_line(start, pose.position);
        let (bearing, goal_mm) = self.senses.goal(pose, self.goal);
        match self.mode {
            Mode::Unreachable => self.senses.stop(pose, Status::Unreachable),
            Mode::ToGoal => self.motion_to_goal(pose, bearing, goal_mm),
            Mode::Follow {
                mut hit,
                hit_mm,
                looked_mm,
                looking,
            } => {
                // Back at H is back on the m-line at H: near it without
                // crossing the line is another boundary met beside it.
                if (hit.update(pose.position).0 && on_line) || hit.spent() {
                    self.mode = Mode::Unreachable;
                    return self.senses.stop(pose, Status::Unreachable);
                }
                let nearer = |than: u16| goal_mm.saturating_add(PROGRESS_MM) <= than;
                let leave = (on_line || looking) && nearer(hit_mm) && nearer(looked_mm);
                let mut next = Mode::Follow {
                    hit,
                    hit_mm,
                    looked_mm,
                    looking: false,
                };
                if leave && !self.senses.in_sector(bearing) {
                    // Look: turn to face the goal; the next cycle asks.
                    next = Mode::Follow {
                        hit,
                        hit_mm,
                        looked_mm,
                        looking: true,
                    };
                    self.mode = next;
                    return self.senses.command(pose, bearing, 0);
                }
                if leave {
                    if self.free_to_goal(pose, bearing, goal_mm) {
                        self.mode = Mode::ToGoal;
                        return self.motion_to_goal(pose, bearing, goal_mm);
                    }
                    // After the look's turn the fold-back filter distrusts,
                    // for one cycle, a beam that read near before the turn
                    // (`FoldBackFilter`): look once more.
                    let distrusted = self.senses.readings().contains(&Reading::TooClose);
                    if looking && distrusted && !self.rechecked {
                        self.rechecked = true;
                        self.mode = Mode::Follow {
                            hit,
                            hit_mm,
                            looked_mm,
                            looking: true,
                        };
                        return self.senses.command(pose, bearing, 0);
                    }
                    self.rechecked = false;
                    next = Mode::Follow {
                        hit,
                        hit_mm,
                        looked_mm: goal_mm,
                        looking: false,
                    };
                }
                self.mode = next;
                let (turn, step) = hug(&mut self.senses, pose, Side::Right);
                self.senses.command(pose, turn, step)
            }
        }
    }

    /// Whether the way towards the goal (`bearing` off the heading,
    /// `goal_mm` away) is free as far as a boundary step asks, or to the
    /// goal.
    fn free_to_goal(&self, pose: Pose, bearing: Angle, goal_mm: u16) -> bool {
        self.senses.free_mm(pose, bearing) >= HUG_FREE_MM.min(goal_mm)
    }

    /// Motion to goal: turn to it, and go while its way is free; where it
    /// is blocked is the hit point.
    fn motion_to_goal(&mut self, pose: Pose, bearing: Angle, goal_mm: u16) -> Output {
        if !self.senses.in_sector(bearing) {
            return self.senses.command(pose, bearing, 0);
        }
        if self.free_to_goal(pose, bearing, goal_mm) {
            return self
                .senses
                .command(pose, bearing, FREE_STEP_MM.min(goal_mm));
        }
        self.mode = Mode::Follow {
            hit: HitLoop::new(pose.position),
            hit_mm: goal_mm,
            looked_mm: goal_mm,
            looking: false,
        };
        let (turn, step) = hug(&mut self.senses, pose, Side::Right);
        self.senses.command(pose, turn, step)
    }

    /// Whether the rover at `p` is on the m-line from `start` to the goal,
    /// between them: within [`ON_LINE_MM`] of it, or on the other side of
    /// it than last cycle.
    fn crossed_m_line(&mut self, start: Point, p: Point) -> bool {
        let (lx, ly) = start.to(self.goal);
        let (px, py) = start.to(p);
        let (lx, ly, px, py) = (lx as i64, ly as i64, px as i64, py as i64);
        let len2 = lx * lx + ly * ly;
        let along = px * lx + py * ly;
        let cross = lx * py - ly * px;
        let side = cross.signum() as i8;
        let len = crate::fixed::hypot(lx as i32, ly as i32).max(1) as i64;
        let near = cross.abs() <= ON_LINE_MM as i64 * len;
        let crossed = side != 0 && self.last_side != 0 && side != self.last_side;
        if side != 0 {
            self.last_side = side;
        }
        // From the start (less the hit point's radius: a hit at the start
        // is come back to from behind it) to the goal.
        let behind = HitLoop::BACK_MM as i64 * len;
        (near || crossed) && (-behind..=len2).contains(&along)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eapf::config::test_config;
    use crate::peers::tests::counts;

    const CLEAR: [Option<u16>; 5] = [None; 5];

    #[test]
    fn goes_straight_along_the_m_line_in_free_space() {
        let cfg = test_config();
        let mut b = Bug2::new(cfg, Point::new(3_000, 0));
        let out = b.step_raw(Pose::default(), &counts(&cfg, CLEAR));
        assert_eq!(out.command.heading, Angle::ZERO);
        assert_eq!(out.command.step_mm, FREE_STEP_MM);
        assert_eq!(b.mode(), Mode::ToGoal);
    }

    /// The defining rule: once following, Bug2 leaves only on the m-line,
    /// nearer the goal than its hit point, with the way to the goal free.
    #[test]
    fn leaves_only_on_the_m_line_nearer_than_the_hit_point() {
        let cfg = test_config();
        let goal = Point::new(3_000, 0);
        let mut b = Bug2::new(cfg, goal);
        let wall = counts(&cfg, [Some(200); 5]);
        let clear = counts(&cfg, CLEAR);
        // Start at the origin, facing the goal: a wall ahead is the hit.
        b.step_raw(Pose::default(), &clear);
        b.step_raw(Pose::default(), &wall);
        let Mode::Follow { hit_mm, .. } = b.mode() else {
            panic!("{:?}", b.mode())
        };
        assert_eq!(hit_mm, 3_000);
        let facing_goal = |x, y| Pose {
            position: Point::new(x, y),
            heading: Angle::atan2(-(y as i32), 3_000 - x as i32),
        };
        // Off the m-line, nearer the goal, the way free: it follows on.
        b.step_raw(facing_goal(500, 600), &clear);
        assert!(matches!(b.mode(), Mode::Follow { .. }));
        // Across the m-line's extension behind the start: follows on.
        b.step_raw(facing_goal(-400, 300), &clear);
        b.step_raw(facing_goal(-400, -10), &clear);
        assert!(matches!(b.mode(), Mode::Follow { .. }), "{:?}", b.mode());
        // On the m-line and nearer, the way free: leaves.
        b.step_raw(facing_goal(900, 300), &clear);
        let out = b.step_raw(facing_goal(900, 5), &clear);
        assert_eq!(b.mode(), Mode::ToGoal);
        assert!(out.command.step_mm > 0);
    }

    #[test]
    fn back_at_the_hit_point_the_goal_is_unreachable() {
        let cfg = test_config();
        let mut b = Bug2::new(cfg, Point::new(3_000, 0));
        let wall = counts(&cfg, [Some(150); 5]);
        b.step_raw(Pose::default(), &wall);
        let at = |x, y| Pose {
            position: Point::new(x, y),
            heading: Angle::QUARTER,
        };
        for (x, y) in [(0, 400), (-300, 800), (-600, 400)] {
            let out = b.step_raw(at(x, y), &wall);
            assert_eq!(out.status, Status::Moving);
        }
        // Near H, off the m-line: another boundary beside H.
        let out = b.step_raw(at(-100, 150), &wall);
        assert_eq!(out.status, Status::Moving);
        b.step_raw(at(-500, -200), &wall);
        // Onto the m-line at H from the other side: round the boundary.
        let out = b.step_raw(at(-50, -20), &wall);
        assert_eq!(out.status, Status::Unreachable);
        assert_eq!(b.step_raw(at(-50, -20), &wall).status, Status::Unreachable);
    }
}
