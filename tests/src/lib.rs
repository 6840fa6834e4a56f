//! Shared pieces of the cross-target tests: recorded input traces (pose and
//! raw counts per planner step, and the guard's samples of each advance,
//! from sim-host's worlds and sensors) and the host core's answers to them,
//! plus the emulator harnesses of the two firmwares ([`avr`], [`stm32`]).
//!
//! Crates: `avr-tester` (simavr inside) drives the ATmega328P firmware: ADC
//! pin voltages, pin levels, UART, exact cycle counts.

pub mod avr;
pub mod flash;
pub mod profile;
pub mod stack_bound;
pub mod stm32;
pub mod stm32_profile;

use planner_core::{
    AdcProfile, ConfigBuilder, Guard, Mode, Output, Planner, Point, Pose, RawCounts,
};
use sim_host::geom::V2;
use sim_host::scenario::Scenario;
use sim_host::sensor::{SensorMode, VirtualSensors};
use sim_host::units::{to_angle, to_point, to_rad};
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

/// One look of the guard during an advance: the raw counts and the part of
/// the step still to go.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GuardSample {
    /// Raw ADC counts the guard read.
    pub raw: RawCounts,
    /// The step still to go, mm.
    pub remaining_mm: u16,
}

/// At most this many guard samples per advance in a trace (a replay
/// answer gives their verdicts as the bits of one byte).
pub const MAX_GUARD_SAMPLES: usize = 8;

/// Inputs of one planner step, and the guard's looks during the advance
/// before it: what the planner learns from them (its flank points) is part
/// of what the step answers.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Frame {
    /// The guard's samples of the last advance, oldest first (at most
    /// [`MAX_GUARD_SAMPLES`]).
    pub guards: Vec<GuardSample>,
    /// Pose the planner was given.
    pub pose: Pose,
    /// Raw ADC counts it read.
    pub raw: RawCounts,
}

/// What the core answered to a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Answer {
    /// The guard's verdicts: bit `i` set if sample `i` said stop.
    pub guard_stops: u8,
    /// The step's output.
    pub output: Output,
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
    /// Host core answers, one per frame.
    pub outputs: Vec<Answer>,
    /// The host planner's mode after each step: what decided it.
    pub modes: Vec<Mode>,
}

/// The guard's samples `guards` (a frame's, oldest first) through
/// `planner`: the verdict bits of [`Answer::guard_stops`].
pub fn run_guards(planner: &mut Planner, guards: &[GuardSample]) -> u8 {
    let mut stops = 0;
    for (i, g) in guards.iter().enumerate() {
        if planner.guard_raw(&g.raw, g.remaining_mm) == Guard::Stop {
            stops |= 1 << i;
        }
    }
    stops
}

/// Record up to `steps` planner steps on a scenario with realistic sensors
/// for `adc`. The rover follows each command exactly (no physics): the
/// point is to exercise the planner on realistic inputs, obstacles in view,
/// memory filling up, escape engaged, flank points kept. During each
/// advance the guard looks at up to [`MAX_GUARD_SAMPLES`] points of it,
/// one sensor period (40 ms) apart so that each look reads where the rover
/// is; its verdicts are recorded, and the recorded rover goes the whole
/// step either way, as it did before the guard was in the traces. (Ending
/// the advance where the guard says stop, as the executor does, moves the
/// dead end's trace to steps that cost the STM32 up to 3,149 instructions,
/// over issue 6's 3,000: the commit history.)
pub fn record(sc: &Scenario, adc: AdcProfile, steps: usize, seed: u64) -> Trace {
    record_with(sc, adc, steps, seed, false)
}

