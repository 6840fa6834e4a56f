//! The five infrared range sensors: raw ADC counts in, trusted distances out.
//!
//! Sharp GP2Y0A21YK0F-class sensors (docs/algorithms.md §5) give a voltage that
//! falls roughly as 1/distance between 10 and 80 cm, fold back below 10 cm
//! (a very near object reads as farther), and give a low phantom voltage
//! when nothing is in range. The core therefore converts each raw count with
//! a per-sensor [`Calibration`] and classifies it as a [`Reading`]: a range,
//! clear (nothing within the calibrated range), too close, or implausible.
//! Only ranges and "clear" are trusted as free space.
//!
//! embedded-hal 1.0 has no ADC trait, so the core owns [`IrSensors`]; the
//! `hal02` feature adapts any five embedded-hal 0.2 `adc::OneShot` channels
//! (stm32f4xx-hal's ADC implements it), and [`ScriptedSensors`] replays
//! recorded counts for tests and emulated builds.

use crate::fixed::Angle;

/// Number of IR sensors, in order −40°, −20°, 0°, +20°, +40°.
pub const SENSOR_COUNT: usize = 5;

/// One raw ADC count per sensor, in sensor order.
pub type RawCounts = [u16; SENSOR_COUNT];

/// Bins of a calibration table; the table has `CAL_BINS + 1` entries.
pub const CAL_BINS: usize = 32;

/// Most measured points a calibration takes.
pub const MAX_CAL_POINTS: usize = 32;

/// Bits of a bin index, and the bits below them in a 16-bit count.
const BIN_BITS: u32 = CAL_BINS.trailing_zeros();
const FRACTION_BITS: u32 = 16 - BIN_BITS;

/// GP2Y0A21YK0F datasheet points (typical curve): (millivolts, millimetres),
/// nearest first.
pub const GP2Y0A21_MV_MM: [(u16, u16); 8] = [
    (2_600, 100),
    (1_390, 200),
    (980, 300),
    (750, 400),
    (610, 500),
    (550, 600),
    (480, 700),
    (420, 800),
];

/// The GP2Y0A21YK0F's minimum range (mm, its first datasheet point): an
/// object nearer its face reads as farther (fold-back). Sensors set this
/// far behind the rim ([`crate::ConfigBuilder::sensors_set_back`]) never
/// have anything outside the body there.
pub const FOLD_BACK_MM: u16 = GP2Y0A21_MV_MM[0].1;

/// An ADC's resolution and reference voltage.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AdcProfile {
    /// Resolution in bits (8 ..= 16).
    pub bits: u8,
    /// Reference (full-scale) voltage in millivolts.
    pub vref_mv: u16,
}

impl AdcProfile {
    /// ATmega328P: 10-bit ADC, AVcc = 5 V reference.
    pub const AVR_10BIT_5V: AdcProfile = AdcProfile {
        bits: 10,
        vref_mv: 5_000,
    };
    /// STM32F4: 12-bit ADC, 3.3 V reference.
    pub const STM32_12BIT_3V3: AdcProfile = AdcProfile {
        bits: 12,
        vref_mv: 3_300,
    };

    /// Largest count the ADC can produce.
    pub const fn full_scale(self) -> u16 {
        let bits = if self.bits > 16 { 16 } else { self.bits };
        ((1u32 << bits) - 1) as u16
    }

    /// The count the ADC reads for `mv` millivolts (rounded, saturating).
    pub const fn counts_for_mv(self, mv: u16) -> u16 {
        let fs = self.full_scale() as u32;
        let vref = if self.vref_mv == 0 {
            1
        } else {
            self.vref_mv as u32
        };
        let c = (mv as u32 * fs + vref / 2) / vref;
        if c < fs {
            c as u16
        } else {
            fs as u16
        }
    }
}

/// Why a calibration table was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CalibrationError {
    /// The ADC profile is outside 8 ..= 16 bits or has a zero reference.
    BadAdc,
    /// Fewer than two points.
    TooFewPoints,
    /// More than [`MAX_CAL_POINTS`] points.
    TooManyPoints,
    /// Counts must rise strictly while distances fall strictly.
    NotMonotonic,
    /// A count above the ADC's full scale.
    CountOutOfRange,
    /// A distance outside 20 ..= 2,000 mm.
    DistanceOutOfRange,
}

/// The least output a working sensor gives, mV. A Sharp IR sensor puts out
/// its phantom level (0.25–0.4 V) with nothing in range (docs/algorithms.md §5),
/// so a count below 0.1 V is no distance: a broken signal wire (the pin
/// pulled to ground), an unpowered sensor or a shorted output. Read as
/// "clear" it would open the way; it is flagged implausible instead, and
/// the planner stops with a sensor fault (§5: "flags implausible
/// readings"). A count above the ADC's full scale is implausible too.
pub const SIGNAL_FLOOR_MV: u16 = 100;

