//! TangentBug (Kamon, Rivlin & Rimon 1998, "TangentBug: a range-sensor
//! based navigation algorithm"), on five beams over ±40°.
//!
//! - **Motion to goal**: straight to the goal while its way is free;
//!   where it is blocked, towards the visible point O that minimises the
//!   heuristic distance d(x, O) + d(O, goal), until that distance starts
//!   to grow ([`PROGRESS_MM`] above the least so far): a local minimum.
//! - **Boundary following** in the direction of the last chosen point,
//!   tracking d_followed, the least goal distance of the boundary points
//!   seen since; **leave** when d_reach, the least goal distance of the
//!   visible free points, is below d_followed by [`PROGRESS_MM`].
//! - **Unreachable** on coming back round to where the following began
//!   ([`HitLoop`]), or (ours) after [`HitLoop::BUDGET_CYCLES`] of
//!   following.
//!
//! How it deviates from the paper's 360° sensor of radius R:
//!
//! - The visible set is the five beams' free ways (the safety rule's
//!   [`Senses::free_mm`] along each beam's heading, at most the 0.8 m
//!   reach), not a disc. The candidate points O are the ends of the free
//!   beams: the free beam beside a blocked one is the endpoint of a
//!   blocking interval as the beams resolve it (20° apart), and a free beam
//!   with no blocked neighbour is a point of free space, which the paper's
//!   T-node covers.
//! - **Scans.** While moving to the goal, a goal bearing outside the sector
//!   is looked at: the rover turns on the spot to face it (a step of 0;
//!   that turn costs simulated time). With nothing free in view it turns
//!   on the spot by the sector's width towards the goal's side.
//! - While following, d_reach is taken over the free points the beams see
//!   ahead; there is no scan behind, so a leave towards a goal behind the
//!   rover waits until the boundary turns it that way. The leave steps
//!   towards the point that gave d_reach (motion to goal goes on from
//!   there).

use super::{begin, hug, HitLoop, Senses, Side, FREE_STEP_MM, HUG_FREE_MM};
use crate::eapf::command::{Output, Status};
use crate::eapf::config::Config;
use crate::eapf::sensors::{RawCounts, Reading, SENSOR_COUNT};
use crate::fixed::{Angle, Point};
use crate::Pose;

/// The heuristic distance has grown (motion to goal), or d_reach is below
/// d_followed (following), by this much, mm: the beams' distances are
/// whole millimetres of a noisy sensor.
pub const PROGRESS_MM: u16 = 50;

/// What TangentBug is doing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Motion to goal, with the least heuristic distance so far (mm).
    ToGoal {
        /// d(x, O) + d(O, goal) at its least since this motion began.
        best_mm: u16,
    },
    /// Boundary following.
    Follow {
        /// The side the boundary is kept on.
        side: Side,
        /// Where the following began.
        hit: HitLoop,
        /// d_followed: the least goal distance of the boundary seen, mm.
        followed_mm: u16,
    },
    /// Round the boundary: the goal cannot be reached.
    Unreachable,
}

/// The TangentBug planner.
#[derive(Clone, Debug)]
pub struct TangentBug {
    pub(super) senses: Senses,
    goal: Point,
    mode: Mode,
}

impl TangentBug {
    /// TangentBug heading for `goal` with the rover's `config`.
    pub fn new(config: Config, goal: Point) -> TangentBug {
        TangentBug {
            senses: Senses::new(config),
            goal,
            mode: Mode::ToGoal { best_mm: u16::MAX },
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
        let (bearing, goal_mm) = self.senses.goal(pose, self.goal);
        match self.mode {
            Mode::Unreachable => self.senses.stop(pose, Status::Unreachable),
            Mode::ToGoal { best_mm } => self.motion_to_goal(pose, bearing, goal_mm, best_mm),
            Mode::Follow {
                side,
                mut hit,
                followed_mm,
            } => {
                if hit.closed(pose.position) || hit.spent() {
                    self.mode = Mode::Unreachable;
                    return self.senses.stop(pose, Status::Unreachable);
                }
                let followed_mm = followed_mm.min(self.boundary_mm(pose));
                let (reach_mm, turn, way) = self.reach(pose, bearing, goal_mm);
                if reach_mm.saturating_add(PROGRESS_MM) <= followed_mm {
                    // Leave, towards the point that gave d_reach: motion to
                    // goal from there on.
                    self.mode = Mode::ToGoal { best_mm: u16::MAX };
                    return self.senses.command(pose, turn, way.min(FREE_STEP_MM));
                }
                self.mode = Mode::Follow {
                    side,
                    hit,
                    followed_mm,
                };
                let (turn, step) = hug(&mut self.senses, pose, side);
                self.senses.command(pose, turn, step)
            }
        }
    }

    /// Motion to goal, the least heuristic distance so far `best_mm`.
    fn motion_to_goal(&mut self, pose: Pose, bearing: Angle, goal_mm: u16, best_mm: u16) -> Output {
        self.mode = Mode::ToGoal { best_mm };
        // The scan: look towards the goal.
        if !self.senses.in_sector(bearing) {
            return self.senses.command(pose, bearing, 0);
        }
        let free = self.senses.free_mm(pose, bearing);
        if free >= HUG_FREE_MM.min(goal_mm) {
            self.mode = Mode::ToGoal {
                best_mm: best_mm.min(goal_mm),
            };
            return self
                .senses
                .command(pose, bearing, FREE_STEP_MM.min(goal_mm));
        }
        // No visible point, or the heuristic distance grows: a local
        // minimum. Follow the boundary the way O lies (with none, on the
        // goal's side).
        let best = self.best_point(pose);
        let Some((turn, way, h)) =
            best.filter(|&(_, _, h)| h <= best_mm.saturating_add(PROGRESS_MM))
        else {
            let side = Side::passing(best.map_or(bearing, |(turn, _, _)| turn));
            self.mode = Mode::Follow {
                side,
                hit: HitLoop::new(pose.position),
                followed_mm: goal_mm.min(self.boundary_mm(pose)),
            };
            let (turn, step) = hug(&mut self.senses, pose, side);
            return self.senses.command(pose, turn, step);
        };
        self.mode = Mode::ToGoal {
            best_mm: best_mm.min(h),
        };
        self.senses.command(pose, turn, way.min(FREE_STEP_MM))
    }

    /// The visible free points: of the beams whose way is free for
    /// [`HUG_FREE_MM`], the heading, the free way and its end's distance
    /// to the goal.
    fn free_points(&self, pose: Pose) -> impl Iterator<Item = (Angle, u16, u16)> + '_ {
        self.senses
            .config()
            .sensor_angles
            .iter()
            .map(move |&a| (a, self.senses.free_mm(pose, a)))
            .filter(|&(_, way)| way >= HUG_FREE_MM)
            .map(move |(a, way)| {
                let o = pose.position.offset(pose.heading.add(a), way);
                (a, way, o.distance_mm(self.goal))
            })
    }

