//! Escape from local minima with virtual obstacles: the "liquid movement"
//! idea of Moaveni & Ghanbari Gol (docs/algorithms.md §3) applied online.
//!
//! A droplet caught in a pit raises the level there so the next one flows
//! past. Online, the rover is "in a pit" (docs/algorithms.md §3) when either
//!
//! * it is **stuck**: over the last `window_steps` planner cycles its net
//!   displacement stayed below `stuck_mm` (it dithers or oscillates), or
//! * it **loops**: it comes back within `revisit_mm` of a breadcrumb it left
//!   earlier (a breadcrumb is dropped every `crumb_mm` of travel; the two
//!   newest do not count).
//!
//! Then a virtual obstacle of radius `V_r` is dropped where the rover stands
//! (§3: "put a virtual obstacle there"). Its push is the §3 potential's: the
//! gradient of `K_v / r²` falls as the cube of the distance, so a virtual
//! obstacle pushes with `p · (V_r / r)³` at `r` from its centre and with `p`
//! inside its radius (finite there, where §3's is infinite), `p = K_v / V_r²`
//! its push at the rim, away from `V` (away from the goal for a rover
//! standing exactly on it). `K_v` = 0.1 makes `p` 4.4 units, about twice
//! the attraction: enough to destroy the minimum, not so much that the
//! rover flees; the cube keeps the push local (1/8 of it at twice the
//! radius), so the obstacles of one pit do not push the rover out of the
//! next passage. The pit fills and the rover spills out of it.
//!
//! A drop within [`VIRTUAL_MERGE_MM`] of a virtual obstacle already held
//! adds to that one's weight instead of taking a slot: a rover stuck turning
//! in place drops one every few cycles on the same spot, and an obstacle of
//! weight `w` repels exactly as `w` obstacles there would, for the cost of one.
//!
//! Reach: an obstacle is skipped where its push has fallen below
//! [`VIRTUAL_MIN_PUSH`] (1/32 of a force unit, 1/64 of the attraction, under
//! a degree of heading); that distance, rounded up to an eighth of the
//! radius, is kept with it, so the test is two compares instead of a
//! division (5.25 radii, 788 mm, for one drop with the defaults).
//!
//! Bounded memory: at most [`VIRTUAL_CAPACITY`] virtual obstacles,
//! [`CRUMB_CAPACITY`] breadcrumbs and [`WINDOW_CAPACITY`] recent positions;
//! when full, the oldest is dropped (the newest describe the pit the rover
//! is in now).
//!
//! Retreat: a step away from the goal (a
//! heading more than 90° off its bearing) is at most `retreat_mm` plus
//! `retreat_per_drop_mm` for every virtual obstacle dropped since the rover
//! last came nearer the goal. The droplet rises only as far as the level in
//! its pit: pushed off a blocked stretch of a wall of obstacles, the rover
//! slides along it a little way back and tries the next gap, instead of
//! running a whole sensor range (0.8 m) back across open ground and meeting
//! the wall somewhere else; a deep pit (a dead end, a U) fills drop by drop
//! and lets it go as far back as it must (a shortened retreat step after a
//! turn of more than 20° waits a cycle: the planner's retreat rule).
//! Measured with the defaults [`RETREAT_MM`] and [`RETREAT_PER_DROP_MM`]
//! (the commit history, "The retreat"): shorter paths, more goals reached, no
//! more collisions than without it (`retreat_mm` 0).
//!
//! Give-up: when `give_up_drops` virtual obstacles have been dropped, or
//! `give_up_steps` cycles have passed, since the rover last came
//! `progress_mm` nearer the goal than ever before, escape is making no
//! progress (a walled-in goal never lets the best distance improve). With
//! `follow` set (the default) the planner then follows boundaries (the
//! `follow` module), which reports a walled-in goal unreachable when it
//! has been all round twice (after the first loop the escape runs again,
//! its count started afresh: [`Escape::again`]); without it the goal is
//! reported unreachable at once. The default budget, 200 cycles, hands
//! over once a second 200 would do less than the follower
//! (the commit history).

use crate::fixed::{
    box_within, inverse_square_force, isqrt, within, Angle, Force, Point, FORCE_ONE, FORCE_SHIFT,
    MAX_SCALED,
};
use crate::ring::Ring;
use heapless::Deque;

