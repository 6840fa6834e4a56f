//! Planning with the free-space assumption (Koenig, Tovey & Smirnov 2003,
//! "Performance bounds for planning in unknown terrain"; the navigation
//! behind D* Lite): the rover keeps a coarse grid of what its beams have
//! shown blocked, takes every cell it has not seen blocked as free, plans
//! the shortest way to the goal over that grid, and drives along the plan
//! until what it sees changes it.
//!
//! - **The grid**: `N`×`N` cells of [`CELL_MM`], centred between the start
//!   and the goal. Each cell holds evidence: a beam that ends in it adds
//!   [`HIT`], a beam that passes through it takes one away. A cell with at
//!   least [`BLOCKED`] is blocked. The disc rule: a cell is passable when
//!   no cell within two cells of it (the 5×5 block less its corners) is
//!   blocked: the rover's radius and the safety rule's margin, 140 mm, are
//!   a little over two cells.
//! - **The plan**: a breadth-first wave from the goal over passable cells
//!   (four neighbours), worked out again whenever a cell changed. Where it
//!   does not reach the rover, a second wave squeezes: a cell is passable
//!   when no cell next to it is blocked (the disc alone, without the
//!   margin; the safety rule decides each step).
//! - **The way**: from the rover's cell down the wave, the farthest cell
//!   within [`LOOK_CELLS`] that the straight line reaches over passable
//!   cells, and advance towards it as far as the safety rule allows.
//! - **Look before a turn** (ours): a way outside the sensed sector is
//!   turned to on the spot, past it by the sector's half width (less
//!   [`LOOK_SLACK`], so that the way is inside the sector next), so that
//!   the beams see the flank the disc will sweep on that side (40° to 80°
//!   off the way), which no beam of the new heading sees: a door's jamb
//!   beside the rover. The next cycle's way is at the sector's edge; the
//!   safety rule keeps what the look saw ([`super::Seen`]).
//! - **Blocked way**: where the safety rule refuses the plan's way, the
//!   free beam that ends lowest on the wave is taken if it is lower than
//!   the rover's cell; else the cell ahead and the next cell down the wave
//!   are marked blocked (so that the next plan goes round them) and the
//!   rover turns on the spot to look.
//! - **Unreachable** when the wave does not reach the rover: walls seen
//!   all round the goal or the rover. Before that is said, the rover looks
//!   round on the spot for [`LOOKS`] cycles and forgets one degree of every
//!   cell's evidence, [`FORGETS`] times (a gap closed by a faint or
//!   inferred block opens; walls seen from several views stay).
//!
//! Memory: the grid is 7 bytes a cell (evidence, two block counts, the
//! wave and the wave's queue), 448 KB at `N` = 256 (16.4 m square): a planner
//! for the simulator and the STM32's class of memory, not the AVR's.

use super::{begin, Senses, FREE_STEP_MM};
use crate::eapf::command::{Output, Status};
use crate::eapf::config::Config;
use crate::eapf::sensors::{RawCounts, SENSOR_COUNT};
use crate::fixed::{Angle, Point};
use crate::Pose;

/// A cell's side, mm (a power of two: a cell index is a shift).
pub const CELL_MM: u16 = 64;
/// [`CELL_MM`] as a shift.
const CELL_SHIFT: u32 = 6;
/// Evidence a beam's end adds to its cell.
pub const HIT: u8 = 3;
/// Evidence at which a cell is blocked.
pub const BLOCKED: u8 = 3;
/// Most evidence a cell holds.
const MOST: u8 = 9;
/// How far along the plan the rover looks for a straight way, cells.
pub const LOOK_CELLS: u16 = 16;
/// Times the evidence is weakened before a goal without a way is
/// unreachable.
pub const FORGETS: u8 = 3;
/// A beam clears a cell only where it passes within this of the cell's
/// centre (either axis), mm: one that grazes the cell's edge passes by
/// what made it blocked (a thin wall's end in a 64 mm cell).
const CORE_MM: i32 = 16;
/// A rover whose own cell the wave does not reach (a wall within two
/// cells) heads for the best reached cell this many cells round it.
const NEAR_CELLS: usize = 2;
/// Cycles without a way, each a look by the sector's width on the spot (a
/// whole turn at 40°), before the evidence is weakened.
pub const LOOKS: u8 = 9;
/// A look before a turn goes past the way by the sector's half width less
/// this.
pub const LOOK_SLACK: Angle = Angle::from_deg(5);
/// Not reached by the wave.
const FAR: u16 = u16::MAX;