/// How long after power-up a sensor gives its first output, ms: one
/// measuring period (GP2Y0A21YK0F: 38.3 ± 9.6 ms). A firmware plans nothing
/// on counts read before it.
pub const SENSOR_WARMUP_MS: u32 = 48;

/// Raw count → distance for one sensor, resampled at build time onto
/// `CAL_BINS` equal bins of counts so that a lookup is a shift and one
/// 16-bit multiply (no division on the AVR).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
// In this order on the AVR, the scalars within a load's 63-byte reach
// (Rust's order put `shift` at byte 72: see `Planner`).
#[cfg_attr(target_arch = "avr", repr(C))]
pub struct Calibration {
    shift: u8,
    full_scale: u16,
    /// Counts above this are nearer than the nearest calibrated distance.
    near_count: u16,
    /// Counts below this are farther than the farthest calibrated distance.
    far_count: u16,
    /// Counts below this are implausible ([`SIGNAL_FLOOR_MV`]; 0 for a table
    /// that reaches below it).
    floor_count: u16,
    /// Distance in mm at count `i << shift` (the end segments extrapolated).
    mm: [u16; CAL_BINS + 1],
}

impl Calibration {
    /// All zeros: part of [`crate::eapf::config::Config::UNSET`].
    pub(crate) const UNSET: Calibration = Calibration {
        shift: 0,
        full_scale: 0,
        near_count: 0,
        far_count: 0,
        floor_count: 0,
        mm: [0; CAL_BINS + 1],
    };

    /// Build from measured `(count, mm)` points, in any order of input but
    /// strictly monotonic: a higher count is a nearer object.
    ///
    /// A `const fn`, so that a firmware's tables can be built and checked
    /// at compile time (hence the plain loops).
    pub const fn from_points(
        adc: AdcProfile,
        points: &[(u16, u16)],
    ) -> Result<Self, CalibrationError> {
        Calibration::build(adc, points, false)
    }

    /// [`Calibration::from_points`], interpolated linearly in 1/d between
    /// the points instead of in d: the sensor's output is close to linear
    /// in 1/d (docs/algorithms.md §5: about 1/distance), and on the
    /// datasheet curve the straight line in d reads 17 mm too far at
    /// 140 mm, between its 100 and 200 mm points. Beyond the end points the
    /// end segments' straight lines, as there (1/d would bend to infinity
    /// before the phantom level). The table of sensors set back
    /// ([`crate::ConfigBuilder::sensors_set_back`]).
    pub const fn from_points_reciprocal(
        adc: AdcProfile,
        points: &[(u16, u16)],
    ) -> Result<Self, CalibrationError> {
        Calibration::build(adc, points, true)
    }

    /// The table, interpolated in 1/d (`reciprocal`) or in d.
    const fn build(
        adc: AdcProfile,
        points: &[(u16, u16)],
        reciprocal: bool,
    ) -> Result<Self, CalibrationError> {
        if adc.bits < 8 || adc.bits > 16 || adc.vref_mv == 0 {
            return Err(CalibrationError::BadAdc);
        }
        if points.len() < 2 {
            return Err(CalibrationError::TooFewPoints);
        }
        if points.len() > MAX_CAL_POINTS {
            return Err(CalibrationError::TooManyPoints);
        }
        let full_scale = adc.full_scale();
        // Points sorted by count (insertion sort, build time only):
        // ascending counts must have descending mm.
        let mut sorted = [(0u16, 0u16); MAX_CAL_POINTS];
        let n = points.len();
        let mut i = 0;
        while i < n {
            let p = points[i];
            if p.0 > full_scale {
                return Err(CalibrationError::CountOutOfRange);
            }
            if p.1 < 20 || p.1 > 2_000 {
                return Err(CalibrationError::DistanceOutOfRange);
            }
            let mut j = i;
            while j > 0 && sorted[j - 1].0 > p.0 {
                sorted[j] = sorted[j - 1];
                j -= 1;
            }
            sorted[j] = p;
            i += 1;
        }
        let mut k = 1;
        while k < n {
            let (a, b) = (sorted[k - 1], sorted[k]);
            if a.0 >= b.0 || a.1 <= b.1 {
                return Err(CalibrationError::NotMonotonic);
            }
            k += 1;
        }
        let shift = adc.bits - (CAL_BINS.trailing_zeros() as u8);
        let mut mm = [0u16; CAL_BINS + 1];
        let mut i = 0;
        while i <= CAL_BINS {
            let c = (i as i32) << shift;
            // The segment containing c, or the end segment to extrapolate.
            let mut k = 1;
            while k < n - 1 && c > sorted[k].0 as i32 {
                k += 1;
            }
            let ((c0, d0), (c1, d1)) = (sorted[k - 1], sorted[k]);
            let (c0, d0, c1, d1) = (c0 as i32, d0 as i32, c1 as i32, d1 as i32);
            let d = if reciprocal && c >= c0 && c <= c1 {
                // 1/d = 1/d0 + (c − c0)/(c1 − c0) · (1/d1 − 1/d0), rounded;
                // in 64 bits (d0·d1·(c1 − c0) reaches 2^37). The
                // denominator is at least d1·(c1 − c0) > 0 within the
                // segment (strictly increasing counts, decreasing mm).
                let (c, c0, d0, c1, d1) = (c as i64, c0 as i64, d0 as i64, c1 as i64, d1 as i64);
                let num = d0 * d1 * (c1 - c0);
                let den = d1 * (c1 - c0) + (c - c0) * (d0 - d1);
                match (2 * num + den).checked_div(2 * den) {
                    Some(q) => q as i32,
                    None => 0,
                }
            } else {
                let num = (c - c0) * (d1 - d0);
                let den = c1 - c0; // > 0: strictly increasing counts
                d0 + match (2 * num + den).checked_div(2 * den) {
                    Some(q) => q,
                    None => 0,
                }
            };
            mm[i] = if d < 0 {
                0
            } else if d > 4_000 {
                4_000
            } else {
                d as u16
            };
            i += 1;
        }
        // A table that reaches below the floor says its sensor's output
        // does: then no count is too low.
        let floor_count = match adc.counts_for_mv(SIGNAL_FLOOR_MV) {
            floor if floor < sorted[0].0 => floor,
            _ => 0,
        };
        Ok(Calibration {
            shift,
            full_scale,
            near_count: sorted[n - 1].0,
            far_count: sorted[0].0,
            floor_count,
            mm,
        })
    }

