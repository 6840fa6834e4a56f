//! Random worlds, written as format 1: circle worlds with the EAPF paper's
//! parameters (environment 2: 80 circles, radii 0.12–0.9 m, 17.15 m ×
//! 14.7 m), and box worlds in the same arena (turned boxes and thin walls:
//! corners at every angle, pockets and walled-in goals, which circles
//! never make).

use crate::geom::{point_in_polygon, point_segment_distance, polygon_edges, V2};
use crate::reference::shortest_path;
use crate::scenario::Scenario;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use std::f64::consts::PI;
use std::fmt::Write;
use std::path::Path;

/// What a random world is made of.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Kind {
    /// 80 circles, radii 0.12–0.9 m: the EAPF paper's environment 2.
    Circles,
    /// 90 boxes (sides 0.15–1.5 m) and 30 thin walls (0.8–2.5 m long, 6 cm
    /// thick), each turned at random. A goal the walls close off is
    /// written `solvable = false`.
    Boxes,
    /// The box world of the same seed with a closed ring of thin walls
    /// round the goal (odd seeds) or round the start (even seeds): 5–9
    /// corners at 0.7–2.2 m from it, a star shape, often with pockets.
    /// Every goal is walled in (`solvable = false`): the right outcome is
    /// to report it unreachable.
    Walled,
    /// The circle world of the same seed and six circles moving back and
    /// forth across the straight way from start to goal (radii 0.1–0.3 m,
    /// 0.05–0.2 m/s, slower than the rover's 0.25; each on a straight run
    /// of 1–4 m that keeps clear of the static circles, the start and the
    /// goal). The reference ignores them: only the static world decides
    /// what is reachable.
    Moving,
    /// An indoor floor: the arena cut into rooms 2.4–4.2 m across (the last
    /// in a row or column up to 6.6 m: what is left) by thin
    /// walls, each room joined to the next through doorways 0.45–0.9 m
    /// wide (a door on every wall of a random spanning tree of the rooms,
    /// and on a third of the rest), with up to three turned boxes of
    /// furniture in each room, kept off the doorways. Furniture that
    /// closes the way is drawn again: every goal is reachable.
    Rooms,
}

impl Kind {
    /// File and scenario names of a set of these worlds: `<prefix>-<seed>`.
    pub fn prefix(self) -> &'static str {
        match self {
            Kind::Circles => "gen",
            Kind::Boxes => "box",
            Kind::Walled => "walled",
            Kind::Moving => "mov",
            Kind::Rooms => "rooms",
        }
    }

    /// What the file's `description` says.
    pub fn description(self) -> &'static str {
        match self {
            Kind::Circles => "random circle world with the EAPF paper's environment 2 parameters",
            Kind::Boxes => "random world of turned boxes and thin walls in the EAPF paper's environment 2 arena",
            Kind::Walled => "random world of turned boxes and thin walls with the goal or the start walled in: unsolvable",
            Kind::Moving => "random circle world with the EAPF paper's environment 2 parameters and six circles moving across the straight way",
            Kind::Rooms => "random indoor floor in the EAPF paper's environment 2 arena: rooms, doorways and furniture",
        }
    }
}

/// Boxes in a box world, and their sides' range, m.
const BOXES: usize = 90;
const BOX_SIDES: [f64; 2] = [0.15, 1.5];
/// Walls in a box world, their lengths' range and their thickness, m.
const WALLS: usize = 30;
const WALL_LENGTHS: [f64; 2] = [0.8, 2.5];
const WALL_THICKNESS: f64 = 0.06;
/// Kept clear round the start and the goal beyond the robot's radius, m.
const KEEP_CLEAR_M: f64 = 0.15;
/// A walled world's ring: its corners' count and their distances from the
/// point walled in, m.
const RING_CORNERS: [usize; 2] = [5, 9];
const RING_RADII: [f64; 2] = [0.7, 2.2];
/// A moving world's movers: their count, radii (m), speeds (m/s), the
/// length of their runs (m) and where along the straight way from start to
/// goal their runs cross it (fractions of it).
const MOVERS: usize = 6;
const MOVER_RADII: [f64; 2] = [0.1, 0.3];
const MOVER_SPEEDS: [f64; 2] = [0.05, 0.2];
const MOVER_RUNS: [f64; 2] = [1.0, 4.0];
const MOVER_CROSSINGS: [f64; 2] = [0.15, 0.85];
/// A floor's rooms (their widths and depths, m), doorways (widths, m; kept
/// this far from a wall's ends), the share of the walls off the spanning
/// tree that have a door too, and the furniture (boxes per room, their
/// sides, m, and how far they keep from a doorway's middle, m).
const ROOM_SIDES: [f64; 2] = [2.4, 4.2];
const DOOR_WIDTHS: [f64; 2] = [0.45, 0.9];
const DOOR_FROM_ENDS: f64 = 0.25;
const EXTRA_DOORS: f64 = 0.33;
const FURNITURE: usize = 3;
const FURNITURE_SIDES: [f64; 2] = [0.2, 0.9];
const FURNITURE_FROM_DOORS: f64 = 0.7;

