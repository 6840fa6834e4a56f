//! The route layer for a known map (docs/algorithms.md §4, after Al-Ansarry,
//! Al-Darraji & Honi 2023): Dijkstra finds candidate routes on a waypoint
//! graph, the potential field scores each candidate's safety and the safest
//! is taken; the online EAPF planner then drives from waypoint to waypoint
//! with its sensors, and a leg it cannot drive (its planner says
//! unreachable, or the leg takes too long) is blocked and the route planned
//! again from where the rover stands: the paper's switch to another path
//! when one is blocked.
//!
//! Allocation-free: the map's capacity is in its type (`N` nodes, `E`
//! edges; a few dozen fit an MCU's flash, the simulator uses thousands),
//! and a search keeps its work on the stack (7 bytes a node, 1 an edge; a
//! plan also its candidates, 2 bytes a node each). A search is `O(N² + E)`
//! (each node's own edges are listed, [`RouteMap`]), and runs only at the
//! start and when a leg is blocked.
//!
//! Ours, where the paper's page is silent:
//! - A map gives each edge its clearance: the least distance from the
//!   segment to any obstacle, worked out by whoever builds the map (the
//!   simulator from the world's geometry). Safety is scored from it, so the
//!   core needs no obstacle list.
//! - Safety is the repulsive potential of eq. 3 (Khatib's form,
//!   `(1/c − 1/ρ₀)²` for a clearance `c` below the influence distance
//!   `ρ₀`), taken along each edge: an edge's risk is its length times
//!   `((ρ₀ − c)/c)²` (the same form times `ρ₀²`), a route's the sum.
//! - The candidates: the shortest route, then up to
//!   `RouteConfig::candidates − 1` more, each the shortest once the edges
//!   of those found are made twice as long (so each differs from the last).
//!   Of those no longer than `1 + slack` times the shortest, the one of
//!   least risk is taken (the shorter on a tie): safety is bought with a
//!   bounded detour only.
//! - Edges at least `preferred_clearance_mm` clear are kept to while a
//!   route over them is within the slack of the shortest route over any
//!   edge: safety bought with a bounded detour, as for the candidates.
//! - A waypoint counts as passed within `pass_mm` (before a tight edge,
//!   within what that edge has to spare), the goal as reached within the
//!   planner's goal tolerance. Waypoints in a row that lie
//!   within `straighten_mm` of one straight line are one leg, driven to
//!   its far end: the planner meets a corridor or a gap as it would
//!   without a map, not as a chain of near targets.
//! - A leg blocked once may have failed for the sensors' noise rather
//!   than the map: when the blocks leave no route, they are forgotten
//!   (`RouteConfig::unblock_rounds` times, once by default) and the route
//!   planned again over the whole map.
//! - No route on the graph is no proof that there is no way (a coarse
//!   graph misses a narrow gap): the planner then drives to the goal
//!   directly, and its own give-up budget (the escape's) decides whether
//!   the goal is unreachable.

use crate::eapf::config::Config;
use crate::fixed::{hypot, Point};
use crate::{Guard, Output, Planner, Pose, RawCounts, Status};

/// Why a map refused a node or an edge.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MapError {
    /// No room left (the map's capacity).
    Full,
    /// An edge names a node the map does not have, or joins a node to
    /// itself.
    BadEdge,
}

/// An edge of the waypoint graph, usable both ways.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Edge {
    /// One end (a node index).
    pub a: u16,
    /// The other end.
    pub b: u16,
    /// The least distance from the segment to any obstacle, mm.
    pub clearance_mm: u16,
    /// Its length, mm (worked out when it is added).
    pub length_mm: u16,
    /// Found undrivable: no route uses it.
    pub blocked: bool,
}

impl Edge {
    /// An edge's risk: `length · ((ρ₀ − c)/c)²` for a clearance `c`
    /// below ρ₀, else 0 (the repulsive potential, module docs). A clearance
    /// of 0 counts as 1 mm.
    pub fn risk(&self, influence_mm: u16) -> u64 {
        let c = self.clearance_mm.max(1) as u64;
        let rho = influence_mm as u64;
        if c >= rho {
            return 0;
        }
        // (ρ₀ − c)/c in Q8: below 2^24 (ρ₀ < 2^16), squared below 2^48,
        // times a u16 length below 2^64.
        let q = ((rho - c) << 8) / c;
        (self.length_mm as u64 * q * q) >> 16
    }
}

/// A waypoint graph of at most `N` nodes and `E` edges, world mm.
///
/// Each node keeps a list of its own edges (its newest edge, and for each
/// edge the next one at either end: 2 bytes a node and 4 an edge), so that
/// a search looks at a node's few edges rather than at all of them: a
/// search is `O(N² + E)`, and a map of a few thousand nodes (the
/// simulator's, on a 0.2 m grid) is planned in milliseconds.
#[derive(Clone, Debug)]
pub struct RouteMap<const N: usize, const E: usize> {
    nodes: heapless::Vec<Point, N>,
    edges: heapless::Vec<Edge, E>,
    /// Each node's newest edge (`NONE`: none).
    first: [u16; N],
    /// For each edge, the next older edge at its `a` end and at its `b` end.
    next: [[u16; 2]; E],
}

impl<const N: usize, const E: usize> Default for RouteMap<N, E> {
    fn default() -> Self {
        Self::new()
    }
}

