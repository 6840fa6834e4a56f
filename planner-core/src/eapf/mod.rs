//! The product planner: EAPF (Mohamed & Abbas 2013) in free space, and what
//! gets it out of local minima: virtual obstacles ([`escape`]) and boundary
//! following ([`follow`]). Its parts, one per concept: [`sensors`] (counts
//! to readings), [`forces`] (the paper's forces), [`memory`] (remembered
//! collision points), [`escape`], [`follow`], [`command`] (the output, the
//! safety rule and the guard), [`config`].

pub mod command;
pub mod config;
pub mod escape;
pub mod follow;
pub mod forces;
pub mod memory;
pub mod sensors;

use crate::fixed::{Angle, Dir, Force, Point, Pose};
use crate::{Navigator, RawCounts};
use command::{Command, Guard, Output, Status};
use config::Config;
use escape::Verdict;
use sensors::{IrSensors, Reading, Readings, SENSOR_COUNT};

use crate::fixed::{box_within, hypot};
use follow::FollowVerdict;
use forces::Motion;

/// Beyond this angle from the rover's heading a force counts as "behind"
/// (see the sector rule in [`Planner::step_raw`]).
const BEHIND: Angle = Angle::from_deg(120);

/// A retreat step the escape's limit shortens, after a turn of more than
/// this, waits a cycle (see the retreat in [`Planner::step_raw`]).
const RETREAT_TURN: Angle = Angle::from_deg(20);

/// One revolution in [`Angle`] units (see the pocket rule in
/// [`Planner::step_raw`]).
const FULL_TURN: u32 = 65_536;

/// A rover within this (mm, either axis) of where it was told to step from
/// has not stepped (see the pocket rule in [`Planner::step_raw`]): odometry
/// may drift a little while it turns on the spot; a step is at least the
/// configured minimum (10 mm by default).
const SPOT_MM: u16 = 5;

/// No position (`stepped_from` when the last cycle commanded no step).
const NOWHERE: Point = Point::new(i16::MIN, i16::MIN);

/// The EAPF planner with its state: remembered collision points, the
/// off-sensor following state, the paper's step size, virtual obstacles.
///
/// On the AVR its fields stay in this order (`repr(C)`): the step's small
/// state first, the configuration and the big buffers after it. An AVR load
/// reaches 63 bytes past a pointer; Rust's own order puts the 460-byte
/// configuration first and the step's state 900 bytes on, each access
/// then a pointer sum (docs/performance.md). Elsewhere Rust's order.
#[derive(Clone, Debug)]
#[cfg_attr(target_arch = "avr", repr(C))]
pub struct Planner {
    last_readings: Readings,
    goal: Point,
    stepped_from: Point,
    /// How far the rover has turned on the spot, and where it was told to
    /// step from last cycle ([`NOWHERE`] if it was not): see the pocket rule
    /// in [`Planner::step_raw`]. Not derived from the kept goal's position,
    /// which would do as "where it stood last cycle": that is a cache, and
    /// forgetting it must change no command (`kept_answers_change_no_command`
    /// fails when it is used so: checked).
    turned_in_place: u32,
    paper_step_mm: u16,
    following: bool,
    turn_side: i8,
    spun: bool,
    unreachable: bool,
    /// The follower's loop has closed once for this goal.
    looped_once: bool,
    /// The goal's distance and bearing, the attraction along it (eq. 16's
    /// first term; below 2^15 per component, so 16 bits), and the position
    /// they were worked out at: a rover turning in place asks again every
    /// cycle (on the AVR the attraction's sine and cosine are ~1,100
    /// cycles). In 16 bits, not as a `Force`: on the AVR each copy and
    /// compare of it is then half the work.
    kept_goal: Option<(Point, u16, Angle, [i16; 2])>,
    /// The midpoint force (eq. 13) and the sums it came from (unchanged
    /// while the rover turns in place and stores no new point).
    kept_midpoint: Option<(i32, i32, Force)>,
    fold_back: sensors::FoldBackFilter,
    /// Finds a sensor stuck at one count.
    freeze: sensors::FreezeWatch,
    /// What the guard saw beside the way (the safety rule's blind flank).
    flank: command::Flank,
    /// The cycle's collision points, for pictures and reports (feature
    /// `report`; the firmwares go without: 21 bytes of the AVR's RAM).
    #[cfg(feature = "report")]
    last_points: heapless::Vec<Point, SENSOR_COUNT>,
    config: Config,
    memory: memory::Memory,
    escape: escape::Escape,
    /// Boundary following after the escape gave up (see `follow`).
    follow: follow::Follow,
    /// Ours (the wedge): where the run of advances along one heading (within
    /// 1°) that brought the rover here started, and that heading.
    came_from: Option<(Point, Angle)>,
    /// This cycle's step backs out along the way the rover came: the guard
    /// lets it go (see the wedge rule in [`Planner::step_raw`]).
    backing_out: bool,
}

// The fields before the fold-back filter are the ones the step reads and
// writes most: on the AVR they must stay within a load's reach (the AVR
// build fails here if a new field pushes them out).
#[cfg(target_arch = "avr")]
const _: () = assert!(core::mem::offset_of!(Planner, fold_back) <= 64);

impl Planner {
    /// A planner heading for `goal`.
    ///
    /// Always inlined on the AVR: built in its caller's place, not in a
    /// frame of its own and then copied (a planner is over 1 KB of its
    /// 2 KB of RAM; [`Planner::load_config`]).
    #[cfg_attr(target_arch = "avr", inline(always))]
    pub fn new(config: Config, goal: Point) -> Self {
        let range = config.sensor_range_mm;
        Planner {
            config,
            goal,
            memory: memory::Memory::new(),
            escape: escape::Escape::new(),
            follow: follow::Follow::default(),
            fold_back: sensors::FoldBackFilter::default(),
            freeze: sensors::FreezeWatch::default(),
            following: false,
            turn_side: 0,
            spun: false,
            turned_in_place: 0,
            stepped_from: NOWHERE,
            paper_step_mm: range,
            unreachable: false,
            looped_once: false,
            #[cfg(feature = "report")]
            last_points: heapless::Vec::new(),
            last_readings: [Reading::Clear; SENSOR_COUNT],
            kept_goal: None,
            kept_midpoint: None,
            flank: command::Flank::default(),
            came_from: None,
            backing_out: false,
        }
    }

    /// Write a configuration over this planner's, in place, and start
    /// afresh (as [`Planner::set_goal`] does, same goal). For a target that
    /// cannot read a [`Config`] where it keeps it (the AVR's program
    /// memory): built with [`Planner::new`] from a copy, the copy sits on
    /// the stack beside the planner, and on the ATmega328P that was the
    /// stack's deepest point (515 bytes more; `tests/src/stack_bound.rs`).
    /// Build the planner with [`Config::UNSET`], then load. `load` must
    /// leave a configuration a [`config::ConfigBuilder`] built (the AVR firmware
    /// copies the bytes of one, which the compiler checked).
    pub fn load_config(&mut self, load: impl FnOnce(&mut Config)) {
        load(&mut self.config);
        self.set_goal(self.goal);
    }

    /// A new goal: forgets the memory, virtual obstacles, the guard's flank
    /// points and status (as a new planner would: a replayed run starts
    /// from nothing on every target).
    pub fn set_goal(&mut self, goal: Point) {
        // Field by field, not `*self = Planner::new(..)`: that would put a
        // second planner (and config) on the AVR's small stack.
        self.goal = goal;
        self.memory = memory::Memory::new();
        self.escape = escape::Escape::new();
        self.follow = follow::Follow::default();
        self.fold_back = sensors::FoldBackFilter::default();
        self.freeze = sensors::FreezeWatch::default();
        self.following = false;
        self.turn_side = 0;
        self.spun = false;
        self.turned_in_place = 0;
        self.stepped_from = NOWHERE;
        self.came_from = None;
        self.backing_out = false;
        self.paper_step_mm = self.config.sensor_range_mm;
        self.unreachable = false;
        self.looped_once = false;
        #[cfg(feature = "report")]
        self.last_points.clear();
        self.last_readings = [Reading::Clear; SENSOR_COUNT];
        self.kept_goal = None;
        self.kept_midpoint = None;
        self.flank = command::Flank::default();
    }

