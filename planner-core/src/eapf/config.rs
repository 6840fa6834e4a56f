//! The planner's configuration: every coefficient of the EAPF paper as a
//! documented default, validated when built so that a bad configuration is an
//! error value, never a panic.
//!
//! The builder and its checks are `const fn`: a firmware builds its
//! configuration in a `const`, so that a bad one fails the build and the
//! image holds the finished tables instead of the code that computes them
//! (docs/performance.md).

use crate::eapf::sensors::{AdcProfile, Calibration, CalibrationError, FOLD_BACK_MM, SENSOR_COUNT};
use crate::fixed::{in_range, Angle, Dir, FORCE_ONE};

/// The largest gain (ξ_att, ξ_MP, ξ_sen) a configuration takes: 16 force
/// units, Q10. The forces built from a gain rely on it (they scale a
/// direction by it without a clamp, and the step sums them without
/// saturating).
pub(crate) const MAX_GAIN: i32 = 16 * FORCE_ONE;

/// Why a configuration was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConfigError {
    /// Robot radius outside 20 ..= 1,000 mm.
    RobotRadius,
    /// Sensor range outside 100 ..= 1,500 mm.
    SensorRange,
    /// Sensor offset (centre to sensor face) larger than 1,000 mm.
    SensorOffset,
    /// Sensor angles must be strictly increasing, two negative, one zero,
    /// two positive, all within ±90°.
    SensorAngles,
    /// A gain outside 0 ..= 16 force units (ξ_att must be above 0).
    Gain,
    /// Goal tolerance outside 10 ..= 1,000 mm.
    GoalTolerance,
    /// A tolerance angle outside 0 ..= 30°.
    AngleTolerance,
    /// Clearance or stand-off above 500 mm.
    Clearance,
    /// Escape parameters out of range (see [`crate::eapf::escape`]).
    Escape,
    /// The calibration table was refused.
    Calibration(CalibrationError),
}

/// Planner configuration. Build with [`ConfigBuilder`]; every field has the
/// paper's value (or ours, where the paper has none) as its default.
///
/// `Copy`, so that a firmware can keep it in program memory and load it
/// (the AVR's constants are otherwise copied into its 2 KB of RAM).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Config {
    pub(crate) robot_radius_mm: u16,
    pub(crate) sensor_offset_mm: u16,
    pub(crate) sensor_range_mm: u16,
    pub(crate) sensor_angles: [Angle; SENSOR_COUNT],
    /// Q14 (cos, sin) of each sensor angle, precomputed.
    pub(crate) sensor_dirs: [Dir; SENSOR_COUNT],
    /// Per sensor, the farthest obstacle distance (mm from the centre)
    /// whose point lies inside the corridor (eq. 7's lateral test),
    /// precomputed.
    pub(crate) corridor_mm: [u16; SENSOR_COUNT],
    pub(crate) xi_att: i32,
    pub(crate) xi_mp: i32,
    pub(crate) xi_sen: i32,
    pub(crate) goal_tolerance_mm: u16,
    pub(crate) clearance_mm: u16,
    pub(crate) standoff_mm: u16,
    pub(crate) min_step_mm: u16,
    pub(crate) diagonal_tolerance: Angle,
    pub(crate) direct_tolerance: Angle,
    pub(crate) escape: crate::eapf::escape::EscapeConfig,
    /// Views after an advance with one count before a sensor is frozen
    /// ([`crate::eapf::sensors::FreezeWatch`]; 0: never).
    pub(crate) frozen_views: u8,
    /// The sensors' table from counts to millimetres: the five are one
    /// model, and one table serves them all (on the AVR one instead of five
    /// is 300 bytes of RAM). A sensor's own offset from it is corrected in
    /// its counts before the planner reads them (`rover::calibration`).
    pub(crate) calibration: Calibration,
    /// The sensor faces sit at least their minimum range behind the rim
    /// ([`ConfigBuilder::sensors_set_back`]). Only with the `set-back`
    /// feature: the firmwares' configuration, built without it, keeps the
    /// layout their step was measured with. Kept rather than worked out
    /// from the offset and radius at each use: that took 88 bytes of the
    /// 158 the AVR set-back image then had to spare beside an Uno's bootloader
    /// (`avr_firmware`'s `set_back_build_replays_bit_exact_and_fits_an_uno`).
    #[cfg(feature = "set-back")]
    pub(crate) set_back: bool,
}

