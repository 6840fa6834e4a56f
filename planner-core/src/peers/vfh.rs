//! VFH+ (Ulrich & Borenstein 1998, "VFH+: reliable obstacle avoidance for
//! fast mobile robots", after VFH, Borenstein & Koren 1991), on five IR
//! beams.
//!
//! 1. **Certainty grid.** A square window of [`CELLS`]² cells of
//!    [`CELL_MM`] centred on the rover, stored as a torus in world cells
//!    (cells the window leaves are cleared as it moves). Each cycle each
//!    beam adds [`HIT`] to the cell where it ends on an obstacle and takes
//!    [`MISS`] from the cells it passes through (the HIMM update of VFH),
//!    values in 0 ..= [`C_MAX`].
//! 2. **Polar histogram** of [`SECTORS`] sectors: each occupied cell within
//!    the window's radius adds m = c² · (d_max − d) (VFH's `a − b·d`) to
//!    every sector within γ = asin(r_s / d) of its direction, r_s the
//!    robot's radius plus the clearance (VFH+'s enlargement).
//! 3. **Binary histogram** with two thresholds: a sector above
//!    [`TAU_HIGH`] is blocked, below [`TAU_LOW`] free, between them as it
//!    was (hysteresis). **Masking** by the turning ability: none, because
//!    the rover turns on the spot (a trajectory radius of zero).
//! 4. **Valleys** (runs of free sectors). In a wide valley (more than
//!    [`S_MAX`] sectors) the candidates are its edges offset inwards by
//!    S_MAX/2, and the goal's direction if it lies between them; in a
//!    narrow one its centre. Cost g = μ1·Δ(c, goal) + μ2·Δ(c, heading) +
//!    μ3·Δ(c, previous choice), μ = 5, 2, 2 (the paper's goal-oriented
//!    setting); the least is chosen.
//!
//! A chosen direction outside the beams' sector is a turn on the spot; a
//! step inside it is at most [`FREE_STEP_MM`] and the safety rule's free
//! way. VFH+ is a local planner: it has no completeness and no rule for an
//! unreachable goal. Ours, the baseline's "no path found" (§1 of the
//! algorithms page): no [`PROGRESS_MM`] nearer the goal than the nearest
//! so far in [`GIVE_UP_CYCLES`] cycles reports the goal unreachable.

use super::{begin, Senses, FREE_STEP_MM};
use crate::eapf::command::{Output, Status};
use crate::eapf::config::Config;
use crate::eapf::sensors::{RawCounts, Reading, SENSOR_COUNT};
use crate::fixed::{isqrt, Angle, Point};
use crate::Pose;

/// Cells per side of the window (odd: the rover's cell is the centre).
pub const CELLS: usize = 31;
/// A cell's side, mm.
pub const CELL_MM: i32 = 100;
/// Certainty added where a beam ends on an obstacle.
pub const HIT: u8 = 3;
/// Certainty taken from a cell a beam passes through.
pub const MISS: u8 = 1;
/// The largest certainty.
pub const C_MAX: u8 = 15;
/// Sectors of the polar histogram (5° each).
pub const SECTORS: usize = 72;
/// A sector at or above this density is blocked.
pub const TAU_HIGH: u32 = 150;
/// A sector below this density is free.
pub const TAU_LOW: u32 = 60;
/// A valley wider than this (sectors) is wide.
pub const S_MAX: usize = 16;
/// The cost weights: goal, current heading, previous choice.
pub const MU: [u32; 3] = [5, 2, 2];
/// Progress towards the goal that counts, mm.
pub const PROGRESS_MM: u16 = 100;
/// Cycles without progress after which the goal is reported unreachable.
pub const GIVE_UP_CYCLES: u16 = 300;

/// The window's radius, mm: cells beyond it add nothing.
const D_MAX: i32 = CELL_MM * (CELLS as i32 / 2);
/// A sector's width in [`Angle`] units.
const SECTOR: u32 = 65_536 / SECTORS as u32;

/// The certainty grid centred on the rover.
#[derive(Clone, Debug)]
pub struct Grid {
    cells: [[u8; CELLS]; CELLS],
    /// The world cell at the window's centre (`None` before the first
    /// cycle).
    centre: Option<(i32, i32)>,
}

impl Default for Grid {
    fn default() -> Self {
        Grid {
            cells: [[0; CELLS]; CELLS],
            centre: None,
        }
    }
}

