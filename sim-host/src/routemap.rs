//! The waypoint graph the `route` planner plans over (planner-core's
//! [`route`](planner_core::route) layer): built here from the scenario's
//! known map, because the world's geometry lives here; the planning and the
//! following are the core's.
//!
//! Nodes on a square grid wherever the rover's disc plus the planner's
//! clearance (40 mm) fits (0.2 m apart, wider for large worlds so that the graph
//! stays within [`ROUTE_NODES`]), edges to the eight neighbours where the
//! swept disc fits all the way, and the start and the goal joined to the
//! grid nodes they see within 2.5 cells. Each edge carries its clearance:
//! the least distance from its segment to the static geometry.

use crate::geom::V2;
use crate::planners::{to_mm, to_point};
use crate::scenario::Scenario;
use crate::world::World;
use planner_core::route::RouteMap;
use std::collections::HashMap;

/// Node capacity of the simulator's maps.
pub const ROUTE_NODES: usize = 1024;
/// Edge capacity of the simulator's maps.
pub const ROUTE_EDGES: usize = 4608;
/// The simulator's map type.
pub type SimRouteMap = RouteMap<ROUTE_NODES, ROUTE_EDGES>;

/// The grid's spacing in small worlds, m.
pub const GRID_M: f64 = 0.2;

/// Beyond the disc, what a node or an edge must keep clear, m: the
/// planner's default clearance.
const MARGIN_M: f64 = 0.04;

/// Beyond the disc, what the edges of a route keep clear while such a
/// route exists, m (`RouteConfig::preferred_clearance_mm`): twice the
/// planner's clearance. With routes at 40 mm, one in barn-193 (seed 1) led
/// the rover to turn beside a 10 cm block none of its beams had seen, then
/// into it (docs/bench.md, "The route layer").
pub const PREFERRED_MARGIN_M: f64 = 0.08;

/// The graph for `sc` (static obstacles only), with the start and the goal
/// among its nodes.
pub fn build(sc: &Scenario) -> SimRouteMap {
    let world = World {
        moving: Vec::new(),
        ..World::from_scenario(sc)
    };
    let r = sc.robot_radius;
    let need = r + MARGIN_M;
    let [x0, y0, x1, y1] = sc.bounds;
    // About 900 grid points at most, leaving room for the start and goal.
    let s = GRID_M.max(((x1 - x0) * (y1 - y0) / 900.0).sqrt());
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
    // The start and the goal, joined to the grid nodes they see nearby
    // (and to each other when in sight).
    let ends = [sc.start, sc.goal].map(|p| V2::new(p[0], p[1]));
    let mut end_nodes = Vec::new();
    for p in ends {
        let Ok(k) = map.add_node(to_point(p)) else {
            continue;
        };
        end_nodes.push((k, p));
        for &((i, j), b) in &cells {
            let q = at(i, j);
            if p.dist(q) <= 2.5 * s {
                let c = world.static_sweep_clearance(p, q);
                if c >= r {
                    let _ = map.add_edge(k, b, to_mm(c));
                }
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

#[cfg(test)]
mod tests {
    use super::*;
    use planner_core::route::RouteConfig;
    use std::path::Path;

    fn scenario(rel: &str) -> Scenario {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
        Scenario::load(&dir.join(rel)).unwrap()
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
