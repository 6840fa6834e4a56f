//! Scenario files, format 1 (`../shared/scenarios/FORMAT.md`): one world, one
//! start, one goal, in TOML. Unknown keys are errors, and every rule broken
//! is reported with the file, the key and the rule.

use crate::geom::V2;
use crate::world::{Moving, World};
use serde::Deserialize;
use std::fmt;
use std::path::{Path, PathBuf};

/// A circle obstacle.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CircleSpec {
    /// Centre, m.
    #[serde(deserialize_with = "exact")]
    pub center: [f64; 2],
    /// Radius, m.
    pub radius: f64,
}

/// A simple polygon obstacle, either winding.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PolygonSpec {
    /// Vertices, m.
    #[serde(deserialize_with = "exact_points")]
    pub points: Vec<[f64; 2]>,
}

/// A circle moving back and forth between waypoints at constant speed.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MovingSpec {
    /// Centre at time zero, m.
    #[serde(deserialize_with = "exact")]
    pub center: [f64; 2],
    /// Radius, m.
    pub radius: f64,
    /// Waypoints, m.
    #[serde(deserialize_with = "exact_points")]
    pub waypoints: Vec<[f64; 2]>,
    /// Speed, m/s.
    pub speed: f64,
}

/// A scenario as written in the file.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Always 1.
    pub format: i64,
    /// Unique short name.
    pub name: String,
    /// Free text.
    #[serde(default)]
    pub description: Option<String>,
    /// xmin, ymin, xmax, ymax, m; the boundary is a wall.
    #[serde(deserialize_with = "exact")]
    pub bounds: [f64; 4],
    /// Start, m.
    #[serde(deserialize_with = "exact")]
    pub start: [f64; 2],
    /// Start heading, degrees; default: facing the goal.
    #[serde(default)]
    pub start_heading: Option<f64>,
    /// Goal, m.
    #[serde(deserialize_with = "exact")]
    pub goal: [f64; 2],
    /// Robot radius, m (default 0.10).
    #[serde(default = "default_radius")]
    pub robot_radius: f64,
    /// Whether a collision-free path exists (default true).
    #[serde(default = "default_true")]
    pub solvable: bool,
    /// Circles.
    #[serde(default)]
    pub circle: Vec<CircleSpec>,
    /// Polygons.
    #[serde(default)]
    pub polygon: Vec<PolygonSpec>,
    /// Moving circles.
    #[serde(default)]
    pub moving: Vec<MovingSpec>,
}

/// Exactly `N` numbers: a longer or shorter array is an error, not cut to
/// size ("a typo must not silently change a world").
fn exact<'de, D: serde::Deserializer<'de>, const N: usize>(d: D) -> Result<[f64; N], D::Error> {
    let v = Vec::<f64>::deserialize(d)?;
    <[f64; N]>::try_from(v.as_slice())
        .map_err(|_| serde::de::Error::custom(format!("expected {N} numbers, found {}", v.len())))
}

/// A list of points of exactly two numbers each.
fn exact_points<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Vec<[f64; 2]>, D::Error> {
    Vec::<Vec<f64>>::deserialize(d)?
        .into_iter()
        .map(|p| {
            <[f64; 2]>::try_from(p.as_slice()).map_err(|_| {
                serde::de::Error::custom(format!(
                    "expected points of 2 numbers, found one of {}",
                    p.len()
                ))
            })
        })
        .collect()
}

fn default_radius() -> f64 {
    0.10
}
fn default_true() -> bool {
    true
}

/// A rejected scenario file: which file, which key, which rule.
#[derive(Debug, Clone, PartialEq)]
pub struct ScenarioError {
    /// The file.
    pub file: PathBuf,
    /// The key (dotted path, e.g. `circle[2].radius`), or `-` for the file.
    pub key: String,
    /// The rule broken.
    pub rule: String,
}

impl fmt::Display for ScenarioError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: key `{}`: {}",
            self.file.display(),
            self.key,
            self.rule
        )
    }
}

impl std::error::Error for ScenarioError {}

