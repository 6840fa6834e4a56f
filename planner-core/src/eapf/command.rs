//! What the planner tells the executor each cycle, and the safety rule that
//! bounds it (docs/algorithms.md §5): a commanded translation never enters space
//! that the current readings do not show free, allowing for the robot radius
//! and a clearance margin; during the advance the executor calls the guard
//! with fresh readings and stops short if something appears. Ours: the
//! guard also keeps what its beams saw beside the way ([`Flank`]), and the
//! next steps keep the body off it, where the five beams of a turned view
//! cannot look.

use crate::eapf::config::Config;
use crate::eapf::forces::sensor_direction;
use crate::eapf::sensors::{Reading, Readings, SENSOR_COUNT};
use crate::fixed::{box_within, isqrt, mul_q14, Angle, Dir, Point};

/// One cycle's command: turn in place to `heading` (world frame), then
/// advance `step_mm` straight ahead.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Command {
    /// Heading to turn to, world frame.
    pub heading: Angle,
    /// Distance to advance after the turn, mm (0: turn only).
    pub step_mm: u16,
}

/// The planner's status.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Status {
    /// On the way.
    Moving,
    /// Within the goal tolerance; the step is zero.
    Arrived,
    /// Escape made no progress within its budget and boundary following
    /// (`follow`) went all round the boundary, or ran out of its budget,
    /// without a way nearer the goal (or escape alone gave up, with
    /// `EscapeConfig::follow` off): stop, the goal cannot be reached. The
    /// step is zero.
    Unreachable,
    /// A sensor gave a reading it cannot produce, or its count stayed the
    /// same over views in which a working sensor's would have changed
    /// ([`crate::eapf::sensors::FreezeWatch`]): stop (the step is zero).
    SensorFault,
}

impl Status {
    /// One-byte code for links and logs: 0 moving, 1 arrived,
    /// 2 unreachable, 3 sensor fault.
    pub fn code(self) -> u8 {
        match self {
            Status::Moving => 0,
            Status::Arrived => 1,
            Status::Unreachable => 2,
            Status::SensorFault => 3,
        }
    }

    /// The status of a [`Status::code`]; `None` for any other byte.
    pub fn from_code(code: u8) -> Option<Status> {
        match code {
            0 => Some(Status::Moving),
            1 => Some(Status::Arrived),
            2 => Some(Status::Unreachable),
            3 => Some(Status::SensorFault),
            _ => None,
        }
    }

    /// Its letter in the telemetry line (`crate::rover::protocol`): `M`
    /// moving, `A` arrived, `U` unreachable, `F` sensor fault.
    pub fn letter(self) -> u8 {
        match self {
            Status::Moving => b'M',
            Status::Arrived => b'A',
            Status::Unreachable => b'U',
            Status::SensorFault => b'F',
        }
    }

    /// The status of a [`Status::letter`]; `None` for any other byte.
    pub fn from_letter(letter: u8) -> Option<Status> {
        [
            Status::Moving,
            Status::Arrived,
            Status::Unreachable,
            Status::SensorFault,
        ]
        .into_iter()
        .find(|s| s.letter() == letter)
    }
}

/// A rule of the step that an [`Output`] broke ([`Output::broken_rule`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BrokenRule {
    /// The step is longer than the sensors' range.
    BeyondRange,
    /// A heading outside the sensed sector with a step: only a turn may
    /// face where no beam looked.
    UnsensedStep,
    /// The step enters space the readings it was planned from do not show
    /// free (the safety rule, docs/algorithms.md §5).
    NotFree,
    /// A step planned from an implausible reading (a sensor fault).
    OnAFault,
    /// A step with a status other than moving: every stop is a zero step.
    StopWithStep,
}

/// The planner's output for one cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Output {
    /// What to do.
    pub command: Command,
    /// Why.
    pub status: Status,
}

