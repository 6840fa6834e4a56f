//! The "liquid movement" planner over a known map (Moaveni & Ghanbari Gol,
//! docs/algorithms.md §3): descend a potential over `A_nsd` discrete headings;
//! wherever no neighbour is lower (a local minimum) drop a virtual obstacle,
//! which raises the potential there like liquid filling a pit; then either
//! restart from the start (the paper's offline algorithm) or go on from
//! there (its modified online algorithm).
//!
//! For an MCU with a stored map: no allocation, integers only. The map is
//! borrowed (circles, polygons and the world's bounds, mm); the path and the
//! virtual obstacles live in bounded buffers, and running out of either, or
//! of the computation budget, means "unreachable".
//!
//! Potentials (§3), the agent a point and every obstacle inflated by the
//! robot radius `A_r`:
//! - target `P_t = K_t · |T − X|` (conical);
//! - obstacle `P_O = K_O / r²`, `r = |O − X| − (O_r + A_r)` for a circle,
//!   the distance to the outline minus `A_r` for a polygon; infinite for
//!   `r ≤ 0` and outside the bounds;
//! - virtual obstacle `P_v = K_v / r_v²`, `r_v = |V − X| − V_r` (the robot
//!   is not inflated into it: only liquid is there), infinite within `V_r`.
//!   The paper leaves `V_r` open; ours is 0.9 step: a droplet fills one
//!   step-sized cell of the pit. With the paper's tiny obstacles (O_r 1.5
//!   against a step of 10) a pit is a few cells; ours are many.
//!
//! Units. The paper's parameters (Step 10, K_t 35, K_O 1, K_v 60, A_nsd 16)
//! are in its own length unit; here one unit is `step_mm / 10`, so the
//! defaults keep the paper's proportions at a step of 100 mm.

use crate::fixed::{hypot, Angle, Point};

/// A circular obstacle, mm.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Circle {
    /// Centre.
    pub center: Point,
    /// Radius.
    pub radius_mm: u16,
}

/// A known map: the bounds (min and max corner, mm), circles and polygons
/// (each a closed outline of points, mm).
#[derive(Clone, Copy, Debug)]
pub struct Map<'a> {
    /// Lower-left corner.
    pub min: Point,
    /// Upper-right corner.
    pub max: Point,
    /// Circles.
    pub circles: &'a [Circle],
    /// Polygons.
    pub polygons: &'a [&'a [Point]],
}

/// The planner's parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LiquidConfig {
    /// Step, mm.
    pub step_mm: u16,
    /// Number of headings, `A_nsd` (4 ..= 64).
    pub headings: u8,
    /// `K_t`, `K_O`, `K_v` in the paper's units.
    pub k_target: u32,
    /// `K_O`.
    pub k_obstacle: u32,
    /// `K_v`.
    pub k_virtual: u32,
    /// Robot radius `A_r`, mm.
    pub robot_radius_mm: u16,
    /// Goal reached within this distance, mm.
    pub goal_tolerance_mm: u16,
    /// Virtual obstacle radius `V_r`, mm.
    pub virtual_radius_mm: u16,
    /// Computation steps (neighbour evaluations rounds) before giving up.
    pub budget: u32,
    /// Restart from the start after each virtual obstacle (offline) or go
    /// on from the local minimum (online).
    pub restart: bool,
}

impl LiquidConfig {
    /// The paper's parameters: A_nsd 16, K_t 35, K_O 1, K_v 60; step 100 mm,
    /// V_r 90 mm, robot radius 100 mm, goal tolerance 50 mm, 200,000
    /// computation steps.
    pub const fn paper(restart: bool) -> Self {
        LiquidConfig {
            step_mm: 100,
            headings: 16,
            k_target: 35,
            k_obstacle: 1,
            k_virtual: 60,
            robot_radius_mm: 100,
            virtual_radius_mm: 90,
            goal_tolerance_mm: 50,
            budget: 200_000,
            restart,
        }
    }
}

/// A finished plan and the counts the paper reports. `W` and `V` bound the
/// waypoints and the virtual obstacles (an MCU picks what its RAM allows:
/// 4 bytes each).
#[derive(Clone, Debug)]
pub struct Plan<const W: usize, const V: usize> {
    /// Waypoints from the start to the goal (both included).
    pub waypoints: heapless::Vec<Point, W>,
    /// Virtual obstacles dropped.
    pub virtual_obstacles: heapless::Vec<Point, V>,
    /// Rounds of neighbour evaluation, all restarts included.
    pub computation_steps: u32,
    /// Moves of the final path.
    pub motion_steps: u32,
}