/// The world cell of a point, mm.
fn cell_of(x: i32, y: i32) -> (i32, i32) {
    (x.div_euclid(CELL_MM), y.div_euclid(CELL_MM))
}

/// The torus index of a world cell coordinate.
fn slot(c: i32) -> usize {
    c.rem_euclid(CELLS as i32) as usize
}

impl Grid {
    /// Centre the window on `p`: the columns and rows it leaves are cleared.
    pub fn centre_on(&mut self, p: Point) {
        let now = cell_of(p.x as i32, p.y as i32);
        let Some(was) = self.centre.replace(now) else {
            return;
        };
        let half = CELLS as i32 / 2;
        let (dx, dy) = (now.0 - was.0, now.1 - was.1);
        if dx.abs() >= CELLS as i32 || dy.abs() >= CELLS as i32 {
            self.cells = [[0; CELLS]; CELLS];
            return;
        }
        // The columns that came in (their slots held the columns that left).
        let cols = if dx > 0 {
            (was.0 + half + 1)..=(now.0 + half)
        } else {
            (now.0 - half)..=(was.0 - half - 1)
        };
        for c in cols {
            for row in self.cells.iter_mut() {
                row[slot(c)] = 0;
            }
        }
        let rows = if dy > 0 {
            (was.1 + half + 1)..=(now.1 + half)
        } else {
            (now.1 - half)..=(was.1 - half - 1)
        };
        for r in rows {
            self.cells[slot(r)] = [0; CELLS];
        }
    }

    /// The certainty of the world cell holding (`x`, `y`) mm, if it is in
    /// the window.
    pub fn get(&self, x: i32, y: i32) -> Option<u8> {
        let (cx, cy) = cell_of(x, y);
        let (ox, oy) = self.centre?;
        let half = CELLS as i32 / 2;
        ((cx - ox).abs() <= half && (cy - oy).abs() <= half).then(|| self.cells[slot(cy)][slot(cx)])
    }

    fn cell_mut(&mut self, x: i32, y: i32) -> Option<&mut u8> {
        self.get(x, y)?;
        let (cx, cy) = cell_of(x, y);
        Some(&mut self.cells[slot(cy)][slot(cx)])
    }

    /// A beam from `from` along `heading`: the cells it passes through for
    /// `free_mm` lose [`MISS`]; the cell at its end gains [`HIT`] if it
    /// ended on an obstacle.
    pub fn beam(&mut self, from: Point, heading: Angle, free_mm: u16, hit: bool) {
        let step = (CELL_MM / 2) as u16;
        let mut d = 0;
        while d < free_mm {
            let p = from.offset(heading, d);
            if let Some(c) = self.cell_mut(p.x as i32, p.y as i32) {
                *c = c.saturating_sub(MISS);
            }
            d = d.saturating_add(step);
        }
        if hit {
            let p = from.offset(heading, free_mm);
            if let Some(c) = self.cell_mut(p.x as i32, p.y as i32) {
                *c = (*c + HIT).min(C_MAX);
            }
        }
    }

    /// The polar histogram seen from `p` (VFH+'s enlarged one).
    pub fn histogram(&self, p: Point, clear_mm: u16) -> [u32; SECTORS] {
        let mut h = [0u32; SECTORS];
        let Some((ox, oy)) = self.centre else {
            return h;
        };
        let half = CELLS as i32 / 2;
        let rs = clear_mm as i32;
        for cy in (oy - half)..=(oy + half) {
            for cx in (ox - half)..=(ox + half) {
                let c = self.cells[slot(cy)][slot(cx)] as u32;
                if c == 0 {
                    continue;
                }
                let dx = cx * CELL_MM + CELL_MM / 2 - p.x as i32;
                let dy = cy * CELL_MM + CELL_MM / 2 - p.y as i32;
                let d = crate::fixed::hypot(dx, dy) as i32;
                if d >= D_MAX {
                    continue;
                }
                let m = c * c * (D_MAX - d) as u32 / CELL_MM as u32;
                let beta = Angle::atan2(dy, dx);
                // γ = asin(r_s / d), as atan2(r_s, √(d² − r_s²)).
                let gamma = if d <= rs {
                    Angle::QUARTER
                } else {
                    Angle::atan2(rs, isqrt((d * d - rs * rs) as u32) as i32)
                };
                let (lo, hi) = (sector_of(beta.sub(gamma)), sector_of(beta.add(gamma)));
                let n = (hi + SECTORS - lo) % SECTORS + 1;
                for k in 0..n {
                    let s = (lo + k) % SECTORS;
                    h[s] = h[s].saturating_add(m);
                }
            }
        }
        h
    }
}