/// The grid of `N`×`N` cells, row by row (`[y][x]`), and the wave over
/// it towards one goal.
#[derive(Clone, Debug)]
pub struct Grid<const N: usize> {
    evidence: [[u8; N]; N],
    /// Blocked cells within two cells of each cell (the 5×5 block less its
    /// corners), and within one (the 3×3 block).
    near: [[u8; N]; N],
    close: [[u8; N]; N],
    /// The wave's distance to the goal, cells (`FAR`: not reached).
    wave: [[u16; N]; N],
    /// The wave's queue of cell indices (`y·N + x`), N×N as N rows.
    queue: [[u16; N]; N],
    /// World mm of cell (0, 0)'s corner.
    origin: (i32, i32),
    goal: Point,
    /// The rover's radius, mm (the straight way's first stretch is its own
    /// disc).
    radius_mm: u16,
    /// A cell changed since the wave was worked out.
    changed: bool,
    /// Times the evidence was weakened for want of a way.
    forgets: u8,
    /// Cycles without a way since the last weakening.
    waiting: u8,
}

impl<const N: usize> Grid<N> {
    /// A cell index fits a `u16` (the wave's queue).
    const FITS: () = assert!(N >= 8 && N <= 256);

    /// An empty grid centred between `start` and `goal`, for a rover of
    /// `radius_mm`.
    pub fn new(start: Point, goal: Point, radius_mm: u16) -> Self {
        let () = Self::FITS;
        let half = (N as i32 * CELL_MM as i32) / 2;
        let mid = (
            (start.x as i32 + goal.x as i32) / 2,
            (start.y as i32 + goal.y as i32) / 2,
        );
        Grid {
            evidence: [[0; N]; N],
            near: [[0; N]; N],
            close: [[0; N]; N],
            wave: [[FAR; N]; N],
            queue: [[0; N]; N],
            origin: (mid.0 - half, mid.1 - half),
            goal,
            radius_mm,
            changed: true,
            forgets: 0,
            waiting: 0,
        }
    }

    /// Whether `p` is in a blocked cell.
    pub fn blocked(&self, p: Point) -> bool {
        self.cell(p)
            .is_some_and(|(x, y)| self.evidence[y][x] >= BLOCKED)
    }

    /// The next point to drive to from `robot`: the farthest cell down the
    /// wave that a straight line reaches (the wave worked out again first
    /// if a cell changed). With no way, `Err(true)`: look round; every
    /// [`LOOKS`] such cycles the evidence is weakened, and after
    /// [`FORGETS`] weakenings `Err(false)`: unreachable.
    pub fn next(&mut self, robot: Point) -> Result<Point, bool> {
        if self.changed {
            self.plan(false);
            // No way with the disc's margin: squeeze, with the disc alone.
            if self.way(robot).is_none() {
                self.plan(true);
            }
        }
        match self.way(robot) {
            Some(to) => Ok(to),
            // What was seen only faintly, or inferred from a refused
            // step, may have closed a gap: forget one degree of every
            // cell's evidence; walls seen from several views stay.
            None if self.forgets < FORGETS => {
                self.waiting += 1;
                if self.waiting >= LOOKS {
                    self.waiting = 0;
                    self.forgets += 1;
                    self.forget();
                }
                Err(true)
            }
            None => Err(false),
        }
    }