    /// Of the visible free points O, the one that minimises d(x, O) +
    /// d(O, goal): its heading, free way and that distance.
    fn best_point(&self, pose: Pose) -> Option<(Angle, u16, u16)> {
        self.free_points(pose)
            .map(|(a, way, to_goal)| (a, way, way.saturating_add(to_goal)))
            .min_by_key(|&(_, _, h)| h)
    }

    /// The least goal distance of the boundary points the beams see, mm
    /// (`u16::MAX`: none).
    fn boundary_mm(&self, pose: Pose) -> u16 {
        (0..SENSOR_COUNT)
            .filter(|&i| matches!(self.senses.readings()[i], Reading::Range(_)))
            .map(|i| self.senses.beam_end(pose, i).0.distance_mm(self.goal))
            .min()
            .unwrap_or(u16::MAX)
    }

    /// d_reach: the least goal distance of the visible free points (the
    /// free beams' ends, and the way towards the goal if it is in view),
    /// mm, with the turn and free way that lead to it.
    fn reach(&self, pose: Pose, bearing: Angle, goal_mm: u16) -> (u16, Angle, u16) {
        let towards = self.senses.free_mm(pose, bearing);
        let direct = (
            goal_mm.saturating_sub(towards),
            bearing,
            towards.min(goal_mm),
        );
        self.free_points(pose)
            .map(|(a, way, to_goal)| (to_goal, a, way))
            .chain(
                (self.senses.in_sector(bearing) && towards >= HUG_FREE_MM.min(goal_mm))
                    .then_some(direct),
            )
            .min_by_key(|&(d, _, _)| d)
            .unwrap_or((u16::MAX, Angle::ZERO, 0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eapf::config::test_config;
    use crate::peers::tests::counts;

    #[test]
    fn heads_for_the_goal_when_its_way_is_free() {
        let cfg = test_config();
        let mut t = TangentBug::new(cfg, Point::new(3_000, 0));
        let out = t.step_raw(Pose::default(), &counts(&cfg, [None; 5]));
        assert_eq!(out.command.heading, Angle::ZERO);
        assert_eq!(t.mode(), Mode::ToGoal { best_mm: 3_000 });
    }

    #[test]
    fn a_blocked_goal_goes_by_the_endpoint_nearer_the_goal() {
        let cfg = test_config();
        // Goal ahead and a little to the left; a wall ahead whose left end
        // is in view: the left beams are free.
        let mut t = TangentBug::new(cfg, Point::new(3_000, 300));
        let raw = counts(&cfg, [Some(300), Some(300), Some(300), None, None]);
        let out = t.step_raw(Pose::default(), &raw);
        assert!(out.command.heading.signed() > 0, "{:?}", out.command);
        assert!(out.command.step_mm > 0);
    }

    /// The defining rule: following leaves when d_reach < d_followed, and
    /// not before.
    #[test]
    fn leaves_the_boundary_when_d_reach_is_below_d_followed() {
        let cfg = test_config();
        let goal = Point::new(0, 3_000);
        let mut t = TangentBug::new(cfg, goal);
        t.mode = Mode::Follow {
            side: Side::Left,
            hit: HitLoop::new(Point::new(0, 0)),
            followed_mm: 2_000,
        };
        // At (0, 0) facing +x, a wall on the left, the goal 3 m to the
        // left: every visible free point is farther than 2 m from it.
        let wall_left = counts(&cfg, [None, None, Some(200), Some(200), Some(200)]);
        t.step_raw(Pose::default(), &wall_left);
        assert!(matches!(t.mode(), Mode::Follow { .. }), "{:?}", t.mode());
        // At (0, 1,500) facing the goal with the way free: d_reach =
        // 1,500 − 400 < 2,000: leave, towards the goal.
        let pose = Pose {
            position: Point::new(0, 1_500),
            heading: Angle::QUARTER,
        };
        let out = t.step_raw(pose, &counts(&cfg, [None; 5]));
        assert!(matches!(t.mode(), Mode::ToGoal { .. }), "{:?}", t.mode());
        assert_eq!(out.command.heading, Angle::QUARTER);
    }
}