/// [`record`] with the sensors on the rim, or `set_back` behind it
/// (`ConfigBuilder::sensors_set_back`, the firmwares' `set-back` feature).
pub fn record_with(
    sc: &Scenario,
    adc: AdcProfile,
    steps: usize,
    seed: u64,
    set_back: bool,
) -> Trace {
    let world = sc.world();
    let cfg = ConfigBuilder::new(adc)
        .sensors_set_back(set_back)
        .build()
        .expect("default config");
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
        modes: Vec::new(),
    };
    let (mut guards, mut guard_stops) = (Vec::new(), 0);
    // Sensor time, s: 50 ms for a step, 40 for each look of the guard.
    let mut t = 0.0;
    for _ in 0..steps {
        t += 0.05;
        let raw = sensors.read(&world, p, h, t);
        let pose = Pose {
            position: to_point(p),
            heading: to_angle(h),
        };
        let output = planner.step_raw(pose, &raw);
        trace.frames.push(Frame {
            guards: std::mem::take(&mut guards),
            pose,
            raw,
        });
        trace.modes.push(planner.mode());
        trace.outputs.push(Answer {
            guard_stops,
            output,
        });
        if output.status != planner_core::Status::Moving {
            break;
        }
        h = to_rad(output.command.heading);
        // The guard looks at 0, 1/8, 2/8, … of the step.
        let step = output.command.step_mm;
        let piece = step.div_ceil(MAX_GUARD_SAMPLES as u16);
        let mut done = 0;
        while done < step && guards.len() < MAX_GUARD_SAMPLES {
            t += 0.04;
            let at = p + V2::from_angle(h) * (done as f64 / 1000.0);
            let raw = sensors.read(&world, at, h, t);
            guards.push(GuardSample {
                raw,
                remaining_mm: step - done,
            });
            done = (done + piece).min(step);
        }
        // The rover goes the whole step whatever the guard says, so it may
        // look at them all once the readings are taken.
        guard_stops = run_guards(&mut planner, &guards);
        p = p + V2::from_angle(h) * (step as f64 / 1000.0);
    }
    trace
}

impl Frame {
    /// The frame's guard samples (each the step still to go, then the five
    /// raw counts), then the step's x, y, heading and raw counts, all
    /// little-endian: the body both firmwares' replays read after the
    /// number of samples (`firmware-avr/src/replay.rs`,
    /// `firmware-stm32/src/emulated.rs`).
    pub fn encode_le(&self, out: &mut Vec<u8>) {
        for g in &self.guards {
            out.extend(g.remaining_mm.to_le_bytes());
            out.extend(g.raw.iter().flat_map(|r| r.to_le_bytes()));
        }
        out.extend(self.pose.position.x.to_le_bytes());
        out.extend(self.pose.position.y.to_le_bytes());
        out.extend(self.pose.heading.0.to_le_bytes());
        out.extend(self.raw.iter().flat_map(|r| r.to_le_bytes()));
    }
}

/// The traces the firmware checks replay: a trap, a paper world, a dense
/// world, each long enough to fill the collision memory, and a dead end
/// where the escape drops virtual obstacles, whose forces make the most
/// expensive steps, and then gives up to the follower: every mode of the
/// planner is replayed (a test holds it, `replay.rs`).
pub fn standard_traces(adc: AdcProfile) -> Vec<Trace> {
    standard_traces_with(adc, false)
}

/// [`standard_traces`] with the sensors on the rim, or `set_back` behind it.
pub fn standard_traces_with(adc: AdcProfile, set_back: bool) -> Vec<Trace> {
    [
        ("traps/u-trap.toml", 120),
        ("paper/env1-ex1.toml", 120),
        ("traps/comb.toml", 120),
        ("paper/env2-ex1.toml", 120),
        // The escape gives up after about 210 steps, and the follower
        // leads the rover out.
        ("traps/dead-end.toml", 330),
    ]
    .iter()
    .enumerate()
    .map(|(i, &(rel, steps))| record_with(&scenario(rel), adc, steps, 7 + i as u64, set_back))
    .collect()
}

/// The replayed steps of `traces` by mode (field, escape, follow: the
/// host planner's [`Mode`] after each), and the worst of `counts` (one per
/// step, in replay order) in each: the reports' mode lines,
/// `<what> step modes: field=<n> escape=<n> follow=<n>` and
/// `<what> step worst by mode: field=<c> escape=<c> follow=<c>`.
pub fn mode_lines(what: &str, traces: &[Trace], counts: &[u32]) -> [String; 2] {
    let modes = [Mode::Field, Mode::Escape, Mode::Follow];
    let (mut steps, mut worst) = ([0usize; 3], [0u32; 3]);
    let all = traces.iter().flat_map(|t| &t.modes);
    for (m, &c) in all.zip(counts) {
        let i = modes.iter().position(|x| x == m).unwrap_or(0);
        steps[i] += 1;
        worst[i] = worst[i].max(c);
    }
    [
        format!(
            "{what} step modes: field={} escape={} follow={}",
            steps[0], steps[1], steps[2]
        ),
        format!(
            "{what} step worst by mode: field={} escape={} follow={}",
            worst[0], worst[1], worst[2]
        ),
    ]
}

