//! Remembered collision points for the midpoint repulsive force (paper
//! §5.4, eqs. 11–13), in bounded memory.
//!
//! Each collision point is classified when it is detected from the robot's
//! direction θr: moving mainly along x (`|cos θr| > |sin θr|`, the paper's
//! eq. 11 read as magnitudes, see ALGORITHMS.md §2) makes it an X-point if
//! its x lies between the robot's and the target's x; mainly along y makes it
//! a Y-point likewise; within the diagonal tolerance of 45° makes it an
//! XY-point if both hold. A point outside its range is not remembered (the
//! paper's "ignored point"). A point stays *active* only while it is still
//! inside its range; the midpoint `P_M` is the mean of the active points.
//!
//! Capacity and eviction: at most [`MEMORY_CAPACITY`] points. A new point
//! within [`MERGE_MM`] of a remembered one of the same class is not stored
//! again (a wall seen on consecutive cycles would otherwise fill the memory
//! with near-copies). When the memory is full the *oldest* point is evicted:
//! the most recent obstacles are the ones the robot is dealing with.

use crate::fixed::{Angle, Point};
use heapless::Deque;

/// Most remembered collision points.
pub const MEMORY_CAPACITY: usize = 16;

/// Points closer than this (Chebyshev distance, mm) to a remembered point of
/// the same class are merged into it.
pub const MERGE_MM: i16 = 60;

/// The class of a remembered point (eqs. 11–13).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PointClass {
    /// Detected while moving mainly along x; active while between robot and target in x.
    X,
    /// Detected while moving mainly along y; active while between robot and target in y.
    Y,
    /// Detected while moving diagonally; active while between them in x and y.
    XY,
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

fn between(v: i16, a: i16, b: i16) -> bool {
    let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
    lo <= v && v <= hi
}

impl Remembered {
    /// Whether the point counts for the midpoint force with the robot at
    /// `robot` and the target at `target`.
    pub fn is_active(&self, robot: Point, target: Point) -> bool {
        let in_x = between(self.point.x, robot.x, target.x);
        let in_y = between(self.point.y, robot.y, target.y);
        match self.class {
            PointClass::X => in_x,
            PointClass::Y => in_y,
            PointClass::XY => in_x && in_y,
        }
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

/// The bounded memory of collision points.
#[derive(Clone, Debug, Default)]
pub struct Memory {
    points: Deque<Remembered, MEMORY_CAPACITY>,
}

impl Memory {
    /// An empty memory.
    pub const fn new() -> Self {
        Memory {
            points: Deque::new(),
        }
    }

    /// Classify and remember a collision point detected with the robot at
    /// `robot` heading `heading`, target `target`. Returns whether it was
    /// stored (it may be ignored, or merged into a near one).
    pub fn remember(
        &mut self,
        point: Point,
        robot: Point,
        heading: Angle,
        target: Point,
        diagonal_tolerance: Angle,
    ) -> bool {
        let class = direction_class(heading, diagonal_tolerance);
        let r = Remembered { point, class };
        if !r.is_active(robot, target) {
            return false;
        }
        let near = |q: &Remembered| {
            q.class == class
                && (q.point.x as i32 - point.x as i32).abs() < MERGE_MM as i32
                && (q.point.y as i32 - point.y as i32).abs() < MERGE_MM as i32
        };
        if self.points.iter().any(near) {
            return false;
        }
        if self.points.is_full() {
            self.points.pop_front();
        }
        self.points.push_back(r).is_ok()
    }

    /// `(n, Σ(P_R − P_i))` over the active points: the direction of
    /// `P_R − P_M` without dividing by `n` (eq. 13 needs only its direction).
    pub fn away_from_midpoint(&self, robot: Point, target: Point) -> (u8, i32, i32) {
        let mut n = 0u8;
        let (mut sx, mut sy) = (0i32, 0i32);
        for p in self.points.iter().filter(|p| p.is_active(robot, target)) {
            let (dx, dy) = p.point.to(robot);
            sx += dx;
            sy += dy;
            n += 1;
        }
        (n, sx, sy)
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
        self.points.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
        // The first three (1000, 1100, 1200) were evicted.
        assert_eq!(m.iter().next().unwrap().point, Point::new(1_300, 0));
    }
}