impl Config {
    /// No configuration, to be written over in place
    /// ([`crate::Planner::load_config`]): all zeros, so that a planner built
    /// with it is a `memset` of its place on the AVR, not a copy of constant
    /// data (which the AVR keeps in RAM). A planner stepped with it all
    /// the same stays put: with no calibration no count reads as a free
    /// way, so every step is 0 mm and the guard stops.
    pub const UNSET: Config = Config {
        robot_radius_mm: 0,
        sensor_offset_mm: 0,
        sensor_range_mm: 0,
        sensor_angles: [Angle(0); SENSOR_COUNT],
        sensor_dirs: [Dir { c: 0, s: 0 }; SENSOR_COUNT],
        corridor_mm: [0; SENSOR_COUNT],
        xi_att: 0,
        xi_mp: 0,
        xi_sen: 0,
        goal_tolerance_mm: 0,
        clearance_mm: 0,
        standoff_mm: 0,
        min_step_mm: 0,
        diagonal_tolerance: Angle(0),
        direct_tolerance: Angle(0),
        escape: crate::eapf::escape::EscapeConfig {
            enabled: false,
            window_steps: 0,
            stuck_mm: 0,
            crumb_mm: 0,
            revisit_mm: 0,
            progress_mm: 0,
            radius_mm: 0,
            k_v: 0,
            give_up_drops: 0,
            give_up_steps: 0,
            retreat_mm: 0,
            retreat_per_drop_mm: 0,
            follow: false,
        },
        frozen_views: 0,
        calibration: Calibration::UNSET,
        #[cfg(feature = "set-back")]
        set_back: false,
    };

    /// Whether the planner follows the rules of sensors set back
    /// ([`ConfigBuilder::sensors_set_back`]): their faces sit at least the
    /// sensors' minimum range behind the rim, and planner-core is built
    /// with its `set-back` feature.
    pub fn sensors_set_back(&self) -> bool {
        self.set_back()
    }

    /// [`Config::sensors_set_back`] for the planner's rules: without the
    /// `set-back` feature a constant `false`.
    #[inline(always)]
    pub(crate) fn set_back(&self) -> bool {
        #[cfg(feature = "set-back")]
        return self.set_back;
        #[cfg(not(feature = "set-back"))]
        false
    }

    /// Robot radius, mm.
    pub fn robot_radius_mm(&self) -> u16 {
        self.robot_radius_mm
    }
    /// Distance from the robot's centre to each sensor face, mm.
    pub fn sensor_offset_mm(&self) -> u16 {
        self.sensor_offset_mm
    }
    /// Sensor range, mm (from the sensor face).
    pub fn sensor_range_mm(&self) -> u16 {
        self.sensor_range_mm
    }
    /// Sensor angles in the robot frame, in sensor order.
    pub fn sensor_angles(&self) -> [Angle; SENSOR_COUNT] {
        self.sensor_angles
    }
    /// Half-width of the sensed sector: the largest |sensor angle|.
    pub fn sector_half_width(&self) -> Angle {
        let a = self.sensor_angles[0]
            .abs_signed()
            .max(self.sensor_angles[4].abs_signed());
        Angle(a)
    }
    /// The sensors' calibration (one table for the five).
    pub fn calibration(&self) -> &Calibration {
        &self.calibration
    }

