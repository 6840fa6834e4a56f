//! The simulated rover: a differential drive that executes the core's
//! command as the firmwares' executor does (a turn in place, a pause of one
//! sensor period after it, then an advance that asks the core's guard
//! before every centimetre, the first included), checks every motion
//! exactly against the world and every stand (a turn on the spot, a pause)
//! against the moving circles, and feeds the planner odometry (exact, or
//! with the `slip` fault's seeded slip).

use crate::fault::{Fault, Faults};
use crate::geom::V2;
use crate::planners::{PlannerKind, SimPlanner};
use crate::scenario::Scenario;
use crate::sensor::{SensorMode, VirtualSensors};
use crate::units::{to_point, to_rad, to_v2};
use crate::world::World;
use planner_core::{AdcProfile, Status};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use rand_pcg::Pcg64;
use serde::{Deserialize, Serialize};

/// How a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Outcome {
    /// Within the goal tolerance, no collision.
    Reached,
    /// The robot's disc touched an obstacle or wall.
    Collision,
    /// The planner reported the goal unreachable and stopped.
    Unreachable,
    /// The budget ran out.
    Timeout,
    /// The planner stopped as arrived, but the true pose is not within
    /// its goal tolerance: odometry went astray (a fault).
    Astray,
}

impl Outcome {
    /// Lower-case name.
    pub fn as_str(self) -> &'static str {
        match self {
            Outcome::Reached => "reached",
            Outcome::Collision => "collision",
            Outcome::Unreachable => "unreachable",
            Outcome::Timeout => "timeout",
            Outcome::Astray => "astray",
        }
    }
}

/// How a run that ended in a collision ended: what the disc touched, and
/// whether the rover was driving or standing (turning in place, pausing
/// after a turn, waiting for a sensor).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Contact {
    /// What it touched.
    pub with: Touched,
    /// Whether the rover stood: then only a moving circle can reach it.
    pub standing: bool,
}

impl Contact {
    /// Its words in the run's figures.
    pub fn describe(self) -> String {
        format!(
            "{} while {}",
            self.with.as_str(),
            if self.standing { "standing" } else { "driving" }
        )
    }
}

/// What the disc touched.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Touched {
    /// A wall or a static obstacle.
    Static,
    /// A moving circle within 45° of the heading, where the beams look
    /// (their sector is ±40°).
    MoverAhead,
    /// A moving circle at the disc's side or back, where no beam looks:
    /// it reached the rover, which could not have seen it come.
    MoverBeside,
}

impl Touched {
    /// Its name in the `--json` rows and the run's figures.
    pub fn as_str(self) -> &'static str {
        match self {
            Touched::Static => "static",
            Touched::MoverAhead => "mover-ahead",
            Touched::MoverBeside => "mover-beside",
        }
    }

    /// What a disc of radius `r` at `p` facing `heading` (rad) touches at
    /// time `t`: the nearer of the static world and the nearest moving
    /// circle, and where that circle is.
    fn at(world: &World, p: V2, t: f64, heading: f64, r: f64) -> Touched {
        let fixed = world.static_sweep_clearance(p, p);
        let mover = world
            .moving
            .iter()
            .map(|m| (p.dist(m.center_at(t)) - m.radius, m.center_at(t)))
            .min_by(|a, b| a.0.total_cmp(&b.0));
        match mover {
            Some((c, centre)) if c < fixed.min(r + 1e-3) + 1e-9 => {
                let bearing = wrap((centre.y - p.y).atan2(centre.x - p.x) - heading);
                if bearing.abs() <= 45f64.to_radians() {
                    Touched::MoverAhead
                } else {
                    Touched::MoverBeside
                }
            }
            _ => Touched::Static,
        }
    }

    /// What the disc touched first while moving `a → b` during `[t0, t1]`
    /// (a piece that ended in a collision): sampled 20 times along it.
    fn first_in(
        world: &World,
        (a, b): (V2, V2),
        (t0, t1): (f64, f64),
        heading: f64,
        r: f64,
    ) -> Touched {
        const SAMPLES: usize = 20;
        let at = |k: usize| {
            let f = k as f64 / SAMPLES as f64;
            (a + (b - a) * f, t0 + (t1 - t0) * f)
        };
        let k = (0..=SAMPLES)
            .find(|&k| {
                let (p, t) = at(k);
                world.clearance(p, t) <= r
            })
            .unwrap_or(SAMPLES);
        let (p, t) = at(k);
        Touched::at(world, p, t, heading, r)
    }
}