    /// The goal.
    pub fn goal(&self) -> Point {
        self.goal
    }

    /// The configuration.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// Convert raw counts to readings with the per-sensor calibrations.
    pub fn readings(&self, raw: &RawCounts) -> Readings {
        Planner::readings_with(&self.config, raw)
    }

    /// Raw counts to readings with `config`'s calibrations.
    pub fn readings_with(config: &Config, raw: &RawCounts) -> Readings {
        let mut out = [Reading::Clear; SENSOR_COUNT];
        Planner::readings_into(&mut out, config, raw, |_, r| r);
        out
    }

    /// Raw counts to readings in `out`, each passed through
    /// `then(sensor, reading)` in the same pass (the step's fold-back
    /// filter). Into a place, not returned: on the AVR every copy of the
    /// five readings (15 bytes) is a `memcpy` call.
    fn readings_into(
        out: &mut Readings,
        config: &Config,
        raw: &RawCounts,
        mut then: impl FnMut(usize, Reading) -> Reading,
    ) {
        let cal = &config.calibration;
        for (i, (o, &c)) in out.iter_mut().zip(raw.iter()).enumerate() {
            *o = then(i, cal.reading(c));
        }
    }

    /// One planner cycle reading the sensors from `sensors`.
    pub fn step<S: IrSensors>(&mut self, pose: Pose, sensors: &mut S) -> Result<Output, S::Error> {
        let raw = sensors.read_raw()?;
        Ok(self.step_raw(pose, &raw))
    }

