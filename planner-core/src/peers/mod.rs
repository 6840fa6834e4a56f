//! The classic sensor-based planners a roboticist would pick instead of
//! EAPF for a range-sensor rover, on the same five IR beams: [`bug2`]
//! (Lumelsky & Stepanov 1987), [`tangent_bug`] (Kamon, Rivlin & Rimon
//! 1998) and [`vfh`] (VFH+, Ulrich & Borenstein 1998). They set the bar
//! the product planner is measured against (docs/results.md).
//!
//! Each one is a [`Navigator`]: the pose and the five raw counts in, a
//! heading, a step and a status out, and the same guard during the
//! advance. What they share lives here, so that the comparison is of
//! decisions, not of sensing or safety:
//!
//! - [`Senses`]: counts to readings (the per-sensor calibration and the
//!   fold-back filter), the safety rule's free way (the beams, and the
//!   points the beams saw near the rover in the cycles and advances before,
//!   [`Seen`], where the five beams of a turned view cannot look;
//!   [`command::free_way_mm`]), the command, and the guard. A translation is only ever commanded within the sensed sector
//!   (±40°) and never beyond the free way; a heading outside the sector is
//!   a turn on the spot, and the next cycle looks along it.
//! - [`hug`]: following a boundary on one side with five forward beams.
//! - [`HitLoop`]: "back at the hit point": the Bug family's proof that the
//!   goal is unreachable.

pub mod apf;
pub mod bug2;
pub mod freespace;
pub mod tangent_bug;
pub mod vfh;

pub use bug2::Bug2;
pub use tangent_bug::TangentBug;
pub use vfh::Vfh;

use crate::eapf::command::{self, Command, Guard, Output, Status};
use crate::eapf::config::Config;
use crate::eapf::sensors::{FoldBackFilter, RawCounts, Reading, Readings, SENSOR_COUNT};
use crate::fixed::{box_within, within, Angle, Dir, Point};
use crate::{Navigator, Planner, Pose};

/// A heading is taken while following a boundary if its way is free this
/// far, mm.
pub const HUG_FREE_MM: u16 = 250;
/// The longest step along a boundary, mm: short enough that a corner does
/// not go by unseen.
pub const HUG_STEP_MM: u16 = 200;
/// The longest step along a boundary out of sight after a whole turn of
/// looks found nothing, mm.
pub const HUG_LOST_STEP_MM: u16 = 100;
/// The longest step in free space, mm (the free way bounds it further).
pub const FREE_STEP_MM: u16 = 400;
/// A rover within this of where it was told to step from (mm, either axis)
/// has not stepped: the guard refused the step.
const SPOT_MM: u16 = 5;

/// The sensing, safety rule and guard every peer shares.
#[derive(Clone, Debug)]
pub struct Senses {
    config: Config,
    fold_back: FoldBackFilter,
    seen: Seen,
    /// The heading and length of the step in progress.
    heading: Angle,
    step_mm: u16,
    /// Where the last step was commanded from (`None`: it was a turn).
    stepped_from: Option<Point>,
    /// Guard refusals in a row: steps commanded that did not move the
    /// rover (see [`Senses::refused`]).
    refused: u8,
    /// Looks on the spot in a row towards a boundary out of sight (see
    /// [`hug`]).
    looks: u8,
    /// This cycle's readings.
    readings: Readings,
}

impl Senses {
    /// Sensing with the rover's `config`.
    pub fn new(config: Config) -> Senses {
        Senses {
            config,
            fold_back: FoldBackFilter::default(),
            seen: Seen::default(),
            heading: Angle::ZERO,
            step_mm: 0,
            stepped_from: None,
            refused: 0,
            looks: 0,
            readings: [Reading::Clear; SENSOR_COUNT],
        }
    }

    /// The configuration.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// This cycle's readings (after [`Senses::read`]).
    pub fn readings(&self) -> &Readings {
        &self.readings
    }

    /// Start a cycle at `pose` with `raw` counts: the readings, and whether
    /// the last step was refused. `None` when a reading is implausible (a
    /// sensor fault: stop).
    pub fn read(&mut self, pose: Pose, raw: &RawCounts) -> Option<&Readings> {
        let refused = self
            .stepped_from
            .is_some_and(|from| box_within(from, pose.position, SPOT_MM));
        if refused {
            self.refused = self.refused.saturating_add(1);
        } else if self.stepped_from.is_some() {
            self.refused = 0;
        }
        self.fold_back
            .look(pose.heading, &self.config.sensor_angles, false);
        let mut readings = Planner::readings_with(&self.config, raw);
        for (i, r) in readings.iter_mut().enumerate() {
            *r = self.fold_back.filter(i, *r);
        }
        self.readings = readings;
        self.seen
            .look(&self.config, pose.position, pose.heading, &readings);
        (!readings.contains(&Reading::Implausible)).then_some(&self.readings)
    }