/// The VFH+ planner.
#[derive(Clone, Debug)]
pub struct Vfh {
    pub(super) senses: Senses,
    goal: Point,
    grid: Grid,
    /// The binary histogram (hysteresis): one bit per sector, set blocked.
    blocked: [bool; SECTORS],
    /// The last chosen sector.
    previous: Option<usize>,
    /// The nearest to the goal so far, mm, and the cycles since.
    nearest_mm: u16,
    since: u16,
    unreachable: bool,
}

impl Vfh {
    /// VFH+ heading for `goal` with the rover's `config`.
    pub fn new(config: Config, goal: Point) -> Vfh {
        Vfh {
            senses: Senses::new(config),
            goal,
            grid: Grid::default(),
            blocked: [false; SECTORS],
            previous: None,
            nearest_mm: u16::MAX,
            since: 0,
            unreachable: false,
        }
    }

    /// The certainty grid.
    pub fn grid(&self) -> &Grid {
        &self.grid
    }

    /// One cycle from raw counts.
    pub fn step_raw(&mut self, pose: Pose, raw: &RawCounts) -> Output {
        if let Err(out) = begin(&mut self.senses, pose, raw, self.goal) {
            return out;
        }
        let (bearing, goal_mm) = self.senses.goal(pose, self.goal);
        if goal_mm.saturating_add(PROGRESS_MM) <= self.nearest_mm {
            self.nearest_mm = goal_mm;
            self.since = 0;
        } else {
            self.since = self.since.saturating_add(1);
        }
        if self.unreachable || self.since > GIVE_UP_CYCLES {
            self.unreachable = true;
            return self.senses.stop(pose, Status::Unreachable);
        }
        self.update_grid(pose);
        let cfg = self.senses.config();
        let clear = cfg.robot_radius_mm() + cfg.clearance_mm();
        let h = self.grid.histogram(pose.position, clear);
        for (b, &v) in self.blocked.iter_mut().zip(h.iter()) {
            if v >= TAU_HIGH {
                *b = true;
            } else if v < TAU_LOW {
                *b = false;
            }
        }
        let target = sector_of(pose.heading.add(bearing));
        let Some(choice) = choose(
            &self.blocked,
            target,
            sector_of(pose.heading),
            self.previous,
        ) else {
            // Nothing free: turn on the spot to see more.
            let width = cfg.sector_half_width();
            return self.senses.command(pose, width.add(width), 0);
        };
        self.previous = Some(choice);
        let relative = Angle((choice as u32 * SECTOR) as u16).sub(pose.heading);
        let step = if self.senses.in_sector(relative) {
            FREE_STEP_MM.min(goal_mm)
        } else {
            0
        };
        self.senses.command(pose, relative, step)
    }

    /// The beams into the grid.
    fn update_grid(&mut self, pose: Pose) {
        self.grid.centre_on(pose.position);
        let cfg = *self.senses.config();
        for i in 0..SENSOR_COUNT {
            let (end, hit) = self.senses.beam_end(pose, i);
            let far = match self.senses.readings()[i] {
                Reading::Clear => cfg.sensor_offset_mm() + cfg.sensor_range_mm(),
                _ => pose.position.distance_mm(end),
            };
            let heading = pose.heading.add(cfg.sensor_angles()[i]);
            self.grid.beam(pose.position, heading, far, hit);
        }
    }
}

/// The sector holding `a`.
fn sector_of(a: Angle) -> usize {
    ((a.0 as u32 + SECTOR / 2) / SECTOR) as usize % SECTORS
}

/// Sectors between `a` and `b` round the shorter way.
fn delta(a: usize, b: usize) -> u32 {
    let d = a.abs_diff(b) % SECTORS;
    d.min(SECTORS - d) as u32
}

