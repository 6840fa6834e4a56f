//! Shared pieces of the cross-target tests: recorded input traces (pose and
//! raw counts per planner step, from sim-host's worlds and sensors) and the
//! host core's answers to them, plus the emulator harnesses of the two
//! firmwares ([`avr`], [`stm32`]).
//!
//! Crates: `avr-tester` (simavr inside) drives the ATmega328P firmware: ADC
//! pin voltages, pin levels, UART, exact cycle counts.

pub mod avr;
pub mod profile;
pub mod stm32;

use planner_core::{AdcProfile, ConfigBuilder, Output, Planner, Point, Pose, RawCounts};
use sim_host::geom::V2;
use sim_host::planners::{to_angle, to_point, to_rad};
use sim_host::scenario::Scenario;
use sim_host::sensor::{SensorMode, VirtualSensors};
use sim_host::world::World;
use std::path::{Path, PathBuf};

/// The repository root.
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// A command for `cargo` in `dir` that uses that folder's own toolchain
/// file and config, not the ones of the cargo that runs these tests.
pub fn clean_cargo(dir: &Path) -> std::process::Command {
    let mut c = std::process::Command::new("cargo");
    c.current_dir(dir);
    for (k, _) in std::env::vars_os() {
        let k = k.to_string_lossy().to_string();
        let inherited = k == "CARGO"
            || (k.starts_with("CARGO_") && k != "CARGO_HOME")
            || k.starts_with("RUSTC")
            || k.starts_with("RUSTDOC")
            || k == "RUSTUP_TOOLCHAIN"
            || k == "RUSTFLAGS";
        if inherited {
            c.env_remove(&k);
        }
    }
    c
}

/// A built-in scenario by its path under `sim-host/scenarios`.
pub fn scenario(rel: &str) -> Scenario {
    let path = repo_root().join("sim-host/scenarios").join(rel);
    Scenario::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Inputs of one planner step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Frame {
    /// Pose the planner was given.
    pub pose: Pose,
    /// Raw ADC counts it read.
    pub raw: RawCounts,
}

/// A recorded run: the goal, the inputs of each step and what the host
/// core answered.
#[derive(Clone, Debug)]
pub struct Trace {
    /// Scenario name.
    pub name: String,
    /// Goal, mm.
    pub goal: Point,
    /// Inputs.
    pub frames: Vec<Frame>,
    /// Host core outputs, one per frame.
    pub outputs: Vec<Output>,
}

/// Record up to `steps` planner steps on a scenario with realistic sensors
/// for `adc`. The rover follows each command exactly (no physics): the
/// point is to exercise the planner on realistic inputs, obstacles in view,
/// memory filling up, escape engaged.
pub fn record(sc: &Scenario, adc: AdcProfile, steps: usize, seed: u64) -> Trace {
    let world = World::from_scenario(sc);
    let cfg = ConfigBuilder::new(adc).build().expect("default config");
    let goal = to_point(V2::new(sc.goal[0], sc.goal[1]));
    let angles = cfg.sensor_angles().map(to_rad);
    let offset = cfg.sensor_offset_mm() as f64 / 1000.0;
    let mut sensors = VirtualSensors::new(adc, SensorMode::REALISTIC, angles, offset, seed);
    let mut planner = Planner::new(cfg, goal);
    let (mut p, mut h) = (V2::new(sc.start[0], sc.start[1]), sc.start_heading_rad());
    let mut trace = Trace {
        name: sc.name.clone(),
        goal,
        frames: Vec::new(),
        outputs: Vec::new(),
    };
    for k in 0..steps {
        let raw = sensors.read(&world, p, h, k as f64 * 0.05);
        let pose = Pose {
            position: to_point(p),
            heading: to_angle(h),
        };
        let out = planner.step_raw(pose, &raw);
        trace.frames.push(Frame { pose, raw });
        trace.outputs.push(out);
        if out.status != planner_core::Status::Moving {
            break;
        }
        h = to_rad(out.command.heading);
        p = p + V2::from_angle(h) * (out.command.step_mm as f64 / 1000.0);
    }
    trace
}

/// The traces the firmware checks replay: a trap, a paper world, a dense
/// world, each long enough to fill the collision memory, and a dead end
/// where the escape drops virtual obstacles, whose forces
/// make the most expensive steps.
pub fn standard_traces(adc: AdcProfile) -> Vec<Trace> {
    [
        ("traps/u-trap.toml", 120),
        ("paper/env1-ex1.toml", 120),
        ("traps/comb.toml", 120),
        ("paper/env2-ex1.toml", 120),
        ("traps/dead-end.toml", 200),
    ]
    .iter()
    .enumerate()
    .map(|(i, &(rel, steps))| record(&scenario(rel), adc, steps, 7 + i as u64))
    .collect()
}

/// Mean and worst of a list of counts.
pub fn mean_worst(v: &[u32]) -> (u32, u32) {
    let worst = v.iter().copied().max().unwrap_or(0);
    let mean = if v.is_empty() {
        0
    } else {
        (v.iter().map(|&c| c as u64).sum::<u64>() / v.len() as u64) as u32
    };
    (mean, worst)
}

/// `(text, data, bss)` from the Berkeley-format output of `size` or
/// `llvm-size` (second line, first three columns).
pub fn parse_size(output: &str) -> Option<(u32, u32, u32)> {
    let nums: Vec<u32> = output
        .lines()
        .nth(1)?
        .split_whitespace()
        .take(3)
        .filter_map(|f| f.parse().ok())
        .collect();
    match nums[..] {
        [t, d, b] => Some((t, d, b)),
        _ => None,
    }
}
