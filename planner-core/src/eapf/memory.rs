//! Remembered collision points for the midpoint repulsive force (paper
//! §5.4, eqs. 11–13), in bounded memory.
//!
//! Each collision point is classified when it is detected from the robot's
//! direction θr: moving mainly along x (`|cos θr| > |sin θr|`, the paper's
//! eq. 11 read as magnitudes, see docs/algorithms.md §2) makes it an X-point if
//! its x lies between the robot's and the target's x; mainly along y makes it
//! a Y-point likewise; within the diagonal tolerance of 45° makes it an
//! XY-point if both hold. A point outside its range is not remembered (the
//! paper's "ignored point"). A point stays *active* only while it is still
//! inside its range; the midpoint `P_M` is the mean of the active points.
//!
//! Capacity and eviction: at most [`MEMORY_CAPACITY`] points. A new point
//! within [`MERGE_MM`] of a remembered one of the same class is not stored
//! again (a wall seen on consecutive cycles would otherwise fill the memory
//! with near-copies). When the memory is full the *oldest* point is
//! evicted: the most recent obstacles are the ones the robot is dealing
//! with.
//!
//! Ours: the planner gives the memory one point a cycle, the nearest of the
//! cycle's collision points (the paper stores every one). That bounds a
//! cycle's work to one store, whatever the five beams see, and spreads the
//! slots over the last [`MEMORY_CAPACITY`] distinct obstacles met rather
//! than the last few cycles along one wall (see the commit history, "One point
//! a cycle", for what it changed).

use crate::fixed::{box_within, Angle, Point};
use crate::ring::Ring;

/// Most remembered collision points.
pub const MEMORY_CAPACITY: usize = 16;

/// Points closer than this (Chebyshev distance, mm) to a remembered point of
/// the same class are merged into it.
pub const MERGE_MM: u16 = 60;

/// Whether two points are nearer than [`MERGE_MM`] on both axes.
fn near(a: Point, b: Point) -> bool {
    box_within(a, b, MERGE_MM)
}

/// The class of a remembered point (eqs. 11–13).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum PointClass {
    /// Detected while moving mainly along x; active while between robot and target in x.
    X = 0b01,
    /// Detected while moving mainly along y; active while between robot and target in y.
    Y = 0b10,
    /// Detected while moving diagonally; active while between them in x and y.
    XY = 0b11,
}

/// A remembered collision point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Remembered {
    /// Where, in world mm.
    pub point: Point,
    /// Its class.
    pub class: PointClass,
}

/// The box spanned by the robot and the target, for the activity test of
/// every remembered point in one cycle (computed once, not per point).
#[derive(Clone, Copy, Debug)]
struct Span {
    x_lo: i16,
    x_len: u16,
    y_lo: i16,
    y_len: u16,
}

impl Span {
    fn new(robot: Point, target: Point) -> Span {
        Span {
            x_lo: robot.x.min(target.x),
            x_len: robot.x.abs_diff(target.x),
            y_lo: robot.y.min(target.y),
            y_len: robot.y.abs_diff(target.y),
        }
    }

    /// Whether `p` lies inside on x, on y. One unsigned compare per axis
    /// in 16 bits (half the AVR's work of 32): below `lo`, the difference
    /// wraps above the span, since `lo + len` ≤ `i16::MAX` and a point is
    /// ≥ `i16::MIN`, so `p − lo + 2^16` > `len`.
    #[inline(always)]
    fn axes(&self, p: Point) -> (bool, bool) {
        (
            p.x.wrapping_sub(self.x_lo) as u16 <= self.x_len,
            p.y.wrapping_sub(self.y_lo) as u16 <= self.y_len,
        )
    }

    /// Whether `p`'s class finds it between robot and target. Always
    /// inlined, as `axes` is: at opt-level `z` the AVR would call it for
    /// every point of every scan.
    #[inline(always)]
    fn holds(&self, p: &Remembered) -> bool {
        let (in_x, in_y) = self.axes(p.point);
        // The class's discriminant has one bit per axis it must lie
        // between: it holds when no needed bit is missing.
        let inside = in_x as u8 | (in_y as u8) << 1;
        p.class as u8 & !inside == 0
    }
}

impl Remembered {
    /// Whether the point counts for the midpoint force with the robot at
    /// `robot` and the target at `target`.
    pub fn is_active(&self, robot: Point, target: Point) -> bool {
        Span::new(robot, target).holds(self)
    }
}