    /// Replace the sensors' calibration (a table measured on the rover's
    /// own sensors). It must be built for the same ADC profile.
    pub fn set_calibration(&mut self, cal: Calibration) -> Result<(), ConfigError> {
        if cal.full_scale() != self.calibration.full_scale() {
            return Err(ConfigError::Calibration(CalibrationError::BadAdc));
        }
        self.calibration = cal;
        Ok(())
    }
    /// Goal tolerance, mm.
    pub fn goal_tolerance_mm(&self) -> u16 {
        self.goal_tolerance_mm
    }
    /// Extra clearance kept beyond the robot radius by the safety rule, mm.
    pub fn clearance_mm(&self) -> u16 {
        self.clearance_mm
    }
    /// The escape (virtual obstacle) parameters.
    pub fn escape(&self) -> &crate::eapf::escape::EscapeConfig {
        &self.escape
    }
}

/// Builds a [`Config`]; `build` validates. Every method is a `const fn`, so
/// a firmware can build its configuration in a `const` and a bad one fails
/// the build:
///
/// ```
/// use planner_core::{AdcProfile, Config, ConfigBuilder};
///
/// const CONFIG: Config = match ConfigBuilder::new(AdcProfile::AVR_10BIT_5V)
///     .robot_radius_mm(120)
///     .build()
/// {
///     Ok(c) => c,
///     Err(_) => panic!("the configuration is refused"),
/// };
/// assert_eq!(CONFIG.robot_radius_mm(), 120);
/// ```
#[derive(Clone, Debug)]
pub struct ConfigBuilder {
    adc: AdcProfile,
    robot_radius_mm: u16,
    sensor_offset_mm: Option<u16>,
    set_back: bool,
    sensor_range_mm: u16,
    sensor_angles_deg: [i16; SENSOR_COUNT],
    xi_att: i32,
    xi_mp: i32,
    xi_sen: i32,
    goal_tolerance_mm: u16,
    clearance_mm: u16,
    standoff_mm: u16,
    min_step_mm: u16,
    diagonal_tolerance_deg: i16,
    direct_tolerance_deg: i16,
    escape: crate::eapf::escape::EscapeConfig,
    frozen_views: u8,
}

impl ConfigBuilder {
    /// The defaults, with the GP2Y0A21YK0F datasheet calibration for `adc`:
    ///
    /// | parameter | default | source |
    /// |---|---|---|
    /// | robot radius | 100 mm | ours (scenario format default) |
    /// | sensor offset | = robot radius (sensors on the rim; [`ConfigBuilder::sensors_set_back`] sets them behind it) | ours |
    /// | sensor range | 800 mm | paper §4 |
    /// | sensor angles | −40, −20, 0, 20, 40° | paper §4 |
    /// | ξ_att | 2 | paper eq. 5 |
    /// | ξ_MP | 1 | paper eq. 12 |
    /// | ξ (off-sensor) | 1 | paper eq. 14 |
    /// | goal tolerance | 50 mm | ours |
    /// | clearance | 40 mm | ours: lateral margin of the safety rule (§5) and of the collision corridor (eqs. 7, 8); 40 rather than 20 mm because a beam samples one point of an obstacle and a corner between the beams reaches past it (the commit history) |
    /// | stand-off | 100 mm | ours: obstacles ahead stay this far beyond the rim (with sensors on the rim, their minimum range: never in fold-back) |
    /// | minimum step | 10 mm | ours: shorter steps become a pure turn |
    /// | XY tolerance | 5° from a diagonal | ours (eq. 13 needs one) |
    /// | DM tolerance | 5° from the target bearing | ours |
    /// | frozen after | 8 views | ours: a count the same in 8 views in a row, each after an advance, is a sensor stuck ([`crate::eapf::sensors::FreezeWatch`]) |
    pub const fn new(adc: AdcProfile) -> Self {
        ConfigBuilder {
            adc,
            robot_radius_mm: 100,
            sensor_offset_mm: None,
            set_back: false,
            sensor_range_mm: 800,
            sensor_angles_deg: [-40, -20, 0, 20, 40],
            xi_att: 2 * FORCE_ONE,
            xi_mp: FORCE_ONE,
            xi_sen: FORCE_ONE,
            goal_tolerance_mm: 50,
            clearance_mm: 40,
            standoff_mm: 100,
            min_step_mm: 10,
            diagonal_tolerance_deg: 5,
            direct_tolerance_deg: 5,
            escape: crate::eapf::escape::EscapeConfig::DEFAULT,
            frozen_views: 8,
        }
    }