/// A box world's goal is written unsolvable only when the reference finds
/// no path for a disc of a radius this much smaller (m) either: the
/// reference's grid can miss a gap up to one cell (0.02 m) wider than the
/// disc, so a way it misses for the smaller disc (0.06 m narrower) is at
/// least 0.04 m too narrow for the robot. Worlds between the two (a way
/// the grid may have missed) are drawn again.
pub const UNSOLVABLE_MARGIN_M: f64 = 0.03;

/// Parameters of a random circle world.
#[derive(Clone, Debug)]
pub struct RandomWorld {
    /// Scenario name.
    pub name: String,
    /// Width and height, m.
    pub size: [f64; 2],
    /// Number of circles.
    pub circles: usize,
    /// Radius range, m.
    pub radii: [f64; 2],
    /// Start and goal, m.
    pub start: [f64; 2],
    /// Goal, m.
    pub goal: [f64; 2],
    /// Robot radius, m.
    pub robot_radius: f64,
    /// Seed.
    pub seed: u64,
    /// Draws left before the world is given up (see [`MAX_DRAWS`]).
    draws: std::cell::Cell<u32>,
}

/// The most random draws (a shape, a run, a ring, a row of rooms, a whole
/// world) one world may take. Start and goal where nothing fits (outside
/// the arena, on top of each other, not numbers) would otherwise be drawn
/// round for ever; a good world takes a few hundred.
pub const MAX_DRAWS: u32 = 20_000;

impl RandomWorld {
    /// The paper's environment 2 parameters with a given start and goal.
    pub fn paper_env2(name: &str, start: [f64; 2], goal: [f64; 2], seed: u64) -> Self {
        RandomWorld {
            name: name.to_string(),
            size: [17.15, 14.7],
            circles: 80,
            radii: [0.12, 0.9],
            start,
            goal,
            robot_radius: 0.10,
            seed,
            draws: std::cell::Cell::new(MAX_DRAWS),
        }
    }

    /// One more draw of `what`, or the error once [`MAX_DRAWS`] are spent.
    fn draw(&self, what: &str) -> Result<(), String> {
        let left = self.draws.get();
        if left == 0 {
            return Err(format!(
                "{}: no {what} fits after {MAX_DRAWS} draws (start {:?}, goal {:?} in a {} × {} m arena)",
                self.name, self.start, self.goal, self.size[0], self.size[1]
            ));
        }
        self.draws.set(left - 1);
        Ok(())
    }

