//! Reference shortest paths, so that path quality is a ratio.
//!
//! Method: obstacles are inflated by the robot radius (a grid node is free
//! when its exact clearance is strictly greater than the radius); A* runs on
//! a grid of `RESOLUTION_M` with 16 move directions (a move is allowed when
//! every node it passes is free); the path found is then string-pulled: each
//! vertex is joined to the farthest later vertex that the robot's disc can
//! reach in a straight line, checked exactly against the geometry.
//!
//! Error bound: the result is a real collision-free path, so it is never
//! shorter than the true shortest path. Before string-pulling, 16-direction
//! moves are at most 1/cos(13.3°) − 1 = 2.7 % longer than the straight
//! segments they approximate; string-pulling only shortens it. So the ratio
//! `driven / reference` is at most 2.7 % (plus one grid cell per turn) below
//! the ratio to the true shortest path. Gaps narrower than the robot's
//! diameter plus one grid cell may be missed.

use crate::geom::V2;
use crate::scenario::Scenario;
use crate::world::World;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Grid resolution, m.
pub const RESOLUTION_M: f64 = 0.02;

/// A reference path.
#[derive(Clone, Debug)]
pub struct Reference {
    /// Length, m.
    pub length: f64,
    /// Vertices, m.
    pub path: Vec<V2>,
}

/// The shortest path for the robot's disc widened by `margin_mm`: the way
/// the planners, which keep that clearance beyond the disc, can take. Beside
/// the disc's own, it tells a goal behind a gap they cannot pass from one
/// they miss.
pub fn with_margin(sc: &Scenario, margin_mm: u16) -> Option<Reference> {
    let wider = Scenario {
        robot_radius: sc.robot_radius + f64::from(margin_mm) / 1000.0,
        ..sc.clone()
    };
    shortest_path(&wider)
}