/// VFH+'s choice of direction on the binary histogram `blocked`: the
/// candidates of each valley, the least cost (module docs). `None` when
/// every sector is blocked.
pub fn choose(
    blocked: &[bool; SECTORS],
    target: usize,
    heading: usize,
    previous: Option<usize>,
) -> Option<usize> {
    let cost = |c: usize| {
        MU[0] * delta(c, target)
            + MU[1] * delta(c, heading)
            + MU[2] * previous.map_or(0, |p| delta(c, p))
    };
    let Some(first_blocked) = blocked.iter().position(|&b| b) else {
        return Some(target);
    };
    let mut best: Option<(u32, usize)> = None;
    let mut consider = |c: usize| {
        let c = c % SECTORS;
        if best.is_none_or(|(g, _)| cost(c) < g) {
            best = Some((cost(c), c));
        }
    };
    // Walk once round from a blocked sector: each run of free ones is a
    // valley from `right` (its first sector counter-clockwise) for `width`.
    let mut k = 0;
    while k < SECTORS {
        let s = (first_blocked + k) % SECTORS;
        if blocked[s] {
            k += 1;
            continue;
        }
        let right = s;
        let mut width = 0;
        while k < SECTORS && !blocked[(first_blocked + k) % SECTORS] {
            width += 1;
            k += 1;
        }
        if width > S_MAX {
            let (lo, hi) = (right + S_MAX / 2, right + width - 1 - S_MAX / 2);
            consider(lo);
            consider(hi);
            // The goal's direction, if it lies between them.
            let t = (target + SECTORS - right) % SECTORS + right;
            if (lo..=hi).contains(&t) {
                consider(t);
            }
        } else {
            consider(right + width / 2);
        }
    }
    best.map(|(_, c)| c)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The valley choice on a hand-made histogram: sectors 10 ..= 30
    /// blocked, the goal at 20 (behind the block).
    #[test]
    fn picks_the_valley_edge_nearer_the_goal() {
        let mut blocked = [false; SECTORS];
        for b in &mut blocked[10..=30] {
            *b = true;
        }
        // Facing the goal: the wide valley's edges offset by S_MAX/2 are
        // 31 + 8 = 39 and 9 − 8 = 1 (round the other way). 39 is 19 from
        // the goal, 1 is 19 too: equal goal terms, so the heading (20)
        // ties and the previous choice decides.
        assert_eq!(choose(&blocked, 20, 20, Some(39)), Some(39));
        assert_eq!(choose(&blocked, 20, 20, Some(1)), Some(1));
        // A goal nearer one edge: that edge.
        assert_eq!(choose(&blocked, 28, 28, None), Some(39));
        assert_eq!(choose(&blocked, 12, 12, None), Some(1));
        // A goal in the free valley: straight there.
        assert_eq!(choose(&blocked, 50, 20, None), Some(50));
        // A narrow valley (sectors 40 ..= 45 free, all else blocked): its
        // centre.
        let mut narrow = [true; SECTORS];
        for b in &mut narrow[40..=45] {
            *b = false;
        }
        assert_eq!(choose(&narrow, 0, 0, None), Some(43));
        assert_eq!(choose(&[true; SECTORS], 0, 0, None), None);
        assert_eq!(choose(&[false; SECTORS], 7, 0, None), Some(7));
    }

    #[test]
    fn the_grid_follows_the_rover_and_forgets_what_it_leaves() {
        let mut g = Grid::default();
        g.centre_on(Point::new(0, 0));
        g.beam(Point::new(0, 0), Angle::ZERO, 500, true);
        assert_eq!(g.get(500, 0), Some(HIT));
        // 0.9 m back, the cell is still in the 3.1 m window; 2 m back it is
        // not.
        g.centre_on(Point::new(-900, 0));
        assert_eq!(g.get(500, 0), Some(HIT));
        g.centre_on(Point::new(-2_000, 0));
        assert_eq!(g.get(500, 0), None);
        // Back again: the slot was cleared when its column left.
        g.centre_on(Point::new(0, 0));
        assert_eq!(g.get(500, 0), Some(0));
    }

    #[test]
    fn an_obstacle_ahead_blocks_the_sectors_round_its_direction() {
        let mut g = Grid::default();
        g.centre_on(Point::new(0, 0));
        for _ in 0..5 {
            g.beam(Point::new(0, 0), Angle::ZERO, 500, true);
        }
        let h = g.histogram(Point::new(0, 0), 140);
        assert!(h[0] >= TAU_HIGH, "{}", h[0]);
        // γ = asin(140 / 552) ≈ 15° about 5°: sectors −2 ..= 4 (5° each,
        // centred on theirs), not 5.
        assert!(h[70] > 0 && h[4] > 0 && h[5] == 0, "{:?}", &h[..8]);
        assert_eq!(h[36], 0);
    }
}
