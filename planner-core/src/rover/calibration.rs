//! Each sensor's own calibration, measured on the rover and stored on the
//! board.
//!
//! GP2Y0A21 units differ by ±5 % or more from the datasheet's typical
//! curve, which the planner's [`crate::Calibration`] is built from. A
//! sensor is measured against a card held at each of [`CARD_MM`] (the
//! datasheet's own distances; `D` prints its counts), and [`fit`] finds the
//! straight line from its counts to the datasheet's counts at the same
//! distances: a gain and an offset, its [`Correction`]. The board keeps
//! the five corrections (`K`, [`crate::rover::protocol`]) and passes each
//! count through its sensor's before the planner reads it
//! ([`Corrections::apply`]): one multiply a count. Counts below the signal
//! floor pass unchanged, so a broken wire is still a fault.
//!
//! The fit is the host's work (the console's); the board checks what it is
//! sent ([`Correction::check`]) and stores it with a checksum
//! ([`Corrections::to_bytes`]). A stored copy that is absent, corrupt or
//! refused leaves the datasheet's curve in use, and the telemetry says
//! which ([`Source`]).

use crate::eapf::sensors::{AdcProfile, RawCounts, GP2Y0A21_MV_MM, SENSOR_COUNT, SIGNAL_FLOOR_MV};
use embedded_storage::nor_flash::{NorFlash, ReadNorFlash};

/// How many card distances a measurement has.
pub const CARD_POINTS: usize = GP2Y0A21_MV_MM.len();

/// Where the card is held, mm from the sensor's face, nearest first: the
/// datasheet's distances.
pub const CARD_MM: [u16; CARD_POINTS] = {
    let mut mm = [0; CARD_POINTS];
    let mut i = 0;
    while i < CARD_POINTS {
        mm[i] = GP2Y0A21_MV_MM[i].1;
        i += 1;
    }
    mm
};

/// One sensor's counts at [`CARD_MM`].
pub type Row = [u16; CARD_POINTS];

/// The datasheet's counts at [`CARD_MM`] on `adc`.
pub const fn datasheet_row(adc: AdcProfile) -> Row {
    let mut row = [0; CARD_POINTS];
    let mut i = 0;
    while i < CARD_POINTS {
        row[i] = adc.counts_for_mv(GP2Y0A21_MV_MM[i].0);
        i += 1;
    }
    row
}

/// Gains a working sensor needs, 1/256: its output 0.6 to 1.6 times the
/// datasheet's (a unit's spread, a card's reflectance and the supply's
/// tolerance together).
pub const GAIN_Q8: core::ops::RangeInclusive<u16> = 160..=427;

/// Offsets a working sensor needs, as a share of the ADC's full scale:
/// at most an eighth (0.6 V of 5 V, 0.4 V of 3.3 V).
pub const OFFSET_SHARE: u16 = 8;

/// How far, in counts at most, a measured point may lie from the fitted
/// line: further, the sensor is not one of these (or the card moved).
pub const FIT_TOLERANCE_COUNTS: u32 = 40;

/// One sensor's correction: the datasheet's count for its count `c` is
/// `c · gain_q8 / 256 + offset`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Correction {
    /// Gain, 1/256.
    pub gain_q8: u16,
    /// Offset, counts.
    pub offset: i16,
}

impl Correction {
    /// Counts pass unchanged.
    pub const NONE: Correction = Correction {
        gain_q8: 256,
        offset: 0,
    };

    /// Whether a working sensor on an ADC of full scale `full` counts can
    /// need this correction ([`GAIN_Q8`], [`OFFSET_SHARE`]).
    pub fn check(self, full: u16) -> Result<Correction, CalibrationError> {
        let most = full / OFFSET_SHARE;
        if GAIN_Q8.contains(&self.gain_q8) && self.offset.unsigned_abs() <= most {
            Ok(self)
        } else {
            Err(CalibrationError::Implausible)
        }
    }
}

/// Which calibration the counts go through.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Source {
    /// None stored: the datasheet's curve.
    Datasheet,
    /// The sensors' own.
    Stored,
    /// A stored copy failed its checksum or checks: the datasheet's curve.
    Corrupt,
}

impl Source {
    /// The telemetry's letter: `-` datasheet, `C` calibrated, `!` corrupt.
    pub fn letter(self) -> u8 {
        match self {
            Source::Datasheet => b'-',
            Source::Stored => b'C',
            Source::Corrupt => b'!',
        }
    }

    /// The source of a [`Source::letter`]; `None` for any other byte.
    pub fn from_letter(letter: u8) -> Option<Source> {
        [Source::Datasheet, Source::Stored, Source::Corrupt]
            .into_iter()
            .find(|s| s.letter() == letter)
    }
}

