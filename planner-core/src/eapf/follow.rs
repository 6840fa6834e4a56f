//! Boundary following: the escape's last resort (ours, the DistBug
//! algorithm of Kamon & Rivlin, of Lumelsky & Stepanov's Bug family; not
//! in the seed papers).
//!
//! The virtual obstacles fill a pit until the rover spills out of it, but
//! in a cluster of large obstacles the rover can work along the cluster's
//! face for the whole give-up budget while the way lies round its far side
//! (the commit history, "Worlds no rule was tuned on"). Giving up there reports
//! a reachable goal unreachable. Instead, once the escape gives up, the
//! rover goes on as DistBug does, and the potential field is not used
//! again for this goal:
//!
//! * **seek**: head for the goal (turning on the spot first when its
//!   bearing is outside the sensed sector) while the way there is free for
//!   [`FOLLOW_FREE_MM`]; where it is not, is the *hit point*;
//! * **follow**: keep the boundary on one side: of the sensors' headings
//!   from that side's edge of the sector to the other's, take the first
//!   whose way is free for [`FOLLOW_FREE_MM`] (the rover turns towards the
//!   boundary until the way there is blocked that near); the side is the
//!   one whose opening, as the beams see it at the first hit, is nearer the
//!   goal's bearing (TangentBug's choice of the boundary's nearer end), and
//!   is kept for the goal, as a Bug algorithm keeps it;
//! * **circle** (ours): [`CIRCLE_TURNS`] turns in a row to the sector's
//!   edge towards the boundary, each with a step, are a whole circle with
//!   nothing on that side to keep the rover off it (what it met was ahead
//!   or on the other side); until the next hit point, follow takes the
//!   first free heading *past* the first blocked one, so that what blocks
//!   is passed on the boundary's side;
//! * **leave** (DistBug's rule) where the way towards the goal is free far
//!   enough to end `progress_mm` nearer the goal than the nearest the rover
//!   has been since the hit: seek again. Where the goal is outside the
//!   sensed sector that rule cannot be asked, so past the boundary's point
//!   nearest the goal (its distance, at the nearest since the hit, grows
//!   again) the rover looks: seeks, turning towards the goal. A boundary
//!   out of sight for
//!   [`LOST_CYCLES`] is left too. Meeting a boundary again no
//!   `progress_mm` nearer than that nearest, the rover follows on from the
//!   same hit point (the same boundary, so that its loop can close);
//! * **looped** (the planner hands back to the potential field the
//!   first time, and reports the goal unreachable the second) when the
//!   rover comes back within `2·revisit_mm` of the hit point after having
//!   been more than `4·revisit_mm` away from it (the track round a
//!   boundary passes the hit point at the follower's distance, not the
//!   seek's), from the other side than it left that
//!   radius by (out of a dead end beside the hit point it comes back the
//!   way it went, and goes on): it has been all round the boundary without
//!   finding a way off it nearer the goal (the Bug family's argument: a
//!   boundary that encloses the goal or the rover has no such point).
//!   Coming into that radius by seeking does not close the loop (out of a
//!   U and back in to the hit point is not round the boundary);
//! * **unreachable** when [`BUDGET_GIVE_UPS`]`·give_up_steps` cycles pass
//!   since the hit (a safety net for a loop the test misses), or
//!   [`SECOND_GIVE_UPS`]`·give_up_steps` in the second round, which only
//!   confirms a first loop.
//!
//! A new hit point is `progress_mm` nearer the goal than the nearest before
//! it, so the hits cannot go on for ever. The step's length is the safety
//! rule's (never beyond what the readings and the guard's flank points show
//! free), so following adds no way to collide.

use crate::eapf::config::Config;
use crate::eapf::sensors::{Reading, Readings, SENSOR_COUNT};
use crate::fixed::{hypot, within, Angle, Point};

/// A heading is taken while seeking or following if its way is free this
/// far, mm.
pub const FOLLOW_FREE_MM: u16 = 250;
/// The longest step while seeking or following, mm: short enough that a
/// corner does not go by unseen.
pub const FOLLOW_STEP_MM: u16 = 200;
/// Something this near a sensor face (mm) is in sight of the follower.
pub const SIGHT_MM: u16 = 300;
/// The follower's safety net: a boundary followed from one hit point for
/// this many times the escape's `give_up_steps` (1,000 cycles with the
/// defaults) ends in "unreachable". Long enough to go round the boundaries
/// of the box worlds, short enough that a walled-in goal is reported
/// before the simulator's budget runs out: with a longer one the follower
/// goes round islands that do not hold the goal (the walled worlds of
/// `sim-host/tests/trap_suite.rs` hold it; the commit history, "Walled
/// worlds", has the sweep).
pub const BUDGET_GIVE_UPS: u16 = 5;
/// [`BUDGET_GIVE_UPS`] in the second round, after a first loop handed back
/// to the potential field (see [`FollowVerdict::Looped`]). That round
/// confirms the first loop: with the first round at 6, 3 give-up budgets
/// report 986 of the 1,000 walled runs against 958 at 6, and change no
/// reached run of any set (two box-world timeouts become reports: 8
/// reachable goals reported unreachable of 1,000, 6 at 6; the commit history,
/// "Walled worlds").
pub const SECOND_GIVE_UPS: u16 = 3;
/// Cycles in a row with nothing in sight after which the boundary is lost:
/// more than the turns to the sector's edge that bring a convex corner back
/// into sight.
pub const LOST_CYCLES: u8 = 4;

