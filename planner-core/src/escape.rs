//! Escape from local minima with virtual obstacles: the "liquid movement"
//! idea of Moaveni & Ghanbari Gol (ALGORITHMS.md §3) applied online.
//!
//! A droplet caught in a pit raises the level there so the next one flows
//! past. Online, the rover is "in a pit" when it stops getting nearer to the
//! goal: the progress monitor remembers the best distance to the goal so far
//! and, when `window_steps` planner cycles pass without beating it by
//! `progress_mm`, drops a virtual obstacle where the rover stands. Every
//! virtual obstacle repels with the §3 clearance `r_v = |V − X| − (V_r + A_r)`
//! and the EAPF force law of eq. 10 (`K_v / r_v²`, away from `V`), so the
//! pit fills and the rover spills out of it. An oscillation or a loop is
//! also "no progress", so it is caught the same way.
//!
//! Bounded memory: at most [`VIRTUAL_CAPACITY`] virtual obstacles; when full,
//! the oldest is dropped (the newest fill the pit the rover is in now).
//!
//! Give-up: when `give_up_drops` virtual obstacles have been dropped since
//! the last new best distance, escape is making no progress and the goal is
//! reported unreachable (a walled-in goal never lets the best improve).

use crate::fixed::{inverse_square_force, Angle, Force, Point, FORCE_ONE};
use heapless::Deque;

/// Most virtual obstacles kept.
pub const VIRTUAL_CAPACITY: usize = 24;

/// Escape parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EscapeConfig {
    /// Whether virtual obstacles are used at all (off: plain EAPF).
    pub enabled: bool,
    /// Planner cycles allowed without a new best distance (2 ..= 1000).
    pub window_steps: u16,
    /// How much nearer the goal counts as progress, mm (1 ..= 2000).
    pub progress_mm: u16,
    /// Radius of a virtual obstacle, mm (`V_r`, 10 ..= 2000).
    pub radius_mm: u16,
    /// `K_v` in Q10 force units (1/1024 ..= 16 units).
    pub k_v: i32,
    /// Virtual obstacles without progress before giving up (1 ..= 1000).
    pub give_up_drops: u16,
}

impl Default for EscapeConfig {
    fn default() -> Self {
        EscapeConfig {
            enabled: true,
            window_steps: 10,
            progress_mm: 100,
            radius_mm: 150,
            k_v: FORCE_ONE,
            give_up_drops: 40,
        }
    }
}

impl EscapeConfig {
    /// Whether every field is in its documented range.
    pub fn is_valid(&self) -> bool {
        (2..=1_000).contains(&self.window_steps)
            && (1..=2_000).contains(&self.progress_mm)
            && (10..=2_000).contains(&self.radius_mm)
            && (1..=16 * FORCE_ONE).contains(&self.k_v)
            && (1..=1_000).contains(&self.give_up_drops)
    }
}

/// What the progress monitor decided this cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Verdict {
    /// Keep going.
    Continue,
    /// A virtual obstacle was dropped here.
    Dropped,
    /// Escape has failed: the goal is unreachable.
    GiveUp,
}

/// Progress monitor and virtual obstacles.
#[derive(Clone, Debug)]
pub struct Escape {
    best_mm: u16,
    since_best: u16,
    drops_since_best: u16,
    obstacles: Deque<Point, VIRTUAL_CAPACITY>,
}

impl Default for Escape {
    fn default() -> Self {
        Escape::new()
    }
}

impl Escape {
    /// No history.
    pub const fn new() -> Self {
        Escape {
            best_mm: u16::MAX,
            since_best: 0,
            drops_since_best: 0,
            obstacles: Deque::new(),
        }
    }

    /// Forget everything (a new goal).
    pub fn reset(&mut self) {
        *self = Escape::new();
    }

    /// Account for one planner cycle with the rover at `robot`, `goal_mm`
    /// from the goal, the goal bearing `bearing`.
    pub fn observe(
        &mut self,
        cfg: &EscapeConfig,
        robot: Point,
        goal_mm: u16,
        bearing: Angle,
    ) -> Verdict {
        if !cfg.enabled {
            return Verdict::Continue;
        }
        if goal_mm.saturating_add(cfg.progress_mm) <= self.best_mm || self.best_mm == u16::MAX {
            self.best_mm = goal_mm;
            self.since_best = 0;
            self.drops_since_best = 0;
            return Verdict::Continue;
        }
        self.since_best = self.since_best.saturating_add(1);
        if self.since_best < cfg.window_steps {
            return Verdict::Continue;
        }
        self.since_best = 0;
        self.drops_since_best = self.drops_since_best.saturating_add(1);
        if self.drops_since_best > cfg.give_up_drops {
            return Verdict::GiveUp;
        }
        // The rover stands at the rim of the new obstacle, on the goal side
        // of it: the obstacle fills the pit between the rover and the goal.
        let v = robot.offset(bearing, cfg.radius_mm);
        if self.obstacles.is_full() {
            self.obstacles.pop_front();
        }
        let _ = self.obstacles.push_back(v);
        Verdict::Dropped
    }