    /// The file's first lines: format, name, description, bounds, start,
    /// goal and robot.
    fn header(&self, description: &str) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "format = 1");
        let _ = writeln!(s, "name = \"{}\"", self.name);
        let _ = writeln!(s, "description = \"{description}\"");
        let _ = writeln!(s, "bounds = [0.0, 0.0, {}, {}]", self.size[0], self.size[1]);
        let _ = writeln!(s, "start = [{}, {}]", self.start[0], self.start[1]);
        let _ = writeln!(s, "goal = [{}, {}]", self.goal[0], self.goal[1]);
        let _ = writeln!(s, "robot_radius = {}", self.robot_radius);
        s
    }

    /// The scenario file text. Circles that would come within
    /// `robot_radius + KEEP_CLEAR_M` (0.15 m) of the start or goal are drawn again.
    pub fn to_toml(&self, description: &str) -> Result<String, String> {
        let mut s = self.header(description);
        let _ = writeln!(
            s,
            "# generated: seed {}, {} circles, radii {}..{} m",
            self.seed, self.circles, self.radii[0], self.radii[1]
        );
        for ([x, y], r) in self.circle_list()? {
            let _ = writeln!(
                s,
                "\n[[circle]]\ncenter = [{x:.3}, {y:.3}]\nradius = {r:.3}"
            );
        }
        Ok(s)
    }

    /// The circle world's circles (centre, radius; m), as written to the
    /// file (millimetres).
    fn circle_list(&self) -> Result<Vec<([f64; 2], f64)>, String> {
        let mut rng = Pcg64::seed_from_u64(self.seed);
        let keep = self.keep_clear_m();
        let mm = |v: f64| (v * 1000.0).round() / 1000.0;
        let mut circles = Vec::with_capacity(self.circles);
        while circles.len() < self.circles {
            self.draw("circle clear of the start and goal")?;
            let r = rng.gen_range(self.radii[0]..=self.radii[1]);
            let x = rng.gen_range(0.0..self.size[0]);
            let y = rng.gen_range(0.0..self.size[1]);
            let far = |p: [f64; 2]| (p[0] - x).hypot(p[1] - y) > r + keep;
            if far(self.start) && far(self.goal) {
                circles.push(([mm(x), mm(y)], mm(r)));
            }
        }
        Ok(circles)
    }

    /// A moving world's file text ([`Kind::Moving`]): the circle world of
    /// the same seed, then its movers, drawn from their own stream so that
    /// the circles are those of `gen-<seed>`. A mover's run is drawn again
    /// while it comes within the mover's radius of a static circle, or
    /// within it plus `robot_radius + KEEP_CLEAR_M` of the start or goal
    /// (the rover is not struck where it begins or ends).
    pub fn moving_toml(&self, description: &str) -> Result<String, String> {
        let mut s = self.to_toml(description)?;
        let circles = self.circle_list()?;
        let mut rng = Pcg64::seed_from_u64(self.seed ^ 0x4d4f_5645);
        let v = |p: [f64; 2]| V2::new(p[0], p[1]);
        let (start, goal) = (v(self.start), v(self.goal));
        let keep = self.keep_clear_m();
        let _ = writeln!(
            s,
            "\n# {MOVERS} movers, radii {}..{} m, {}..{} m/s, runs {}..{} m across the straight way",
            MOVER_RADII[0], MOVER_RADII[1], MOVER_SPEEDS[0], MOVER_SPEEDS[1], MOVER_RUNS[0], MOVER_RUNS[1]
        );
        let mut n = 0;
        while n < MOVERS {
            self.draw("mover's run clear of the start, the goal and the circles")?;
            let r = rng.gen_range(MOVER_RADII[0]..=MOVER_RADII[1]);
            let speed = rng.gen_range(MOVER_SPEEDS[0]..=MOVER_SPEEDS[1]);
            let run = rng.gen_range(MOVER_RUNS[0]..=MOVER_RUNS[1]);
            let cross =
                start + (goal - start) * rng.gen_range(MOVER_CROSSINGS[0]..=MOVER_CROSSINGS[1]);
            let dir = V2::from_angle(rng.gen_range(0.0..PI));
            // Where along its run it crosses the way.
            let before = rng.gen_range(0.0..=run);
            let (a, b) = (cross - dir * before, cross + dir * (run - before));
            let clear_of = |c: V2, d: f64| point_segment_distance(c, a, b) > d;
            let inside =
                |p: V2| p.x > r && p.y > r && p.x < self.size[0] - r && p.y < self.size[1] - r;
            if !(inside(a)
                && inside(b)
                && clear_of(start, r + keep)
                && clear_of(goal, r + keep)
                && circles.iter().all(|&(c, cr)| clear_of(v(c), cr + r)))
            {
                continue;
            }
            let _ = writeln!(
                s,
                "\n[[moving]]\ncenter = [{:.3}, {:.3}]\nradius = {r:.3}\nwaypoints = [[{:.3}, {:.3}]]\nspeed = {speed:.3}",
                a.x, a.y, b.x, b.y
            );
            n += 1;
        }
        Ok(s)
    }
}

/// The file text of a random world of `kind` in the paper's environment 2
/// arena, named `name`, from `start` to `goal`, drawn from `seed`.
pub fn world(
    kind: Kind,
    name: &str,
    start: [f64; 2],
    goal: [f64; 2],
    seed: u64,
) -> Result<String, String> {
    if !start.iter().chain(&goal).all(|v| v.is_finite()) {
        return Err(format!(
            "{name}: start {start:?} and goal {goal:?} must be numbers"
        ));
    }
    let w = RandomWorld::paper_env2(name, start, goal, seed);
    match kind {
        Kind::Circles => w.to_toml(kind.description()),
        Kind::Boxes => w.boxes_toml(kind.description()),
        Kind::Walled => w.walled_toml(kind.description()),
        Kind::Moving => w.moving_toml(kind.description()),
        Kind::Rooms => w.rooms_toml(kind.description()),
    }
}

impl RandomWorld {
    /// A box world's file text ([`Kind::Boxes`]): the arena, start, goal,
    /// robot and seed of `self`. Shapes that would come within
    /// `robot_radius + KEEP_CLEAR_M` (0.15 m) of the start or goal are drawn again; so is
    /// the whole world while the reference cannot tell whether the goal is
    /// closed off (see [`UNSOLVABLE_MARGIN_M`]).
    pub fn boxes_toml(&self, description: &str) -> Result<String, String> {
        self.boxes_with(description, &[])
    }

    /// What nothing may come within round the start and the goal, m.
    fn keep_clear_m(&self) -> f64 {
        self.robot_radius + KEEP_CLEAR_M
    }