/// Why no plan came out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LiquidError {
    /// The start is inside an (inflated) obstacle or out of bounds.
    StartBlocked,
    /// Budget, path or virtual-obstacle capacity ran out: the goal is
    /// taken as unreachable.
    Unreachable,
    /// A parameter is out of range.
    BadConfig,
}

/// Potential value standing for "infinite" (inside an obstacle).
pub const INFINITE: u64 = u64::MAX;
/// Fixed-point scale of the potential.
pub const SCALE: u64 = 1 << 16;

/// The potential at `x` (paper §3), in units of `1/SCALE`; [`INFINITE`]
/// inside an (inflated) obstacle, a virtual obstacle or out of bounds.
pub fn potential(map: &Map, cfg: &LiquidConfig, virtuals: &[Point], goal: Point, x: Point) -> u64 {
    potential_parts(map, cfg, virtuals, goal, x).unwrap_or(INFINITE)
}

fn potential_parts(
    map: &Map,
    cfg: &LiquidConfig,
    virtuals: &[Point],
    goal: Point,
    x: Point,
) -> Option<u64> {
    let unit = unit_mm(cfg);
    // (`checked_div` here and below: no panicking path, though every
    // divisor is known to be positive.)
    let mut p = (cfg.k_target as u64 * x.distance_mm(goal) as u64 * SCALE).checked_div(unit)?;
    p = p.saturating_add(obstacle_potential(map, cfg, x)?);
    for v in virtuals {
        let r = x.distance_mm(*v) as i32 - cfg.virtual_radius_mm as i32;
        p = p.saturating_add(inverse_square(cfg.k_virtual, r, unit)?);
    }
    Some(p)
}

/// One paper length unit in mm (≥ 1).
fn unit_mm(cfg: &LiquidConfig) -> u64 {
    (cfg.step_mm as u64 / 10).max(1)
}

/// `K / (r/unit)² = K · unit² / r²` in `1/SCALE`; `None` (infinite) for `r ≤ 0`.
fn inverse_square(k: u32, r: i32, unit: u64) -> Option<u64> {
    if r <= 0 {
        return None;
    }
    let r = r as u64;
    (k as u64 * unit * unit * SCALE).checked_div(r * r)
}

/// The obstacles' and the bounds' part of the potential at `x`; `None`
/// inside an inflated obstacle or out of bounds.
fn obstacle_potential(map: &Map, cfg: &LiquidConfig, x: Point) -> Option<u64> {
    let a_r = cfg.robot_radius_mm as i32;
    if (x.x as i32) < map.min.x as i32 + a_r
        || (x.y as i32) < map.min.y as i32 + a_r
        || (x.x as i32) > map.max.x as i32 - a_r
        || (x.y as i32) > map.max.y as i32 - a_r
    {
        return None;
    }
    let unit = unit_mm(cfg);
    let mut p = 0u64;
    for c in map.circles {
        let r = x.distance_mm(c.center) as i32 - c.radius_mm as i32 - a_r;
        p = p.saturating_add(inverse_square(cfg.k_obstacle, r, unit)?);
    }
    for poly in map.polygons {
        let (inside, d) = polygon_distance(poly, x);
        if inside {
            return None;
        }
        p = p.saturating_add(inverse_square(cfg.k_obstacle, d as i32 - a_r, unit)?);
    }
    Some(p)
}

/// (inside, distance to the outline in mm) of a point and a polygon.
fn polygon_distance(poly: &[Point], x: Point) -> (bool, u16) {
    let mut inside = false;
    let mut best = u16::MAX;
    for (&a, &b) in poly.iter().zip(poly.iter().cycle().skip(1)) {
        best = best.min(segment_distance(a, b, x));
        // Ray crossing to +x.
        let (ay, by, py) = (a.y as i32, b.y as i32, x.y as i32);
        if (ay > py) != (by > py) {
            let (ax, bx) = (a.x as i64, b.x as i64);
            // x of the edge at py, compared without division.
            let lhs = (x.x as i64 - ax) * (by - ay) as i64;
            let rhs = (bx - ax) * (py - ay) as i64;
            if (by > ay && lhs < rhs) || (by < ay && lhs > rhs) {
                inside = !inside;
            }
        }
    }
    (inside, best)
}