    /// Steps in a row that the guard refused before they began (the view
    /// after the turn saw the way blocked that the view before showed
    /// free).
    pub fn refused(&self) -> u8 {
        self.refused
    }

    /// Whether `relative` (robot frame) is inside the sensed sector.
    pub fn in_sector(&self, relative: Angle) -> bool {
        relative.abs_signed() <= self.config.sector_half_width().0
    }

    /// How far the rover at `pose` may advance along `relative`: the
    /// safety rule's free way from this cycle's readings and the guard's
    /// flank points; 0 outside the sensed sector.
    pub fn free_mm(&self, pose: Pose, relative: Angle) -> u16 {
        if !self.in_sector(relative) {
            return 0;
        }
        let points = self.seen.points.as_slice();
        let flank = (!points.is_empty()).then(|| (pose.position, Dir::of(pose.heading), points));
        command::free_way_mm(&self.config, &self.readings, flank, relative)
    }

    /// The cycle's command: turn by `relative`, then advance `step_mm`,
    /// bounded by the free way (nothing outside the sector).
    pub fn command(&mut self, pose: Pose, relative: Angle, step_mm: u16) -> Output {
        let step = step_mm.min(self.free_mm(pose, relative));
        let step = if step < self.config.min_step_mm {
            0
        } else {
            step
        };
        let heading = pose.heading.add(relative);
        self.stepped_from = (step > 0).then_some(pose.position);
        self.heading = heading;
        self.step_mm = step;
        Output {
            command: Command {
                heading,
                step_mm: step,
            },
            status: Status::Moving,
        }
    }

    /// Stay put with `status`.
    pub fn stop(&mut self, pose: Pose, status: Status) -> Output {
        self.stepped_from = None;
        Output::stop(pose.heading, status)
    }

    /// The guard during an advance (the product planner's rule): stop when
    /// fresh readings no longer show the rest of the step free. What the
    /// beams see near the way is kept ([`Seen`]).
    pub fn guard(&mut self, raw: &RawCounts, remaining_mm: u16) -> Guard {
        let readings = Planner::readings_with(&self.config, raw);
        if let Some(from) = self.stepped_from {
            let done = self.step_mm.saturating_sub(remaining_mm);
            let at = from.offset(self.heading, done);
            self.seen.look(&self.config, at, self.heading, &readings);
        }
        command::guard(&self.config, &readings, remaining_mm)
    }

    /// The bearing of `goal` from `pose` (relative to its heading) and the
    /// distance, mm.
    pub fn goal(&self, pose: Pose, goal: Point) -> (Angle, u16) {
        let (dx, dy) = pose.position.to(goal);
        (
            Angle::atan2(dy, dx).sub(pose.heading),
            pose.position.distance_mm(goal),
        )
    }

    /// Where beam `i` ends, seen from `pose`: on the obstacle it reads (at
    /// the sensor face for "too close"), or at its reach; and whether it
    /// met an obstacle.
    pub fn beam_end(&self, pose: Pose, i: usize) -> (Point, bool) {
        let cfg = &self.config;
        let i = i.min(SENSOR_COUNT - 1);
        let (far, hit) = match self.readings[i] {
            Reading::Range(mm) => (cfg.sensor_offset_mm.saturating_add(mm), true),
            Reading::Clear => (cfg.sensor_offset_mm + cfg.sensor_range_mm, false),
            Reading::TooClose | Reading::Implausible => (cfg.sensor_offset_mm, true),
        };
        (
            pose.position
                .offset(pose.heading.add(cfg.sensor_angles[i]), far),
            hit,
        )
    }
}

/// How many points [`Seen`] keeps.
pub const SEEN_POINTS: usize = 12;
/// Beam points within this of the rover (mm, either axis) are kept, and
/// forgotten once it is this far from them: beyond it a new view's beams
/// see the ground again.
const SEEN_REACH_MM: u16 = 320;
/// A point within this of a kept one (mm, either axis) replaces it: a beam
/// sliding along a face leaves the last point it saw of it.
const SEEN_MERGE_MM: u16 = 40;

