//! # planner-float
//!
//! The EAPF planner step of `planner-core`, written again from the equations
//! (docs/algorithms.md §2 and the choices documented in planner-core) in floating
//! point, generic over `f32` and `f64`. Two uses:
//!
//! - `f64`: the reference that bounds planner-core's fixed-point error
//!   (`planner-core/tests/float_reference.rs`). It reports how close each
//!   discrete decision came to its threshold ([`FloatPlanner::margin`]), so
//!   that cases where 1 mm of rounding may flip a decision can be set aside.
//! - `f32`: what a "naive" floating-point port of the same step costs on the
//!   ATmega328P (software float, `libm`), measured by the firmware's
//!   `f32-step` bench.
//!
//! It covers the EAPF step (sensors, collision points, memory, forces,
//! motion classes, heading, step and the safety rule), not the escape, with
//! the sensors on the rim or set back from it (the configuration's offset,
//! and with them set back the view's points near the rim kept and kept off,
//! as planner-core's `ConfigBuilder::sensors_set_back` does).
//!
//! Crates: `num-traits` (with `libm`) for one `Float` bound over both widths
//! without `std`; `heapless` for the bounded memory.
#![no_std]
#![forbid(unsafe_code)]
#![warn(missing_docs)]
// The equations index sensors the way the paper does (i = 0..5).
#![allow(clippy::needless_range_loop)]

use num_traits::{Float, FloatConst};
use planner_core::{Config, Status, SENSOR_COUNT};

/// A reading in floating point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum R<F> {
    /// An obstacle this far from the sensor face, mm.
    Range(F),
    /// Nothing in range.
    Clear,
    /// Nearer than the table trusts.
    TooClose,
    /// Impossible count.
    Implausible,
}

/// Robot radius, mm (planner-core's default configuration).
pub const RADIUS: f64 = 100.0;
/// Sensor face offset from the centre, mm, of the default configuration
/// (the sensors on the rim); [`FloatPlanner::step`] takes the
/// configuration's.
pub const OFFSET: f64 = 100.0;
/// Sensor range, mm.
pub const RANGE: f64 = 800.0;
/// Clearance added to the radius, mm.
pub const CLEARANCE: f64 = 40.0;
/// Stand-off kept ahead of the rim, mm.
pub const STANDOFF: f64 = 100.0;
/// With the sensors set back, a view's point within this of the rim is kept
/// as a flank point, mm.
pub const NEAR: f64 = 100.0;
/// Flank points kept.
pub const FLANK_POINTS: usize = 4;
/// A flank point within this (either axis) of a kept one replaces it, mm.
pub const FLANK_MERGE: f64 = 40.0;
/// Goal tolerance, mm.
pub const TOL_GOAL: f64 = 50.0;
/// Shortest step, mm.
pub const MIN_STEP: f64 = 10.0;
/// Sensor angles, degrees.
pub const ANGLES: [f64; 5] = [-40.0, -20.0, 0.0, 20.0, 40.0];

fn c<F: Float>(v: f64) -> F {
    F::from(v).unwrap_or_else(F::zero)
}

/// Wrap an angle into [−π, π).
pub fn wrap<F: Float + FloatConst>(a: F) -> F {
    let tau = F::TAU();
    a - tau * ((a + F::PI()) / tau).floor()
}

/// Where the transcendental functions come from: [`Libm`] (the `libm`
/// crate, through num-traits) by default; a firmware can supply its C
/// library's (the AVR bench uses avr-libc's, as an Arduino sketch would).
pub trait Math<F> {
    /// sin x.
    fn sin(x: F) -> F;
    /// cos x.
    fn cos(x: F) -> F;
    /// atan2(y, x).
    fn atan2(y: F, x: F) -> F;
    /// √(x² + y²).
    fn hypot(x: F, y: F) -> F;
    /// √x.
    fn sqrt(x: F) -> F;
}

/// The `libm` crate's functions.
pub struct Libm;

impl<F: Float> Math<F> for Libm {
    fn sin(x: F) -> F {
        x.sin()
    }
    fn cos(x: F) -> F {
        x.cos()
    }
    fn atan2(y: F, x: F) -> F {
        y.atan2(x)
    }
    fn hypot(x: F, y: F) -> F {
        x.hypot(y)
    }
    fn sqrt(x: F) -> F {
        x.sqrt()
    }
}