/// Most virtual obstacles kept.
pub const VIRTUAL_CAPACITY: usize = 24;
/// A drop nearer than this (mm) to a held virtual obstacle strengthens it,
/// for the cost of one term in every later sum. 40 mm rather than 16: with
/// 16 the STM32's worst replayed step went over issue 6's 3,000
/// instructions, at outcomes within noise of these (the commit history, "The
/// inverse-cube push").
pub const VIRTUAL_MERGE_MM: u16 = 40;
/// A virtual obstacle whose push is below this (Q10) is skipped.
pub const VIRTUAL_MIN_PUSH: i32 = FORCE_ONE / 32;
/// The strongest push of one drop, at its rim (Q10: just under 64 force
/// units, 32 times the attraction; the default is 4.4). It bounds the
/// products of [`Escape::force`] below 2^32.
pub const MAX_PUSH: i32 = u16::MAX as i32;
/// The default [`EscapeConfig::retreat_mm`], mm (measured: the commit history,
/// "The retreat").
pub const RETREAT_MM: u16 = 100;
/// The default [`EscapeConfig::retreat_per_drop_mm`], mm.
pub const RETREAT_PER_DROP_MM: u16 = 40;
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
    /// Longest step away from the goal while no virtual obstacle has been
    /// dropped since the last progress, mm (10 ..= 5000; 0: no retreat
    /// limit).
    pub retreat_mm: u16,
    /// How much longer such a step may be for each virtual obstacle
    /// dropped since the last progress, mm (0 ..= 5000).
    pub retreat_per_drop_mm: u16,
    /// Whether a give-up hands over to boundary following (the `follow`
    /// module) instead of reporting the goal unreachable at once.
    pub follow: bool,
}

impl Default for EscapeConfig {
    fn default() -> Self {
        EscapeConfig::DEFAULT
    }
}

impl EscapeConfig {
    /// The defaults (also `Default::default()`; this one is usable in a
    /// `const`).
    pub const DEFAULT: EscapeConfig = EscapeConfig {
        enabled: true,
        window_steps: 12,
        stuck_mm: 150,
        crumb_mm: 400,
        revisit_mm: 150,
        progress_mm: 100,
        radius_mm: 150,
        k_v: FORCE_ONE / 10,
        give_up_drops: 40,
        give_up_steps: 200,
        retreat_mm: RETREAT_MM,
        retreat_per_drop_mm: RETREAT_PER_DROP_MM,
        follow: true,
    };

    /// Whether every field is in its documented range.
    pub const fn is_valid(&self) -> bool {
        use crate::fixed::in_range;
        in_range(self.window_steps as i32, 2, WINDOW_CAPACITY as i32)
            && in_range(self.crumb_mm as i32, 20, 5_000)
            && self.revisit_mm < self.crumb_mm
            && self.stuck_mm <= 5_000
            && in_range(self.give_up_steps as i32, 10, 60_000)
            && in_range(self.progress_mm as i32, 1, 2_000)
            && in_range(self.radius_mm as i32, 10, 2_000)
            && in_range(self.k_v, 1, 16 * FORCE_ONE)
            && in_range(self.give_up_drops as i32, 1, 1_000)
            && (self.retreat_mm == 0 || in_range(self.retreat_mm as i32, 10, 5_000))
            && self.retreat_per_drop_mm <= 5_000
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
        VirtualObstacle {
            centre,
            weight,
            reach_mm: reach_mm(&Law::of(cfg), weight),
        }
    }
}

/// The push law's constants, worked out from the configuration at the
/// first drop rather than for every obstacle of every cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Law {
    /// `V_r`, mm, and `K_v` (Q10): the configuration the law is of.
    radius_mm: u16,
    k_v: i32,
    /// `p`: the push of one drop at the rim, `K_v / V_r²` in Q10 force
    /// units (`V_r` below 91 mm counts as 91 mm here, as in
    /// [`inverse_square_force`]), at most [`MAX_PUSH`].
    rim: u16,
    /// `V_r²` in mm², shifted right by `shift` below 2^16, so that
    /// `rim_sq << 15` plus half of any `s` fits.
    rim_sq: u16,
    shift: u8,
    /// `2^16 / V_r`, rounded: a multiply instead of a division by `V_r`
    /// per component (0.1 % off at the default 150 mm, 1.5 % at 2 m).
    per_radius_q16: u16,
    /// The reach of one drop in eighths of `V_r` (the search's `h`; most
    /// drops are new obstacles), which also bounds the search for more.
    h_one: u16,
}

