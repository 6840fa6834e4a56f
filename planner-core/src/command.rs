//! What the planner tells the executor each cycle, and the safety rule that
//! bounds it (ALGORITHMS.md §5): a commanded translation never enters space
//! that the current readings do not show free, allowing for the robot radius
//! and a clearance margin; during the advance the executor calls the guard
//! with fresh readings and stops short if something appears.

use crate::config::Config;
use crate::fixed::{isqrt, mul_q14, Angle, Dir};
use crate::sensors::{Reading, Readings, SENSOR_COUNT};

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
    /// Escape made no progress within its budget: stop, the goal cannot be
    /// reached. The step is zero.
    Unreachable,
    /// A sensor gave a reading it cannot produce: stop (the step is zero).
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
    /// Stay put, facing `heading`, with `status`.
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
/// Stand-off: an obstacle in the corridor is also kept the sensors'
/// minimum range (`standoff_mm`) beyond the sensor faces, so the rover never
/// drives an obstacle into the fold-back region where it would read as far.
pub fn free_distance_mm(cfg: &Config, readings: &Readings, relative: Angle) -> u16 {
    let rs = (cfg.robot_radius_mm + cfg.clearance_mm) as i32;
    let reach = (cfg.sensor_offset_mm + cfg.sensor_range_mm) as i32;
    let standoff = (cfg.sensor_offset_mm + cfg.standoff_mm) as i32;
    // The usual headings are a sensor's (straight ahead, a sector edge):
    // their sine and cosine are in the config already.
    let dir = match cfg.sensor_angles.iter().position(|&a| a == relative) {
        Some(i) => cfg.sensor_dirs[i.min(SENSOR_COUNT - 1)],
        None => Dir::of(relative),
    };
    let (c, s) = (dir.c, dir.s);
    let mut free = (reach - rs).max(0);
    for (&r, dir) in readings.iter().zip(cfg.sensor_dirs.iter()) {
        // A clear beam never lowers `free`: its end is `reach` from the
        // centre at some angle δ from the path, and the disc meets it after
        // reach·cos δ − √(rs² − reach²·sin² δ), which grows with |δ| from
        // its value at δ = 0, reach − rs, where `free` starts.
        let e = match r {
            Reading::Range(mm) => cfg.sensor_offset_mm as i32 + mm as i32,
            Reading::Clear => continue,
            Reading::TooClose | Reading::Implausible => cfg.sensor_offset_mm as i32,
        };
        // The beam end in the robot frame, then in the frame of `relative`.
        let (x, y) = dir.scaled(e);
        let along = mul_q14(x, c) + mul_q14(y, s);
        let lateral = mul_q14(y, c) - mul_q14(x, s);
        if lateral.abs() < rs {
            free = free.min((along - standoff).max(0));
            if free == 0 {
                break;
            }
            // The chord can only lower `free` if `along − rs` is below it
            // (the half chord is at most rs): skip the square root otherwise.
            if along - rs < free {
                let half_chord = isqrt((rs * rs - lateral * lateral) as u32) as i32;
                free = free.min((along - half_chord).max(0));
            }
        }
    }
    free as u16
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
    use crate::config::ConfigBuilder;
    use crate::sensors::{AdcProfile, SENSOR_COUNT};

    #[test]
    fn status_codes_round_trip() {
        for s in [
            Status::Moving,
            Status::Arrived,
            Status::Unreachable,
            Status::SensorFault,
        ] {
            assert_eq!(Status::from_code(s.code()), Some(s));
        }
        assert_eq!(Status::from_code(4), None);
    }

    fn cfg() -> Config {
        ConfigBuilder::new(AdcProfile::AVR_10BIT_5V)
            .build()
            .unwrap()
    }

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