/// Turns to the sector's edge towards the boundary, each with a step, in
/// a row that make a whole circle (nine of 40°, the default sector's half
/// width; with a narrower sector the rule starts before a whole turn,
/// with a wider one after it; see [`Follow::note_turn`]).
pub const CIRCLE_TURNS: u8 = 9;
/// A turn this near the sector's edge counts as one to the edge.
const EDGE_SLACK: Angle = Angle::from_deg(5);

/// What the boundary follower decided this cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FollowVerdict {
    /// Not following.
    Off,
    /// All round the boundary: no way off it nearer the goal was found.
    Looped,
    /// The budget spent: the goal is unreachable.
    GiveUp,
    /// Seek: turn by this (relative to the heading) and step at most this
    /// far, mm (0: turn on the spot).
    Seek(Angle, u16),
    /// Follow: the first free of [`Follow::turns`].
    Hug,
}

/// The boundary follower's state.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Follow {
    /// +1: the boundary kept on the left, −1: on the right, 0: off.
    side: i8,
    /// Whether the rover has been more than `4·revisit_mm` from the hit
    /// point.
    away: bool,
    /// Whether it was within `2·revisit_mm` of the hit point last cycle.
    near_hit: bool,
    /// Its offset from the hit point (mm) when it last left that radius.
    out: (i16, i16),
    /// Cycles in a row with nothing in sight while following.
    lost: u8,
    /// Cycles since the last new hit point (since the start before it).
    cycles: u16,
    /// The nearest the rover has been to the goal since the hit, mm.
    nearest_mm: u16,
    /// The goal's distance at the last cycle of following, mm.
    last_mm: u16,
    /// Where the boundary followed was met (`None` before the first).
    hit: Option<Point>,
    /// Seeking (the goal), not following.
    seeking: bool,
    /// The second round (see [`SECOND_GIVE_UPS`]).
    second: bool,
    /// Steps the guard stopped before they began since the rover last
    /// moved: that many of the boundary side's first free turns are
    /// skipped (see [`Follow::turns_to_skip`]).
    refused: u8,
    /// Turns to the edge towards the boundary in a row, each with a step,
    /// since the last hit point (see [`Follow::note_turn`]); stays at
    /// [`CIRCLE_TURNS`] once there.
    wound: u8,
}

impl Follow {
    /// Whether the rover seeks or follows a boundary (the escape gave up).
    #[cfg_attr(target_arch = "avr", inline(never))]
    pub fn active(&self) -> bool {
        self.side != 0
    }

    /// Whether a boundary is being followed (met, not only sought).
    pub fn following(&self) -> bool {
        self.side != 0 && !self.seeking
    }

    /// Where the boundary followed last was met.
    pub fn hit(&self) -> Option<Point> {
        self.hit
    }

    /// Start: seek first. The `second` round, after a first loop handed
    /// back to the potential field, has the shorter budget.
    #[cfg_attr(target_arch = "avr", inline(never))]
    pub fn start(&mut self, second: bool) {
        *self = Follow {
            side: 1,
            seeking: true,
            second,
            ..Follow::default()
        };
    }

    /// A turn to the sector's edge away from the boundary's side (what a
    /// blocked way calls for).
    #[cfg_attr(target_arch = "avr", inline(never))]
    pub fn away_turn(&self, cfg: &Config) -> Angle {
        let half = cfg.sector_half_width();
        if self.side > 0 {
            half.neg()
        } else {
            half
        }
    }