/// The points the beams saw near the rover, in the planner's views and
/// the guard's, world mm. The five beams cover ±40°: after a turn the
/// body's first centimetres sweep ground beside it that no beam of the new
/// view sees. The safety rule keeps the disc off these points too (the
/// product planner's [`command::Flank`] is the same idea).
#[derive(Clone, Debug, Default)]
pub struct Seen {
    points: heapless::Vec<Point, SEEN_POINTS>,
}

impl Seen {
    /// The kept points.
    pub fn points(&self) -> &[Point] {
        &self.points
    }

    /// A view from `at` facing `heading`: forget what is now out of reach,
    /// keep what the beams read near.
    pub fn look(&mut self, cfg: &Config, at: Point, heading: Angle, readings: &Readings) {
        self.points.retain(|&p| box_within(p, at, SEEN_REACH_MM));
        for (i, &r) in readings.iter().enumerate() {
            let Reading::Range(mm) = r else { continue };
            let angle = cfg.sensor_angles[i.min(SENSOR_COUNT - 1)];
            let p = at.offset(heading.add(angle), cfg.sensor_offset_mm.saturating_add(mm));
            if !box_within(p, at, SEEN_REACH_MM) {
                continue;
            }
            command::keep_near(&mut self.points, p, at, SEEN_MERGE_MM);
        }
    }
}

/// The side a boundary is kept on while following it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// The boundary on the left: round it clockwise.
    Left,
    /// The boundary on the right: round it counter-clockwise.
    Right,
}

impl Side {
    /// The side an opening at `relative` leaves the boundary on: going
    /// round by the left keeps it on the right.
    pub fn passing(relative: Angle) -> Side {
        if relative.signed() >= 0 {
            Side::Right
        } else {
            Side::Left
        }
    }
}

/// One step of boundary following with five forward beams, the boundary
/// kept on `side`. Of the beams' headings from that side's edge of the
/// sector to the other's, take the first whose way is free for
/// [`HUG_FREE_MM`] *past a blocked one*: what blocks is then passed on the
/// boundary's side, whichever beam sees it (taking the first free heading
/// from the edge instead turns the rover away from a boundary that is
/// ahead, round a circle back to where it met it). With no free heading
/// past the blocked ones (what blocks is on the other side, or
/// everywhere), a turn on the spot away from the boundary by the sector's
/// width, which brings it to the boundary's side. Each step the guard
/// refused before it began passes over one more free heading (the view
/// after the turn saw what the view before did not).
///
/// With nothing blocked the boundary is out of sight, beside or behind
/// the rover (round a convex corner, a wall's end): a turn on the spot
/// towards it by the sector's half width, a look, since a step along the
/// turned heading would sweep the body's flank over ground no beam has
/// seen (the blind flank). After as many turns on the spot in a row as
/// make a whole turn of looks, a short step along the boundary's edge of
/// the sector instead (a corner where the view flips between "all
/// blocked" and "nothing in sight" would hold the rover for ever).
///
/// Returns the turn and the step.
pub fn hug(senses: &mut Senses, pose: Pose, side: Side) -> (Angle, u16) {
    let cfg = senses.config();
    let mut turns = cfg.sensor_angles;
    if side == Side::Left {
        turns.reverse();
    }
    let half = cfg.sector_half_width();
    let skip = (senses.refused() as usize).min(SENSOR_COUNT - 1);
    let ways = turns.map(|t| (t, senses.free_mm(pose, t)));
    let free = |&(_, way): &(Angle, u16)| way >= HUG_FREE_MM;
    let whole_turn = 65_536u32.div_ceil(half.0.max(1) as u32) as u8;
    let (turn, step) = if ways.iter().all(free) {
        if senses.looks < whole_turn {
            (ways[0].0, 0)
        } else {
            (ways[0].0, ways[0].1.min(HUG_LOST_STEP_MM))
        }
    } else {
        let found = ways
            .iter()
            .skip_while(|w| free(w))
            .filter(|w| free(w))
            .nth(skip);
        match found {
            Some(&(turn, way)) => (turn, way.min(HUG_STEP_MM)),
            None => {
                let away = half.add(half);
                (if side == Side::Left { away.neg() } else { away }, 0)
            }
        }
    };
    senses.looks = if step == 0 {
        senses.looks.saturating_add(1)
    } else {
        0
    };
    (turn, step)
}

