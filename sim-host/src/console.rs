//! The host's console for a rover running the firmware (a real one over a
//! serial port, or the emulated one): it sets the pose and the goal, reads
//! the telemetry lines (`T …`, `planner_core::rover::protocol`), logs them
//! as CSV and draws the run as the simulator draws its own.
//!
//! [`drive`] drives the rover over any [`Link`] that carries the lines;
//! the `drive` command runs it over a serial port.

use crate::geom::V2;
use crate::scenario::Scenario;
use crate::sim::{Outcome, RunResult, TraceRow};
use crate::units::to_rad;
pub use planner_core::rover::app::Look;
use planner_core::rover::calibration::{Correction, Source};
use planner_core::{Angle, Status};
use std::sync::atomic::{AtomicBool, Ordering};

/// A line link to the rover.
pub trait Link {
    /// Send one line (the `\n` is added).
    fn send(&mut self, line: &str) -> Result<(), String>;
    /// The next line received (without its end), or `None` if none came
    /// within the link's wait.
    fn read_line(&mut self) -> Result<Option<String>, String>;
}

/// One telemetry line.
#[derive(Clone, Debug, PartialEq)]
pub struct Record {
    /// The rover's clock, ms.
    pub ms: u32,
    /// Odometry position, mm.
    pub x_mm: i16,
    /// Odometry position, mm.
    pub y_mm: i16,
    /// Heading, binary angle units (65,536 = 360°).
    pub heading: u16,
    /// What the planner answered.
    pub status: Status,
    /// Commanded heading, binary angle units.
    pub cmd_heading: u16,
    /// Commanded step, mm.
    pub step_mm: u16,
    /// The step's cycles on the rover.
    pub cycles: u32,
    /// Which calibration the counts went through.
    pub cal: Source,
    /// The counts the planner read for the step.
    pub counts: [u16; 5],
    /// The guard's looks during the advance before the step that changed
    /// what the planner keeps (`g` lines), oldest first.
    pub looks: Vec<Look>,
}

/// The guard look a `g <remaining_mm> <c0> … <c4>` line logs (the
/// application's [`Look`]); `None` for any other line.
pub fn parse_look(line: &str) -> Option<Look> {
    let f: Vec<&str> = line.split_whitespace().collect();
    let ["g", remaining, counts @ ..] = f.as_slice() else {
        return None;
    };
    Some(Look {
        remaining_mm: remaining.parse().ok()?,
        counts: five(counts)?,
    })
}

/// Five counts.
fn five(fields: &[&str]) -> Option<[u16; 5]> {
    let v: Vec<u16> = fields
        .iter()
        .map(|c| c.parse().ok())
        .collect::<Option<_>>()?;
    v.try_into().ok()
}

/// The `K` line that gives sensor `sensor` the correction `k` (`K sensor
/// gain_q8 offset`, `planner_core::rover::protocol`), without its `\n`.
pub fn calibration_line(sensor: u8, k: Correction) -> String {
    format!("K {sensor} {} {}", k.gain_q8, k.offset)
}

/// The CSV log's header.
pub const CSV_HEADER: &str =
    "ms,x_mm,y_mm,heading_deg,status,cmd_heading_deg,step_mm,cycles,calibration,c0,c1,c2,c3,c4";

fn degrees(bam: u16) -> f64 {
    to_rad(Angle(bam)).to_degrees()
}

impl Record {
    /// The record of a telemetry line; `None` for any other line.
    pub fn parse(line: &str) -> Option<Record> {
        let f: Vec<&str> = line.split_whitespace().collect();
        let [t, ms, x, y, h, s, ch, st, cy, cal, counts @ ..] = f.as_slice() else {
            return None;
        };
        // A field of one letter.
        let one = |s: &str| match s.as_bytes() {
            &[b] => Some(b),
            _ => None,
        };
        (*t == "T").then_some(())?;
        Some(Record {
            ms: ms.parse().ok()?,
            x_mm: x.parse().ok()?,
            y_mm: y.parse().ok()?,
            heading: h.parse().ok()?,
            status: Status::from_letter(one(s)?)?,
            cmd_heading: ch.parse().ok()?,
            step_mm: st.parse().ok()?,
            cycles: cy.parse().ok()?,
            cal: Source::from_letter(one(cal)?)?,
            counts: five(counts)?,
            looks: Vec::new(),
        })
    }

    /// Its row of the CSV log ([`CSV_HEADER`]).
    pub fn csv_row(&self) -> String {
        let c = self.counts;
        format!(
            "{},{},{},{:.1},{},{:.1},{},{},{},{},{},{},{},{}",
            self.ms,
            self.x_mm,
            self.y_mm,
            degrees(self.heading),
            char::from(self.status.letter()),
            degrees(self.cmd_heading),
            self.step_mm,
            self.cycles,
            char::from(self.cal.letter()),
            c[0],
            c[1],
            c[2],
            c[3],
            c[4]
        )
    }