impl Output {
    /// The first rule of the step this output breaks, planned at `pose`
    /// from `readings` with `cfg`; `None` when it keeps them all. The
    /// property tests and the fuzz target hold every planner to it.
    pub fn broken_rule(
        self,
        cfg: &Config,
        readings: &Readings,
        pose: crate::Pose,
    ) -> Option<BrokenRule> {
        let step = self.command.step_mm;
        let rel = self.command.heading.sub(pose.heading);
        if step > cfg.sensor_range_mm() {
            Some(BrokenRule::BeyondRange)
        } else if step == 0 {
            None
        } else if self.status != Status::Moving {
            Some(BrokenRule::StopWithStep)
        } else if rel.abs_signed() > cfg.sector_half_width().0 {
            Some(BrokenRule::UnsensedStep)
        } else if readings.contains(&Reading::Implausible) {
            Some(BrokenRule::OnAFault)
        } else if step > free_distance_mm(cfg, readings, rel) {
            Some(BrokenRule::NotFree)
        } else {
            None
        }
    }

    /// Stay put, facing `heading`, with `status`.
    #[cfg_attr(target_arch = "avr", inline(never))]
    pub fn stop(heading: Angle, status: Status) -> Output {
        Output {
            command: Command {
                heading,
                step_mm: 0,
            },
            status,
        }
    }
}

/// The guard's answer during an advance.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Guard {
    /// The rest of the step is still free.
    Continue,
    /// Something appeared: stop now.
    Stop,
}

/// How far the robot may advance along `relative` (robot frame, 0 = straight
/// ahead) before its disc, widened by the clearance, would touch the end of
/// a beam: an obstacle a sensor sees, or the far end of what a clear sensor
/// has seen free. Readings that are not trusted count as an obstacle at the
/// sensor face. Never more than the front sensor's reach minus the disc.
///
/// Stand-off: an obstacle in the corridor is also kept `standoff_mm` beyond
/// the rim ahead (by default the sensors' minimum range: sensors on the rim
/// then never have an obstacle driven into the fold-back region, where it
/// would read as far; set back, it keeps the body as far off).
pub fn free_distance_mm(cfg: &Config, readings: &Readings, relative: Angle) -> u16 {
    free_way_mm(cfg, readings, None, relative)
}

/// [`free_distance_mm`], and the disc, widened by a 20 mm margin only (by
/// the clearance with the sensors set back), kept off the flank points (see
/// [`Flank`]):
/// `flank` is the robot's position and heading and the points (world mm).
pub fn free_way_mm(
    cfg: &Config,
    readings: &Readings,
    flank: Option<(Point, Dir, &[Point])>,
    relative: Angle,
) -> u16 {
    let rs = (cfg.robot_radius_mm + cfg.clearance_mm) as i32;
    let reach = (cfg.sensor_offset_mm + cfg.sensor_range_mm) as i32;
    let standoff = (cfg.robot_radius_mm + cfg.standoff_mm) as i32;
    // The usual headings are a sensor's (straight ahead, a sector edge):
    // their sine and cosine are in the config already.
    let dir = match cfg.sensor_angles.iter().position(|&a| a == relative) {
        Some(i) => cfg.sensor_dirs[i.min(SENSOR_COUNT - 1)],
        None => Dir::of(relative),
    };
    let mut free = (reach - rs).max(0);
    for (&r, sensor) in readings.iter().zip(cfg.sensor_dirs.iter()) {
        // A clear beam never lowers `free`: its end is `reach` from the
        // centre at some angle δ from the path, and the disc meets it after
        // reach·cos δ − √(rs² − reach²·sin² δ), which grows with |δ| from
        // its value at δ = 0, reach − rs, where `free` starts.
        let e = match r {
            Reading::Range(mm) => cfg.sensor_offset_mm as i32 + mm as i32,
            Reading::Clear => continue,
            Reading::TooClose | Reading::Implausible => cfg.sensor_offset_mm as i32,
        };
        // The beam end in the robot frame, then in the frame of `relative`:
        // how far along first. The beam lowers `free` only through the
        // stand-off (`along − standoff`) or the chord (at least
        // `along − rs`, the half chord being at most rs): if neither can be
        // below `free`, its side offset is not needed.
        // At most 1,000 + 65,535 (the config's offset limit and a `u16`):
        // within `MAX_SCALED`.
        let (x, y) = sensor.scaled_bounded(e);
        let along = along(x, y, dir);
        if along - standoff.max(rs) >= free {
            continue;
        }
        let lateral = lateral(x, y, dir);
        if lateral.abs() < rs {
            free = free.min((along - standoff).max(0));
            if free == 0 {
                break;
            }
            // The chord can only lower `free` if `along − rs` is below it
            // (the half chord is at most rs): skip the square root otherwise.
            if along - rs < free {
                free = free.min((along - half_chord(rs, lateral)).max(0));
            }
        }
    }
    let Some((robot, heading, points)) = flank else {
        return free as u16;
    };
    // The path's world direction once, rather than each point in the
    // robot's frame.
    let dir = dir.rotated(heading);
    // With the sensors set back, the clearance: with 20 mm the benches met
    // collisions that 40 mm do not (a beam reads one point of a face, and
    // the face reaches on beyond it; the commit history, "Sensors set back").
    let rb = if cfg.set_back() {
        rs
    } else {
        cfg.robot_radius_mm as i32 + FLANK_MARGIN_MM
    };
    for &p in points {
        if free == 0 {
            break;
        }
        // As for the beams: the half chord is at most rb, so only a point
        // with `along − rb` below `free` can lower it.
        let (x, y) = robot.to(p);
        let along = along(x, y, dir);
        if along <= 0 || along - rb >= free {
            continue;
        }
        let lateral = lateral(x, y, dir);
        if lateral.abs() < rb {
            free = free.min((along - half_chord(rb, lateral)).max(0));
        }
    }
    free as u16
}

