//! Small exact 2-D geometry in f64: vectors, segment distances, ray hits.

use std::ops::{Add, Mul, Sub};

/// A 2-D vector or point, metres.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct V2 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
}

impl V2 {
    /// A vector.
    pub const fn new(x: f64, y: f64) -> V2 {
        V2 { x, y }
    }
    /// Unit vector at angle `a` (radians).
    pub fn from_angle(a: f64) -> V2 {
        V2::new(a.cos(), a.sin())
    }
    /// Dot product.
    pub fn dot(self, o: V2) -> f64 {
        self.x * o.x + self.y * o.y
    }
    /// z of the cross product.
    pub fn cross(self, o: V2) -> f64 {
        self.x * o.y - self.y * o.x
    }
    /// Length.
    pub fn len(self) -> f64 {
        self.x.hypot(self.y)
    }
    /// Distance to `o`.
    pub fn dist(self, o: V2) -> f64 {
        (self - o).len()
    }
}

impl Add for V2 {
    type Output = V2;
    fn add(self, o: V2) -> V2 {
        V2::new(self.x + o.x, self.y + o.y)
    }
}
impl Sub for V2 {
    type Output = V2;
    fn sub(self, o: V2) -> V2 {
        V2::new(self.x - o.x, self.y - o.y)
    }
}
impl Mul<f64> for V2 {
    type Output = V2;
    fn mul(self, k: f64) -> V2 {
        V2::new(self.x * k, self.y * k)
    }
}

/// Distance from point `p` to segment `a`–`b`.
pub fn point_segment_distance(p: V2, a: V2, b: V2) -> f64 {
    let ab = b - a;
    let l2 = ab.dot(ab);
    let t = if l2 == 0.0 {
        0.0
    } else {
        ((p - a).dot(ab) / l2).clamp(0.0, 1.0)
    };
    p.dist(a + ab * t)
}

/// Whether segments `a`–`b` and `c`–`d` intersect (touching counts).
pub fn segments_intersect(a: V2, b: V2, c: V2, d: V2) -> bool {
    let d1 = (b - a).cross(c - a);
    let d2 = (b - a).cross(d - a);
    let d3 = (d - c).cross(a - c);
    let d4 = (d - c).cross(b - c);
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    let on = |p: V2, q: V2, r: V2| {
        (q - p).cross(r - p).abs() < 1e-15
            && r.x >= p.x.min(q.x)
            && r.x <= p.x.max(q.x)
            && r.y >= p.y.min(q.y)
            && r.y <= p.y.max(q.y)
    };
    on(a, b, c) || on(a, b, d) || on(c, d, a) || on(c, d, b)
}

/// Distance between segments `a`–`b` and `c`–`d` (exact).
pub fn segment_segment_distance(a: V2, b: V2, c: V2, d: V2) -> f64 {
    if segments_intersect(a, b, c, d) {
        return 0.0;
    }
    point_segment_distance(a, c, d)
        .min(point_segment_distance(b, c, d))
        .min(point_segment_distance(c, a, b))
        .min(point_segment_distance(d, a, b))
}

/// Distance along the ray `o + t·dir` (|dir| = 1, t ≥ 0) to a circle, if hit.
pub fn ray_circle(o: V2, dir: V2, c: V2, r: f64) -> Option<f64> {
    let oc = o - c;
    let b = oc.dot(dir);
    let cc = oc.dot(oc) - r * r;
    if cc <= 0.0 {
        return Some(0.0); // starts inside
    }
    let disc = b * b - cc;
    if disc < 0.0 {
        return None;
    }
    let t = -b - disc.sqrt();
    (t >= 0.0).then_some(t)
}

/// Distance along the ray `o + t·dir` (|dir| = 1) to segment `a`–`b`, if hit.
pub fn ray_segment(o: V2, dir: V2, a: V2, b: V2) -> Option<f64> {
    let e = b - a;
    let den = dir.cross(e);
    if den.abs() < 1e-15 {
        return None; // parallel: a grazing ray meets the segment's ends via the neighbours
    }
    let ao = a - o;
    let t = ao.cross(e) / den;
    let u = ao.cross(dir) / den;
    (t >= 0.0 && (-1e-12..=1.0 + 1e-12).contains(&u)).then_some(t)
}

/// The edges of `poly`, each corner to the next and the last to the first.
pub fn polygon_edges(poly: &[V2]) -> impl Iterator<Item = (V2, V2)> + '_ {
    (0..poly.len()).map(move |i| (poly[i], poly[(i + 1) % poly.len()]))
}

