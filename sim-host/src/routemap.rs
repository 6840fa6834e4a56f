//! The waypoint graph the `route` planner plans over (planner-core's
//! [`route`](planner_core::maps::route) layer): built here from the scenario's
//! known map, because the world's geometry lives here; the planning and the
//! following are the core's.
//!
//! Nodes on a square grid wherever the rover's disc plus the planner's
//! clearance (40 mm) fits (0.2 m apart, wider where such nodes would take
//! more than 80 % of [`ROUTE_NODES`]), edges to the eight neighbours where the
//! swept disc fits all the way, and the start and the goal joined to the
//! grid nodes they see within 2.5 cells and to every node they see with
//! the disc plus 40 mm within 1.5 m (`END_SIGHT_M`). Each edge carries its
//! clearance: the least distance from its segment to the static geometry.
//!
//! Gap nodes: a passage a little wider than the disc and its clearance
//! holds a strip of centre positions narrower than the grid's spacing,
//! which the grid's nodes and edges often miss (with a 0.2 m grid alone,
//! routes of 2–5× the reference in some random worlds of the paper's
//! parameters, where the reference's way went through such gaps). So where
//! the clearance, scanned every 40 mm, is between the need and 0.15 m more,
//! and highest across the passage (a ridge of the clearance: the middle of
//! a gap), the best such point of each grid cell is a node too, joined to
//! every node within 2.25 spacings that it sees with the disc plus 40 mm.
//! A strip narrower than the scan's spacing can lie between its points,
//! each short of the need (the library's narrow passage: a strip 20 mm
//! wide, its middle 20 mm from the scan's rows on either side, which are
//! 10 mm short of the need): a ridge point up to
//! h/√2 short of it (the farthest a scan point can be from the strip) is
//! searched within half a step in 5 mm steps for a point that fits with
//! 5 mm to spare (a narrower strip no rover hits).

use crate::geom::V2;
use crate::scenario::Scenario;
use crate::units::{to_mm, to_point, to_v2};
use crate::world::World;
use planner_core::maps::route::RouteMap;
use std::collections::HashMap;

/// Node capacity of the simulator's maps.
pub const ROUTE_NODES: usize = 4096;
/// Edge capacity of the simulator's maps.
pub const ROUTE_EDGES: usize = 5 * ROUTE_NODES;
/// The simulator's map type.
pub type SimRouteMap = RouteMap<ROUTE_NODES, ROUTE_EDGES>;

/// The grid's spacing in small worlds, m.
pub const GRID_M: f64 = 0.2;

/// The share of [`ROUTE_NODES`] the grid may take (the free points of a
/// 0.2 m grid; a wider spacing where they are more).
const GRID_SHARE: f64 = 0.8;

/// How finely the clearance is scanned for gap nodes, m.
const GAP_SCAN_M: f64 = 0.04;

/// How finely the scan's candidates are searched for the highest
/// clearance near them, m: a strip of centre positions narrower than the
/// scan's spacing lies between two of its points, each below the need.
const GAP_REFINE_M: f64 = 0.005;

/// A gap the refining search finds must have this much to spare beyond
/// the need, m: a strip of centre positions at least two search steps
/// wide. Narrower ones are there in random worlds (gen-126: 1.9 mm to
/// spare between two circles) and no rover hits them: sent into one, the
/// rover turns about at its mouth until the leg's budget runs out.
const GAP_MIN_SPARE_M: f64 = 0.005;

/// Gap nodes are where the clearance is at most this much above the need,
/// m: passages up to 0.3 m wider than the disc with its clearance (wider
/// ones hold a strip of centre positions the grid does not miss).
const GAP_BAND_M: f64 = 0.15;

/// The start and the goal join every node they see within this, m: a
/// route can then leave the start, or meet the goal, straight on (through
/// the mouth of a gap the goal lies behind, along its axis) rather than
/// along a grid row beside it.
const END_SIGHT_M: f64 = 1.5;