/// How far along a path along `dir` the point (`x`, `y`) lies.
fn along(x: i32, y: i32, dir: Dir) -> i32 {
    mul_q14(x, dir.cos()) + mul_q14(y, dir.sin())
}

/// How far to the left of a path along `dir` the point (`x`, `y`) lies.
fn lateral(x: i32, y: i32, dir: Dir) -> i32 {
    mul_q14(y, dir.cos()) - mul_q14(x, dir.sin())
}

/// Half the chord a disc of radius `r` cuts from a line `lateral` from
/// its centre (`|lateral| < r`).
fn half_chord(r: i32, lateral: i32) -> i32 {
    isqrt((r * r - lateral * lateral) as u32) as i32
}

/// How many of the guard's flank points the planner keeps (see [`Flank`]).
pub const FLANK_POINTS: usize = 4;

/// Beams' points within this of the advance's line (mm, either side) are
/// flank points: the body passes them closely, and a turn towards them
/// puts them where no beam of the new view looks (see [`Flank`]).
const FLANK_LATERAL_MM: i32 = 170;

/// With the sensors set back, a beam's point within this of the rim (mm) in
/// the planner's own view is a flank point too (see [`Flank::saw_near`]).
#[cfg(feature = "set-back")]
const FLANK_NEAR_MM: u16 = 100;

/// A flank point within this (mm, either axis) of a kept one replaces it:
/// a beam sliding along a face leaves the last point it saw of it.
const FLANK_MERGE_MM: u16 = 40;

/// Flank points farther than this from the rover (mm, either axis) are not
/// kept, and are forgotten as it advances: beyond it the beams of any new
/// view see the ground again.
const FLANK_REACH_MM: u16 = 300;

/// Margin (mm) beyond the robot radius that the step keeps from a flank
/// point with the sensors on the rim: less than the clearance, which would
/// stop the rover beside what it has just passed.
const FLANK_MARGIN_MM: i32 = 20;