/// The float planner's state.
pub struct FloatPlanner<F, M = Libm> {
    math: core::marker::PhantomData<M>,
    goal: (F, F),
    memory: heapless::Vec<((F, F), u8), 16>,
    following: bool,
    turn_side: i8,
    spun: bool,
    paper_step: F,
    last_mm: [F; SENSOR_COUNT],
    /// With the sensors set back: the points the view read within [`NEAR`]
    /// of the rim (world mm), as the fixed planner's flank keeps them.
    flank: heapless::Vec<(F, F), FLANK_POINTS>,
    track: bool,
    /// Smallest distance of any discrete decision from its threshold since
    /// it was last reset (only when built with `tracking`).
    pub margin: F,
}

impl<F: Float + FloatConst, M: Math<F>> FloatPlanner<F, M> {
    /// A planner heading for `goal` (mm); `tracking` turns the decision
    /// margins on (the reference needs them, a benchmark does not).
    pub fn new(goal: (F, F), tracking: bool) -> Self {
        FloatPlanner {
            math: core::marker::PhantomData,
            goal,
            memory: heapless::Vec::new(),
            following: false,
            turn_side: 0,
            spun: false,
            paper_step: c(RANGE),
            last_mm: [F::zero(); SENSOR_COUNT],
            flank: heapless::Vec::new(),
            track: tracking,
            margin: F::infinity(),
        }
    }

    fn near(&mut self, v: F, threshold: F) {
        if self.track {
            self.margin = self.margin.min((v - threshold).abs());
        }
    }

    /// A sensor's reading of `raw`, interpolating the same calibration
    /// bins as the fixed planner.
    pub fn reading(cfg: &Config, raw: u16) -> R<F> {
        let cal = cfg.calibration();
        let (far, near) = cal.window();
        if raw > cal.full_scale() {
            return R::Implausible;
        }
        if raw > near {
            return R::TooClose;
        }
        if raw < cal.floor_count() {
            return R::Implausible;
        }
        if raw < far {
            return R::Clear;
        }
        let w = 1u32 << cal.shift();
        let k = (raw as u32 / w) as usize;
        let int = int_f::<F>;
        let f: F = int(raw as u32 % w) / int(w);
        let mut bins = cal.bins().skip(k);
        let d0 = bins.next().map_or(0, |b| b.1 as u32);
        let d1 = bins.next().map_or(d0, |b| b.1 as u32);
        R::Range(int(d0) + f * (int(d1) - int(d0)))
    }