/// How routes are chosen and followed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RouteConfig {
    /// The potential's influence distance ρ₀, mm: an edge farther than
    /// this from every obstacle carries no risk.
    pub influence_mm: u16,
    /// How much longer than the shortest a safer route may be, percent.
    pub slack_pct: u16,
    /// How many candidates Dijkstra offers (1: the shortest only; at most
    /// 8 are looked at).
    pub candidates: u8,
    /// A waypoint is passed once the rover is this near it, mm (before an
    /// edge with less than the planner's clearance to spare, only as near
    /// as that edge has to spare).
    pub pass_mm: u16,
    /// Routes keep to edges at least this clear of obstacles, mm, while
    /// such a route is within `slack_pct` of the shortest over any edge;
    /// else narrower edges are used too (0: any edge).
    pub preferred_clearance_mm: u16,
    /// Planner cycles a leg may take before it is given up (blocked) like
    /// one the planner gives up on: a leg is a few hundred mm, and one the
    /// rover cannot pass (a gap the graph fits but the planner's safety
    /// corridor barely does) would otherwise hold it for the planner's
    /// whole give-up budget.
    pub leg_cycles: u16,
    /// Waypoints in a row that all lie within this of the straight line
    /// from the waypoint passed last to the last of them are one leg, mm
    /// (0: every waypoint its own leg). A grid graph's routes are chains of
    /// short edges; driven one by one, each a near target, the planner
    /// crawls (in a corridor the simulator's graph has a node every
    /// 0.2 m). The straight leg stays within this of the edges it
    /// replaces, so its clearance is theirs less this.
    pub straighten_mm: u16,
    /// How many times the blocked legs are forgotten when they leave no
    /// route (module docs). A leg is blocked on one failure, which may be
    /// the sensors' noise or a bad turn rather than the map: box-23 of the
    /// box worlds with seed 2 blocked its way in a gap and was reported
    /// unreachable; with one round more it reached the goal
    /// (the commit history, "The route layer").
    pub unblock_rounds: u8,
}

impl Default for RouteConfig {
    /// ρ₀ = 200 mm (with 300, the classical APF baseline's ρ, the safest
    /// candidate ran wider of every obstacle than the preferred clearance
    /// asks, for longer paths: the commit history "The route layer"), 25 % slack
    /// (the product's path-length aim), four candidates, waypoints passed
    /// within 250 mm (a step or so: the planner does not stop at each),
    /// any edge clearance, 100 cycles a leg, waypoints within 20 mm of a
    /// straight leg merged into it (half the planner's clearance; 0 and
    /// 40 mm measured worse, the commit history "The route layer"), the blocks
    /// forgotten once.
    fn default() -> Self {
        RouteConfig {
            influence_mm: 200,
            slack_pct: 25,
            candidates: 4,
            pass_mm: 250,
            preferred_clearance_mm: 0,
            leg_cycles: 100,
            straighten_mm: 20,
            unblock_rounds: 1,
        }
    }
}

/// A route: node indices from start to goal, its length and risk.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Route<const N: usize> {
    /// The nodes in order.
    pub nodes: heapless::Vec<u16, N>,
    /// Summed edge lengths, mm.
    pub length_mm: u32,
    /// Summed edge risks (see the module docs).
    pub risk: u64,
}

/// Nothing: a node index no node has.
const NONE: u16 = u16::MAX;

impl<const N: usize, const E: usize> RouteMap<N, E> {
    /// An empty map.
    pub const fn new() -> Self {
        RouteMap {
            nodes: heapless::Vec::new(),
            edges: heapless::Vec::new(),
            first: [NONE; N],
            next: [[NONE; 2]; E],
        }
    }

    /// Add a waypoint; its index.
    pub fn add_node(&mut self, p: Point) -> Result<u16, MapError> {
        // Indices are u16 and `NONE` is reserved.
        if self.nodes.len() >= (NONE as usize).min(N) {
            return Err(MapError::Full);
        }
        self.nodes.push(p).map_err(|_| MapError::Full)?;
        Ok(self.nodes.len() as u16 - 1)
    }

    /// Join nodes `a` and `b` by a straight edge with `clearance_mm` to
    /// the nearest obstacle.
    pub fn add_edge(&mut self, a: u16, b: u16, clearance_mm: u16) -> Result<(), MapError> {
        let (Some(&pa), Some(&pb)) = (self.nodes.get(a as usize), self.nodes.get(b as usize))
        else {
            return Err(MapError::BadEdge);
        };
        if a == b {
            return Err(MapError::BadEdge);
        }
        // Edge indices are u16 too, `NONE` reserved.
        let k = self.edges.len();
        if k >= NONE as usize {
            return Err(MapError::Full);
        }
        let (dx, dy) = pa.to(pb);
        let edge = Edge {
            a,
            b,
            clearance_mm,
            length_mm: hypot(dx, dy),
            blocked: false,
        };
        self.edges.push(edge).map_err(|_| MapError::Full)?;
        // Both ends' lists start with it now (the nodes exist: checked above).
        let (Some(fa), Some(fb), Some(next)) = (
            self.first.get(a as usize).copied(),
            self.first.get(b as usize).copied(),
            self.next.get_mut(k),
        ) else {
            return Err(MapError::Full);
        };
        *next = [fa, fb];
        self.first[a as usize] = k as u16;
        self.first[b as usize] = k as u16;
        Ok(())
    }