/// Ours (the safety rule's blind flank, the commit history "The flank"): the
/// points the guard's beams saw beside the way during the advances, world
/// mm. The five beams cover ±40°; after a turn towards a side the body's
/// first centimetres sweep ground within `r / sin 40°` of the centre that
/// no beam of the new view can see — where the rover has just passed a
/// corner. The beams saw it as the rover approached it, so the step's free
/// distance also keeps the body off these points.
#[derive(Clone, Debug, Default)]
pub struct Flank {
    points: heapless::Vec<Point, FLANK_POINTS>,
    /// The advance in progress: its heading and length (it starts where
    /// the planner's cycle was; `None` while the rover turns in place).
    advance: Option<(Angle, u16)>,
    /// A heading and its direction, kept by the looks: the looks of one
    /// advance share it (on the AVR a sine and a cosine are ~680 cycles of
    /// a look's ~7,700). Keyed by the heading, so that the step need not
    /// forget it.
    kept_dir: Option<(Angle, Dir)>,
    /// Counts the looks that dropped or kept a point (wrapping).
    changes: u8,
}

impl Flank {
    /// The kept points.
    pub fn points(&self) -> &[Point] {
        &self.points
    }

    /// A count that moves on with each look that dropped or kept a point
    /// (wrapping): a look that leaves it where it was changed nothing the
    /// planner keeps, and a replay may skip it.
    pub fn changes(&self) -> u8 {
        self.changes
    }

    /// The cycle commanded `step_mm` along `heading` (0: none).
    #[cfg_attr(target_arch = "avr", inline(never))]
    pub(crate) fn start(&mut self, heading: Angle, step_mm: u16) {
        self.advance = if step_mm > 0 {
            Some((heading, step_mm))
        } else {
            None
        };
    }

    /// The heading of the advance in progress (`None` while turning in
    /// place).
    pub(crate) fn heading(&self) -> Option<Angle> {
        self.advance.map(|(heading, _)| heading)
    }

    /// A guard sample: the advance from `from` has `remaining_mm` to go and
    /// the beams read `readings`; keep the points beside the way.
    #[inline(never)]
    pub(crate) fn saw(
        &mut self,
        cfg: &Config,
        from: Point,
        readings: &Readings,
        remaining_mm: u16,
    ) {
        let Some((heading, step)) = self.advance else {
            return;
        };
        let dir = match self.kept_dir {
            Some((h, dir)) if h == heading => dir,
            _ => {
                let dir = Dir::of(heading);
                self.kept_dir = Some((heading, dir));
                dir
            }
        };
        let centre = from.offset_dir(dir, step.saturating_sub(remaining_mm));
        // Points the rover has left behind: the forgetting is here, where
        // the rover moves, not in the step (a rover turning in place keeps
        // what it has).
        let had = self.points.len();
        self.points
            .retain(|&p| box_within(p, centre, FLANK_REACH_MM));
        if self.points.len() != had {
            self.changes = self.changes.wrapping_add(1);
        }
        for (i, (&r, sensor)) in readings.iter().zip(cfg.sensor_dirs.iter()).enumerate() {
            let Reading::Range(mm) = r else { continue };
            let e = cfg.sensor_offset_mm + mm;
            if mul_q14(sensor.sin(), e as i32).abs() < FLANK_LATERAL_MM {
                // Beyond the reach the rover has yet to pass it; it keeps
                // the nearer sightings as it comes.
                let p = centre.offset_dir(sensor_direction(cfg, dir, i), e);
                if box_within(p, centre, FLANK_REACH_MM) {
                    self.keep(p, centre);
                }
            }
        }
    }

    /// With the sensors set back, the planner's view from `robot` facing
    /// `heading` (its direction): a beam's point within [`FLANK_NEAR_MM`]
    /// of the rim is kept too. Ours: turning back towards the force, the
    /// rover loses sight of what its last view read beside it, and its
    /// disc swept into a post 42 mm off the rim that the view before the
    /// turn had read (barn-tight-243, seed 11, sensors set back). Only
    /// ranged readings: "too close" has no position. The potential
    /// field's step keeps them in its own loop over the collision points,
    /// which places them anyway ([`Flank::saw_point`]).
    #[cfg(feature = "set-back")]
    pub(crate) fn saw_near(
        &mut self,
        cfg: &Config,
        robot: Point,
        heading: Dir,
        readings: &Readings,
    ) {
        for (i, &r) in readings.iter().enumerate() {
            if let Reading::Range(mm) = r {
                let e = cfg.sensor_offset_mm + mm;
                if is_near(cfg, r, e) {
                    let p = robot.offset_dir(sensor_direction(cfg, heading, i), e);
                    self.keep(p, robot);
                }
            }
        }
    }

