//! The EAPF forces (Mohamed & Abbas 2013, §5; docs/algorithms.md §2), each a
//! [`Force`] pointing the way the paper describes (eq. 16's printed signs are
//! inconsistent; the directions are the design).

use crate::eapf::config::{Config, MAX_GAIN};
use crate::eapf::sensors::{Reading, Readings, SENSOR_COUNT};
use crate::fixed::{inverse_square_force, mul_q14, Angle, Dir, Force, MAX_SCALED};

// The attraction, midpoint and off-sensor forces scale a direction by a
// gain without a clamp (`Force::along_bounded`).
const _: () = assert!(MAX_GAIN <= MAX_SCALED);

/// A collision point: a reading inside the swept corridor of the next step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CollisionPoint {
    /// Which sensor saw it.
    pub sensor: u8,
    /// Its distance from the robot's centre, mm.
    pub distance_mm: u16,
}

/// Distance from the robot's centre to the obstacle a reading shows, mm:
/// `None` for "clear" and for a reading that is not trusted as an obstacle
/// position. "Too close" is an obstacle at the sensor face.
pub fn obstacle_distance_mm(cfg: &Config, r: Reading) -> Option<u16> {
    Some(cfg.sensor_offset_mm.saturating_add(r.obstacle_mm()?))
}

/// Collision points (eqs. 7, 8): a detection at distance `D` from the centre
/// along sensor angle `θs` counts when `D·|sin θs| ≤ radius + clearance`
/// (inside the corridor, with our safety margin) and `D·cos θs ≤ step`.
#[cfg_attr(target_arch = "avr", inline(never))]
pub fn collision_points(
    cfg: &Config,
    readings: &Readings,
    step_mm: u16,
) -> heapless::Vec<CollisionPoint, SENSOR_COUNT> {
    let mut out = heapless::Vec::new();
    // Zipped, not indexed: an index `% SENSOR_COUNT` to keep the panic path
    // out costs a 16-bit division per sensor on the AVR.
    let per_sensor = readings
        .iter()
        .zip(cfg.sensor_dirs.iter())
        .zip(cfg.corridor_mm.iter());
    for (i, ((&r, dir), &corridor)) in per_sensor.enumerate() {
        if let Some(d) = obstacle_distance_mm(cfg, r) {
            // `d·|sin θs| ≤ radius + clearance` as `d ≤` its precomputed limit.
            let inside = d <= corridor;
            if inside && mul_q14(d as i32, dir.cos()) <= step_mm as i32 {
                let _ = out.push(CollisionPoint {
                    sensor: i as u8,
                    distance_mm: d,
                });
            }
        }
    }
    out
}

/// Attractive force (eqs. 5, 6): constant magnitude ξ_att towards the target.
pub fn attractive(cfg: &Config, bearing: Angle) -> Force {
    Force::along_bounded(bearing, cfg.xi_att)
}

/// Eq. 10 for one collision point `distance_mm` away along the world
/// direction `toward`: `1/d²` pointing back from it. The repulsive force
/// (eq. 9, `Σ (P_R − P_Ci) / d³`) is the sum over the cycle's collision
/// points; the planner sums it in the loop that also places them.
pub fn repulsion(toward: Dir, distance_mm: u16) -> Force {
    // At most 1.024e9 / 91² (`inverse_square_force`): within `MAX_SCALED`.
    Force::along_dir_bounded(-toward, inverse_square_force(distance_mm))
}

/// World direction of sensor `i`'s beam for a robot heading `heading`.
/// An index past the last sensor reads as the last (clamped, not `% 5`: a
/// division per call on the AVR, and no panic path either way).
pub fn sensor_direction(cfg: &Config, heading: Dir, i: usize) -> Dir {
    cfg.sensor_dirs[i.min(SENSOR_COUNT - 1)].rotated(heading)
}

