//! The classical artificial potential field (Khatib 1986,
//! docs/algorithms.md §1), on the same five IR sensors, as the baseline the EAPF is compared
//! with. It is meant to show the classical failures (local minima, goals
//! near obstacles, oscillation in narrow passages), so it has no memory and
//! no escape; it shares only the rover's safety rule (§5), so that it stops
//! rather than collides.
//!
//! Forces (the 1986 form, named as docs/algorithms.md §1 gives it):
//! - attractive `F_att = ξ (q_goal − q)`, ξ per metre (linear, not capped);
//! - repulsive, for each obstacle a sensor sees within the influence
//!   distance ρ: `F_rep = η (1/d − 1/ρ) (1/d²) · unit(q − o)`, d in metres.
//!
//! The robot moves a fixed step along `F_att + ΣF_rep`, never beyond the
//! free distance the readings show; with an obstacle in sight it turns at
//! most to the sensed sector's edge (the rover's rule, shared with the
//! EAPF planner), otherwise a force outside the sector gives a turn with
//! zero step.

use crate::eapf::command::{self, Command, Guard, Output, Status};
use crate::eapf::config::Config;
use crate::eapf::forces::obstacle_distance_mm;
use crate::eapf::sensors::{RawCounts, Reading};
use crate::fixed::{inverse_square_force, Force, FORCE_ONE};
use crate::{Planner, Point, Pose};

/// The baseline's parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ApfConfig {
    /// ξ, Q10 force units per metre of distance to the goal.
    pub xi: i32,
    /// η, Q10.
    pub eta: i32,
    /// Influence distance ρ, mm from the robot's centre.
    pub influence_mm: u16,
    /// The "small step", mm.
    pub step_mm: u16,
}

impl Default for ApfConfig {
    /// Gains 1 (as the liquid paper's comparison uses), ρ = 0.3 m (an obstacle
    /// a sensor sees at its 100 mm minimum is 0.2 m from the centre), step 0.1 m.
    fn default() -> Self {
        ApfConfig {
            xi: FORCE_ONE,
            eta: FORCE_ONE,
            influence_mm: 300,
            step_mm: 100,
        }
    }
}

/// The classical APF planner.
#[derive(Clone, Debug)]
pub struct ApfPlanner {
    config: Config,
    apf: ApfConfig,
    goal: Point,
}

impl ApfPlanner {
    /// A planner heading for `goal`, with the rover's `config` (sensors,
    /// radius, goal tolerance, safety margins) and the baseline's gains.
    pub fn new(config: Config, apf: ApfConfig, goal: Point) -> Self {
        ApfPlanner { config, apf, goal }
    }

    /// The configuration.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// The attractive plus repulsive force at `pose` with `readings`.
    pub fn force(&self, pose: Pose, readings: &[Reading; 5]) -> Force {
        let (gx, gy) = pose.position.to(self.goal);
        // ξ (q_goal − q), distances in m: Q10 · mm / 1000.
        let attract = Force {
            x: ((self.apf.xi as i64 * gx as i64) / 1_000) as i32,
            y: ((self.apf.xi as i64 * gy as i64) / 1_000) as i32,
        };
        let rho = self.apf.influence_mm.max(1) as i32;
        let mut f = attract;
        for (i, &r) in readings.iter().enumerate() {
            let Some(d) = obstacle_distance_mm(&self.config, r) else {
                continue;
            };
            let d = d.max(91) as i32;
            if d >= rho {
                continue;
            }
            // (1/d − 1/ρ) in Q10 per metre, times 1/d² in Q10, times η.
            let gap = (FORCE_ONE * 1_000) / d - (FORCE_ONE * 1_000) / rho;
            let per_eta = (gap as i64 * inverse_square_force(d as u16) as i64) >> 10;
            let mag = ((per_eta * self.apf.eta as i64) >> 10)
                .clamp(0, crate::fixed::MAX_SCALED as i64) as i32;
            let angle = self.config.sensor_angles()[i % 5];
            let away = pose.heading.add(angle).add(crate::fixed::Angle::HALF);
            f = f.plus(Force::along(away, mag));
        }
        f
    }