    /// A walled world's file text ([`Kind::Walled`]): the box world of
    /// the same seed and a closed ring of walls round the goal (odd seeds)
    /// or the start (even seeds), drawn from its own stream so that the
    /// boxes are those of `box-<seed>`.
    pub fn walled_toml(&self, description: &str) -> Result<String, String> {
        let mut rng = Pcg64::seed_from_u64(self.seed ^ 0x5741_4c4c);
        let inside = if self.seed % 2 == 1 {
            self.goal
        } else {
            self.start
        };
        let keep = self.keep_clear_m();
        loop {
            self.draw("ring of walls clear of what it holds")?;
            let n = rng.gen_range(RING_CORNERS[0]..=RING_CORNERS[1]);
            let corners: Vec<[f64; 2]> = (0..n)
                .map(|i| {
                    let a = (i as f64 + rng.gen_range(-0.3..0.3)) * 2.0 * PI / n as f64;
                    let r = rng.gen_range(RING_RADII[0]..=RING_RADII[1]);
                    [inside[0] + r * a.cos(), inside[1] + r * a.sin()]
                })
                .collect();
            // Each wall runs half its thickness past both corners, so
            // that neighbours overlap there and the ring is closed.
            let walls: Vec<TurnedBox> = (0..n)
                .map(|i| {
                    let (a, b) = (corners[i], corners[(i + 1) % n]);
                    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
                    TurnedBox {
                        c: [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0],
                        half: [
                            dx.hypot(dy) / 2.0 + WALL_THICKNESS / 2.0,
                            WALL_THICKNESS / 2.0,
                        ],
                        turn: dy.atan2(dx),
                    }
                })
                .collect();
            if walls.iter().all(|w| w.distance(inside) > keep) {
                return self.boxes_with(description, &walls);
            }
        }
    }

    /// The box world of `self`'s seed with `extra` shapes added.
    fn boxes_with(&self, description: &str, extra: &[TurnedBox]) -> Result<String, String> {
        let mut rng = Pcg64::seed_from_u64(self.seed);
        let keep = self.keep_clear_m();
        loop {
            self.draw("box world whose goal the reference can tell")?;
            let mut body = polygons_text(extra);
            let mut n = 0;
            while n < BOXES + WALLS {
                self.draw("box or wall clear of the start and goal")?;
                let (w, h) = if n < BOXES {
                    (
                        rng.gen_range(BOX_SIDES[0]..=BOX_SIDES[1]),
                        rng.gen_range(BOX_SIDES[0]..=BOX_SIDES[1]),
                    )
                } else {
                    (
                        rng.gen_range(WALL_LENGTHS[0]..=WALL_LENGTHS[1]),
                        WALL_THICKNESS,
                    )
                };
                let c = [
                    rng.gen_range(0.0..self.size[0]),
                    rng.gen_range(0.0..self.size[1]),
                ];
                let turn = rng.gen_range(0.0..PI);
                let b = TurnedBox {
                    c,
                    half: [w / 2.0, h / 2.0],
                    turn,
                };
                if b.distance(self.start) <= keep || b.distance(self.goal) <= keep {
                    continue;
                }
                body += &polygons_text(std::slice::from_ref(&b));
                n += 1;
            }
            let head = |solvable: bool| {
                let mut s = self.header(description);
                if !solvable {
                    let _ = writeln!(s, "solvable = false");
                }
                let _ = writeln!(
                    s,
                    "# generated: seed {}, {BOXES} boxes of sides {}..{} m, {WALLS} walls {}..{} m long",
                    self.seed, BOX_SIDES[0], BOX_SIDES[1], WALL_LENGTHS[0], WALL_LENGTHS[1]
                );
                if !extra.is_empty() {
                    let _ = writeln!(s, "# and first a closed ring of {} walls", extra.len());
                }
                s + &body
            };
            let text = head(true);
            match Scenario::parse(&text, Path::new(&self.name)).map(|sc| reachable(&sc)) {
                Ok(Some(true)) => return Ok(text),
                Ok(Some(false)) => return Ok(head(false)),
                _ => {}
            }
        }
    }
}

impl RandomWorld {
    /// Wall lines across one side of the arena, `length` m long: room
    /// sides drawn from [`ROOM_SIDES`] until the last room is at least the
    /// smallest side, none within `keep` (plus half a wall) of `avoid`.
    fn wall_lines(
        &self,
        rng: &mut Pcg64,
        length: f64,
        avoid: [f64; 2],
        keep: f64,
    ) -> Result<Vec<f64>, String> {
        loop {
            self.draw("row of rooms whose walls miss the start and goal")?;
            let mut lines = Vec::new();
            let mut at = rng.gen_range(ROOM_SIDES[0]..=ROOM_SIDES[1]);
            while at < length - ROOM_SIDES[0] {
                lines.push(at);
                at += rng.gen_range(ROOM_SIDES[0]..=ROOM_SIDES[1]);
            }
            let clear = |&w: &f64| {
                avoid
                    .iter()
                    .all(|a| (a - w).abs() > keep + WALL_THICKNESS / 2.0)
            };
            if lines.iter().all(clear) {
                return Ok(lines);
            }
        }
    }