/// A planner that stops as arrived is there if its true pose is within its
/// goal tolerance plus this, m (the core's positions are whole mm).
const ARRIVAL_SLACK_M: f64 = 0.01;

/// How long the executor waits on stalled wheels before it ends the step, s.
const STALL_S: f64 = 0.1;

/// Simulation settings.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Which planner drives.
    pub planner: PlannerKind,
    /// Seed for sensor noise and the faults.
    pub seed: u64,
    /// Sensor model.
    pub sensors: SensorMode,
    /// ADC of the emulated board.
    pub adc: AdcProfile,
    /// The sensors set back from the rim by their minimum range
    /// (`planner_core::ConfigBuilder::sensors_set_back`); on the rim
    /// otherwise.
    pub set_back: bool,
    /// Forward speed, m/s.
    pub speed: f64,
    /// Turn rate, rad/s.
    pub turn_rate: f64,
    /// Faults injected (`--fault`).
    pub faults: Vec<Fault>,
    /// Budget: planner cycles.
    pub max_steps: usize,
    /// Budget: driven length as a multiple of the reference plus 5 m
    /// (without a reference: five times that multiple of the straight line
    /// plus 10 m, room for a planner to find out by itself).
    pub max_length_ratio: f64,
}

impl Default for SimConfig {
    fn default() -> Self {
        SimConfig {
            planner: PlannerKind::Eapf,
            seed: 1,
            sensors: SensorMode::REALISTIC,
            adc: AdcProfile::AVR_10BIT_5V,
            set_back: false,
            speed: 0.25,
            turn_rate: 2.0,
            faults: Vec::new(),
            max_steps: 3_000,
            max_length_ratio: 8.0,
        }
    }
}

impl SimConfig {
    /// The clearance the planners keep beyond the disc (the safety rule's,
    /// of the default configuration for this board's ADC), mm.
    pub fn margin_mm(&self) -> Result<u16, String> {
        planner_core::ConfigBuilder::new(self.adc)
            .build()
            .map(|c| c.clearance_mm())
            .map_err(|e| format!("{e:?}"))
    }
}

/// One row of the driven path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraceRow {
    /// Time, s.
    pub t: f64,
    /// x, m.
    pub x: f64,
    /// y, m.
    pub y: f64,
    /// Heading, rad.
    pub heading: f64,
}

/// Everything a run produced.
#[derive(Clone, Debug)]
pub struct RunResult {
    /// How it ended.
    pub outcome: Outcome,
    /// Planner cycles.
    pub steps: usize,
    /// Driven length, m.
    pub path_length: f64,
    /// Simulated time at the end, s: turns, pauses and waits included.
    pub duration_s: f64,
    /// Smallest clearance between the robot's disc and any obstacle, m.
    pub min_clearance: f64,
    /// What the disc touched, when the run ended in a collision.
    pub contact: Option<Contact>,
    /// The true driven path, rows at most 1 cm apart.
    pub trace: Vec<TraceRow>,
    /// Collision points the planner saw (world, m).
    pub seen: Vec<V2>,
    /// Remembered points at the end (world, m).
    pub remembered: Vec<V2>,
    /// Midpoint of the active remembered points at the end.
    pub midpoint: Option<V2>,
    /// Virtual obstacles at the end (centre, radius), m.
    pub virtual_obstacles: Vec<(V2, f64)>,
    /// Total virtual obstacles dropped.
    pub virtual_dropped: usize,
    /// Cycles whose status was a sensor fault.
    pub sensor_faults: usize,
    /// The route over the known map at the end (planner `route`): its
    /// waypoints, then the goal; empty for the other planners.
    pub route: Vec<V2>,
}

