//! The one place that defines the fixed-point formats, and the few
//! arithmetic routines (trigonometry, square root) built on them.
//!
//! The formats are chosen for the ATmega328P: 16-bit storage, 32-bit
//! intermediates, no floating point, and as few 32-bit divisions per planner
//! step as possible (one costs ~400 cycles there with the firmware's own
//! routine, `avr_costs`; 1,575 with compiler-builtins'). There are no lookup
//! tables: sine is a polynomial, so nothing has to be copied into the AVR's
//! 2 KB of RAM.
//!
//! | quantity | type | unit / scale | range | resolution | overflow |
//! |---|---|---|---|---|---|
//! | world coordinate | [`Point`] fields, `i16` | millimetre | ±32.767 m | 1 mm | saturates on conversion |
//! | distance, step | `u16` (`_mm` names) | millimetre | 0…65.535 m | 1 mm | saturates |
//! | angle, heading | [`Angle`] (`u16`) | binary angle, 65,536 = one turn | any (wraps) | 0.0055° | wraps (angles are circular) |
//! | sine, cosine | `i32`; in a [`Dir`], [`Q14`] (`i16` on the AVR, `i32` elsewhere) | Q14: 16,384 = 1.0 | ±1.0 | 6.1e-5 | n/a |
//! | force | [`Force`] (`i32` x, y) | Q10: 1,024 = 1 force unit | ±2,097,151 units | 0.001 | saturating adds |
//!
//! A "force unit" is the paper's: the attractive force has magnitude
//! ξ_att = 2, a collision point 1 m away repels with 1, one 0.1 m away with 100.

/// Fraction bits of a [`Force`] component.
pub const FORCE_SHIFT: u32 = 10;
/// One force unit in [`Force`] components (Q10).
pub const FORCE_ONE: i32 = 1 << FORCE_SHIFT;
/// Fraction bits of the trigonometric results.
pub const TRIG_SHIFT: u32 = 14;
/// 1.0 in the Q14 format of [`Angle::sin`] and [`Angle::cos`].
pub const TRIG_ONE: i32 = 1 << TRIG_SHIFT;

/// An angle as a binary fraction of a full turn: 65,536 = 360°.
///
/// Wrapping `u16` arithmetic is exactly circular arithmetic, so headings never
/// need normalising and cannot leave their range. Counter-clockwise positive,
/// zero along +x (docs/algorithms.md, the frames).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Angle(pub u16);

impl Angle {
    /// 0°.
    pub const ZERO: Angle = Angle(0);
    /// 90°.
    pub const QUARTER: Angle = Angle(16_384);
    /// 180°.
    pub const HALF: Angle = Angle(32_768);

    /// Whole degrees to an angle (exact to the angle's resolution).
    pub const fn from_deg(deg: i16) -> Angle {
        // deg * 65536 / 360, rounded; computed in i32 so it is exact for any i16.
        let turns = (deg as i32 % 360 + 360) % 360;
        Angle(((turns * 65_536 + 180) / 360) as u16)
    }

    /// Tenths of a degree to an angle.
    pub const fn from_decideg(decideg: i16) -> Angle {
        let t = (decideg as i32 % 3600 + 3600) % 3600;
        Angle(((t * 65_536 + 1_800) / 3_600) as u16)
    }

    /// The angle as a signed value in (−32,768 … 32,767] ≙ [−180°, 180°).
    pub const fn signed(self) -> i16 {
        self.0 as i16
    }

    /// `self + other`, wrapping.
    pub const fn add(self, other: Angle) -> Angle {
        Angle(self.0.wrapping_add(other.0))
    }

    /// `self − other`, wrapping.
    pub const fn sub(self, other: Angle) -> Angle {
        Angle(self.0.wrapping_sub(other.0))
    }

    /// `−self`.
    pub const fn neg(self) -> Angle {
        Angle(self.0.wrapping_neg())
    }

    /// The magnitude of the signed angle, 0 … 32,768.
    pub const fn abs_signed(self) -> u16 {
        self.signed().unsigned_abs()
    }

