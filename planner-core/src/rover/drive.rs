//! The rover's body: differential-drive odometry from wheel-encoder ticks,
//! and the turn-then-advance executor that carries out one [`Command`].
//!
//! Both firmwares share this code, so the only thing a board supplies is
//! pins: encoder tick counts in, wheel duties out. Nothing here is from the
//! papers; it is the executor that docs/algorithms.md §5 assumes (turn in place,
//! advance straight, ask the guard on the way).
//!
//! Formats (see [`crate::fixed`] for the rest): position in 1/4,096 mm (`i32`,
//! ±524 m), heading in 1/2³² of a turn (`u32`, wraps), so that sub-tick
//! motion accumulates without drift from rounding.

use crate::eapf::command::{Command, Guard};
use crate::fixed::{mul_q14, sat_i16, Angle, Point};
use crate::Pose;

/// The wheels and encoders of a rover, checked by [`Body::new`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Body {
    um_per_tick: u16,
    wheel_base_mm: u16,
}

/// Why [`Body::new`] refused a body.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BodyError {
    /// Wheel travel per tick outside [`Body::UM_PER_TICK`].
    UmPerTick(u16),
    /// Wheel base outside [`Body::WHEEL_BASE_MM`].
    WheelBase(u16),
}

impl Body {
    /// The reference rover: 65 mm wheels with 210 ticks per turn (an N20
    /// gear motor with a 7-pulse magnetic encoder, 1:30), 130 mm track.
    pub const REFERENCE: Body = Body {
        um_per_tick: 972,
        wheel_base_mm: 130,
    };

    /// Wheel travel per tick a body may have, µm: a tick of 1 µm to 1 cm.
    pub const UM_PER_TICK: core::ops::RangeInclusive<u16> = 1..=10_000;

    /// Wheel bases a body may have, mm.
    pub const WHEEL_BASE_MM: core::ops::RangeInclusive<u16> = 20..=2_000;

    /// A body with `um_per_tick` µm of wheel travel per encoder tick and
    /// `wheel_base_mm` between the wheels' contact points; outside the
    /// ranges above it is refused (a zero base would divide by zero, a huge
    /// tick overflow the odometry's formats).
    pub const fn new(um_per_tick: u16, wheel_base_mm: u16) -> Result<Body, BodyError> {
        if um_per_tick < *Self::UM_PER_TICK.start() || um_per_tick > *Self::UM_PER_TICK.end() {
            return Err(BodyError::UmPerTick(um_per_tick));
        }
        if wheel_base_mm < *Self::WHEEL_BASE_MM.start()
            || wheel_base_mm > *Self::WHEEL_BASE_MM.end()
        {
            return Err(BodyError::WheelBase(wheel_base_mm));
        }
        Ok(Body {
            um_per_tick,
            wheel_base_mm,
        })
    }

    /// Wheel travel per encoder tick, µm.
    pub const fn um_per_tick(self) -> u16 {
        self.um_per_tick
    }

    /// Distance between the wheel contact points, mm.
    pub const fn wheel_base_mm(self) -> u16 {
        self.wheel_base_mm
    }

    /// Heading change per tick of wheel difference, 1/2³² turn:
    /// Δθ = (Δr − Δl)·s / b radians (the differential-drive model).
    fn angle_per_tick(self) -> i32 {
        // 2³² / (2π) = 683,565,275.6; s/b in µm/µm. Done once, at build.
        let num = self.um_per_tick as i64 * 683_565_276;
        let den = self.wheel_base_mm as i64 * 1_000;
        (num / den) as i32
    }
}

/// Dead reckoning from encoder ticks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Odometry {
    x: i32,
    y: i32,
    heading: u32,
    /// Path length, 1/4,096 mm (wraps after 1 km; only differences are used).
    travelled: u32,
    q12_per_tick: i32,
    angle_per_tick: i32,
    /// Most ticks a wheel that one integration takes (see [`Odometry::update`]).
    piece_ticks: u16,
}