    /// The GP2Y0A21YK0F datasheet curve for an ADC (docs/algorithms.md §5).
    pub const fn gp2y0a21(adc: AdcProfile) -> Result<Self, CalibrationError> {
        Calibration::gp2y0a21_with(adc, false)
    }

    /// [`Calibration::gp2y0a21`] interpolated in 1/d
    /// ([`Calibration::from_points_reciprocal`]).
    pub const fn gp2y0a21_reciprocal(adc: AdcProfile) -> Result<Self, CalibrationError> {
        Calibration::gp2y0a21_with(adc, true)
    }

    const fn gp2y0a21_with(adc: AdcProfile, reciprocal: bool) -> Result<Self, CalibrationError> {
        let mut pts = [(0u16, 0u16); GP2Y0A21_MV_MM.len()];
        let mut i = 0;
        while i < pts.len() {
            let (mv, mm) = GP2Y0A21_MV_MM[i];
            pts[i] = (adc.counts_for_mv(mv), mm);
            i += 1;
        }
        Calibration::build(adc, &pts, reciprocal)
    }

    /// Classify one raw count.
    pub fn reading(&self, raw: u16) -> Reading {
        if raw < self.far_count {
            // Below the floor: a silent sensor, not a far one.
            if raw < self.floor_count {
                Reading::Implausible
            } else {
                Reading::Clear
            }
        } else if raw > self.full_scale {
            Reading::Implausible
        } else if raw > self.near_count {
            Reading::TooClose
        } else {
            // The count as a 16-bit fraction of full scale (`raw < 2^bits`,
            // `bits = shift + BIN_BITS`): the bin is its top `BIN_BITS`,
            // the offset in the bin the rest, scaled by `2^(FRACTION_BITS −
            // shift)`. The interpolation `(Δ·offset + half) >> shift` is the
            // same with numerator and divisor scaled alike, and takes one
            // variable shift instead of four (the AVR shifts one bit per
            // instruction, a 32-bit value four instructions a bit).
            let x = raw << (FRACTION_BITS - self.shift as u32);
            let i = (x >> FRACTION_BITS) as usize;
            let f = (x & ((1 << FRACTION_BITS) - 1)) as i32;
            let d0 = self.mm.get(i).copied().unwrap_or(0) as i32;
            let d1 = self.mm.get(i + 1).copied().unwrap_or(d0 as u16) as i32;
            // Between `d0` and `d1` (f < 2^FRACTION_BITS, and the rounding
            // cannot pass `d1`): a `u16` as it is, no clamp needed.
            let d = d0 + (((d1 - d0) * f + (1 << (FRACTION_BITS - 1))) >> FRACTION_BITS);
            Reading::Range(d as u16)
        }
    }

    /// Largest count of the ADC the table was built for.
    pub fn full_scale(&self) -> u16 {
        self.full_scale
    }

    /// Nearest distance the table trusts, mm.
    pub fn min_mm(&self) -> u16 {
        self.reading(self.near_count).range_mm().unwrap_or(0)
    }