    /// One cycle at pose (`x`, `y` mm, `h` rad) with raw counts: (heading
    /// rad, step mm, status).
    pub fn step(&mut self, cfg: &Config, x: F, y: F, h: F, raw: &[u16; 5]) -> (F, F, Status) {
        let mut rd = [R::Clear; 5];
        for (r, &c) in rd.iter_mut().zip(raw) {
            *r = Self::reading(cfg, c);
        }
        let (n150, big) = (c::<F>(150.0), c::<F>(65_535.0));
        // Fold-back filter.
        for i in 0..5 {
            let now = match rd[i] {
                R::Range(mm) => mm,
                R::Clear => big,
                _ => F::zero(),
            };
            let last = self.last_mm[i];
            if last != F::zero() {
                self.near(last, n150);
            }
            let two = c::<F>(2.0);
            if last != F::zero() && last <= n150 {
                self.near(now, two * last);
            }
            let suspect = last != F::zero() && last <= n150 && now > two * last;
            self.last_mm[i] = if now == F::zero() { F::one() } else { now };
            if suspect {
                rd[i] = R::TooClose;
            }
        }
        if rd.contains(&R::Implausible) {
            return (h, F::zero(), Status::SensorFault);
        }
        let (gx, gy) = (self.goal.0 - x, self.goal.1 - y);
        let gd = M::hypot(gx, gy);
        self.near(gd, c(TOL_GOAL));
        if gd <= c(TOL_GOAL) {
            return (h, F::zero(), Status::Arrived);
        }
        let bearing = M::atan2(gy, gx);
        self.near(gd, c(RANGE));
        let near = gd < c(RANGE);
        let radius = c::<F>(RADIUS);
        let offset = int_f::<F>(cfg.sensor_offset_mm() as u32);
        let set_back = cfg.sensors_set_back();
        if set_back {
            self.saw_near(x, y, h, &rd, offset);
        }
        let rs = radius + c(CLEARANCE);
        // Collision points (eqs. 7, 8).
        let mut pts: heapless::Vec<(usize, F), 5> = heapless::Vec::new();
        for i in 0..5 {
            let d = match rd[i] {
                R::Range(mm) => offset + mm,
                R::TooClose => offset,
                _ => continue,
            };
            let a = c::<F>(ANGLES[i]).to_radians();
            let lat = d * M::sin(a).abs();
            let fwd = d * M::cos(a);
            self.near(lat, rs);
            self.near(fwd, self.paper_step);
            if lat <= rs && fwd <= self.paper_step {
                let _ = pts.push((i, d));
            }
        }
        // Memory (eqs. 11-13).
        let hd = wrap(h).to_degrees();
        let n90 = c::<F>(90.0);
        let within = hd - n90 * (hd / n90).floor();
        let (n45, n5) = (c::<F>(45.0), c::<F>(5.0));
        self.near((within - n45).abs(), n5);
        let class = if (within - n45).abs() <= n5 {
            2
        } else if M::cos(h).abs() > M::sin(h).abs() {
            0
        } else {
            1
        };
        let between = |v: F, a: F, b: F| v >= a.min(b) && v <= a.max(b);
        let n60 = c::<F>(60.0);
        // Only the nearest point of the cycle goes to the memory.
        let mut nearest: Option<(usize, F)> = None;
        for &(i, d) in pts.iter() {
            if let Some((_, best)) = nearest {
                self.near(d, best);
            }
            if nearest.is_none_or(|(_, best)| d < best) {
                nearest = Some((i, d));
            }
        }
        if let Some((i, d)) = nearest {
            let a = h + c::<F>(ANGLES[i]).to_radians();
            let p = (x + d * M::cos(a), y + d * M::sin(a));
            let (ix, iy) = (between(p.0, x, self.goal.0), between(p.1, y, self.goal.1));
            self.near(p.0, x);
            self.near(p.0, self.goal.0);
            self.near(p.1, y);
            self.near(p.1, self.goal.1);
            let active = match class {
                0 => ix,
                1 => iy,
                _ => ix && iy,
            };
            let dup = self
                .memory
                .iter()
                .any(|(q, k)| *k == class && (q.0 - p.0).abs() < n60 && (q.1 - p.1).abs() < n60);
            if self.track {
                let mut m = F::infinity();
                for (q, k) in self.memory.iter() {
                    if *k == class {
                        m = m
                            .min(((q.0 - p.0).abs() - n60).abs())
                            .min(((q.1 - p.1).abs() - n60).abs());
                    }
                }
                self.margin = self.margin.min(m);
            }
            if active && !dup {
                if self.memory.is_full() {
                    self.memory.remove(0);
                }
                let _ = self.memory.push((p, class));
            }
        }
        // Motion class.
        let delta = wrap(h - bearing).to_degrees();
        self.near(delta.abs(), n5);
        // Heading straight away from the goal: CW and CCW meet at ±180°.
        self.near(delta.abs(), c(180.0));
        let motion = if delta.abs() <= n5 {
            0
        } else if delta > F::zero() {
            1
        } else {
            2
        };
        if motion == 0 {
            self.following = false;
        } else if !pts.is_empty() {
            self.following = true;
        }
        // Forces (eq. 16).
        let two = c::<F>(2.0);
        let mut f = (two * M::cos(bearing), two * M::sin(bearing));
        let (n91, million) = (c::<F>(91.0), c::<F>(1e6));
        for &(i, d) in pts.iter() {
            let a = h + c::<F>(ANGLES[i]).to_radians() + F::PI();
            let m = million / (d.max(n91) * d.max(n91));
            f.0 = f.0 + m * M::cos(a);
            f.1 = f.1 + m * M::sin(a);
        }
        if !near {
            let (mut sx, mut sy, mut n) = (F::zero(), F::zero(), 0);
            if self.track {
                let mut m = F::infinity();
                for (q, _) in self.memory.iter() {
                    m = m.min((q.0 - x).abs()).min((q.0 - self.goal.0).abs());
                    m = m.min((q.1 - y).abs()).min((q.1 - self.goal.1).abs());
                }
                self.margin = self.margin.min(m);
            }
            for (q, k) in self.memory.iter() {
                let (ix, iy) = (between(q.0, x, self.goal.0), between(q.1, y, self.goal.1));
                let act = match k {
                    0 => ix,
                    1 => iy,
                    _ => ix && iy,
                };
                if act {
                    sx = sx + x - q.0;
                    sy = sy + y - q.1;
                    n += 1;
                }
            }
            if n > 0 {
                // The direction of Σ(P_R − P_i) is ill-conditioned when the
                // points surround the rover: 1 mm moves it far.
                self.near(M::hypot(sx, sy) / c(10.0), F::zero());
            }
            if n > 0 && (sx != F::zero() || sy != F::zero()) {
                let a = M::atan2(sy, sx);
                f.0 = f.0 + M::cos(a);
                f.1 = f.1 + M::sin(a);
            }
            if self.following {
                let group: &[usize] = match motion {
                    1 => &[0, 1],
                    2 => &[3, 4],
                    _ => &[],
                };
                for &i in group {
                    if rd[i] == R::Clear {
                        let a = h + c::<F>(ANGLES[i]).to_radians();
                        f.0 = f.0 + M::cos(a);
                        f.1 = f.1 + M::sin(a);
                    }
                }
            }
        }
        self.near(M::hypot(f.0, f.1), F::zero());
        let mut heading = if f.0 == F::zero() && f.1 == F::zero() {
            bearing
        } else {
            M::atan2(f.1, f.0)
        };
        let mut farthest: Option<F> = None;
        for &(_, d) in pts.iter() {
            let d = d - offset;
            farthest = Some(farthest.map_or(d, |m| m.max(d)));
        }
        // The fixed planner keeps the paper step in whole mm.
        self.paper_step = match farthest {
            None => c(RANGE),
            Some(d) => (d + two * radius).round(),
        };
        let half = c::<F>(40.0).to_radians();
        let mut rel = wrap(heading - h);
        self.near(rel.abs().to_degrees(), c(40.0));
        if !pts.is_empty() && rel.abs() > half {
            // Which edge: a force straight behind is a decision boundary.
            self.near(rel.abs().to_degrees(), c(180.0));
            // Beyond ±120° the side turned last is kept (the rover turns round).
            self.near(rel.abs().to_degrees(), c(120.0));
            let mut left = rel >= F::zero();
            if rel.abs() > c::<F>(120.0).to_radians() && self.turn_side != 0 {
                left = self.turn_side > 0;
            }
            self.turn_side = if left { 1 } else { -1 };
            rel = if left { half } else { -half };
            heading = h + rel;
        } else {
            self.turn_side = 0;
        }
        let mut step = if rel.abs() > half {
            F::zero()
        } else {
            let (free, margin) = free_margin::<F, M>(&rd, rel, offset);
            self.near(margin, F::zero());
            let free = if set_back {
                self.flank_free(x, y, h + rel, free)
            } else {
                free
            };
            self.paper_step.min(free)
        };
        if near {
            step = step.min(gd);
        }
        self.near(step, c(MIN_STEP));
        if step < c(MIN_STEP) {
            step = F::zero();
        }
        // Two turns on the spot in a row with nothing in sight: advance
        // along the heading faced instead.
        let spin = step == F::zero() && pts.is_empty() && rel.abs() > half;
        if spin && self.spun {
            heading = h;
            let (free, margin) = free_margin::<F, M>(&rd, F::zero(), offset);
            self.near(margin, F::zero());
            let free = if set_back {
                self.flank_free(x, y, h, free)
            } else {
                free
            };
            step = (self.paper_step.min(free) / c(2.0)).floor();
            self.near(step, c(MIN_STEP));
            if step < c(MIN_STEP) {
                step = F::zero();
            }
        }
        self.spun = spin && step == F::zero();
        (wrap(heading), step, Status::Moving)
    }
}