    /// One beam's point `at`, `distance_mm` from the centre `robot`, read
    /// as `r`: kept as [`Flank::saw_near`] keeps it.
    #[cfg(feature = "set-back")]
    #[cfg_attr(target_arch = "avr", inline(never))]
    pub(crate) fn saw_point(
        &mut self,
        cfg: &Config,
        r: Reading,
        distance_mm: u16,
        at: Point,
        robot: Point,
    ) {
        if is_near(cfg, r, distance_mm) {
            self.keep(at, robot);
        }
    }

    /// Keep `p`, seen with the rover at `centre` ([`keep_near`]).
    fn keep(&mut self, p: Point, centre: Point) {
        keep_near(&mut self.points, p, centre, FLANK_MERGE_MM);
        self.changes = self.changes.wrapping_add(1);
    }
}

/// Keep `p`, seen with the rover at `centre`, among `points`: it replaces
/// a kept point within `merge_mm` of it (a beam sliding along a face
/// leaves the last point it saw of it) or, all places taken, the kept
/// point farthest from the rover if `p` is nearer (the nearest matter: the
/// farthest are the first the rover leaves behind).
pub(crate) fn keep_near<const N: usize>(
    points: &mut heapless::Vec<Point, N>,
    p: Point,
    centre: Point,
    merge_mm: u16,
) {
    if let Some(q) = points.iter_mut().find(|q| box_within(**q, p, merge_mm)) {
        *q = p;
    } else if let Err(p) = points.push(p) {
        let far = |q: &Point| q.x.abs_diff(centre.x).max(q.y.abs_diff(centre.y));
        if let Some(q) = points.iter_mut().max_by_key(|q| far(q)) {
            if far(&p) < far(q) {
                *q = p;
            }
        }
    }
}

/// Whether a reading `r`, `distance_mm` from the centre, is a ranged one
/// within [`FLANK_NEAR_MM`] of the rim (see [`Flank::saw_near`]).
#[cfg(feature = "set-back")]
fn is_near(cfg: &Config, r: Reading, distance_mm: u16) -> bool {
    matches!(r, Reading::Range(_)) && distance_mm <= cfg.robot_radius_mm + FLANK_NEAR_MM
}