impl Scenario {
    /// The world this scenario describes.
    pub fn world(&self) -> World {
        let s = self;
        let v = |p: [f64; 2]| V2::new(p[0], p[1]);
        World {
            bounds: s.bounds,
            circles: s.circle.iter().map(|c| (v(c.center), c.radius)).collect(),
            polygons: s
                .polygon
                .iter()
                .map(|p| p.points.iter().map(|&q| v(q)).collect())
                .collect(),
            moving: s
                .moving
                .iter()
                .map(|m| {
                    let wps: Vec<V2> = m.waypoints.iter().map(|&q| v(q)).collect();
                    Moving::new(v(m.center), m.radius, &wps, m.speed)
                })
                .collect(),
        }
    }

    /// Read and validate a file.
    pub fn load(path: &Path) -> Result<Scenario, ScenarioError> {
        let text = std::fs::read_to_string(path).map_err(|e| ScenarioError {
            file: path.to_path_buf(),
            key: "-".into(),
            rule: format!("cannot read the file: {e}"),
        })?;
        Scenario::parse(&text, path)
    }

    /// Parse and validate text; `path` names it in errors.
    pub fn parse(text: &str, path: &Path) -> Result<Scenario, ScenarioError> {
        let err = |key: &str, rule: String| ScenarioError {
            file: path.to_path_buf(),
            key: key.to_string(),
            rule,
        };
        let sc: Scenario = toml::from_str(text).map_err(|e| {
            let msg = e.message().trim().to_string();
            // The line the error is on, and the key written there; an
            // unknown or missing field is named in the message.
            let at = e.span().map(|s| s.start.min(text.len()));
            let line_no = at.map(|a| text[..a].matches('\n').count() + 1);
            let line_key = at.and_then(|a| {
                let line = text[..a].rsplit('\n').next().unwrap_or("").to_string()
                    + text[a..].split('\n').next().unwrap_or("");
                line.split_once('=')
                    .map(|(k, _)| k.trim().to_string())
                    .filter(|k| !k.is_empty() && !k.starts_with('['))
            });
            let named = (msg.starts_with("unknown field") || msg.starts_with("missing field"))
                .then(|| msg.split('`').nth(1).map(str::to_string))
                .flatten();
            let key = named.or(line_key).unwrap_or_else(|| "-".to_string());
            let line = line_no.map_or_else(String::new, |n| format!("line {n}: "));
            err(&key, format!("{line}not valid format 1 TOML: {msg}"))
        })?;
        sc.validate().map_err(|(k, r)| err(&k, r))?;
        Ok(sc)
    }