impl<F: Float + FloatConst, M: Math<F>> FloatPlanner<F, M> {
    /// With the sensors set back: keep what the view from (`x`, `y`) facing
    /// `h` reads within [`NEAR`] of the rim (faces `offset` from the
    /// centre). A point near a kept one replaces it; all places taken, the
    /// kept point farthest from the rover (either axis) goes if the new one
    /// is nearer.
    fn saw_near(&mut self, x: F, y: F, h: F, rd: &[R<F>; 5], offset: F) {
        let near = c::<F>(RADIUS + NEAR);
        let merge = c::<F>(FLANK_MERGE);
        for (i, r) in rd.iter().enumerate() {
            let R::Range(mm) = *r else { continue };
            let e = offset + mm;
            self.near(e, near);
            if e > near {
                continue;
            }
            let a = h + c::<F>(ANGLES[i]).to_radians();
            let p = (x + e * M::cos(a), y + e * M::sin(a));
            let mut merged = false;
            for k in 0..self.flank.len() {
                let q = self.flank[k];
                let (dx, dy) = ((q.0 - p.0).abs(), (q.1 - p.1).abs());
                self.near(dx, merge);
                self.near(dy, merge);
                if dx < merge && dy < merge {
                    self.flank[k] = p;
                    merged = true;
                    break;
                }
            }
            if merged || self.flank.push(p).is_ok() {
                continue;
            }
            let far = |q: &(F, F)| (q.0 - x).abs().max((q.1 - y).abs());
            let mut k = 0;
            for j in 1..self.flank.len() {
                if far(&self.flank[j]) > far(&self.flank[k]) {
                    k = j;
                }
            }
            self.near(far(&p), far(&self.flank[k]));
            if far(&p) < far(&self.flank[k]) {
                self.flank[k] = p;
            }
        }
    }