/// The guard (§5): with fresh readings taken while advancing, may the robot
/// still cover the `remaining_mm` of its step straight ahead?
pub fn guard(cfg: &Config, readings: &Readings, remaining_mm: u16) -> Guard {
    if readings.contains(&Reading::Implausible) {
        return Guard::Stop;
    }
    if free_distance_mm(cfg, readings, Angle::ZERO) >= remaining_mm {
        Guard::Continue
    } else {
        Guard::Stop
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eapf::config::ConfigBuilder;
    use crate::eapf::sensors::{AdcProfile, SENSOR_COUNT};

    #[test]
    fn status_codes_round_trip() {
        for s in [
            Status::Moving,
            Status::Arrived,
            Status::Unreachable,
            Status::SensorFault,
        ] {
            assert_eq!(Status::from_code(s.code()), Some(s));
            assert_eq!(Status::from_letter(s.letter()), Some(s));
        }
        assert_eq!(Status::from_code(4), None);
        assert_eq!(Status::from_letter(b'X'), None);
        let letters: std::vec::Vec<u8> = (0..4)
            .filter_map(Status::from_code)
            .map(Status::letter)
            .collect();
        assert_eq!(letters, b"MAUF");
    }

    use crate::eapf::config::test_config as cfg;

    #[test]
    fn free_distance_by_hand() {
        // Clearance 20 mm: a 120 mm half-width.
        let c = ConfigBuilder::new(AdcProfile::AVR_10BIT_5V)
            .clearance_mm(20)
            .build()
            .unwrap();
        let clear = [Reading::Clear; SENSOR_COUNT];
        // Nothing seen: front reach 900 − 120 = 780 mm.
        assert_eq!(free_distance_mm(&c, &clear, Angle::ZERO), 780);
        // Front obstacle 300 mm from the face: the disc could go 400 − 120 =
        // 280 mm, the stand-off keeps it 100 mm from the face: 200 mm.
        let mut r = clear;
        r[2] = Reading::Range(300);
        assert_eq!(free_distance_mm(&c, &r, Angle::ZERO), 200);
        let mut r6 = clear;
        r6[2] = Reading::Range(600);
        assert_eq!(free_distance_mm(&c, &r6, Angle::ZERO), 500);
        // Heading 20° right, towards the −20° beam's end (900 mm, clear):
        // 900 − 120 = 780; the front obstacle at 400 mm is 136.8 mm to the
        // side, outside the 120 mm half-width.
        assert_eq!(free_distance_mm(&c, &r, Angle::from_deg(-20)), 780);
        // Heading 10° right: front point lateral 400·sin10° = 69.5,
        // along 393.9, half chord √(120² − 69.5²) = 97.8 → 296; stand-off
        // 393.9 − 200 = 193.9 → 194.
        let got = free_distance_mm(&c, &r, Angle::from_deg(-10));
        assert!((got as i32 - 194).abs() <= 1, "{got}");
        // Too close at the front: nothing ahead is free.
        let mut r = clear;
        r[2] = Reading::TooClose;
        assert_eq!(free_distance_mm(&c, &r, Angle::ZERO), 0);
    }

    #[test]
    fn the_default_clearance_widens_the_corridor() {
        // Defaults: radius 100 + clearance 40 = 140 mm.
        let c = cfg();
        let clear = [Reading::Clear; SENSOR_COUNT];
        assert_eq!(free_distance_mm(&c, &clear, Angle::ZERO), 900 - 140);
        // Heading 20° right with a front obstacle at 400 mm: 136.8 mm to
        // the side, outside 120 mm but inside 140 mm. Half chord
        // √(140² − 136.8²) = 29.8, along 375.9: 346.1; the stand-off
        // 375.9 − 200 = 175.9 is lower.
        let mut r = clear;
        r[2] = Reading::Range(300);
        let got = free_distance_mm(&c, &r, Angle::from_deg(-20));
        assert!((got as i32 - 176).abs() <= 1, "{got}");
    }

    /// The +40° beam reading 102 mm: 202 mm from the centre, 155 ahead
    /// and 130 to the left.
    fn left_face() -> Readings {
        let mut r = [Reading::Clear; SENSOR_COUNT];
        r[4] = Reading::Range(102);
        r
    }

    fn set_back() -> Config {
        ConfigBuilder::new(AdcProfile::AVR_10BIT_5V)
            .sensors_set_back(true)
            .build()
            .unwrap()
    }

    #[test]
    fn the_stand_off_is_kept_beyond_the_rim_wherever_the_sensors_sit() {
        // The same obstacle 250 mm ahead of the centre: read 150 mm from a
        // face on the rim, 250 mm from one at the centre. Either way the
        // step stops 100 mm (the stand-off) short of the rim: 50 mm.
        let mut rim = [Reading::Clear; SENSOR_COUNT];
        rim[2] = Reading::Range(150);
        assert_eq!(free_distance_mm(&cfg(), &rim, Angle::ZERO), 50);
        let centre = set_back();
        assert_eq!(centre.sensor_offset_mm(), 0);
        let mut behind = [Reading::Clear; SENSOR_COUNT];
        behind[2] = Reading::Range(250);
        assert_eq!(free_distance_mm(&centre, &behind, Angle::ZERO), 50);
    }

    #[test]
    #[cfg(feature = "set-back")]
    fn set_back_the_view_keeps_what_it_reads_near_the_rim() {
        let c = set_back();
        let mut f = Flank::default();
        // The +40° beam reads a post 150 mm from the centre (50 mm off the
        // rim); the −40° one a wall 400 mm off: only the post is kept.
        let mut r = [Reading::Clear; SENSOR_COUNT];
        r[4] = Reading::Range(150);
        r[0] = Reading::Range(400);
        f.saw_near(&c, Point::new(0, 0), Dir::of(Angle::ZERO), &r);
        assert_eq!(f.points().len(), 1);
        let p = f.points()[0];
        assert!((p.x - 115).abs() <= 1 && (p.y - 96).abs() <= 1, "{p:?}");
        // Turned 80° left, the post is 40° right of the new heading, where
        // no beam of this view looks beyond the ±40° of the last one...
        let clear = [Reading::Clear; SENSOR_COUNT];
        let left = Angle::from_deg(80);
        let flank = Some((Point::new(0, 0), Dir::of(left), f.points()));
        // ...yet the step along the −40° beam keeps the disc and the 40 mm
        // clearance off it (set back; 20 mm on the rim): 150 − 140 mm.
        let step = free_way_mm(&c, &clear, flank, Angle::from_deg(-40));
        assert!((9..=11).contains(&step), "{step}");
        assert!(free_way_mm(&c, &clear, None, Angle::from_deg(-40)) > 500);
    }

    #[test]
    fn the_flank_keeps_what_the_beams_saw_beside_the_way() {
        let c = cfg();
        let mut f = Flank::default();
        let r = left_face();
        // Turning in place: no advance, nothing kept.
        f.saw(&c, Point::new(0, 0), &r, 500);
        assert!(f.points().is_empty());
        // 375 then 385 mm into an advance along +x from the origin: the
        // same face 10 mm on, one point, the newer.
        f.start(Angle::ZERO, 500);
        f.saw(&c, Point::new(0, 0), &r, 500 - 375);
        f.saw(&c, Point::new(0, 0), &r, 500 - 385);
        assert_eq!(f.points().len(), 1);
        let p = f.points()[0];
        assert!((p.x - 540).abs() <= 1 && (p.y - 130).abs() <= 1, "{p:?}");
        // Far to the side (the +40° beam, 257 mm to the left), or far
        // ahead (the front beam, 500 mm on): not kept.
        let mut wide = [Reading::Clear; SENSOR_COUNT];
        wide[4] = Reading::Range(300);
        f.saw(&c, Point::new(0, 0), &wide, 100);
        let mut ahead = [Reading::Clear; SENSOR_COUNT];
        ahead[2] = Reading::Range(400);
        f.saw(&c, Point::new(0, 0), &ahead, 100);
        assert_eq!(f.points().len(), 1);
        // At the advance's end the point is 130 mm to the left, 40 ahead:
        // straight on the body passes it; turned 40° left it is 114 mm
        // ahead and 74 to the side, and the disc widened to 120 mm meets
        // it after 114 − √(120² − 74²) ≈ 20 mm; turned right it is behind.
        let end = Point::new(500, 0);
        let clear = [Reading::Clear; SENSOR_COUNT];
        let east = Dir::of(Angle::ZERO);
        let free = |deg| {
            free_way_mm(
                &c,
                &clear,
                Some((end, east, f.points())),
                Angle::from_deg(deg),
            )
        };
        assert_eq!(free(0), 760);
        assert!((free(40) as i32 - 20).abs() <= 2, "{}", free(40));
        assert_eq!(free(-40), 760);
        // The rover turned 90° left, looking 50° right of its heading: the
        // same way, the same limit.
        let north = Dir::of(Angle::from_deg(90));
        let turned = free_way_mm(
            &c,
            &clear,
            Some((end, north, f.points())),
            Angle::from_deg(-50),
        );
        assert!((turned as i32 - 20).abs() <= 2, "{turned}");
        // Kept while the rover is near (a new advance, 800 then 900 mm
        // along), forgotten beyond 300 mm.
        f.start(Angle::ZERO, 1_000);
        f.saw(&c, Point::new(0, 0), &clear, 200);
        assert_eq!(f.points().len(), 1);
        f.saw(&c, Point::new(0, 0), &clear, 100);
        assert!(f.points().is_empty());
    }

    #[test]
    fn a_full_flank_keeps_the_nearest_points() {
        let c = cfg();
        let mut f = Flank::default();
        f.start(Angle::ZERO, 2_000);
        for k in 0..6 {
            f.saw(&c, Point::new(0, 0), &left_face(), 2_000 - 100 * k);
        }
        let mut xs: Vec<i16> = f.points().iter().map(|p| p.x).collect();
        xs.sort();
        assert_eq!(xs.len(), FLANK_POINTS);
        for (x, want) in xs.iter().zip([355, 455, 555, 655]) {
            assert!((x - want).abs() <= 1, "{xs:?}");
        }
        // All places taken, a point farther than every kept one (the
        // front beam, 290 mm ahead of the rover at 500) is not kept.
        let mut ahead = [Reading::Clear; SENSOR_COUNT];
        ahead[2] = Reading::Range(190);
        f.saw(&c, Point::new(0, 0), &ahead, 2_000 - 500);
        assert!(f.points().iter().all(|p| p.x < 700), "{:?}", f.points());
        // 700 mm along, the one at 355 is forgotten and frees its place.
        let clear = [Reading::Clear; SENSOR_COUNT];
        f.saw(&c, Point::new(0, 0), &clear, 2_000 - 700);
        assert_eq!(f.points().len(), 3);
        f.saw(&c, Point::new(0, 0), &left_face(), 2_000 - 700);
        assert_eq!(f.points().len(), 4);
    }

    /// The rule without its shortcuts (the skipped side offsets and square
    /// roots, the stop at zero): every beam in the corridor lowers `free`
    /// to its stand-off and its chord limits.
    fn free_plain(c: &Config, readings: &Readings, relative: Angle) -> u16 {
        let rs = (c.robot_radius_mm + c.clearance_mm) as i32;
        let standoff = (c.robot_radius_mm + c.standoff_mm) as i32;
        let dir = Dir::of(relative);
        let ends = readings
            .iter()
            .zip(c.sensor_dirs.iter())
            .filter_map(|(r, d)| {
                let e = match *r {
                    Reading::Range(mm) => c.sensor_offset_mm + mm,
                    Reading::Clear => return None,
                    _ => c.sensor_offset_mm,
                };
                let (x, y) = d.scaled(e as i32);
                Some((along(x, y, dir), lateral(x, y, dir)))
            });
        let limits = ends
            .filter(|&(_, l)| l.abs() < rs)
            .map(|(a, l)| (a - standoff).min(a - half_chord(rs, l)).max(0));
        let reach = (c.sensor_offset_mm + c.sensor_range_mm) as i32 - rs;
        limits.fold(reach.max(0), i32::min) as u16
    }

    #[test]
    fn the_shortcuts_change_no_free_distance() {
        // 100,000 random readings and headings (a fixed xorshift sequence).
        let c = cfg();
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        for _ in 0..100_000 {
            let mut r = [Reading::Clear; SENSOR_COUNT];
            for v in r.iter_mut() {
                *v = match next() % 10 {
                    0..=5 => Reading::Range((next() % 900) as u16),
                    6..=8 => Reading::Clear,
                    _ => Reading::TooClose,
                };
            }
            // Both the usual headings (a sensor's: their table) and any.
            let rel = match next() % 3 {
                0 => c.sensor_angles[(next() % 5) as usize],
                _ => Angle((next() % 65_536) as u16),
            };
            assert_eq!(
                free_distance_mm(&c, &r, rel),
                free_plain(&c, &r, rel),
                "{r:?} {rel:?}"
            );
        }
    }

    #[test]
    fn guard_stops_when_the_way_closes() {
        let c = cfg();
        let mut r = [Reading::Clear; SENSOR_COUNT];
        assert_eq!(guard(&c, &r, 500), Guard::Continue);
        r[2] = Reading::Range(200);
        assert_eq!(guard(&c, &r, 500), Guard::Stop);
        assert_eq!(guard(&c, &r, 100), Guard::Continue);
        r[0] = Reading::Implausible;
        assert_eq!(guard(&c, &r, 0), Guard::Stop);
    }
}