/// Distance from `x` to the segment `a b`, mm.
fn segment_distance(a: Point, b: Point, x: Point) -> u16 {
    let (abx, aby) = a.to(b);
    let (axx, axy) = a.to(x);
    let len2 = abx as i64 * abx as i64 + aby as i64 * aby as i64;
    let dot = axx as i64 * abx as i64 + axy as i64 * aby as i64;
    if len2 == 0 || dot <= 0 {
        return a.distance_mm(x);
    }
    if dot >= len2 {
        return b.distance_mm(x);
    }
    // Foot of the perpendicular: a + ab·dot/len2.
    let fx = a.x as i64 + (abx as i64 * dot).checked_div(len2).unwrap_or(0);
    let fy = a.y as i64 + (aby as i64 * dot).checked_div(len2).unwrap_or(0);
    hypot((x.x as i64 - fx) as i32, (x.y as i64 - fy) as i32)
}

/// Plan from `start` to `goal` on `map`, with room for `W` waypoints and
/// `V` virtual obstacles.
pub fn plan<const W: usize, const V: usize>(
    map: &Map,
    cfg: &LiquidConfig,
    start: Point,
    goal: Point,
) -> Result<Plan<W, V>, LiquidError> {
    if !(4..=64).contains(&cfg.headings) || cfg.step_mm < 10 {
        return Err(LiquidError::BadConfig);
    }
    let mut out = Plan {
        waypoints: heapless::Vec::new(),
        virtual_obstacles: heapless::Vec::new(),
        computation_steps: 0,
        motion_steps: 0,
    };
    if potential(map, cfg, &[], goal, start) == INFINITE {
        return Err(LiquidError::StartBlocked);
    }
    let push =
        |w: &mut heapless::Vec<Point, W>, p: Point| w.push(p).map_err(|_| LiquidError::Unreachable);
    push(&mut out.waypoints, start)?;
    let mut x = start;
    loop {
        if x.distance_mm(goal) <= cfg.goal_tolerance_mm.max(cfg.step_mm / 2) {
            if x != goal {
                push(&mut out.waypoints, goal)?;
                out.motion_steps += 1;
            }
            return Ok(out);
        }
        out.computation_steps += 1;
        if out.computation_steps > cfg.budget {
            return Err(LiquidError::Unreachable);
        }
        let here = potential(map, cfg, &out.virtual_obstacles, goal, x);
        let mut best: Option<(u64, Point)> = None;
        for k in 0..cfg.headings as u32 {
            let dir = Angle(((k * 65_536).checked_div(cfg.headings as u32).unwrap_or(0)) as u16);
            let y = x.offset(dir, cfg.step_mm);
            let p = potential(map, cfg, &out.virtual_obstacles, goal, y);
            if p == INFINITE || !move_is_free(map, cfg, x, y) {
                continue;
            }
            if best.is_none_or(|(bp, _)| p < bp) {
                best = Some((p, y));
            }
        }
        match best {
            Some((p, y)) if p < here => {
                x = y;
                push(&mut out.waypoints, y)?;
                out.motion_steps += 1;
            }
            _ => {
                // A local minimum: liquid collects here.
                out.virtual_obstacles
                    .push(x)
                    .map_err(|_| LiquidError::Unreachable)?;
                if cfg.restart {
                    x = start;
                    out.waypoints.clear();
                    out.motion_steps = 0;
                    push(&mut out.waypoints, start)?;
                }
            }
        }
    }
}