    /// Sine in Q14.
    ///
    /// Fifth-order polynomial `x·(a − x²·(b − x²·c))` with `a = π/2`,
    /// `b = π − 5/2`, `c = π/2 − 3/2`, exact at 0 and ±90°, maximum error
    /// about 5·10⁻⁴ (0.03° of heading); four 32-bit multiplies and no table.
    pub const fn sin(self) -> i32 {
        // Fold into [−90°, 90°]: sin(180° − t) = sin(t).
        let mut s = self.signed() as i32;
        if s > 16_384 {
            s = 32_768 - s;
        } else if s < -16_384 {
            s = -32_768 - s;
        }
        // s is now x in Q14, x ∈ [−1, 1] standing for x·90°. Every operand
        // below fits in i16 (each product in i32).
        const A: i32 = 25_736; // π/2 in Q14
        const B: i32 = 10_512; // (π − 5/2) in Q14
        const C: i32 = 1_160; // (π/2 − 3/2) in Q14
        let x = s as i16;
        let x2 = (mul16(x, x) >> 14) as i16;
        let t = (B - (mul16(C as i16, x2) >> 14)) as i16;
        let t = (A - (mul16(t, x2) >> 14)) as i16;
        (mul16(x, t) + (1 << 13)) >> 14
    }

    /// Cosine in Q14.
    pub const fn cos(self) -> i32 {
        self.add(Angle::QUARTER).sin()
    }

    /// `atan2(y, x)` as an angle; `atan2(0, 0)` is 0.
    ///
    /// Octant reduction, one 32-bit division for the ratio `t = min/max`,
    /// then `atan(t) ≈ (π/4)t + t(1 − t)(0.2447 + 0.0663t)`, maximum error
    /// 0.0015 rad (0.09°).
    pub fn atan2(y: i32, x: i32) -> Angle {
        if x == 0 && y == 0 {
            return Angle::ZERO;
        }
        let mut ax = x.unsigned_abs();
        let mut ay = y.unsigned_abs();
        // Keep both below 2^16 so `lo << 15` fits in u32.
        while (ax | ay) >= 1 << 16 {
            ax >>= 1;
            ay >>= 1;
        }
        let (lo, hi) = if ay > ax { (ax, ay) } else { (ay, ax) };
        // t in Q15, 0 ..= 32768 (hi > 0 here; `checked_div` keeps the
        // panicking path out).
        let t = (lo << 15).checked_div(hi).unwrap_or(0) as i32;
        // Binary-angle constants: 0.2447 rad and 0.0663 rad in units of 2π/65536.
        let p = 2_552 + ((692 * t) >> 15);
        let q = (t * (32_768 - t)) >> 15;
        let mut a = (t >> 2) + ((q * p) >> 15); // 0 ..= 8192 (45°)
        if ay > ax {
            a = 16_384 - a;
        }
        if x < 0 {
            a = 32_768 - a;
        }
        if y < 0 {
            a = -a;
        }
        Angle(a as u16)
    }

    /// Angle in degrees as f64, for tests, reports and telemetry only.
    #[cfg(test)]
    pub fn to_deg_f64(self) -> f64 {
        self.signed() as f64 * 360.0 / 65_536.0
    }
}

/// A direction as a Q14 unit vector `(cos, sin)`.
///
/// Turning a direction by another is four multiplies, cheaper
/// than a sine and a cosine: the planner takes the heading's sine and
/// cosine once per cycle and turns the sensors' fixed directions by it.
///
/// The components are at most 2^14 (a little more after a turn, from
/// rounding): see [`Q14`] for the width they are held in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Dir {
    /// Cosine, Q14.
    pub c: Q14,
    /// Sine, Q14.
    pub s: Q14,
}

/// A [`Dir`] component: 16 bits on the AVR, where every direction passed,
/// kept or spilled is then half the bytes; 32 elsewhere, where a 16-bit
/// value costs a sign extension at each use. The values are the same
/// either way (docs/performance.md).
#[cfg(target_arch = "avr")]
pub type Q14 = i16;
/// A [`Dir`] component (see the AVR's definition).
#[cfg(not(target_arch = "avr"))]
pub type Q14 = i32;