    /// One cycle at `robot`, `goal_mm` from the goal whose bearing is
    /// `bearing_rel` off the heading, the way towards it free for
    /// `free_to_goal_mm` (0 outside the sensed sector).
    #[cfg_attr(target_arch = "avr", inline(never))]
    pub fn decide(
        &mut self,
        cfg: &Config,
        readings: &Readings,
        robot: Point,
        goal_mm: u16,
        bearing_rel: Angle,
        free_to_goal_mm: u16,
    ) -> FollowVerdict {
        if self.side == 0 {
            return FollowVerdict::Off;
        }
        let esc = &cfg.escape;
        let half = cfg.sector_half_width();
        let in_sector = bearing_rel.abs_signed() <= half.0;
        // The track round a boundary passes its hit point at the
        // follower's distance, not the seek's: "back" is twice
        // `revisit_mm`, "away" four times.
        let back = esc.revisit_mm.saturating_mul(2);
        self.cycles = self.cycles.saturating_add(1);
        let budgets = if self.second {
            SECOND_GIVE_UPS
        } else {
            BUDGET_GIVE_UPS
        };
        if self.cycles > esc.give_up_steps.saturating_mul(budgets) {
            self.side = 0;
            return FollowVerdict::GiveUp;
        }
        if let (false, Some(hit)) = (self.seeking, self.hit) {
            // DistBug's leave: the way towards the goal is free (as far as
            // seeking asks) and ends nearer than the nearest since the hit.
            let nearest = self.nearest_mm.min(goal_mm);
            let ends_at = goal_mm.saturating_sub(free_to_goal_mm);
            let leave = in_sector
                && free_to_goal_mm >= FOLLOW_FREE_MM.min(goal_mm)
                && ends_at.saturating_add(esc.progress_mm) <= nearest;
            // A boundary out of sight for several turns towards it is
            // lost (a small obstacle left behind; the circle would close
            // a false loop): seek again.
            let seen = readings
                .iter()
                .any(|&r| r.obstacle_mm().is_some_and(|d| d <= SIGHT_MM));
            self.lost = if seen { 0 } else { self.lost.saturating_add(1) };
            // Where the goal is outside the sensed sector, the leave rule
            // cannot be asked: round a small obstacle with the goal beside
            // the rover the follower would close a loop with a way to the
            // goal in plain view behind the beams. So where the goal's
            // distance, after coming to the nearest since the hit, grows
            // again (the boundary's point nearest the goal, as Bug1 leaves
            // from), look: seek, which turns towards the goal and either
            // goes or follows on from the same hit point.
            let look = !in_sector && self.last_mm == self.nearest_mm && goal_mm > self.last_mm;
            self.last_mm = goal_mm;
            if leave || look || self.lost >= LOST_CYCLES {
                self.seeking = true;
                self.lost = 0;
            } else {
                // The nearest counts where the boundary was followed from
                // (a seek from here compares with what came before).
                self.nearest_mm = nearest;
                // Round the boundary, the rover comes back to the hit point
                // from the side opposite the one it left it by; out of a
                // dead end beside the hit point it comes back the way it
                // went. So the loop closes only on coming back from the
                // other side (the offset from the hit point on entering
                // "back" more than 90° from the one on leaving it); coming
                // back the same way, the rover must go away again first.
                // With the sensors set back, more than 60°: a track that
                // passes the hit point off to one side enters and leaves
                // its radius on the same side of it (walled-in, seed 1: 82°
                // apart, round the walls for 1,000 cycles without closing).
                let (entered, (x, y)) = self.pass_hit(hit, robot, back);
                if !self.away {
                    self.away = !within(hit, robot, back.saturating_mul(2));
                } else if entered {
                    // Every offset clamped below 2^14 (the offsets are a
                    // few hundred mm): the dot product and the product of
                    // the lengths fit i32 (no 64-bit multiply on the AVR).
                    let along = self.out.0 as i32 * x + self.out.1 as i32 * y;
                    let apart = if cfg.set_back() {
                        // cos 60° = 1/2.
                        let out = hypot(self.out.0 as i32, self.out.1 as i32) as i32;
                        2 * along <= out * hypot(x, y) as i32
                    } else {
                        along <= 0
                    };
                    if apart {
                        self.side = 0;
                        return FollowVerdict::Looped;
                    }
                    self.away = false;
                }
                return FollowVerdict::Hug;
            }
        }
        // Seeking. Coming near the hit point by seeking is not coming
        // round the boundary (in a U the rover looks out of the U, seeks
        // back in to the hit point, and had closed a false loop: u-trap,
        // seed 5): the hit point's radius is tracked, but only following
        // into it can close the loop.
        if let Some(hit) = self.hit {
            self.pass_hit(hit, robot, back);
        }
        if !in_sector {
            return FollowVerdict::Seek(clamp(bearing_rel, half), 0);
        }
        if free_to_goal_mm >= FOLLOW_FREE_MM.min(goal_mm) {
            // No farther than the goal.
            return FollowVerdict::Seek(bearing_rel, FOLLOW_STEP_MM.min(goal_mm));
        }
        // The way to the goal is blocked. Not `progress_mm` nearer than
        // the nearest on the boundary followed before: the same boundary
        // (the leave promised more than the seek could make, or a corner
        // went out of sight), followed on from the same hit point, so that
        // its loop can close. Else a new hit point.
        self.seeking = false;
        if self.hit.is_some() && goal_mm.saturating_add(esc.progress_mm) > self.nearest_mm {
            return FollowVerdict::Hug;
        }
        // The side is chosen at the first hit and kept (a Bug algorithm
        // goes round every boundary the same way: choosing again at each
        // hit, the rover went back and forth between two).
        if self.hit.is_none() {
            self.side = side_of(readings, bearing_rel);
        }
        self.hit = Some(robot);
        self.wound = 0;
        self.away = false;
        self.near_hit = true;
        self.lost = 0;
        self.cycles = 0;
        self.nearest_mm = goal_mm;
        self.last_mm = goal_mm;
        FollowVerdict::Hug
    }

