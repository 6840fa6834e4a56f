//! Escape from local minima with virtual obstacles: the "liquid movement"
//! idea of Moaveni & Ghanbari Gol (ALGORITHMS.md §3) applied online.
//!
//! A droplet caught in a pit raises the level there so the next one flows
//! past. Online, the rover is "in a pit" (ALGORITHMS.md §3) when either
//!
//! * it is **stuck**: over the last `window_steps` planner cycles its net
//!   displacement stayed below `stuck_mm` (it dithers or oscillates), or
//! * it **loops**: it comes back within `revisit_mm` of a breadcrumb it left
//!   earlier (a breadcrumb is dropped every `crumb_mm` of travel; the two
//!   newest do not count).
//!
//! Then a virtual obstacle of radius `V_r` is dropped where the rover stands
//! (§3: "put a virtual obstacle there"). It repels with `K_v / d²`, `d` the
//! distance from its centre but never less than `V_r` (the §3 potential
//! `K_v / r²` made finite inside the obstacle, as a force with the law of
//! eq. 10), away from `V` (away from the goal for a rover standing exactly
//! on it). `K_v` = 0.1 makes it worth 4.4 units at its rim, about twice the
//! attraction: enough to destroy the minimum, not so much that the rover
//! flees. The pit fills and the rover spills out of it.
//!
//! A drop within [`VIRTUAL_MERGE_MM`] of a virtual obstacle already held
//! adds to that one's weight instead of taking a slot: a rover stuck turning
//! in place drops one every few cycles on the same spot, and an obstacle of
//! weight `w` repels exactly as `w` obstacles there would, for the cost of one.
//!
//! Reach: an obstacle is skipped where its push has fallen below
//! [`VIRTUAL_MIN_PUSH`] (1/32 of a force unit, 1/64 of the attraction, under
//! a degree of heading); the distance where that happens is kept with it, so
//! the test is two compares instead of a square root and two divisions.
//!
//! Bounded memory: at most [`VIRTUAL_CAPACITY`] virtual obstacles,
//! [`CRUMB_CAPACITY`] breadcrumbs and [`WINDOW_CAPACITY`] recent positions;
//! when full, the oldest is dropped (the newest describe the pit the rover
//! is in now).
//!
//! Give-up: when `give_up_drops` virtual obstacles have been dropped, or
//! `give_up_steps` cycles have passed, since the rover last came
//! `progress_mm` nearer the goal than ever before, escape is making no
//! progress and the goal is reported unreachable (a walled-in goal never
//! lets the best distance improve).

use crate::fixed::{
    hypot, inverse_square_force, isqrt, within, Angle, Force, Point, FORCE_ONE, FORCE_SHIFT,
    MAX_SCALED,
};
use crate::ring::Ring;
use heapless::Deque;

/// Most virtual obstacles kept.
pub const VIRTUAL_CAPACITY: usize = 24;
/// A drop nearer than this (mm) to a held virtual obstacle strengthens it.
pub const VIRTUAL_MERGE_MM: u16 = 16;
/// A virtual obstacle whose push is below this (Q10) is skipped.
pub const VIRTUAL_MIN_PUSH: i32 = FORCE_ONE / 32;
/// Most breadcrumbs kept.
pub const CRUMB_CAPACITY: usize = 16;
/// Longest stuck-detection window, cycles.
pub const WINDOW_CAPACITY: usize = 16;

/// Escape parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EscapeConfig {
    /// Whether virtual obstacles are used at all (off: plain EAPF).
    pub enabled: bool,
    /// Stuck-detection window, planner cycles (2 ..= 16).
    pub window_steps: u16,
    /// Net displacement over the window below which the rover is stuck, mm.
    pub stuck_mm: u16,
    /// Travel between breadcrumbs, mm (20 ..= 5000).
    pub crumb_mm: u16,
    /// Coming this near an old breadcrumb is a loop, mm (below `crumb_mm`).
    pub revisit_mm: u16,
    /// How much nearer the goal than ever before counts as progress, mm (1 ..= 2000).
    pub progress_mm: u16,
    /// Radius of a virtual obstacle, mm (`V_r`, 10 ..= 2000).
    pub radius_mm: u16,
    /// `K_v` in Q10 force units (1/1024 ..= 16 units).
    pub k_v: i32,
    /// Virtual obstacles without progress before giving up (1 ..= 1000).
    pub give_up_drops: u16,
    /// Planner cycles without progress before giving up (10 ..= 60000).
    pub give_up_steps: u16,
}