impl Law {
    /// No law yet (no drop): zero push, no reach.
    const NONE: Law = Law {
        radius_mm: 0,
        k_v: 0,
        rim: 0,
        rim_sq: 0,
        shift: 0,
        per_radius_q16: 0,
        h_one: 0,
    };

    fn of(cfg: &EscapeConfig) -> Law {
        let v_r = cfg.radius_mm.max(1) as u32;
        let rim =
            ((inverse_square_force(cfg.radius_mm) >> 4) * cfg.k_v.max(0)) >> (FORCE_SHIFT - 4);
        let mut rim_sq = v_r * v_r;
        let mut shift = 0;
        while rim_sq >= 1 << 16 {
            rim_sq >>= 1;
            shift += 1;
        }
        let rim = rim.clamp(0, MAX_PUSH) as u16;
        let h_one = eighths(rim, 1, 0, 1_024);
        Law {
            radius_mm: cfg.radius_mm,
            k_v: cfg.k_v,
            rim,
            rim_sq: rim_sq as u16,
            shift,
            // 6,554 at most (V_r ≥ 10 mm).
            per_radius_q16: (((1 << 16) + v_r / 2) / v_r) as u16,
            h_one: h_one as u16,
        }
    }

    /// Whether this is the law of `cfg` (a drop works it out again only
    /// when not: two divisions and a search saved on every later drop).
    #[cfg_attr(target_arch = "avr", inline(never))]
    fn is_of(&self, cfg: &EscapeConfig) -> bool {
        self.radius_mm == cfg.radius_mm && self.k_v == cfg.k_v
    }
}

/// The push `p` of an obstacle the rover stands exactly on: straight away
/// from the goal. Out of line and cold: LLVM would otherwise work out its
/// sine and cosine before the loop, on every call, for a case that almost
/// never comes.
#[cold]
#[inline(never)]
fn away_from_goal(bearing: Angle, rim: u32) -> Force {
    const _: () = assert!(MAX_PUSH <= MAX_SCALED);
    // `rim` is a `Law`'s, at most `MAX_PUSH`.
    Force::along_bounded(bearing.add(Angle::HALF), rim as i32)
}

/// Where the push of `weight` drops falls below [`VIRTUAL_MIN_PUSH`]:
/// `w·p·(V_r / r)³ < min` ⇔ `r > V_r · ∛(w·p / min)`, rounded up to an
/// eighth of `V_r` (the least `h` with `(h/8)³ · min ≥ w·p`, found by
/// halving), at most 32,767 mm (a push from farther is ignored: the world
/// is ±32 m).
fn reach_mm(law: &Law, weight: u8) -> u16 {
    let h = law.h_one as u32;
    let v_r = law.radius_mm.max(1) as u32;
    if weight == 1 {
        return reach_of(v_r, h);
    }
    // More drops never reach less: `h₁` is a lower bound. And `k³ ≥ w`
    // gives an upper one, `(k·h₁)³ ≥ k³·16·p ≥ 16·w·p`: a merge into a
    // held obstacle (most often its second drop) searches a few values,
    // not 1,024. (A walk up from `1.26·h₁` for the second drop, as it
    // once had, cost the AVR image 460 bytes for the same answer.)
    let hi = match weight {
        2..=8 => 2 * h,
        9..=27 => 3 * h,
        28..=64 => 4 * h,
        _ => 7 * h,
    };
    reach_of(v_r, eighths(law.rim, weight, h, hi))
}

/// The least `h` ≤ 1,024 with `h³ ≥ 16·w·p` for `p` = `rim`, `w` =
/// `weight`, searched by halving between `lo` (which must not be above it)
/// and `hi` (1,024 if `hi` does not satisfy it).
fn eighths(rim: u16, weight: u8, lo: u32, hi: u32) -> u32 {
    let need = need(rim, weight);
    let mut hi = hi.min(1_024);
    if hi * hi * hi < need {
        hi = 1_024;
    }
    let mut lo = lo.min(hi);
    while lo < hi {
        let h = (lo + hi) / 2;
        if h * h * h >= need {
            hi = h;
        } else {
            lo = h + 1;
        }
    }
    lo
}