    /// One planner cycle from raw ADC counts (the entry point every front
    /// end shares).
    #[cfg_attr(target_arch = "avr", inline(never))]
    pub fn step_raw(&mut self, pose: Pose, raw: &RawCounts) -> Output {
        // Whether last cycle's step moved the rover, or the guard stopped it
        // before it began (see the pocket rule below).
        let stepped = self.stepped_from != NOWHERE;
        let stopped = stepped && box_within(pose.position, self.stepped_from, SPOT_MM);
        let moved = stepped && !stopped;
        self.backing_out = false;
        if moved {
            self.note_advance();
        }
        // Held on this spot for three full turns: the fold-back filter
        // compares each sensor with the one that looked its way the cycle
        // before (see `FoldBackFilter`).
        let held = !moved && self.turned_in_place >= 3 * FULL_TURN;
        // Counts to readings and the fold-back filter, one pass.
        let fold_back = &mut self.fold_back;
        fold_back.look(pose.heading, &self.config.sensor_angles, held);
        Planner::readings_into(&mut self.last_readings, &self.config, raw, |i, r| {
            fold_back.filter(i, r)
        });
        let readings = &self.last_readings;
        #[cfg(feature = "report")]
        self.last_points.clear();
        let stop = |status| Output::stop(pose.heading, status);
        let frozen = self.freeze.frozen(raw, moved, self.config.frozen_views);
        if frozen || readings.contains(&Reading::Implausible) {
            return stop(Status::SensorFault);
        }
        let robot = pose.position;
        let (goal_mm, bearing, pull) = match self.kept_goal {
            Some((at, d, b, pull)) if at == robot => (d, b, pull),
            _ => {
                let (gx, gy) = robot.to(self.goal);
                let d = hypot(gx, gy);
                let b = Angle::atan2(gy, gx);
                // |ξ_att| ≤ 16 units (the config's check): each component
                // is at most 2^14 in Q10.
                let a = forces::attractive(&self.config, b);
                let pull = [a.x as i16, a.y as i16];
                self.kept_goal = Some((robot, d, b, pull));
                (d, b, pull)
            }
        };
        if goal_mm <= self.config.goal_tolerance_mm {
            return stop(Status::Arrived);
        }
        if self.unreachable {
            return stop(Status::Unreachable);
        }
        // Ours (the wedge): four full turns on the spot without a step. In a
        // pocket whose walls are nearer than the sensors' minimum range,
        // every heading has a beam in the disc's way that reads too close,
        // so no heading is ever free (the commit history, "The wedge"). The way
        // the rover came in is: the disc has just swept it. Back out along
        // it, once, and let the guard trust it.
        if !moved && self.turned_in_place >= 4 * FULL_TURN {
            if let Some(out) = self.back_out(robot) {
                #[cfg(feature = "set-back")]
                self.see_near(pose);
                return out;
            }
        }
        let readings = &self.last_readings;
        // Ours: once the escape gives up, boundary following (the `follow`
        // module) instead of reporting the goal unreachable at once; the
        // potential field is not used again for this goal.
        if !self.follow.active()
            && self.escape.observe(&self.config.escape, robot, goal_mm) == Verdict::GiveUp
        {
            if !self.config.escape.follow {
                self.unreachable = true;
                return stop(Status::Unreachable);
            }
            self.follow.start(self.looped_once);
        }
        if self.follow.active() {
            #[cfg(feature = "set-back")]
            self.see_near(pose);
            #[cfg(feature = "set-back")]
            let readings = &self.last_readings;
            self.follow.after_step(moved, stopped);
            let bearing_rel = bearing.sub(pose.heading);
            let in_sector = bearing_rel.abs_signed() <= self.config.sector_half_width().0;
            let free_to_goal = if in_sector {
                let flank = self.flank_at(pose);
                command::free_way_mm(&self.config, readings, flank, bearing_rel)
            } else {
                0
            };
            return match self.follow.decide(
                &self.config,
                readings,
                robot,
                goal_mm,
                bearing_rel,
                free_to_goal,
            ) {
                // Ours: a boundary followed all round the first time hands
                // back to the potential field, its virtual obstacles kept
                // and its give-up count started again: a gap the field can
                // squeeze through is one the follower passes by (its way
                // must be free for `FOLLOW_FREE_MM`), so the first loop may
                // close round a goal that is not walled in (barn-tight-206,
                // seed 1). The second loop is the answer; that round only
                // confirms the first, so its follower has the shorter
                // budget (`follow::SECOND_GIVE_UPS`).
                FollowVerdict::Looped if !self.looped_once => {
                    self.looped_once = true;
                    self.follow = follow::Follow::default();
                    self.escape.again();
                    self.command(robot, pose.heading, 0)
                }
                FollowVerdict::Off | FollowVerdict::Looped | FollowVerdict::GiveUp => {
                    self.unreachable = true;
                    stop(Status::Unreachable)
                }
                v => self.follow_step(pose, v, free_to_goal, moved, stopped),
            };
        }
        let cfg = &self.config;
        let near = goal_mm < cfg.sensor_range_mm;

        // Collision points (eqs. 7, 8) and the memory of them (eqs. 11-13).
        let points = forces::collision_points(cfg, readings, self.paper_step_mm);
        // The heading's sine and cosine once; each sensor's world direction
        // is its fixed direction turned by them, and serves both the point's
        // position and its repulsion (eqs. 9, 10).
        let heading_dir = Dir::of(pose.heading);
        let mut repulsive = Force::ZERO;
        let mut nearest: Option<(u16, Point)> = None;
        for p in points.iter() {
            let toward = forces::sensor_direction(cfg, heading_dir, p.sensor as usize);
            let at = robot.offset_dir(toward, p.distance_mm);
            #[cfg(feature = "set-back")]
            if cfg.set_back() {
                let r = readings.get(p.sensor as usize).copied();
                let r = r.unwrap_or(Reading::Clear);
                self.flank.saw_point(cfg, r, p.distance_mm, at, robot);
            }
            #[cfg(feature = "report")]
            let _ = self.last_points.push(at);
            if nearest.is_none_or(|(d, _)| p.distance_mm < d) {
                nearest = Some((p.distance_mm, at));
            }
            // At most five terms below 2^17 each (`Dir::scaled` clamps).
            repulsive = repulsive.plus_bounded(forces::repulsion(toward, p.distance_mm));
        }
        // Ours: the memory takes the nearest point of the cycle only, which
        // bounds a cycle's work (see `memory`).
        if let Some((_, point)) = nearest {
            self.memory.remember(
                point,
                robot,
                pose.heading,
                self.goal,
                cfg.diagonal_tolerance,
            );
        }

        // Off-sensor following state (§5.5): from the first collision until DM.
        let motion = forces::motion(cfg, pose.heading, bearing);
        if motion == Motion::Direct {
            self.following = false;
        } else if !points.is_empty() {
            self.following = true;
        }

        // Eq. 16: the sum of the forces; the near-target rule drops the
        // midpoint and off-sensor forces.
        let attraction = Force {
            x: pull[0] as i32,
            y: pull[1] as i32,
        };
        // Plain adds: the terms' bounds keep the sum below 2^30 (the
        // attraction and the midpoint force at most 2^14 a component, the
        // repulsion 5 · 2^17, the off-sensor force 5 · 2^14, the virtual
        // obstacles' 2^29: see `Escape::force`), so a saturating add never
        // saturates here, and on the AVR it costs ~50 cycles a component.
        let mut f = attraction
            .plus_unsaturated(repulsive)
            .plus_unsaturated(self.escape.force_kept(robot, bearing));
        if !near {
            let (_, ax, ay) = self.memory.away_from_midpoint_kept(robot, self.goal);
            let mid = match self.kept_midpoint {
                Some((x, y, m)) if (x, y) == (ax, ay) => m,
                _ => forces::midpoint(cfg, ax, ay),
            };
            self.kept_midpoint = Some((ax, ay, mid));
            f = f.plus_unsaturated(mid);
            if self.following {
                f = f.plus_unsaturated(forces::off_sensor(cfg, heading_dir, motion, readings));
            }
        }
        // Eq. 17.
        let mut heading = f.direction().unwrap_or(bearing);

        // The paper's step: the sensor range when free, else the farthest
        // detection plus the robot's width.
        // (A plain loop: `Iterator::max` over these u16s was miscompiled for
        // avr-none, caught by the firmware's bit-exactness test.)
        let mut farthest: u16 = 0;
        for p in points.iter() {
            farthest = farthest.max(p.distance_mm.saturating_sub(cfg.sensor_offset_mm));
        }
        self.paper_step_mm = if points.is_empty() {
            cfg.sensor_range_mm
        } else {
            farthest.saturating_add(2 * cfg.robot_radius_mm)
        };

        // Safety (§5): never outside the sensed sector, never beyond what the
        // readings show free. Ours: with something in the way, turn at most
        // to the edge of the sector towards the heading, so that the next
        // cycle still sees the obstacle; a full turn away would lose sight of
        // it and the attraction would turn the rover straight back (a
        // livelock of turns). Bounded turns make it slide along the obstacle.
        //
        // A force pointing nearly backwards (beyond ±120°) gives no reliable
        // side: the side flips from cycle to cycle with the noise and the
        // rover see-saws between two headings, stuck. There it keeps
        // turning the way it turned last, and so turns round.
        let half = cfg.sector_half_width();
        let mut relative = heading.sub(pose.heading);
        if !points.is_empty() && relative.abs_signed() > half.0 {
            let mut left = relative.signed() > 0;
            if relative.abs_signed() > BEHIND.0 && self.turn_side != 0 {
                left = self.turn_side > 0;
            }
            self.turn_side = if left { 1 } else { -1 };
            relative = if left { half } else { half.neg() };
            heading = pose.heading.add(relative);
        } else {
            self.turn_side = 0;
        }
        let flank = self.flank.points();
        let flank = (!flank.is_empty()).then_some((robot, heading_dir, flank));
        let free = |relative: Angle| command::free_way_mm(cfg, readings, flank, relative);
        // Steps shorter than the executor can make are none.
        let at_least_min = |step: u16| if step < cfg.min_step_mm { 0 } else { step };
        let mut step = if relative.abs_signed() > half.0 {
            0
        } else {
            self.paper_step_mm.min(free(relative))
        };
        if near {
            step = step.min(goal_mm);
        }
        // Ours (the escape's retreat, `escape` module docs): away from the
        // goal, only as far as the virtual obstacles dropped since the last
        // progress call for. A step the limit shortens, after a turn of more
        // than `RETREAT_TURN`, waits a cycle: the rover turns and looks
        // first, so that the short step does not go blind into a corner on
        // the new flank (what the retreat's collisions were).
        if heading.sub(bearing).abs_signed() > Angle::QUARTER.0 {
            if let Some(limit) = self.escape.retreat_limit_mm(&cfg.escape) {
                if step > limit {
                    step = if relative.abs_signed() > RETREAT_TURN.0 {
                        0
                    } else {
                        limit
                    };
                }
            }
        }
        step = at_least_min(step);
        // Ours: two turns on the spot in a row with nothing in sight is the
        // start of a livelock (turn to the force, see the obstacle, turn
        // away, lose sight of it, turn back). Break it by advancing along
        // the free heading the rover already faces.
        let spin = step == 0 && points.is_empty() && relative.abs_signed() > half.0;
        if spin && self.spun {
            heading = pose.heading;
            step = at_least_min(self.paper_step_mm.min(free(Angle::ZERO)) / 2);
        }
        self.spun = spin && step == 0;
        // Ours: a full turn on the spot without a step is the same livelock
        // with something in sight (in a pocket every heading's force is
        // clamped to the sector edge, where the way is not free, round and
        // round; the escape's virtual obstacles cannot help a rover that
        // never moves). Then advance where the rover faces, if free: without
        // a turn, the guard sees what the planner saw.
        //
        // A step the executor's guard stopped before it began (after the
        // turn the beams saw the way blocked) moved nothing: its turn counts
        // as one on the spot, and the count goes on. The count restarts
        // once a step has moved the rover.
        Planner::count_turn(&mut self.turned_in_place, moved, relative);
        if (step == 0 || stopped) && self.turned_in_place >= FULL_TURN {
            let ahead = at_least_min(self.paper_step_mm.min(free(Angle::ZERO)) / 2);
            if ahead > 0 {
                heading = pose.heading;
                step = ahead;
            }
        }
        self.command(robot, heading, step)
    }

    /// The last step moved the rover: it extends the run of advances along
    /// one heading (within 1°: every point driven and the run's end then
    /// lie in a 1° cone round that heading, so the straight way back stays
    /// within sin 2°, 3.5 %, of the run's length of the way driven), or
    /// starts a new one where it began (the wedge rule's way back). The
    /// step's heading is the guard's (`Flank`). Out of line: a few cycles,
    /// off the step's costliest path.
    #[inline(never)]
    fn note_advance(&mut self) {
        let Some(heading) = self.flank.heading() else {
            return;
        };
        let along = self
            .came_from
            .is_some_and(|(_, run)| heading.sub(run).abs_signed() <= Angle::from_deg(1).0);
        if !along {
            self.came_from = Some((self.stepped_from, heading));
        }
    }