    /// What a beam from `from` shows: it passes through cells (less
    /// evidence) and, if it `hit` something, ends in one (more).
    pub fn see(&mut self, from: Point, end: Point, hit: bool) {
        let Some(end_cell) = self.cell(end) else {
            return;
        };
        let len = from.distance_mm(end) as i32;
        let mut last = None;
        let mut s = 0;
        while s < len {
            let p = along(from, end, s, len);
            if let Some(c) = self.cell(p) {
                let (cx, cy) = p.to(self.centre(c));
                let core = cx.abs() <= CORE_MM && cy.abs() <= CORE_MM;
                if core && c != end_cell && Some(c) != last {
                    self.add(c, -1);
                    last = Some(c);
                }
            }
            s += CORE_MM;
        }
        if hit {
            self.add(end_cell, HIT as i8);
        }
    }

    /// The cell a rover at `from` heading `heading` would enter next
    /// beyond its disc: blocked.
    pub fn mark_ahead(&mut self, from: Point, heading: Angle) {
        let ahead = from.offset(heading, self.radius_mm + CELL_MM);
        if let Some(c) = self.cell(ahead) {
            self.block(c);
        }
    }

    /// The cell after the rover's down the wave: blocked.
    pub fn mark_next(&mut self, robot: Point) {
        let Some(here) = self.cell(robot) else { return };
        let w = self.wave[here.1][here.0];
        let next = neighbours8(here.0, here.1, N)
            .filter(|&(x, y)| self.wave[y][x] < w)
            .min_by_key(|&(x, y)| self.wave[y][x]);
        if let Some(c) = next {
            self.block(c);
        }
    }

    /// The wave at `p`'s cell (`FAR` outside the grid or not reached).
    pub fn wave_at(&self, p: Point) -> u16 {
        self.cell(p).map_or(FAR, |(x, y)| self.wave[y][x])
    }

    /// Whether the straight line from `a` to `b` crosses only cells the
    /// wave reached (the first `radius_mm`, the rover's own disc, excepted).
    pub fn straight(&self, a: Point, b: Point) -> bool {
        let len = a.distance_mm(b) as i32;
        let mut s = (self.radius_mm as i32).min(len);
        while s <= len {
            match self.cell(along(a, b, s, len)) {
                Some((x, y)) if self.wave[y][x] != FAR => {}
                _ => return false,
            }
            s += CELL_MM as i32 / 2;
        }
        true
    }

    /// Blocked, at least.
    fn block(&mut self, (x, y): (usize, usize)) {
        let e = self.evidence[y][x];
        self.add((x, y), BLOCKED.saturating_sub(e) as i8);
    }

    /// Weaken every cell's evidence by one.
    fn forget(&mut self) {
        for y in 0..N {
            for x in 0..N {
                if self.evidence[y][x] > 0 {
                    self.add((x, y), -1);
                }
            }
        }
        self.changed = true;
    }

    /// The cell of `p`, if inside the grid.
    fn cell(&self, p: Point) -> Option<(usize, usize)> {
        let x = (p.x as i32 - self.origin.0) >> CELL_SHIFT;
        let y = (p.y as i32 - self.origin.1) >> CELL_SHIFT;
        ((0..N as i32).contains(&x) && (0..N as i32).contains(&y))
            .then_some((x as usize, y as usize))
    }

    /// A cell's centre, world mm.
    fn centre(&self, (x, y): (usize, usize)) -> Point {
        let c = |o: i32, i: usize| o + ((i as i32) << CELL_SHIFT) + CELL_MM as i32 / 2;
        Point::saturating(c(self.origin.0, x), c(self.origin.1, y))
    }