    /// A floor's file text ([`Kind::Rooms`]).
    pub fn rooms_toml(&self, description: &str) -> Result<String, String> {
        let mut rng = Pcg64::seed_from_u64(self.seed ^ 0x524f_4f4d);
        let keep = self.keep_clear_m();
        let [w, h] = self.size;
        let xs = self.wall_lines(&mut rng, w, [self.start[0], self.goal[0]], keep)?;
        let ys = self.wall_lines(&mut rng, h, [self.start[1], self.goal[1]], keep)?;
        // Room (i, j) spans edges[i]..edges[i + 1] across and likewise up.
        let edges = |lines: &[f64], end: f64| {
            let mut e = vec![0.0];
            e.extend_from_slice(lines);
            e.push(end);
            e
        };
        let (ex, ey) = (edges(&xs, w), edges(&ys, h));
        let (nx, ny) = (ex.len() - 1, ey.len() - 1);
        // The walls between neighbours: (room a, room b), rooms numbered
        // i + nx·j.
        let room = |i: usize, j: usize| i + nx * j;
        let mut walls: Vec<(usize, usize)> = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                if i + 1 < nx {
                    walls.push((room(i, j), room(i + 1, j)));
                }
                if j + 1 < ny {
                    walls.push((room(i, j), room(i, j + 1)));
                }
            }
        }
        let door = doors_of(&mut rng, &walls, nx * ny);
        // Each wall as boxes with a gap at its door: a wall between rooms
        // side by side is upright, at the left room's right edge.
        let mut shapes: Vec<TurnedBox> = Vec::new();
        let mut doors: Vec<[f64; 2]> = Vec::new();
        let t = WALL_THICKNESS / 2.0;
        for (k, &(a, b)) in walls.iter().enumerate() {
            let (i, j) = (a % nx, a / nx);
            let upright = b == a + 1;
            // The wall's fixed coordinate and its span along the other axis.
            let (at, lo, hi) = if upright {
                (ex[i + 1], ey[j], ey[j + 1])
            } else {
                (ey[j + 1], ex[i], ex[i + 1])
            };
            let piece = |from: f64, to: f64| {
                let (mid, half) = ((from + to) / 2.0, (to - from) / 2.0 + t);
                if upright {
                    TurnedBox {
                        c: [at, mid],
                        half: [t, half],
                        turn: 0.0,
                    }
                } else {
                    TurnedBox {
                        c: [mid, at],
                        half: [half, t],
                        turn: 0.0,
                    }
                }
            };
            if door[k] {
                let width = rng.gen_range(DOOR_WIDTHS[0]..=DOOR_WIDTHS[1]);
                let from = rng.gen_range(lo + DOOR_FROM_ENDS..=hi - DOOR_FROM_ENDS - width);
                shapes.push(piece(lo, from));
                shapes.push(piece(from + width, hi));
                let mid = from + width / 2.0;
                doors.push(if upright { [at, mid] } else { [mid, at] });
            } else {
                shapes.push(piece(lo, hi));
            }
        }
        let head = self.header(description);
        let comment = format!(
            "# generated: seed {}, {nx} × {ny} rooms, {} doorways, up to {FURNITURE} boxes of furniture a room\n",
            self.seed,
            doors.len()
        );
        loop {
            self.draw("furnished floor whose goal the reference reaches")?;
            let mut furniture: Vec<TurnedBox> = Vec::new();
            for j in 0..ny {
                for i in 0..nx {
                    for _ in 0..rng.gen_range(0..=FURNITURE) {
                        let b = TurnedBox {
                            c: [
                                rng.gen_range(ex[i]..ex[i + 1]),
                                rng.gen_range(ey[j]..ey[j + 1]),
                            ],
                            half: [
                                rng.gen_range(FURNITURE_SIDES[0]..=FURNITURE_SIDES[1]) / 2.0,
                                rng.gen_range(FURNITURE_SIDES[0]..=FURNITURE_SIDES[1]) / 2.0,
                            ],
                            turn: rng.gen_range(0.0..PI),
                        };
                        let clear = b.distance(self.start) > keep
                            && b.distance(self.goal) > keep
                            && doors.iter().all(|&d| b.distance(d) > FURNITURE_FROM_DOORS);
                        if clear {
                            furniture.push(b);
                        }
                    }
                }
            }
            let text = format!(
                "{head}{comment}{}{}",
                polygons_text(&shapes),
                polygons_text(&furniture)
            );
            if let Ok(sc) = Scenario::parse(&text, Path::new(&self.name)) {
                if reachable(&sc) == Some(true) {
                    return Ok(text);
                }
            }
        }
    }
}