    /// Note how the last step ended: `moved` (the rover is somewhere new)
    /// or `stopped` (the guard stopped it before it began: after the turn
    /// the beams saw the way blocked).
    pub fn after_step(&mut self, moved: bool, stopped: bool) {
        if moved {
            self.refused = 0;
        } else if stopped {
            self.refused = self.refused.saturating_add(1);
        }
    }

    /// How many of the first free turns (in [`Follow::turns`]' order) to
    /// pass over. A turn towards the boundary that the planner's view
    /// shows free can be blocked in the guard's view after the turn (a
    /// face beside the rover that only the turned beams see); the turn
    /// away from it then looks free again, and the rover would turn to
    /// the refused heading and back for ever (seen on generated worlds:
    /// 800 cycles on one spot). Each refusal on the spot passes over one
    /// more, up to all but the last (the other edge of the sector).
    pub fn turns_to_skip(&self) -> usize {
        (self.refused as usize).min(SENSOR_COUNT - 1)
    }

    /// The heading to follow by, of [`Follow::turns`] with `free(turn)`
    /// the way free along each: the first free for [`FOLLOW_FREE_MM`]
    /// from the boundary's side (the rover turns towards the boundary until
    /// the way there is blocked), passing over [`Follow::turns_to_skip`]
    /// of them. Once the rover has gone round a whole circle of such turns
    /// (see [`Follow::note_turn`]), the first free past the first blocked
    /// one instead (past what blocks, the rover keeps it on its side):
    /// with what the beams see ahead or on the other side and the sector's
    /// edge free, the edge turned the rover away from it, round a circle of
    /// nine 40° turns, back to the same pose every nine cycles until a budget
    /// ran out (box-69 with seed 4: from cycle 311 to the simulator's
    /// budget at 587).
    pub fn hug(&self, cfg: &Config, free: impl Fn(Angle) -> u16) -> Option<(Angle, u16)> {
        let skip = self.turns_to_skip();
        // One pass, one call of `free` per turn and none past the answer.
        // Free turns are counted past the first blocked one (`past`; from
        // the first turn before the circle, as if past one already) and
        // from the first (`any`: what to fall back on).
        let mut blocked = self.wound < CIRCLE_TURNS;
        let (mut past, mut any, mut pick) = (0, 0, None);
        for turn in self.turns(cfg) {
            let way = free(turn);
            if way < FOLLOW_FREE_MM {
                blocked = true;
                continue;
            }
            if blocked {
                if past == skip {
                    return Some((turn, way));
                }
                past += 1;
            }
            if any == skip && pick.is_none() {
                pick = Some((turn, way));
            }
            any += 1;
        }
        pick
    }

    /// Count the rover's circle: `turn` and `step` are this cycle's
    /// command. Turns towards the boundary's side by the sector's half
    /// width (its edge), each with a step, [`CIRCLE_TURNS`] in a row: the
    /// rover has gone round a whole circle (nine 40° turns), not along a
    /// boundary; from then until the next hit point it follows past what
    /// blocks (see [`Follow::hug`]).
    pub fn note_turn(&mut self, cfg: &Config, turn: Angle, step: u16) {
        // No turn goes past the sector's edge: within `EDGE_SLACK` of the
        // edge towards the boundary (the away turn's opposite) is at least
        // the half width less the slack that way.
        let edge = self.away_turn(cfg).neg();
        let towards = turn.sub(edge).abs_signed() <= EDGE_SLACK.0;
        if self.wound < CIRCLE_TURNS {
            self.wound = if towards && step > 0 {
                self.wound + 1
            } else {
                0
            };
        }
    }

    /// Track the rover against the hit point's radius `back`: whether it
    /// has just come within it, and its offset from the hit point (each
    /// axis clamped below 2^14). Leaving the radius, the offset is kept as
    /// the way out (`out`).
    fn pass_hit(&mut self, hit: Point, robot: Point, back: u16) -> (bool, (i32, i32)) {
        let near_hit = within(hit, robot, back);
        let (x, y) = hit.to(robot);
        let (x, y) = (clamp14(x), clamp14(y));
        let entered = near_hit && !self.near_hit;
        if self.near_hit && !near_hit {
            self.out = (x as i16, y as i16);
        }
        self.near_hit = near_hit;
        (entered, (x, y))
    }

    /// The turns to try while following, the boundary's side first: the
    /// sensors' angles from that side's edge of the sector to the other's.
    pub fn turns(&self, cfg: &Config) -> [Angle; SENSOR_COUNT] {
        let mut a = cfg.sensor_angles;
        if self.side > 0 {
            a.reverse();
        }
        a
    }
}