    /// A sensor whose count is the same in `views` views in a row, each
    /// after an advance, is stuck: the planner stops with a sensor fault
    /// ([`crate::eapf::sensors::FreezeWatch`]). 0 never calls a sensor stuck:
    /// for noise-free sensors (a simulation's), whose count is the same
    /// whenever the distance is.
    pub const fn frozen_after_views(mut self, views: u8) -> Self {
        self.frozen_views = views;
        self
    }

    /// Robot radius in mm.
    pub const fn robot_radius_mm(mut self, v: u16) -> Self {
        self.robot_radius_mm = v;
        self
    }
    /// Centre-to-sensor-face distance in mm (default: the robot radius,
    /// or with [`ConfigBuilder::sensors_set_back`] the radius less the
    /// sensors' minimum range).
    pub const fn sensor_offset_mm(mut self, v: u16) -> Self {
        self.sensor_offset_mm = Some(v);
        self
    }
    /// With `set_back`, the sensors mounted [`FOLD_BACK_MM`] (100 mm, their
    /// minimum range) behind the rim, at least at the centre, unless
    /// [`ConfigBuilder::sensor_offset_mm`] places them. Ours: a sensor on
    /// the rim reads an obstacle within 100 mm of its face as farther
    /// (fold-back), which is what the benches' last collisions were
    /// (the commit history, "Known failures"); set back, nothing outside the
    /// body is ever that near a face. Whenever the faces are that far
    /// behind the rim (whichever way the offset was set), the planner
    /// follows the rules measured with them (the commit history, "Sensors set
    /// back"): the datasheet table interpolated in 1/d
    /// ([`Calibration::from_points_reciprocal`]), what the view reads
    /// within 100 mm of the rim kept as flank points, flank points kept
    /// off with the clearance instead of 20 mm, and the boundary
    /// follower's loop closed on passing its hit point more than 60° from
    /// the way it left it (90° on the rim). The rules need planner-core's
    /// `set-back` feature (a default one; the firmwares build without it
    /// and hold none of their code): without it the sensors are placed
    /// here all the same, and the rules of the rim apply.
    pub const fn sensors_set_back(mut self, set_back: bool) -> Self {
        self.set_back = set_back;
        self
    }
    /// Sensor range in mm.
    pub const fn sensor_range_mm(mut self, v: u16) -> Self {
        self.sensor_range_mm = v;
        self
    }
    /// Sensor angles in whole degrees, robot frame, in sensor order.
    pub const fn sensor_angles_deg(mut self, v: [i16; SENSOR_COUNT]) -> Self {
        self.sensor_angles_deg = v;
        self
    }
    /// ξ_att, ξ_MP and ξ in 1/1024 force units (paper: 2048, 1024, 1024).
    pub const fn gains_q10(mut self, xi_att: i32, xi_mp: i32, xi_sen: i32) -> Self {
        self.xi_att = xi_att;
        self.xi_mp = xi_mp;
        self.xi_sen = xi_sen;
        self
    }
    /// Distance at which the goal counts as reached, mm.
    pub const fn goal_tolerance_mm(mut self, v: u16) -> Self {
        self.goal_tolerance_mm = v;
        self
    }
    /// Clearance kept beyond the robot radius by the safety rule, mm.
    pub const fn clearance_mm(mut self, v: u16) -> Self {
        self.clearance_mm = v;
        self
    }
    /// Distance kept between obstacles ahead and the rim, mm.
    pub const fn standoff_mm(mut self, v: u16) -> Self {
        self.standoff_mm = v;
        self
    }
    /// Angle tolerances in degrees: XY classification (eq. 13) and DM motion.
    pub const fn tolerances_deg(mut self, diagonal: i16, direct: i16) -> Self {
        self.diagonal_tolerance_deg = diagonal;
        self.direct_tolerance_deg = direct;
        self
    }
    /// Escape (virtual obstacle) parameters.
    pub const fn escape(mut self, v: crate::eapf::escape::EscapeConfig) -> Self {
        self.escape = v;
        self
    }