/// Why a measurement, a correction or a stored copy was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CalibrationError {
    /// No such sensor.
    NoSensor,
    /// The counts do not fall strictly with distance.
    NotFalling,
    /// The points do not lie on a line near enough
    /// ([`FIT_TOLERANCE_COUNTS`]).
    PoorFit,
    /// A gain or offset no working sensor needs.
    Implausible,
    /// A stored copy's checksum does not match it.
    Checksum,
}

/// The straight line (least squares) from a sensor's counts at
/// [`CARD_MM`] to the datasheet's on `adc`, checked: the counts must fall
/// strictly with distance, lie within [`FIT_TOLERANCE_COUNTS`] of the line,
/// and need a plausible correction.
pub fn fit(adc: AdcProfile, measured: &Row) -> Result<Correction, CalibrationError> {
    if measured.windows(2).any(|w| w[1] >= w[0]) {
        return Err(CalibrationError::NotFalling);
    }
    let target = datasheet_row(adc);
    let n = CARD_POINTS as i64;
    let (mut sx, mut sy, mut sxx, mut sxy) = (0i64, 0i64, 0i64, 0i64);
    for (&x, &y) in measured.iter().zip(&target) {
        let (x, y) = (i64::from(x), i64::from(y));
        (sx, sy, sxx, sxy) = (sx + x, sy + y, sxx + x * x, sxy + x * y);
    }
    let den = n * sxx - sx * sx;
    // Falling strictly, the counts are not all equal: `den` > 0.
    let gain_q8 = ((n * sxy - sy * sx) * 256 + den / 2)
        .checked_div(den)
        .unwrap_or(0);
    let offset = (sy * 256 - gain_q8 * sx).div_euclid(n * 256);
    let c = Correction {
        gain_q8: u16::try_from(gain_q8).map_err(|_| CalibrationError::Implausible)?,
        offset: i16::try_from(offset).map_err(|_| CalibrationError::Implausible)?,
    }
    .check(adc.full_scale())?;
    let worst = measured
        .iter()
        .zip(&target)
        .map(|(&x, &y)| u32::from(apply_one(c, x, 0, u16::MAX).abs_diff(y)))
        .max()
        .unwrap_or(0);
    if worst > FIT_TOLERANCE_COUNTS {
        return Err(CalibrationError::PoorFit);
    }
    Ok(c)
}

/// `c` through `k`: counts below `floor` unchanged, the rest within
/// `floor ..= full`.
fn apply_one(k: Correction, c: u16, floor: u16, full: u16) -> u16 {
    if c < floor {
        return c;
    }
    let v = ((u32::from(c) * u32::from(k.gain_q8) + 128) >> 8) as i32 + i32::from(k.offset);
    // `max` then `min`: `clamp` would link a panic for bounds it cannot
    // see are ordered.
    v.max(i32::from(floor)).min(i32::from(full)) as u16
}

/// Bytes of the stored corrections: each gain and offset, little-endian,
/// then a checksum.
pub const STORED_BYTES: usize = SENSOR_COUNT * 4 + 2;

/// The five sensors' corrections.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Corrections {
    each: [Correction; SENSOR_COUNT],
    /// The signal floor and full scale of the ADC, counts.
    floor: u16,
    full: u16,
}

impl Corrections {
    /// None: every count passes unchanged.
    pub const fn none(adc: AdcProfile) -> Self {
        Corrections {
            each: [Correction::NONE; SENSOR_COUNT],
            floor: adc.counts_for_mv(SIGNAL_FLOOR_MV),
            full: adc.full_scale(),
        }
    }

    /// Take `k` for sensor `sensor` if a working sensor can need it.
    pub fn set(&mut self, sensor: usize, k: Correction) -> Result<(), CalibrationError> {
        let k = k.check(self.full)?;
        *self
            .each
            .get_mut(sensor)
            .ok_or(CalibrationError::NoSensor)? = k;
        Ok(())
    }

    /// Each count through its sensor's correction.
    pub fn apply(&self, raw: &RawCounts) -> RawCounts {
        let mut out = *raw;
        for (c, &k) in out.iter_mut().zip(&self.each) {
            *c = apply_one(k, *c, self.floor, self.full);
        }
        out
    }

    /// The corrections, little-endian, and their checksum.
    pub fn to_bytes(&self) -> [u8; STORED_BYTES] {
        let mut out = [0; STORED_BYTES];
        for (b, k) in out.chunks_exact_mut(4).zip(&self.each) {
            b[..2].copy_from_slice(&k.gain_q8.to_le_bytes());
            b[2..].copy_from_slice(&k.offset.to_le_bytes());
        }
        let sum = checksum(&out[..STORED_BYTES - 2]);
        out[STORED_BYTES - 2..].copy_from_slice(&sum.to_le_bytes());
        out
    }