    /// The edges at node `u` (newest first), each with its index and the
    /// node at its other end.
    fn edges_at(&self, u: u16) -> impl Iterator<Item = (usize, &Edge, u16)> + '_ {
        let mut k = self.first.get(u as usize).copied().unwrap_or(NONE);
        core::iter::from_fn(move || {
            let i = k as usize;
            let e = self.edges.get(i)?;
            k = self.next_at(i, u);
            Some((i, e, if e.a == u { e.b } else { e.a }))
        })
    }

    /// The edge after edge `k` in node `u`'s list (`NONE`: the last).
    fn next_at(&self, k: usize, u: u16) -> u16 {
        match (self.edges.get(k), self.next.get(k)) {
            (Some(e), Some(n)) => n[usize::from(e.a != u)],
            _ => NONE,
        }
    }

    /// The waypoints.
    pub fn nodes(&self) -> &[Point] {
        &self.nodes
    }

    /// The edges.
    pub fn edges(&self) -> &[Edge] {
        &self.edges
    }

    /// The node nearest `p` (the first of equals), if any.
    pub fn nearest_node(&self, p: Point) -> Option<u16> {
        let d = |q: &Point| {
            let (dx, dy) = p.to(*q);
            (dx as i64 * dx as i64 + dy as i64 * dy as i64) as u64
        };
        let (i, _) = self
            .nodes
            .iter()
            .enumerate()
            .min_by_key(|&(i, q)| (d(q), i))?;
        Some(i as u16)
    }

    /// Forget every block (a new round over the map).
    pub fn unblock_all(&mut self) {
        for e in self.edges.iter_mut() {
            e.blocked = false;
        }
    }

    /// Block the edges between `a` and `b` (either way): routes avoid them.
    pub fn block(&mut self, a: u16, b: u16) {
        let mut k = self.first.get(a as usize).copied().unwrap_or(NONE) as usize;
        while k < self.edges.len() {
            let next = self.next_at(k, a);
            if let Some(e) = self.edges.get_mut(k) {
                let other = if e.a == a { e.b } else { e.a };
                e.blocked |= other == b;
            }
            k = next as usize;
        }
    }

    /// Dijkstra from `from` to `to` over the unblocked edges, each edge's
    /// length doubled once for every time it is in `penalised` (earlier
    /// candidates). `None` if `to` cannot be reached.
    fn shortest(
        &self,
        from: u16,
        to: u16,
        min_clearance_mm: u16,
        penalised: &[&Route<N>],
    ) -> Option<Route<N>> {
        let n = self.nodes.len();
        if from as usize >= n || to as usize >= n {
            return None;
        }
        // How often each edge is on an earlier candidate, once.
        let mut times = [0u8; E];
        for r in penalised {
            for w in r.nodes.windows(2) {
                for (k, _, v) in self.edges_at(w[0]) {
                    if let (true, Some(t)) = (v == w[1], times.get_mut(k)) {
                        *t = t.saturating_add(1);
                    }
                }
            }
        }
        let mut dist = [u32::MAX; N];
        let mut prev = [NONE; N];
        let mut done = [false; N];
        dist[from as usize] = 0;
        loop {
            // The nearest node not yet done (O(N): the maps are small).
            let mut u = NONE;
            let mut best = u32::MAX;
            for (i, (&d, &f)) in dist.iter().zip(done.iter()).take(n).enumerate() {
                if !f && d < best {
                    best = d;
                    u = i as u16;
                }
            }
            if u == NONE || u == to {
                break;
            }
            done[u as usize] = true;
            for (k, e, v) in self.edges_at(u) {
                if e.blocked || e.clearance_mm < min_clearance_mm {
                    continue;
                }
                let t = times.get(k).copied().unwrap_or(0);
                let w = (e.length_mm as u32) << t.min(8);
                let alt = best.saturating_add(w);
                if alt < dist[v as usize] {
                    dist[v as usize] = alt;
                    prev[v as usize] = u;
                }
            }
        }
        if dist[to as usize] == u32::MAX {
            return None;
        }
        // Walk back from `to`, then reverse.
        let mut nodes: heapless::Vec<u16, N> = heapless::Vec::new();
        let mut at = to;
        while at != NONE {
            nodes.push(at).ok()?;
            at = prev[at as usize];
        }
        nodes.reverse();
        Some(self.measured(nodes))
    }

    /// A route through `nodes` with its true length (its risk is scored
    /// by [`RouteMap::plan`]).
    fn measured(&self, nodes: heapless::Vec<u16, N>) -> Route<N> {
        let mut route = Route {
            nodes,
            length_mm: 0,
            risk: 0,
        };
        for w in route.nodes.windows(2) {
            if let Some(e) = self.edge_between(w[0], w[1]) {
                route.length_mm += e.length_mm as u32;
            }
        }
        route
    }

    /// The shortest unblocked edge between `a` and `b`.
    fn edge_between(&self, a: u16, b: u16) -> Option<&Edge> {
        self.edges_at(a)
            .filter(|&(_, e, v)| v == b && !e.blocked)
            .map(|(_, e, _)| e)
            .min_by_key(|e| e.length_mm)
    }

    /// The route from `from` to `to` (node indices): of Dijkstra's
    /// candidates within the length slack, the one of least risk (module
    /// docs), over the edges of the preferred clearance if they join them
    /// within the slack of the shortest route over any edge. `None` if no
    /// unblocked route does.
    pub fn plan(&self, from: u16, to: u16, cfg: &RouteConfig) -> Option<Route<N>> {
        let (any, shortest) = self.plan_over(from, to, cfg, 0)?;
        if cfg.preferred_clearance_mm == 0 {
            return Some(any);
        }
        match self.plan_over(from, to, cfg, cfg.preferred_clearance_mm) {
            Some((r, _))
                if r.length_mm as u64 * 100 <= shortest as u64 * (100 + cfg.slack_pct as u64) =>
            {
                Some(r)
            }
            _ => Some(any),
        }
    }

    /// [`RouteMap::plan`] over the edges at least `min_clearance_mm` clear,
    /// and the length of the shortest route over them.
    fn plan_over(
        &self,
        from: u16,
        to: u16,
        cfg: &RouteConfig,
        min_clearance_mm: u16,
    ) -> Option<(Route<N>, u32)> {
        let mut best = self.shortest(from, to, min_clearance_mm, &[])?;
        let shortest = best.length_mm;
        best.risk = self.route_risk(&best, cfg.influence_mm);
        let limit = best.length_mm as u64 * (100 + cfg.slack_pct as u64) / 100;
        let mut found = [None, None, None, None, None, None, None, None];
        let k = (cfg.candidates as usize).clamp(1, found.len());
        found[0] = Some(best.clone());
        for i in 1..k {
            let mut c = {
                let earlier: heapless::Vec<&Route<N>, 8> = found.iter().flatten().collect();
                match self.shortest(from, to, min_clearance_mm, &earlier) {
                    // The same again: no other route is left to offer.
                    Some(c) if !earlier.iter().any(|r| r.nodes == c.nodes) => c,
                    _ => break,
                }
            };
            c.risk = self.route_risk(&c, cfg.influence_mm);
            if c.length_mm as u64 <= limit && (c.risk, c.length_mm) < (best.risk, best.length_mm) {
                best = c.clone();
            }
            found[i] = Some(c);
        }
        Some((best, shortest))
    }

    /// The summed risk of `r`'s edges.
    fn route_risk(&self, r: &Route<N>, influence_mm: u16) -> u64 {
        r.nodes
            .windows(2)
            .filter_map(|w| self.edge_between(w[0], w[1]))
            .map(|e| e.risk(influence_mm))
            .fold(0u64, u64::saturating_add)
    }
}