/// The direction class of a robot heading: eq. 11 (X), 12 (Y) or 13 (XY).
pub fn direction_class(heading: Angle, diagonal_tolerance: Angle) -> PointClass {
    // Distance of the heading from the nearest diagonal (45° + k·90°).
    let within_quarter = heading.0 & 0x3FFF; // 0 ..< 90°
    let from_diagonal = (within_quarter as i32 - 8_192).unsigned_abs();
    if from_diagonal <= diagonal_tolerance.0 as u32 {
        return PointClass::XY;
    }
    // |cos| > |sin| ⇔ the heading is within 45° of the x axis.
    let folded = heading.0.wrapping_add(8_192) & 0x7FFF; // 0 ..< 180°, x axis near 8192
    if folded < 16_384 {
        PointClass::X
    } else {
        PointClass::Y
    }
}

/// The active points' count and coordinate sums for one robot position and
/// target: what the midpoint force needs (eq. 13).
#[derive(Clone, Copy, Debug)]
struct ActiveSums {
    robot: Point,
    target: Point,
    n: u8,
    sx: i32,
    sy: i32,
}

impl ActiveSums {
    /// Count one more active point.
    fn add(&mut self, p: Point) {
        self.n = self.n.wrapping_add(1);
        self.sx += p.x as i32;
        self.sy += p.y as i32;
    }

    /// `(n, Σ(P_R − P_i))` = `(n, n·P_R − ΣP_i)`.
    fn away_from(&self, robot: Point) -> (u8, i32, i32) {
        let k = self.n as i32;
        (
            self.n,
            k * robot.x as i32 - self.sx,
            k * robot.y as i32 - self.sy,
        )
    }

    /// Count one active point less.
    fn remove(&mut self, p: Point) {
        self.n = self.n.wrapping_sub(1);
        self.sx -= p.x as i32;
        self.sy -= p.y as i32;
    }
}

/// The bounded memory of collision points: a [`Ring`], so that the scans
/// that run every cycle (merging, the midpoint) are single tight loops.
///
/// It also keeps the midpoint's sums for the robot position and target of
/// the last cycle that stored a point or asked for the midpoint, updated as
/// points come and go. While the rover turns in place, facing a wall and
/// storing what its beams sweep over, the midpoint then costs no scan of
/// the memory.
#[derive(Clone, Debug, Default)]
pub struct Memory {
    points: Ring<Remembered, MEMORY_CAPACITY>,
    sums: Option<ActiveSums>,
}

impl Memory {
    /// An empty memory.
    pub const fn new() -> Self {
        Memory {
            points: Ring::new(),
            sums: None,
        }
    }

    /// The active points' sums: the kept ones if they are for this robot
    /// position and target, else by a scan.
    fn sums_at(&self, robot: Point, target: Point) -> ActiveSums {
        match self.sums {
            Some(s) if s.robot == robot && s.target == target => s,
            _ => self.scan_sums(robot, target),
        }
    }

    /// Make the kept sums those for this robot position and target (a scan
    /// if they are not), in place: the sums are 17 bytes, and on the AVR
    /// each copy of them is a `memcpy` call. Not inlined: the AVR calls it
    /// either way, and inlined into `remember` it lengthens the STM32's
    /// worst step.
    #[inline(never)]
    fn keep_sums_at(&mut self, robot: Point, target: Point) {
        if !matches!(&self.sums, Some(s) if s.robot == robot && s.target == target) {
            self.sums = Some(self.scan_sums(robot, target));
        }
    }

    /// The active points' sums by one scan of the memory. The count rides
    /// in the x sum's top bits (a point adds `2^24 + x`; at most
    /// [`MEMORY_CAPACITY`] points of |x| ≤ 2^15 keep Σx within ±2^19), so
    /// the loop carries two sums, not three: on the STM32 they then stay in
    /// registers (`cargo xtask stm32-profile`: 7 instructions a held point
    /// with three, the sums spilled).
    fn scan_sums(&self, robot: Point, target: Point) -> ActiveSums {
        const ONE: i32 = 1 << 24;
        const _: () = assert!(MEMORY_CAPACITY < 64);
        let span = Span::new(robot, target);
        let (mut sx, mut sy) = (0i32, 0i32);
        for p in self.points.as_slice() {
            if span.holds(p) {
                sx += ONE + p.point.x as i32;
                sy += p.point.y as i32;
            }
        }
        let n = (sx + ONE / 2) >> 24;
        ActiveSums {
            robot,
            target,
            n: n as u8,
            sx: sx - n * ONE,
            sy,
        }
    }