impl Odometry {
    /// Start at `pose`.
    pub fn new(body: Body, pose: Pose) -> Self {
        let q12_per_tick = ((body.um_per_tick as i32) * 4_096 + 500) / 1_000;
        let angle_per_tick = body.angle_per_tick();
        // A piece of `n` ticks a wheel moves at most n·q12 (1/4,096 mm),
        // which `mul_q14` takes below 2³¹/2¹⁴ = 131,072; and turns by at
        // most 2n·angle_per_tick, below 2³¹. Both are positive for every
        // body `Body::new` accepts.
        let piece_ticks = (131_071 / q12_per_tick).min(i32::MAX / 2 / angle_per_tick);
        let mut o = Odometry {
            x: 0,
            y: 0,
            heading: 0,
            travelled: 0,
            q12_per_tick,
            angle_per_tick,
            piece_ticks: piece_ticks.clamp(1, i16::MAX as i32) as u16,
        };
        o.set_pose(pose);
        o
    }

    /// Reset the pose (a new start, or an external fix).
    pub fn set_pose(&mut self, pose: Pose) {
        self.x = (pose.position.x as i32) << 12;
        self.y = (pose.position.y as i32) << 12;
        self.heading = (pose.heading.0 as u32) << 16;
    }

    /// Add the ticks counted since the last update (signed: backwards is
    /// negative). Integrates along the mean heading of the interval.
    ///
    /// Any count is taken: a long interval (a stalled control loop) is
    /// integrated in pieces small enough for the 32-bit formats (at most
    /// 32 ticks a wheel for [`Body::REFERENCE`], 130 ms at cruise speed).
    pub fn update(&mut self, left: i16, right: i16) {
        let most = self.piece_ticks as i32;
        let (mut left, mut right) = (left as i32, right as i32);
        loop {
            // `max` then `min`, not `clamp`: bounds held in a field are not
            // known to be ordered, and `clamp` would link a panic.
            let (l, r) = (left.max(-most).min(most), right.max(-most).min(most));
            self.integrate(l, r);
            (left, right) = (left - l, right - r);
            if left == 0 && right == 0 {
                return;
            }
        }
    }

    /// One piece of [`Odometry::update`]: `left` and `right` at most
    /// `piece_ticks` each.
    #[cfg_attr(target_arch = "avr", inline(never))]
    fn integrate(&mut self, left: i32, right: i32) {
        if left == 0 && right == 0 {
            return;
        }
        let dtheta = (right - left) * self.angle_per_tick;
        let mid = Angle((self.heading.wrapping_add((dtheta / 2) as u32) >> 16) as u16);
        self.heading = self.heading.wrapping_add(dtheta as u32);
        let d = (left + right) * self.q12_per_tick / 2;
        self.x = self.x.saturating_add(mul_q14(d, mid.cos()));
        self.y = self.y.saturating_add(mul_q14(d, mid.sin()));
        self.travelled = self.travelled.wrapping_add(d.unsigned_abs());
    }

    /// The pose in the planner's formats. Its positions are 16-bit mm, so
    /// the rover works within ±32.767 m of the origin `set_pose` gives: past
    /// that the pose stays at the edge (the simulator refuses worlds that
    /// reach past it; a goal out of it does not parse).
    pub fn pose(&self) -> Pose {
        Pose {
            position: Point::new(
                sat_i16((self.x + 2_048) >> 12),
                sat_i16((self.y + 2_048) >> 12),
            ),
            heading: Angle(((self.heading.wrapping_add(1 << 15)) >> 16) as u16),
        }
    }

    /// Path length so far, mm (wrapping; subtract two readings).
    pub fn travelled_mm(&self) -> u16 {
        (self.travelled >> 12) as u16
    }
}

/// Duties of the two wheels, −255 (full reverse) … 255 (full forward).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Wheels {
    /// Left wheel duty.
    pub left: i16,
    /// Right wheel duty.
    pub right: i16,
}

impl Wheels {
    /// Both motors off.
    pub const STOP: Wheels = Wheels { left: 0, right: 0 };
}

/// How the executor drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ExecutorConfig {
    /// A turn ends when the heading is this close to the command.
    pub turn_tolerance: Angle,
    /// Largest and smallest spin duty (the smallest still moves the wheels).
    pub turn_duty: (i16, i16),
    /// Cruise duty and the slowest duty that still moves.
    pub advance_duty: (i16, i16),
    /// Duty added per degree of heading error while advancing.
    pub hold_gain: i16,
    /// Slow down over this last part of a step, mm.
    pub slow_mm: u16,
    /// Ticks to stand still after a turn, before the advance: the guard's
    /// first reading of the way is then one the IR sensors took after the
    /// turn (a GP2Y0A21 gives a new value every 38.3 ± 9.6 ms). The step
    /// was planned from the view before the turn.
    pub settle_ticks: u16,
}