    /// A one-line status for a terminal.
    pub fn status_line(&self, goal: (i16, i16)) -> String {
        let (dx, dy) = (
            f64::from(goal.0) - f64::from(self.x_mm),
            f64::from(goal.1) - f64::from(self.y_mm),
        );
        let what = match self.status {
            Status::Moving => "moving",
            Status::Arrived => "arrived",
            Status::Unreachable => "unreachable",
            Status::SensorFault => "sensor fault",
        };
        format!(
            "t {:7.2} s  at ({:6}, {:6}) mm  {:6.1}°  {:5.2} m to go  step {:4} mm  {what}",
            f64::from(self.ms) / 1e3,
            self.x_mm,
            self.y_mm,
            degrees(self.heading),
            dx.hypot(dy) / 1e3,
            self.step_mm,
        )
    }
}

/// How a drive ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum End {
    /// The rover says it arrived.
    Arrived,
    /// The rover says the goal is unreachable.
    Unreachable,
    /// The rover stopped on a sensor fault.
    SensorFault,
    /// Stopped from the host (Ctrl-C): `S` was sent.
    Stopped,
    /// No telemetry for longer than the link waits, or no answer.
    Silent,
}

/// What to ask the rover.
#[derive(Clone, Copy, Debug)]
pub struct Plan {
    /// The pose to set first (mm, mm, degrees), if any.
    pub pose: Option<(i16, i16, i16)>,
    /// The goal, mm.
    pub goal: (i16, i16),
}

/// Send `line` and wait for its `OK` (telemetry and other lines between are
/// passed to `other`).
fn request(link: &mut impl Link, line: &str, other: &mut impl FnMut(&str)) -> Result<(), String> {
    link.send(line)?;
    for _ in 0..1_000 {
        match link.read_line()? {
            Some(l) if l == "OK" => return Ok(()),
            Some(l) if l == "ERR" => return Err(format!("the rover refused `{line}`")),
            Some(l) => other(&l),
            None => break,
        }
    }
    Err(format!("no answer to `{line}`"))
}

/// Set the pose, send the goal and follow the telemetry until the rover
/// stops, `stop` is set (then `S` is sent) or the link goes silent. Each
/// record goes to `on_record` as it comes.
pub fn drive(
    link: &mut impl Link,
    plan: Plan,
    stop: &AtomicBool,
    mut on_record: impl FnMut(&Record),
) -> Result<(Vec<Record>, End), String> {
    let mut ignore = |_: &str| {};
    if let Some((x, y, deg)) = plan.pose {
        request(link, &format!("P {x} {y} {deg}"), &mut ignore)?;
    }
    request(
        link,
        &format!("G {} {}", plan.goal.0, plan.goal.1),
        &mut ignore,
    )?;
    let mut records = Vec::new();
    let mut looks = Vec::new();
    loop {
        if stop.load(Ordering::Relaxed) {
            link.send("S")?;
            return Ok((records, End::Stopped));
        }
        let Some(line) = link.read_line()? else {
            return Ok((records, End::Silent));
        };
        if let Some(look) = parse_look(&line) {
            looks.push(look);
            continue;
        }
        let Some(mut r) = Record::parse(&line) else {
            continue;
        };
        r.looks = std::mem::take(&mut looks);
        on_record(&r);
        let status = r.status;
        records.push(r);
        let end = match status {
            Status::Arrived => End::Arrived,
            Status::Unreachable => End::Unreachable,
            Status::SensorFault => End::SensorFault,
            Status::Moving => continue,
        };
        return Ok((records, end));
    }
}

/// A logged run replayed through the host's core.
#[derive(Clone, Debug, Default)]
pub struct Replay {
    /// The steps whose heading, step or status differ from the rover's
    /// (none: the core decides the same bit for bit everywhere).
    pub differ: Vec<usize>,
    /// What the planner saw and kept, as the simulator's pictures show it:
    /// the collision points of every step, then at the end the remembered
    /// points, their midpoint, the virtual obstacles and how many were
    /// dropped.
    pub seen: Vec<V2>,
    /// See [`Replay::seen`].
    pub diagnostics: crate::planners::Diagnostics,
}

/// The logged run replayed through the host's core, configured as the
/// rover's firmware (`cfg`) and driving to `goal`: each step from its
/// logged pose and counts, after the logged guard looks before it.
pub fn replay(cfg: planner_core::Config, goal: (i16, i16), records: &[Record]) -> Replay {
    use crate::units::to_v2;
    use planner_core::{Planner, Point, Pose};
    let mut planner = Planner::new(cfg, Point::new(goal.0, goal.1));
    let mut out = Replay::default();
    let mut at = V2::new(0.0, 0.0);
    for (i, r) in records.iter().enumerate() {
        for look in &r.looks {
            planner.guard_raw(&look.counts, look.remaining_mm);
        }
        let pose = Pose {
            position: Point::new(r.x_mm, r.y_mm),
            heading: Angle(r.heading),
        };
        at = to_v2(pose.position);
        let step = planner.step_raw(pose, &r.counts);
        let same = step.command.heading.0 == r.cmd_heading
            && step.command.step_mm == r.step_mm
            && step.status == r.status;
        if !same {
            out.differ.push(i);
        }
        for &q in planner.last_collision_points() {
            let q = to_v2(q);
            if out.seen.iter().all(|s| s.dist(q) > 0.03) {
                out.seen.push(q);
            }
        }
    }
    out.diagnostics = crate::planners::eapf_diagnostics(&planner, at);
    out
}