impl Dir {
    /// The cosine as 32 bits (a [`Q14`] is 16 on the AVR).
    #[allow(clippy::unnecessary_cast)] // `Q14` is `i32` off the AVR
    pub const fn cos(self) -> i32 {
        self.c as i32
    }

    /// The sine as 32 bits.
    #[allow(clippy::unnecessary_cast)]
    pub const fn sin(self) -> i32 {
        self.s as i32
    }

    /// The direction of an angle.
    pub const fn of(a: Angle) -> Dir {
        // |sin|, |cos| ≤ 2^14 (exact at ±90°).
        Dir {
            c: a.cos() as Q14,
            s: a.sin() as Q14,
        }
    }

    /// This direction turned by `by` (the angle sum, as a complex product).
    pub fn rotated(self, by: Dir) -> Dir {
        // Each sum is the cosine or sine of the angle sum, ≤ 2^14 but for
        // the rounding of the four products: it fits 16 bits.
        let (c, s, bc, bs) = (self.cos(), self.sin(), by.cos(), by.sin());
        Dir {
            c: (mul_q14(c, bc) - mul_q14(s, bs)) as Q14,
            s: (mul_q14(s, bc) + mul_q14(c, bs)) as Q14,
        }
    }

    /// `(x, y)` of a vector of length `magnitude` along this direction
    /// (clamped to ±[`MAX_SCALED`] so the Q14 products fit in 32 bits).
    pub fn scaled(self, magnitude: i32) -> (i32, i32) {
        self.scaled_bounded(magnitude.clamp(-MAX_SCALED, MAX_SCALED))
    }

    /// [`Dir::scaled`] for a caller that has bounded the magnitude within
    /// ±[`MAX_SCALED`]: no clamp. Every caller in the crate has (each says
    /// how); on the AVR the clamp is two 32-bit compares per call.
    pub(crate) fn scaled_bounded(self, magnitude: i32) -> (i32, i32) {
        (
            mul_q14(self.cos(), magnitude),
            mul_q14(self.sin(), magnitude),
        )
    }
}

impl core::ops::Neg for Dir {
    type Output = Dir;

    /// The opposite direction.
    fn neg(self) -> Dir {
        Dir {
            c: -self.c,
            s: -self.s,
        }
    }
}

/// Largest magnitude [`Dir::scaled`] accepts (`2^17 − 1`).
pub const MAX_SCALED: i32 = (1 << 17) - 1;

/// `lo ≤ v ≤ hi` (`RangeInclusive::contains` is not a `const fn`).
pub(crate) const fn in_range(v: i32, lo: i32, hi: i32) -> bool {
    lo <= v && v <= hi
}

/// `a · b` where one of them is Q14, rounded; `|a · b| < 2^31`.
pub const fn mul_q14(a: i32, b: i32) -> i32 {
    (a * b + (1 << 13)) >> 14
}

/// `a · b` as 32 bits from 16-bit operands: the types state the operands'
/// range. (On the AVR it costs a full 32-bit multiply all the same: LLVM
/// widens it to libgcc's `__mulsi3`.)
#[inline]
pub const fn mul16(a: i16, b: i16) -> i32 {
    a as i32 * b as i32
}

/// Whether `a` and `b` are less than `r_mm` apart: exactly
/// `a.distance_mm(b) < r_mm`, by a bounding-box test and squared lengths
/// (no square root).
pub fn within(a: Point, b: Point, r_mm: u16) -> bool {
    // Most pairs fail the box test, one unsigned compare per axis (the
    // escape runs it over its whole trail every cycle).
    if !box_within(a, b, r_mm) {
        return false;
    }
    // |dx|, |dy| < r ≤ 65,535: squares as u32 (16 × 16 bits); their sum
    // saturates, and a saturated sum exceeds any r².
    let (dx, dy) = a.to(b);
    let (ux, uy) = (dx.unsigned_abs(), dy.unsigned_abs());
    let r = r_mm as u32;
    (ux * ux).saturating_add(uy * uy) < r * r
}