    /// Validate and build.
    pub const fn build(self) -> Result<Config, ConfigError> {
        if !in_range(self.robot_radius_mm as i32, 20, 1_000) {
            return Err(ConfigError::RobotRadius);
        }
        if !in_range(self.sensor_range_mm as i32, 100, 1_500) {
            return Err(ConfigError::SensorRange);
        }
        let offset = match self.sensor_offset_mm {
            Some(v) => v,
            None if self.set_back => self.robot_radius_mm.saturating_sub(FOLD_BACK_MM),
            None => self.robot_radius_mm,
        };
        let set_back = cfg!(feature = "set-back") && is_set_back(offset, self.robot_radius_mm);
        if offset > 1_000 {
            return Err(ConfigError::SensorOffset);
        }
        let a = self.sensor_angles_deg;
        let mut increasing = true;
        let mut i = 1;
        while i < SENSOR_COUNT {
            increasing &= a[i - 1] < a[i];
            i += 1;
        }
        if !increasing || a[1] >= 0 || a[2] != 0 || a[3] <= 0 || a[0] < -90 || a[4] > 90 {
            return Err(ConfigError::SensorAngles);
        }
        if self.xi_att <= 0
            || !in_range(self.xi_att, 0, MAX_GAIN)
            || !in_range(self.xi_mp, 0, MAX_GAIN)
            || !in_range(self.xi_sen, 0, MAX_GAIN)
        {
            return Err(ConfigError::Gain);
        }
        if !in_range(self.goal_tolerance_mm as i32, 10, 1_000) {
            return Err(ConfigError::GoalTolerance);
        }
        if !in_range(self.diagonal_tolerance_deg as i32, 0, 30)
            || !in_range(self.direct_tolerance_deg as i32, 0, 30)
        {
            return Err(ConfigError::AngleTolerance);
        }
        if self.clearance_mm > 500 || self.standoff_mm > 500 {
            return Err(ConfigError::Clearance);
        }
        if !self.escape.is_valid() {
            return Err(ConfigError::Escape);
        }
        // Every sensor starts on the datasheet curve; `Config::set_calibration`
        // replaces one. (The builder holds no tables: on the AVR a builder,
        // a config and a planner with five tables each would not fit in RAM
        // at once.)
        let c = if set_back {
            Calibration::gp2y0a21_reciprocal(self.adc)
        } else {
            Calibration::gp2y0a21(self.adc)
        };
        let c = match c {
            Ok(c) => c,
            Err(e) => return Err(ConfigError::Calibration(e)),
        };
        let half_width = self.robot_radius_mm + self.clearance_mm;
        let mut angles = [Angle::ZERO; SENSOR_COUNT];
        let mut sensor_dirs = [Dir { c: 0, s: 0 }; SENSOR_COUNT];
        let mut corridor = [0u16; SENSOR_COUNT];
        let mut i = 0;
        while i < SENSOR_COUNT {
            angles[i] = Angle::from_deg(a[i]);
            sensor_dirs[i] = Dir::of(angles[i]);
            corridor[i] = corridor_mm(sensor_dirs[i], half_width);
            i += 1;
        }
        Ok(Config {
            robot_radius_mm: self.robot_radius_mm,
            sensor_offset_mm: offset,
            sensor_range_mm: self.sensor_range_mm,
            sensor_angles: angles,
            sensor_dirs,
            corridor_mm: corridor,
            xi_att: self.xi_att,
            xi_mp: self.xi_mp,
            xi_sen: self.xi_sen,
            goal_tolerance_mm: self.goal_tolerance_mm,
            clearance_mm: self.clearance_mm,
            standoff_mm: self.standoff_mm,
            min_step_mm: self.min_step_mm,
            diagonal_tolerance: Angle::from_deg(self.diagonal_tolerance_deg),
            direct_tolerance: Angle::from_deg(self.direct_tolerance_deg),
            escape: self.escape,
            frozen_views: self.frozen_views,
            calibration: c,
            #[cfg(feature = "set-back")]
            set_back,
        })
    }
}