    /// The rules of FORMAT.md, as (key, rule) on failure.
    fn validate(&self) -> Result<(), (String, String)> {
        let fail = |k: &str, r: &str| Err((k.to_string(), r.to_string()));
        if self.format != 1 {
            return fail("format", "must be 1");
        }
        if self.name.trim().is_empty() {
            return fail("name", "must not be empty");
        }
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        let [x0, y0, x1, y1] = self.bounds;
        if !finite(&self.bounds) || x1 <= x0 || y1 <= y0 {
            return fail("bounds", "must be finite with xmin < xmax and ymin < ymax");
        }
        // Ours, not FORMAT.md's: the core's positions are signed 16-bit
        // millimetres, so a world beyond ±32.767 m cannot be driven (and
        // its reference grid would not fit in memory).
        if self.bounds.iter().any(|b| b.abs() > MAX_COORD_M) {
            return fail(
                "bounds",
                "must lie within ±32.767 m (the planner's positions are 16-bit millimetres)",
            );
        }
        // Ours: the planner's disc is at least 20 mm (its configuration's
        // least radius), so a smaller one would be driven as another robot
        // than the one the simulator checks.
        if !(self.robot_radius.is_finite()
            && self.robot_radius >= MIN_RADIUS_M
            && self.robot_radius < 1.0)
        {
            return fail("robot_radius", "must be in [0.02, 1) m");
        }
        if let Some(h) = self.start_heading {
            if !h.is_finite() {
                return fail("start_heading", "must be a finite number of degrees");
            }
        }
        for (k, c) in self.circle.iter().enumerate() {
            if !finite(&c.center) {
                return fail(&format!("circle[{k}].center"), "must be finite");
            }
            if !(c.radius.is_finite() && c.radius > 0.0) {
                return fail(&format!("circle[{k}].radius"), "must be positive");
            }
        }
        for (k, p) in self.polygon.iter().enumerate() {
            if p.points.len() < 3 {
                return fail(&format!("polygon[{k}].points"), "needs at least 3 points");
            }
            if !p.points.iter().all(|q| finite(q)) {
                return fail(&format!("polygon[{k}].points"), "must be finite");
            }
            if polygon_area(&p.points).abs() < 1e-12 {
                return fail(&format!("polygon[{k}].points"), "has no area");
            }
            if self_intersects(&p.points) {
                return fail(
                    &format!("polygon[{k}].points"),
                    "must be a simple polygon: two of its edges cross",
                );
            }
        }
        for (k, m) in self.moving.iter().enumerate() {
            if !(m.radius.is_finite() && m.radius > 0.0) {
                return fail(&format!("moving[{k}].radius"), "must be positive");
            }
            if !(m.speed.is_finite() && m.speed >= 0.0) {
                return fail(&format!("moving[{k}].speed"), "must be zero or positive");
            }
            if m.waypoints.is_empty() || !m.waypoints.iter().all(|q| finite(q)) {
                return fail(
                    &format!("moving[{k}].waypoints"),
                    "needs at least one finite point",
                );
            }
            if !finite(&m.center) {
                return fail(&format!("moving[{k}].center"), "must be finite");
            }
        }
        let inside = |p: [f64; 2]| p[0] > x0 && p[0] < x1 && p[1] > y0 && p[1] < y1;
        for (key, p) in [("start", self.start), ("goal", self.goal)] {
            if !finite(&p) || !inside(p) {
                return fail(key, "must lie inside bounds");
            }
            let world = self.world();
            let clear = world.clearance(glam(p), 0.0);
            if clear < self.robot_radius - 1e-9 {
                return fail(
                    key,
                    &format!(
                        "must be at least robot_radius ({}) from every obstacle at time zero (it is {:.4} m)",
                        self.robot_radius,
                        clear.max(0.0)
                    ),
                );
            }
        }
        Ok(())
    }

    /// Start heading in radians, within [0, 2π) (default: facing the
    /// goal). Reduced in degrees first: a heading of 1e300° is a finite
    /// number of degrees, but in radians the simulator's turns would be
    /// lost in its rounding, and the rover's true heading would part from
    /// the one its odometry reports.
    pub fn start_heading_rad(&self) -> f64 {
        match self.start_heading {
            Some(d) => d.rem_euclid(360.0).to_radians(),
            None => (self.goal[1] - self.start[1]).atan2(self.goal[0] - self.start[0]),
        }
    }
}

fn glam(p: [f64; 2]) -> crate::geom::V2 {
    crate::geom::V2::new(p[0], p[1])
}

/// The least robot radius, m: the planner's (20 mm).
pub const MIN_RADIUS_M: f64 = 0.02;

/// Whether two edges of the closed polygon `pts` that are not neighbours
/// cross or touch (a simple polygon's edges meet only at their shared
/// corners).
pub fn self_intersects(pts: &[[f64; 2]]) -> bool {
    let n = pts.len();
    let edge = |i: usize| (pts[i], pts[(i + 1) % n]);
    let orient = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).signum()
    };
    let on = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        c[0] >= a[0].min(b[0])
            && c[0] <= a[0].max(b[0])
            && c[1] >= a[1].min(b[1])
            && c[1] <= a[1].max(b[1])
    };
    let meet = |(a, b): ([f64; 2], [f64; 2]), (c, d): ([f64; 2], [f64; 2])| {
        let (o1, o2, o3, o4) = (
            orient(a, b, c),
            orient(a, b, d),
            orient(c, d, a),
            orient(c, d, b),
        );
        (o1 * o2 < 0.0 && o3 * o4 < 0.0)
            || (o1 == 0.0 && on(a, b, c))
            || (o2 == 0.0 && on(a, b, d))
            || (o3 == 0.0 && on(c, d, a))
            || (o4 == 0.0 && on(c, d, b))
    };
    (0..n).any(|i| {
        (i + 2..n)
            .filter(|&j| !(i == 0 && j == n - 1))
            .any(|j| meet(edge(i), edge(j)))
    })
}