/// Gap nodes join the nodes within this many grid spacings (two cells
/// diagonally, a little more).
const GAP_LINK: f64 = 2.25;

/// Beyond the disc, what a node or an edge must keep clear, m: the
/// planner's default clearance.
const MARGIN_M: f64 = 0.04;

/// Beyond the disc, what the edges of a route keep clear while such a
/// route exists, m (`RouteConfig::preferred_clearance_mm`): twice the
/// planner's clearance. With routes at 40 mm, one in barn-193 (seed 1) led
/// the rover to turn beside a 10 cm block none of its beams had seen, then
/// into it (the commit history, "The route layer").
pub const PREFERRED_MARGIN_M: f64 = 0.08;

/// The graph for `sc` (static obstacles only), with the start and the goal
/// among its nodes.
pub fn build(sc: &Scenario) -> SimRouteMap {
    let world = World {
        moving: Vec::new(),
        ..sc.world()
    };
    let r = sc.robot_radius;
    let need = r + MARGIN_M;
    let [x0, y0, x1, y1] = sc.bounds;
    // The grid's free points at `s` apart.
    let free = |s: f64| {
        let (nx, ny) = (((x1 - x0) / s) as i32, ((y1 - y0) / s) as i32);
        (1..ny.max(1))
            .flat_map(|j| (1..nx.max(1)).map(move |i| (i, j)))
            .filter(|&(i, j)| {
                let p = V2::new(x0 + i as f64 * s, y0 + j as f64 * s);
                world.clearance(p, 0.0) >= need
            })
            .count()
    };
    // 0.2 m, or wider where the grid's free points would take more than
    // `GRID_SHARE` of the capacity (the rest is for the gap nodes).
    let most = ROUTE_NODES as f64 * GRID_SHARE;
    let s = GRID_M * (free(GRID_M) as f64 / most).sqrt().max(1.0);
    let (nx, ny) = (((x1 - x0) / s) as i32, ((y1 - y0) / s) as i32);
    let at = |i: i32, j: i32| V2::new(x0 + i as f64 * s, y0 + j as f64 * s);
    let mut map = SimRouteMap::new();
    let mut grid: HashMap<(i32, i32), u16> = HashMap::new();
    for j in 1..ny.max(1) {
        for i in 1..nx.max(1) {
            if world.clearance(at(i, j), 0.0) >= need {
                if let Ok(k) = map.add_node(to_point(at(i, j))) {
                    grid.insert((i, j), k);
                }
            }
        }
    }
    let mut cells: Vec<_> = grid.iter().map(|(&c, &k)| (c, k)).collect();
    cells.sort();
    for &((i, j), a) in &cells {
        for (di, dj) in [(1, 0), (0, 1), (1, 1), (-1, 1)] {
            let Some(&b) = grid.get(&(i + di, j + dj)) else {
                continue;
            };
            let c = world.static_sweep_clearance(at(i, j), at(i + di, j + dj));
            if c >= need {
                let _ = map.add_edge(a, b, to_mm(c));
            }
        }
    }
    let grid_nodes: Vec<(u16, V2)> = cells.iter().map(|&((i, j), k)| (k, at(i, j))).collect();
    add_gap_nodes(&mut map, &world, sc.bounds, s, need, &grid_nodes);
    // The start and the goal, joined to the grid nodes they see nearby,
    // to every node they see within `END_SIGHT_M` with the need (nearest
    // first), and to each other when in sight.
    let nodes: Vec<(u16, V2)> = (0..).zip(map.nodes().iter().map(|&p| to_v2(p))).collect();
    let ends = [sc.start, sc.goal].map(|p| V2::new(p[0], p[1]));
    let mut end_nodes = Vec::new();
    for p in ends {
        let Ok(k) = map.add_node(to_point(p)) else {
            continue;
        };
        end_nodes.push((k, p));
        let mut seen: Vec<(f64, u16, V2)> = nodes
            .iter()
            .map(|&(b, q)| (p.dist(q), b, q))
            .filter(|&(d, _, _)| d <= END_SIGHT_M.max(2.5 * s))
            .collect();
        seen.sort_by(|a, b| a.0.total_cmp(&b.0));
        for (d, b, q) in seen {
            let c = world.static_sweep_clearance(p, q);
            if c >= need || (c >= r && d <= 2.5 * s) {
                let _ = map.add_edge(k, b, to_mm(c));
            }
        }
    }
    if let [(a, p), (b, q)] = end_nodes[..] {
        let c = world.static_sweep_clearance(p, q);
        if c >= need {
            let _ = map.add_edge(a, b, to_mm(c));
        }
    }
    map
}