/// The longest piece of a stand checked against the moving circles as one
/// linear motion, s: the time an advance's 1 cm piece takes at 0.25 m/s.
const STAND_PIECE_S: f64 = 0.04;

/// The true motion of a run: trace rows, driven length, smallest clearance.
struct Track {
    trace: Vec<TraceRow>,
    length: f64,
    min_clear: f64,
    contact: Option<Contact>,
}

impl Track {
    /// Standing at `p`.
    fn new(world: &World, p: V2, heading: f64, r: f64) -> Track {
        Track {
            trace: vec![TraceRow {
                t: 0.0,
                x: p.x,
                y: p.y,
                heading,
            }],
            length: 0.0,
            min_clear: world.clearance(p, 0.0) - r,
            contact: None,
        }
    }

    /// A trace row.
    fn row(&mut self, t: f64, p: V2, heading: f64) {
        self.trace.push(TraceRow {
            t,
            x: p.x,
            y: p.y,
            heading,
        });
    }

    /// The disc of radius `r` moves `a → b` during `[t0, t1]`: the smallest
    /// clearance of the sweep to anything (at most `r`: a collision).
    fn piece(&mut self, world: &World, a: V2, b: V2, t: (f64, f64), heading: f64, r: f64) -> f64 {
        let c = world
            .static_sweep_clearance(a, b)
            .min(world.moving_sweep_clearance(a, b, t.0, t.1));
        self.min_clear = self.min_clear.min(c - r);
        self.length += a.dist(b);
        self.row(t.1, b, heading);
        if c <= r && self.contact.is_none() {
            self.contact = Some(Contact {
                with: Touched::first_in(world, (a, b), t, heading, r),
                standing: false,
            });
        }
        c
    }

    /// The disc of radius `r` stands at `p` during `[t0, t1]` (turning in
    /// place, pausing after a turn, waiting for a sensor): the smallest
    /// clearance to the moving circles meanwhile (at most `r`: one ran into
    /// it). Why: a disc that stands sweeps nothing new of the static world,
    /// but a moving circle can still reach it. The interval is checked in
    /// pieces of at most [`STAND_PIECE_S`], so that a circle turning at a
    /// waypoint is linear over each.
    fn stand(&mut self, world: &World, p: V2, heading: f64, (t0, t1): (f64, f64), r: f64) -> f64 {
        if world.moving.is_empty() || t1 <= t0 {
            return f64::INFINITY;
        }
        let pieces = ((t1 - t0) / STAND_PIECE_S).ceil().max(1.0) as usize;
        let mut c = f64::INFINITY;
        for k in 0..pieces {
            let a = t0 + (t1 - t0) * k as f64 / pieces as f64;
            let b = t0 + (t1 - t0) * (k + 1) as f64 / pieces as f64;
            let piece = world.moving_sweep_clearance(p, p, a, b);
            c = c.min(piece);
            if piece <= r {
                // The run ends here: the trace ends at this piece's end.
                self.contact = Some(Contact {
                    with: Touched::first_in(world, (p, p), (a, b), heading, r),
                    standing: true,
                });
                self.row(b, p, heading);
                break;
            }
        }
        self.min_clear = self.min_clear.min(c - r);
        c
    }

    /// The result of a run that drove this track, without planner
    /// diagnostics (the caller adds its own).
    fn into_result(self, outcome: Outcome, steps: usize) -> RunResult {
        RunResult {
            outcome,
            steps,
            path_length: self.length,
            duration_s: self.trace.last().map_or(0.0, |r| r.t),
            min_clearance: self.min_clear,
            contact: self.contact,
            trace: self.trace,
            seen: Vec::new(),
            remembered: Vec::new(),
            midpoint: None,
            virtual_obstacles: Vec::new(),
            virtual_dropped: 0,
            sensor_faults: 0,
            route: Vec::new(),
        }
    }
}

fn wrap(a: f64) -> f64 {
    let t = std::f64::consts::TAU;
    (a + std::f64::consts::PI).rem_euclid(t) - std::f64::consts::PI
}