/// `16·w·p`, the least `h³` a reach of `h` eighths of `V_r` needs:
/// `(h/8)³·32 ≥ w·p` ⇔ `h³ ≥ 16·w·p`; `w·p < 2^24`, so both sides < 2^30.
#[cfg_attr(target_arch = "avr", inline(never))]
fn need(rim: u16, weight: u8) -> u32 {
    const _: () = assert!(VIRTUAL_MIN_PUSH == 32);
    16 * rim as u32 * weight as u32
}

/// `h` eighths of `V_r` = `v_r` mm, rounded up, at most 32,767 mm.
#[cfg_attr(target_arch = "avr", inline(never))]
fn reach_of(v_r: u32, h: u32) -> u16 {
    (v_r * h).div_ceil(8).min(i16::MAX as u32) as u16
}

/// Progress monitor and virtual obstacles.
///
/// On the AVR its fields stay in this order (`repr(C)`, as `Planner`'s):
/// the counters and the law first, within a load's reach of the pointer,
/// the buffers after them (docs/performance.md).
#[derive(Clone, Debug)]
#[cfg_attr(target_arch = "avr", repr(C))]
pub struct Escape {
    best_mm: u16,
    since_best: u16,
    drops_since_best: u16,
    dropped: u16,
    /// The push law of the configuration of the last drop (a planner's
    /// configuration does not change).
    law: Law,
    /// The last answer of [`Escape::force_kept`] and its question (robot,
    /// bearing): a rover turning in place asks the same question every
    /// cycle, and a stuck one, surrounded by the obstacles it dropped, is
    /// where the sum costs most. A drop forgets it.
    kept_force: Option<(Point, Angle, Force)>,
    /// Where, and for which radius, the trail was last searched and no old
    /// breadcrumb was near, the trail unchanged since: a rover turning in
    /// place asks the same question every cycle.
    no_revisit_at: Option<(Point, u16)>,
    obstacles: Ring<VirtualObstacle, VIRTUAL_CAPACITY>,
    recent: Deque<Point, WINDOW_CAPACITY>,
    crumbs: Deque<Point, CRUMB_CAPACITY>,
}

impl Default for Escape {
    fn default() -> Self {
        Escape::new()
    }
}