/// Midpoint repulsive force (eqs. 12, 13): constant magnitude ξ_MP away from
/// the midpoint of the active remembered points. Takes `Σ(P_R − P_i)`, whose
/// direction is that of `P_R − P_M`.
pub fn midpoint(cfg: &Config, away_x: i32, away_y: i32) -> Force {
    if away_x == 0 && away_y == 0 {
        return Force::ZERO;
    }
    Force::along_bounded(Angle::atan2(away_y, away_x), cfg.xi_mp)
}

/// The motion class relative to the target (paper §5.5 a).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Motion {
    /// Heading at the target (within the DM tolerance).
    Direct,
    /// Circling the target clockwise: the target is on the robot's right.
    Clockwise,
    /// Circling the target counter-clockwise: the target is on the left.
    CounterClockwise,
}

/// Classify the robot's motion from its heading and the target bearing.
pub fn motion(cfg: &Config, heading: Angle, bearing: Angle) -> Motion {
    let delta = heading.sub(bearing).signed();
    if delta.unsigned_abs() <= cfg.direct_tolerance.0 {
        Motion::Direct
    } else if delta > 0 {
        Motion::Clockwise
    } else {
        Motion::CounterClockwise
    }
}

/// The sensors of the group nearer the target for a motion class: the
/// clockwise group (−40°, −20°) for CWM, the counter-clockwise group
/// (+20°, +40°) for CCWM.
pub fn sensor_group(m: Motion) -> &'static [usize] {
    match m {
        Motion::Direct => &[],
        Motion::Clockwise => &[0, 1],
        Motion::CounterClockwise => &[3, 4],
    }
}