/// Whether the robot can reach the goal: `Some(true)` when the reference
/// finds a path, `Some(false)` when it finds none even for a disc whose
/// radius is [`UNSOLVABLE_MARGIN_M`] smaller, `None` between the two (the
/// reference's grid may have missed a way).
pub fn reachable(sc: &Scenario) -> Option<bool> {
    if shortest_path(sc).is_some() {
        return Some(true);
    }
    let narrower = Scenario {
        robot_radius: sc.robot_radius - UNSOLVABLE_MARGIN_M,
        ..sc.clone()
    };
    shortest_path(&narrower).is_none().then_some(false)
}

/// Which of the `walls` between `rooms` rooms (each a pair of room numbers)
/// get a doorway: every wall of a random spanning tree, found by a random
/// walk's first visits to each room (Aldous–Broder: every tree equally
/// likely), so that every room is joined; then each other wall with the
/// chance [`EXTRA_DOORS`].
fn doors_of(rng: &mut Pcg64, walls: &[(usize, usize)], rooms: usize) -> Vec<bool> {
    let mut door = vec![false; walls.len()];
    let mut seen = vec![false; rooms];
    let mut at = rng.gen_range(0..rooms);
    seen[at] = true;
    let mut left = rooms - 1;
    while left > 0 {
        let next: Vec<usize> = (0..walls.len())
            .filter(|&k| walls[k].0 == at || walls[k].1 == at)
            .collect();
        let k = next[rng.gen_range(0..next.len())];
        let to = if walls[k].0 == at {
            walls[k].1
        } else {
            walls[k].0
        };
        if !seen[to] {
            seen[to] = true;
            door[k] = true;
            left -= 1;
        }
        at = to;
    }
    for d in door.iter_mut() {
        if !*d && rng.gen_bool(EXTRA_DOORS) {
            *d = true;
        }
    }
    door
}

/// The boxes as the file's `[[polygon]]` tables, corners in millimetres.
fn polygons_text(boxes: &[TurnedBox]) -> String {
    let mut body = String::new();
    for b in boxes {
        let points: Vec<String> = b
            .corners()
            .iter()
            .map(|p| format!("[{:.3}, {:.3}]", p[0], p[1]))
            .collect();
        let _ = writeln!(body, "\n[[polygon]]\npoints = [{}]", points.join(", "));
    }
    body
}

/// A rectangle turned by `turn` (rad) about its centre `c`, m.
struct TurnedBox {
    c: [f64; 2],
    half: [f64; 2],
    turn: f64,
}

impl TurnedBox {
    /// Its corners in order.
    fn corners(&self) -> [[f64; 2]; 4] {
        let (s, c) = self.turn.sin_cos();
        [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].map(|(i, j)| {
            let (x, y) = (i * self.half[0], j * self.half[1]);
            [self.c[0] + x * c - y * s, self.c[1] + x * s + y * c]
        })
    }