impl Default for EscapeConfig {
    fn default() -> Self {
        EscapeConfig {
            enabled: true,
            window_steps: 12,
            stuck_mm: 150,
            crumb_mm: 400,
            revisit_mm: 150,
            progress_mm: 100,
            radius_mm: 150,
            k_v: FORCE_ONE / 10,
            give_up_drops: 40,
            give_up_steps: 400,
        }
    }
}

impl EscapeConfig {
    /// Whether every field is in its documented range.
    pub fn is_valid(&self) -> bool {
        (2..=WINDOW_CAPACITY as u16).contains(&self.window_steps)
            && (20..=5_000).contains(&self.crumb_mm)
            && self.revisit_mm < self.crumb_mm
            && self.stuck_mm <= 5_000
            && (10..=60_000).contains(&self.give_up_steps)
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

/// A virtual obstacle: its centre and how many drops it stands for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct VirtualObstacle {
    /// Centre, world mm.
    pub centre: Point,
    /// Drops merged into it (1 ..= 255); it repels `weight` times as hard.
    pub weight: u8,
    /// Beyond this distance on either axis its push is below
    /// [`VIRTUAL_MIN_PUSH`], mm.
    pub reach_mm: u16,
}

impl VirtualObstacle {
    /// A virtual obstacle of `weight` drops at `centre`.
    pub fn new(cfg: &EscapeConfig, centre: Point, weight: u8) -> Self {
        // weight·K_v / d² < min ⇔ d² > weight·K_v·(10⁶ mm² / min), with K_v
        // and min both Q10; saturating (a reach of ~65 m) if that overflows.
        const MM2_PER_MIN: u32 = 1_000_000 / VIRTUAL_MIN_PUSH as u32;
        let k = (weight as u32).saturating_mul(cfg.k_v.max(0) as u32);
        VirtualObstacle {
            centre,
            weight,
            reach_mm: isqrt(k.saturating_mul(MM2_PER_MIN)).saturating_add(1),
        }
    }
}

/// Progress monitor and virtual obstacles.
#[derive(Clone, Debug)]
pub struct Escape {
    best_mm: u16,
    since_best: u16,
    drops_since_best: u16,
    dropped: u16,
    recent: Deque<Point, WINDOW_CAPACITY>,
    crumbs: Deque<Point, CRUMB_CAPACITY>,
    /// Where, and for which radius, the trail was last searched and no old
    /// breadcrumb was near, the trail unchanged since: a rover turning in
    /// place asks the same question every cycle.
    no_revisit_at: Option<(Point, u16)>,
    obstacles: Ring<VirtualObstacle, VIRTUAL_CAPACITY>,
    /// The last answer of [`Escape::force_kept`] and its question (robot,
    /// bearing): a rover turning in place asks the same question every
    /// cycle, and a stuck one, surrounded by the obstacles it dropped, is
    /// where the sum costs most. A drop forgets it.
    kept_force: Option<(Point, Angle, Force)>,
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
            dropped: 0,
            recent: Deque::new(),
            crumbs: Deque::new(),
            no_revisit_at: None,
            obstacles: Ring::new(),
            kept_force: None,
        }
    }

    /// Forget everything (a new goal).
    pub fn reset(&mut self) {
        *self = Escape::new();
    }

    /// Account for one planner cycle with the rover at `robot`, `goal_mm`
    /// from the goal.
    pub fn observe(&mut self, cfg: &EscapeConfig, robot: Point, goal_mm: u16) -> Verdict {
        if !cfg.enabled {
            return Verdict::Continue;
        }
        if self.best_mm == u16::MAX || goal_mm.saturating_add(cfg.progress_mm) <= self.best_mm {
            self.best_mm = goal_mm;
            self.since_best = 0;
            self.drops_since_best = 0;
        } else {
            self.since_best = self.since_best.saturating_add(1);
        }
        if self.since_best > cfg.give_up_steps || self.drops_since_best >= cfg.give_up_drops {
            return Verdict::GiveUp;
        }
        // Stuck: little net displacement over the window.
        if self.recent.len() >= cfg.window_steps as usize {
            self.recent.pop_front();
        }
        let _ = self.recent.push_back(robot);
        let stuck = self.recent.len() >= cfg.window_steps as usize
            && self
                .recent
                .front()
                .is_some_and(|&p| within(p, robot, cfg.stuck_mm));
        // Loop: back near an old breadcrumb.
        let question = (robot, cfg.revisit_mm);
        let looped = self.no_revisit_at != Some(question) && self.revisits(robot, cfg.revisit_mm);
        self.no_revisit_at = (!looped).then_some(question);
        if self
            .crumbs
            .back()
            .is_none_or(|&c| !within(c, robot, cfg.crumb_mm))
        {
            if self.crumbs.is_full() {
                self.crumbs.pop_front();
            }
            let _ = self.crumbs.push_back(robot);
            self.no_revisit_at = None;
        }
        if !(stuck || looped) {
            return Verdict::Continue;
        }
        self.recent.clear();
        if looped {
            self.crumbs.clear();
        }
        self.drop_at(robot, cfg);
        Verdict::Dropped
    }

    /// Whether `robot` is within `r_mm` of a breadcrumb other than the two
    /// newest. Runs every cycle over the whole trail: plain loops over the
    /// deque's two slices.
    fn revisits(&self, robot: Point, r_mm: u16) -> bool {
        let old = self.crumbs.len().saturating_sub(2);
        let (a, b) = self.crumbs.as_slices();
        let (a_old, b_old) = (old.min(a.len()), old.saturating_sub(a.len()));
        a.get(..a_old).is_some_and(|s| any_within(s, robot, r_mm))
            || b.get(..b_old).is_some_and(|s| any_within(s, robot, r_mm))
    }

    /// Drop a virtual obstacle at `robot` (or strengthen the one held there).
    fn drop_at(&mut self, robot: Point, cfg: &EscapeConfig) {
        self.kept_force = None;
        self.drops_since_best = self.drops_since_best.saturating_add(1);
        let held = self
            .obstacles
            .iter_mut()
            .find(|v| within(v.centre, robot, VIRTUAL_MERGE_MM));
        if let Some(v) = held {
            *v = VirtualObstacle::new(cfg, v.centre, v.weight.saturating_add(1));
        } else {
            self.obstacles.push(VirtualObstacle::new(cfg, robot, 1));
        }
        self.dropped = self.dropped.saturating_add(1);
    }

    /// The summed repulsion of the virtual obstacles on the rover at
    /// `robot`, whose goal bearing is `bearing`: `K_v / max(d, V_r)²` each,
    /// along the unit vector `(dx, dy) / r` from the obstacle's centre (`r`
    /// its true distance), computed as components: no angle, so no `atan2`
    /// and no sine per obstacle.
    pub fn force(&self, cfg: &EscapeConfig, robot: Point, bearing: Angle) -> Force {
        // At most 24 terms below 2^25 each: the sum stays below 2^30, so a
        // plain add, and the slot order does not change it.
        let mut f = Force::ZERO;
        for v in self.obstacles.as_slice() {
            let (dx, dy) = v.centre.to(robot);
            let reach = v.reach_mm as u32;
            if dx.unsigned_abs() >= reach || dy.unsigned_abs() >= reach {
                continue;
            }
            let r = hypot(dx, dy);
            let d = r.max(cfg.radius_mm);
            // (1/d²)·K_v in Q10 without 64-bit maths: ≤ 7,750 · 16,384 fits in i32.
            let mag =
                (((inverse_square_force(d) >> 4) * cfg.k_v) >> (FORCE_SHIFT - 4)).min(MAX_SCALED);
            // Unsigned (mag ≥ 0, r ≥ 0): the AVR's signed division is the
            // unsigned one wrapped in sign handling.
            let r = r as u32;
            let one = match (((mag as u32) << 12) + r / 2).checked_div(r) {
                // mag/r in Q12, rounded (mag < 2^17), then times |dx|, |dy|
                // ≤ r: the products stay below mag · 2^12 + r < 2^30.
                Some(per_mm) => Force {
                    x: (dx * per_mm as i32 + (1 << 11)) >> 12,
                    y: (dy * per_mm as i32 + (1 << 11)) >> 12,
                },
                // Standing on the centre: straight away from the goal.
                _ => Force::along(bearing.add(Angle::HALF), mag),
            };
            // |one| ≤ 2^17 and weight ≤ 255: the products fit in i32.
            let w = v.weight as i32;
            f = f.plus_bounded(Force {
                x: one.x * w,
                y: one.y * w,
            });
        }
        f
    }

    /// [`Escape::force`] for the planner: the answer is kept, and given
    /// again while the rover stands where it stood, facing the same goal
    /// bearing, and no obstacle has been dropped (the same `cfg` every call:
    /// a planner's configuration does not change).
    pub(crate) fn force_kept(&mut self, cfg: &EscapeConfig, robot: Point, bearing: Angle) -> Force {
        match self.kept_force {
            Some((at, b, f)) if at == robot && b == bearing => f,
            _ => {
                let f = self.force(cfg, robot, bearing);
                self.kept_force = Some((robot, bearing, f));
                f
            }
        }
    }

    /// Forget the kept force (tests compare against a fresh sum).
    #[cfg(test)]
    pub(crate) fn forget_kept(&mut self) {
        self.kept_force = None;
    }

    /// Virtual obstacles, oldest first.
    pub fn obstacles(&self) -> impl Iterator<Item = &VirtualObstacle> {
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

    /// Virtual obstacles dropped in all (including evicted ones).
    pub fn dropped(&self) -> u16 {
        self.dropped
    }

    /// Best distance to the goal so far, mm.
    pub fn best_mm(&self) -> u16 {
        self.best_mm
    }
}