/// The side to keep the boundary on, met with the goal `bearing_rel` off
/// the heading: the way round is by the opening (the first beam from the
/// middle out that sees nothing within [`SIGHT_MM`]) nearer the middle,
/// as TangentBug takes the boundary's end nearer the goal; on a tie, the
/// goal's side. Round by the left keeps the boundary on the right (−1).
fn side_of(readings: &Readings, bearing_rel: Angle) -> i8 {
    let open = |r: &Reading| r.obstacle_mm().is_none_or(|d| d > SIGHT_MM);
    // Beam steps from the middle to the first opening on each side (3:
    // none in sight). Iterators over the halves, not indices: the AVR
    // image must hold no bounds-check panic (`firmware_has_no_panicking_paths`).
    let [r0, r1, mid, l1, l0] = readings;
    let left = [mid, l1, l0].into_iter().position(open).unwrap_or(3);
    let right = [mid, r1, r0].into_iter().position(open).unwrap_or(3);
    let by_left = match left.cmp(&right) {
        core::cmp::Ordering::Less => true,
        core::cmp::Ordering::Greater => false,
        core::cmp::Ordering::Equal => bearing_rel.signed() >= 0,
    };
    if by_left {
        -1
    } else {
        1
    }
}

/// `v` clamped to ±(2^14 − 1).
#[cfg_attr(target_arch = "avr", inline(never))]
fn clamp14(v: i32) -> i32 {
    v.clamp(-16_383, 16_383)
}

