//! # planner-core
//!
//! The navigation brain of a two-wheel rover that sees through five infrared
//! range sensors: the Enhanced Artificial Potential Field planner (EAPF,
//! Mohamed & Abbas 2013) with virtual-obstacle escape from local minima
//! (Moaveni & Ghanbari Gol), in fixed point, without allocation or `unsafe`.
//! The same code runs in the host simulator, on an ATmega328P and on an
//! STM32F4, and gives the same commands bit for bit from the same inputs.
//!
//! Each cycle the caller passes the pose (from odometry) and the five raw
//! ADC counts; the planner returns a [`Command`] (world heading, step length)
//! and a [`Status`]. The executor turns in place, then advances, calling
//! [`Planner::guard_raw`] with fresh counts before it drives and during the
//! advance (after a turn it stands still for one sensor period first, so
//! that the guard's first look is at the new way: the step was planned
//! from the view before the turn). What the guard's beams see beside the
//! way is kept ([`eapf::command::Flank`]): the guard's looks are inputs of the
//! next steps as much as the counts the steps are given.
//!
//! ```
//! use planner_core::{AdcProfile, ConfigBuilder, Planner, Point, Pose, Angle, Status};
//! let cfg = ConfigBuilder::new(AdcProfile::AVR_10BIT_5V).build().unwrap();
//! let mut planner = Planner::new(cfg, Point::new(3_000, 0));
//! let pose = Pose { position: Point::new(0, 0), heading: Angle::ZERO };
//! // Nothing in sight: each sensor at its phantom level (0.28 V of 5 V).
//! let out = planner.step_raw(pose, &[57; 5]);
//! assert_eq!(out.status, Status::Moving);
//! assert_eq!(out.command.heading, Angle::ZERO);
//! assert_eq!(out.command.step_mm, 760); // sensor reach minus the widened disc
//! ```
//!
//! The layers, each depending only on those above it:
//!
//! - [`fixed`] (the fixed-point formats and the pose) and [`ring`]
//!   (bounded buffers): what every planner is built of;
//! - [`eapf`], the product planner, one module per concept of the papers:
//!   [`eapf::sensors`], [`eapf::forces`], [`eapf::memory`] (remembered
//!   collision points), [`eapf::escape`] (virtual obstacles),
//!   [`eapf::follow`] (boundary following once the escape gives up),
//!   [`eapf::command`] (the output, the safety rule and the guard),
//!   [`eapf::config`];
//! - [`peers`], the sensor-only planners it is measured against (the
//!   classical APF baseline, Bug2, TangentBug, VFH+, the free-space grid),
//!   and [`maps`], the planners over a known map ([`maps::liquid`], the
//!   liquid-movement planner; [`maps::route`], the Dijkstra +
//!   potential-field route layer): they use the product planner's
//!   sensing, safety rule and configuration;
//! - [`rover`], what the firmwares share beside a planner: odometry and
//!   the turn-then-advance executor ([`rover::drive`]), the serial command
//!   lines ([`rover::protocol`]).
//!
//! Crates: `heapless` for the bounded buffers (fixed capacity, no allocator);
//! `embedded-hal` 0.2 (feature `hal02`) for the ADC adapter, because 1.0 has
//! no ADC trait; `defmt` (feature `defmt`) for logging the types on target.
//!
//! Sensors mounted on the rim (the default) read an obstacle within their
//! 100 mm minimum range as farther; [`ConfigBuilder::sensors_set_back`]
//! mounts them that far behind it, with the planner's rules for them
//! (feature `set-back`, on by default; the firmwares build without it
//! unless asked).
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod fixed;
pub mod maps;
pub mod peers;
pub mod ring;
pub mod rover;

// Declared last: the order of the definitions steers LLVM's inlining in the
// AVR image, and with the product planner's last it fits an Uno with room
// to spare (the tests of `tests/tests/avr_firmware.rs` hold its size).
pub mod eapf;

pub use eapf::command::{BrokenRule, Command, Guard, Output, Status};
pub use eapf::config::{Config, ConfigBuilder, ConfigError};
pub use eapf::escape::{EscapeConfig, Verdict};
pub use eapf::sensors::{
    AdcProfile, Calibration, IrSensors, RawCounts, Reading, Readings, ScriptedSensors, SENSOR_COUNT,
};
pub use eapf::{Mode, Planner};
pub use fixed::{Angle, Dir, Force, Point, Pose};

/// A planner the rover's executor drives, whatever it decides by: each
/// cycle the pose and the five raw counts in, a command and a status out;
/// during the advance the guard, with fresh counts and the part of the
/// step still to go. The product planner ([`Planner`]), the baseline
/// ([`peers::apf::ApfPlanner`]), the route layer ([`maps::route::RoutePlanner`]) and
/// the peers ([`peers`]) all are, so that one executor and one simulator
/// run them all.
pub trait Navigator {
    /// One cycle from raw ADC counts.
    fn step_raw(&mut self, pose: Pose, raw: &RawCounts) -> Output;
    /// The guard during an advance.
    fn guard_raw(&mut self, raw: &RawCounts, remaining_mm: u16) -> Guard;
    /// The rover's configuration.
    fn config(&self) -> &Config;
}