/// The shortest path for the scenario's robot at time zero, ignoring moving
/// obstacles; `None` when the grid finds no path.
pub fn shortest_path(sc: &Scenario) -> Option<Reference> {
    let world = sc.world();
    let r = sc.robot_radius;
    let h = RESOLUTION_M;
    let [x0, y0, x1, y1] = sc.bounds;
    let nx = ((x1 - x0) / h).ceil() as usize + 1;
    let ny = ((y1 - y0) / h).ceil() as usize + 1;
    let pos = |i: usize, j: usize| V2::new(x0 + i as f64 * h, y0 + j as f64 * h);
    let static_world = World {
        moving: Vec::new(),
        ..world.clone()
    };
    let free = static_world.free_grid([x0, y0], h, [nx, ny], r);
    let start = V2::new(sc.start[0], sc.start[1]);
    let goal = V2::new(sc.goal[0], sc.goal[1]);
    let near = |p: V2| {
        let i = ((p.x - x0) / h).round().clamp(0.0, (nx - 1) as f64) as usize;
        let j = ((p.y - y0) / h).round().clamp(0.0, (ny - 1) as f64) as usize;
        (i, j)
    };
    let (si, sj) = near(start);
    let (gi, gj) = near(goal);
    let (s, g) = (sj * nx + si, gj * nx + gi);
    if !free[s] || !free[g] {
        return None;
    }
    const MOVES: [(i32, i32); 16] = [
        (1, 0),
        (-1, 0),
        (0, 1),
        (0, -1),
        (1, 1),
        (1, -1),
        (-1, 1),
        (-1, -1),
        (1, 2),
        (2, 1),
        (-1, 2),
        (-2, 1),
        (1, -2),
        (2, -1),
        (-1, -2),
        (-2, -1),
    ];
    let heur = |k: usize| {
        let (i, j) = ((k % nx) as f64, (k / nx) as f64);
        ((i - gi as f64).hypot(j - gj as f64) * 1e6) as u64
    };
    let mut dist = vec![u64::MAX; nx * ny];
    let mut prev = vec![usize::MAX; nx * ny];
    let mut heap = BinaryHeap::new();
    dist[s] = 0;
    heap.push(Reverse((heur(s), s)));
    while let Some(Reverse((_, k))) = heap.pop() {
        if k == g {
            break;
        }
        let (i, j) = ((k % nx) as i32, (k / nx) as i32);
        for (di, dj) in MOVES {
            let (ni, nj) = (i + di, j + dj);
            if ni < 0 || nj < 0 || ni >= nx as i32 || nj >= ny as i32 {
                continue;
            }
            let nk = nj as usize * nx + ni as usize;
            if !free[nk] {
                continue;
            }
            // Knight and diagonal moves need the nodes they pass to be free.
            let passes_free = match (di.abs(), dj.abs()) {
                (1, 1) => {
                    free[(j as usize) * nx + ni as usize] && free[(nj as usize) * nx + i as usize]
                }
                (1, 2) | (2, 1) => {
                    // The move passes midway between the two nodes beside
                    // its midpoint: both must be free.
                    let (si, sj) = (di.signum(), dj.signum());
                    let (a, b) = if dj.abs() == 2 {
                        ((i, j + sj), (i + si, j + sj))
                    } else {
                        ((i + si, j), (i + si, j + sj))
                    };
                    free[a.1 as usize * nx + a.0 as usize] && free[b.1 as usize * nx + b.0 as usize]
                }
                _ => true,
            };
            if !passes_free {
                continue;
            }
            let cost = ((di as f64).hypot(dj as f64) * 1e6) as u64;
            let nd = dist[k] + cost;
            if nd < dist[nk] {
                dist[nk] = nd;
                prev[nk] = k;
                heap.push(Reverse((nd + heur(nk), nk)));
            }
        }
    }
    if dist[g] == u64::MAX {
        return None;
    }
    let mut cells = vec![g];
    while *cells.last().unwrap() != s {
        cells.push(prev[*cells.last().unwrap()]);
    }
    cells.reverse();
    let mut pts: Vec<V2> = cells.iter().map(|&k| pos(k % nx, k / nx)).collect();
    pts[0] = start;
    *pts.last_mut().unwrap() = goal;
    // String-pull with exact swept-disc checks.
    let clear = |a: V2, b: V2| static_world.static_sweep_clearance(a, b) > r;
    let mut path = vec![pts[0]];
    let mut i = 0;
    while i < pts.len() - 1 {
        let mut j = pts.len() - 1;
        while j > i + 1 && !clear(pts[i], pts[j]) {
            // Binary-ish back-off keeps this fast on long paths.
            j = if j - i > 64 { i + (j - i) / 2 } else { j - 1 };
        }
        // Walk forward again from the found j as far as it stays visible.
        while j + 1 < pts.len() && clear(pts[i], pts[j + 1]) {
            j += 1;
        }
        path.push(pts[j]);
        i = j;
    }
    let length = path.windows(2).map(|w| w[0].dist(w[1])).sum();
    Some(Reference { length, path })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn open_world_is_the_straight_line() {
        let sc = Scenario::parse(
            "format = 1\nname = \"o\"\nbounds = [0.0, 0.0, 4.0, 3.0]\nstart = [0.5, 0.5]\ngoal = [3.5, 2.5]\n",
            Path::new("o"),
        )
        .unwrap();
        let r = shortest_path(&sc).unwrap();
        assert!((r.length - 13f64.sqrt()).abs() < 1e-9, "{}", r.length);
    }

    #[test]
    fn around_a_circle_by_hand() {
        // Circle radius 0.9 inflated by 0.1: a disc of 1.0 at (2, 1.5);
        // start and goal 1.5 m either side: the shortest path wraps it.
        let sc = Scenario::parse(
            "format = 1\nname = \"c\"\nbounds = [0.0, 0.0, 4.0, 3.0]\nstart = [0.5, 1.5]\ngoal = [3.5, 1.5]\n[[circle]]\ncenter = [2.0, 1.5]\nradius = 0.9\n",
            Path::new("c"),
        )
        .unwrap();
        let r = shortest_path(&sc).unwrap();
        // Two tangents √(1.5² − 1²) and an arc of 2·(π/2 − acos(1/1.5)).
        let want = 2.0 * (1.5f64.powi(2) - 1.0).sqrt()
            + 2.0 * (std::f64::consts::FRAC_PI_2 - (1.0f64 / 1.5).acos());
        assert!(r.length >= want - 1e-9, "{} < {want}", r.length);
        assert!(r.length < want * 1.01, "{} vs {want}", r.length);
    }

    #[test]
    fn walled_in_goal_has_no_path_and_shared_files_agree() {
        let shared = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/scenarios/examples");
        let enclosed = Scenario::load(&shared.join("ex-enclosed-1-0.toml")).unwrap();
        assert!(shortest_path(&enclosed).is_none());
        // The file records 5.569 m (4 cm grid, 16 directions, no smoothing);
        // ours is a smoothed path on a finer grid: no longer, at most a little shorter.
        let u = Scenario::load(&shared.join("ex-utrap-1-0.toml")).unwrap();
        let r = shortest_path(&u).unwrap();
        assert!(
            r.length <= 5.569 + 0.02 && r.length > 5.569 * 0.95,
            "{}",
            r.length
        );
    }
}