/// `a` clamped to ±`half`.
fn clamp(a: Angle, half: Angle) -> Angle {
    if a.abs_signed() <= half.0 {
        a
    } else if a.signed() > 0 {
        half
    } else {
        half.neg()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::eapf::config::test_config as cfg;
    use crate::eapf::config::ConfigBuilder;
    use crate::eapf::sensors::AdcProfile;

    const CLEAR: Readings = [Reading::Clear; SENSOR_COUNT];
    /// Something 150 mm off the left beams' faces, nothing on the right.
    const WALL_LEFT: Readings = [
        Reading::Clear,
        Reading::Clear,
        Reading::Range(150),
        Reading::Range(150),
        Reading::Range(150),
    ];
    const P0: Point = Point::new(0, 0);

    /// A follower that met a boundary at `P0`, 3,000 mm from the goal,
    /// with the opening on the right (so the boundary is kept on the left).
    fn following() -> (Config, Follow) {
        let cfg = cfg();
        let mut f = Follow::default();
        f.start(false);
        let v = f.decide(&cfg, &WALL_LEFT, P0, 3_000, Angle::ZERO, 100);
        assert_eq!(v, FollowVerdict::Hug);
        assert!(f.following());
        (cfg, f)
    }

    #[test]
    fn refusals_on_the_spot_pass_over_turns_until_the_rover_moves() {
        let mut f = Follow::default();
        f.start(false);
        assert_eq!(f.turns_to_skip(), 0);
        f.after_step(false, true);
        f.after_step(false, false); // the turn away: no step, no refusal
        f.after_step(false, true);
        assert_eq!(f.turns_to_skip(), 2);
        for _ in 0..10 {
            f.after_step(false, true);
        }
        // Never all five: the other edge of the sector stays.
        assert_eq!(f.turns_to_skip(), SENSOR_COUNT - 1);
        f.after_step(true, false);
        assert_eq!(f.turns_to_skip(), 0);
    }

    #[test]
    fn hugging_passes_the_boundary_on_its_side() {
        let (cfg, mut f) = following();
        // The boundary on the left: turns from the left edge of the sector.
        let turns = f.turns(&cfg);
        let blocked_at = |blocked: &'static [usize]| {
            move |turn: Angle| {
                let i = turns.iter().position(|&t| t == turn).unwrap();
                if blocked.contains(&i) {
                    FOLLOW_FREE_MM - 1
                } else {
                    FOLLOW_FREE_MM + 10 * i as u16
                }
            }
        };
        let way = |i: usize| FOLLOW_FREE_MM + 10 * i as u16;
        // The first free from the left, towards the boundary.
        assert_eq!(f.hug(&cfg, blocked_at(&[2])), Some((turns[0], way(0))));
        assert_eq!(f.hug(&cfg, blocked_at(&[0])), Some((turns[1], way(1))));
        // Round a whole circle of turns to the left edge, each with a
        // step; a straight step or a turn on the spot starts the count
        // again.
        let edge = cfg.sector_half_width();
        for _ in 0..CIRCLE_TURNS - 1 {
            f.note_turn(&cfg, edge, FOLLOW_STEP_MM);
        }
        f.note_turn(&cfg, Angle::ZERO, FOLLOW_STEP_MM);
        for _ in 0..CIRCLE_TURNS - 1 {
            f.note_turn(&cfg, edge, FOLLOW_STEP_MM);
        }
        f.note_turn(&cfg, edge, 0);
        for _ in 0..CIRCLE_TURNS - 1 {
            f.note_turn(&cfg, edge, FOLLOW_STEP_MM);
        }
        assert_eq!(f.hug(&cfg, blocked_at(&[2])), Some((turns[0], way(0))));
        f.note_turn(&cfg, edge, FOLLOW_STEP_MM);
        // Something ahead, both edges free: past it on its right, so that
        // it stays on the left (not the left edge: round in a circle).
        assert_eq!(f.hug(&cfg, blocked_at(&[2])), Some((turns[3], way(3))));
        // The boundary beside, on the left edge: the first free past it.
        assert_eq!(f.hug(&cfg, blocked_at(&[0])), Some((turns[1], way(1))));
        // Nothing blocks: towards the boundary, round its corner.
        assert_eq!(f.hug(&cfg, blocked_at(&[])), Some((turns[0], way(0))));
        // Nothing free past what blocks: the first free from the left.
        assert_eq!(f.hug(&cfg, blocked_at(&[3, 4])), Some((turns[0], way(0))));
        assert_eq!(f.hug(&cfg, blocked_at(&[0, 1, 2, 3, 4])), None);
        // A refusal on the spot passes over one more.
        f.after_step(false, true);
        assert_eq!(f.hug(&cfg, blocked_at(&[2])), Some((turns[4], way(4))));
        assert_eq!(f.hug(&cfg, blocked_at(&[])), Some((turns[1], way(1))));
        // A new hit point: the circle is forgotten.
        f.after_step(true, false);
        f.decide(&cfg, &CLEAR, P0, 3_000, Angle::ZERO, 760);
        f.decide(&cfg, &WALL_LEFT, P0, 2_000, Angle::ZERO, 100);
        assert_eq!(f.hit(), Some(P0));
        assert_eq!(f.hug(&cfg, blocked_at(&[2])), Some((turns[0], way(0))));
    }

    proptest::proptest! {
        /// Against a plain model of the rule: before the circle, the
        /// `skip`-th free turn from the boundary's side; after it, the
        /// `skip`-th free past the first blocked one, else the `skip`-th
        /// free of all.
        #[test]
        fn hug_is_the_plain_rule(
            ways in proptest::array::uniform5(0u16..2 * FOLLOW_FREE_MM),
            refusals in 0usize..6,
            circled: bool,
        ) {
            let (cfg, mut f) = following();
            for _ in 0..refusals {
                f.after_step(false, true);
            }
            if circled {
                for _ in 0..CIRCLE_TURNS {
                    f.note_turn(&cfg, cfg.sector_half_width(), FOLLOW_STEP_MM);
                }
            }
            let turns = f.turns(&cfg);
            let way = |turn: Angle| ways[turns.iter().position(|&t| t == turn).unwrap()];
            let skip = f.turns_to_skip();
            let free: std::vec::Vec<usize> =
                (0..SENSOR_COUNT).filter(|&i| ways[i] >= FOLLOW_FREE_MM).collect();
            let first_blocked = (0..SENSOR_COUNT).find(|&i| ways[i] < FOLLOW_FREE_MM);
            let past = first_blocked
                .and_then(|b| free.iter().copied().filter(|&i| i > b).nth(skip));
            let want = if circled {
                past.or_else(|| free.get(skip).copied())
            } else {
                free.get(skip).copied()
            };
            proptest::prop_assert_eq!(f.hug(&cfg, way), want.map(|i| (turns[i], ways[i])));
        }
    }

    #[test]
    fn off_until_started() {
        let mut f = Follow::default();
        let v = f.decide(&cfg(), &CLEAR, P0, 3_000, Angle::ZERO, 760);
        assert_eq!(v, FollowVerdict::Off);
        assert!(!f.active());
    }

    #[test]
    fn seeks_the_goal_while_its_way_is_free() {
        let cfg = cfg();
        let mut f = Follow::default();
        f.start(false);
        let ten = Angle::from_deg(10);
        assert_eq!(
            f.decide(&cfg, &CLEAR, P0, 3_000, ten, 760),
            FollowVerdict::Seek(ten, FOLLOW_STEP_MM)
        );
        // Never past the goal.
        assert_eq!(
            f.decide(&cfg, &CLEAR, P0, 120, ten, 760),
            FollowVerdict::Seek(ten, 120)
        );
        // Outside the sector: a turn on the spot to its edge first.
        let v = f.decide(&cfg, &CLEAR, P0, 3_000, Angle::from_deg(90), 0);
        assert_eq!(v, FollowVerdict::Seek(cfg.sector_half_width(), 0));
        assert!(!f.following());
    }

    #[test]
    fn the_opening_nearer_the_middle_picks_the_side() {
        let (cfg, f) = following();
        // Open on the right: round by the right, the boundary on the left,
        // so the left edge of the sector is tried first.
        assert_eq!(f.turns(&cfg)[0], cfg.sensor_angles[SENSOR_COUNT - 1]);
        assert_eq!(f.away_turn(&cfg), cfg.sector_half_width().neg());
        let mirrored = [
            WALL_LEFT[4],
            WALL_LEFT[3],
            WALL_LEFT[2],
            WALL_LEFT[1],
            WALL_LEFT[0],
        ];
        let mut g = Follow::default();
        g.start(false);
        g.decide(&cfg, &mirrored, P0, 3_000, Angle::ZERO, 100);
        assert_eq!(g.turns(&cfg)[0], cfg.sensor_angles[0]);
        assert_eq!(
            side_of(&CLEAR, Angle::from_deg(5)),
            -1,
            "a tie: the goal's side"
        );
        assert_eq!(side_of(&CLEAR, Angle::from_deg(-5)), 1);
    }

    #[test]
    fn leaves_where_the_way_to_the_goal_ends_nearer() {
        let (cfg, mut f) = following();
        let at = Point::new(0, 300);
        // Free for 150 mm: it would end 2,850 mm off, not 100 nearer than
        // the 2,950 the rover has come to. Follow on.
        let v = f.decide(&cfg, &WALL_LEFT, at, 2_950, Angle::ZERO, 150);
        assert_eq!(v, FollowVerdict::Hug);
        // Free for 300 mm, ending at 2,650: leave, and seek.
        let v = f.decide(&cfg, &WALL_LEFT, at, 2_950, Angle::ZERO, 300);
        assert_eq!(v, FollowVerdict::Seek(Angle::ZERO, FOLLOW_STEP_MM));
        assert!(f.active() && !f.following());
    }

    #[test]
    fn past_the_nearest_point_with_the_goal_beside_it_looks() {
        let (cfg, mut f) = following();
        let beside = Angle::from_deg(90);
        // Nearer and nearer, the goal outside the sector: follow on.
        for (y, d) in [(100, 2_950), (200, 2_900)] {
            let v = f.decide(&cfg, &WALL_LEFT, Point::new(0, y), d, beside, 0);
            assert_eq!(v, FollowVerdict::Hug);
        }
        // Farther again: the last point was the nearest, look (a turn
        // towards the goal, to the sector's edge, on the spot).
        let v = f.decide(&cfg, &WALL_LEFT, Point::new(0, 300), 2_920, beside, 0);
        assert_eq!(v, FollowVerdict::Seek(cfg.sector_half_width(), 0));
        // The way blocked, no nearer: the same boundary, the same hit.
        let v = f.decide(&cfg, &WALL_LEFT, Point::new(0, 300), 2_920, Angle::ZERO, 0);
        assert_eq!(v, FollowVerdict::Hug);
        assert_eq!(f.hit(), Some(P0));
    }

    #[test]
    fn a_loop_round_the_boundary_reports_unreachable() {
        let (cfg, mut f) = following();
        // Round a square of 2 m, the boundary in sight, the goal's way
        // never free, never nearer.
        let track = [(700, 0), (2_000, 0), (2_000, 2_000), (0, 2_000), (0, 700)];
        for (x, y) in track {
            let v = f.decide(&cfg, &WALL_LEFT, Point::new(x, y), 3_000, Angle::ZERO, 0);
            assert_eq!(v, FollowVerdict::Hug, "at ({x}, {y})");
        }
        let v = f.decide(&cfg, &WALL_LEFT, Point::new(0, 250), 3_000, Angle::ZERO, 0);
        assert_eq!(v, FollowVerdict::Looped);
        assert!(!f.active());
    }

    #[test]
    fn out_of_a_dead_end_and_back_past_the_hit_point_is_no_loop() {
        let (cfg, mut f) = following();
        // Up a dead end beside the hit point and back down the same way.
        for (x, y) in [(0, 400), (0, 800), (100, 800), (100, 400), (100, 250)] {
            let v = f.decide(&cfg, &WALL_LEFT, Point::new(x, y), 3_000, Angle::ZERO, 0);
            assert_eq!(v, FollowVerdict::Hug, "at ({x}, {y})");
        }
        // On along the boundary, round it and back from the other side.
        let track = [
            (400, 0),
            (2_000, 0),
            (2_000, -2_000),
            (-1_000, -2_000),
            (-1_000, 0),
        ];
        for (x, y) in track {
            let v = f.decide(&cfg, &WALL_LEFT, Point::new(x, y), 3_000, Angle::ZERO, 0);
            assert_eq!(v, FollowVerdict::Hug, "at ({x}, {y})");
        }
        let v = f.decide(&cfg, &WALL_LEFT, Point::new(-250, 0), 3_000, Angle::ZERO, 0);
        assert_eq!(v, FollowVerdict::Looped);
    }

    /// A track out of the hit point's radius towards −y, round, and back
    /// into it 87° from the way out, both offsets on the hit point's −x
    /// side (as a track that passes it some way off): the verdict on
    /// coming back.
    fn passing_off_to_one_side(cfg: &Config) -> FollowVerdict {
        let mut f = Follow::default();
        f.start(false);
        assert_eq!(
            f.decide(cfg, &WALL_LEFT, P0, 3_000, Angle::ZERO, 100),
            FollowVerdict::Hug
        );
        let track = [
            (-150, -200),
            (-250, -300),
            (-250, -2_000),
            (-2_000, -2_000),
            (-2_000, 0),
        ];
        for (x, y) in track {
            let v = f.decide(cfg, &WALL_LEFT, Point::new(x, y), 3_000, Angle::ZERO, 0);
            assert_eq!(v, FollowVerdict::Hug, "at ({x}, {y})");
        }
        // (-250, -300) left the radius; back at (-200, 150), 87° from it
        // (their dot product positive).
        let back = Point::new(-200, 150);
        f.decide(cfg, &WALL_LEFT, back, 3_000, Angle::ZERO, 0)
    }

    #[test]
    #[cfg(feature = "set-back")]
    fn with_the_sensors_set_back_a_loop_closes_past_60_degrees() {
        let set_back = ConfigBuilder::new(AdcProfile::AVR_10BIT_5V)
            .sensors_set_back(true)
            .build()
            .unwrap();
        assert!(set_back.sensors_set_back());
        assert_eq!(passing_off_to_one_side(&set_back), FollowVerdict::Looped);
        // On the rim, 90°: not yet.
        assert_eq!(passing_off_to_one_side(&cfg()), FollowVerdict::Hug);
    }

    #[test]
    fn back_at_the_hit_point_by_seeking_is_no_loop() {
        let (cfg, mut f) = following();
        for x in [400, 1_500] {
            let v = f.decide(&cfg, &WALL_LEFT, Point::new(x, 0), 3_000, Angle::ZERO, 0);
            assert_eq!(v, FollowVerdict::Hug);
        }
        // The way to the goal free far enough: leave, and seek round to
        // the other side of the hit point (as out of a U and back in).
        let v = f.decide(
            &cfg,
            &WALL_LEFT,
            Point::new(1_500, 0),
            3_000,
            Angle::ZERO,
            760,
        );
        assert_eq!(v, FollowVerdict::Seek(Angle::ZERO, FOLLOW_STEP_MM));
        for (x, y) in [(1_000, 600), (0, 700), (-250, 100)] {
            let v = f.decide(&cfg, &CLEAR, Point::new(x, y), 3_000, Angle::ZERO, 760);
            assert_eq!(v, FollowVerdict::Seek(Angle::ZERO, FOLLOW_STEP_MM));
        }
        // Blocked beside the hit point, no nearer: follow on from it. Not
        // round the boundary, so no loop.
        for y in [100, 50] {
            let v = f.decide(&cfg, &WALL_LEFT, Point::new(-250, y), 3_000, Angle::ZERO, 0);
            assert_eq!(v, FollowVerdict::Hug, "at (-250, {y})");
        }
        assert_eq!(f.hit(), Some(P0));
    }

    #[test]
    fn near_the_hit_point_before_going_away_is_no_loop() {
        let (cfg, mut f) = following();
        for y in [100, 200, 300, 200, 100, 0] {
            let v = f.decide(&cfg, &WALL_LEFT, Point::new(0, y), 3_000, Angle::ZERO, 0);
            assert_eq!(v, FollowVerdict::Hug);
        }
    }

    #[test]
    fn a_boundary_out_of_sight_is_lost_and_met_again() {
        let (cfg, mut f) = following();
        let at = Point::new(900, 0);
        for _ in 1..LOST_CYCLES {
            let v = f.decide(&cfg, &CLEAR, at, 3_000, Angle::ZERO, 0);
            assert_eq!(v, FollowVerdict::Hug);
        }
        // Lost: seek. The way to the goal blocked, no nearer: the same
        // boundary, from the same hit point.
        let v = f.decide(&cfg, &CLEAR, at, 3_000, Angle::ZERO, 0);
        assert_eq!(v, FollowVerdict::Hug);
        assert_eq!(f.hit(), Some(P0));
        // Lost again, and blocked 100 mm nearer than ever: a new hit point.
        for _ in 1..LOST_CYCLES {
            f.decide(&cfg, &CLEAR, at, 3_000, Angle::ZERO, 0);
        }
        let near = Point::new(900, 100);
        let v = f.decide(&cfg, &CLEAR, near, 2_900, Angle::ZERO, 0);
        assert_eq!(v, FollowVerdict::Hug);
        assert_eq!(f.hit(), Some(near));
    }

    /// Meet a boundary and follow it, never closing a loop: the verdict is
    /// `Hug` for `budget` cycles after the hit and `GiveUp` the next.
    fn gives_up_after(second: bool, budget: u16) {
        let cfg = cfg();
        let mut f = Follow::default();
        f.start(second);
        assert_eq!(
            f.decide(&cfg, &WALL_LEFT, P0, 3_000, Angle::ZERO, 100),
            FollowVerdict::Hug
        );
        let mut verdicts = (1..=budget).map(|i| {
            let x = 700 + (i % 2) as i16 * 10;
            f.decide(&cfg, &WALL_LEFT, Point::new(x, 0), 3_000, Angle::ZERO, 0)
        });
        assert!(verdicts.all(|v| v == FollowVerdict::Hug));
        let v = f.decide(&cfg, &WALL_LEFT, Point::new(700, 0), 3_000, Angle::ZERO, 0);
        assert_eq!(v, FollowVerdict::GiveUp);
    }

    #[test]
    fn the_budget_ends_a_boundary_that_never_closes() {
        gives_up_after(false, cfg().escape.give_up_steps * BUDGET_GIVE_UPS);
    }

    #[test]
    fn the_second_round_has_the_shorter_budget() {
        gives_up_after(true, cfg().escape.give_up_steps * SECOND_GIVE_UPS);
    }
}