/// How far `p` lies from the segment `a`–`b`, mm (rounded down; a point
/// beside the segment by its perpendicular, others by the nearer end).
/// Not `liquid`'s `segment_distance` (the foot of the perpendicular,
/// then its distance): the two round differently by a millimetre, which
/// moved 8 of 500 routes of BARN and the generated worlds (seed 1) across
/// the `straighten_mm` line, and the measured figures are this one's.
fn off_segment_mm(a: Point, b: Point, p: Point) -> u32 {
    let (dx, dy) = a.to(b);
    let (px, py) = a.to(p);
    let (dx, dy, px, py) = (dx as i64, dy as i64, px as i64, py as i64);
    let along = px * dx + py * dy;
    let len_sq = dx * dx + dy * dy;
    if along <= 0 || len_sq == 0 {
        return hypot(px as i32, py as i32) as u32;
    }
    if along >= len_sq {
        let (qx, qy) = b.to(p);
        return hypot(qx, qy) as u32;
    }
    // |cross| / |ab|: |ab| ≥ 1 here, and both below 2^34.
    let cross = (px * dy - py * dx).unsigned_abs();
    let len = hypot(dx as i32, dy as i32).max(1) as u64;
    (cross / len) as u32
}

/// The EAPF planner driven along a route of a known map (module docs).
pub struct RoutePlanner<const N: usize, const E: usize> {
    planner: Planner,
    map: RouteMap<N, E>,
    cfg: RouteConfig,
    goal: Point,
    /// The route's nodes; `next` indexes the waypoint being driven to
    /// (`route.len()`: the goal itself).
    route: heapless::Vec<u16, N>,
    next: usize,
    planned: bool,
    unreachable: bool,
    /// Cycles spent on the current leg.
    on_leg: u16,
    /// Rounds left of `RouteConfig::unblock_rounds`.
    unblocks: u8,
}

impl<const N: usize, const E: usize> RoutePlanner<N, E> {
    /// Drive to `goal` over `map` (planned at the first step, from the node
    /// nearest the rover to the node nearest the goal).
    pub fn new(config: Config, map: RouteMap<N, E>, cfg: RouteConfig, goal: Point) -> Self {
        RoutePlanner {
            planner: Planner::new(config, goal),
            map,
            cfg,
            goal,
            route: heapless::Vec::new(),
            next: 0,
            planned: false,
            unreachable: false,
            on_leg: 0,
            unblocks: cfg.unblock_rounds,
        }
    }

    /// The EAPF planner underneath (its goal is the current waypoint).
    pub fn planner(&self) -> &Planner {
        &self.planner
    }

    /// The map (with the legs found blocked).
    pub fn map(&self) -> &RouteMap<N, E> {
        &self.map
    }