    /// The summed repulsion of the virtual obstacles on a robot of radius
    /// `robot_radius_mm` at `robot`: `K_v / r_v²` away from each (§3, eq. 10 law).
    pub fn force(&self, cfg: &EscapeConfig, robot: Point, robot_radius_mm: u16) -> Force {
        let mut f = Force::ZERO;
        for v in self.obstacles.iter() {
            let (dx, dy) = v.to(robot);
            let d = robot.distance_mm(*v);
            let clearance = d.saturating_sub(cfg.radius_mm + robot_radius_mm);
            // (1/r²)·K_v in Q10 without 64-bit maths: ≤ 7,750 · 16,384 fits in i32.
            let mag = ((inverse_square_force(clearance) >> 4) * cfg.k_v)
                >> (crate::fixed::FORCE_SHIFT - 4);
            let dir = if dx == 0 && dy == 0 {
                Angle::ZERO
            } else {
                Angle::atan2(dy, dx)
            };
            f = f.plus(Force::along(dir, mag));
        }
        f
    }

    /// Virtual obstacle centres, oldest first.
    pub fn obstacles(&self) -> impl Iterator<Item = &Point> {
        self.obstacles.iter()
    }

    /// Number of virtual obstacles held.
    pub fn len(&self) -> usize {
        self.obstacles.len()
    }

    /// Whether none is held.
    pub fn is_empty(&self) -> bool {
        self.obstacles.is_empty()
    }

    /// Best distance to the goal so far, mm.
    pub fn best_mm(&self) -> u16 {
        self.best_mm
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn progress_resets_and_stagnation_drops_then_gives_up() {
        let cfg = EscapeConfig {
            window_steps: 3,
            give_up_drops: 2,
            ..EscapeConfig::default()
        };
        let mut e = Escape::new();
        let p = Point::new(0, 0);
        assert_eq!(e.observe(&cfg, p, 2_000, Angle::ZERO), Verdict::Continue);
        assert_eq!(e.observe(&cfg, p, 1_800, Angle::ZERO), Verdict::Continue);
        assert_eq!(e.best_mm(), 1_800);
        // Less than progress_mm better is no progress.
        assert_eq!(e.observe(&cfg, p, 1_750, Angle::ZERO), Verdict::Continue);
        assert_eq!(e.observe(&cfg, p, 1_750, Angle::ZERO), Verdict::Continue);
        assert_eq!(e.observe(&cfg, p, 1_750, Angle::ZERO), Verdict::Dropped);
        assert_eq!(e.len(), 1);
        // The obstacle sits radius_mm towards the goal.
        assert_eq!(*e.obstacles().next().unwrap(), Point::new(150, 0));
        for _ in 0..2 {
            e.observe(&cfg, p, 1_750, Angle::ZERO);
        }
        assert_eq!(e.observe(&cfg, p, 1_750, Angle::ZERO), Verdict::Dropped);
        for _ in 0..2 {
            e.observe(&cfg, p, 1_750, Angle::ZERO);
        }
        assert_eq!(e.observe(&cfg, p, 1_750, Angle::ZERO), Verdict::GiveUp);
    }

    #[test]
    fn virtual_obstacle_force_by_hand() {
        let cfg = EscapeConfig::default();
        let mut e = Escape::new();
        e.obstacles.push_back(Point::new(0, 0)).unwrap();
        // Robot 750 mm to the right: r_v = 750 − (150 + 100) = 500 mm → 4 units.
        let f = e.force(&cfg, Point::new(750, 0), 100);
        assert_eq!(f, Force { x: 4_096, y: 0 });
        assert!(!EscapeConfig {
            window_steps: 0,
            ..cfg
        }
        .is_valid());
    }

    #[test]
    fn capacity_evicts_the_oldest() {
        let cfg = EscapeConfig {
            window_steps: 2,
            give_up_drops: 1_000,
            ..EscapeConfig::default()
        };
        let mut e = Escape::new();
        e.observe(&cfg, Point::new(0, 0), 1_000, Angle::ZERO);
        for i in 0..(2 * (VIRTUAL_CAPACITY as i16 + 5)) {
            e.observe(&cfg, Point::new(i, 0), 1_000, Angle::ZERO);
        }
        assert_eq!(e.len(), VIRTUAL_CAPACITY);
    }
}
