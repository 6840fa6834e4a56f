//! The world: circles, polygons, the boundary walls and moving circles, with
//! exact ray casting and exact swept-disc collision checking.

use crate::geom::{self, polygon_edges, V2};

/// A circle moving back and forth along its waypoints at constant speed.
#[derive(Clone, Debug)]
pub struct Moving {
    /// Radius, m.
    pub radius: f64,
    /// The closed back-and-forth path: centre, then waypoints, then back.
    path: Vec<V2>,
    /// Cumulative length at each path vertex.
    cum: Vec<f64>,
    speed: f64,
}

impl Moving {
    pub(crate) fn new(center: V2, radius: f64, waypoints: &[V2], speed: f64) -> Moving {
        let mut fwd = vec![center];
        fwd.extend(waypoints.iter().copied());
        // Back and forth: out along the waypoints, then back to the start.
        let mut path = fwd.clone();
        path.extend(fwd.iter().rev().skip(1).copied());
        let mut cum = vec![0.0];
        for w in path.windows(2) {
            cum.push(cum.last().unwrap() + w[0].dist(w[1]));
        }
        Moving {
            radius,
            path,
            cum,
            speed,
        }
    }

    /// Centre at time `t` seconds.
    pub fn center_at(&self, t: f64) -> V2 {
        let total = *self.cum.last().unwrap();
        if total <= 0.0 || self.speed <= 0.0 {
            return self.path[0];
        }
        let s = (t * self.speed).rem_euclid(total);
        let k = self
            .cum
            .partition_point(|&c| c <= s)
            .clamp(1, self.path.len() - 1);
        let (a, b) = (self.path[k - 1], self.path[k]);
        let seg = self.cum[k] - self.cum[k - 1];
        if seg <= 0.0 {
            return b;
        }
        a + (b - a) * ((s - self.cum[k - 1]) / seg)
    }
}

/// How far apart the boxes `lo`–`hi` and `a`–`b` (lowest, highest corners)
/// lie along x and along y (0 where they overlap): their distance is at
/// least the hypotenuse of the two.
fn box_gap((lo, hi): (V2, V2), (a, b): (V2, V2)) -> (f64, f64) {
    (
        (lo.x - b.x).max(a.x - hi.x).max(0.0),
        (lo.y - b.y).max(a.y - hi.y).max(0.0),
    )
}

/// The corners of the axis-aligned box round `poly`: lowest, highest.
fn bounding_box(poly: &[V2]) -> (V2, V2) {
    poly.iter().fold(
        (V2::new(f64::MAX, f64::MAX), V2::new(f64::MIN, f64::MIN)),
        |(lo, hi), q| {
            (
                V2::new(lo.x.min(q.x), lo.y.min(q.y)),
                V2::new(hi.x.max(q.x), hi.y.max(q.y)),
            )
        },
    )
}

/// The static and moving geometry of a scenario.
#[derive(Clone, Debug)]
pub struct World {
    /// xmin, ymin, xmax, ymax.
    pub bounds: [f64; 4],
    /// Static circles (centre, radius).
    pub circles: Vec<(V2, f64)>,
    /// Static polygons.
    pub polygons: Vec<Vec<V2>>,
    /// Moving circles.
    pub moving: Vec<Moving>,
}

impl World {
    fn boundary_segments(&self) -> [(V2, V2); 4] {
        let [x0, y0, x1, y1] = self.bounds;
        let (a, b, c, d) = (
            V2::new(x0, y0),
            V2::new(x1, y0),
            V2::new(x1, y1),
            V2::new(x0, y1),
        );
        [(a, b), (b, c), (c, d), (d, a)]
    }