/// The gap nodes (module docs) of the world `world` within `bounds`, for
/// a grid of spacing `s` whose nodes are `grid` (index, position), joined
/// to the nodes near them.
fn add_gap_nodes(
    map: &mut SimRouteMap,
    world: &World,
    bounds: [f64; 4],
    s: f64,
    need: f64,
    grid: &[(u16, V2)],
) {
    let [x0, y0, x1, y1] = bounds;
    let h = GAP_SCAN_M;
    let (nx, ny) = (((x1 - x0) / h) as usize + 1, ((y1 - y0) / h) as usize + 1);
    let at = |i: usize, j: usize| V2::new(x0 + i as f64 * h, y0 + j as f64 * h);
    let clear: Vec<f64> = (0..nx * ny)
        .map(|k| world.clearance(at(k % nx, k / nx), 0.0))
        .collect();
    // The best ridge point of each grid cell (the cell of the grid node
    // nearest it).
    let mut best: HashMap<(i32, i32), (f64, V2)> = HashMap::new();
    // A scan point nearest a strip of centre positions is at most h/√2
    // from it, and the clearance changes by at most as much as the point
    // moves: a point that low may still be next to a way.
    let shortfall = h * std::f64::consts::FRAC_1_SQRT_2;
    for j in 1..ny.saturating_sub(1) {
        for i in 1..nx.saturating_sub(1) {
            let c = clear[j * nx + i];
            if c < need - shortfall || c > need + GAP_BAND_M {
                continue;
            }
            let ridge = [(1, 0), (0, 1), (1, 1), (1, -1)]
                .iter()
                .any(|&(di, dj): &(i64, i64)| {
                    let side = |sign: i64| {
                        let (a, b) = (i as i64 + sign * di, j as i64 + sign * dj);
                        clear[b as usize * nx + a as usize]
                    };
                    // Highest across, and not level (along a wall the
                    // clearance is level).
                    let (a, b) = (side(1), side(-1));
                    c >= a && c >= b && c > a.min(b)
                });
            if !ridge {
                continue;
            }
            let (c, p) = if c >= need {
                (c, at(i, j))
            } else {
                // Below the need: the highest clearance within half a
                // scan step, in finer steps.
                let Some(best) = highest_near(world, at(i, j), h / 2.0)
                    .filter(|b| b.0 >= need + GAP_MIN_SPARE_M)
                else {
                    continue;
                };
                best
            };
            let cell = (
                ((p.x - x0) / s).round() as i32,
                ((p.y - y0) / s).round() as i32,
            );
            let e = best.entry(cell).or_insert((f64::MIN, p));
            if c > e.0 {
                *e = (c, p);
            }
        }
    }
    // Every node so far by cell, to join the gap nodes to those near them.
    let mut near: HashMap<(i32, i32), Vec<(u16, V2)>> = HashMap::new();
    let cell_of = |p: V2| {
        (
            ((p.x - x0) / s).floor() as i32,
            ((p.y - y0) / s).floor() as i32,
        )
    };
    for &(k, p) in grid {
        near.entry(cell_of(p)).or_default().push((k, p));
    }
    let mut gaps: Vec<_> = best.into_iter().collect();
    gaps.sort_by_key(|g| g.0);
    let reach = GAP_LINK * s;
    let span = reach.div_euclid(s) as i32 + 1;
    for (_, (_, p)) in gaps {
        // Room for the start and the goal, added after.
        if map.nodes().len() + 2 >= ROUTE_NODES {
            return;
        }
        let Ok(k) = map.add_node(to_point(p)) else {
            return;
        };
        let (ci, cj) = cell_of(p);
        for dj in -span..=span {
            for di in -span..=span {
                for &(b, q) in near.get(&(ci + di, cj + dj)).into_iter().flatten() {
                    if p.dist(q) > reach {
                        continue;
                    }
                    let c = world.static_sweep_clearance(p, q);
                    if c >= need {
                        let _ = map.add_edge(k, b, to_mm(c));
                    }
                }
            }
        }
        near.entry((ci, cj)).or_default().push((k, p));
    }
}