    /// The resampled table, `(count, mm)` per bin edge: for reports and for
    /// the float reference in the tests.
    pub fn bins(&self) -> impl Iterator<Item = (u16, u16)> + '_ {
        self.mm
            .iter()
            .enumerate()
            .map(move |(i, &d)| (((i as u32) << self.shift).min(u16::MAX as u32) as u16, d))
    }

    /// Counts per bin as a shift.
    pub fn shift(&self) -> u8 {
        self.shift
    }

    /// Counts below this are implausible: a silent sensor
    /// ([`SIGNAL_FLOOR_MV`]; 0 for a table that reaches below it).
    pub fn floor_count(&self) -> u16 {
        self.floor_count
    }

    /// `(far_count, near_count)`: the trusted window of counts.
    pub fn window(&self) -> (u16, u16) {
        (self.far_count, self.near_count)
    }
}

/// What one sensor says this cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Reading {
    /// An obstacle this many mm from the sensor face.
    Range(u16),
    /// Nothing within the calibrated range: free as far as the sensor sees.
    Clear,
    /// Nearer than the calibrated minimum (or in the fold-back region):
    /// an obstacle at the sensor face, for safety.
    TooClose,
    /// A count the sensor cannot produce: not trusted, flagged as a fault.
    Implausible,
}

impl Reading {
    /// The range in mm, if this is a range reading.
    pub fn range_mm(self) -> Option<u16> {
        match self {
            Reading::Range(mm) => Some(mm),
            _ => None,
        }
    }

    /// How far from the sensor face the obstacle this reading shows is,
    /// mm: "too close" is one at the face; `None` for "clear" and for a
    /// reading not trusted as an obstacle position. The one place that says
    /// which readings are obstacles (the forces and the boundary follower
    /// ask it). Always inlined: out of line on the AVR, the collision
    /// points' loop would make a call per reading.
    #[inline(always)]
    pub fn obstacle_mm(self) -> Option<u16> {
        match self {
            Reading::Range(mm) => Some(mm),
            Reading::TooClose => Some(0),
            Reading::Clear | Reading::Implausible => None,
        }
    }
}

/// One reading per sensor, in sensor order.
pub type Readings = [Reading; SENSOR_COUNT];

/// Ours: finds a sensor stuck at one count, frozen or stuck at the
/// "nothing in range" level, which reads as plausible and wrong. A working
/// sensor's count changes from one view to the next while the rover moves,
/// by its noise if by nothing else: the Sharp's output ripples by about
/// 10 mV, two counts of the AVR's ADC and a dozen of the STM32's, so one
/// count seen again has a chance of about one in seven on the AVR. A count
/// the same in [`crate::ConfigBuilder::frozen_after_views`] views in a row,
/// each after an advance (so that the sensor has put out new values in
/// between), is a sensor that no longer looks.
///
/// Every view is compared with the one before, and a change ends the
/// streak; only the views after an advance count towards the eight, so
/// that two views of one sensor output (a turn too short for the sensor
/// to put out a new value) do not. The watch keeps one streak for all sensors, not one count each:
/// the sensors that repeated at the streak's first view, less each that
/// has changed since. A sensor that starts to repeat during another's
/// streak is counted from the next streak: found later, never wrongly.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FreezeWatch {
    /// The counts of the last view.
    last: RawCounts,
    /// Bit `i`: sensor `i` has repeated its count in every view of the
    /// streak.
    suspects: u8,
    /// Views after an advance in the streak, the first one included.
    views: u8,
}

impl FreezeWatch {
    /// Take a view's counts, `moved` if the rover advanced since the last
    /// view: whether a sensor's count has now been the same in `views`
    /// views, each after the first taken after an advance, and in every
    /// view between them (never for `views` 0).
    pub fn frozen(&mut self, raw: &RawCounts, moved: bool, views: u8) -> bool {
        let mut same = 0;
        for (i, (&c, last)) in raw.iter().zip(self.last.iter_mut()).enumerate() {
            if c == *last {
                same |= 1 << i;
            }
            *last = c;
        }
        self.suspects &= same;
        if moved {
            if self.suspects == 0 {
                // A new streak: the count before and this one.
                self.suspects = same;
                self.views = 1;
            }
            self.views = self.views.saturating_add(1);
        }
        views > 0 && self.suspects != 0 && self.views >= views
    }
}

/// Distrusts a reading that jumps from very near to far in one cycle: that
/// is what an object entering the fold-back region looks like. The jump is
/// read as "too close" for that one cycle (the planner turns away rather
/// than driving on), then trusted again.
///
/// A sensor is compared with its own last reading, of another direction
/// after a turn: something near on that side may reach into the new view,
/// and that comparison is what stops advances into flank obstacles the
/// outer beam reads in its fold-back region after a turn (comparing with
/// the sensor that looked the same way instead: 13 collisions in 1,500
/// BARN-tight runs instead of 2, the commit history). A rover held on one spot
/// ([`Self::look`]'s `by_way`, see the pocket rule in `Planner::step_raw`)
/// compares each sensor with the one that looked its way the cycle before,
/// if one did (turning 40° left, the −40° sensor with the 0° one): else each
/// free way it turned to read "too close" through the outer beam that had
/// seen the pocket's wall the cycle before, and it turned round until the
/// escape gave up (barn-tight-225 with seed 2: 401 cycles).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FoldBackFilter {
    last_mm: [u16; SENSOR_COUNT],
    heading: Angle,
}