    /// `free` along world heading `h` from (`x`, `y`), and the disc with the
    /// clearance kept off the flank points.
    fn flank_free(&mut self, x: F, y: F, h: F, mut free: F) -> F {
        let rb = c::<F>(RADIUS + CLEARANCE);
        let (cos, sin) = (M::cos(h), M::sin(h));
        for i in 0..self.flank.len() {
            let (px, py) = (self.flank[i].0 - x, self.flank[i].1 - y);
            let along = px * cos + py * sin;
            let lat = py * cos - px * sin;
            self.near(along, F::zero());
            self.near(lat.abs(), rb);
            if along > F::zero() && lat.abs() < rb {
                free = free.min((along - M::sqrt(rb * rb - lat * lat)).max(F::zero()));
            }
        }
        free
    }
}

/// An integer as `F` (no f64 on the way: the f32 build must not pull in
/// double-precision routines).
fn int_f<F: Float>(v: u32) -> F {
    F::from(v).unwrap_or_else(F::zero)
}

/// The safety rule in float: how far the disc may go along `rel`, the
/// sensor faces `offset` mm from the centre.
pub fn free<F: Float + FloatConst, M: Math<F>>(rd: &[R<F>; 5], rel: F, offset: F) -> F {
    free_margin::<F, M>(rd, rel, offset).0
}

/// [`free`], and how near (mm) a beam's end came to the edge of the
/// corridor (a decision boundary: just inside it blocks, just outside not).
pub fn free_margin<F: Float + FloatConst, M: Math<F>>(rd: &[R<F>; 5], rel: F, offset: F) -> (F, F) {
    let rs = c::<F>(RADIUS + CLEARANCE);
    let reach = offset + c(RANGE);
    let mut free = reach - rs;
    let mut margin = F::infinity();
    for i in 0..5 {
        let (e, obstacle) = match rd[i] {
            R::Range(mm) => (offset + mm, true),
            R::Clear => (reach, false),
            _ => (offset, true),
        };
        let a = c::<F>(ANGLES[i]).to_radians() - rel;
        let (along, lat) = (e * M::cos(a), e * M::sin(a));
        if obstacle {
            margin = margin.min((lat.abs() - rs).abs());
        }
        if lat.abs() < rs {
            let mut limit = along - M::sqrt(rs * rs - lat * lat);
            if obstacle {
                limit = limit.min(along - c(RADIUS + STANDOFF));
            }
            free = free.min(limit.max(F::zero()));
        }
    }
    (free, margin)
}