/// Run one scenario.
pub fn run(sc: &Scenario, cfg: &SimConfig, reference: Option<f64>) -> RunResult {
    if cfg.planner.uses_map() {
        return run_known_map(sc, cfg);
    }
    let world = sc.world();
    let r = sc.robot_radius;
    let goal = V2::new(sc.goal[0], sc.goal[1]);
    let mut planner = SimPlanner::new(cfg.planner, sc, cfg.adc, cfg.set_back, cfg.sensors.noisy());
    let angles = planner.sensor_angles_rad();
    let mut sensors = VirtualSensors::new(
        cfg.adc,
        cfg.sensors,
        angles,
        planner.sensor_offset_m(),
        cfg.seed,
    );
    let mut rng = Pcg64::seed_from_u64(cfg.seed ^ 0x05ee_d0d0);
    let unit = Normal::new(0.0, 1.0).expect("unit normal");

    let mut p = V2::new(sc.start[0], sc.start[1]);
    let mut heading = sc.start_heading_rad();
    // Odometry: what the planner believes.
    let (mut op, mut oh) = (p, heading);
    let mut t = 0.0;
    let mut track = Track::new(&world, p, heading, r);
    let straight = p.dist(goal);
    // Without a reference (unsolvable, or no grid path) the planner must
    // give up by itself: allow it a longer drive to do so.
    let budget = match reference {
        Some(l) => cfg.max_length_ratio * l + 5.0,
        None => 5.0 * cfg.max_length_ratio * straight + 10.0,
    };
    let mut seen: Vec<V2> = Vec::new();
    let mut faults = 0;
    let mut injected = Faults::new(&cfg.faults, cfg.adc, cfg.seed);
    let slip = injected.slip();
    let mut outcome = Outcome::Timeout;
    let mut steps = 0;
    let debug = std::env::var_os("SIM_DEBUG").is_some();
    let executor = planner_core::rover::drive::ExecutorConfig::default();
    let (settle_after_rad, settle_s) = (
        to_rad(executor.turn_tolerance),
        executor.settle_ticks as f64 / 1000.0,
    );

    'run: while steps < cfg.max_steps {
        steps += 1;
        let raw = injected.sensors(sensors.read(&world, p, heading, t), t);
        let out = planner.step(op, oh, &injected.planner_counts(raw));
        if debug {
            // The beams' true ranges (mm; "-" beyond reach) beside the counts.
            let true_mm = (0..planner_core::SENSOR_COUNT).map(|i| {
                sensors
                    .true_distance(&world, p, heading, i, t)
                    .map_or("-".to_string(), |d| format!("{:.0}", d * 1000.0))
            });
            eprintln!(
                "step {steps:4} t {t:7.2} pos ({:.3},{:.3}) hd {:6.1} raw {:?} true [{}] -> hd {:6.1} step {:.3} {:?}",
                p.x, p.y, heading.to_degrees(), raw, true_mm.collect::<Vec<_>>().join(", "),
                out.heading.to_degrees(), out.step_m, out.status
            );
            if let Some(state) = planner.follow_state() {
                eprintln!("  {state}");
            }
        }
        for q in planner.last_collision_points() {
            if seen.iter().all(|s| s.dist(q) > 0.03) {
                seen.push(q);
            }
        }
        match out.status {
            // Reached is the true pose's verdict, not odometry's (1 cm
            // for the core's whole millimetres).
            Status::Arrived => {
                outcome = if p.dist(goal) <= planner.goal_tolerance_m() + ARRIVAL_SLACK_M {
                    Outcome::Reached
                } else {
                    Outcome::Astray
                };
                break;
            }
            Status::Unreachable => {
                outcome = Outcome::Unreachable;
                break;
            }
            Status::SensorFault => {
                faults += 1;
                // Wait for the next sensor value.
                if track.stand(&world, p, heading, (t, t + 0.04), r) <= r {
                    outcome = Outcome::Collision;
                    break;
                }
                t += 0.04;
                continue;
            }
            Status::Moving => {}
        }
        // Turn in place (a disc turning in place sweeps nothing new).
        let dturn = wrap(out.heading - oh);
        let turned = t + dturn.abs() / cfg.turn_rate;
        if track.stand(&world, p, heading, (t, turned), r) <= r {
            outcome = Outcome::Collision;
            break;
        }
        t = turned;
        let mut true_turn = injected.turn(dturn);
        if let Some((_, hs)) = slip {
            true_turn += unit.sample(&mut rng) * hs * dturn.abs();
        }
        heading = wrap(heading + true_turn);
        oh = out.heading;
        if dturn != 0.0 {
            track.row(t, p, heading);
        }
        // After a turn the executor stands still for one sensor period
        // before it advances, so that its guard first looks at the turned
        // view (`ExecutorConfig::settle_ticks`, 1 ms ticks).
        if out.step_m > 0.0 && dturn.abs() > settle_after_rad {
            if track.stand(&world, p, heading, (t, t + settle_s), r) <= r {
                outcome = Outcome::Collision;
                break;
            }
            t += settle_s;
        }
        // Advance in pieces of at most 1 cm, asking the guard before each
        // piece, the first one included: the firmware's executor
        // (`planner_core::rover::drive::Executor`) asks it on every tick of an
        // advance before it drives, so the turn's new view of the way is
        // checked before the rover moves (the step was planned from the
        // readings before the turn).
        let step = out.step_m;
        let mut done = 0.0;
        while done < step - 1e-9 {
            let raw = injected.sensors(sensors.read(&world, p, heading, t), t);
            if !planner.guard(&raw, step - done) {
                break;
            }
            // Stalled wheels: the encoders see no progress and the
            // executor ends the step.
            if injected.stalled(t) {
                if track.stand(&world, p, heading, (t, t + STALL_S), r) <= r {
                    outcome = Outcome::Collision;
                    break 'run;
                }
                t += STALL_S;
                break;
            }
            let piece = (step - done).min(0.01);
            let mut true_piece = piece;
            if let Some((ds, _)) = slip {
                true_piece *= 1.0 + unit.sample(&mut rng) * ds;
            }
            let q = p + V2::from_angle(heading) * true_piece;
            let t1 = t + piece / cfg.speed;
            let c = track.piece(&world, p, q, (t, t1), heading, r);
            p = q;
            t = t1;
            op = op + V2::from_angle(oh) * injected.odometry(piece);
            done += piece;
            if c <= r {
                outcome = Outcome::Collision;
                break 'run;
            }
            if track.length > budget {
                break 'run;
            }
        }
    }
    let (remembered, midpoint, virtual_obstacles, virtual_dropped) = planner.diagnostics(op);
    RunResult {
        seen,
        remembered,
        midpoint,
        virtual_obstacles,
        virtual_dropped,
        sensor_faults: faults,
        route: planner.route(),
        ..track.into_result(outcome, steps)
    }
}