impl FoldBackFilter {
    /// A previous reading at or below this (mm) makes a far jump suspect.
    pub const NEAR_MM: u16 = 150;

    /// Two sensor directions within this of each other look the same way.
    pub const SAME_WAY: Angle = Angle::from_deg(5);

    /// The rover now faces `heading`, its sensors at `angles` (robot frame);
    /// with `by_way`, each sensor takes the last reading of the sensor that
    /// looked its way, if one did (call before this cycle's
    /// [`Self::filter`]).
    pub fn look(&mut self, heading: Angle, angles: &[Angle; SENSOR_COUNT], by_way: bool) {
        let turn = heading.sub(self.heading);
        self.heading = heading;
        if !by_way || turn.abs_signed() <= Self::SAME_WAY.0 {
            return;
        }
        let before = self.last_mm;
        for (last, &a) in self.last_mm.iter_mut().zip(angles) {
            // This sensor's way in the frame of the last heading.
            let way = a.add(turn);
            if let Some(j) = angles
                .iter()
                .position(|&b| b.sub(way).abs_signed() <= Self::SAME_WAY.0)
            {
                *last = before[j.min(SENSOR_COUNT - 1)];
            }
        }
    }

    /// Filter this cycle's reading of sensor `i`.
    pub fn filter(&mut self, i: usize, r: Reading) -> Reading {
        let Some(last) = self.last_mm.get_mut(i) else {
            return r;
        };
        let now = match r {
            Reading::Range(mm) => mm,
            Reading::Clear => u16::MAX,
            Reading::TooClose | Reading::Implausible => 0,
        };
        // `last` in 1 ..= NEAR_MM, as one unsigned compare.
        let was_near = last.wrapping_sub(1) < Self::NEAR_MM;
        let suspect = was_near && now > last.saturating_mul(2);
        *last = now.max(1);
        if suspect {
            Reading::TooClose
        } else {
            r
        }
    }
}

/// A source of the five IR channels as raw ADC counts.
pub trait IrSensors {
    /// Why a read failed.
    type Error;
    /// Read all five channels, in sensor order (−40° … +40°).
    fn read_raw(&mut self) -> Result<RawCounts, Self::Error>;
}

/// A fixed set of counts is a (constant) sensor source.
impl IrSensors for RawCounts {
    type Error = core::convert::Infallible;
    fn read_raw(&mut self) -> Result<RawCounts, Self::Error> {
        Ok(*self)
    }
}

/// The script ran out of recorded frames.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EndOfScript;

/// Replays recorded raw counts, one frame per read: for host tests, the
/// simulator and emulated firmware builds that have no real ADC.
#[derive(Clone, Debug)]
pub struct ScriptedSensors<'a> {
    frames: &'a [RawCounts],
    next: usize,
}

impl<'a> ScriptedSensors<'a> {
    /// A source that yields `frames` in order, then [`EndOfScript`].
    pub fn new(frames: &'a [RawCounts]) -> Self {
        ScriptedSensors { frames, next: 0 }
    }

    /// Frames not yet read.
    pub fn remaining(&self) -> usize {
        self.frames.len() - self.next
    }
}

impl IrSensors for ScriptedSensors<'_> {
    type Error = EndOfScript;
    fn read_raw(&mut self) -> Result<RawCounts, EndOfScript> {
        let f = self.frames.get(self.next).copied().ok_or(EndOfScript)?;
        self.next += 1;
        Ok(f)
    }
}

#[cfg(feature = "hal02")]
mod hal02 {
    use super::{IrSensors, RawCounts};
    use core::marker::PhantomData;
    use embedded_hal_02::adc::{Channel, OneShot};

    /// Five embedded-hal 0.2 one-shot ADC channels as an [`IrSensors`]
    /// source. `pins` are in sensor order (−40° … +40°). Each read blocks
    /// until its conversion ends (a few µs on an STM32).
    pub struct OneShotSensors<ADC, A, P0, P1, P2, P3, P4> {
        /// The ADC peripheral driver.
        pub adc: A,
        /// The five analog pins, in sensor order.
        pub pins: (P0, P1, P2, P3, P4),
        _adc: PhantomData<ADC>,
    }

    impl<ADC, A, P0, P1, P2, P3, P4> OneShotSensors<ADC, A, P0, P1, P2, P3, P4> {
        /// Wrap an ADC driver and five pins.
        pub fn new(adc: A, pins: (P0, P1, P2, P3, P4)) -> Self {
            OneShotSensors {
                adc,
                pins,
                _adc: PhantomData,
            }
        }
    }