    /// The waypoints still to come, then the goal.
    pub fn waypoints(&self) -> impl Iterator<Item = Point> + '_ {
        self.route().skip(self.next)
    }

    /// The whole route being followed (the waypoints passed included),
    /// then the goal.
    pub fn route(&self) -> impl Iterator<Item = Point> + '_ {
        let nodes = self.map.nodes();
        self.route
            .iter()
            .filter_map(|&i| nodes.get(i as usize).copied())
            .chain(core::iter::once(self.goal))
    }

    /// Plan from the node nearest `at`; when the blocks leave no route,
    /// forget them if a round is left; without a route, head for the goal
    /// directly (module docs).
    fn replan(&mut self, at: Point) {
        let ends = (self.map.nearest_node(at), self.map.nearest_node(self.goal));
        let mut route = None;
        if let (Some(from), Some(to)) = ends {
            route = self.map.plan(from, to, &self.cfg);
            let blocked = self.map.edges().iter().any(|e| e.blocked);
            if route.is_none() && blocked && self.unblocks > 0 {
                self.unblocks -= 1;
                self.map.unblock_all();
                route = self.map.plan(from, to, &self.cfg);
            }
        }
        self.route = route.map(|r| r.nodes).unwrap_or_default();
        self.next = 0;
        self.planned = true;
    }

    /// Waypoint `i` of the route; `route.len()` is the goal.
    fn point(&self, i: usize) -> Option<Point> {
        match self.route.get(i) {
            Some(&n) => self.map.nodes().get(n as usize).copied(),
            None => (i == self.route.len()).then_some(self.goal),
        }
    }

    /// The index of the waypoint being driven to (`route.len()`: the goal):
    /// from the next one on, the last of those that all lie within
    /// `straighten_mm` of the straight line from the waypoint passed last
    /// to it (`RouteConfig::straighten_mm`).
    fn target_index(&self) -> usize {
        let from = match self.next.checked_sub(1).and_then(|i| self.point(i)) {
            Some(p) if self.cfg.straighten_mm > 0 => p,
            _ => return self.next,
        };
        let mut k = self.next;
        while let Some(to) = self.point(k + 1) {
            let near = (self.next..=k)
                .filter_map(|i| self.point(i))
                .all(|p| off_segment_mm(from, to, p) <= self.cfg.straighten_mm as u32);
            if !near {
                break;
            }
            k += 1;
        }
        k
    }

    /// The point being driven to: a waypoint, or the goal.
    fn target(&self) -> Point {
        self.point(self.target_index()).unwrap_or(self.goal)
    }

    /// How near waypoint `k` the rover must come to pass it: `pass_mm`,
    /// or, before a tight edge, only what that edge has to spare. A rover
    /// that passes a waypoint early cuts the corner; an edge with less to
    /// spare than the planner's clearance beyond the disc and that
    /// clearance (a gap a little wider than the rover needs) would then be
    /// met off its line, at the mouth's edge, where the safety rule stops
    /// the rover (the library's narrow passage, 10 mm to spare: on four
    /// seeds of five the rover turned about at the mouth, 3.1–3.8× the
    /// reference). Roomier edges keep `pass_mm`: with `pass_mm` cut to
    /// the spare before every edge with less than it to spare, the
    /// examples' routes were longer (the commit history, "The route layer").
    fn pass_mm(&self, k: usize) -> u16 {
        let (Some(&a), Some(&b)) = (self.route.get(k), self.route.get(k + 1)) else {
            return self.cfg.pass_mm;
        };
        let cfg = self.planner.config();
        let need = cfg.robot_radius_mm + cfg.clearance_mm;
        let spare = self
            .map
            .edges_at(a)
            .filter(|&(_, _, other)| other == b)
            .map(|(_, e, _)| e.clearance_mm.saturating_sub(need))
            .max()
            .unwrap_or(u16::MAX);
        if spare < cfg.clearance_mm {
            spare
        } else {
            self.cfg.pass_mm
        }
    }

    /// One cycle, as [`Planner::step_raw`]: waypoints within `pass_mm` are
    /// passed; a waypoint reached is passed; a leg the planner gives up on,
    /// or that takes more than `leg_cycles`, is blocked and the route
    /// planned again from here.
    pub fn step_raw(&mut self, pose: Pose, raw: &RawCounts) -> Output {
        if self.unreachable {
            return Output::stop(pose.heading, Status::Unreachable);
        }
        if !self.planned {
            self.replan(pose.position);
        }
        // At most one pass and one replan per node of the route each
        // cycle: the loop ends.
        for _ in 0..=2 * N + 2 {
            let k = self.target_index();
            let target = self.point(k).unwrap_or(self.goal);
            let is_goal = k >= self.route.len();
            if self.planner.goal() != target {
                self.planner.set_goal(target);
                self.on_leg = 0;
            }
            if !is_goal {
                let (dx, dy) = pose.position.to(target);
                if hypot(dx, dy) <= self.pass_mm(k) {
                    self.next = k + 1;
                    continue;
                }
            }
            let out = self.planner.step_raw(pose, raw);
            self.on_leg = self.on_leg.saturating_add(1);
            // A leg given up: by the planner, or for taking too long.
            let given_up = match out.status {
                Status::Unreachable => true,
                Status::Moving => self.on_leg > self.cfg.leg_cycles,
                _ => false,
            };
            match out.status {
                Status::Arrived if !is_goal => self.next = k + 1,
                // The waypoints merged into the last leg are passed too.
                Status::Arrived => {
                    self.next = k;
                    return out;
                }
                _ if given_up && !is_goal => {
                    // Block the leg's edges from the last waypoint to this
                    // one (to the first: from the node nearest the rover)
                    // and plan again.
                    let from = match self.next.checked_sub(1) {
                        Some(i) => self.route.get(i).copied(),
                        None => self.map.nearest_node(pose.position),
                    };
                    let mut blocked = false;
                    let mut a = from;
                    for i in self.next..=k {
                        let b = self.route.get(i).copied();
                        if let (Some(a), Some(b)) = (a, b) {
                            if a != b {
                                self.map.block(a, b);
                                blocked = true;
                            }
                        }
                        a = b;
                    }
                    if !blocked {
                        // A waypoint the rover stands at yet cannot reach:
                        // no leg to block; drive to the goal directly.
                        self.route.clear();
                    }
                    if !self.route.is_empty() {
                        self.replan(pose.position);
                    }
                    // A fresh start for the planner (its give-up cleared),
                    // even towards the same point.
                    self.planner.set_goal(self.target());
                    self.on_leg = 0;
                }
                Status::Unreachable => {
                    self.unreachable = true;
                    return out;
                }
                _ => return out,
            }
        }
        self.unreachable = true;
        Output::stop(pose.heading, Status::Unreachable)
    }

    /// The guard during an advance, as [`Planner::guard_raw`].
    pub fn guard_raw(&mut self, raw: &RawCounts, remaining_mm: u16) -> Guard {
        self.planner.guard_raw(raw, remaining_mm)
    }
}