/// Signed area (shoelace).
pub fn polygon_area(pts: &[[f64; 2]]) -> f64 {
    let n = pts.len();
    (0..n)
        .map(|i| {
            let (a, b) = (pts[i], pts[(i + 1) % n]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum::<f64>()
        / 2.0
}

/// Every `.toml` scenario under the given files or folders, sorted by path.
pub fn collect(paths: &[PathBuf]) -> Result<Vec<PathBuf>, String> {
    let mut out = Vec::new();
    for p in paths {
        if p.is_dir() {
            walk(p, &mut out).map_err(|e| format!("{}: {e}", p.display()))?;
        } else if p.is_file() {
            out.push(p.clone());
        } else {
            return Err(format!("{}: no such file or folder", p.display()));
        }
    }
    out.sort();
    out.dedup();
    Ok(out)
}

fn walk(dir: &Path, out: &mut Vec<PathBuf>) -> std::io::Result<()> {
    for e in std::fs::read_dir(dir)? {
        let p = e?.path();
        if p.is_dir() {
            walk(&p, out)?;
        } else if p.extension().is_some_and(|x| x == "toml") {
            out.push(p);
        }
    }
    Ok(())
}

/// The largest coordinate a world may have, m: `i16::MAX` millimetres,
/// the planner core's range.
pub const MAX_COORD_M: f64 = i16::MAX as f64 / 1000.0;

#[cfg(test)]
mod tests {
    use super::*;

    const OK: &str = r#"
format = 1
name = "t"
bounds = [0.0, 0.0, 6.0, 5.0]
start = [0.5, 2.5]
goal = [5.5, 2.5]
[[circle]]
center = [3.0, 2.5]
radius = 0.5
"#;

    fn parse(s: &str) -> Result<Scenario, ScenarioError> {
        Scenario::parse(s, Path::new("t.toml"))
    }

    #[test]
    fn defaults() {
        let s = parse(OK).unwrap();
        assert_eq!(s.robot_radius, 0.10);
        assert!(s.solvable);
        assert!((s.start_heading_rad() - 0.0).abs() < 1e-12);
    }

    #[test]
    fn unknown_key_names_the_key() {
        let e = parse(&OK.replace("radius = 0.5", "radius = 0.5\nradios = 1")).unwrap_err();
        assert_eq!(e.key, "radios");
        assert!(e.to_string().contains("t.toml"), "{e}");
    }

    #[test]
    fn rules_name_key_and_rule() {
        let cases = [
            (OK.replace("format = 1", "format = 2"), "format"),
            (
                OK.replace("[0.0, 0.0, 6.0, 5.0]", "[6.0, 0.0, 0.0, 5.0]"),
                "bounds",
            ),
            (
                OK.replace("start = [0.5, 2.5]", "start = [9.5, 2.5]"),
                "start",
            ),
            (OK.replace("goal = [5.5, 2.5]", "goal = [3.3, 2.5]"), "goal"),
            (
                OK.replace("radius = 0.5", "radius = -1.0"),
                "circle[0].radius",
            ),
            (OK.replace("name = \"t\"", "name = \"\""), "name"),
            (
                format!("{OK}\n[[polygon]]\npoints = [[1.0, 1.0], [2.0, 2.0]]\n"),
                "polygon[0].points",
            ),
            (OK.replace("goal = [5.5, 2.5]", ""), "goal"),
            // Beyond the core's 16-bit millimetres (it was an out-of-memory
            // abort in the reference grid).
            (
                OK.replace("[0.0, 0.0, 6.0, 5.0]", "[0.0, 0.0, 1e9, 5.0]"),
                "bounds",
            ),
            (
                OK.replace("[0.0, 0.0, 6.0, 5.0]", "[-32.8, 0.0, 6.0, 5.0]"),
                "bounds",
            ),
        ];
        for (text, key) in cases {
            let e = parse(&text).unwrap_err();
            assert_eq!(e.key, key, "{e}");
            assert!(!e.rule.is_empty());
        }
    }

    /// What FORMAT.md says may not pass silently: an array longer or
    /// shorter than the format's (cut to size before), a polygon whose
    /// edges cross (it had area, so it loaded), a disc smaller than the
    /// planner's 20 mm (driven as a 20 mm one while the simulator checked
    /// the small one); a type error names its line and key.
    #[test]
    fn what_would_change_a_world_silently_is_refused() {
        let cases = [
            (OK.replace("[0.0, 0.0, 6.0, 5.0]", "[0.0, 0.0, 6.0, 5.0, 9.0]"), "bounds", "expected 4 numbers, found 5"),
            (OK.replace("start = [0.5, 2.5]", "start = [0.5, 2.5, 1.0]"), "start", "expected 2 numbers, found 3"),
            (OK.replace("center = [3.0, 2.5]", "center = [3.0]"), "center", "expected 2 numbers, found 1"),
            (
                format!("{OK}\n[[polygon]]\npoints = [[1.0, 1.0], [2.0, 2.0, 0.0], [1.0, 2.0]]\n"),
                "points",
                "expected points of 2 numbers, found one of 3",
            ),
            (
                format!("{OK}\n[[polygon]]\npoints = [[2.0, 0.5], [4.0, 1.5], [4.0, 0.5], [2.0, 1.0]]\n"),
                "polygon[0].points",
                "two of its edges cross",
            ),
            (OK.replace("goal = [5.5, 2.5]", "goal = [5.5, 2.5]\nrobot_radius = 0.001"), "robot_radius", "[0.02, 1) m"),
            (OK.replace("radius = 0.5", "radius = \"big\""), "radius", "line 9: "),
        ];
        for (text, key, rule) in cases {
            let e = parse(&text).unwrap_err();
            assert_eq!(e.key, key, "{e}");
            assert!(e.rule.contains(rule), "{e}");
        }
        // A simple polygon, concave and touching nothing, still loads.
        let u = "\n[[polygon]]\npoints = [[2.0, 3.5], [3.5, 3.5], [3.5, 4.5], [2.0, 4.5], [2.0, 4.3], [3.3, 4.3], [3.3, 3.7], [2.0, 3.7]]\n";
        assert!(parse(&format!("{OK}{u}")).is_ok());
        assert!(!self_intersects(&[
            [0.0, 0.0],
            [1.0, 0.0],
            [1.0, 1.0],
            [0.0, 1.0]
        ]));
        assert!(self_intersects(&[
            [0.0, 0.0],
            [1.0, 1.0],
            [1.0, 0.0],
            [0.0, 1.0]
        ]));
    }

    #[test]
    fn the_start_heading_is_reduced_to_one_turn() {
        let at = |deg: &str| {
            parse(&OK.replace(
                "goal = [5.5, 2.5]",
                &format!("goal = [5.5, 2.5]\nstart_heading = {deg}"),
            ))
            .unwrap()
            .start_heading_rad()
        };
        assert!((at("-90.0") - 1.5 * std::f64::consts::PI).abs() < 1e-12);
        assert!((at("450.0") - 0.5 * std::f64::consts::PI).abs() < 1e-12);
        let huge = at("1e300");
        assert!((0.0..std::f64::consts::TAU).contains(&huge), "{huge}");
    }

    #[test]
    fn a_world_as_wide_as_the_core_reaches_loads() {
        let wide = OK.replace("[0.0, 0.0, 6.0, 5.0]", "[-32.767, -1.0, 32.767, 5.0]");
        assert!(parse(&wide).is_ok());
    }

    #[test]
    fn every_shared_scenario_loads() {
        let shared = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/scenarios");
        let files = collect(&[shared]).unwrap();
        assert!(files.len() >= 600, "found {}", files.len());
        for f in files {
            Scenario::load(&f).unwrap_or_else(|e| panic!("{e}"));
        }
    }
}