impl ExecutorConfig {
    /// The reference rover's.
    pub const DEFAULT: ExecutorConfig = ExecutorConfig {
        turn_tolerance: Angle::from_decideg(10),
        turn_duty: (160, 60),
        advance_duty: (220, 70),
        hold_gain: 12,
        slow_mm: 40,
        // 1 ms ticks in both firmwares: the sensors' longest period.
        settle_ticks: 48,
    };
}

impl Default for ExecutorConfig {
    fn default() -> Self {
        ExecutorConfig::DEFAULT
    }
}

/// What the executor is doing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Phase {
    /// Done with the last command: time to plan.
    Idle,
    /// Turning in place to `heading`, then advancing `step_mm`.
    Turn {
        /// Target heading.
        heading: Angle,
        /// Step to take after the turn.
        step_mm: u16,
        /// Has it spun yet (then it settles before the advance)?
        spun: bool,
    },
    /// Advancing along `heading` until `travelled_mm` reaches `end_mm`,
    /// after standing still for `settle` ticks.
    Advance {
        /// Heading to hold.
        heading: Angle,
        /// Odometry path length at which the step is complete.
        end_mm: u16,
        /// Ticks still to stand still (after a turn, see
        /// [`ExecutorConfig::settle_ticks`]).
        settle: u16,
    },
}

/// Turn-then-advance: one [`Command`] at a time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Executor {
    cfg: ExecutorConfig,
    phase: Phase,
}

impl Executor {
    /// An idle executor.
    pub fn new(cfg: ExecutorConfig) -> Self {
        Executor {
            cfg,
            phase: Phase::Idle,
        }
    }

    /// The current phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// Is it waiting for a command?
    pub fn is_idle(&self) -> bool {
        self.phase == Phase::Idle
    }

    /// Take a new command (replaces any command in progress).
    #[cfg_attr(target_arch = "avr", inline(never))]
    pub fn start(&mut self, command: Command) {
        self.phase = Phase::Turn {
            heading: command.heading,
            step_mm: command.step_mm,
            spun: false,
        };
    }

    /// Abandon the command (motors stop on the next tick).
    pub fn halt(&mut self) {
        self.phase = Phase::Idle;
    }