/// The Bug family's test that a boundary has been followed all round:
/// after going more than [`HitLoop::AWAY_MM`] from the hit point, the
/// rover comes back within [`HitLoop::BACK_MM`] of it from the other side
/// than it left by (the offsets from the hit point on leaving and on
/// coming back more than 90° apart). Round a boundary the rover comes back
/// from the side opposite the one it left by; out of a pocket beside the
/// hit point, among obstacles the five beams lose and find again, it comes
/// back the way it went.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HitLoop {
    /// Where the boundary was met.
    pub hit: Point,
    away: bool,
    near: bool,
    /// The offset from the hit point when the rover first left its radius.
    out: Option<(i32, i32)>,
    /// Cycles since the hit.
    cycles: u16,
}

impl HitLoop {
    /// Back at the hit point: within this, mm (a step along a boundary is
    /// at most [`HUG_STEP_MM`], so the track cannot jump over the disc).
    pub const BACK_MM: u16 = 250;
    /// Away from the hit point: beyond this, mm.
    pub const AWAY_MM: u16 = 600;
    /// Ours: a boundary followed this many cycles from one hit point is
    /// taken as gone round. Among obstacles the five beams lose and find
    /// again the rover can come round a loop that does not pass the hit
    /// point (another cluster beside the boundary it met), where the
    /// papers' test never closes; this bounds it (the product's follower
    /// has the same safety net).
    pub const BUDGET_CYCLES: u16 = 1_000;

    /// A boundary met at `hit`.
    pub fn new(hit: Point) -> HitLoop {
        HitLoop {
            hit,
            away: false,
            near: true,
            out: None,
            cycles: 0,
        }
    }

    /// The rover is at `robot`: has it come back round (into the hit
    /// point's radius, from the other side)?
    pub fn closed(&mut self, robot: Point) -> bool {
        self.update(robot).1
    }

    /// Whether [`HitLoop::BUDGET_CYCLES`] have passed since the hit.
    pub fn spent(&self) -> bool {
        self.cycles > Self::BUDGET_CYCLES
    }

    /// The rover is at `robot`: is it back within the hit point's radius
    /// after going away, and has it come back round (just entered it from
    /// the other side)?
    pub fn update(&mut self, robot: Point) -> (bool, bool) {
        self.cycles = self.cycles.saturating_add(1);
        let near = within(self.hit, robot, Self::BACK_MM);
        let (x, y) = self.hit.to(robot);
        let entered = near && !self.near;
        if self.near && !near && self.out.is_none() {
            self.out = Some((x, y));
        }
        self.near = near;
        if !self.away {
            self.away = !within(self.hit, robot, Self::AWAY_MM);
            return (false, false);
        }
        // Offsets are within the arena (16-bit mm each): the products fit
        // an i64.
        let round = entered
            && self
                .out
                .is_some_and(|(ox, oy)| ox as i64 * x as i64 + oy as i64 * y as i64 <= 0);
        (near, round)
    }
}

/// The shared part of every peer's cycle: read the sensors, stop on a
/// sensor fault or at the goal.
pub(crate) fn begin(
    senses: &mut Senses,
    pose: Pose,
    raw: &RawCounts,
    goal: Point,
) -> Result<(), Output> {
    if senses.read(pose, raw).is_none() {
        return Err(senses.stop(pose, Status::SensorFault));
    }
    if pose.position.distance_mm(goal) <= senses.config().goal_tolerance_mm() {
        return Err(senses.stop(pose, Status::Arrived));
    }
    Ok(())
}

macro_rules! navigator {
    ($t:ty) => {
        impl Navigator for $t {
            fn step_raw(&mut self, pose: Pose, raw: &RawCounts) -> Output {
                <$t>::step_raw(self, pose, raw)
            }
            fn guard_raw(&mut self, raw: &RawCounts, remaining_mm: u16) -> Guard {
                self.senses.guard(raw, remaining_mm)
            }
            fn config(&self) -> &Config {
                self.senses.config()
            }
        }
    };
}
navigator!(Bug2);
navigator!(TangentBug);
navigator!(Vfh);