    /// Change a cell's evidence by `delta`, keeping the counts of blocked
    /// cells near each cell.
    fn add(&mut self, (x, y): (usize, usize), delta: i8) {
        let e = &mut self.evidence[y][x];
        let was = *e >= BLOCKED;
        *e = if delta >= 0 {
            e.saturating_add(delta as u8).min(MOST)
        } else {
            e.saturating_sub(delta.unsigned_abs())
        };
        let now = *e >= BLOCKED;
        if was == now {
            return;
        }
        self.changed = true;
        for ny in y.saturating_sub(2)..=(y + 2).min(N - 1) {
            for nx in x.saturating_sub(2)..=(x + 2).min(N - 1) {
                if ny.abs_diff(y) == 2 && nx.abs_diff(x) == 2 {
                    continue;
                }
                let n = &mut self.near[ny][nx];
                *n = if now { *n + 1 } else { *n - 1 };
                if ny.abs_diff(y) <= 1 && nx.abs_diff(x) <= 1 {
                    let c = &mut self.close[ny][nx];
                    *c = if now { *c + 1 } else { *c - 1 };
                }
            }
        }
    }

    /// The wave from the goal over passable cells (breadth first: every
    /// cell enters the queue once, so a queue of N×N cells never
    /// overflows).
    fn plan(&mut self, tight: bool) {
        self.changed = false;
        let open = |near: u8, close: u8| if tight { close == 0 } else { near == 0 };
        for row in self.wave.iter_mut() {
            row.fill(FAR);
        }
        let Some(goal) = self.cell(self.goal) else {
            return;
        };
        self.wave[goal.1][goal.0] = 0;
        let (mut head, mut tail) = (0usize, 1usize);
        self.queue[0][0] = (goal.1 * N + goal.0) as u16;
        while head < tail {
            let i = self.queue[head / N][head % N] as usize;
            head += 1;
            let (x, y) = (i % N, i / N);
            let d = self.wave[y][x];
            for (nx, ny) in neighbours(x, y, N) {
                if self.wave[ny][nx] == FAR && open(self.near[ny][nx], self.close[ny][nx]) {
                    self.wave[ny][nx] = d + 1;
                    self.queue[tail / N][tail % N] = (ny * N + nx) as u16;
                    tail += 1;
                }
            }
        }
    }

    /// The farthest cell down the wave from `robot` (up to
    /// [`LOOK_CELLS`]) with a straight way over reached cells, or the goal
    /// if that is in reach. `None`: the wave does not reach the rover.
    fn way(&self, robot: Point) -> Option<Point> {
        let here = self.cell(robot)?;
        // The rover's own cell may be near a blocked one (a wall within
        // two cells): start from the best cell near it then.
        let mut at = here;
        if self.wave[at.1][at.0] == FAR {
            at = self.best_near(here)?;
        }
        let goal_cell = self.cell(self.goal);
        let mut pick = self.centre(at);
        for _ in 0..LOOK_CELLS {
            if Some(at) == goal_cell {
                if self.straight(robot, self.goal) {
                    pick = self.goal;
                }
                break;
            }
            let w = self.wave[at.1][at.0];
            let Some(next) = neighbours8(at.0, at.1, N)
                .filter(|&(x, y)| self.wave[y][x] < w)
                .min_by_key(|&(x, y)| self.wave[y][x])
            else {
                break;
            };
            at = next;
            let c = self.centre(at);
            if self.straight(robot, c) {
                pick = c;
            }
        }
        Some(pick)
    }

    /// The reached cell within [`NEAR_CELLS`] of `c` with the least wave.
    fn best_near(&self, c: (usize, usize)) -> Option<(usize, usize)> {
        let mut best: Option<((usize, usize), u16)> = None;
        for y in c.1.saturating_sub(NEAR_CELLS)..=(c.1 + NEAR_CELLS).min(N - 1) {
            for x in c.0.saturating_sub(NEAR_CELLS)..=(c.0 + NEAR_CELLS).min(N - 1) {
                let w = self.wave[y][x];
                if w != FAR && best.is_none_or(|(_, b)| w < b) {
                    best = Some(((x, y), w));
                }
            }
        }
        best.map(|(c, _)| c)
    }
}