/// The straight move `x → y` keeps the robot's disc clear of every
/// obstacle (checked at its quarter points: a step is shorter than any
/// inflated obstacle is wide, so nothing fits between them).
fn move_is_free(map: &Map, cfg: &LiquidConfig, x: Point, y: Point) -> bool {
    let (dx, dy) = x.to(y);
    (1..4).all(|q| {
        let m = Point::saturating(x.x as i32 + dx * q / 4, x.y as i32 + dy * q / 4);
        obstacle_potential(map, cfg, m).is_some()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn open(circles: &[Circle]) -> Map<'_> {
        Map {
            min: Point::new(0, 0),
            max: Point::new(7_000, 6_000),
            circles,
            polygons: &[],
        }
    }

    #[test]
    fn potential_by_hand() {
        let cfg = LiquidConfig::paper(true);
        let c = [Circle {
            center: Point::new(3_000, 3_000),
            radius_mm: 500,
        }];
        let map = open(&c);
        // 1,000 mm from the goal (unit 10 mm → 100 units): K_t·100 = 3,500;
        // the circle's surface is 2,000 − 500 − 100 = 1,400 mm = 140 units
        // away: 1/140² = 5.1e-5. Total ≈ 3,500.00005.
        let p = potential(
            &map,
            &cfg,
            &[],
            Point::new(1_000, 2_000),
            Point::new(1_000, 3_000),
        );
        assert_eq!(p / SCALE, 3_500);
        assert!(!p.is_multiple_of(SCALE));
        // Inside the inflated circle, or out of bounds: infinite.
        assert_eq!(
            potential(&map, &cfg, &[], Point::new(0, 0), Point::new(3_000, 2_420)),
            INFINITE
        );
        assert_eq!(
            potential(&map, &cfg, &[], Point::new(0, 0), Point::new(50, 3_000)),
            INFINITE
        );
    }

    #[test]
    fn polygon_inside_and_distance() {
        let square = [
            Point::new(0, 0),
            Point::new(1_000, 0),
            Point::new(1_000, 1_000),
            Point::new(0, 1_000),
        ];
        assert_eq!(polygon_distance(&square, Point::new(500, 500)), (true, 500));
        assert_eq!(
            polygon_distance(&square, Point::new(1_300, 500)),
            (false, 300)
        );
        assert_eq!(
            polygon_distance(&square, Point::new(1_300, 1_400)),
            (false, 500)
        );
    }

    #[test]
    fn no_local_minimum_needs_no_virtual_obstacle() {
        let cfg = LiquidConfig::paper(true);
        let map = open(&[]);
        let p: Plan<64, 4> = plan(
            &map,
            &cfg,
            Point::new(1_000, 3_000),
            Point::new(6_000, 3_000),
        )
        .unwrap();
        assert_eq!(p.virtual_obstacles.len(), 0);
        assert_eq!(p.motion_steps, 50);
        assert_eq!(*p.waypoints.last().unwrap(), Point::new(6_000, 3_000));
    }

    fn two_circles() -> [Circle; 2] {
        [
            Circle {
                center: Point::new(3_500, 2_450),
                radius_mm: 550,
            },
            Circle {
                center: Point::new(3_500, 3_550),
                radius_mm: 550,
            },
        ]
    }

    #[test]
    fn a_local_minimum_fills_with_liquid_offline_and_online() {
        let c = two_circles();
        let map = open(&c);
        let (s, g) = (Point::new(1_000, 3_000), Point::new(6_000, 3_000));
        let off: Plan<256, 64> = plan(&map, &LiquidConfig::paper(true), s, g).unwrap();
        let on: Plan<256, 64> = plan(&map, &LiquidConfig::paper(false), s, g).unwrap();
        for p in [&off.waypoints, &on.waypoints] {
            assert_eq!(*p.last().unwrap(), g);
            // Every waypoint is outside the inflated circles.
            assert!(p.iter().all(|w| c
                .iter()
                .all(|o| w.distance_mm(o.center) > o.radius_mm + 100)));
        }
        assert!(!off.virtual_obstacles.is_empty() && !on.virtual_obstacles.is_empty());
        // The offline path is the shorter, the online search the cheaper.
        assert!(off.motion_steps < on.motion_steps);
        assert!(on.computation_steps < off.computation_steps);
    }

    #[test]
    fn too_little_room_for_liquid_is_unreachable_not_a_panic() {
        let c = two_circles();
        let map = open(&c);
        let r: Result<Plan<256, 4>, _> = plan(
            &map,
            &LiquidConfig::paper(true),
            Point::new(1_000, 3_000),
            Point::new(6_000, 3_000),
        );
        assert_eq!(r.err(), Some(LiquidError::Unreachable));
    }

    #[test]
    fn a_walled_in_goal_is_unreachable() {
        // A closed square room around the goal.
        let room = [
            Point::new(4_500, 2_000),
            Point::new(6_500, 2_000),
            Point::new(6_500, 4_000),
            Point::new(4_500, 4_000),
        ];
        let inner = [
            Point::new(4_600, 2_100),
            Point::new(6_400, 2_100),
            Point::new(6_400, 3_900),
            Point::new(4_600, 3_900),
        ];
        // Walls: the ring between the two squares, as four thin polygons.
        let walls: [&[Point]; 4] = [
            &[room[0], room[1], inner[1], inner[0]],
            &[room[1], room[2], inner[2], inner[1]],
            &[room[2], room[3], inner[3], inner[2]],
            &[room[3], room[0], inner[0], inner[3]],
        ];
        let map = Map {
            min: Point::new(0, 0),
            max: Point::new(7_000, 6_000),
            circles: &[],
            polygons: &walls,
        };
        let mut cfg = LiquidConfig::paper(false);
        cfg.budget = 3_000;
        let r: Result<Plan<4_096, 1_024>, _> = plan(
            &map,
            &cfg,
            Point::new(1_000, 3_000),
            Point::new(5_500, 3_000),
        );
        assert_eq!(r.err(), Some(LiquidError::Unreachable));
    }
}