/// Whether any of `points` is within `r_mm` of `robot`. Out of line: it
/// runs on both halves of a deque, and the AVR pays for each copy.
#[inline(never)]
fn any_within(points: &[Point], robot: Point, r_mm: u16) -> bool {
    points.iter().any(|&c| within(c, robot, r_mm))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_strongest_full_set_of_virtual_obstacles_sums_without_overflow() {
        // The force sum is a plain add on the bound that every term is
        // below 2^25 (a magnitude clamped below 2^17, times a weight up
        // to 255) and there are at most VIRTUAL_CAPACITY of them. The
        // extreme: the largest K_v, every slot of weight 255 on one spot
        // right behind the rover, all pushing the same way.
        let cfg = EscapeConfig {
            k_v: 16 * FORCE_ONE,
            ..EscapeConfig::default()
        };
        let robot = Point::new(0, 0);
        let strongest = VirtualObstacle::new(&cfg, Point::new(-100, 0), u8::MAX);
        let mut one = Escape::new();
        one.obstacles.push(strongest);
        let mut full = Escape::new();
        for _ in 0..VIRTUAL_CAPACITY {
            full.obstacles.push(strongest);
        }
        let f1 = one.force(&cfg, robot, Angle::ZERO);
        let f = full.force(&cfg, robot, Angle::ZERO);
        assert_eq!(
            f1.x,
            MAX_SCALED * u8::MAX as i32,
            "clamped magnitude along +x"
        );
        assert_eq!(f.x as i64, VIRTUAL_CAPACITY as i64 * f1.x as i64);
        assert_eq!(f.y, 0);
    }

    #[test]
    fn stuck_rover_drops_then_gives_up() {
        let cfg = EscapeConfig {
            window_steps: 3,
            give_up_drops: 2,
            ..EscapeConfig::default()
        };
        let mut e = Escape::new();
        let p = Point::new(0, 0);
        // Cycles 1, 2: window not full yet.
        assert_eq!(e.observe(&cfg, p, 2_000), Verdict::Continue);
        assert_eq!(e.observe(&cfg, Point::new(50, 0), 1_950), Verdict::Continue);
        // Cycle 3: 100 mm net over the window < 150 mm → stuck.
        assert_eq!(e.observe(&cfg, Point::new(100, 0), 1_950), Verdict::Dropped);
        // The obstacle sits where the rover stands.
        assert_eq!(e.obstacles().next().unwrap().centre, Point::new(100, 0));
        assert_eq!(e.observe(&cfg, p, 2_000), Verdict::Continue);
        assert_eq!(e.observe(&cfg, p, 2_000), Verdict::Continue);
        assert_eq!(e.observe(&cfg, p, 2_000), Verdict::Dropped);
        // Two drops without a new best distance: give up.
        assert_eq!(e.observe(&cfg, p, 2_000), Verdict::GiveUp);
        assert_eq!(e.dropped(), 2);
    }

    proptest::proptest! {
        /// The trail scan finds a revisit exactly when the plain scan over
        /// all but the two newest crumbs does, wherever the deque wraps.
        #[test]
        fn revisits_matches_the_plain_scan(
            trail in proptest::collection::vec((-600i16..600, -600i16..600), 0..40),
            (x, y) in (-600i16..600, -600i16..600),
            r in 0u16..400,
        ) {
            let mut e = Escape::new();
            for &(cx, cy) in &trail {
                if e.crumbs.is_full() {
                    e.crumbs.pop_front();
                }
                let _ = e.crumbs.push_back(Point::new(cx, cy));
            }
            let robot = Point::new(x, y);
            let n = e.crumbs.len();
            let plain = e.crumbs.iter().take(n.saturating_sub(2)).any(|&c| within(c, robot, r));
            proptest::prop_assert_eq!(e.revisits(robot, r), plain);
        }
    }

    proptest::proptest! {
        /// Skipping the trail search where it last found nothing changes
        /// no verdict, and the kept force is the force: the same walk with
        /// the search forced and the force summed every cycle.
        #[test]
        fn the_kept_search_result_changes_nothing(
            walk in proptest::collection::vec((0i16..4, 0i16..4, 0u16..3), 1..120),
        ) {
            let cfg = EscapeConfig { crumb_mm: 250, revisit_mm: 200, ..EscapeConfig::default() };
            let (mut kept, mut plain) = (Escape::new(), Escape::new());
            for &(i, j, stay) in &walk {
                // A coarse grid, visited in runs: loops, stays and moves.
                let robot = Point::new(300 * i, 300 * j);
                for _ in 0..=stay {
                    plain.no_revisit_at = None;
                    let goal_mm = 3_000 - 100 * (i + j) as u16;
                    let want = plain.observe(&cfg, robot, goal_mm);
                    proptest::prop_assert_eq!(kept.observe(&cfg, robot, goal_mm), want);
                    proptest::prop_assert!(kept.obstacles().eq(plain.obstacles()));
                    // The kept force too (a stay repeats the question).
                    let bearing = Angle(4_000 * i as u16);
                    let fresh = plain.force(&cfg, robot, bearing);
                    proptest::prop_assert_eq!(kept.force_kept(&cfg, robot, bearing), fresh);
                }
            }
        }
    }

    #[test]
    fn a_zero_revisit_distance_finds_nothing() {
        // (Found by the proptest above: the box test overflowed for 0 in
        // debug builds.)
        let p = Point::new(5, -5);
        assert!(!any_within(&[p, p], p, 0));
        assert!(any_within(&[p, p], p, 1));
    }

    #[test]
    fn moving_rover_is_not_stuck_but_a_loop_is_caught() {
        let cfg = EscapeConfig::default();
        let mut e = Escape::new();
        // Drive a 1.2 m square, 200 mm per cycle, and come back to the start.
        let mut pts = heapless::Vec::<Point, 32>::new();
        for i in 0..6 {
            pts.push(Point::new(200 * i, 0)).unwrap();
        }
        for i in 0..6 {
            pts.push(Point::new(1_200, 200 * i)).unwrap();
        }
        for i in 0..6 {
            pts.push(Point::new(1_200 - 200 * i, 1_200)).unwrap();
        }
        for i in 0..6 {
            pts.push(Point::new(0, 1_200 - 200 * i)).unwrap();
        }
        let mut verdicts = heapless::Vec::<Verdict, 32>::new();
        for &p in pts.iter() {
            verdicts.push(e.observe(&cfg, p, 5_000)).unwrap();
        }
        // No drop while going round; the return to the first crumb is a loop.
        assert!(
            verdicts[..23].iter().all(|&v| v == Verdict::Continue),
            "{verdicts:?}"
        );
        assert_eq!(e.observe(&cfg, Point::new(0, 0), 5_000), Verdict::Dropped);
    }

    #[test]
    fn progress_resets_the_give_up_budget() {
        let cfg = EscapeConfig {
            window_steps: 2,
            give_up_drops: 2,
            ..EscapeConfig::default()
        };
        let mut e = Escape::new();
        let p = Point::new(0, 0);
        e.observe(&cfg, p, 3_000);
        assert_eq!(e.observe(&cfg, p, 3_000), Verdict::Dropped);
        // 200 mm nearer than ever: budget restored.
        e.observe(&cfg, p, 2_800);
        assert_eq!(e.best_mm(), 2_800);
        assert_eq!(e.observe(&cfg, p, 2_800), Verdict::Dropped);
        // Each drop clears the window, so the next comes two cycles later.
        assert_eq!(e.observe(&cfg, p, 2_800), Verdict::Continue);
        assert_eq!(e.observe(&cfg, p, 2_800), Verdict::Dropped);
        assert_eq!(e.observe(&cfg, p, 2_800), Verdict::GiveUp);
    }

    #[test]
    fn virtual_obstacle_force_by_hand() {
        let cfg = EscapeConfig {
            k_v: FORCE_ONE,
            ..EscapeConfig::default()
        };
        let mut e = Escape::new();
        e.obstacles
            .push(VirtualObstacle::new(&cfg, Point::new(0, 0), 1));
        // K_v = 1, rover 500 mm to the right: 1/0.5² = 4 units along +x.
        assert_eq!(
            e.force(&cfg, Point::new(500, 0), Angle::ZERO),
            Force { x: 4_096, y: 0 }
        );
        // Inside the radius the distance counts as V_r = 150 mm: 44.4 units.
        let f = e.force(&cfg, Point::new(0, 100), Angle::ZERO);
        assert_eq!((f.x, f.y / 1024), (0, 44));
        // Weight 3 repels three times as hard.
        *e.obstacles.iter_mut().next().unwrap() = VirtualObstacle::new(&cfg, Point::new(0, 0), 3);
        assert_eq!(
            e.force(&cfg, Point::new(500, 0), Angle::ZERO),
            Force { x: 3 * 4_096, y: 0 }
        );
        // Weight 1 reaches to where 1/d² = 1/32: √32 m = 5.657 m; just
        // inside it pushes with 1/32 unit, at it not at all.
        *e.obstacles.iter_mut().next().unwrap() = VirtualObstacle::new(&cfg, Point::new(0, 0), 1);
        assert_eq!(e.obstacles().next().unwrap().reach_mm, 5_657);
        let f = e.force(&cfg, Point::new(5_656, 0), Angle::ZERO);
        assert_eq!(
            f,
            Force {
                x: VIRTUAL_MIN_PUSH,
                y: 0
            }
        );
        assert_eq!(
            e.force(&cfg, Point::new(0, -5_657), Angle::ZERO),
            Force::ZERO
        );
        assert_eq!(
            e.force(&cfg, Point::new(5_657, 1), Angle::ZERO),
            Force::ZERO
        );
        // Exactly on it: away from the goal.
        let f = e.force(&cfg, Point::new(0, 0), Angle::ZERO);
        assert!(f.x < -44 * 1024 && f.y == 0, "{f:?}");
        assert!(!EscapeConfig {
            window_steps: 0,
            ..cfg
        }
        .is_valid());
    }

    #[test]
    fn drops_on_the_same_spot_merge() {
        let cfg = EscapeConfig {
            window_steps: 2,
            give_up_drops: 1_000,
            ..EscapeConfig::default()
        };
        let mut e = Escape::new();
        // A rover turning in place, its odometry wandering by a few mm.
        for i in 0..20 {
            e.observe(&cfg, Point::new(1_000 + i % 3, 500 - i % 5), 1_000);
        }
        assert_eq!(e.len(), 1);
        let v = e.obstacles().next().unwrap();
        assert_eq!(v.weight as u16, e.dropped());
        assert!(within(v.centre, Point::new(1_000, 500), 6));
        assert!(e.dropped() >= 9);
        // 19 mm away is a new one.
        e.observe(&cfg, Point::new(1_020, 500), 1_000);
        e.observe(&cfg, Point::new(1_020, 500), 1_000);
        assert_eq!(e.len(), 2);
    }

    #[test]
    fn capacity_evicts_the_oldest() {
        let cfg = EscapeConfig {
            window_steps: 2,
            give_up_drops: 1_000,
            ..EscapeConfig::default()
        };
        let mut e = Escape::new();
        for i in 0..(2 * (VIRTUAL_CAPACITY as i16 + 5)) {
            e.observe(&cfg, Point::new(20 * i, 0), 1_000);
        }
        assert!(e.dropped() as usize > VIRTUAL_CAPACITY);
        assert_eq!(e.len(), VIRTUAL_CAPACITY);
    }
}