    /// One control tick: the wheel duties for the current pose. `guard` is
    /// asked, with the distance still to go, on every tick of an advance.
    pub fn tick(
        &mut self,
        pose: Pose,
        travelled_mm: u16,
        guard: impl FnOnce(u16) -> Guard,
    ) -> Wheels {
        let c = self.cfg;
        match self.phase {
            Phase::Idle => Wheels::STOP,
            Phase::Turn {
                heading,
                step_mm,
                spun,
            } => {
                let err = heading.sub(pose.heading);
                if err.abs_signed() <= c.turn_tolerance.0 {
                    self.phase = if step_mm == 0 {
                        Phase::Idle
                    } else {
                        Phase::Advance {
                            heading,
                            end_mm: travelled_mm.wrapping_add(step_mm),
                            settle: if spun { c.settle_ticks } else { 0 },
                        }
                    };
                    return Wheels::STOP;
                }
                self.phase = Phase::Turn {
                    heading,
                    step_mm,
                    spun: true,
                };
                // Duty proportional to the error (1 duty per 0.35°), bounded.
                // `max` then `min`: a configuration's bounds may be in
                // either order, and `clamp` would panic.
                let duty = ((err.abs_signed() >> 6) as i16)
                    .max(c.turn_duty.1)
                    .min(c.turn_duty.0);
                if err.signed() > 0 {
                    Wheels {
                        left: -duty,
                        right: duty,
                    }
                } else {
                    Wheels {
                        left: duty,
                        right: -duty,
                    }
                }
            }
            Phase::Advance {
                heading,
                end_mm,
                settle,
            } => {
                if settle > 0 {
                    self.phase = Phase::Advance {
                        heading,
                        end_mm,
                        settle: settle - 1,
                    };
                    return Wheels::STOP;
                }
                let remaining = end_mm.wrapping_sub(travelled_mm) as i16;
                if remaining <= 0 || guard(remaining as u16) == Guard::Stop {
                    self.phase = Phase::Idle;
                    return Wheels::STOP;
                }
                let remaining = remaining as u16;
                let (cruise, slow) = c.advance_duty;
                let base = if remaining >= c.slow_mm {
                    cruise
                } else {
                    let ramp = ((cruise - slow) as i32 * remaining as i32)
                        .checked_div(c.slow_mm as i32)
                        .unwrap_or(0);
                    (slow as i32 + ramp) as i16
                };
                // Heading hold: error in degrees (182 binary units per degree).
                let err_deg = (heading.sub(pose.heading).signed() / 182).clamp(-10, 10);
                let turn = err_deg * c.hold_gain;
                Wheels {
                    left: (base - turn).clamp(-255, 255),
                    right: (base + turn).clamp(-255, 255),
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn origin() -> Pose {
        Pose::default()
    }

    #[test]
    fn straight_ticks_move_along_the_heading() {
        let mut o = Odometry::new(Body::REFERENCE, origin());
        for _ in 0..1_000 {
            o.update(1, 1);
        }
        // 1,000 ticks × 0.972 mm = 972 mm.
        assert_eq!(o.pose().position, Point::new(972, 0));
        assert_eq!(o.pose().heading, Angle::ZERO);
        // Path length is floored: 1,000 × 3,981 / 4,096 = 971.9.
        assert_eq!(o.travelled_mm(), 971);
    }

    /// A long interval (a stalled loop) moves the pose as its ticks one by
    /// one would: 33 ticks a wheel overflowed the 32-bit product before.
    #[test]
    fn a_long_interval_is_its_ticks_one_by_one() {
        for (l, r) in [(33, 33), (1_000, 1_000), (-700, 700), (i16::MAX, i16::MAX)] {
            let mut at_once = Odometry::new(Body::REFERENCE, origin());
            at_once.update(l, r);
            let mut by_tick = Odometry::new(Body::REFERENCE, origin());
            let n = l.unsigned_abs().max(r.unsigned_abs()) as i32;
            for k in 1..=n {
                let step = |t: i16| (t as i32 * k / n - t as i32 * (k - 1) / n) as i16;
                by_tick.update(step(l), step(r));
            }
            let (a, b) = (at_once.pose(), by_tick.pose());
            assert!(
                (a.position.x - b.position.x).abs() <= 1
                    && (a.position.y - b.position.y).abs() <= 1
                    && a.heading.0.abs_diff(b.heading.0) <= 1,
                "{l} {r}: {a:?} against {b:?}"
            );
        }
        // Straight on from the origin: 33 ticks are 32.1 mm ahead, not behind.
        let mut o = Odometry::new(Body::REFERENCE, origin());
        o.update(33, 33);
        assert_eq!(o.pose().position, Point::new(32, 0));
    }

    /// Every body `Body::new` accepts takes any count, both extremes of
    /// both ranges included (the tests build with overflow checks).
    #[test]
    fn every_body_takes_any_count() {
        let (um, base) = (Body::UM_PER_TICK, Body::WHEEL_BASE_MM);
        for (s, b) in [
            (*um.start(), *base.start()),
            (*um.end(), *base.start()),
            (*um.start(), *base.end()),
            (*um.end(), *base.end()),
        ] {
            let mut o = Odometry::new(Body::new(s, b).unwrap(), origin());
            for (l, r) in [(i16::MAX, i16::MAX), (i16::MIN, i16::MAX), (i16::MIN, 7)] {
                o.update(l, r);
            }
        }
        assert_eq!(Body::new(0, 130), Err(BodyError::UmPerTick(0)));
        assert_eq!(Body::new(10_001, 130), Err(BodyError::UmPerTick(10_001)));
        assert_eq!(Body::new(972, 0), Err(BodyError::WheelBase(0)));
        assert_eq!(Body::new(972, 19), Err(BodyError::WheelBase(19)));
        assert_eq!(Body::new(972, 130), Ok(Body::REFERENCE));
    }

    /// Past the planner's 16-bit millimetres (±32.767 m), the pose stays at
    /// the edge: it does not jump to the other side.
    #[test]
    fn the_pose_saturates_at_the_edge_of_its_format() {
        let mut o = Odometry::new(Body::REFERENCE, origin());
        for _ in 0..40 {
            o.update(i16::MAX / 32, i16::MAX / 32);
        }
        assert_eq!(o.pose().position, Point::new(i16::MAX, 0));
    }

    #[test]
    fn spinning_in_place_turns_by_the_arc_over_the_base() {
        let mut o = Odometry::new(Body::REFERENCE, origin());
        // A quarter turn: each wheel travels π/2 · 65 mm = 102.1 mm = 105 ticks.
        for _ in 0..105 {
            o.update(-1, 1);
        }
        let deg = o.pose().heading.signed() as f64 * 360.0 / 65_536.0;
        // 105 ticks · 0.972 mm · 2 / 130 mm = 1.5702 rad = 89.97°.
        assert!((deg - 89.97).abs() < 0.05, "{deg}");
        assert_eq!(o.pose().position, Point::new(0, 0));
    }

    #[test]
    fn executor_turns_then_advances_then_goes_idle() {
        let mut e = Executor::new(ExecutorConfig::default());
        e.start(Command {
            heading: Angle::from_deg(90),
            step_mm: 100,
        });
        let w = e.tick(origin(), 0, |_| Guard::Continue);
        assert!(w.left < 0 && w.right > 0, "counter-clockwise spin: {w:?}");
        let facing = Pose {
            heading: Angle::from_deg(90),
            ..origin()
        };
        // Aligned after a spin: it stands still while the sensors take a
        // view of the new way (the guard is not asked), then advances.
        let settle = ExecutorConfig::default().settle_ticks;
        for _ in 0..=settle {
            let w = e.tick(facing, 0, |_| panic!("guard asked while settling"));
            assert_eq!(w, Wheels::STOP);
        }
        let w = e.tick(facing, 0, |rem| {
            assert_eq!(rem, 100);
            Guard::Continue
        });
        assert_eq!((w.left, w.right), (220, 220));
        // Near the end it slows down; at the end it stops and idles.
        let w = e.tick(facing, 80, |_| Guard::Continue);
        assert!(w.left < 220 && w.left >= 70);
        assert_eq!(e.tick(facing, 100, |_| Guard::Continue), Wheels::STOP);
        assert!(e.is_idle());
    }

    #[test]
    fn without_a_spin_it_advances_at_once() {
        let mut e = Executor::new(ExecutorConfig::default());
        e.start(Command {
            heading: Angle::ZERO,
            step_mm: 100,
        });
        // Already facing the heading: nothing turned, nothing to settle.
        assert_eq!(e.tick(origin(), 0, |_| Guard::Continue), Wheels::STOP);
        assert!(matches!(e.phase(), Phase::Advance { .. }));
        let w = e.tick(origin(), 0, |_| Guard::Continue);
        assert_eq!((w.left, w.right), (220, 220));
    }

    #[test]
    fn the_guard_stops_an_advance() {
        let mut e = Executor::new(ExecutorConfig::default());
        e.start(Command {
            heading: Angle::ZERO,
            step_mm: 300,
        });
        e.tick(origin(), 65_500, |_| Guard::Continue); // aligned: to Advance
                                                       // Path length wraps: 65,500 + 300 wraps past zero and still works.
        assert!(!e.is_idle());
        assert_eq!(e.tick(origin(), 10, |_| Guard::Stop), Wheels::STOP);
        assert!(e.is_idle());
    }

    #[test]
    fn heading_hold_steers_back() {
        let mut e = Executor::new(ExecutorConfig::default());
        e.start(Command {
            heading: Angle::ZERO,
            step_mm: 300,
        });
        e.tick(origin(), 0, |_| Guard::Continue);
        let drifted_left = Pose {
            heading: Angle::from_deg(3),
            ..origin()
        };
        let w = e.tick(drifted_left, 0, |_| Guard::Continue);
        assert!(w.left > w.right, "turn right to come back: {w:?}");
    }
}