    impl<ADC, A, E, P0, P1, P2, P3, P4> IrSensors for OneShotSensors<ADC, A, P0, P1, P2, P3, P4>
    where
        P0: Channel<ADC>,
        P1: Channel<ADC>,
        P2: Channel<ADC>,
        P3: Channel<ADC>,
        P4: Channel<ADC>,
        A: OneShot<ADC, u16, P0, Error = E>
            + OneShot<ADC, u16, P1, Error = E>
            + OneShot<ADC, u16, P2, Error = E>
            + OneShot<ADC, u16, P3, Error = E>
            + OneShot<ADC, u16, P4, Error = E>,
    {
        type Error = E;
        fn read_raw(&mut self) -> Result<RawCounts, E> {
            let (p0, p1, p2, p3, p4) = &mut self.pins;
            Ok([
                nb::block!(self.adc.read(p0))?,
                nb::block!(self.adc.read(p1))?,
                nb::block!(self.adc.read(p2))?,
                nb::block!(self.adc.read(p3))?,
                nb::block!(self.adc.read(p4))?,
            ])
        }
    }
}

#[cfg(feature = "hal02")]
pub use hal02::OneShotSensors;

#[cfg(test)]
mod tests {
    use super::*;

    fn avr() -> Calibration {
        Calibration::gp2y0a21(AdcProfile::AVR_10BIT_5V).unwrap()
    }

    #[test]
    fn too_close_is_an_obstacle_at_the_face_and_a_fault_none() {
        assert_eq!(Reading::Range(120).obstacle_mm(), Some(120));
        assert_eq!(Reading::TooClose.obstacle_mm(), Some(0));
        assert_eq!(Reading::Clear.obstacle_mm(), None);
        assert_eq!(Reading::Implausible.obstacle_mm(), None);
    }

    #[test]
    fn datasheet_counts_by_hand() {
        // 2.6 V of 5 V on 10 bits: 2600 * 1023 / 5000 = 531.96 → 532.
        assert_eq!(AdcProfile::AVR_10BIT_5V.counts_for_mv(2_600), 532);
        assert_eq!(AdcProfile::AVR_10BIT_5V.counts_for_mv(420), 86);
        // 0.42 V of 3.3 V on 12 bits: 420 * 4095 / 3300 = 521.2 → 521.
        assert_eq!(AdcProfile::STM32_12BIT_3V3.counts_for_mv(420), 521);
        let cal = avr();
        assert_eq!(cal.window(), (86, 532));
    }

    #[test]
    fn readings_follow_the_datasheet_within_the_resampling_error() {
        for adc in [AdcProfile::AVR_10BIT_5V, AdcProfile::STM32_12BIT_3V3] {
            let cal = Calibration::gp2y0a21(adc).unwrap();
            for &(mv, mm) in GP2Y0A21_MV_MM.iter() {
                let got = cal.reading(adc.counts_for_mv(mv)).range_mm().unwrap();
                let err = (got as i32 - mm as i32).abs();
                // Resampling onto 32 bins costs at most this much here.
                assert!(err <= 25, "{adc:?} {mv} mV: {got} mm vs {mm} mm");
            }
        }
    }

    #[test]
    fn the_reciprocal_table_reads_between_the_points_as_1_over_d() {
        for adc in [AdcProfile::AVR_10BIT_5V, AdcProfile::STM32_12BIT_3V3] {
            let inv = Calibration::gp2y0a21_reciprocal(adc).unwrap();
            let lin = Calibration::gp2y0a21(adc).unwrap();
            let mm = |cal: &Calibration, mv| cal.reading(adc.counts_for_mv(mv)).range_mm().unwrap();
            // Halfway in volts between the 100 and 200 mm points: 1/d
            // halfway, 133 mm; the straight line in d says 150 mm.
            let (got, straight) = (mm(&inv, 1_995), mm(&lin, 1_995));
            assert!(got.abs_diff(133) <= 6, "{adc:?}: {got} mm");
            assert!(straight.abs_diff(150) <= 6, "{adc:?}: {straight} mm");
            // The datasheet points themselves, within the resampling error.
            for &(mv, want) in GP2Y0A21_MV_MM.iter() {
                assert!(mm(&inv, mv).abs_diff(want) <= 25, "{adc:?} {mv} mV");
            }
            // 1/d between two points lies below their chord in d: never
            // farther than the linear table (but for rounding).
            let (far, near) = inv.window();
            for raw in far..=near {
                let (a, b) = (inv.reading(raw), lin.reading(raw));
                let (a, b) = (a.range_mm().unwrap(), b.range_mm().unwrap());
                assert!(a <= b + 1, "{adc:?} count {raw}: {a} > {b}");
            }
        }
    }