/// For each frame of `traces`, in replay order: whether the rover stands
/// somewhere new (the first frame of a trace, or after an advance), where
/// the step works out again what it keeps for a rover turning on the spot
/// (the goal's distance and bearing, the virtual obstacles' force).
pub fn at_new_position(traces: &[Trace]) -> Vec<bool> {
    traces
        .iter()
        .flat_map(|t| {
            t.frames.iter().scan(None, |last, f| {
                let new = *last != Some(f.pose.position);
                *last = Some(f.pose.position);
                Some(new)
            })
        })
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

/// `cargo ARGS…` in the workspace `dir` (see [`clean_cargo`]), which must
/// succeed: its standard output.
pub fn cargo_stdout(dir: &Path, args: &[&str]) -> String {
    let out = clean_cargo(dir)
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("cargo {args:?}: {e}"));
    assert!(
        out.status.success(),
        "cargo {args:?} in {}: {}",
        dir.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Section sizes (text, data, bss) as `cargo size --release ARGS…` prints
/// them in the firmware workspace `dir` (cargo-binutils; the firmware
/// READMEs' command).
pub fn cargo_size(dir: &Path, args: &[&str]) -> (u32, u32, u32) {
    let mut all = vec!["size", "--release", "--quiet"];
    all.extend_from_slice(args);
    let text = cargo_stdout(dir, &all);
    parse_size(&text).unwrap_or_else(|| panic!("cargo size output: {text}"))
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

/// Print how many of `counts` fall at or below each of `bounds` (in
/// order, the last `u32::MAX`) and above the one before: the profilers'
/// split of the steps against a budget and an aim.
pub fn print_by_bounds(counts: &[u32], bounds: &[u32]) {
    let (mut prev, mut below) = (0, 0);
    for &hi in bounds {
        let n = counts.iter().filter(|&&c| c <= hi).count() - below;
        below += n;
        let range = match (prev, hi) {
            (0, _) => format!("up to {hi}"),
            (_, u32::MAX) => format!("above {prev}"),
            _ => format!("{} to {hi}", prev + 1),
        };
        println!("{n:>7} steps  {range}");
        prev = hi;
    }
}

/// Print the mean and worst of `counts` for the steps on the spot of the
/// step before and for those somewhere new (`new`, from
/// [`at_new_position`]), and how many of each are over `budget`: a turn
/// on the spot keeps the answers that depend on the position only.
pub fn print_by_position(counts: &[u32], new: &[bool], budget: u32) {
    for (label, want) in [
        ("on the spot of the step before", false),
        ("somewhere new", true),
    ] {
        let c: Vec<u32> = (counts.iter().zip(new))
            .filter(|(_, &n)| n == want)
            .map(|(&c, _)| c)
            .collect();
        let (mean, worst) = mean_worst(&c);
        let over = c.iter().filter(|&&c| c > budget).count();
        println!(
            "{:>7} steps  {label}: mean {mean}, worst {worst}, {over} over {budget}",
            c.len()
        );
    }
}

/// Print the first `rows` of a profiler's table (`name`, count over all
/// steps) as a count per step (`per`) and a share of `total`.
pub fn print_table(title: &str, table: &[(String, u64)], total: u64, per: u64, rows: usize) {
    println!("\n{title}:");
    for (name, c) in table.iter().take(rows) {
        println!(
            "{:>7}/step {:>5.1}%  {name}",
            c / per.max(1),
            *c as f64 * 100.0 / total.max(1) as f64
        );
    }
}

/// A profiler's table (name, count) with the largest counts first, equal
/// counts by name.
pub fn sorted(table: std::collections::HashMap<String, u64>) -> Vec<(String, u64)> {
    let mut v: Vec<_> = table.into_iter().collect();
    v.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    v
}