    /// Take the corrections stored in `bytes` ([`Corrections::to_bytes`]):
    /// `Err`, and none taken, if the checksum fails or one is refused.
    pub fn load(&mut self, bytes: &[u8; STORED_BYTES]) -> Result<(), CalibrationError> {
        let (body, sum) = bytes.split_at(STORED_BYTES - 2);
        if checksum(body).to_le_bytes() != sum {
            return Err(CalibrationError::Checksum);
        }
        let mut all = *self;
        for (sensor, b) in body.chunks_exact(4).enumerate() {
            let k = Correction {
                gain_q8: u16::from_le_bytes([b[0], b[1]]),
                offset: i16::from_le_bytes([b[2], b[3]]),
            };
            all.set(sensor, k)?;
        }
        *self = all;
        Ok(())
    }
}

/// The stored corrections read from a NOR flash at `offset` (the STM32
/// keeps them in a sector of its own): `false` if it cannot be read.
pub fn load_from_flash<F: ReadNorFlash>(
    flash: &mut F,
    offset: u32,
    bytes: &mut [u8; STORED_BYTES],
) -> bool {
    flash.read(offset, bytes).is_ok()
}

/// Store `bytes` in a NOR flash at `offset`: the erase sector holding it
/// is erased first (NOR bits are only cleared by a write), so it must hold
/// nothing else.
pub fn store_in_flash<F: NorFlash>(flash: &mut F, offset: u32, bytes: &[u8; STORED_BYTES]) -> bool {
    let size = F::ERASE_SIZE as u32;
    let sector = offset - offset % size;
    flash.erase(sector, sector + size).is_ok() && flash.write(offset, bytes).is_ok()
}