/// The run as the simulator's pictures take it, from the telemetry: the
/// odometry's path (not the true one: the rover knows no other), how it
/// ended, and what the planner saw and kept if the run was `replayed`.
pub fn run_result(records: &[Record], end: End, replayed: Option<&Replay>) -> RunResult {
    let trace: Vec<TraceRow> = records
        .iter()
        .map(|r| TraceRow {
            t: f64::from(r.ms) / 1e3,
            x: f64::from(r.x_mm) / 1e3,
            y: f64::from(r.y_mm) / 1e3,
            heading: to_rad(Angle(r.heading)),
        })
        .collect();
    let length = trace
        .windows(2)
        .map(|w| V2::new(w[0].x, w[0].y).dist(V2::new(w[1].x, w[1].y)))
        .sum();
    let outcome = match end {
        End::Arrived => Outcome::Reached,
        End::Unreachable => Outcome::Unreachable,
        _ => Outcome::Timeout,
    };
    let r = replayed.cloned().unwrap_or_default();
    let (remembered, midpoint, virtual_obstacles, virtual_dropped) = r.diagnostics;
    RunResult {
        outcome,
        steps: records.len(),
        path_length: length,
        duration_s: trace.last().map_or(0.0, |r| r.t),
        // Unknown: the rover sees no clearance (the picture leaves it out).
        min_clearance: f64::INFINITY,
        contact: None,
        trace,
        seen: r.seen,
        remembered,
        midpoint,
        virtual_obstacles,
        virtual_dropped,
        sensor_faults: usize::from(end == End::SensorFault),
        route: Vec::new(),
    }
}

/// The picture of a logged run over `world`, or over an empty floor
/// around the path and the goal; with what the planner saw and kept if
/// the run was `replayed`.
pub fn picture(
    records: &[Record],
    end: End,
    goal: (i16, i16),
    world: Option<&Scenario>,
    replayed: Option<&Replay>,
) -> String {
    let run = run_result(records, end, replayed);
    let goal_m = [f64::from(goal.0) / 1e3, f64::from(goal.1) / 1e3];
    let start = run.trace.first().map_or([0.0, 0.0], |r| [r.x, r.y]);
    let floor;
    let sc = match world {
        Some(sc) => sc,
        None => {
            let xs = run.trace.iter().map(|r| r.x).chain([goal_m[0]]);
            let ys = run.trace.iter().map(|r| r.y).chain([goal_m[1]]);
            let (x0, x1) = xs.fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(v), b.max(v)));
            let (y0, y1) = ys.fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(v), b.max(v)));
            floor = Scenario {
                format: 1,
                name: "the rover's run".into(),
                description: None,
                bounds: [x0 - 0.5, y0 - 0.5, x1 + 0.5, y1 + 0.5],
                start,
                start_heading: None,
                goal: goal_m,
                robot_radius: 0.1,
                solvable: true,
                circle: Vec::new(),
                polygon: Vec::new(),
                moving: Vec::new(),
            };
            &floor
        }
    };
    crate::svg::render(sc, &run, "the rover's telemetry", None, None)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn telemetry_lines_parse_and_others_do_not() {
        let r = Record::parse("T 1234 -50 300 16384 M 32768 120 15012 C 57 60 204 58 59").unwrap();
        assert_eq!(
            (r.ms, r.x_mm, r.y_mm, r.heading, r.status, r.step_mm, r.cycles, r.cal),
            (
                1234,
                -50,
                300,
                16_384,
                Status::Moving,
                120,
                15_012,
                Source::Stored
            )
        );
        assert_eq!(r.counts, [57, 60, 204, 58, 59]);
        assert_eq!(
            r.csv_row(),
            "1234,-50,300,90.0,M,-180.0,120,15012,C,57,60,204,58,59"
        );
        assert_eq!(
            parse_look("g 88 1 2 3 4 5"),
            Some(Look {
                remaining_mm: 88,
                counts: [1, 2, 3, 4, 5]
            })
        );
        for bad in [
            "OK",
            "T 1 2 3 4 M 5 6 7 C 1 2 3 4",
            "T 1 2 3 4 X 5 6 7 C 1 2 3 4 5",
            "T 1 2 3 4 M 5 6 7 CC 1 2 3 4 5",
            "T 1 2 3 99999 M 5 6 7 C 1 2 3 4 5",
            "T 1 2 3 4 M 5 6 7 C 1 2 3 4 5 6",
            "D 1 2 3 4 5 - - - - -",
        ] {
            assert_eq!(Record::parse(bad), None, "{bad}");
        }
        for bad in ["g 1 2 3 4 5", "g 1 2 3 4 5 6 7", "G 1 2 3 4 5 6"] {
            assert_eq!(parse_look(bad), None, "{bad}");
        }
    }
}