impl Escape {
    /// No history.
    ///
    /// Always inlined: otherwise the AVR builds it in a 185-byte temporary
    /// and copies it into the planner, and at start-up that temporary sits
    /// on the stack beside the configuration's copy, past the RAM there is
    /// (`tests/src/stack_bound.rs` bounds the stack).
    #[inline(always)]
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
            law: Law::NONE,
        }
    }

    /// Start the give-up count again, keeping the virtual obstacles (the
    /// boundary follower's loop closed once: see `Planner::step_raw`).
    pub fn again(&mut self) {
        self.best_mm = u16::MAX;
        self.since_best = 0;
        self.drops_since_best = 0;
    }

    /// Forget everything (a new goal).
    pub fn reset(&mut self) {
        *self = Escape::new();
    }

    /// Account for one planner cycle with the rover at `robot`, `goal_mm`
    /// from the goal.
    ///
    /// Out of line on the AVR (docs/performance.md, "Inlining on the AVR").
    #[cfg_attr(target_arch = "avr", inline(never))]
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
    #[cfg_attr(target_arch = "avr", inline(never))]
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
        if !self.law.is_of(cfg) {
            self.law = Law::of(cfg);
        }
        let law = &self.law;
        let new = |centre, weight| VirtualObstacle {
            centre,
            weight,
            reach_mm: reach_mm(law, weight),
        };
        self.drops_since_best = self.drops_since_best.saturating_add(1);
        let held = self.obstacles.iter_mut().find(|v| {
            // `within`'s box test first, as in `any_within`.
            box_within(v.centre, robot, VIRTUAL_MERGE_MM)
                && within(v.centre, robot, VIRTUAL_MERGE_MM)
        });
        if let Some(v) = held {
            *v = new(v.centre, v.weight.saturating_add(1));
        } else {
            self.obstacles.push(new(robot, 1));
        }
        self.dropped = self.dropped.saturating_add(1);
    }

    /// The summed repulsion of the virtual obstacles on the rover at
    /// `robot`, whose goal bearing is `bearing`: `w·p·(V_r / r)³` each
    /// (`w·p` inside `V_r`), along the unit vector `(dx, dy) / r` from the
    /// obstacle's centre, with the law of the configuration they were
    /// dropped with; computed as components: no angle, so no `atan2` and no
    /// sine per obstacle. Outside `V_r` the components are
    /// `p·(V_r²/s)²·(dx, dy)/V_r` with `s = r²`: one division and no square
    /// root per obstacle (inside, where the push is constant, a root).
    #[inline(never)]
    pub fn force(&self, robot: Point, bearing: Angle) -> Force {
        let law = &self.law;
        let (rim, rim_sq) = (law.rim as u32, law.rim_sq as u32);
        let per_radius_q16 = law.per_radius_q16 as u32;
        // At most 24 terms below 2^24 each: the sum stays below 2^29, so a
        // plain add, and the slot order does not change it.
        let mut f = Force::ZERO;
        for v in self.obstacles.as_slice() {
            // The reach test in 16 bits (`abs_diff` of two i16 is exact).
            let (ax, ay) = (v.centre.x.abs_diff(robot.x), v.centre.y.abs_diff(robot.y));
            if ax >= v.reach_mm || ay >= v.reach_mm {
                continue;
            }
            // |dx|, |dy| < reach ≤ 2^15 − 1: s < 2^31.
            let (ax, ay) = (ax as u32, ay as u32);
            let s = ax * ax + ay * ay;
            let one = if s >= rim_sq << law.shift {
                // t = V_r²/s ≤ 1 in Q15, rounded. The push is p·t², and
                // its component along x is p·t·(t·|dx|/V_r): the first
                // factor ≈ p·(V_r/r)² ≤ 2^16, the second ≈ 2^15·(V_r/r)·
                // (|dx|/r) ≤ 2^15 (1.6 % more at most, from rounding
                // 2^16/V_r), so every product stays below 2^32 and neither
                // loses the small pushes' bits.
                let s = (s >> law.shift).max(1);
                // Both fit 16 bits (t ≤ 2^15, so p·t/2^15 ≤ p ≤
                // MAX_PUSH): on the AVR the loop then spills less.
                let t = (((rim_sq << 15) + s / 2) / s) as u16 as u32;
                let pt = ((rim * t + (1 << 14)) >> 15) as u16 as u32;
                // Always inlined, not a closure: as a closure LLVM's AVR
                // code for the loop is slower.
                #[inline(always)]
                fn along(negative: bool, a: u32, (t, per_radius_q16): (u32, u32), pt: u32) -> i32 {
                    let u = (t * a * per_radius_q16 + (1 << 15)) >> 16;
                    let m = ((pt * u + (1 << 14)) >> 15) as i32;
                    if negative {
                        -m
                    } else {
                        m
                    }
                }
                // On the AVR, where a multiply is a call, t·(2^16/V_r) once
                // for both axes: t ≤ 2^15 and 2^16/V_r ≤ 6,554 (V_r ≥ 10
                // mm), so it is below 2^28, and times |dx| it is the same
                // product as in the other order, below 2^32. (Elsewhere the
                // other order, which the STM32 does in fewer instructions.)
                let factors = if cfg!(target_arch = "avr") {
                    (t * per_radius_q16, 1)
                } else {
                    (t, per_radius_q16)
                };
                // The signs of robot − centre, by 16-bit compares.
                Force {
                    x: along(robot.x < v.centre.x, ax, factors, pt),
                    y: along(robot.y < v.centre.y, ay, factors, pt),
                }
            } else {
                let (dx, dy) = v.centre.to(robot);
                let r = isqrt(s) as u32;
                match ((rim << 12) + r / 2).checked_div(r) {
                    // p/r in Q12, rounded (p ≤ 2^16), then times |dx|, |dy|
                    // ≤ r: the products stay below p · 2^12 + r < 2^29.
                    Some(per_mm) => Force {
                        x: (dx * per_mm as i32 + (1 << 11)) >> 12,
                        y: (dy * per_mm as i32 + (1 << 11)) >> 12,
                    },
                    _ => away_from_goal(bearing, rim),
                }
            };
            // |one| ≤ 2^16 and weight ≤ 255: the products fit in i32. Most
            // obstacles are single drops; on the AVR a multiply is a call.
            let w = v.weight as i32;
            let one = if cfg!(target_arch = "avr") && w == 1 {
                one
            } else {
                Force {
                    x: one.x * w,
                    y: one.y * w,
                }
            };
            f = f.plus_bounded(one);
        }
        f
    }

    /// [`Escape::force`] for the planner: the answer is kept, and given
    /// again while the rover stands where it stood, facing the same goal
    /// bearing, and no obstacle has been dropped.
    #[cfg_attr(target_arch = "avr", inline(never))]
    pub(crate) fn force_kept(&mut self, robot: Point, bearing: Angle) -> Force {
        match self.kept_force {
            Some((at, b, f)) if at == robot && b == bearing => f,
            _ => {
                let f = self.force(robot, bearing);
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

    /// The longest step away from the goal allowed now (see "Retreat" in
    /// the module docs), mm; `None` (no limit) when the retreat or the
    /// escape is off (plain EAPF).
    pub fn retreat_limit_mm(&self, cfg: &EscapeConfig) -> Option<u16> {
        if !cfg.enabled || cfg.retreat_mm == 0 {
            return None;
        }
        let more = cfg
            .retreat_per_drop_mm
            .saturating_mul(self.drops_since_best);
        Some(more.saturating_add(cfg.retreat_mm))
    }
}

/// Whether any of `points` is within `r_mm` of `robot`. Out of line: it
/// runs on both halves of a deque, and the AVR pays for each copy.
#[inline(never)]
fn any_within(points: &[Point], robot: Point, r_mm: u16) -> bool {
    // `within`'s own box test first, here: most crumbs fail it, and then
    // no call is made.
    points
        .iter()
        .any(|&c| box_within(c, robot, r_mm) && within(c, robot, r_mm))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_strongest_full_set_of_virtual_obstacles_sums_without_overflow() {
        // The force sum is a plain add on the bound that every term is
        // below 2^24 (a push clamped at MAX_PUSH < 2^16, times a weight
        // up to 255) and there are at most VIRTUAL_CAPACITY of them. The
        // extreme: the largest K_v, every slot of weight 255 on one spot
        // right behind the rover, all pushing the same way.
        let cfg = EscapeConfig {
            k_v: 16 * FORCE_ONE,
            ..EscapeConfig::default()
        };
        let robot = Point::new(0, 0);
        let strongest = VirtualObstacle::new(&cfg, Point::new(-100, 0), u8::MAX);
        let mut one = Escape::new();
        one.law = Law::of(&cfg);
        one.obstacles.push(strongest);
        let mut full = one.clone();
        for _ in 0..VIRTUAL_CAPACITY {
            full.obstacles.push(strongest);
        }
        let f1 = one.force(robot, Angle::ZERO);
        let f = full.force(robot, Angle::ZERO);
        assert_eq!(
            f1.x,
            MAX_PUSH * u8::MAX as i32,
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
                    let fresh = plain.force(robot, bearing);
                    proptest::prop_assert_eq!(kept.force_kept(robot, bearing), fresh);
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
    fn the_bounded_reach_search_is_the_plain_one() {
        // Every weight, pushes across the whole range: the bounds from one
        // drop's `h` change no reach.
        for rim in (0..=u16::MAX).step_by(251).chain([1, 2, 3, 7, u16::MAX]) {
            let h_one = eighths(rim, 1, 0, 1_024);
            let law = Law {
                rim,
                radius_mm: 150,
                h_one: h_one as u16,
                ..Law::NONE
            };
            for weight in 1..=u8::MAX {
                let plain = reach_of(150, eighths(rim, weight, 0, 1_024));
                assert_eq!(reach_mm(&law, weight), plain, "p={rim} w={weight}");
            }
        }
    }

    #[test]
    fn the_retreat_grows_with_the_drops_since_progress() {
        let cfg = EscapeConfig {
            window_steps: 2,
            retreat_mm: RETREAT_MM,
            ..EscapeConfig::default()
        };
        let mut e = Escape::new();
        let p = Point::new(0, 0);
        assert_eq!(e.observe(&cfg, p, 3_000), Verdict::Continue);
        assert_eq!(e.retreat_limit_mm(&cfg), Some(100));
        assert_eq!(e.observe(&cfg, p, 3_000), Verdict::Dropped);
        assert_eq!(e.retreat_limit_mm(&cfg), Some(140));
        e.observe(&cfg, p, 3_000);
        assert_eq!(e.observe(&cfg, p, 3_000), Verdict::Dropped);
        assert_eq!(e.retreat_limit_mm(&cfg), Some(180));
        // 200 mm nearer than ever: back to the shortest retreat.
        e.observe(&cfg, p, 2_800);
        assert_eq!(e.retreat_limit_mm(&cfg), Some(100));
        // Plain EAPF (no escape) and `retreat_mm` 0 have no limit; a huge
        // one saturates.
        let off = EscapeConfig {
            enabled: false,
            ..cfg
        };
        assert_eq!(e.retreat_limit_mm(&off), None);
        let none = EscapeConfig {
            retreat_mm: 0,
            ..cfg
        };
        assert_eq!(e.retreat_limit_mm(&none), None);
        assert!(none.is_valid() && EscapeConfig::default().is_valid());
        let huge = EscapeConfig {
            retreat_mm: 5_000,
            retreat_per_drop_mm: 5_000,
            ..cfg
        };
        e.observe(&cfg, p, 2_800);
        for _ in 0..40 {
            e.drop_at(p, &huge);
        }
        assert_eq!(e.retreat_limit_mm(&huge), Some(u16::MAX));
        assert!(huge.is_valid());
        assert!(!EscapeConfig {
            retreat_mm: 5,
            ..cfg
        }
        .is_valid());
    }

    #[test]
    fn virtual_obstacle_force_by_hand() {
        let cfg = EscapeConfig {
            k_v: FORCE_ONE,
            ..EscapeConfig::default()
        };
        let mut e = Escape::new();
        e.law = Law::of(&cfg);
        e.obstacles
            .push(VirtualObstacle::new(&cfg, Point::new(0, 0), 1));
        // K_v = 1, V_r = 0.15 m: p = 1/0.15² = 44.4 units (45,504 in Q10);
        // at twice the radius an eighth of it, 5,688, along +x (2^16/V_r
        // is rounded to 437: 0.02 % more).
        let f = e.force(Point::new(300, 0), Angle::ZERO);
        assert_eq!((f.x, f.y), (5_689, 0));
        // Inside the radius the push is p.
        let f = e.force(Point::new(0, 100), Angle::ZERO);
        assert_eq!((f.x, f.y), (0, 45_504));
        // Weight 3 repels three times as hard.
        *e.obstacles.iter_mut().next().unwrap() = VirtualObstacle::new(&cfg, Point::new(0, 0), 3);
        assert_eq!(
            e.force(Point::new(-300, 0), Angle::ZERO),
            Force {
                x: -3 * 5_689,
                y: 0
            }
        );
        // Weight 1 pushes with 1/32 unit at V_r·∛(45,504/32) = 1,686 mm;
        // its reach is that rounded up to an eighth of the radius, 90/8 of
        // it.
        *e.obstacles.iter_mut().next().unwrap() = VirtualObstacle::new(&cfg, Point::new(0, 0), 1);
        assert_eq!(e.obstacles().next().unwrap().reach_mm, 1_688);
        let push = |x, y| e.force(Point::new(x, y), Angle::ZERO);
        assert!(push(1_600, 0).x > VIRTUAL_MIN_PUSH);
        assert!((1..=VIRTUAL_MIN_PUSH).contains(&push(1_687, 0).x));
        assert_eq!(push(0, -1_688), Force::ZERO);
        assert_eq!(push(1_688, 1), Force::ZERO);
        // Exactly on it: away from the goal.
        let f = e.force(Point::new(0, 0), Angle::ZERO);
        assert!(f.x < -44 * 1024 && f.y == 0, "{f:?}");
        assert!(!EscapeConfig {
            window_steps: 0,
            ..cfg
        }
        .is_valid());
    }

    #[test]
    fn a_drop_with_another_configuration_works_out_its_law() {
        let stuck = |cfg: &EscapeConfig, e: &mut Escape| {
            for _ in 0..cfg.window_steps {
                e.observe(cfg, Point::new(0, 0), 1_000);
            }
        };
        let a = EscapeConfig {
            window_steps: 2,
            ..EscapeConfig::default()
        };
        let b = EscapeConfig {
            k_v: 3 * a.k_v,
            radius_mm: 2 * a.radius_mm,
            ..a
        };
        let mut e = Escape::new();
        stuck(&a, &mut e);
        assert_eq!(e.law, Law::of(&a));
        stuck(&b, &mut e);
        assert_eq!(e.law, Law::of(&b));
        assert_ne!(Law::of(&a), Law::of(&b));
    }

    #[test]
    fn reach_is_the_least_eighth_of_the_radius_past_the_smallest_push() {
        for radius_mm in [10, 91, 150, 1_000, 2_000] {
            for k_v in [1, FORCE_ONE / 10, FORCE_ONE, 16 * FORCE_ONE] {
                let cfg = EscapeConfig {
                    radius_mm,
                    k_v,
                    ..EscapeConfig::default()
                };
                let law = Law::of(&cfg);
                for weight in 1..=u8::MAX {
                    // By counting: the least h with (h/8)³·min ≥ w·p.
                    let wp = law.rim as u64 * weight as u64;
                    let h = (0u64..)
                        .find(|h| h * h * h * VIRTUAL_MIN_PUSH as u64 >= wp * 512)
                        .unwrap();
                    let want = (radius_mm as u64 * h).div_ceil(8).min(32_767);
                    assert_eq!(
                        reach_mm(&law, weight) as u64,
                        want,
                        "{radius_mm} {k_v} {weight}"
                    );
                }
            }
        }
    }

    proptest::proptest! {
        /// The fixed-point push against `w·p·(V_r/r)³` (`w·p` inside) in
        /// f64, for every valid radius and `K_v`: within 1 % plus the
        /// rounding of `2^16/V_r` (and 2 Q10 units for the smallest),
        /// along `(dx, dy)`.
        #[test]
        fn the_push_is_the_inverse_cube_law(
            radius_mm in 10u16..=2_000,
            k_v in 1i32..=16 * FORCE_ONE,
            weight in 1u8..=255,
            dx in -8_000i16..=8_000,
            dy in -8_000i16..=8_000,
        ) {
            let cfg = EscapeConfig { radius_mm, k_v, ..EscapeConfig::default() };
            let mut e = Escape::new();
            e.law = Law::of(&cfg);
            e.obstacles.push(VirtualObstacle::new(&cfg, Point::new(0, 0), weight));
            let f = e.force(Point::new(dx, dy), Angle::ZERO);
            let law = Law::of(&cfg);
            let (x, y) = (dx as f64, dy as f64);
            let r = x.hypot(y);
            let v_r = radius_mm as f64;
            proptest::prop_assume!(r > 0.0);
            let push = weight as f64 * law.rim as f64 * (v_r / r.max(v_r)).powi(3);
            let reach = e.obstacles().next().unwrap().reach_mm as f64;
            if x.abs() >= reach || y.abs() >= reach {
                proptest::prop_assert_eq!(f, Force::ZERO);
                proptest::prop_assert!(push < VIRTUAL_MIN_PUSH as f64 * 1.001 || r > 32_767.0);
            } else {
                let per = ((1u32 << 16) + radius_mm as u32 / 2) / radius_mm as u32;
                let off = (per as f64 * v_r / 65_536.0 - 1.0).abs();
                // Inside V_r the unit vector divides by an integer root.
                let root = if r < v_r { push / r } else { 0.0 };
                let tol = |want: f64| want.abs() * (0.01 + off) + 2.0 * weight as f64 + root;
                let (wx, wy) = (push * x / r, push * y / r);
                proptest::prop_assert!((f.x as f64 - wx).abs() <= tol(wx), "x {} want {}", f.x, wx);
                proptest::prop_assert!((f.y as f64 - wy).abs() <= tol(wy), "y {} want {}", f.y, wy);
            }
        }
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
        // Farther than the merge distance is a new one.
        let beyond = Point::new(1_005 + VIRTUAL_MERGE_MM as i16, 500);
        e.observe(&cfg, beyond, 1_000);
        e.observe(&cfg, beyond, 1_000);
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
        let apart = VIRTUAL_MERGE_MM as i16 + 4;
        for i in 0..(2 * (VIRTUAL_CAPACITY as i16 + 5)) {
            e.observe(&cfg, Point::new(apart * i, 0), 1_000);
        }
        assert!(e.dropped() as usize > VIRTUAL_CAPACITY);
        assert_eq!(e.len(), VIRTUAL_CAPACITY);
    }
}