/// The trace as CSV: `t,x,y,heading` (s, m, m, rad).
pub fn trace_csv(rows: &[TraceRow]) -> String {
    let mut s = String::from("t,x,y,heading\n");
    for r in rows {
        s.push_str(&format!(
            "{:.4},{:.5},{:.5},{:.5}\n",
            r.t, r.x, r.y, r.heading
        ));
    }
    s
}

/// The host's plan buffers: 16,384 waypoints, 4,096 virtual obstacles.
pub type HostPlan = planner_core::maps::liquid::Plan<16_384, 4_096>;

/// Plan a scenario with the liquid-movement planner over its static map
/// (circles, polygons, bounds), offline (`restart`) or online.
pub fn plan_known_map(
    sc: &Scenario,
    restart: bool,
) -> Result<Box<HostPlan>, planner_core::maps::liquid::LiquidError> {
    plan_on(&sc.world(), sc, restart)
}

/// [`plan_known_map`] on the scenario's world, already built.
fn plan_on(
    world: &World,
    sc: &Scenario,
    restart: bool,
) -> Result<Box<HostPlan>, planner_core::maps::liquid::LiquidError> {
    use planner_core::maps::liquid::{plan, Circle, LiquidConfig, Map};
    let mm = |v: f64| (v * 1000.0).round().clamp(i16::MIN as f64, i16::MAX as f64) as i16;
    let circles: Vec<Circle> = world
        .circles
        .iter()
        .map(|&(c, r)| Circle {
            center: to_point(c),
            radius_mm: (r * 1000.0).round().clamp(0.0, u16::MAX as f64) as u16,
        })
        .collect();
    let polys: Vec<Vec<planner_core::Point>> = world
        .polygons
        .iter()
        .map(|p| p.iter().map(|&q| to_point(q)).collect())
        .collect();
    let poly_refs: Vec<&[planner_core::Point]> = polys.iter().map(|p| p.as_slice()).collect();
    let [x0, y0, x1, y1] = world.bounds;
    let map = Map {
        min: planner_core::Point::new(mm(x0), mm(y0)),
        max: planner_core::Point::new(mm(x1), mm(y1)),
        circles: &circles,
        polygons: &poly_refs,
    };
    let mut lc = LiquidConfig::paper(restart);
    lc.robot_radius_mm = (sc.robot_radius * 1000.0).round().clamp(20.0, 1000.0) as u16;
    let start = to_point(V2::new(sc.start[0], sc.start[1]));
    let goal = to_point(V2::new(sc.goal[0], sc.goal[1]));
    plan(&map, &lc, start, goal).map(Box::new)
}