impl<const N: usize> Navigator for freespace::FreeSpace<N> {
    fn step_raw(&mut self, pose: Pose, raw: &RawCounts) -> Output {
        freespace::FreeSpace::step_raw(self, pose, raw)
    }
    fn guard_raw(&mut self, raw: &RawCounts, remaining_mm: u16) -> Guard {
        self.senses.guard(raw, remaining_mm)
    }
    fn config(&self) -> &Config {
        self.senses.config()
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::eapf::config::test_config;

    /// Counts that read `mm` from the face on every sensor (`None`: clear).
    pub fn counts(cfg: &Config, mm: [Option<u16>; SENSOR_COUNT]) -> RawCounts {
        let mut raw = [0; SENSOR_COUNT];
        let cal = cfg.calibration();
        for (i, want) in mm.iter().enumerate() {
            raw[i] = (0..cal.full_scale())
                .find(|&c| match (want, cal.reading(c)) {
                    (None, Reading::Clear) => true,
                    (Some(w), Reading::Range(r)) => r <= *w,
                    _ => false,
                })
                .unwrap();
        }
        raw
    }

    #[test]
    fn hug_turns_towards_the_boundary_until_the_way_is_blocked() {
        let cfg = test_config();
        let mut s = Senses::new(cfg);
        let pose = Pose::default();
        // A wall on the left: the left beams read 150 mm, the others clear.
        let raw = counts(&cfg, [None, None, None, Some(150), Some(150)]);
        s.read(pose, &raw).unwrap();
        // Boundary kept on the left: the first free heading from the left
        // edge, every heading left of it blocked.
        let (turn, step) = hug(&mut s, pose, Side::Left);
        assert!(turn.signed() <= 0, "{turn:?}");
        assert!(s.free_mm(pose, turn) >= HUG_FREE_MM);
        assert_eq!(step, s.free_mm(pose, turn).min(HUG_STEP_MM));
        for left in cfg
            .sensor_angles()
            .iter()
            .filter(|a| a.signed() > turn.signed())
        {
            assert!(s.free_mm(pose, *left) < HUG_FREE_MM, "{left:?}");
        }
        // Boundary kept on the right, what blocks on the left: a turn on
        // the spot to the left, which brings it to the right.
        assert_eq!(hug(&mut s, pose, Side::Right), (Angle::from_deg(80), 0));
        // Nothing in sight: a look towards the lost boundary, on the spot;
        // after a whole turn of them (nine of 40°), a short step.
        let mut lost = Senses::new(cfg);
        lost.read(pose, &counts(&cfg, [None; SENSOR_COUNT]))
            .unwrap();
        for _ in 0..9 {
            assert_eq!(hug(&mut lost, pose, Side::Right), (Angle::from_deg(-40), 0));
        }
        assert_eq!(
            hug(&mut lost, pose, Side::Right),
            (Angle::from_deg(-40), HUG_LOST_STEP_MM)
        );
        // Everything blocked: turn on the spot away from the boundary.
        let raw = counts(&cfg, [Some(120); SENSOR_COUNT]);
        s.read(pose, &raw).unwrap();
        assert_eq!(hug(&mut s, pose, Side::Left), (Angle::from_deg(-80), 0));
    }

    #[test]
    fn a_hit_loop_closes_only_coming_back_round() {
        let mut l = HitLoop::new(Point::new(0, 0));
        assert!(!l.closed(Point::new(100, 0)));
        assert!(!l.closed(Point::new(500, 0)), "left by +x");
        assert!(!l.closed(Point::new(100, 0)), "not yet away");
        assert!(!l.closed(Point::new(700, 0)));
        assert!(!l.closed(Point::new(700, 700)));
        // Back the way it went: a pocket beside the hit point.
        assert!(!l.closed(Point::new(200, 50)));
        assert!(!l.closed(Point::new(300, 600)));
        assert!(!l.closed(Point::new(-400, 300)));
        // Back from the other side: round the boundary.
        assert!(l.closed(Point::new(-200, 0)));
    }

    #[test]
    fn no_translation_outside_the_sector() {
        let cfg = test_config();
        let mut s = Senses::new(cfg);
        let pose = Pose::default();
        s.read(pose, &counts(&cfg, [None; SENSOR_COUNT])).unwrap();
        let out = s.command(pose, Angle::from_deg(90), 300);
        assert_eq!(out.command.step_mm, 0);
        assert_eq!(out.command.heading, Angle::from_deg(90));
        let out = s.command(pose, Angle::ZERO, 300);
        assert_eq!(out.command.step_mm, 300);
    }
}