/// Whether sensor faces `offset_mm` from the centre of a rover of
/// `radius_mm` sit at least their minimum range behind its rim.
const fn is_set_back(offset_mm: u16, radius_mm: u16) -> bool {
    offset_mm as u32 + FOLD_BACK_MM as u32 <= radius_mm as u32
}

/// The largest `d` (mm) with `mul_q14(d, |sin|) ≤ half_width`: the
/// lateral test of eq. 7 for a sensor along `dir`, as one compare of the
/// distance. The product grows with `d`, so the set is `0 ..= d_max`:
/// `(d·s + 2^13) >> 14 ≤ w` ⇔ `d·s ≤ (w + 1)·2^14 − 2^13 − 1`.
const fn corridor_mm(dir: Dir, half_width: u16) -> u16 {
    let s = dir.sin().unsigned_abs();
    let limit = (half_width as u32 + 1) * (1 << 14) - (1 << 13) - 1;
    match limit.checked_div(s) {
        Some(d) if d < u16::MAX as u32 => d as u16,
        _ => u16::MAX,
    }
}

/// The default configuration for the AVR's ADC, for the modules' tests.
#[cfg(test)]
pub(crate) fn test_config() -> Config {
    ConfigBuilder::new(crate::eapf::sensors::AdcProfile::AVR_10BIT_5V)
        .build()
        .unwrap()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corridor_limit_is_the_lateral_test() {
        for deg in [-90, -40, -20, -7, 0, 3, 20, 40, 89] {
            for w in [20u16, 120, 1_500] {
                let dir = Dir::of(Angle::from_deg(deg));
                let d_max = corridor_mm(dir, w);
                for d in (0..=u16::MAX)
                    .step_by(7)
                    .chain([d_max, d_max.saturating_add(1)])
                {
                    let lateral = crate::fixed::mul_q14(d as i32, dir.sin().abs());
                    assert_eq!(lateral <= w as i32, d <= d_max, "{deg}° w={w} d={d}");
                }
            }
        }
    }

    fn b() -> ConfigBuilder {
        ConfigBuilder::new(AdcProfile::AVR_10BIT_5V)
    }

    /// Built by the compiler, as the firmwares build theirs.
    const AT_COMPILE_TIME: Result<Config, ConfigError> =
        ConfigBuilder::new(AdcProfile::AVR_10BIT_5V).build();
    const REFUSED_AT_COMPILE_TIME: Result<Config, ConfigError> =
        ConfigBuilder::new(AdcProfile::AVR_10BIT_5V)
            .clearance_mm(600)
            .build();

    #[test]
    #[cfg(feature = "set-back")]
    fn set_back_sensors_sit_their_minimum_range_behind_the_rim() {
        let set_back = |radius| {
            b().robot_radius_mm(radius)
                .sensors_set_back(true)
                .build()
                .unwrap()
        };
        let c = set_back(100);
        assert_eq!(c.sensor_offset_mm(), 0, "a 100 mm rover: at the centre");
        assert!(c.sensors_set_back());
        assert_eq!(set_back(160).sensor_offset_mm(), 60);
        // A smaller rover: at the centre, still within the minimum range of
        // the rim, so not set back for the rules.
        let small = set_back(50);
        assert_eq!(small.sensor_offset_mm(), 0, "never in front of the centre");
        assert!(!small.sensors_set_back());
        // The default: on the rim.
        let rim = b().build().unwrap();
        assert_eq!(rim.sensor_offset_mm(), 100);
        assert!(!rim.sensors_set_back());
        // An offset placed by hand decides, whichever way it was set.
        let placed = b()
            .robot_radius_mm(160)
            .sensor_offset_mm(40)
            .build()
            .unwrap();
        assert!(placed.sensors_set_back());
        let placed = b()
            .robot_radius_mm(160)
            .sensor_offset_mm(61)
            .sensors_set_back(true);
        assert!(!placed.build().unwrap().sensors_set_back());
        // Set back, the table is the one interpolated in 1/d.
        let adc = AdcProfile::AVR_10BIT_5V;
        assert_eq!(
            c.calibration,
            Calibration::gp2y0a21_reciprocal(adc).unwrap()
        );
        assert_eq!(rim.calibration, Calibration::gp2y0a21(adc).unwrap());
    }

    #[test]
    fn a_config_built_at_compile_time_is_the_one_built_at_run_time() {
        assert_eq!(AT_COMPILE_TIME, b().build());
        assert!(AT_COMPILE_TIME.is_ok());
        assert_eq!(REFUSED_AT_COMPILE_TIME, Err(ConfigError::Clearance));
    }

    #[test]
    fn a_calibration_is_replaced_only_by_one_for_the_same_adc() {
        let mut c = b().build().unwrap();
        let mine =
            Calibration::from_points(AdcProfile::AVR_10BIT_5V, &[(100, 800), (600, 100)]).unwrap();
        c.set_calibration(mine).unwrap();
        assert_eq!(c.calibration(), &mine);
        let stm = Calibration::gp2y0a21(AdcProfile::STM32_12BIT_3V3).unwrap();
        assert_eq!(
            c.set_calibration(stm),
            Err(ConfigError::Calibration(CalibrationError::BadAdc))
        );
        assert_eq!(c.calibration(), &mine);
    }

    #[test]
    fn defaults_are_the_papers() {
        let c = b().build().unwrap();
        assert_eq!(c.robot_radius_mm(), 100);
        assert_eq!(c.sensor_range_mm(), 800);
        assert_eq!(c.sensor_angles()[0], Angle::from_deg(-40));
        assert_eq!(c.sensor_angles()[4], Angle::from_deg(40));
        assert_eq!(c.xi_att, 2 * FORCE_ONE);
        assert_eq!(c.xi_mp, FORCE_ONE);
        assert_eq!(c.xi_sen, FORCE_ONE);
        assert_eq!(c.sector_half_width(), Angle::from_deg(40));
        assert!(ConfigBuilder::new(AdcProfile::STM32_12BIT_3V3)
            .build()
            .is_ok());
    }

    #[test]
    fn bad_configs_are_errors() {
        assert_eq!(
            b().robot_radius_mm(0).build(),
            Err(ConfigError::RobotRadius)
        );
        assert_eq!(
            b().sensor_range_mm(50).build(),
            Err(ConfigError::SensorRange)
        );
        assert_eq!(
            b().sensor_offset_mm(5_000).build(),
            Err(ConfigError::SensorOffset)
        );
        assert_eq!(
            b().sensor_angles_deg([-40, 20, 0, 20, 40]).build(),
            Err(ConfigError::SensorAngles)
        );
        assert_eq!(
            b().sensor_angles_deg([-100, -20, 0, 20, 40]).build(),
            Err(ConfigError::SensorAngles)
        );
        assert_eq!(b().gains_q10(0, 1024, 1024).build(), Err(ConfigError::Gain));
        assert_eq!(
            b().gains_q10(2048, -1, 1024).build(),
            Err(ConfigError::Gain)
        );
        assert_eq!(
            b().goal_tolerance_mm(0).build(),
            Err(ConfigError::GoalTolerance)
        );
        assert_eq!(
            b().tolerances_deg(45, 5).build(),
            Err(ConfigError::AngleTolerance)
        );
        assert_eq!(b().clearance_mm(900).build(), Err(ConfigError::Clearance));
        let bad_adc = AdcProfile {
            bits: 3,
            vref_mv: 0,
        };
        assert_eq!(
            ConfigBuilder::new(bad_adc).build(),
            Err(ConfigError::Calibration(CalibrationError::BadAdc))
        );
    }
}