    /// The wedge rule's step: back to where the run of advances that
    /// brought the rover here began, once (`None` if there is none, or it
    /// is nearer than a step).
    #[cold]
    #[inline(never)]
    fn back_out(&mut self, robot: Point) -> Option<Output> {
        let (from, _) = self.came_from.take()?;
        let (dx, dy) = robot.to(from);
        // No longer than the sensors' range (a run of advances can be
        // metres long; the rest of the way back is planned from the next
        // view).
        let back_mm = hypot(dx, dy).min(self.config.sensor_range_mm);
        let heading = Angle::atan2(dy, dx);
        self.turned_in_place = 0;
        if back_mm < self.config.min_step_mm {
            return None;
        }
        self.backing_out = true;
        Some(self.command(robot, heading, back_mm))
    }

    /// Add this cycle's `turn` to the turning on the spot (restarted once a
    /// step has `moved` the rover): the pocket rule and the fold-back
    /// filter's `held` read it, while following a boundary too.
    #[cfg_attr(target_arch = "avr", inline(never))]
    fn count_turn(turned_in_place: &mut u32, moved: bool, turn: Angle) {
        if moved {
            *turned_in_place = 0;
        }
        *turned_in_place = turned_in_place.saturating_add(turn.abs_signed() as u32);
    }

    /// The cycle's command: a step of `step_mm` along `heading` from
    /// `robot` (the pocket rule's `stepped_from`, the guard's flank
    /// started with it).
    fn command(&mut self, robot: Point, heading: Angle, step_mm: u16) -> Output {
        self.stepped_from = if step_mm > 0 { robot } else { NOWHERE };
        self.flank.start(heading, step_mm);
        Output {
            command: Command { heading, step_mm },
            status: Status::Moving,
        }
    }

    /// A step of boundary following: seeking, towards the goal as far as
    /// the way is free (`free_to_goal_mm`); following, the first of the
    /// follower's turns whose way is free for [`follow::FOLLOW_FREE_MM`],
    /// or in a tight spot where none is, straight on. Never beyond the
    /// safety rule's free way; where that is nothing, a turn on the spot
    /// away from the boundary.
    fn follow_step(
        &mut self,
        pose: Pose,
        verdict: FollowVerdict,
        free_to_goal_mm: u16,
        moved: bool,
        stopped: bool,
    ) -> Output {
        let cfg = &self.config;
        let most = follow::FOLLOW_STEP_MM;
        let flank = self.flank_at(pose);
        let free = |turn| command::free_way_mm(cfg, &self.last_readings, flank, turn);
        let (turn, step) = match verdict {
            FollowVerdict::Seek(turn, most) => (turn, free_to_goal_mm.min(most)),
            _ => {
                // The first turn free for `FOLLOW_FREE_MM`; in a tight spot
                // where none is (or where the guard stopped the last step
                // before it began: the planner's view of a turned heading
                // and the guard's view after the turn differ), straight on
                // as far as free, which is what the guard checks; else a
                // turn on the spot away from the boundary, the same way
                // each time, until a way opens.
                let found = if stopped {
                    None
                } else {
                    self.follow.hug(cfg, free)
                };
                let (turn, way) = found.unwrap_or((Angle::ZERO, free(Angle::ZERO)));
                if way.min(most) < cfg.min_step_mm {
                    (self.follow.away_turn(cfg), 0)
                } else {
                    (turn, way.min(most))
                }
            }
        };
        // Held on the spot while following, the fold-back filter compares
        // each sensor with the one that looked its way the cycle before
        // (else, turning round in a tight pocket, each outer beam's view of
        // a free way read "too close" through its own last look at the
        // wall, and no heading was ever free: gen-223, seed 1).
        self.follow.note_turn(cfg, turn, step);
        Planner::count_turn(&mut self.turned_in_place, moved, turn);
        self.command(pose.position, pose.heading.add(turn), step)
    }

    /// With the sensors set back, what the view from `pose` reads near the
    /// rim is kept as flank points ([`command::Flank::saw_near`]). Out of
    /// line: only the boundary follower and the wedge rule's way back call
    /// it (the potential field keeps them in its loop over the collision
    /// points).
    #[cfg(feature = "set-back")]
    #[inline(never)]
    fn see_near(&mut self, pose: Pose) {
        if self.config.set_back() {
            let dir = Dir::of(pose.heading);
            let readings = &self.last_readings;
            self.flank
                .saw_near(&self.config, pose.position, dir, readings);
        }
    }

    /// The guard's flank points as the safety rule takes them at `pose`.
    fn flank_at(&self, pose: Pose) -> Option<(Point, Dir, &[Point])> {
        let flank = self.flank.points();
        (!flank.is_empty()).then(|| (pose.position, Dir::of(pose.heading), flank))
    }

    /// The guard the executor calls during an advance with fresh raw counts
    /// and the part of the step still to go.
    pub fn guard_raw(&mut self, raw: &RawCounts, remaining_mm: u16) -> Guard {
        let mut readings = self.readings(raw);
        self.flank
            .saw(&self.config, self.stepped_from, &readings, remaining_mm);
        if self.backing_out {
            // The wedge rule's way back: the disc has just swept it, and
            // the beams' "too close" (the wedge's walls, nearer than the
            // sensors' minimum range) says nothing of it. A ranged reading
            // in the way (a thing that moved there) still stops it.
            for r in readings.iter_mut() {
                if matches!(r, Reading::TooClose) {
                    *r = Reading::Clear;
                }
            }
        }
        command::guard(&self.config, &readings, remaining_mm)
    }

    /// The points the guard saw beside the way (see [`command::Flank`]).
    pub fn flank(&self) -> &command::Flank {
        &self.flank
    }

    /// The remembered collision points.
    pub fn memory(&self) -> &memory::Memory {
        &self.memory
    }

    /// The escape state (virtual obstacles).
    pub fn escape(&self) -> &escape::Escape {
        &self.escape
    }

    /// The boundary follower's state.
    pub fn follow(&self) -> &follow::Follow {
        &self.follow
    }

    /// The collision points of the last cycle, world mm (feature `report`).
    #[cfg(feature = "report")]
    pub fn last_collision_points(&self) -> &[Point] {
        &self.last_points
    }

    /// Whether this cycle's step backs out along the way the rover came
    /// (the wedge rule): its guard trusts "too close" readings, which the
    /// wedge's walls give, but not ranged ones.
    pub fn backing_out(&self) -> bool {
        self.backing_out
    }

    /// The readings of the last cycle, after filtering.
    pub fn last_readings(&self) -> &Readings {
        &self.last_readings
    }

    /// The paper's step size the next cycle will test collisions against.
    pub fn paper_step_mm(&self) -> u16 {
        self.paper_step_mm
    }

    /// Which part of the planner decides its steps now.
    pub fn mode(&self) -> Mode {
        if self.follow.active() {
            Mode::Follow
        } else if self.escape.is_empty() {
            Mode::Field
        } else {
            Mode::Escape
        }
    }
}

/// Which part of the planner decides a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Mode {
    /// The potential field alone (EAPF): the goal's pull, the collision
    /// points' push.
    Field,
    /// The field with the escape's virtual obstacles ("liquid movement")
    /// pushing the rover out of a local minimum.
    Escape,
    /// Boundary following, once the escape has given up.
    Follow,
}