    /// Classify and remember a collision point detected with the robot at
    /// `robot` heading `heading`, target `target`. Returns whether it was
    /// stored (it may be ignored, or merged into a near one).
    ///
    /// One scan of the memory for a merge, and one more for the midpoint's
    /// sums when the robot has moved since they were kept (the midpoint
    /// needs that scan this cycle anyway).
    ///
    /// Out of line on the AVR (docs/performance.md, "Inlining on the AVR").
    #[cfg_attr(target_arch = "avr", inline(never))]
    pub fn remember(
        &mut self,
        point: Point,
        robot: Point,
        heading: Angle,
        target: Point,
        diagonal_tolerance: Angle,
    ) -> bool {
        let new = Remembered {
            point,
            class: direction_class(heading, diagonal_tolerance),
        };
        let span = Span::new(robot, target);
        if !span.holds(&new)
            || self
                .points
                .as_slice()
                .iter()
                .any(|q| q.class == new.class && near(q.point, point))
        {
            return false;
        }
        // A stored point is active (the span's rule let it in): the kept
        // sums (those of the memory before the store) gain it, and lose
        // the point it evicts if that was active.
        self.keep_sums_at(robot, target);
        let gone = self.points.push(new);
        if let Some(sums) = self.sums.as_mut() {
            sums.add(point);
            if let Some(gone) = gone.filter(|g| span.holds(g)) {
                sums.remove(gone.point);
            }
        }
        true
    }

    /// `(n, Σ(P_R − P_i))` over the active points: the direction of
    /// `P_R − P_M` without dividing by `n` (eq. 13 needs only its direction).
    pub fn away_from_midpoint(&self, robot: Point, target: Point) -> (u8, i32, i32) {
        self.sums_at(robot, target).away_from(robot)
    }

    /// [`Memory::away_from_midpoint`] for the planner: a scan it needs is
    /// kept for the next cycles at this robot position.
    pub(crate) fn away_from_midpoint_kept(
        &mut self,
        robot: Point,
        target: Point,
    ) -> (u8, i32, i32) {
        self.keep_sums_at(robot, target);
        self.sums
            .as_ref()
            .map_or((0, 0, 0), |sums| sums.away_from(robot))
    }

    /// The midpoint `P_M` of the active points (eq. 11), for reports.
    pub fn midpoint(&self, robot: Point, target: Point) -> Option<Point> {
        let (n, sx, sy) = self.away_from_midpoint(robot, target);
        if n == 0 {
            return None;
        }
        let n = n as i32;
        Some(Point::saturating(
            robot.x as i32 - sx.checked_div(n)?,
            robot.y as i32 - sy.checked_div(n)?,
        ))
    }

    /// All remembered points, oldest first.
    pub fn iter(&self) -> impl Iterator<Item = &Remembered> {
        self.points.iter()
    }