/// The point of highest clearance within `half` (either axis) of `p`, on a
/// [`GAP_REFINE_M`] grid, with its clearance.
fn highest_near(world: &World, p: V2, half: f64) -> Option<(f64, V2)> {
    let n = (half / GAP_REFINE_M).round() as i32;
    (-n..=n)
        .flat_map(|j| (-n..=n).map(move |i| (i, j)))
        .map(|(i, j)| {
            let q = V2::new(p.x + i as f64 * GAP_REFINE_M, p.y + j as f64 * GAP_REFINE_M);
            (world.clearance(q, 0.0), q)
        })
        .max_by(|a, b| a.0.total_cmp(&b.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use planner_core::maps::route::RouteConfig;
    use std::path::Path;

    fn scenario(rel: &str) -> Scenario {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
        Scenario::load(&dir.join(rel)).unwrap()
    }

    /// A wall across the world with one gap 0.34 m wide, centred between
    /// two grid rows, and the start and the goal on either side.
    fn gap_world(start: [f64; 2], goal: [f64; 2]) -> Scenario {
        let text = format!(
            r#"
format = 1
name = "gap"
bounds = [0.0, 0.0, 4.0, 3.0]
start = [{}, {}]
goal = [{}, {}]
robot_radius = 0.1
[[polygon]]
points = [[1.9, 0.0], [2.1, 0.0], [2.1, 1.33], [1.9, 1.33]]
[[polygon]]
points = [[1.9, 1.67], [2.1, 1.67], [2.1, 3.0], [1.9, 3.0]]
"#,
            start[0], start[1], goal[0], goal[1]
        );
        Scenario::parse(&text, Path::new("gap.toml")).unwrap()
    }

    /// No grid node fits in the gap (its strip of centre positions 0.14 m
    /// clear is 60 mm wide): only the gap nodes join the two sides, and
    /// the route goes through them.
    #[test]
    fn gap_nodes_open_a_gap_the_grid_misses() {
        let map = build(&gap_world([1.0, 0.8], [3.0, 2.3]));
        let n = map.nodes().len() as u16;
        let route = map
            .plan(n - 2, n - 1, &RouteConfig::default())
            .expect("a route through the gap");
        assert!(route.length_mm < 2_800, "{} mm", route.length_mm);
        let through = route.nodes.iter().any(|&k| {
            let p = map.nodes()[k as usize];
            (1_900..=2_100).contains(&p.x) && (p.y - 1_500).abs() <= 30
        });
        assert!(through, "a gap node on the route");
        assert!(map.edges().iter().all(|e| e.clearance_mm >= 100));
    }

    /// The start, on the gap's axis, sees through its mouth: it is joined
    /// to the nodes it sees a metre away, beyond the grid's 2.5 cells.
    #[test]
    fn the_ends_are_joined_to_the_nodes_they_see() {
        let map = build(&gap_world([1.0, 1.5], [3.0, 0.8]));
        let s = map.nodes().len() as u16 - 2;
        let start = map.nodes()[s as usize];
        let far = map.edges().iter().any(|e| {
            let other = match (e.a == s, e.b == s) {
                (true, _) => e.b,
                (_, true) => e.a,
                _ => return false,
            };
            let (dx, dy) = start.to(map.nodes()[other as usize]);
            dx >= 900 && dy.abs() <= 30
        });
        assert!(far, "the start joined to the nodes it sees");
    }

    /// The library's narrow passage: its gap is 20 mm wider than the disc
    /// and the clearance, so the strip of centre positions that fit is 20
    /// mm wide and lies between two rows of the 40 mm scan, each 10 mm
    /// short of the need. The scan's near misses are searched more finely
    /// and the gap gets its nodes (without that search: no route).
    #[test]
    fn a_gap_between_the_scan_points_gets_its_nodes() {
        let sc = scenario("traps/narrow-passage.toml");
        let map = build(&sc);
        let n = map.nodes().len() as u16;
        let route = map
            .plan(n - 2, n - 1, &RouteConfig::default())
            .expect("a route through the gap");
        let in_gap = |p: planner_core::Point| (2_900..=3_100).contains(&p.x);
        let through: Vec<_> = route
            .nodes
            .iter()
            .map(|&k| map.nodes()[k as usize])
            .filter(|&p| in_gap(p))
            .collect();
        assert!(!through.is_empty(), "no node in the gap");
        // In the strip: within 10 mm of the gap's axis (y = 2.5 m).
        assert!(
            through.iter().all(|p| (p.y - 2_500).abs() <= 10),
            "{through:?}"
        );
    }

    /// A gap with 2 mm to spare beyond the need (a strip of centre
    /// positions 4 mm wide, between the scan's rows): too narrow for a
    /// rover to hit, so no node is made in it.
    #[test]
    fn a_gap_with_almost_nothing_to_spare_gets_no_node() {
        let (low, high) = (1.5 - 0.142, 1.5 + 0.142);
        let text = format!(
            r#"
format = 1
name = "hair"
bounds = [0.0, 0.0, 4.0, 3.0]
start = [1.0, 0.8]
goal = [3.0, 2.3]
robot_radius = 0.1
[[polygon]]
points = [[1.9, 0.0], [2.1, 0.0], [2.1, {low}], [1.9, {low}]]
[[polygon]]
points = [[1.9, {high}], [2.1, {high}], [2.1, 3.0], [1.9, 3.0]]
"#
        );
        let map = build(&Scenario::parse(&text, Path::new("hair.toml")).unwrap());
        let in_gap: Vec<_> = map
            .nodes()
            .iter()
            .filter(|p| (1_900..=2_100).contains(&p.x) && (p.y - 1_500).abs() <= 20)
            .collect();
        assert!(in_gap.is_empty(), "{in_gap:?}");
    }

    /// Every library world's graph fits, and joins start and goal where a
    /// way exists (the walled-in goal has none), every edge clear.
    #[test]
    fn library_graphs_join_start_and_goal() {
        for rel in [
            "paper/env1-ex1.toml",
            "paper/env2-ex2.toml",
            "traps/u-trap.toml",
            "traps/dead-end.toml",
            "traps/rooms.toml",
            "traps/walled-in.toml",
        ] {
            let sc = scenario(rel);
            let map = build(&sc);
            let n = map.nodes().len() as u16;
            assert!(n > 10 && (n as usize) < ROUTE_NODES, "{rel}: {n} nodes");
            let (start, goal) = (n - 2, n - 1);
            let route = map.plan(start, goal, &RouteConfig::default());
            assert_eq!(route.is_some(), sc.solvable, "{rel}");
            let r_mm = (sc.robot_radius * 1000.0).round() as u16;
            assert!(map.edges().iter().all(|e| e.clearance_mm >= r_mm), "{rel}");
        }
    }
}