/// Whether `a` and `b` are less than `r_mm` apart on each axis (Chebyshev
/// distance below `r_mm`): the memory's merge test.
pub fn box_within(a: Point, b: Point, r_mm: u16) -> bool {
    // |d| < r per axis in 16 bits (`abs_diff` of two i16 is exact in a
    // u16; the memory and the escape run it over every point they hold,
    // every cycle, and the AVR does 16 bits in half the work of 32).
    a.x.abs_diff(b.x) < r_mm && a.y.abs_diff(b.y) < r_mm
}

/// A point of the world in millimetres (world frame, x right, y up).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Point {
    /// x in mm.
    pub x: i16,
    /// y in mm.
    pub y: i16,
}

impl Point {
    /// A point from millimetres.
    pub const fn new(x: i16, y: i16) -> Point {
        Point { x, y }
    }

    /// A point from 32-bit millimetres, saturating to the `i16` range.
    pub fn saturating(x: i32, y: i32) -> Point {
        Point {
            x: sat_i16(x),
            y: sat_i16(y),
        }
    }

    /// `other − self` as 32-bit millimetres (never overflows).
    pub fn to(self, other: Point) -> (i32, i32) {
        (
            other.x as i32 - self.x as i32,
            other.y as i32 - self.y as i32,
        )
    }

    /// Distance to `other` in mm, saturating at `u16::MAX`.
    pub fn distance_mm(self, other: Point) -> u16 {
        let (dx, dy) = self.to(other);
        hypot(dx, dy)
    }

    /// The point `distance_mm` away along `dir`.
    pub fn offset(self, dir: Angle, distance_mm: u16) -> Point {
        self.offset_dir(Dir::of(dir), distance_mm)
    }

    /// The point `distance_mm` away along the unit vector `dir`.
    pub fn offset_dir(self, dir: Dir, distance_mm: u16) -> Point {
        // A `u16` is within `MAX_SCALED`.
        let (dx, dy) = dir.scaled_bounded(distance_mm as i32);
        Point::saturating(self.x as i32 + dx, self.y as i32 + dy)
    }
}

/// Saturating conversion to `i16`.
#[cfg_attr(target_arch = "avr", inline(never))]
pub fn sat_i16(v: i32) -> i16 {
    v.clamp(i16::MIN as i32, i16::MAX as i32) as i16
}

/// Saturating conversion to `u16`.
pub fn sat_u16(v: i32) -> u16 {
    v.clamp(0, u16::MAX as i32) as u16
}

/// Integer square root, `floor(√v)`.
///
/// Two algorithms with the same result, chosen per target: bit by bit on
/// the AVR (no division: Newton's three or four would cost ~400 cycles each
/// there, `avr_costs`), Newton's iteration
/// elsewhere (a Cortex-M4 divides in a few cycles, and three or four steps
/// from a power-of-two start replace sixteen).
pub fn isqrt(v: u32) -> u16 {
    // Below 2^16 (the free-distance rule's half chords, always) the same
    // steps in 16 bits: on the AVR half the instructions.
    #[cfg(target_arch = "avr")]
    return match u16::try_from(v) {
        Ok(v) => isqrt_bitwise16(v) as u16,
        Err(_) => isqrt_bitwise(v),
    };
    #[cfg(not(target_arch = "avr"))]
    return isqrt_newton(v);
}