/// A 16-bit checksum: each byte added to a sum rotated a bit left, so
/// that a byte changed, lost or moved changes it; seeded so that an erased
/// store (every byte 0xff or 0) fails.
fn checksum(bytes: &[u8]) -> u16 {
    bytes
        .iter()
        .fold(0x5a17u16, |s, &b| s.rotate_left(1) ^ u16::from(b))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const ADC: AdcProfile = AdcProfile::AVR_10BIT_5V;

    /// A unit whose counts are `percent` of the datasheet's, plus `plus`.
    fn unit(percent: u32, plus: i32) -> Row {
        datasheet_row(ADC).map(|c| (i32::from(c) * percent as i32 / 100 + plus) as u16)
    }

    #[test]
    fn sources_round_trip_through_their_letters() {
        for s in [Source::Datasheet, Source::Stored, Source::Corrupt] {
            assert_eq!(Source::from_letter(s.letter()), Some(s));
        }
        assert_eq!(Source::from_letter(b'M'), None);
    }

    #[test]
    fn the_datasheet_fits_as_no_correction() {
        assert_eq!(fit(ADC, &datasheet_row(ADC)), Ok(Correction::NONE));
        let none = Corrections::none(ADC);
        for c in 0..=ADC.full_scale() {
            assert_eq!(none.apply(&[c; 5]), [c; 5]);
        }
    }

    #[test]
    fn a_unit_reads_as_the_datasheet_at_each_card() {
        for (percent, plus) in [(110, 0), (90, 12), (125, -20), (70, 30)] {
            let row = unit(percent, plus);
            let k = fit(ADC, &row).unwrap();
            let mut all = Corrections::none(ADC);
            all.set(2, k).unwrap();
            for (&c, &want) in row.iter().zip(&datasheet_row(ADC)) {
                let got = all.apply(&[c; 5]);
                assert!(
                    got[2].abs_diff(want) <= 2,
                    "{percent}% {plus:+}: {c} -> {got:?}, want {want}"
                );
                assert_eq!(got[0], c, "the others unchanged");
            }
            // A broken wire is still a fault.
            assert_eq!(all.apply(&[0; 5])[2], 0);
        }
    }

    #[test]
    fn measurements_no_working_sensor_gives_are_refused() {
        let mut flat = unit(100, 0);
        flat[3] = flat[2];
        assert_eq!(fit(ADC, &flat), Err(CalibrationError::NotFalling));
        assert_eq!(fit(ADC, &unit(200, 0)), Err(CalibrationError::Implausible));
        assert_eq!(fit(ADC, &unit(40, 0)), Err(CalibrationError::Implausible));
        let mut bent = unit(100, 0);
        bent[1] += 80;
        assert_eq!(fit(ADC, &bent), Err(CalibrationError::PoorFit));
        let mut all = Corrections::none(ADC);
        let k = fit(ADC, &unit(100, 0)).unwrap();
        assert_eq!(all.set(5, k), Err(CalibrationError::NoSensor));
        let wild = Correction {
            gain_q8: 256,
            offset: 200,
        };
        assert_eq!(all.set(0, wild), Err(CalibrationError::Implausible));
        assert_eq!(all, Corrections::none(ADC), "nothing taken");
    }

    #[test]
    fn stored_corrections_read_back_and_a_damaged_copy_is_refused() {
        let mut all = Corrections::none(ADC);
        all.set(1, fit(ADC, &unit(92, 5)).unwrap()).unwrap();
        all.set(3, fit(ADC, &unit(107, -8)).unwrap()).unwrap();
        let bytes = all.to_bytes();
        let read = |bytes: &[u8; STORED_BYTES]| {
            let mut back = Corrections::none(ADC);
            back.load(bytes).map(|()| back)
        };
        assert_eq!(read(&bytes), Ok(all));
        for i in 0..STORED_BYTES {
            for bit in 0..8 {
                let mut bad = bytes;
                bad[i] ^= 1 << bit;
                assert!(read(&bad).is_err(), "byte {i} bit {bit}");
            }
        }
        assert!(read(&[0xff; STORED_BYTES]).is_err());
        assert!(read(&[0; STORED_BYTES]).is_err());
    }

    /// A NOR flash in RAM, as a chip behaves: erased bytes read 0xff, a
    /// write only clears bits, an erase takes whole sectors of 1 KB.
    struct Nor(std::vec::Vec<u8>);

    impl embedded_storage::nor_flash::ErrorType for Nor {
        type Error = embedded_storage::nor_flash::NorFlashErrorKind;
    }

    impl ReadNorFlash for Nor {
        const READ_SIZE: usize = 1;
        fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
            let at = offset as usize;
            let got = self.0.get(at..at + bytes.len());
            bytes.copy_from_slice(got.ok_or(Self::Error::OutOfBounds)?);
            Ok(())
        }
        fn capacity(&self) -> usize {
            self.0.len()
        }
    }

    impl NorFlash for Nor {
        const WRITE_SIZE: usize = 1;
        const ERASE_SIZE: usize = 1024;
        fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
            if !from.is_multiple_of(1024) || !to.is_multiple_of(1024) {
                return Err(Self::Error::NotAligned);
            }
            self.0[from as usize..to as usize].fill(0xff);
            Ok(())
        }
        fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
            for (cell, b) in self.0[offset as usize..].iter_mut().zip(bytes) {
                *cell &= b;
            }
            Ok(())
        }
    }

    #[test]
    fn corrections_are_stored_in_a_nor_flash_sector_and_read_back() {
        let mut nor = Nor(std::vec![0xff; 4 * 1024]);
        let mut none = [0; STORED_BYTES];
        assert!(load_from_flash(&mut nor, 2 * 1024, &mut none));
        assert!(none.iter().all(|&b| b == 0xff), "erased: none stored");
        let mut all = Corrections::none(ADC);
        all.set(2, fit(ADC, &unit(111, -4)).unwrap()).unwrap();
        // Twice, the second over the first (which only an erase allows),
        // and the sector's neighbours untouched.
        nor.0[1023] = 0x42;
        for k in [fit(ADC, &unit(90, 7)).unwrap(), Correction::NONE] {
            all.set(4, k).unwrap();
            assert!(store_in_flash(&mut nor, 2 * 1024 + 16, &all.to_bytes()));
            let mut back = [0; STORED_BYTES];
            assert!(load_from_flash(&mut nor, 2 * 1024 + 16, &mut back));
            let mut read = Corrections::none(ADC);
            assert_eq!(read.load(&back), Ok(()));
            assert_eq!(read, all);
        }
        assert_eq!(nor.0[1023], 0x42);
        // Past its end: cannot be read.
        assert!(!load_from_flash(&mut nor, 4 * 1024 - 4, &mut none));
    }

    proptest! {
        /// A correction keeps the order of counts (a nearer object still
        /// reads nearer), for any correction a sensor may have.
        #[test]
        fn corrections_keep_the_order_of_counts(
            gain_q8 in GAIN_Q8,
            offset in -127i16..=127,
            a in 0u16..=1_023,
            b in 0u16..=1_023,
        ) {
            let mut all = Corrections::none(ADC);
            all.set(0, Correction { gain_q8, offset }).unwrap();
            let (lo, hi) = (a.min(b), a.max(b));
            prop_assert!(all.apply(&[lo; 5])[0] <= all.apply(&[hi; 5])[0]);
        }
    }
}