    /// Distance from `p` to the box (0 inside).
    fn distance(&self, p: [f64; 2]) -> f64 {
        let corners = self.corners().map(|[x, y]| V2::new(x, y));
        let p = V2::new(p[0], p[1]);
        if point_in_polygon(p, &corners) {
            return 0.0;
        }
        polygon_edges(&corners)
            .map(|(a, b)| point_segment_distance(p, a, b))
            .fold(f64::INFINITY, f64::min)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generated_worlds_are_valid_and_seeded() {
        let w = RandomWorld::paper_env2("g", START, GOAL, 3);
        let a = w.to_toml("test").unwrap();
        assert_eq!(a, w.to_toml("test").unwrap());
        let sc = parsed(&a);
        assert_eq!(sc.circle.len(), 80);
        assert!(sc.circle.iter().all(|c| (0.12..=0.9).contains(&c.radius)));
    }

    /// The tests' start and goal (the CLI's defaults).
    const START: [f64; 2] = [6.0, 7.3];
    const GOAL: [f64; 2] = [12.7, 9.75];

    /// `kind`'s world of `seed` between [`START`] and [`GOAL`], which must
    /// come out the same twice.
    fn generated(kind: Kind, seed: u64) -> String {
        let text = world(kind, "g", START, GOAL, seed).unwrap();
        assert_eq!(
            text,
            world(kind, "g", START, GOAL, seed).unwrap(),
            "seed {seed}"
        );
        text
    }

    /// Where nothing fits, every kind ends with an error naming the world,
    /// not a loop: start and goal that are not numbers, a start in the
    /// arena's corner (no ring of walls or row of rooms misses it), start
    /// and goal on one spot (every mover's run crosses them).
    #[test]
    fn where_nothing_fits_generation_ends_with_an_error() {
        let nan = [f64::NAN, f64::NAN];
        for kind in [
            Kind::Circles,
            Kind::Boxes,
            Kind::Walled,
            Kind::Moving,
            Kind::Rooms,
        ] {
            let e = world(kind, "g", nan, GOAL, 1).unwrap_err();
            assert!(e.contains("must be numbers"), "{e}");
        }
        for kind in [Kind::Boxes, Kind::Walled, Kind::Rooms] {
            match world(kind, "g", [0.01, 0.01], GOAL, 1) {
                Ok(text) => assert!(Scenario::parse(&text, Path::new("g")).is_ok()),
                Err(e) => assert!(e.contains("g: no ") && e.contains("draws"), "{e}"),
            }
        }
        let e = world(Kind::Moving, "g", START, START, 1).unwrap_err();
        assert!(e.contains("no mover's run"), "{e}");
    }

    #[test]
    fn box_worlds_are_valid_seeded_and_keep_clear_of_start_and_goal() {
        let (start, goal) = (START, GOAL);
        for seed in 1..=4 {
            let a = generated(Kind::Boxes, seed);
            assert_ne!(a, generated(Kind::Boxes, seed + 1));
            let sc = parsed(&a);
            assert_eq!(sc.polygon.len(), BOXES + WALLS);
            for p in [start, goal] {
                assert_kept_clear(&sc, p, seed);
            }
        }
    }

    /// A generated file, parsed.
    fn parsed(text: &str) -> Scenario {
        Scenario::parse(text, std::path::Path::new("gen")).unwrap()
    }

    /// Nothing of `sc` within `robot_radius + KEEP_CLEAR_M` of `p` (what
    /// the generators keep clear round the start and the goal).
    fn assert_kept_clear(sc: &Scenario, p: [f64; 2], seed: u64) {
        let w = sc.world();
        let clear = w.clearance(crate::geom::V2::new(p[0], p[1]), 0.0);
        assert!(
            clear > sc.robot_radius + KEEP_CLEAR_M - 1e-9,
            "seed {seed}: {clear}"
        );
    }

    #[test]
    fn moving_worlds_are_the_circle_world_and_movers_that_cross_the_way_clear_of_it() {
        for seed in 1..=4 {
            let sc = parsed(&generated(Kind::Moving, seed));
            let circles = parsed(&generated(Kind::Circles, seed));
            assert_eq!(sc.circle, circles.circle, "seed {seed}");
            assert!(sc.solvable);
            assert_eq!(sc.moving.len(), MOVERS);
            let (start, goal) = (V2::new(START[0], START[1]), V2::new(GOAL[0], GOAL[1]));
            for m in &sc.moving {
                let (a, b) = (
                    V2::new(m.center[0], m.center[1]),
                    V2::new(m.waypoints[0][0], m.waypoints[0][1]),
                );
                assert!((MOVER_RADII[0]..=MOVER_RADII[1]).contains(&m.radius));
                assert!((MOVER_SPEEDS[0]..=MOVER_SPEEDS[1]).contains(&m.speed));
                let run = a.dist(b);
                assert!(
                    (MOVER_RUNS[0] - 0.01..=MOVER_RUNS[1] + 0.01).contains(&run),
                    "{run}"
                );
                // It crosses the straight way (the two segments meet).
                let meet = crate::geom::segment_segment_distance(a, b, start, goal);
                assert!(meet < 0.01, "seed {seed}: {meet}");
                // Never onto a static circle, the start or the goal.
                for c in &sc.circle {
                    let d = point_segment_distance(V2::new(c.center[0], c.center[1]), a, b);
                    assert!(d > c.radius + m.radius - 0.002, "seed {seed}");
                }
                for p in [start, goal] {
                    let d = point_segment_distance(p, a, b) - m.radius;
                    assert!(
                        d > sc.robot_radius + KEEP_CLEAR_M - 0.002,
                        "seed {seed}: {d}"
                    );
                }
            }
        }
    }

    #[test]
    fn floors_are_rooms_joined_by_doorways_with_every_goal_reachable() {
        for seed in 1..=3 {
            let text = generated(Kind::Rooms, seed);
            let sc = parsed(&text);
            assert!(sc.solvable);
            assert_eq!(reachable(&sc), Some(true), "seed {seed}");
            for p in [START, GOAL] {
                assert_kept_clear(&sc, p, seed);
            }
            // "N × M rooms, D doorways": a spanning tree's doors at least.
            let comment = text.lines().find(|l| l.starts_with("# generated")).unwrap();
            let words: Vec<&str> = comment.split_whitespace().collect();
            let at = words.iter().position(|w| *w == "rooms,").unwrap();
            let (nx, ny): (usize, usize) = (
                words[at - 3].parse().unwrap(),
                words[at - 1].parse().unwrap(),
            );
            let doors: usize = words[at + 1].parse().unwrap();
            assert!(nx >= 4 && ny >= 3, "seed {seed}: {nx} × {ny}");
            assert!(doors >= nx * ny - 1, "seed {seed}: {doors} doorways");
            // Without the doorways (a disc too wide for the widest), no way.
            let wide = Scenario {
                robot_radius: DOOR_WIDTHS[1] / 2.0 + 0.01,
                ..sc.clone()
            };
            assert!(shortest_path(&wide).is_none(), "seed {seed}");
        }
    }

    #[test]
    fn the_doorways_join_every_room() {
        // A 4 × 3 grid of rooms: the walls between neighbours.
        let (nx, ny) = (4, 3);
        let mut walls = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                if i + 1 < nx {
                    walls.push((i + nx * j, i + 1 + nx * j));
                }
                if j + 1 < ny {
                    walls.push((i + nx * j, i + nx * (j + 1)));
                }
            }
        }
        for seed in 0..50 {
            let door = doors_of(&mut Pcg64::seed_from_u64(seed), &walls, nx * ny);
            // Through doorways only, from room 0 every room is reached.
            let mut reached = vec![false; nx * ny];
            reached[0] = true;
            let mut grew = true;
            while grew {
                grew = false;
                for (k, &(a, b)) in walls.iter().enumerate() {
                    if door[k] && reached[a] != reached[b] {
                        reached[a] = true;
                        reached[b] = true;
                        grew = true;
                    }
                }
            }
            assert!(reached.iter().all(|&r| r), "seed {seed}");
            // A tree has rooms − 1 walls; the rest are extra doors.
            assert!(door.iter().filter(|&&d| d).count() >= nx * ny - 1);
        }
    }

    #[test]
    fn walled_worlds_are_the_box_world_and_a_closed_ring_round_the_goal_or_start() {
        let (start, goal) = (START, GOAL);
        for seed in 1..=4 {
            let sc = parsed(&generated(Kind::Walled, seed));
            assert!(!sc.solvable, "seed {seed}");
            let ring = sc.polygon.len() - (BOXES + WALLS);
            assert!(
                (RING_CORNERS[0]..=RING_CORNERS[1]).contains(&ring),
                "seed {seed}: {ring} walls"
            );
            // The boxes are box-<seed>'s, after the ring's walls.
            let boxes = parsed(&generated(Kind::Boxes, seed));
            assert_eq!(sc.polygon[ring..], boxes.polygon[..], "seed {seed}");
            // Odd seeds wall the goal in, even ones the start: without the
            // ring that point is the box world's, and with it no disc of
            // any size gets from one to the other.
            let inside = if seed % 2 == 1 { goal } else { start };
            assert_kept_clear(&sc, inside, seed);
            let tiny = Scenario {
                robot_radius: 0.01,
                ..sc.clone()
            };
            assert!(
                shortest_path(&tiny).is_none(),
                "seed {seed}: the ring is open"
            );
        }
    }

    #[test]
    fn a_goal_is_unreachable_only_when_no_way_is_near_the_robots_width() {
        // The goal behind a wall from one side to the other, with a gap
        // `gap` m wide at its middle; the robot's disc is 0.2 m across.
        let walled = |gap: f64| {
            let (a, b) = (1.5 - gap / 2.0, 1.5 + gap / 2.0);
            let text = format!(
                "format = 1\nname = \"w\"\nbounds = [0.0, 0.0, 4.0, 3.0]\nstart = [0.5, 1.5]\ngoal = [3.5, 1.5]\n\
                 [[polygon]]\npoints = [[1.9, -0.1], [2.1, -0.1], [2.1, {a}], [1.9, {a}]]\n\
                 [[polygon]]\npoints = [[1.9, {b}], [2.1, {b}], [2.1, 3.1], [1.9, 3.1]]\n"
            );
            parsed(&text)
        };
        assert_eq!(reachable(&walled(0.0)), Some(false));
        assert_eq!(reachable(&walled(0.1)), Some(false));
        assert_eq!(reachable(&walled(0.3)), Some(true));
        // Just wider than the disc: the grid may or may not find it.
        let near = reachable(&walled(0.205));
        assert_ne!(near, Some(false));
    }

    #[test]
    fn turned_box_distance_matches_its_corners() {
        let b = TurnedBox {
            c: [1.0, 2.0],
            half: [0.5, 0.1],
            turn: 0.7,
        };
        for p in b.corners() {
            assert!(b.distance(p) < 1e-9);
        }
        assert_eq!(b.distance(b.c), 0.0);
        // Straight out from the middle of a long side, 0.3 m.
        let (s, c) = b.turn.sin_cos();
        let p = [b.c[0] - 0.4 * s, b.c[1] + 0.4 * c];
        assert!((b.distance(p) - 0.3).abs() < 1e-9);
    }
}