/// A map planner (`liquid`, `liquid-online`): plan over the scenario's
/// static obstacles with planner-core's `liquid` module, then drive the
/// waypoints (turn, then advance in pieces of at most 1 cm, checking the
/// swept disc against the world, moving obstacles included).
fn run_known_map(sc: &Scenario, cfg: &SimConfig) -> RunResult {
    let world = sc.world();
    let start = V2::new(sc.start[0], sc.start[1]);
    let r = sc.robot_radius;
    let mut p = start;
    let mut heading = sc.start_heading_rad();
    let mut t = 0.0;
    let mut track = Track::new(&world, p, heading, r);
    let result = plan_on(&world, sc, cfg.planner == PlannerKind::Liquid);
    if std::env::var_os("SIM_DEBUG").is_some() {
        match &result {
            Ok(p) => eprintln!(
                "liquid: {} waypoints, {} virtual obstacles, {} computation steps",
                p.waypoints.len(),
                p.virtual_obstacles.len(),
                p.computation_steps
            ),
            Err(e) => eprintln!("liquid: {e:?}"),
        }
    }
    let (outcome, steps, vos) = match &result {
        Err(_) => (Outcome::Unreachable, 0, Vec::new()),
        Ok(plan) => {
            let mut outcome = Outcome::Reached;
            'drive: for w in plan.waypoints.iter().skip(1) {
                let q = to_v2(*w);
                let d = p.dist(q);
                if d < 1e-9 {
                    continue;
                }
                let h = (q.y - p.y).atan2(q.x - p.x);
                let turned = t + wrap(h - heading).abs() / cfg.turn_rate;
                if track.stand(&world, p, heading, (t, turned), r) <= r {
                    outcome = Outcome::Collision;
                    break 'drive;
                }
                t = turned;
                heading = h;
                let n = (d / 0.01).ceil() as usize;
                let mut a = p;
                for k in 1..=n {
                    let b = p + (q - p) * (k as f64 / n as f64);
                    let t1 = t + a.dist(b) / cfg.speed;
                    let c = track.piece(&world, a, b, (t, t1), heading, r);
                    t = t1;
                    a = b;
                    if c <= r {
                        outcome = Outcome::Collision;
                        break 'drive;
                    }
                }
                p = q;
            }
            let vos = plan
                .virtual_obstacles
                .iter()
                .map(|&v| (to_v2(v), 0.03))
                .collect();
            (outcome, plan.computation_steps as usize, vos)
        }
    };
    let dropped = result.as_ref().map_or(0, |p| p.virtual_obstacles.len());
    RunResult {
        virtual_obstacles: vos,
        virtual_dropped: dropped,
        ..track.into_result(outcome, steps)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    /// Facing away from the goal, the rover's first command is a half turn
    /// on the spot (1.57 s); a circle at 2 m/s crosses the start during it
    /// and is 16 s down its 33.5 m way before the rover advances.
    const STRUCK_WHILE_TURNING: &str = r#"
format = 1
name = "struck-while-turning"
bounds = [0.0, 0.0, 6.0, 4.0]
start = [1.0, 2.0]
start_heading = 180.0
goal = [5.0, 2.0]

[[moving]]
center = [1.0, 3.5]
radius = 0.2
waypoints = [[1.0, -30.0]]
speed = 2.0
"#;

    #[test]
    fn a_circle_that_runs_into_a_standing_rover_is_a_collision() {
        let sc = Scenario::parse(STRUCK_WHILE_TURNING, Path::new("struck.toml")).unwrap();
        for planner in [PlannerKind::Eapf, PlannerKind::Liquid] {
            let cfg = SimConfig {
                planner,
                ..SimConfig::default()
            };
            let res = run(&sc, &cfg, None);
            assert_eq!(res.outcome, Outcome::Collision, "{planner:?}");
            // From its left, with the rover facing away from the goal.
            let struck = Contact {
                with: Touched::MoverBeside,
                standing: true,
            };
            assert_eq!(res.contact, Some(struck), "{planner:?}");
            assert!(res.min_clearance <= 0.0, "{planner:?}");
            // It was struck on the spot: the rover had not driven.
            assert_eq!(res.path_length, 0.0, "{planner:?}");
        }
    }

    #[test]
    fn the_picture_of_a_collision_says_what_reached_the_rover_and_shows_where() {
        let sc = Scenario::parse(STRUCK_WHILE_TURNING, Path::new("struck.toml")).unwrap();
        let res = run(&sc, &SimConfig::default(), None);
        let pic = crate::svg::render(&sc, &res, "eapf", None, None);
        assert!(pic.contains("collision (mover-beside while standing)"));
        // The circle where it was at the end: on the rover, which stood at
        // the start, drawn at its 0.2 m radius (SVG y grows downwards).
        let t_end = res.trace.last().unwrap().t;
        let end = sc.world().moving[0].center_at(t_end);
        assert!(end.dist(V2::new(1.0, 2.0)) <= 0.3, "{end:?}");
        let scale = 900.0 / 6.0;
        let (cx, cy) = ((end.x * scale), ((4.0 - end.y) * scale + 86.0));
        let ring = format!(
            r##"<circle cx="{cx:.1}" cy="{cy:.1}" r="{:.1}" fill="#8c959f""##,
            0.2 * scale
        );
        assert!(pic.contains(&ring), "{ring}");
    }

    #[test]
    fn a_stand_checks_every_piece_of_a_circles_back_and_forth() {
        // A circle of 0.1 m comes from 1 m above the point to 0.2 m above
        // it at 1 m/s and goes back: nearest at 0.8 s, 0.1 m off the
        // rim of a 0.1 m disc; at 0 s and 1.6 s it is where it began.
        let text = STRUCK_WHILE_TURNING.replace(
            "center = [1.0, 3.5]\nradius = 0.2\nwaypoints = [[1.0, -30.0]]\nspeed = 2.0",
            "center = [1.0, 3.0]\nradius = 0.1\nwaypoints = [[1.0, 2.2]]\nspeed = 1.0",
        );
        let sc = Scenario::parse(&text, Path::new("near.toml")).unwrap();
        let world = sc.world();
        let p = V2::new(1.0, 2.0);
        let mut track = Track::new(&world, p, 0.0, 0.1);
        // As one linear motion its two ends would be 0.9 m clear.
        assert!((world.moving_sweep_clearance(p, p, 0.0, 1.6) - 0.9).abs() < 1e-9);
        let c = track.stand(&world, p, 0.0, (0.0, 1.6), 0.1);
        assert!((c - 0.1).abs() < 0.02, "{c}");
        assert!((track.min_clear - 0.0).abs() < 0.02, "{}", track.min_clear);
        // Before it comes near, a stand sees it where it is then.
        let early = track.stand(&world, p, 0.0, (0.0, 0.4), 0.1);
        assert!((early - 0.5).abs() < 1e-9, "{early}");
        // A stand of no time checks nothing.
        assert_eq!(track.stand(&world, p, 0.0, (2.0, 2.0), 0.1), f64::INFINITY);
    }
}