impl Navigator for Planner {
    fn step_raw(&mut self, pose: Pose, raw: &RawCounts) -> Output {
        Planner::step_raw(self, pose, raw)
    }
    fn guard_raw(&mut self, raw: &RawCounts, remaining_mm: u16) -> Guard {
        Planner::guard_raw(self, raw, remaining_mm)
    }
    fn config(&self) -> &Config {
        Planner::config(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{AdcProfile, ConfigBuilder, EscapeConfig, ScriptedSensors};

    fn planner(goal: Point) -> Planner {
        planner_with(EscapeConfig::default(), goal)
    }

    /// The default planner with the escape `escape`, without the watch for
    /// stuck sensors: the tests' counts are scripted, noise-free.
    fn planner_with(escape: EscapeConfig, goal: Point) -> Planner {
        Planner::new(
            ConfigBuilder::new(AdcProfile::AVR_10BIT_5V)
                .escape(escape)
                .frozen_after_views(0)
                .build()
                .unwrap(),
            goal,
        )
    }

    /// The default planner less the escape's retreat limit (for the
    /// pocket rule's tests, which count the steps it commands).
    fn planner_without_retreat(goal: Point) -> Planner {
        let escape = EscapeConfig {
            retreat_mm: 0,
            ..EscapeConfig::default()
        };
        planner_with(escape, goal)
    }

    /// The front sensor's first count that reads `mm` or nearer.
    fn count_for(p: &Planner, mm: u16) -> u16 {
        let cal = p.config().calibration();
        (86..=532)
            .find(|&c| cal.reading(c).range_mm().unwrap_or(9_999) <= mm)
            .unwrap()
    }

    /// A sensor's count with nothing in range: its phantom level, 0.28 V
    /// on the 10-bit 5 V ADC (0 V would be a dead sensor: see
    /// [`sensors::SIGNAL_FLOOR_MV`]).
    const FAR: u16 = 57;

    fn at(x: i16, y: i16, deg: i16) -> Pose {
        Pose {
            position: Point::new(x, y),
            heading: Angle::from_deg(deg),
        }
    }

    #[test]
    fn the_step_force_sum_cannot_saturate() {
        // What lets the step add its forces without saturating
        // (`Force::plus_unsaturated`): each term at its bound, all one way.
        // Fails if a capacity, clamp or gain limit grows past it.
        use crate::eapf::escape::{MAX_PUSH, VIRTUAL_CAPACITY};
        use crate::fixed::{FORCE_ONE, MAX_SCALED};
        let gain = config::MAX_GAIN as i64 + 2; // the config's limit, and rounding
        let attraction = gain;
        let repulsion = SENSOR_COUNT as i64 * MAX_SCALED as i64;
        let escape = VIRTUAL_CAPACITY as i64 * MAX_PUSH as i64 * u8::MAX as i64;
        let midpoint = gain;
        let off_sensor = SENSOR_COUNT as i64 * gain;
        let sum = attraction + repulsion + escape + midpoint + off_sensor;
        assert!(sum < i32::MAX as i64, "{sum}");
        assert!(ConfigBuilder::new(AdcProfile::AVR_10BIT_5V)
            .gains_q10(config::MAX_GAIN + 1, FORCE_ONE, FORCE_ONE)
            .build()
            .is_err());
    }

    #[test]
    fn a_planner_loaded_in_place_is_the_one_new_builds() {
        // The same answers, step and guard, over a wandering run of odd
        // counts (a small linear congruential sequence, so the test is
        // the same every time). Fails if `load_config` keeps anything
        // `new` worked out from the unset one.
        let cfg = ConfigBuilder::new(AdcProfile::AVR_10BIT_5V)
            .sensor_range_mm(700)
            .build()
            .unwrap();
        let goal = Point::new(1_500, -800);
        let mut a = Planner::new(cfg, goal);
        let mut b = Planner::new(Config::UNSET, goal);
        b.load_config(|c| *c = cfg);
        assert_eq!(a.config(), b.config());
        let mut seed = 12_345u32;
        let mut next = |m: u32| {
            seed = seed.wrapping_mul(1_103_515_245).wrapping_add(12_345);
            (seed >> 16) % m
        };
        for _ in 0..400 {
            let raw: RawCounts = core::array::from_fn(|_| 40 + next(560) as u16);
            let pose = at(
                next(2_000) as i16 - 200,
                next(1_600) as i16 - 1_200,
                next(360) as i16,
            );
            let remaining = next(500) as u16;
            assert_eq!(a.guard_raw(&raw, remaining), b.guard_raw(&raw, remaining));
            assert_eq!(a.step_raw(pose, &raw), b.step_raw(pose, &raw));
        }
    }

    #[test]
    fn a_planner_with_no_configuration_stays_put() {
        // `Config::UNSET` before a load: whatever the counts and the pose,
        // no step, and the guard stops.
        let mut p = Planner::new(Config::UNSET, Point::new(1_000, 0));
        for c in (0..=1_100u16).step_by(7).chain([u16::MAX]) {
            for raw in [[c; 5], [FAR, c, FAR, c, FAR]] {
                let out = p.step_raw(at(c as i16 % 500, 0, c as i16), &raw);
                assert_eq!(out.command.step_mm, 0, "{raw:?}: {out:?}");
                assert_eq!(p.guard_raw(&raw, 100), Guard::Stop, "{raw:?}");
            }
        }
    }

    #[test]
    fn free_motion_heads_for_the_goal() {
        let mut p = planner(Point::new(0, 3_000));
        let out = p.step_raw(at(0, 0, 90), &[FAR; 5]);
        assert_eq!(out.command.heading, Angle::QUARTER);
        // Reach 900 mm less radius and clearance (140 mm).
        assert_eq!(out.command.step_mm, 760);
        assert_eq!(out.status, Status::Moving);
    }

    #[test]
    fn a_step_away_from_the_goal_goes_only_as_far_as_the_drops_allow() {
        // Held on one spot facing the goal, nothing in sight: after a
        // window of cycles the escape drops a virtual obstacle there, whose
        // push (4.4 units, more than the attraction's 2) points away from
        // the goal. The rover turns round, then retreats `retreat_mm` plus
        // `retreat_per_drop_mm` for the one drop (100 + 40), not the 760 mm
        // the way is free for (without the retreat limit).
        let run = |escape: EscapeConfig| {
            let mut p = planner_with(escape, Point::new(3_000, 0));
            let mut pose = at(0, 0, 0);
            for _ in 0..40 {
                let out = p.step_raw(pose, &[FAR; 5]);
                if out.command.heading.sub(Angle::HALF).abs_signed() < Angle::from_deg(1).0 {
                    if pose.heading == out.command.heading {
                        return (p.escape().dropped(), out.command.step_mm);
                    }
                    assert_eq!(out.command.step_mm, 0, "turns round first");
                    pose.heading = out.command.heading;
                }
            }
            panic!("no retreat in 40 cycles");
        };
        assert_eq!(run(EscapeConfig::default()), (1, 140));
        let without = EscapeConfig {
            retreat_mm: 0,
            ..EscapeConfig::default()
        };
        assert_eq!(run(without), (1, 760));
    }

    #[test]
    fn a_shortened_retreat_after_a_turn_waits_a_cycle() {
        // As above, with the retreat: a drop on the spot, the force points
        // back (180°). Facing 150°, the retreat needs a 30° turn: the rover
        // turns without a step; facing 170° (10°) it steps the limit.
        let mut p = planner(Point::new(3_000, 0));
        let mut cycles = 0;
        while p.escape().dropped() == 0 {
            p.step_raw(at(0, 0, 0), &[FAR; 5]);
            cycles += 1;
            assert!(cycles < 40, "no drop");
        }
        let out = p.step_raw(at(0, 0, 150), &[FAR; 5]);
        assert_eq!(out.command.heading, Angle::HALF);
        assert_eq!(out.command.step_mm, 0, "a 30° turn first");
        let out = p.step_raw(at(0, 0, 170), &[FAR; 5]);
        assert_eq!(out.command.heading, Angle::HALF);
        assert_eq!(out.command.step_mm, 140, "a 10° turn and the limit");
    }

    #[test]
    fn heading_outside_the_sector_turns_first() {
        let mut p = planner(Point::new(-3_000, 0));
        let out = p.step_raw(at(0, 0, 0), &[FAR; 5]);
        assert_eq!(out.command.heading, Angle::HALF);
        assert_eq!(out.command.step_mm, 0);
    }

    #[test]
    fn arrival_and_near_target_step() {
        let mut p = planner(Point::new(500, 0));
        let out = p.step_raw(at(0, 0, 0), &[FAR; 5]);
        assert_eq!(out.command.step_mm, 500);
        let out = p.step_raw(at(470, 0, 0), &[FAR; 5]);
        assert_eq!(out.status, Status::Arrived);
        assert_eq!(out.command.step_mm, 0);
    }

    #[test]
    fn obstacle_ahead_deflects_and_shortens_the_step() {
        let mut p = planner(Point::new(3_000, 0));
        let cal = *p.config().calibration();
        // An obstacle 300 mm ahead on the front sensor (count for ~300 mm).
        let c300 = count_for(&p, 300);
        let out = p.step_raw(at(0, 0, 0), &[FAR, FAR, c300, FAR, FAR]);
        // Attraction 2 forward, repulsion 1/0.4² = 6.25 back: the heading
        // reverses, so the rover turns to the sector's edge (±40°) instead,
        // keeping the obstacle in view, and may step along it if free.
        assert_eq!(out.command.heading.abs_signed(), Angle::from_deg(40).0);
        // Along ±40° the obstacle lies 400·sin 40° = 257 mm to the side,
        // outside the corridor, and every other beam is clear: the step is
        // the paper's, the detection plus the robot's width (2 × 100 mm).
        let seen_mm = cal.reading(c300).range_mm().unwrap();
        assert_eq!(out.command.step_mm, seen_mm + 200);
        assert_eq!(p.last_collision_points().len(), 1);
        assert_eq!(p.memory().len(), 1);
    }

    #[test]
    fn a_step_keeps_off_what_the_guard_saw_beside_the_way() {
        // A rover drives along +x; during the advance its +40° beam sees a
        // face 150 mm to the left of the way (outside the guard's 140 mm
        // corridor), about (540, 150). Next cycle, from (439, 52), the way
        // to the goal passes that point 45° to its left, 141 mm off, where
        // no beam looks: the beams see nothing, and without the guard's
        // flank points the rover would step out the full reach over it.
        let goal = Point::new(3_000, 0);
        let mut seen = planner(goal);
        let mut blind = planner(goal);
        let face = count_for(&seen, 133);
        for p in [&mut seen, &mut blind] {
            let out = p.step_raw(at(0, 0, 0), &[FAR; 5]);
            assert_eq!(out.command.step_mm, 760);
        }
        for gone in [342, 352, 362] {
            let g = seen.guard_raw(&[FAR, FAR, FAR, FAR, face], 760 - gone);
            assert_eq!(g, Guard::Continue);
            blind.guard_raw(&[FAR; 5], 760 - gone);
        }
        assert_eq!(seen.flank().points().len(), 1);
        assert!(blind.flank().points().is_empty());
        let steps = [&mut seen, &mut blind].map(|p| {
            let out = p.step_raw(at(439, 52, -1), &[FAR; 5]);
            assert_eq!(out.status, Status::Moving);
            out.command.step_mm
        });
        assert_eq!(steps[1], 760);
        assert!((20..60).contains(&steps[0]), "{steps:?}");
        // A new goal starts from nothing, the flank included.
        seen.set_goal(goal);
        assert!(seen.flank().points().is_empty());
    }

    #[test]
    fn the_memory_takes_the_nearest_point_of_a_cycle() {
        let mut p = planner(Point::new(3_000, 0));
        // The front and the front-left sensors both see something, the
        // front-left nearer.
        let (far, close) = (count_for(&p, 400), count_for(&p, 200));
        let out = p.step_raw(at(0, 0, 0), &[FAR, close, far, FAR, FAR]);
        assert_eq!(out.status, Status::Moving);
        let seen = p.last_collision_points().to_vec();
        assert_eq!(seen.len(), 2);
        // Only the nearer one is remembered (the memory takes one a cycle).
        let nearest = *seen
            .iter()
            .min_by_key(|q| q.distance_mm(Point::new(0, 0)))
            .unwrap();
        let kept: std::vec::Vec<Point> = p.memory().iter().map(|r| r.point).collect();
        assert_eq!(kept, [nearest]);
    }

    #[test]
    fn a_force_from_behind_turns_the_rover_round_one_way() {
        let mut p = planner(Point::new(3_000, 0));
        // A wall 150 mm ahead of the front sensor: its repulsion (≈ 16
        // units) dwarfs the attraction (2) and points straight back.
        let near = count_for(&p, 150);
        let counts = [FAR, FAR, near, FAR, FAR];
        let first = p.step_raw(at(0, 0, 0), &counts).command.heading;
        assert_eq!(first.abs_signed(), Angle::from_deg(40).0);
        // From there the wall is still dead ahead, but the attraction now
        // pulls to the other side: without the rule the rover would turn
        // back to 0° and see-saw. It goes on turning the same way.
        let deg = first.signed() / 182;
        let second = p.step_raw(at(0, 0, deg), &counts).command.heading;
        assert_eq!(second, first.add(first));
        let third = p.step_raw(at(0, 0, 2 * deg), &counts).command.heading;
        assert_eq!(third, first.add(first).add(first));
    }

    #[test]
    fn a_second_turn_on_the_spot_in_a_row_becomes_an_advance() {
        // The goal behind the rover and nothing in sight: turn on the spot.
        let mut p = planner(Point::new(-3_000, 0));
        let out = p.step_raw(at(0, 0, 0), &[FAR; 5]).command;
        assert_eq!((out.heading, out.step_mm), (Angle::HALF, 0));
        // The rover faces 90° instead (as when the force swings between a
        // seen and an unseen obstacle): a second pure turn would start the
        // livelock, so it advances along 90°, half the free distance.
        let out = p.step_raw(at(0, 0, 90), &[FAR; 5]).command;
        assert_eq!(out.heading, Angle::from_deg(90));
        let c = p.config();
        let free =
            c.sensor_offset_mm() + c.sensor_range_mm() - c.robot_radius_mm() - c.clearance_mm();
        assert_eq!(out.step_mm, free / 2);
        // After that advance, a pure turn is allowed again.
        let out = p.step_raw(at(0, (free / 2) as i16, 0), &[FAR; 5]).command;
        assert_eq!(out.step_mm, 0);
    }

    #[test]
    fn a_full_turn_in_a_pocket_ends_in_a_step_out() {
        // Obstacles at every sensor face ("too close") unless the rover
        // faces 225° ..= 305°; the goal is east. Each cycle the force points
        // back and is clamped to the sector edge, where the way is blocked:
        // 40° turns on the spot; facing the opening (the cycle after the
        // fold-back filter distrusted the view's jump) the force points
        // outside the sector, and the rover turns on. After a full turn it
        // steps out where it faces, if that is free. (Without the rule the
        // first step comes after one and a half turns, and off the heading
        // faced: checked.)
        let mut p = planner(Point::new(3_000, 0));
        let near = p.config().calibration().full_scale() / 2 + 100;
        assert_eq!(p.readings(&[near; 5])[2], Reading::TooClose);
        let open = |deg: f64| (225.0..=305.0).contains(&deg);
        let mut heading = Angle::ZERO;
        let mut turned = 0u32;
        for _ in 0..30 {
            let deg = heading.to_deg_f64().rem_euclid(360.0);
            let raw = if open(deg) { [FAR; 5] } else { [near; 5] };
            let pose = Pose {
                position: Point::new(0, 0),
                heading,
            };
            let out = p.step_raw(pose, &raw);
            if out.command.step_mm > 0 {
                assert_eq!(out.command.heading, heading, "out along the facing");
                assert!(open(deg), "{deg}");
                assert!(turned >= 65_536, "only after a full turn: {turned}");
                return;
            }
            turned += out.command.heading.sub(heading).abs_signed() as u32;
            heading = out.command.heading;
        }
        panic!("still turning on the spot after 30 cycles");
    }

    #[test]
    fn wedged_the_rover_backs_out_the_way_it_came() {
        // The rover advances north from (0, 0) into a pocket; at (0, 400)
        // every sensor reads "too close" whichever way it faces, so no
        // heading is ever free. After four full turns on the spot it backs
        // out to where the run of advances began, along the line it came
        // (due south), and the guard lets that step go although every beam
        // still reads too close; the step after is guarded as ever.
        let mut p = planner(Point::new(0, 3_000));
        let near = p.config().calibration().full_scale() / 2 + 100;
        let out = p.step_raw(at(0, 0, 90), &[FAR; 5]).command;
        assert!(out.step_mm >= 400, "{out:?}");
        let mut heading = Angle::from_deg(90);
        let mut cycles = 0;
        let back = loop {
            let pose = Pose {
                position: Point::new(0, 400),
                heading,
            };
            let out = p.step_raw(pose, &[near; 5]).command;
            cycles += 1;
            if out.step_mm > 0 {
                break out;
            }
            assert!(cycles < 100, "still turning after {cycles} cycles");
            heading = out.heading;
        };
        assert!(
            p.turned_in_place == 0 && cycles > 4 * 9,
            "after {cycles} cycles"
        );
        assert_eq!(back.heading, Angle::from_deg(-90), "due south");
        assert_eq!(back.step_mm, 400, "back to where the run began");
        assert_eq!(p.guard_raw(&[near; 5], 400), Guard::Continue);
        // A thing the beams range in the way stops it all the same.
        let cal = p.config().calibration();
        let c200 = (0..cal.full_scale())
            .find(|&c| cal.reading(c).range_mm().is_some_and(|mm| mm <= 200))
            .unwrap();
        assert_eq!(
            p.guard_raw(&[near, near, c200, near, near], 400),
            Guard::Stop
        );
        // Backed out: the next cycle plans and guards as before.
        let _ = p.step_raw(at(0, 0, -90), &[near; 5]);
        assert_eq!(p.guard_raw(&[near; 5], 100), Guard::Stop);
    }

    #[test]
    fn a_long_way_in_is_backed_out_no_farther_than_a_step() {
        // Four advances north (760 mm each, the longest step) into the
        // pocket: the way back is 3,040 mm, the back-out the sensors'
        // range of it.
        let mut p = planner(Point::new(0, 9_000));
        let near = p.config().calibration().full_scale() / 2 + 100;
        let mut y = 0;
        for _ in 0..4 {
            let out = p.step_raw(at(0, y, 90), &[FAR; 5]).command;
            assert_eq!((out.heading, out.step_mm), (Angle::from_deg(90), 760));
            y += 760;
        }
        let mut heading = Angle::from_deg(90);
        let back = loop {
            let pose = Pose {
                position: Point::new(0, y),
                heading,
            };
            let out = p.step_raw(pose, &[near; 5]).command;
            if out.step_mm > 0 {
                break out;
            }
            heading = out.heading;
        };
        assert_eq!(back.heading, Angle::from_deg(-90));
        assert_eq!(
            back.step_mm, 800,
            "the sensors' range, not the 3,040 mm run"
        );
    }

    #[test]
    fn held_on_a_spot_the_fold_back_filter_compares_sensors_by_way() {
        // The −40° sensor reads a wall near every cycle, the others nothing,
        // and the rover turns 40° left a cycle on one spot (its steps
        // stopped before they begin). Then every sensor reads clear. Before
        // three turns round, the −40° sensor's clear reading is compared
        // with its own last one (near, of another way) and distrusted;
        // after, with the 0° sensor's, which looked its way (clear), and
        // trusted.
        let after = |cycles: usize| {
            let mut p = planner(Point::new(3_000, 0));
            let (_, near) = p.config().calibration().window();
            let mut heading = Angle::ZERO;
            for _ in 0..cycles {
                let pose = Pose {
                    position: Point::new(0, 0),
                    heading,
                };
                let _ = p.step_raw(pose, &[near, FAR, FAR, FAR, FAR]);
                heading = heading.add(Angle::from_deg(40));
            }
            let pose = Pose {
                position: Point::new(0, 0),
                heading,
            };
            let _ = p.step_raw(pose, &[FAR; 5]);
            (p.turned_in_place, p.last_readings()[0])
        };
        let (turned, early) = after(3);
        assert!(turned < 3 * FULL_TURN, "{turned}");
        assert_eq!(early, Reading::TooClose);
        let (turned, late) = after(40);
        assert!(turned >= 3 * FULL_TURN, "{turned}");
        assert_eq!(late, Reading::Clear);
    }

    #[test]
    fn steps_stopped_before_they_began_count_as_turns_on_the_spot() {
        // A wall 300 mm ahead of the front sensor whichever way the rover
        // faces: each cycle the force turns it 40° to the sector edge with a
        // step along it, and the executor's guard, which sees the wall again
        // after the turn, stops the step before it begins, so the rover only
        // turns. After a full turn on the spot it advances where it faces
        // (the guard then sees what the planner saw). When every commanded
        // step reset the count, it turned round for ever, 40° and a 499 mm
        // step a cycle: checked. Without the retreat limit, whose turn-first
        // cycles command no step.
        let mut p = planner_without_retreat(Point::new(3_000, 0));
        let raw = [FAR, FAR, count_for(&p, 300), FAR, FAR];
        let mut heading = Angle::ZERO;
        let mut turned = 0u32;
        for _ in 0..20 {
            let pose = Pose {
                position: Point::new(0, 0),
                heading,
            };
            let out = p.step_raw(pose, &raw).command;
            assert!(out.step_mm > 0);
            if out.heading == heading {
                // The turns so far and the 40° this cycle would add.
                let edge = Angle::from_deg(40).0 as u32;
                assert!(turned + edge >= FULL_TURN, "before a full turn: {turned}");
                return;
            }
            turned += out.heading.sub(heading).abs_signed() as u32;
            heading = out.heading;
        }
        panic!("still turning on the spot after 20 cycles");
    }

    #[test]
    fn a_step_that_moved_the_rover_restarts_the_count() {
        // As above, but after five stopped steps (200°) one step moves the
        // rover: at the new spot the count starts again, so the advance
        // where it faces comes only after a full turn there (it came after
        // four more cycles when the count carried over: checked). Without
        // the retreat limit, as above.
        let mut p = planner_without_retreat(Point::new(3_000, 0));
        let raw = [FAR, FAR, count_for(&p, 300), FAR, FAR];
        let mut pose = Pose::default();
        let mut cycles_here = 0;
        for cycle in 0..30 {
            if cycle == 5 {
                pose.position = Point::new(0, 500);
                cycles_here = 0;
            }
            let out = p.step_raw(pose, &raw).command;
            assert!(out.step_mm > 0);
            cycles_here += 1;
            if out.heading == pose.heading {
                assert!(
                    cycle > 5 && cycles_here >= 9,
                    "cycle {cycle}, {cycles_here} here"
                );
                return;
            }
            pose.heading = out.heading;
        }
        panic!("still turning on the spot after 30 cycles");
    }

    #[test]
    fn implausible_reading_is_a_fault_and_a_stop() {
        let mut p = planner(Point::new(3_000, 0));
        let out = p.step_raw(at(0, 0, 0), &[FAR, FAR, 5_000, FAR, FAR]);
        assert_eq!(out.status, Status::SensorFault);
        assert_eq!(out.command.step_mm, 0);
    }

    /// A count the same in eight views in a row, each after an advance, is
    /// a stuck sensor: a stop with a fault. Views on one spot do not count,
    /// and one count that changes starts the count again.
    #[test]
    fn a_sensor_stuck_while_the_rover_advances_is_a_fault() {
        let cfg = ConfigBuilder::new(AdcProfile::AVR_10BIT_5V)
            .build()
            .unwrap();
        let mut p = Planner::new(cfg, Point::new(30_000, 0));
        let counts = |k: i16| {
            let noisy = (60 + k % 3) as u16;
            [noisy, noisy + 1, 57, noisy, noisy + 2]
        };
        // On the spot, any number of views.
        for k in 0..20 {
            let out = p.step_raw(at(0, 0, 0), &counts(k));
            assert_eq!(out.status, Status::Moving, "view {k} on the spot");
        }
        // Advancing: the last view on the spot and seven after advances
        // with one count are a fault.
        for k in 1..=7 {
            let out = p.step_raw(at(20 * k, 0, 0), &counts(k));
            let want = if k < 7 {
                Status::Moving
            } else {
                Status::SensorFault
            };
            assert_eq!(out.status, want, "view {k} after an advance");
        }
        // The sensor changes: trusted again.
        let mut changed = counts(8);
        changed[2] = 58;
        assert_eq!(p.step_raw(at(160, 0, 0), &changed).status, Status::Moving);
        // A change in a view on the spot ends a streak too: six views
        // after advances, one on the spot with another count, and eight
        // more after advances before the fault.
        let mut p = Planner::new(cfg, Point::new(30_000, 0));
        let mut x = 0;
        let mut view = |p: &mut Planner, advance: bool, c: u16| {
            x += if advance { 20 } else { 0 };
            let mut raw = counts(x / 20);
            raw[2] = c;
            p.step_raw(at(x, 0, 0), &raw).status
        };
        for _ in 0..6 {
            assert_eq!(view(&mut p, true, 57), Status::Moving);
        }
        assert_eq!(view(&mut p, false, 59), Status::Moving);
        for k in 1..=8 {
            let want = if k < 8 {
                Status::Moving
            } else {
                Status::SensorFault
            };
            assert_eq!(view(&mut p, true, 57), want, "view {k} after the change");
        }
        // Off (noise-free sensors): never.
        let off = ConfigBuilder::new(AdcProfile::AVR_10BIT_5V)
            .frozen_after_views(0)
            .build()
            .unwrap();
        let mut p = Planner::new(off, Point::new(30_000, 0));
        for k in 1..=50 {
            assert_eq!(
                p.step_raw(at(20 * k, 0, 0), &counts(k)).status,
                Status::Moving
            );
        }
    }

    #[test]
    fn sensor_trait_and_guard() {
        let mut p = planner(Point::new(3_000, 0));
        let mut s = ScriptedSensors::new(&[[FAR; 5]]);
        assert!(p.step(at(0, 0, 0), &mut s).is_ok());
        assert!(p.step(at(0, 0, 0), &mut s).is_err());
        assert_eq!(p.guard_raw(&[FAR; 5], 700), Guard::Continue);
        assert_eq!(p.guard_raw(&[FAR, FAR, 500, FAR, FAR], 700), Guard::Stop);
    }

    #[test]
    fn walled_in_goal_becomes_unreachable() {
        // The rover never gets nearer: the escape gives up after its
        // budget, then the boundary follower after its own (it never
        // meets a boundary to go round).
        let mut p = planner(Point::new(3_000, 0));
        let esc = p.config().escape;
        let budget = esc.give_up_steps * (follow::BUDGET_GIVE_UPS + 1) + 10;
        let mut status = Status::Moving;
        for _ in 0..budget {
            status = p.step_raw(at(0, 0, 180), &[FAR; 5]).status;
            if status == Status::Unreachable {
                break;
            }
        }
        assert_eq!(status, Status::Unreachable);
        assert_eq!(
            p.step_raw(at(10, 0, 0), &[FAR; 5]).status,
            Status::Unreachable
        );
        p.set_goal(Point::new(0, 3_000));
        assert_eq!(p.step_raw(at(0, 0, 90), &[FAR; 5]).status, Status::Moving);
    }

    #[test]
    fn after_the_escape_gives_up_the_rover_follows_instead() {
        // Held on one spot: no progress, so the escape gives up after its
        // budget of 10 cycles. Without boundary following that is
        // "unreachable"; with it the rover seeks the goal (straight ahead,
        // the way free) and the potential field is not asked again.
        let run = |follow| {
            let escape = EscapeConfig {
                give_up_steps: 10,
                follow,
                ..EscapeConfig::default()
            };
            let mut p = planner_with(escape, Point::new(3_000, 0));
            let outs: Vec<Output> = (0..20)
                .map(|_| p.step_raw(at(0, 0, 0), &[FAR; 5]))
                .collect();
            (outs, p.follow().active())
        };
        let (off, following) = run(false);
        assert!(!following);
        let gave_up = off
            .iter()
            .position(|o| o.status == Status::Unreachable)
            .expect("gave up");
        let (on, following) = run(true);
        assert!(following);
        for o in &on[gave_up..] {
            assert_eq!(o.status, Status::Moving);
            assert_eq!(o.command.heading, Angle::ZERO);
            assert_eq!(o.command.step_mm, follow::FOLLOW_STEP_MM);
        }
    }

    #[test]
    fn the_first_loop_round_a_boundary_hands_back_to_the_field() {
        // A boundary all round, 150 mm off every beam, the goal 30 m away
        // behind it: the escape gives up after 10 cycles held on one spot,
        // the follower meets the boundary there and is taken round it
        // (the poses below) back to its hit point from the other side.
        let escape = EscapeConfig {
            give_up_steps: 10,
            ..EscapeConfig::default()
        };
        let mut p = planner_with(escape, Point::new(-30_000, 0));
        let wall = [count_for(&p, 150); 5];
        let round = |p: &mut Planner, (x, y): (i16, i16)| {
            let mut status = Status::Moving;
            for _ in 0..30 {
                status = p.step_raw(at(x, y, 180), &wall).status;
                if p.follow().following() {
                    break;
                }
            }
            assert!(p.follow().following(), "following from ({x}, {y})");
            assert_eq!(p.follow().hit(), Some(Point::new(x, y)));
            assert_eq!(status, Status::Moving);
            let track = [(700, 0), (2_000, 0), (2_000, 2_000), (0, 2_000), (0, 700)];
            for (dx, dy) in track {
                let out = p.step_raw(at(x + dx, y + dy, 180), &wall);
                assert_eq!(out.status, Status::Moving, "at ({}, {})", x + dx, y + dy);
            }
            p.step_raw(at(x, y + 250, 180), &wall).status
        };
        // The first loop: back to the potential field, not "unreachable".
        assert_eq!(round(&mut p, (0, 0)), Status::Moving);
        assert!(!p.follow().active());
        // Its give-up count starts again; the second loop is the answer.
        assert_eq!(round(&mut p, (0, 250)), Status::Unreachable);
    }

    proptest::proptest! {
        /// The answers the planner keeps (the goal's distance and bearing,
        /// the escape's force, the midpoint force) change no command: each
        /// cycle against a copy that has forgotten them. Turns on the spot
        /// (the same position, another heading) are where they are used.
        #[test]
        fn kept_answers_change_no_command(
            cycles in proptest::collection::vec(
                ((0i16..6, 0i16..6, 0u8..3), proptest::array::uniform5(0u16..600)),
                1..150,
            ),
        ) {
            let mut p = planner(Point::new(2_000, 1_500));
            for ((i, j, turn), raw) in cycles {
                let pose = at(150 * i, 150 * j, 120 * turn as i16);
                let mut fresh = p.clone();
                fresh.kept_goal = None;
                fresh.kept_midpoint = None;
                fresh.escape.forget_kept();
                let want = fresh.step_raw(pose, &raw);
                proptest::prop_assert_eq!(p.step_raw(pose, &raw), want);
            }
        }
    }
}