/// The free-space planner over an `N`×`N` grid, driven by its beams alone.
#[derive(Clone, Debug)]
pub struct FreeSpace<const N: usize> {
    pub(super) senses: Senses,
    goal: Point,
    grid: Grid<N>,
    unreachable: bool,
}

impl<const N: usize> FreeSpace<N> {
    /// The planner heading for `goal` from `start`, with the rover's
    /// `config`.
    pub fn new(config: Config, start: Point, goal: Point) -> Self {
        FreeSpace {
            grid: Grid::new(start, goal, config.robot_radius_mm),
            senses: Senses::new(config),
            goal,
            unreachable: false,
        }
    }

    /// The grid.
    pub fn grid(&self) -> &Grid<N> {
        &self.grid
    }

    /// One cycle from raw counts.
    pub fn step_raw(&mut self, pose: Pose, raw: &RawCounts) -> Output {
        if let Err(out) = begin(&mut self.senses, pose, raw, self.goal) {
            return out;
        }
        if self.unreachable {
            return self.senses.stop(pose, Status::Unreachable);
        }
        for i in 0..SENSOR_COUNT {
            let (end, hit) = self.senses.beam_end(pose, i);
            self.grid.see(pose.position, end, hit);
        }
        let to = match self.grid.next(pose.position) {
            Ok(to) => to,
            // No way yet: look round on the spot.
            Err(true) => {
                let half = self.senses.config().sector_half_width();
                return self.senses.command(pose, half.add(half), 0);
            }
            Err(false) => {
                self.unreachable = true;
                return self.senses.stop(pose, Status::Unreachable);
            }
        };
        let (dx, dy) = pose.position.to(to);
        let relative = Angle::atan2(dy, dx).sub(pose.heading);
        if !self.senses.in_sector(relative) {
            // Look before the turn (module docs), a little short of the
            // sector's edge so that the way is inside it next cycle.
            let half = self.senses.config().sector_half_width().sub(LOOK_SLACK);
            let past = if relative.signed() >= 0 {
                half
            } else {
                half.neg()
            };
            return self.senses.command(pose, relative.add(past), 0);
        }
        let want = FREE_STEP_MM.min(pose.position.distance_mm(to));
        let min = self.senses.config().min_step_mm;
        if self.senses.free_mm(pose, relative) >= min.min(want) {
            return self.senses.command(pose, relative, want);
        }
        // The safety rule refuses the plan's way (module docs, "blocked
        // way").
        let here = self.grid.wave_at(pose.position);
        let best = self
            .senses
            .config()
            .sensor_angles
            .into_iter()
            .filter_map(|a| {
                let way = self.senses.free_mm(pose, a).min(FREE_STEP_MM);
                (way >= min).then(|| {
                    let end = pose.position.offset(pose.heading.add(a), way);
                    (a, way, self.grid.wave_at(end))
                })
            })
            .min_by_key(|&(_, _, w)| w);
        match best {
            Some((a, way, w)) if w < here => self.senses.command(pose, a, way),
            _ => {
                self.grid
                    .mark_ahead(pose.position, pose.heading.add(relative));
                self.grid.mark_next(pose.position);
                let half = self.senses.config().sector_half_width();
                let turn = if relative.signed() >= 0 {
                    half
                } else {
                    half.neg()
                };
                self.senses.command(pose, turn, 0)
            }
        }
    }
}

/// The point `s` mm from `a` on the way to `b`, `len` mm away.
fn along(a: Point, b: Point, s: i32, len: i32) -> Point {
    let (dx, dy) = a.to(b);
    let len = len.max(1);
    Point::saturating(a.x as i32 + dx * s / len, a.y as i32 + dy * s / len)
}