    /// 5 V ADCs of 8, 10, 12 and 16 bits.
    fn adcs() -> [AdcProfile; 4] {
        [8, 10, 12, 16].map(|bits| AdcProfile {
            bits,
            vref_mv: 5_000,
        })
    }

    #[test]
    fn the_scaled_interpolation_is_the_plain_one() {
        // Every count of the 8-, 10-, 12- and 16-bit ADCs against the
        // interpolation with the bin's own shift.
        for adc in adcs() {
            let bits = adc.bits;
            let cal = Calibration::gp2y0a21(adc).unwrap();
            for raw in cal.far_count..=cal.near_count {
                let (s, i) = (cal.shift, (raw >> cal.shift) as usize);
                let f = (raw & ((1 << s) - 1)) as i32;
                let d0 = cal.mm[i] as i32;
                let d1 = cal.mm.get(i + 1).map_or(d0, |&d| d as i32);
                let d = d0 + (((d1 - d0) * f + (1 << (s - 1))) >> s);
                assert_eq!(
                    cal.reading(raw),
                    Reading::Range(d as u16),
                    "{bits} bits, {raw}"
                );
            }
        }
    }

    #[test]
    fn every_reading_lies_between_its_bins_edges() {
        // What lets `reading` return its interpolation as a `u16` with no
        // clamp: the datasheet tables and a steep one (2,000 mm to 20
        // between two adjacent counts, its bins extrapolated to the
        // table's limits), every count of 8- to 16-bit ADCs.
        for adc in adcs() {
            let bits = adc.bits;
            let mid = 1u16 << (bits - 1);
            let steep = Calibration::from_points(adc, &[(mid, 2_000), (mid + 1, 20)]).unwrap();
            for cal in [Calibration::gp2y0a21(adc).unwrap(), steep] {
                for raw in cal.far_count..=cal.near_count {
                    let i = (raw >> cal.shift) as usize;
                    let d0 = cal.mm[i];
                    let d1 = cal.mm.get(i + 1).copied().unwrap_or(d0);
                    let d = cal.reading(raw).range_mm().unwrap();
                    assert!(
                        (d0.min(d1)..=d0.max(d1)).contains(&d),
                        "{bits} bits, {raw}: {d} outside {d0}..{d1}"
                    );
                }
            }
        }
    }

    /// A dead or unplugged sensor (0 V, or anything under 0.1 V) is a
    /// fault on both ADCs; the phantom level a working sensor gives with
    /// nothing in range (0.25 V at the least) is clear.
    #[test]
    fn a_silent_sensor_is_implausible_and_the_phantom_level_clear() {
        for adc in [AdcProfile::AVR_10BIT_5V, AdcProfile::STM32_12BIT_3V3] {
            let cal = Calibration::gp2y0a21(adc).unwrap();
            for mv in [0, 50, 90] {
                let r = cal.reading(adc.counts_for_mv(mv));
                assert_eq!(r, Reading::Implausible, "{adc:?} {mv} mV");
            }
            for mv in [101, 250, 300, 400] {
                let r = cal.reading(adc.counts_for_mv(mv));
                assert_eq!(r, Reading::Clear, "{adc:?} {mv} mV");
            }
        }
        // A table whose far end is below the floor keeps its whole range.
        let adc = AdcProfile::AVR_10BIT_5V;
        let cal = Calibration::from_points(adc, &[(10, 1_500), (500, 100)]).unwrap();
        assert!(matches!(cal.reading(10), Reading::Range(_)));
        assert_eq!(cal.reading(0), Reading::Clear);
    }

    #[test]
    fn classification_at_the_edges() {
        let cal = avr();
        // 0.1 V is count 20 of 1,023 at 5 V: below it, no sensor answers.
        assert_eq!(cal.reading(0), Reading::Implausible);
        assert_eq!(cal.reading(19), Reading::Implausible);
        assert_eq!(cal.reading(20), Reading::Clear);
        assert_eq!(cal.reading(85), Reading::Clear);
        assert!(matches!(cal.reading(86), Reading::Range(_)));
        assert!(matches!(cal.reading(532), Reading::Range(_)));
        assert_eq!(cal.reading(533), Reading::TooClose);
        assert_eq!(cal.reading(1_023), Reading::TooClose);
        assert_eq!(cal.reading(1_024), Reading::Implausible);
        assert_eq!(cal.reading(u16::MAX), Reading::Implausible);
    }

    #[test]
    fn readings_are_monotonic_in_counts() {
        let cal = avr();
        let mut prev = u16::MAX;
        for c in 86..=532 {
            let d = cal.reading(c).range_mm().unwrap();
            assert!(d <= prev, "count {c}: {d} > {prev}");
            prev = d;
        }
    }