    /// One cycle from raw counts.
    pub fn step_raw(&mut self, pose: Pose, raw: &RawCounts) -> Output {
        let readings = Planner::readings_with(&self.config, raw);
        let stop = |status| Output::stop(pose.heading, status);
        if readings.contains(&Reading::Implausible) {
            return stop(Status::SensorFault);
        }
        let goal_mm = pose.position.distance_mm(self.goal);
        if goal_mm <= self.config.goal_tolerance_mm() {
            return stop(Status::Arrived);
        }
        let Some(mut heading) = self.force(pose, &readings).direction() else {
            return stop(Status::Moving); // a true equilibrium: stuck
        };
        // The rover's turn rule (shared with the EAPF planner, §5 and
        // lib.rs): with something in sight, turn at most to the sector's
        // edge, so the next cycle still sees it.
        let half = self.config.sector_half_width();
        let mut relative = heading.sub(pose.heading);
        let seen = readings.iter().any(|&r| {
            obstacle_distance_mm(&self.config, r).is_some_and(|d| d < self.apf.influence_mm)
        });
        if seen && relative.abs_signed() > half.0 {
            relative = if relative.signed() > 0 {
                half
            } else {
                half.neg()
            };
            heading = pose.heading.add(relative);
        }
        let step = if relative.abs_signed() > half.0 {
            0
        } else {
            self.apf
                .step_mm
                .min(command::free_distance_mm(&self.config, &readings, relative))
                .min(goal_mm)
        };
        Output {
            command: Command {
                heading,
                step_mm: step,
            },
            status: Status::Moving,
        }
    }

    /// The guard during an advance (the same as the EAPF planner's).
    pub fn guard_raw(&self, raw: &RawCounts, remaining_mm: u16) -> command::Guard {
        command::guard(
            &self.config,
            &Planner::readings_with(&self.config, raw),
            remaining_mm,
        )
    }
}

impl crate::Navigator for ApfPlanner {
    fn step_raw(&mut self, pose: Pose, raw: &RawCounts) -> Output {
        ApfPlanner::step_raw(self, pose, raw)
    }
    fn guard_raw(&mut self, raw: &RawCounts, remaining_mm: u16) -> Guard {
        ApfPlanner::guard_raw(self, raw, remaining_mm)
    }
    fn config(&self) -> &Config {
        ApfPlanner::config(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eapf::config::ConfigBuilder;
    use crate::eapf::sensors::AdcProfile;
    use crate::fixed::Angle;

    fn apf(goal: Point) -> ApfPlanner {
        let cfg = ConfigBuilder::new(AdcProfile::AVR_10BIT_5V)
            .build()
            .unwrap();
        ApfPlanner::new(cfg, ApfConfig::default(), goal)
    }

    #[test]
    fn attraction_is_linear_in_the_distance() {
        let p = apf(Point::new(2_000, 0));
        let clear = [Reading::Clear; 5];
        let f = p.force(Pose::default(), &clear);
        // ξ = 1 per metre, 2 m away: 2 units along +x.
        assert_eq!((f.x, f.y), (2 * FORCE_ONE, 0));
    }

    #[test]
    fn repulsion_by_hand() {
        // At the goal itself: no attraction.
        let p = apf(Point::new(0, 0));
        // Front sensor, obstacle 150 mm from the face: d = 250 mm = 0.25 m.
        // η (1/0.25 − 1/0.3) / 0.25² = 0.667 · 16 = 10.67 units, along −x.
        // In Q10: (4,096 − 3,413) · 16,384 / 1,024 = 10,928 (10.67 · 1,024
        // = 10,923; the 5 come from 1/ρ truncated to 3,413).
        let mut r = [Reading::Clear; 5];
        r[2] = Reading::Range(150);
        let f = p.force(Pose::default(), &r);
        assert_eq!((f.x, f.y), (-10_928, 0));
        // Beyond the influence distance (d = 0.35 m): nothing.
        r[2] = Reading::Range(250);
        assert_eq!(p.force(Pose::default(), &r), Force::ZERO);
    }

    #[test]
    fn a_wall_ahead_makes_the_classical_local_minimum() {
        // Goal 1 m straight ahead, a wall 150 mm from the faces (d = 0.25 m):
        // attraction 1 unit, repulsion 10.7 units: the force points back;
        // the rover turns to the sector's edge: the classical trap, where
        // it turns back and forth in front of the wall.
        let mut p = apf(Point::new(1_000, 0));
        let cal = *p.config().calibration();
        let c150 = (0..1023)
            .find(|&c| cal.reading(c).range_mm().is_some_and(|mm| mm <= 150))
            .unwrap();
        // The others at their phantom level (0.28 V): nothing in range.
        let out = p.step_raw(Pose::default(), &[57, 57, c150, 57, 57]);
        assert_eq!(out.command.heading.abs_signed(), Angle::from_deg(40).0);
        assert_eq!(out.status, Status::Moving);
    }
}