/// `floor(√v)` bit by bit, shifts and subtractions only, in the width of
/// `$t` (`$root` holds the root). One text for both widths: a generic
/// function over the operator traits gives slower AVR code.
macro_rules! isqrt_bitwise {
    ($(#[$doc:meta])* $name:ident, $t:ty, $root:ty, $start:expr) => {
        $(#[$doc])*
        #[cfg_attr(not(any(test, target_arch = "avr")), allow(dead_code))]
        fn $name(v: $t) -> $root {
            if v == 0 {
                return 0;
            }
            let mut rem = v;
            let mut root: $t = 0;
            let mut bit: $t = $start(v);
            if bit >> 8 > v {
                bit >>= 8;
            }
            while bit > v {
                bit >>= 2;
            }
            while bit != 0 {
                if rem >= root + bit {
                    rem -= root + bit;
                    root = (root >> 1) + bit;
                } else {
                    root >>= 1;
                }
                bit >>= 2;
            }
            root as $root
        }
    };
}

isqrt_bitwise!(
    /// `floor(√v)` bit by bit. The start is the highest even power of two
    /// not above v, found by halves and a byte, then two bits at a time
    /// (`1 << leading_zeros(..)` would be a call and a shift loop of up to
    /// 30 turns on the AVR).
    isqrt_bitwise,
    u32,
    u16,
    |v: u32| if v >= 1 << 16 { 1 << 30 } else { 1 << 14 }
);
isqrt_bitwise!(
    /// [`isqrt_bitwise`] for `v` below 2^16, in 16 bits.
    isqrt_bitwise16,
    u16,
    u8,
    |_| 1 << 14
);

/// `floor(√v)` by Newton's iteration from above `√v`, from where it
/// decreases monotonically to the floor.
#[cfg_attr(target_arch = "avr", allow(dead_code))]
fn isqrt_newton(v: u32) -> u16 {
    if v == 0 {
        return 0;
    }
    // Start one Newton step from 2^h, h = ⌊bits/2⌋: `(2^h + v/2^h) / 2`
    // by shifts. It is at least ⌊√v⌋ (so the iteration decreases
    // monotonically to the floor) and at most 1.5·√v, which saves one or
    // two divisions over starting at a power of two.
    let h = (32 - v.leading_zeros()) / 2;
    let mut x: u32 = ((1 << h) + (v >> h)) / 2;
    loop {
        let y = (x + v / x) / 2;
        if y >= x {
            return x as u16;
        }
        x = y;
    }
}

/// `√(dx² + dy²)` in the inputs' unit, saturating at `u16::MAX`.
pub fn hypot(dx: i32, dy: i32) -> u16 {
    let mut ax = dx.unsigned_abs();
    let mut ay = dy.unsigned_abs();
    let mut shift = 0;
    // Each component below 2^15 keeps the sum of squares below 2^31.
    while (ax | ay) >= 1 << 15 {
        ax >>= 1;
        ay >>= 1;
        shift += 1;
    }
    let r = isqrt(ax * ax + ay * ay) as u32;
    let r = r << shift;
    if r > u16::MAX as u32 {
        u16::MAX
    } else {
        r as u16
    }
}

/// A force in the world frame, components in Q10 force units.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Force {
    /// x component, Q10.
    pub x: i32,
    /// y component, Q10.
    pub y: i32,
}

impl Force {
    /// No force.
    pub const ZERO: Force = Force { x: 0, y: 0 };

    /// A force of `magnitude` (Q10) pointing along `dir`.
    pub fn along(dir: Angle, magnitude: i32) -> Force {
        Force::along_dir(Dir::of(dir), magnitude)
    }

    /// Component-wise saturating sum.
    pub fn plus(self, other: Force) -> Force {
        Force {
            x: self.x.saturating_add(other.x),
            y: self.y.saturating_add(other.y),
        }
    }

    /// Component-wise sum for callers that have bounded it below 2^31 (a
    /// plain add: the saturating one costs ~50 cycles a component on the
    /// AVR, in loops over every collision point and virtual obstacle).
    pub fn plus_bounded(self, other: Force) -> Force {
        Force {
            x: self.x.wrapping_add(other.x),
            y: self.y.wrapping_add(other.y),
        }
    }

    /// The sum for callers that have bounded it below 2^31, so that
    /// [`Force::plus`] would not saturate: the same value as either sum,
    /// by the cheaper one on each target. On the AVR the plain add (a
    /// saturating one is ~50 cycles a component); elsewhere the saturating
    /// one, which the Cortex-M4 does in one instruction.
    pub fn plus_unsaturated(self, other: Force) -> Force {
        if cfg!(target_arch = "avr") {
            self.plus_bounded(other)
        } else {
            self.plus(other)
        }
    }

    /// A force of `magnitude` (Q10) pointing along the unit vector `dir`.
    pub fn along_dir(dir: Dir, magnitude: i32) -> Force {
        let (x, y) = dir.scaled(magnitude);
        Force { x, y }
    }

    /// [`Force::along_dir`] for a magnitude the caller has bounded within
    /// ±[`MAX_SCALED`] (see [`Dir::scaled_bounded`]).
    pub(crate) fn along_dir_bounded(dir: Dir, magnitude: i32) -> Force {
        let (x, y) = dir.scaled_bounded(magnitude);
        Force { x, y }
    }

    /// [`Force::along`] for a magnitude the caller has bounded within
    /// ±[`MAX_SCALED`].
    pub(crate) fn along_bounded(dir: Angle, magnitude: i32) -> Force {
        Force::along_dir_bounded(Dir::of(dir), magnitude)
    }

    /// The direction of the force (`atan2`, eq. 17); `None` for a zero force.
    pub fn direction(self) -> Option<Angle> {
        if self.x == 0 && self.y == 0 {
            None
        } else {
            Some(Angle::atan2(self.y, self.x))
        }
    }
}

/// `1 / d²` in Q10 force units, `d` in mm (`d` = 1 m gives 1.0).
///
/// Eq. 10's magnitude `|P_R − P_C| / d³ = 1/d²`. One 32-bit division; `d`
/// below 91 mm (closer than any IR reading can place an obstacle from the
/// robot's centre) is treated as 91 mm, ~124 force units, which keeps the
/// magnitude inside [`MAX_SCALED`].
#[cfg_attr(target_arch = "avr", inline(never))]
pub fn inverse_square_force(d_mm: u16) -> i32 {
    const _: () = assert!(1_024_000_000 / (91 * 91) <= MAX_SCALED);
    let d = d_mm.max(91) as u32;
    // 10^6 mm² · 1024 = 1.024e9 fits in u32.
    (1_024_000_000u32 / (d * d)) as i32
}

/// The rover's pose from odometry.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Pose {
    /// Position, world mm.
    pub position: Point,
    /// Heading, world frame.
    pub heading: Angle,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn from_deg_is_exact_on_quarters() {
        assert_eq!(Angle::from_deg(90), Angle(16_384));
        assert_eq!(Angle::from_deg(-90), Angle(49_152));
        assert_eq!(Angle::from_deg(180), Angle(32_768));
        assert_eq!(Angle::from_deg(360), Angle(0));
        assert_eq!(Angle::from_deg(45).signed(), 8_192);
        assert_eq!(Angle::from_decideg(-400), Angle::from_deg(-40));
    }

    #[test]
    fn sine_matches_f64_everywhere() {
        let mut worst = 0.0f64;
        for a in (0..=u16::MAX).step_by(7) {
            let ang = a as f64 * core::f64::consts::TAU / 65_536.0;
            let s = Angle(a).sin() as f64 / TRIG_ONE as f64;
            let c = Angle(a).cos() as f64 / TRIG_ONE as f64;
            worst = worst.max((s - ang.sin()).abs()).max((c - ang.cos()).abs());
        }
        assert!(worst < 6.0e-4, "sine error {worst}");
        assert_eq!(Angle::ZERO.sin(), 0);
        assert_eq!(Angle::QUARTER.sin(), TRIG_ONE);
        assert_eq!(Angle::HALF.cos(), -TRIG_ONE);
    }

    #[test]
    fn atan2_matches_f64_within_a_tenth_of_a_degree() {
        let mut worst = 0.0f64;
        for i in -60i32..=60 {
            for j in -60i32..=60 {
                for scale in [1, 37, 1_000, 100_000] {
                    let (x, y) = (i * scale, j * scale);
                    if x == 0 && y == 0 {
                        continue;
                    }
                    let got = Angle::atan2(y, x).to_deg_f64();
                    let want = (y as f64).atan2(x as f64).to_degrees();
                    let mut e = (got - want).abs();
                    if e > 180.0 {
                        e = 360.0 - e;
                    }
                    worst = worst.max(e);
                }
            }
        }
        assert!(worst < 0.1, "atan2 error {worst}°");
        assert_eq!(Angle::atan2(0, 0), Angle::ZERO);
        assert_eq!(Angle::atan2(5, 0), Angle::QUARTER);
        assert_eq!(Angle::atan2(0, -5), Angle::HALF);
        assert_eq!(Angle::atan2(i32::MIN, i32::MIN).signed(), -24_576);
    }

    #[test]
    fn both_square_roots_are_the_floor() {
        let check = |v: u32| {
            let r = isqrt_newton(v) as u64;
            assert!(r * r <= v as u64 && (r + 1) * (r + 1) > v as u64, "{v}");
            assert_eq!(isqrt_bitwise(v), r as u16, "{v}");
            if let Ok(v) = u16::try_from(v) {
                assert_eq!(isqrt_bitwise16(v), r as u8, "{v}");
            }
        };
        (0..1 << 20).for_each(check);
        (0..=u16::MAX as u32).for_each(|r| {
            check(r * r);
            check((r * r).wrapping_sub(1));
            check(r * r + 1);
        });
        (0..1_000_000u32).for_each(|k| check(k.wrapping_mul(2_654_435_761)));
        check(u32::MAX);
    }

    #[test]
    fn box_within_is_the_plain_chebyshev_test() {
        let edges = [
            i16::MIN,
            i16::MIN + 1,
            -20_000,
            -1,
            0,
            1,
            59,
            60,
            20_000,
            i16::MAX,
        ];
        for r_mm in [0u16, 1, 60, 150, 40_000, u16::MAX] {
            for u in edges {
                for v in edges {
                    let near = (u as i32 - v as i32).abs() < r_mm as i32;
                    // One axis apart at a time, the other equal.
                    for c in [i16::MIN, 0, i16::MAX] {
                        let along_x = box_within(Point::new(u, c), Point::new(v, c), r_mm);
                        let along_y = box_within(Point::new(c, u), Point::new(c, v), r_mm);
                        assert_eq!((along_x, along_y), (near, near), "{u} {v} {r_mm}");
                    }
                }
            }
        }
    }

    #[test]
    fn isqrt_and_hypot() {
        for v in [0u32, 1, 2, 3, 4, 15, 16, 17, 99_999, 1 << 30, u32::MAX] {
            let r = isqrt(v) as u64;
            assert!(r * r <= v as u64 && (r + 1) * (r + 1) > v as u64, "{v}");
        }
        assert_eq!(hypot(3_000, -4_000), 5_000);
        assert_eq!(hypot(-32_768, 0), 32_768);
        assert_eq!(hypot(i32::MAX, i32::MAX), u16::MAX);
        assert_eq!(Point::new(0, 0).distance_mm(Point::new(300, 400)), 500);
    }

    #[test]
    fn within_is_the_exact_distance_test() {
        let vals = [
            i16::MIN,
            -20_000,
            -151,
            -150,
            -149,
            -1,
            0,
            1,
            99,
            149,
            150,
            151,
            i16::MAX,
        ];
        for &x in &vals {
            for &y in &vals {
                for r in [0u16, 1, 2, 100, 150, 151, 400, 40_000, u16::MAX] {
                    let (a, b) = (Point::new(x / -2, 7), Point::new(x, y));
                    let (dx, dy) = (x as i64 - (x / -2) as i64, y as i64 - 7);
                    let want = dx * dx + dy * dy < r as i64 * r as i64;
                    assert_eq!(within(a, b, r), want, "{x} {y} {r}");
                    assert_eq!(within(b, a, r), want, "{x} {y} {r}");
                }
            }
        }
    }

    #[test]
    fn inverse_square_force_by_hand() {
        // 1 m → 1.0, 0.5 m → 4.0, 0.1 m → 100.0 force units.
        assert_eq!(inverse_square_force(1_000), 1_024);
        assert_eq!(inverse_square_force(500), 4_096);
        assert_eq!(inverse_square_force(100), 102_400);
        assert_eq!(inverse_square_force(0), inverse_square_force(91));
        assert!(inverse_square_force(0) <= MAX_SCALED);
    }

    #[test]
    fn point_offset_and_saturation() {
        let p = Point::new(1_000, 1_000).offset(Angle::from_deg(90), 500);
        assert_eq!(p, Point::new(1_000, 1_500));
        assert_eq!(
            Point::saturating(40_000, -40_000),
            Point::new(32_767, -32_768)
        );
    }
}