    fn edges(&self) -> impl Iterator<Item = (V2, V2)> + '_ {
        self.polygons.iter().flat_map(|p| polygon_edges(p))
    }

    /// Distance from `p` to the nearest obstacle or wall at time `t`
    /// (0 when inside an obstacle or outside the bounds).
    ///
    /// A polygon whose bounding box is farther than the nearest distance
    /// so far cannot be nearer: its edges are skipped (the same answer;
    /// the route layer's map asks this for every point of its scans).
    pub fn clearance(&self, p: V2, t: f64) -> f64 {
        let [x0, y0, x1, y1] = self.bounds;
        let mut d = (p.x - x0).min(x1 - p.x).min(p.y - y0).min(y1 - p.y);
        for &(c, r) in &self.circles {
            d = d.min(p.dist(c) - r);
        }
        for m in &self.moving {
            d = d.min(p.dist(m.center_at(t)) - m.radius);
        }
        if d <= 0.0 {
            return 0.0;
        }
        for poly in &self.polygons {
            let (gx, gy) = box_gap(bounding_box(poly), (p, p));
            if gx == 0.0 && gy == 0.0 {
                if geom::point_in_polygon(p, poly) {
                    return 0.0;
                }
            } else if gx * gx + gy * gy > d * d * (1.0 + 1e-9) {
                // Farther than a distance already found, by far more than
                // rounding: so is every edge.
                continue;
            }
            for (a, b) in polygon_edges(poly) {
                d = d.min(geom::point_segment_distance(p, a, b));
            }
        }
        d.max(0.0)
    }

    /// Of the grid nodes `(x0 + i·h, y0 + j·h)`, `i < nx`, `j < ny` (row
    /// by row), which have a static [`World::clearance`] above `r`: the same
    /// answers, but each obstacle looks only at the nodes within `r` of its
    /// bounding box (plus a node each side), not every node at every
    /// obstacle (a world of 120 boxes took seconds).
    pub fn free_grid(&self, [x0, y0]: [f64; 2], h: f64, [nx, ny]: [usize; 2], r: f64) -> Vec<bool> {
        let [bx0, by0, bx1, by1] = self.bounds;
        let pos = |i: usize, j: usize| V2::new(x0 + i as f64 * h, y0 + j as f64 * h);
        let mut free: Vec<bool> = (0..nx * ny)
            .map(|k| {
                let p = pos(k % nx, k / nx);
                (p.x - bx0).min(bx1 - p.x).min(p.y - by0).min(by1 - p.y) > r
            })
            .collect();
        // The node ranges a box [lo, hi] widened by r and a node covers.
        let span = |lo: f64, hi: f64, o: f64, n: usize| {
            let a = ((lo - r - o) / h).floor() - 1.0;
            let b = ((hi + r - o) / h).ceil() + 1.0;
            let a = a.clamp(0.0, n as f64) as usize;
            let b = (b + 1.0).clamp(0.0, n as f64) as usize;
            a..b
        };
        let mut block = |lo: V2, hi: V2, hit: &dyn Fn(V2) -> bool| {
            for j in span(lo.y, hi.y, y0, ny) {
                for i in span(lo.x, hi.x, x0, nx) {
                    if free[j * nx + i] && hit(pos(i, j)) {
                        free[j * nx + i] = false;
                    }
                }
            }
        };
        for &(c, rc) in &self.circles {
            let e = V2::new(rc, rc);
            block(c - e, c + e, &|p| p.dist(c) - rc <= r);
        }
        for poly in &self.polygons {
            let (lo, hi) = bounding_box(poly);
            block(lo, hi, &|p| {
                geom::point_in_polygon(p, poly)
                    || polygon_edges(poly).any(|(a, b)| geom::point_segment_distance(p, a, b) <= r)
            });
        }
        free
    }

    /// Smallest distance from the segment `a`–`b` (the path of a disc
    /// centre) to the static geometry: the swept disc of radius r is free
    /// exactly when this exceeds r.
    pub fn static_sweep_clearance(&self, a: V2, b: V2) -> f64 {
        let mut d = f64::INFINITY;
        let [x0, y0, x1, y1] = self.bounds;
        for p in [a, b] {
            if p.x <= x0 || p.x >= x1 || p.y <= y0 || p.y >= y1 {
                return 0.0;
            }
            d = d.min(p.x - x0).min(x1 - p.x).min(p.y - y0).min(y1 - p.y);
        }
        for &(c, r) in &self.circles {
            d = d.min(geom::point_segment_distance(c, a, b) - r);
        }
        if d <= 0.0 {
            return 0.0;
        }
        // As in `clearance`: a polygon whose bounding box is farther from
        // the segment's than the nearest distance so far is skipped.
        let swept = bounding_box(&[a, b]);
        for poly in &self.polygons {
            let (gx, gy) = box_gap(bounding_box(poly), swept);
            if gx == 0.0 && gy == 0.0 {
                if geom::point_in_polygon(a, poly) || geom::point_in_polygon(b, poly) {
                    return 0.0;
                }
            } else if gx * gx + gy * gy > d * d * (1.0 + 1e-9) {
                continue;
            }
            for (p, q) in polygon_edges(poly) {
                d = d.min(geom::segment_segment_distance(a, b, p, q));
            }
        }
        d.max(0.0)
    }

    /// Smallest distance between the disc centre moving linearly from `a`
    /// (time `t0`) to `b` (time `t1`) and the moving circles' rims, with
    /// each moving circle linear over the interval (exact between its
    /// waypoint turns; callers keep intervals short).
    pub fn moving_sweep_clearance(&self, a: V2, b: V2, t0: f64, t1: f64) -> f64 {
        let mut d = f64::INFINITY;
        for m in &self.moving {
            let (c0, c1) = (m.center_at(t0), m.center_at(t1));
            // Relative motion r(s) = (a − c0) + s·((b − a) − (c1 − c0)), s ∈ [0, 1].
            let r0 = a - c0;
            let dv = (b - a) - (c1 - c0);
            let l2 = dv.dot(dv);
            let s = if l2 == 0.0 {
                0.0
            } else {
                (-r0.dot(dv) / l2).clamp(0.0, 1.0)
            };
            d = d.min((r0 + dv * s).len() - m.radius);
        }
        d.max(0.0)
    }

    /// Distance along a ray from `o` in direction `angle` to the first
    /// surface at time `t`, up to `max` (None: nothing within `max`).
    pub fn ray(&self, o: V2, angle: f64, max: f64, t: f64) -> Option<f64> {
        let dir = V2::from_angle(angle);
        let mut best = f64::INFINITY;
        for (a, b) in self.boundary_segments() {
            if let Some(h) = geom::ray_segment(o, dir, a, b) {
                best = best.min(h);
            }
        }
        for &(c, r) in &self.circles {
            if let Some(h) = geom::ray_circle(o, dir, c, r) {
                best = best.min(h);
            }
        }
        for m in &self.moving {
            if let Some(h) = geom::ray_circle(o, dir, m.center_at(t), m.radius) {
                best = best.min(h);
            }
        }
        for (a, b) in self.edges() {
            if let Some(h) = geom::ray_segment(o, dir, a, b) {
                best = best.min(h);
            }
        }
        for poly in &self.polygons {
            if geom::point_in_polygon(o, poly) {
                best = 0.0;
            }
        }
        (best <= max).then_some(best)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::Scenario;
    use std::path::Path;

    fn world(extra: &str) -> World {
        let text = format!(
            "format = 1\nname = \"w\"\nbounds = [0.0, 0.0, 10.0, 10.0]\nstart = [1.0, 1.0]\ngoal = [9.0, 9.0]\n{extra}"
        );
        Scenario::parse(&text, Path::new("w.toml")).unwrap().world()
    }

    #[test]
    fn ray_casting_is_exact() {
        let w = world("[[circle]]\ncenter = [5.0, 5.0]\nradius = 1.0\n[[polygon]]\npoints = [[7.0, 0.0], [8.0, 0.0], [8.0, 3.0], [7.0, 3.0]]\n");
        // Along +x from (1, 5): the circle's rim at x = 4.
        assert!((w.ray(V2::new(1.0, 5.0), 0.0, 20.0, 0.0).unwrap() - 3.0).abs() < 1e-12);
        // Along +x from (1, 1): the polygon's face at x = 7.
        assert!((w.ray(V2::new(1.0, 1.0), 0.0, 20.0, 0.0).unwrap() - 6.0).abs() < 1e-12);
        // Along +y from (1, 1): the boundary at y = 10.
        let up = std::f64::consts::FRAC_PI_2;
        assert!((w.ray(V2::new(1.0, 1.0), up, 20.0, 0.0).unwrap() - 9.0).abs() < 1e-12);
        assert!(w.ray(V2::new(1.0, 1.0), up, 5.0, 0.0).is_none());
        // 45° towards the circle: it hits at |(5,5)−(1,1)| − 1.
        let d = w.ray(V2::new(1.0, 1.0), up / 2.0, 20.0, 0.0).unwrap();
        assert!((d - (32f64.sqrt() - 1.0)).abs() < 1e-12);
    }

    #[test]
    fn swept_collision_is_exact() {
        let w = world("[[circle]]\ncenter = [5.0, 5.0]\nradius = 1.0\n[[polygon]]\npoints = [[7.0, 0.0], [8.0, 0.0], [8.0, 3.0], [7.0, 3.0]]\n");
        // A motion passing 1.1 m below the circle's centre: 0.1 m from its rim.
        let c = w.static_sweep_clearance(V2::new(3.0, 3.9), V2::new(6.0, 3.9));
        assert!((c - 0.1).abs() < 1e-12);
        // The endpoints are far from the circle, but the middle is not:
        // a sampled check at the ends would miss this.
        let c = w.static_sweep_clearance(V2::new(3.0, 4.0), V2::new(7.0, 4.0));
        assert!(c < 1e-12);
        // Starting diagonally off the polygon's corner (7, 3): 0.05·√2.
        let c = w.static_sweep_clearance(V2::new(6.95, 3.05), V2::new(6.95, 5.0));
        assert!((c - 0.05 * 2f64.sqrt()).abs() < 1e-12, "{c}");
        // Outside the bounds is a collision.
        assert_eq!(
            w.static_sweep_clearance(V2::new(1.0, 1.0), V2::new(-1.0, 1.0)),
            0.0
        );
    }

    #[test]
    fn moving_circles_move_and_are_swept() {
        let w = world("[[moving]]\ncenter = [5.0, 1.0]\nradius = 0.2\nwaypoints = [[5.0, 9.0]]\nspeed = 1.0\n");
        let m = &w.moving[0];
        assert_eq!(m.center_at(0.0), V2::new(5.0, 1.0));
        assert_eq!(m.center_at(4.0), V2::new(5.0, 5.0));
        assert_eq!(m.center_at(12.0), V2::new(5.0, 5.0)); // on its way back
        assert_eq!(m.center_at(16.0), V2::new(5.0, 1.0));
        // The robot crosses x = 5 at y = 5 exactly when the circle is there.
        let c = w.moving_sweep_clearance(V2::new(4.0, 5.0), V2::new(6.0, 5.0), 3.0, 5.0);
        assert!(c < 1e-12);
        // Same path, but a second later the circle has gone on.
        let c = w.moving_sweep_clearance(V2::new(4.0, 5.0), V2::new(6.0, 5.0), 6.0, 6.1);
        assert!(c > 0.5);
    }

    /// Every world of the library, and a box world and a circle world of
    /// `gen`.
    fn library_and_generated() -> Vec<Scenario> {
        use crate::generate::{world as generated, Kind};
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
        let mut scenarios: Vec<Scenario> = crate::scenario::collect(&[dir])
            .unwrap()
            .iter()
            .map(|f| Scenario::load(f).unwrap())
            .collect();
        for kind in [Kind::Boxes, Kind::Circles] {
            let text = generated(kind, "g", [6.0, 7.3], [12.7, 9.75], 5).unwrap();
            scenarios.push(Scenario::parse(&text, Path::new("g")).unwrap());
        }
        scenarios
    }

    /// `free_grid` answers as the clearance of each node does, on every
    /// world of the library, a box world and a circle world of `gen`, for
    /// the robot's radius and for radii with nodes on the threshold.
    #[test]
    fn the_free_grid_is_the_clearance_at_every_node() {
        let scenarios = library_and_generated();
        for sc in &scenarios {
            let w = World {
                moving: Vec::new(),
                ..sc.world()
            };
            let h = 0.05;
            let [x0, y0, x1, y1] = sc.bounds;
            let n = [((x1 - x0) / h) as usize + 1, ((y1 - y0) / h) as usize + 1];
            for r in [sc.robot_radius, 0.05, 0.25] {
                let free = w.free_grid([x0, y0], h, n, r);
                for (k, &f) in free.iter().enumerate() {
                    let p = V2::new(x0 + (k % n[0]) as f64 * h, y0 + (k / n[0]) as f64 * h);
                    assert_eq!(f, w.clearance(p, 0.0) > r, "{} at {p:?}, r {r}", sc.name);
                }
            }
        }
    }

    /// `clearance` and `static_sweep_clearance` skip the polygons whose
    /// bounding box is farther than the nearest distance so far: the same
    /// answers as every edge of every polygon, on the library, a box world
    /// and a circle world, on a grid that meets no obstacle's coordinates
    /// on purpose (and sweeps 0.3 m long from each of its points).
    #[test]
    fn clearance_skips_no_nearer_polygon() {
        let plain = |w: &World, p: V2| {
            let [x0, y0, x1, y1] = w.bounds;
            let mut d = (p.x - x0).min(x1 - p.x).min(p.y - y0).min(y1 - p.y);
            for &(c, r) in &w.circles {
                d = d.min(p.dist(c) - r);
            }
            if w.polygons
                .iter()
                .any(|poly| geom::point_in_polygon(p, poly))
            {
                return 0.0;
            }
            for (a, b) in w.edges() {
                d = d.min(geom::point_segment_distance(p, a, b));
            }
            d.max(0.0)
        };
        let plain_sweep = |w: &World, a: V2, b: V2| {
            let [x0, y0, x1, y1] = w.bounds;
            let mut d = f64::INFINITY;
            for p in [a, b] {
                if p.x <= x0 || p.x >= x1 || p.y <= y0 || p.y >= y1 {
                    return 0.0;
                }
                d = d.min(p.x - x0).min(x1 - p.x).min(p.y - y0).min(y1 - p.y);
            }
            for &(c, r) in &w.circles {
                d = d.min(geom::point_segment_distance(c, a, b) - r);
            }
            let inside = |p| {
                w.polygons
                    .iter()
                    .any(|poly| geom::point_in_polygon(p, poly))
            };
            if inside(a) || inside(b) {
                return 0.0;
            }
            for (p, q) in w.edges() {
                d = d.min(geom::segment_segment_distance(a, b, p, q));
            }
            d.max(0.0)
        };
        let scenarios = library_and_generated();
        let mut compared = 0;
        for sc in &scenarios {
            let w = World {
                moving: Vec::new(),
                ..sc.world()
            };
            let [x0, y0, x1, y1] = sc.bounds;
            let h = 0.073;
            let (nx, ny) = (((x1 - x0) / h) as usize + 2, ((y1 - y0) / h) as usize + 2);
            for k in 0..nx * ny {
                let p = V2::new(x0 - h + (k % nx) as f64 * h, y0 - h + (k / nx) as f64 * h);
                assert_eq!(w.clearance(p, 0.0), plain(&w, p), "{} at {p:?}", sc.name);
                // And a sweep from there, 0.3 m on a turning heading.
                let q = p + V2::new((k as f64).cos(), (k as f64).sin()) * 0.3;
                assert_eq!(
                    w.static_sweep_clearance(p, q),
                    plain_sweep(&w, p, q),
                    "{} from {p:?} to {q:?}",
                    sc.name
                );
                compared += 1;
            }
        }
        assert!(compared > 80_000, "{compared}");
    }
}