    /// Number of remembered points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether nothing is remembered.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Forget everything (a new goal).
    pub fn clear(&mut self) {
        *self = Memory::new();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_16_bit_span_test_is_the_plain_one() {
        let edges = [
            i16::MIN,
            i16::MIN + 1,
            -20_000,
            -1,
            0,
            1,
            7,
            20_000,
            i16::MAX - 1,
            i16::MAX,
        ];
        for a in edges {
            for b in edges {
                let span = Span::new(Point::new(a, b), Point::new(b, a));
                for p in edges
                    .iter()
                    .flat_map(|&x| [x, x.wrapping_add(3), x.wrapping_sub(3)])
                {
                    let (lo, hi) = (a.min(b) as i32, a.max(b) as i32);
                    let inside = (lo..=hi).contains(&(p as i32));
                    assert_eq!(span.axes(Point::new(p, p)), (inside, inside), "{a} {b} {p}");
                }
            }
        }
    }

    const TOL: Angle = Angle::from_deg(5);

    #[test]
    fn direction_classes_of_eqs_11_to_13() {
        assert_eq!(direction_class(Angle::from_deg(0), TOL), PointClass::X);
        assert_eq!(direction_class(Angle::from_deg(30), TOL), PointClass::X);
        assert_eq!(direction_class(Angle::from_deg(170), TOL), PointClass::X);
        assert_eq!(direction_class(Angle::from_deg(-160), TOL), PointClass::X);
        assert_eq!(direction_class(Angle::from_deg(60), TOL), PointClass::Y);
        assert_eq!(direction_class(Angle::from_deg(-90), TOL), PointClass::Y);
        assert_eq!(direction_class(Angle::from_deg(45), TOL), PointClass::XY);
        assert_eq!(direction_class(Angle::from_deg(-132), TOL), PointClass::XY);
        assert_eq!(direction_class(Angle::from_deg(138), TOL), PointClass::XY);
        assert_eq!(direction_class(Angle::from_deg(128), TOL), PointClass::Y);
    }

    #[test]
    fn only_points_between_robot_and_target_are_remembered() {
        let mut m = Memory::new();
        let robot = Point::new(0, 0);
        let target = Point::new(2_000, 500);
        // Moving along x: x between 0 and 2000 → X-point.
        assert!(m.remember(Point::new(500, 900), robot, Angle::ZERO, target, TOL));
        // Behind the robot in x: ignored.
        assert!(!m.remember(Point::new(-300, 0), robot, Angle::ZERO, target, TOL));
        // Moving along y: y 900 is not between 0 and 500 → ignored.
        assert!(!m.remember(Point::new(100, 900), robot, Angle::QUARTER, target, TOL));
        assert_eq!(m.len(), 1);
        // Once the robot passes x = 500 the point is no longer active.
        assert_eq!(m.away_from_midpoint(Point::new(400, 0), target).0, 1);
        assert_eq!(m.away_from_midpoint(Point::new(600, 0), target).0, 0);
    }

    #[test]
    fn midpoint_by_hand() {
        let mut m = Memory::new();
        let robot = Point::new(0, 0);
        let target = Point::new(3_000, 0);
        m.remember(Point::new(1_000, 200), robot, Angle::ZERO, target, TOL);
        m.remember(Point::new(1_000, -400), robot, Angle::ZERO, target, TOL);
        // P_M = (1000, −100); Σ(P_R − P_i) = (−2000, 200).
        assert_eq!(m.midpoint(robot, target), Some(Point::new(1_000, -100)));
        assert_eq!(m.away_from_midpoint(robot, target), (2, -2_000, 200));
    }

    #[test]
    fn near_copies_merge_and_the_oldest_is_evicted_when_full() {
        let mut m = Memory::new();
        let robot = Point::new(0, 0);
        let target = Point::new(30_000, 0);
        assert!(m.remember(Point::new(1_000, 0), robot, Angle::ZERO, target, TOL));
        assert!(!m.remember(Point::new(1_030, 20), robot, Angle::ZERO, target, TOL));
        for i in 1..(MEMORY_CAPACITY as i16 + 3) {
            assert!(m.remember(
                Point::new(1_000 + 100 * i, 0),
                robot,
                Angle::ZERO,
                target,
                TOL
            ));
        }
        assert_eq!(m.len(), MEMORY_CAPACITY);
        // The first three (1000, 1100, 1200) were evicted; the rest come
        // oldest first.
        let xs: std::vec::Vec<i16> = m.iter().map(|r| r.point.x).collect();
        let want: std::vec::Vec<i16> = (0..MEMORY_CAPACITY as i16)
            .map(|i| 1_300 + 100 * i)
            .collect();
        assert_eq!(xs, want);
        m.clear();
        assert!(m.is_empty() && m.iter().next().is_none());
    }

    /// The memory as the rules state it, for the tests: a point is stored
    /// unless the span's rule drops it or it is near a held point of the
    /// same class; when full, it overwrites the oldest. Returns whether it
    /// was stored.
    fn naive(
        mem: &mut std::vec::Vec<Remembered>,
        oldest: &mut usize,
        r: Remembered,
        span: Span,
    ) -> bool {
        if !span.holds(&r)
            || mem
                .iter()
                .any(|q| near(q.point, r.point) && q.class == r.class)
        {
            return false;
        }
        if mem.len() < MEMORY_CAPACITY {
            mem.push(r);
        } else {
            mem[*oldest] = r;
            *oldest = (*oldest + 1) % MEMORY_CAPACITY;
        }
        true
    }

    proptest::proptest! {
        /// Remembering stores what the rules store, evictions included, and
        /// gives the points back oldest first.
        #[test]
        fn remembering_follows_the_rules(
            points in proptest::collection::vec(
                (0i16..600, -300i16..300, -180i16..180),
                0..60,
            ),
        ) {
            let (robot, target) = (Point::new(-10, -400), Point::new(700, 400));
            let span = Span::new(robot, target);
            let mut a = Memory::new();
            let (mut model, mut oldest) = (std::vec::Vec::new(), 0usize);
            for &(x, y, deg) in &points {
                let heading = Angle::from_deg(deg);
                let point = Point::new(x, y);
                let class = direction_class(heading, TOL);
                let want = naive(&mut model, &mut oldest, Remembered { point, class }, span);
                proptest::prop_assert_eq!(a.remember(point, robot, heading, target, TOL), want);
                proptest::prop_assert!(a.points.as_slice().iter().eq(model.iter()));
                let (newer, older) = model.split_at(oldest);
                proptest::prop_assert!(a.iter().eq(older.iter().chain(newer)));
            }
        }
    }

    proptest::proptest! {
        /// The kept midpoint sums equal a scan of the memory, whether the
        /// robot stays (sums updated point by point) or moves (rescanned),
        /// and whether the planner's midpoint call or a store kept them.
        #[test]
        fn kept_sums_equal_a_scan(
            cycles in proptest::collection::vec(
                (proptest::collection::vec((0i16..600, -300i16..300), 0..6),
                 -180i16..180, 0i16..3),
                0..40,
            ),
        ) {
            let target = Point::new(700, 400);
            let mut m = Memory::new();
            for (cycle, deg, at) in &cycles {
                // Few robot positions, so that many cycles repeat one.
                let robot = Point::new(-10 + 200 * at, -400 + 150 * at);
                let pts: std::vec::Vec<Point> =
                    cycle.iter().map(|&(x, y)| Point::new(x, y)).collect();
                // The planner's form, on some cycles before the points come
                // in: it keeps a scan the next remembering then updates.
                if deg % 2 == 0 {
                    let want = m.scan_sums(robot, target).away_from(robot);
                    proptest::prop_assert_eq!(m.away_from_midpoint_kept(robot, target), want);
                }
                for &p in &pts {
                    m.remember(p, robot, Angle::from_deg(*deg), target, TOL);
                }
                for probe in [robot, Point::new(300, 0)] {
                    let s = m.scan_sums(probe, target);
                    let k = s.n as i32;
                    let want = (s.n, k * probe.x as i32 - s.sx, k * probe.y as i32 - s.sy);
                    proptest::prop_assert_eq!(m.away_from_midpoint(probe, target), want);
                }
            }
        }
    }

    #[test]
    fn merging_is_strictly_within_the_merge_distance() {
        let mut m = Memory::new();
        let (robot, target) = (Point::new(0, 0), Point::new(30_000, 0));
        assert!(m.remember(Point::new(1_000, 0), robot, Angle::ZERO, target, TOL));
        let d = MERGE_MM as i16;
        for (x, y) in [(d - 1, 0), (1 - d, d - 1), (0, 1 - d)] {
            assert!(!m.remember(Point::new(1_000 + x, y), robot, Angle::ZERO, target, TOL));
        }
        assert!(m.remember(Point::new(1_000 - d, 0), robot, Angle::ZERO, target, TOL));
        assert!(m.remember(Point::new(1_000, d), robot, Angle::ZERO, target, TOL));
        // Same place, other class: kept apart.
        assert!(m.remember(
            Point::new(1_000, 0),
            robot,
            Angle::from_deg(45),
            Point::new(3_000, 3_000),
            TOL
        ));
    }

    #[test]
    fn the_span_test_is_the_betweenness_of_eqs_11_to_13() {
        fn between(v: i16, a: i16, b: i16) -> bool {
            a.min(b) <= v && v <= a.max(b)
        }
        let vals = [
            i16::MIN,
            -30_000,
            -501,
            -500,
            -1,
            0,
            1,
            499,
            500,
            30_000,
            i16::MAX,
        ];
        for &a in &vals {
            for &b in &vals {
                for &v in &vals {
                    for class in [PointClass::X, PointClass::Y, PointClass::XY] {
                        let w = v.wrapping_add(250);
                        let p = Remembered {
                            point: Point::new(v, w),
                            class,
                        };
                        let (robot, target) = (Point::new(a, b), Point::new(b, a));
                        let (in_x, in_y) = (between(v, a, b), between(w, b, a));
                        let want = match class {
                            PointClass::X => in_x,
                            PointClass::Y => in_y,
                            PointClass::XY => in_x && in_y,
                        };
                        assert_eq!(p.is_active(robot, target), want, "{a} {b} {v} {class:?}");
                    }
                }
            }
        }
    }
}