    #[test]
    fn bad_tables_are_errors() {
        let adc = AdcProfile::AVR_10BIT_5V;
        assert_eq!(
            Calibration::from_points(adc, &[(100, 500)]),
            Err(CalibrationError::TooFewPoints)
        );
        assert_eq!(
            Calibration::from_points(adc, &[(100, 500), (200, 600)]),
            Err(CalibrationError::NotMonotonic)
        );
        assert_eq!(
            Calibration::from_points(adc, &[(100, 500), (100, 400)]),
            Err(CalibrationError::NotMonotonic)
        );
        assert_eq!(
            Calibration::from_points(adc, &[(100, 500), (2_000, 100)]),
            Err(CalibrationError::CountOutOfRange)
        );
        assert_eq!(
            Calibration::from_points(adc, &[(100, 5_000), (200, 100)]),
            Err(CalibrationError::DistanceOutOfRange)
        );
        let many: [(u16, u16); MAX_CAL_POINTS + 1] =
            core::array::from_fn(|i| (10 * i as u16, 1_000 - 10 * i as u16));
        assert_eq!(
            Calibration::from_points(adc, &many),
            Err(CalibrationError::TooManyPoints)
        );
        assert!(Calibration::from_points(adc, &many[..MAX_CAL_POINTS]).is_ok());
        let bad = AdcProfile {
            bits: 20,
            vref_mv: 5_000,
        };
        assert_eq!(
            Calibration::from_points(bad, &[(100, 500), (200, 100)]),
            Err(CalibrationError::BadAdc)
        );
        // Order of input does not matter.
        assert!(Calibration::from_points(adc, &[(200, 300), (100, 500)]).is_ok());
    }

    #[test]
    fn fold_back_jump_is_distrusted_for_one_cycle() {
        let mut f = FoldBackFilter::default();
        let apply = |f: &mut FoldBackFilter, r: &mut Readings| {
            for (i, x) in r.iter_mut().enumerate() {
                *x = f.filter(i, *x);
            }
        };
        let mut r = [Reading::Range(120); SENSOR_COUNT];
        apply(&mut f, &mut r);
        assert_eq!(r[0], Reading::Range(120));
        let mut r = [Reading::Clear; SENSOR_COUNT];
        apply(&mut f, &mut r);
        assert_eq!(r[0], Reading::TooClose);
        let mut r = [Reading::Clear; SENSOR_COUNT];
        apply(&mut f, &mut r);
        assert_eq!(r[0], Reading::Clear);
    }

    #[test]
    fn held_on_a_spot_each_sensor_is_compared_with_the_one_that_looked_its_way() {
        let angles = [-40, -20, 0, 20, 40].map(Angle::from_deg);
        let mut f = FoldBackFilter::default();
        let mut apply = |heading: i16, by_way: bool, r: [Reading; SENSOR_COUNT]| {
            f.look(Angle::from_deg(heading), &angles, by_way);
            let mut out = r;
            for (i, x) in out.iter_mut().enumerate() {
                *x = f.filter(i, *x);
            }
            out
        };
        let (near, far) = (Reading::Range(120), Reading::Clear);
        // Near on the right (−40°), clear elsewhere; then 40° left, not
        // held: the −40° sensor is compared with its own last reading
        // (near, of the way now 80° right): suspect.
        apply(0, false, [near, far, far, far, far]);
        let got = apply(40, false, [far; SENSOR_COUNT]);
        assert_eq!(got[0], Reading::TooClose, "{got:?}");
        // The same held on the spot: the −40° sensor now looks where the 0°
        // one looked (clear), and its clear reading is trusted; the +20°
        // and +40° sensors look where none looked and keep their own.
        apply(40, false, [near, far, far, far, far]);
        assert_eq!(apply(80, true, [far; SENSOR_COUNT]), [far; SENSOR_COUNT]);
        // Held, near ahead, then 40° left: the −40° sensor looks where the
        // 0° one saw it near, and reads far: suspect.
        apply(80, true, [far, far, near, far, far]);
        let got = apply(120, true, [far; SENSOR_COUNT]);
        assert_eq!(got[0], Reading::TooClose, "{got:?}");
        assert!(got[1..].iter().all(|&r| r == far), "{got:?}");
        // A turn within the tolerance is no turn.
        apply(120, true, [far, far, near, far, far]);
        assert_eq!(apply(124, true, [far; SENSOR_COUNT])[2], Reading::TooClose);
    }

    #[test]
    fn scripted_source_replays_then_ends() {
        let frames = [[1, 2, 3, 4, 5], [6, 7, 8, 9, 10]];
        let mut s = ScriptedSensors::new(&frames);
        assert_eq!(s.read_raw(), Ok([1, 2, 3, 4, 5]));
        assert_eq!(s.remaining(), 1);
        assert_eq!(s.read_raw(), Ok([6, 7, 8, 9, 10]));
        assert_eq!(s.read_raw(), Err(EndOfScript));
    }
}