/// Off-sensor attractive force (eqs. 14, 15): `ξ Σ SC_i · unit(P_Sen_i − P_R)`
/// over the chosen group, `SC_i = 1` when sensor i sees nothing. The end of
/// a sensor's range lies along its axis, so the unit vector is exact.
pub fn off_sensor(cfg: &Config, heading: Dir, group: Motion, readings: &Readings) -> Force {
    let mut f = Force::ZERO;
    for &i in sensor_group(group) {
        if let Some(Reading::Clear) = readings.get(i) {
            // At most five terms of |ξ_sen| ≤ 2^14 (and a little, from a
            // turned direction's rounding): the sum never saturates.
            f = f.plus_unsaturated(Force::along_dir_bounded(
                sensor_direction(cfg, heading, i),
                cfg.xi_sen,
            ));
        }
    }
    f
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eapf::config::ConfigBuilder;
    use crate::eapf::sensors::AdcProfile;

    use crate::eapf::config::test_config as cfg;

    #[test]
    fn collision_point_conditions_by_hand() {
        // Clearance 20 mm: a 120 mm half-width.
        let c = ConfigBuilder::new(AdcProfile::AVR_10BIT_5V)
            .clearance_mm(20)
            .build()
            .unwrap();
        // Front sensor, 300 mm from the face: D = 400 from the centre,
        // lateral 0, forward 400 ≤ 800 → a collision point.
        let mut r = [Reading::Clear; SENSOR_COUNT];
        r[2] = Reading::Range(300);
        assert_eq!(collision_points(&c, &r, 800).len(), 1);
        // Same, but the step is 300: forward 400 > 300 → not one (eq. 8).
        assert!(collision_points(&c, &r, 300).is_empty());
        // +40° sensor at 100 mm: D = 200, lateral = 200·sin40° = 128.6 > 120 → no (eq. 7).
        let mut r = [Reading::Clear; SENSOR_COUNT];
        r[4] = Reading::Range(100);
        assert!(collision_points(&c, &r, 800).is_empty());
        // +20° sensor at 250 mm: D = 350, lateral = 119.7 ≤ 120 → yes.
        let mut r = [Reading::Clear; SENSOR_COUNT];
        r[3] = Reading::Range(250);
        assert_eq!(collision_points(&c, &r, 800)[0].sensor, 3);
        // Too close counts at the sensor face; implausible never does.
        let mut r = [Reading::Implausible; SENSOR_COUNT];
        r[2] = Reading::TooClose;
        let cp = collision_points(&c, &r, 800);
        assert_eq!((cp.len(), cp[0].distance_mm), (1, 100));
        // With the default clearance (40 mm, half-width 140) the +40° point
        // at D = 200 (lateral 128.6) is one.
        let mut r = [Reading::Clear; SENSOR_COUNT];
        r[4] = Reading::Range(100);
        assert_eq!(collision_points(&cfg(), &r, 800).len(), 1);
    }

    #[test]
    fn attractive_force_by_hand() {
        // ξ_att = 2 towards 90°: (0, 2) force units = (0, 2048) in Q10.
        assert_eq!(attractive(&cfg(), Angle::QUARTER), Force { x: 0, y: 2_048 });
    }

    /// Eq. 9 summed as the planner sums it.
    fn repulsive(cfg: &Config, heading: Dir, points: &[CollisionPoint]) -> Force {
        points.iter().fold(Force::ZERO, |f, p| {
            f.plus(repulsion(
                sensor_direction(cfg, heading, p.sensor as usize),
                p.distance_mm,
            ))
        })
    }

    #[test]
    fn repulsive_force_by_hand() {
        // Heading 0, front collision point 500 mm away: 1/0.5² = 4 units, pointing −x.
        let p = [CollisionPoint {
            sensor: 2,
            distance_mm: 500,
        }];
        assert_eq!(
            repulsive(&cfg(), Dir::of(Angle::ZERO), &p),
            Force { x: -4_096, y: 0 }
        );
        // Two symmetric points at ±20°, 1 m: each 1 unit; y cancels, x = −2·cos20° = −1.879.
        let p = [
            CollisionPoint {
                sensor: 1,
                distance_mm: 1_000,
            },
            CollisionPoint {
                sensor: 3,
                distance_mm: 1_000,
            },
        ];
        let f = repulsive(&cfg(), Dir::of(Angle::ZERO), &p);
        assert_eq!(f.y, 0);
        assert!((f.x + 1_924).abs() <= 2, "{f:?}");
    }

    #[test]
    fn midpoint_force_by_hand() {
        // Σ(P_R − P_i) = (−3, 0) → ξ_MP = 1 along −x.
        assert_eq!(midpoint(&cfg(), -3, 0), Force { x: -1_024, y: 0 });
        assert_eq!(midpoint(&cfg(), 0, 0), Force::ZERO);
    }

    #[test]
    fn motion_classes_and_groups() {
        let c = cfg();
        assert_eq!(
            motion(&c, Angle::from_deg(92), Angle::QUARTER),
            Motion::Direct
        );
        // Heading left of the bearing: target on the right → clockwise.
        assert_eq!(
            motion(&c, Angle::from_deg(30), Angle::ZERO),
            Motion::Clockwise
        );
        assert_eq!(
            motion(&c, Angle::from_deg(-30), Angle::ZERO),
            Motion::CounterClockwise
        );
        assert_eq!(sensor_group(Motion::Clockwise), &[0, 1]);
    }

    #[test]
    fn off_sensor_force_by_hand() {
        let c = cfg();
        // CCWM, +20° off, +40° on: one unit along heading + 20°.
        let mut r = [Reading::Clear; SENSOR_COUNT];
        r[4] = Reading::Range(300);
        let f = off_sensor(&c, Dir::of(Angle::ZERO), Motion::CounterClockwise, &r);
        let want = Force::along(Angle::from_deg(20), 1_024);
        assert_eq!(f, want);
        assert!((f.x - 962).abs() <= 1 && (f.y - 350).abs() <= 1, "{f:?}");
        assert_eq!(
            off_sensor(&c, Dir::of(Angle::ZERO), Motion::Direct, &r),
            Force::ZERO
        );
    }
}