/// The four neighbours of (x, y) inside an `n`×`n` grid.
fn neighbours(x: usize, y: usize, n: usize) -> impl Iterator<Item = (usize, usize)> {
    [(0, 1), (2, 1), (1, 0), (1, 2)]
        .into_iter()
        .filter_map(move |(ox, oy)| step(x, y, ox, oy, n))
}

/// The eight neighbours of (x, y) inside an `n`×`n` grid.
fn neighbours8(x: usize, y: usize, n: usize) -> impl Iterator<Item = (usize, usize)> {
    (0..9)
        .filter(|&k| k != 4)
        .filter_map(move |k| step(x, y, k % 3, k / 3, n))
}

fn step(x: usize, y: usize, ox: usize, oy: usize, n: usize) -> Option<(usize, usize)> {
    let nx = (x + ox).checked_sub(1)?;
    let ny = (y + oy).checked_sub(1)?;
    (nx < n && ny < n).then_some((nx, ny))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eapf::config::test_config;
    use crate::peers::tests::counts;

    type Small = FreeSpace<64>;

    fn at(x: i16, y: i16, deg: i16) -> Pose {
        Pose {
            position: Point::new(x, y),
            heading: Angle::from_deg(deg),
        }
    }

    fn blocked(p: &Small, at: Point) -> bool {
        p.grid.blocked(at)
    }

    /// A wall of blocked cells across x = `x_mm`, y from `y0` to `y1` mm.
    fn wall(p: &mut Small, x_mm: i16, y0: i16, y1: i16) {
        let mut y = y0;
        while y <= y1 {
            let c = p.grid.cell(Point::new(x_mm, y)).unwrap();
            p.grid.add(c, MOST as i8);
            y += CELL_MM as i16 / 2;
        }
    }

    #[test]
    fn a_beam_blocks_the_cell_it_ends_in_and_clears_those_it_crosses() {
        let cfg = test_config();
        let mut p = Small::new(cfg, Point::new(0, 0), Point::new(1_500, 0));
        // The rover on a row of cell centres (y = 32 mm), facing +x.
        let pose = at(0, 32, 0);
        let ahead = |x| Point::new(x, 32);
        // Something 700 mm on, seen before: a beam that now passes
        // through it weakens it.
        let c = p.grid.cell(ahead(700)).unwrap();
        p.grid.add(c, HIT as i8);
        let raw = counts(&cfg, [None, None, Some(300), None, None]);
        p.step_raw(pose, &raw);
        let end = p.senses.beam_end(pose, 2).0;
        assert!(blocked(&p, end));
        assert!(!blocked(&p, ahead(150)));
        // Beyond the front beam's end, and no side beam crosses it: it
        // stays.
        assert!(blocked(&p, ahead(700)));
        let raw = counts(&cfg, [None; SENSOR_COUNT]);
        p.step_raw(pose, &raw);
        assert!(!blocked(&p, ahead(700)));
        // A beam through a cell 24 mm off its centre (off its core)
        // leaves it.
        let c = p.grid.cell(ahead(500)).unwrap();
        p.grid.add(c, HIT as i8);
        p.step_raw(at(0, 32 + 24, 0), &raw);
        assert!(blocked(&p, ahead(500)));
        p.step_raw(pose, &raw);
        assert!(!blocked(&p, ahead(500)));
    }

    #[test]
    fn heads_straight_for_a_goal_in_free_space() {
        let cfg = test_config();
        let mut p = Small::new(cfg, Point::new(0, 0), Point::new(1_500, 0));
        let out = p.step_raw(at(0, 0, 0), &counts(&cfg, [None; SENSOR_COUNT]));
        // Towards a cell's centre a metre on: within half a cell.
        assert!(
            out.command.heading.abs_signed() < Angle::from_deg(2).0,
            "{out:?}"
        );
        assert_eq!(out.command.step_mm, FREE_STEP_MM);
        assert_eq!(out.status, Status::Moving);
    }

    #[test]
    fn the_plan_goes_round_a_wall_by_its_nearer_end() {
        let cfg = test_config();
        let goal = Point::new(1_500, 0);
        let mut p = Small::new(cfg, Point::new(0, 0), goal);
        // A wall across the way, its end 300 mm to the left (+y) and
        // 1,000 mm to the right.
        wall(&mut p, 600, -1_000, 300);
        p.grid.plan(false);
        let to = p.grid.way(Point::new(0, 0)).unwrap();
        assert!(to.y > 0, "round the left end: {to:?}");
        // Past the wall's end, nothing in between: the way is the goal.
        assert_eq!(p.grid.way(Point::new(1_000, 500)), Some(goal));
    }

    #[test]
    fn a_goal_walled_in_is_unreachable_after_the_forgets() {
        let cfg = test_config();
        let goal = Point::new(1_000, 0);
        let mut p = Small::new(cfg, Point::new(0, 0), goal);
        for x in [700, 1_300] {
            wall(&mut p, x, -300, 300);
        }
        for y in [-300, 300] {
            let mut x = 700;
            while x <= 1_300 {
                let c = p.grid.cell(Point::new(x, y)).unwrap();
                p.grid.add(c, MOST as i8);
                x += CELL_MM as i16 / 2;
            }
        }
        // Facing away from the box with nothing in view: no beam crosses
        // its walls.
        let clear = counts(&cfg, [None; SENSOR_COUNT]);
        let pose = at(0, 0, 180);
        for _ in 0..FORGETS as u16 * LOOKS as u16 {
            let out = p.step_raw(pose, &clear);
            assert_eq!(out.status, Status::Moving);
            assert_eq!(out.command.step_mm, 0);
        }
        assert_eq!(p.step_raw(pose, &clear).status, Status::Unreachable);
        assert_eq!(p.step_raw(pose, &clear).status, Status::Unreachable);
    }

    #[test]
    fn a_way_the_safety_rule_refuses_blocks_the_cell_ahead() {
        let cfg = test_config();
        let mut p = Small::new(cfg, Point::new(0, 0), Point::new(1_500, 0));
        let clear = counts(&cfg, [None; SENSOR_COUNT]);
        let out = p.step_raw(at(0, 0, 0), &clear);
        assert!(out.command.step_mm > 0);
        let ahead = Point::new(0, 0).offset(out.command.heading, cfg.robot_radius_mm + CELL_MM);
        assert!(!blocked(&p, ahead));
        // From the same spot, something too close to range in front: the
        // safety rule refuses the way and no free beam leads lower on the
        // wave.
        let mut near = clear;
        let cal = cfg.calibration();
        near[2] = (0..cal.full_scale())
            .rev()
            .find(|&c| cal.reading(c) == crate::eapf::sensors::Reading::TooClose)
            .unwrap();
        p.step_raw(at(0, 0, 0), &near);
        assert!(blocked(&p, ahead));
    }

    #[test]
    fn a_turn_looks_past_the_way_before_the_step() {
        let cfg = test_config();
        let mut p = Small::new(cfg, Point::new(0, 0), Point::new(0, 1_500));
        let clear = counts(&cfg, [None; SENSOR_COUNT]);
        // The goal 90° to the left: turn on the spot to 125°.
        let out = p.step_raw(at(0, 0, 0), &clear);
        assert_eq!(out.command.step_mm, 0);
        let past = out.command.heading.sub(Angle::from_deg(125));
        assert!(past.abs_signed() < Angle::from_deg(2).0, "{out:?}");
        // Then the way is near the sector's edge: step along it.
        let out = p.step_raw(at(0, 0, 125), &clear);
        assert!(out.command.step_mm > 0, "{out:?}");
        let off = out.command.heading.sub(Angle::QUARTER);
        assert!(off.abs_signed() < Angle::from_deg(3).0, "{out:?}");
    }
}