/// Whether `p` lies inside the polygon (even-odd rule).
pub fn point_in_polygon(p: V2, poly: &[V2]) -> bool {
    let mut inside = false;
    let n = poly.len();
    let mut j = n - 1;
    for i in 0..n {
        let (a, b) = (poly[i], poly[j]);
        if (a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x {
            inside = !inside;
        }
        j = i;
    }
    inside
}

/// A two-wheel rover at `p`, heading `h` (rad), wheels `vl`, `vr` (m/s)
/// `base` apart (m), after `dt` seconds: the new position and heading,
/// exact for constant wheel speeds (an arc, or a line when they are equal).
pub fn differential_drive(p: V2, h: f64, vl: f64, vr: f64, base: f64, dt: f64) -> (V2, f64) {
    let (v, w) = ((vl + vr) / 2.0, (vr - vl) / base);
    if w.abs() < 1e-9 {
        return (p + V2::from_angle(h) * (v * dt), h);
    }
    let r = v / w;
    let q = V2::new(
        p.x + r * ((h + w * dt).sin() - h.sin()),
        p.y - r * ((h + w * dt).cos() - h.cos()),
    );
    (q, h + w * dt)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances() {
        let (a, b) = (V2::new(0.0, 0.0), V2::new(2.0, 0.0));
        assert_eq!(point_segment_distance(V2::new(1.0, 1.0), a, b), 1.0);
        assert_eq!(point_segment_distance(V2::new(3.0, 0.0), a, b), 1.0);
        let d = segment_segment_distance(a, b, V2::new(1.0, 0.5), V2::new(1.0, 3.0));
        assert!((d - 0.5).abs() < 1e-12);
        assert_eq!(
            segment_segment_distance(a, b, V2::new(1.0, -1.0), V2::new(1.0, 1.0)),
            0.0
        );
    }

    #[test]
    fn rays() {
        let o = V2::new(0.0, 0.0);
        let x = V2::new(1.0, 0.0);
        assert!((ray_circle(o, x, V2::new(3.0, 0.0), 1.0).unwrap() - 2.0).abs() < 1e-12);
        assert!(ray_circle(o, x, V2::new(3.0, 1.5), 1.0).is_none());
        assert!(ray_circle(o, x, V2::new(-3.0, 0.0), 1.0).is_none());
        let t = ray_segment(o, x, V2::new(2.0, -1.0), V2::new(2.0, 1.0)).unwrap();
        assert!((t - 2.0).abs() < 1e-12);
        assert!(ray_segment(o, x, V2::new(-2.0, -1.0), V2::new(-2.0, 1.0)).is_none());
    }

    #[test]
    fn polygon_inside() {
        let sq = [
            V2::new(0.0, 0.0),
            V2::new(1.0, 0.0),
            V2::new(1.0, 1.0),
            V2::new(0.0, 1.0),
        ];
        assert!(point_in_polygon(V2::new(0.5, 0.5), &sq));
        assert!(!point_in_polygon(V2::new(1.5, 0.5), &sq));
    }

    #[test]
    fn differential_drive_by_hand() {
        // Equal wheels: a straight line.
        let (q, h) = differential_drive(V2::new(0.0, 0.0), 0.0, 0.2, 0.2, 0.13, 1.0);
        assert!((q.x - 0.2).abs() < 1e-12 && q.y.abs() < 1e-12 && h == 0.0);
        // Opposite wheels: a turn in place by (vr − vl)/base · dt.
        let (q, h) = differential_drive(V2::new(1.0, 1.0), 0.0, -0.13, 0.13, 0.13, 0.5);
        assert!(q.dist(V2::new(1.0, 1.0)) < 1e-12 && (h - 1.0).abs() < 1e-12);
        // A quarter circle of radius 1 m: left wheel on the inside.
        let b = 0.2;
        let (vl, vr) = (1.0 - b / 2.0, 1.0 + b / 2.0); // ω = 1 rad/s, v = 1 m/s
        let (q, h) = differential_drive(
            V2::new(0.0, 0.0),
            0.0,
            vl,
            vr,
            b,
            std::f64::consts::FRAC_PI_2,
        );
        assert!(q.dist(V2::new(1.0, 1.0)) < 1e-9, "{q:?}");
        assert!((h - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    }
}