impl<const N: usize, const E: usize> crate::Navigator for RoutePlanner<N, E> {
    fn step_raw(&mut self, pose: Pose, raw: &RawCounts) -> Output {
        RoutePlanner::step_raw(self, pose, raw)
    }
    fn guard_raw(&mut self, raw: &RawCounts, remaining_mm: u16) -> Guard {
        RoutePlanner::guard_raw(self, raw, remaining_mm)
    }
    fn config(&self) -> &Config {
        self.planner().config()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    proptest::proptest! {
        /// The search over each node's own edges finds routes as long as
        /// the shortest by Bellman-Ford over the whole edge list, blocked
        /// and too narrow edges left out, on random graphs (parallel
        /// edges included); and a route found is a chain of such edges.
        #[test]
        fn the_search_over_node_lists_finds_the_shortest_length(
            points in proptest::collection::vec((-2_000i16..2_000, -2_000i16..2_000), 2..12),
            edges in proptest::collection::vec((0u16..12, 0u16..12, 0u16..300), 0..40),
            blocked in proptest::collection::vec((0u16..12, 0u16..12), 0..4),
            min_clearance in 0u16..200,
        ) {
            let mut m: RouteMap<12, 40> = RouteMap::new();
            for &(x, y) in &points {
                m.add_node(Point::new(x, y)).unwrap();
            }
            let n = points.len() as u16;
            for &(a, b, c) in &edges {
                let r = m.add_edge(a, b, c);
                proptest::prop_assert_eq!(r.is_ok(), a < n && b < n && a != b);
            }
            for &(a, b) in &blocked {
                m.block(a, b);
            }
            let usable = |e: &Edge| !e.blocked && e.clearance_mm >= min_clearance;
            // Bellman-Ford from node 0.
            let mut dist = std::vec![u32::MAX; n as usize];
            dist[0] = 0;
            for _ in 0..n {
                for e in m.edges().iter().filter(|e| usable(e)) {
                    for (u, v) in [(e.a, e.b), (e.b, e.a)] {
                        let d = dist[u as usize].saturating_add(e.length_mm as u32);
                        if d < dist[v as usize] {
                            dist[v as usize] = d;
                        }
                    }
                }
            }
            for to in 1..n {
                let found = m.shortest(0, to, min_clearance, &[]);
                proptest::prop_assert_eq!(found.as_ref().map(|r| r.length_mm), (dist[to as usize] != u32::MAX).then_some(dist[to as usize]));
                if let Some(r) = found {
                    proptest::prop_assert_eq!(r.nodes.first(), Some(&0));
                    proptest::prop_assert_eq!(r.nodes.last(), Some(&to));
                    for w in r.nodes.windows(2) {
                        proptest::prop_assert!(m.edges().iter().any(|e| usable(e)
                            && ((e.a, e.b) == (w[0], w[1]) || (e.a, e.b) == (w[1], w[0]))));
                    }
                }
            }
        }
    }

    /// A ladder: two rails of `n` nodes 500 mm apart, rungs between them;
    /// the lower rail runs 50 mm from obstacles, the upper 400 mm.
    fn ladder(n: u16) -> RouteMap<32, 96> {
        let mut m = RouteMap::new();
        for i in 0..n {
            m.add_node(Point::new(i as i16 * 500, 0)).unwrap();
            m.add_node(Point::new(i as i16 * 500, 500)).unwrap();
        }
        for i in 0..n {
            let (lo, hi) = (2 * i, 2 * i + 1);
            m.add_edge(lo, hi, 200).unwrap();
            if i + 1 < n {
                m.add_edge(lo, lo + 2, 50).unwrap();
                m.add_edge(hi, hi + 2, 400).unwrap();
            }
        }
        m
    }

    #[test]
    fn dijkstra_finds_the_shortest_route() {
        let m = ladder(5);
        let r = m.shortest(0, 8, 0, &[]).unwrap();
        assert_eq!(r.nodes.as_slice(), &[0, 2, 4, 6, 8]);
        assert_eq!(r.length_mm, 2_000);
        // Blocked rails are gone around.
        let mut m = m;
        m.block(4, 2);
        let r = m.shortest(0, 8, 0, &[]).unwrap();
        assert_eq!(r.length_mm, 3_000, "{:?}", r.nodes);
        let e = m.edges()[3];
        assert!(!r
            .nodes
            .windows(2)
            .any(|w| (w[0], w[1]) == (e.a, e.b) || (w[0], w[1]) == (e.b, e.a)));
    }

    #[test]
    fn risk_is_the_repulsive_potential_along_the_edge() {
        let e = |clearance_mm| Edge {
            a: 0,
            b: 1,
            clearance_mm,
            length_mm: 1_000,
            blocked: false,
        };
        let risk = |c| e(c).risk(300);
        assert_eq!(risk(300), 0);
        assert_eq!(risk(1_000), 0);
        // ((300 − 100)/100)² = 4 per mm of length.
        assert_eq!(risk(100), 4_000);
        // ((300 − 150)/150)² = 1.
        assert_eq!(risk(150), 1_000);
        assert!(risk(50) > risk(100) && risk(0) > risk(50));
    }

    #[test]
    fn the_safer_route_is_taken_within_the_slack() {
        // The lower rail is shortest (2,000 mm) but runs 50 mm from
        // obstacles (risk 2,000 · 25); the upper one (two rungs more:
        // 3,000 mm, 1.5×) runs 400 mm from them; ρ₀ 300 mm.
        let m = ladder(5);
        let tight = RouteConfig {
            slack_pct: 25,
            influence_mm: 300,
            ..RouteConfig::default()
        };
        let r = m.plan(0, 8, &tight).unwrap();
        assert_eq!(r.length_mm, 2_000, "25 % allows no detour of 50 %");
        let loose = RouteConfig {
            slack_pct: 60,
            ..tight
        };
        let r = m.plan(0, 8, &loose).unwrap();
        assert_eq!(r.nodes.as_slice(), &[0, 1, 3, 5, 7, 9, 8]);
        // Only its two rungs (200 mm clear) carry risk: 2 · 500 · 0.25.
        assert_eq!((r.length_mm, r.risk), (3_000, 250));
        // One candidate: the shortest, whatever its risk.
        let one = RouteConfig {
            candidates: 1,
            ..loose
        };
        assert_eq!(m.plan(0, 8, &one).unwrap().length_mm, 2_000);
    }

    /// The start, the goal 3 m north, and a waypoint 1.5 m east of their
    /// middle: straight on is shorter but 20 mm from obstacles.
    fn detour() -> RouteMap<4, 4> {
        let mut m = RouteMap::new();
        let s = m.add_node(Point::new(0, 0)).unwrap();
        let w = m.add_node(Point::new(1_500, 1_500)).unwrap();
        let g = m.add_node(Point::new(0, 3_000)).unwrap();
        m.add_edge(s, w, 500).unwrap();
        m.add_edge(w, g, 500).unwrap();
        m.add_edge(s, g, 20).unwrap();
        m
    }

    use crate::eapf::config::test_config as config;

    /// Nodes at `points`, each joined to the next by an edge of the
    /// clearance given for it.
    fn chain<const N: usize, const E: usize>(
        points: &[(i16, i16)],
        clearances_mm: &[u16],
    ) -> RouteMap<N, E> {
        let mut m = RouteMap::new();
        for &(x, y) in points {
            m.add_node(Point::new(x, y)).unwrap();
        }
        for (i, &c) in (0..).zip(clearances_mm) {
            m.add_edge(i, i + 1, c).unwrap();
        }
        m
    }

    fn planner(cfg: RouteConfig) -> RoutePlanner<4, 4> {
        RoutePlanner::new(config(), detour(), cfg, Point::new(0, 3_000))
    }

    /// Nothing in sight: each sensor at its phantom level (0.28 V).
    const CLEAR: RawCounts = [57; 5];

    #[test]
    fn the_rover_follows_the_route_through_its_waypoint() {
        let mut p = planner(RouteConfig {
            slack_pct: 50,
            ..RouteConfig::default()
        });
        let mut pose = Pose::default();
        let mut nearest_waypoint = u16::MAX;
        for _ in 0..60 {
            let out = p.step_raw(pose, &CLEAR);
            if out.status == Status::Arrived {
                assert!(
                    nearest_waypoint <= 250,
                    "passed within {nearest_waypoint} mm"
                );
                assert_eq!(p.waypoints().count(), 1, "only the goal left");
                return;
            }
            assert_eq!(out.status, Status::Moving);
            // A perfect rover: turn, then the whole step.
            pose.heading = out.command.heading;
            let d = crate::fixed::Dir::of(pose.heading);
            pose.position = pose.position.offset_dir(d, out.command.step_mm);
            let (dx, dy) = pose.position.to(Point::new(1_500, 1_500));
            nearest_waypoint = nearest_waypoint.min(hypot(dx, dy));
        }
        panic!("not arrived: at {:?}", pose.position);
    }

    /// Waypoints in a row within `straighten_mm` of a straight line are one
    /// leg: the planner is sent to the last of them, not the next.
    #[test]
    fn waypoints_in_a_row_are_one_leg() {
        // Nodes every 200 mm east, 10 mm off the line from the second
        // on, then north to the goal's node.
        let m: RouteMap<8, 8> = chain(
            &[(0, 0), (200, 10), (400, 0), (600, 10), (800, 0), (800, 800)],
            &[500; 5],
        );
        let goal_for = |straighten_mm| {
            let cfg = RouteConfig {
                straighten_mm,
                ..RouteConfig::default()
            };
            let mut p = RoutePlanner::new(config(), m.clone(), cfg, Point::new(800, 800));
            p.step_raw(Pose::default(), &CLEAR);
            p.planner().goal()
        };
        // From the start node (passed, the rover stands on it): 200 mm
        // ahead is within `pass_mm`, so the leg starts at the second
        // node; the line to (800, 0) passes 10 mm from those between.
        assert_eq!(goal_for(40), Point::new(800, 0));
        assert_eq!(goal_for(9), Point::new(400, 0));
        assert_eq!(goal_for(0), Point::new(400, 0));
    }

    #[test]
    fn a_waypoint_before_a_tight_edge_is_not_passed_early() {
        // Start, a waypoint 600 mm east, the goal's node 600 mm north of
        // it. 200 mm short of the waypoint (within `pass_mm`) the rover
        // passes it when the edge on is roomy, and not when that edge has
        // 10 mm to spare beyond the disc and the clearance (a gap).
        let goal_after = |clearance_mm| {
            let m: RouteMap<4, 4> = chain(&[(0, 0), (600, 0), (600, 600)], &[500, clearance_mm]);
            let config = config();
            let need = config.robot_radius_mm + config.clearance_mm;
            assert_eq!(need, 140);
            let goal = Point::new(600, 600);
            let mut p = RoutePlanner::new(config, m, RouteConfig::default(), goal);
            p.step_raw(Pose::default(), &CLEAR);
            assert_eq!(p.planner().goal(), Point::new(600, 0));
            let near = Pose {
                position: Point::new(400, 0),
                heading: crate::Angle::ZERO,
            };
            p.step_raw(near, &CLEAR);
            p.planner().goal()
        };
        assert_eq!(goal_after(500), Point::new(600, 600));
        assert_eq!(goal_after(150), Point::new(600, 0));
        // 40 mm to spare (the planner's clearance) is roomy enough.
        assert_eq!(goal_after(180), Point::new(600, 600));
    }

    #[test]
    fn a_leg_the_planner_gives_up_on_is_blocked_and_another_route_taken() {
        let mut p = planner(RouteConfig {
            slack_pct: 50,
            ..RouteConfig::default()
        });
        // A wall right in front whatever the heading, and a rover that
        // never moves: the planner's escape gives up on each way in turn.
        let near = p.planner().config().calibration().full_scale() / 2 + 100;
        let wall = [near; 5];
        let pose = Pose::default();
        let first: heapless::Vec<Point, 4> = {
            let _ = p.step_raw(pose, &wall);
            p.waypoints().collect()
        };
        assert_eq!(first.len(), 3, "start, waypoint, goal: {first:?}");
        let mut switched = None;
        for cycle in 0..5_000 {
            let out = p.step_raw(pose, &wall);
            let now: heapless::Vec<Point, 4> = p.waypoints().collect();
            if now != first && switched.is_none() {
                // Within the leg's budget (100 cycles), not the planner's
                // give-up (400).
                assert!(cycle <= 101, "switched after {cycle} cycles");
                switched = Some(cycle);
            }
            if out.status == Status::Unreachable {
                assert!(switched.is_some(), "the route changed before giving up");
                assert!(p.map().edges().iter().any(|e| e.blocked));
                // And it stays given up.
                assert_eq!(p.step_raw(pose, &CLEAR).status, Status::Unreachable);
                return;
            }
            assert_eq!(out.command.step_mm, 0, "never into the wall");
        }
        panic!("never gave up");
    }

    #[test]
    fn blocks_that_leave_no_route_are_forgotten_once() {
        // Two ways to the goal 3 m north, by a waypoint 1.5 m east or
        // west. A wall in front while both are blocked in turn; then the
        // way is clear. With a round left the route is planned again over
        // the whole map, and followed to the goal; without, the rover
        // heads for the goal directly with the blocks kept.
        let mut m: RouteMap<4, 4> = chain(
            &[(1_500, 1_500), (0, 0), (-1_500, 1_500), (0, 3_000)],
            &[500, 500, 500],
        );
        m.add_edge(0, 3, 500).unwrap();
        let after_blocks = |unblock_rounds| {
            let cfg = RouteConfig {
                unblock_rounds,
                ..RouteConfig::default()
            };
            let mut p = RoutePlanner::new(config(), m.clone(), cfg, Point::new(0, 3_000));
            let near = p.planner().config().calibration().full_scale() / 2 + 100;
            let wall = [near; 5];
            let pose = Pose::default();
            let mut seen_blocked = false;
            for _ in 0..1_000 {
                let out = p.step_raw(pose, &wall);
                assert_eq!(out.command.step_mm, 0, "never into the wall");
                let blocked = p.map().edges().iter().filter(|e| e.blocked).count();
                seen_blocked |= blocked > 0;
                let waypoints = p.waypoints().count();
                if seen_blocked && (blocked == 0 || waypoints == 1) {
                    return (blocked, waypoints, p);
                }
            }
            panic!("no new round and no direct way");
        };
        // A route again, nothing blocked.
        let (blocked, waypoints, mut p) = after_blocks(1);
        assert_eq!(blocked, 0);
        assert!(waypoints > 1);
        let mut pose = Pose::default();
        let mut arrived = false;
        for _ in 0..80 {
            let out = p.step_raw(pose, &CLEAR);
            if out.status == Status::Arrived {
                arrived = true;
                break;
            }
            pose.heading = out.command.heading;
            let d = crate::fixed::Dir::of(pose.heading);
            pose.position = pose.position.offset_dir(d, out.command.step_mm);
        }
        assert!(arrived, "not arrived: at {:?}", pose.position);
        // No round left: the goal directly, the blocks kept.
        let (blocked, waypoints, _) = after_blocks(0);
        assert_eq!(waypoints, 1);
        assert!(blocked > 0);
    }

    #[test]
    fn the_preferred_clearance_is_kept_while_a_route_keeps_it_within_the_slack() {
        // The upper rail and the rungs are 200 mm clear or more, the
        // lower rail 50 mm: preferring 150 mm takes the upper way (3,000
        // mm) when the slack allows it beside the shortest (2,000 mm), even
        // if the risk alone would not (influence 40 mm: no edge has risk);
        // beyond the slack, or preferring more than any edge has, it falls
        // back to all edges.
        let m = ladder(5);
        let prefer = |mm, slack_pct| RouteConfig {
            preferred_clearance_mm: mm,
            slack_pct,
            influence_mm: 40,
            ..RouteConfig::default()
        };
        assert_eq!(m.plan(0, 8, &prefer(150, 50)).unwrap().length_mm, 3_000);
        assert_eq!(m.plan(0, 8, &prefer(150, 49)).unwrap().length_mm, 2_000);
        assert_eq!(m.plan(0, 8, &prefer(1_000, 50)).unwrap().length_mm, 2_000);
    }

    #[test]
    fn bad_maps_are_refused_and_unjoined_nodes_have_no_route() {
        let mut m: RouteMap<2, 1> = RouteMap::new();
        let a = m.add_node(Point::new(0, 0)).unwrap();
        let b = m.add_node(Point::new(100, 0)).unwrap();
        assert_eq!(m.add_node(Point::new(1, 1)), Err(MapError::Full));
        assert_eq!(m.add_edge(a, 7, 100), Err(MapError::BadEdge));
        assert_eq!(m.add_edge(a, a, 100), Err(MapError::BadEdge));
        assert_eq!(m.plan(a, b, &RouteConfig::default()), None);
        m.add_edge(a, b, 100).unwrap();
        assert_eq!(m.add_edge(b, a, 100), Err(MapError::Full));
        assert_eq!(
            m.plan(a, b, &RouteConfig::default()).unwrap().length_mm,
            100
        );
        assert_eq!(m.plan(a, 9, &RouteConfig::default()), None);
        assert_eq!(m.nearest_node(Point::new(90, 50)), Some(b));
    }
}
