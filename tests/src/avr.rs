//! The ATmega328P firmware in simavr (through avr-tester): build it, replay
//! recorded traces through its planner, read its size.

use crate::{clean_cargo, repo_root, Answer, Frame, Trace};
use avr_tester::AvrTester;
use planner_core::{Angle, Command, Output, Point, Status};
use std::path::PathBuf;
use std::process::Command as Cmd;
use std::sync::Mutex;

/// CPU clock of the board, Hz.
pub const F_CPU: u32 = 16_000_000;

static BUILT: Mutex<Vec<(String, PathBuf)>> = Mutex::new(Vec::new());

/// Build one binary of firmware-avr (release) with `features` once per
/// process. The builds share one target folder (the host tools that
/// avr-device's build script compiles are hundreds of megabytes, built
/// once), and cargo copies each set of features' binaries into a folder of
/// its own (`--artifact-dir`), so that the builds of one binary do not
/// overwrite each other's ELF.
fn build(bin: &'static str, features: &[&str]) -> PathBuf {
    let key = format!("{bin} {}", features.join(","));
    let mut built = BUILT.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((_, p)) = built.iter().find(|(k, _)| *k == key) {
        return p.clone();
    }
    let dir = repo_root().join("firmware-avr");
    let artifacts = match features {
        [] => "target/elf/default".to_string(),
        f => format!("target/elf/{}", f.join("+")),
    };
    let mut cmd = clean_cargo(&dir);
    cmd.args(["build", "--release", "--quiet", "--bin", bin]);
    cmd.args(["-Z", "unstable-options", "--artifact-dir", &artifacts]);
    if !features.is_empty() {
        cmd.args(["--features", &features.join(",")]);
    }
    let status = cmd.status().expect("run cargo for firmware-avr");
    assert!(status.success(), "firmware-avr build of {bin} failed");
    let elf = dir.join(format!("{artifacts}/{bin}.elf"));
    built.push((key, elf.clone()));
    elf
}

/// The firmware's production image (release build); the ELF path.
pub fn firmware_elf() -> PathBuf {
    build("firmware-avr", &[])
}

/// The `replay` binary: the firmware's planner behind the replay protocol,
/// what the tests replay recorded traces through and time.
pub fn replay_firmware_elf() -> PathBuf {
    build("replay", &[])
}

/// The production image for sensors set back from the rim (its
/// `set-back` feature).
pub fn set_back_firmware_elf() -> PathBuf {
    build("firmware-avr", &["set-back"])
}

/// The `replay` binary for sensors set back.
pub fn set_back_replay_firmware_elf() -> PathBuf {
    build("replay", &["set-back"])
}

/// The `costs` bench: the step's parts timed on fixed inputs.
pub fn costs_elf() -> PathBuf {
    build("costs", &[])
}

/// The `f32-step` bench: the same step in f32 with avr-libc's math.
pub fn f32_step_elf() -> PathBuf {
    build("f32-step", &["f32-step"])
}

/// The cycles of each step of `traces` through the f32 build
/// (planner-float, avr-libc's math), for the fixed-point step's to be set
/// beside.
pub fn f32_step_cycles(traces: &[Trace]) -> Vec<u32> {
    let mut float = Avr::boot_elf(&f32_step_elf());
    traces
        .iter()
        .flat_map(|t| float.replay(t.goal, &t.frames))
        .map(|r| r.cycles)
        .collect()
}

/// Section sizes of an AVR ELF: (text, data, bss), from `avr-size` (binutils
/// for AVR, installed with gcc-avr) in Berkeley format.
pub fn elf_size(elf: &std::path::Path) -> (u32, u32, u32) {
    let out = Cmd::new("avr-size")
        .arg(elf)
        .output()
        .expect("avr-size (Debian gcc-avr/binutils-avr)");
    let text = String::from_utf8_lossy(&out.stdout);
    crate::parse_size(&text).unwrap_or_else(|| panic!("avr-size output: {text}"))
}

/// The ATmega328P's RAM, bytes.
pub const RAM_BYTES: u32 = 2_048;

/// RAM the image `elf` needs with a stack of `stack_peak` bytes: its
/// static data (`.data` + `.bss`) plus the stack; (data, bss, total).
pub fn ram_used(elf: &std::path::Path, stack_peak: u32) -> (u32, u32, u32) {
    let (_, data, bss) = elf_size(elf);
    (data, bss, data + bss + stack_peak)
}

/// The firmware running in simavr at 16 MHz.
pub struct Avr {
    /// The emulator.
    pub avr: AvrTester,
    rx: Vec<u8>,
}

impl Avr {
    /// Boot the production firmware and wait for its `READY` line.
    pub fn boot() -> Avr {
        Avr::boot_elf(&firmware_elf())
    }

    /// Boot the `replay` binary.
    pub fn boot_replay() -> Avr {
        Avr::boot_elf(&replay_firmware_elf())
    }

    /// Boot an ELF that greets with `READY` (the firmware or a bench).
    pub fn boot_elf(elf: &std::path::Path) -> Avr {
        let avr = AvrTester::atmega328p().with_clock(F_CPU).load(elf);
        let mut a = Avr {
            avr,
            rx: Vec::new(),
        };
        let line = a.read_line(200);
        assert_eq!(line.as_deref(), Some("READY"), "boot line");
        a
    }

    /// Run the emulator for `us` microseconds, collecting serial output.
    pub fn run_us(&mut self, us: u64) {
        self.avr.run_for_us(us);
        while let Some(b) = self.avr.uart0().read::<Option<u8>>() {
            self.rx.push(b);
        }
    }

    /// Send bytes on the serial line.
    pub fn send(&mut self, bytes: &[u8]) {
        self.avr.uart0().write(bytes);
    }

    /// The next line received within `ms` emulated milliseconds.
    pub fn read_line(&mut self, ms: u64) -> Option<String> {
        for _ in 0..ms * 10 {
            if let Some(i) = self.rx.iter().position(|&b| b == b'\n') {
                let line: Vec<u8> = self.rx.drain(..=i).collect();
                return Some(String::from_utf8_lossy(&line).trim_end().to_string());
            }
            self.run_us(100);
        }
        None
    }

    /// `n` raw bytes received within `ms` emulated milliseconds.
    pub fn read_bytes(&mut self, n: usize, ms: u64) -> Option<Vec<u8>> {
        for _ in 0..ms * 10 {
            if self.rx.len() >= n {
                return Some(self.rx.drain(..n).collect());
            }
            self.run_us(100);
        }
        None
    }

    /// A command line and its one-line reply.
    pub fn request(&mut self, line: &str) -> Option<String> {
        self.send(format!("{line}\n").as_bytes());
        self.read_line(100)
    }

    /// The firmware's painted stack peak so far, bytes (its answer to
    /// `M`), if it answers.
    pub fn stack_peak(&mut self) -> Option<u32> {
        self.request("M")
            .and_then(|l| l.strip_prefix("M stack_peak=").and_then(|v| v.parse().ok()))
    }

    /// Replay frames toward `goal` in the firmware's replay mode: its
    /// answers and what each frame's step and guard looks cost.
    pub fn replay(&mut self, goal: Point, frames: &[Frame]) -> Vec<Replayed> {
        let ok = self.request(&format!("R {} {}", goal.x, goal.y));
        assert_eq!(ok.as_deref(), Some("OK"), "enter replay");
        let mut got = Vec::new();
        for (k, f) in frames.iter().enumerate() {
            self.send(&replay_frame(f));
            let r = self
                .read_bytes(REPLAY_ANSWER_LEN, 500)
                .expect("replay answer");
            let answer = replay_answer(&r).unwrap_or_else(|| {
                panic!(
                    "replay answer, frame {k}: {r:?} then {:?}",
                    String::from_utf8_lossy(&self.rx)
                )
            });
            // The firmware times a span exactly below 65,536 cycles, and
            // says when one was longer rather than send a wrong count.
            assert!(
                answer.cycles != UNTIMED && answer.guard_cycles != UNTIMED,
                "replay frame {k}: a step or guard look ran 65,536 cycles or more, \
                 longer than the firmware can time"
            );
            got.push(answer);
        }
        self.send(&[0x00]);
        assert_eq!(self.read_line(100).as_deref(), Some("OK"), "leave replay");
        got
    }
}

/// A replay-mode frame for the firmware: `0xa5`, the number of guard
/// samples, each as the step still to go and the five raw counts, then x,
/// y, heading and the five raw counts of the step, little-endian
/// (`firmware-avr/src/replay.rs`).
pub fn replay_frame(f: &Frame) -> Vec<u8> {
    let mut msg = vec![0xa5, f.guards.len() as u8];
    f.encode_le(&mut msg);
    msg
}

/// The cycles a replay answer gives for a span the firmware could not
/// time: 65,536 cycles or more (`firmware-avr/src/replay.rs`).
pub const UNTIMED: u32 = u32::MAX;

/// Bytes of the firmware's answer to a replay frame.
pub const REPLAY_ANSWER_LEN: usize = 15;

/// The firmware's answer to a replay frame and what it cost.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Replayed {
    /// The guard's verdicts and the step's output.
    pub answer: Answer,
    /// Cycles of the planner step.
    pub cycles: u32,
    /// Cycles of the frame's costliest guard look (0 without one).
    pub guard_cycles: u32,
}

/// The firmware's answer to a replay frame: `0x5a`, heading, step, status
/// code, the step's cycles, the guard's verdicts (bit `i`: sample `i`
/// said stop), the costliest guard look's cycles; `None` if it is not one.
pub fn replay_answer(r: &[u8]) -> Option<Replayed> {
    let r: &[u8; REPLAY_ANSWER_LEN] = r.try_into().ok()?;
    if r[0] != 0x5a {
        return None;
    }
    let output = Output {
        command: Command {
            heading: Angle(u16::from_le_bytes([r[1], r[2]])),
            step_mm: u16::from_le_bytes([r[3], r[4]]),
        },
        status: Status::from_code(r[5])?,
    };
    let answer = Answer {
        guard_stops: r[10],
        output,
    };
    Some(Replayed {
        answer,
        cycles: u32::from_le_bytes([r[6], r[7], r[8], r[9]]),
        guard_cycles: u32::from_le_bytes([r[11], r[12], r[13], r[14]]),
    })
}

/// How a closed-loop drive ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LoopOutcome {
    /// The firmware reported arrival and the emulated rover is at the goal.
    Reached,
    /// The firmware reported `unreachable`.
    Unreachable,
    /// The firmware reported a sensor fault and stopped.
    SensorFault,
    /// The rover's disc touched an obstacle.
    Collision,
    /// Out of emulated time.
    Timeout,
}

/// The emulated rover of the closed loop: the reference body
/// (`planner_core::rover::drive::Body::REFERENCE`), wheels at `duty/255 · 0.4 m/s`.
pub const WHEEL_SPEED_MPS: f64 = 0.4;

/// A sensor unplugged during a [`drive_with`]: from `at_s` emulated
/// seconds on, its ADC pin reads 0 V (a broken signal wire, the pin pulled
/// to ground).
#[derive(Clone, Copy, Debug)]
pub struct Unplug {
    /// Which sensor (0 ..= 4, right to left).
    pub sensor: usize,
    /// When, emulated seconds.
    pub at_s: f64,
}

/// Result of [`drive`].
#[derive(Debug)]
pub struct LoopRun {
    /// How it ended.
    pub outcome: LoopOutcome,
    /// Emulated seconds.
    pub seconds: f64,
    /// Distance driven, m.
    pub path_m: f64,
    /// Planner steps the firmware reported.
    pub steps: usize,
    /// Final true distance to the goal, m.
    pub to_goal_m: f64,
    /// After a stop (arrival, unreachable, sensor fault), over the 100 ms
    /// that follow it from 2 ms on: the PWM samples that were high (0: the
    /// motors stayed off), and how far the rover moved, m.
    pub after_stop: Option<(u32, f64)>,
    /// After a stop, the firmware's painted stack peak over the whole
    /// drive, bytes (its `M` reply): the closed loop reaches code paths
    /// the replayed traces do not (the boundary follower, the sensor
    /// fault), and their stack must fit the 2 KB of RAM too.
    pub stack_peak: Option<u32>,
    /// The image that drove (the shipped build, or the `set-back` one).
    pub elf: PathBuf,
}

/// Run the firmware for one millisecond, sampling its PWM pins every 16 µs:
/// the wheel speeds the pins ask for (m/s, signed by the direction pins at
/// the end) and the PWM samples that were high, both wheels.
pub fn wheels_for_1ms(a: &mut Avr) -> (f64, f64, u32) {
    const SAMPLES: u32 = 62;
    let (mut high_l, mut high_r) = (0u32, 0u32);
    for _ in 0..SAMPLES {
        a.avr.run_for(256u64);
        let mut pins = a.avr.pins();
        high_l += pins.pd6().is_high() as u32;
        high_r += pins.pd5().is_high() as u32;
    }
    let mut pins = a.avr.pins();
    let dir_l = pins.pd7().is_high() as i32 - pins.pb0().is_high() as i32;
    let dir_r = pins.pb1().is_high() as i32 - pins.pb2().is_high() as i32;
    let speed = |dir: i32, high: u32| dir as f64 * high as f64 / SAMPLES as f64 * WHEEL_SPEED_MPS;
    (speed(dir_l, high_l), speed(dir_r, high_r), high_l + high_r)
}

/// Drive a scenario closed-loop: the emulated firmware reads the five ADC
/// pins (driven with sim-host's realistic sensor voltages for the true
/// pose), drives its PWM and direction pins, and counts encoder edges
/// that this harness generates from the wheel travel; the harness moves
/// the rover by what the pins say (duty measured by sampling the PWM pins
/// every 16 µs) and checks collisions with the swept disc.
pub fn drive(sc: &sim_host::scenario::Scenario, seed: u64, max_s: f64) -> LoopRun {
    drive_with(sc, seed, max_s, None)
}

/// [`drive`], with a sensor unplugged on the way if `unplug` says so.
pub fn drive_with(
    sc: &sim_host::scenario::Scenario,
    seed: u64,
    max_s: f64,
    unplug: Option<Unplug>,
) -> LoopRun {
    drive_mounted(sc, seed, max_s, unplug, false)
}

/// [`drive`] for the firmware built for sensors set back from the rim (its
/// `set-back` feature), the virtual sensors mounted alike.
pub fn drive_set_back(sc: &sim_host::scenario::Scenario, seed: u64, max_s: f64) -> LoopRun {
    drive_mounted(sc, seed, max_s, None, true)
}

/// The emulated rover of the closed loop: the firmware in simavr, its five
/// ADC pins driven with sim-host's realistic sensor voltages for the true
/// pose, its PWM and direction pins moving the rover (duty measured by
/// sampling them every 16 µs), and the encoder edges the wheel travel
/// makes; collisions checked with the swept disc.
pub struct EmulatedRover {
    /// The firmware.
    pub a: Avr,
    world: sim_host::world::World,
    radius: f64,
    sensors: sim_host::sensor::VirtualSensors,
    unplug: Option<Unplug>,
    /// True pose, m and rad.
    pub p: sim_host::geom::V2,
    h: f64,
    /// Each wheel's encoder disc position, in ticks.
    disc: (f64, f64),
    /// Emulated time, s, and distance driven, m.
    pub t: f64,
    pub path: f64,
    /// The disc touched an obstacle.
    pub collided: bool,
    /// Lines the firmware sent, not yet taken.
    lines: std::collections::VecDeque<String>,
    /// The image it runs.
    pub elf: PathBuf,
}

/// A millisecond, the closed loop's tick, s.
const TICK_S: f64 = 0.001;

impl EmulatedRover {
    /// The firmware booted at `sc`'s start, the sensors on the rim or
    /// `set_back` behind it (the firmware built alike), the heading rounded
    /// to whole degrees (as `P` sets it): the `P` line for it, not sent.
    pub fn new(
        sc: &sim_host::scenario::Scenario,
        seed: u64,
        unplug: Option<Unplug>,
        set_back: bool,
    ) -> (EmulatedRover, String) {
        use sim_host::geom::V2;
        use sim_host::sensor::{SensorMode, VirtualSensors};
        let adc = planner_core::AdcProfile::AVR_10BIT_5V;
        // The firmware's geometry: its default configuration's.
        let cfg = planner_core::ConfigBuilder::new(adc)
            .sensors_set_back(set_back)
            .build()
            .expect("the default configuration");
        let angles = [-40f64, -20.0, 0.0, 20.0, 40.0].map(f64::to_radians);
        let offset_m = cfg.sensor_offset_mm() as f64 / 1e3;
        let sensors = VirtualSensors::new(adc, SensorMode::REALISTIC, angles, offset_m, seed);
        let elf = if set_back {
            set_back_firmware_elf()
        } else {
            firmware_elf()
        };
        let (p, h) = (V2::new(sc.start[0], sc.start[1]), sc.start_heading_rad());
        let pose = format!(
            "P {} {} {}",
            (p.x * 1e3).round(),
            (p.y * 1e3).round(),
            h.to_degrees().round()
        );
        let rover = EmulatedRover {
            a: Avr::boot_elf(&elf),
            elf,
            world: sc.world(),
            radius: sc.robot_radius,
            sensors,
            unplug,
            p,
            h: h.to_degrees().round().to_radians(),
            disc: (0.5, 0.5),
            t: 0.0,
            path: 0.0,
            collided: false,
            lines: Default::default(),
        };
        (rover, pose)
    }

    /// One millisecond: the sensors' voltages for the true pose, the
    /// firmware run, the rover moved as its pins say, the encoder edges.
    /// The wheels' PWM samples that were high.
    pub fn tick(&mut self) -> u32 {
        // simavr's ADC reference is 3.3 V when the ELF does not declare
        // AVCC: scale so that the firmware sees what a 5 V AVCC would give.
        self.sensors.read(&self.world, self.p, self.h, self.t);
        for (i, v) in self.sensors.volts().iter().enumerate() {
            let unplugged = self
                .unplug
                .is_some_and(|u| u.sensor == i && self.t >= u.at_s);
            let mv = if unplugged {
                0
            } else {
                (v * 1_000.0 * 3_300.0 / 5_000.0)
                    .round()
                    .clamp(0.0, 3_300.0) as u32
            };
            let mut pins = self.a.avr.pins();
            match i {
                0 => pins.adc0().set_mv(mv),
                1 => pins.adc1().set_mv(mv),
                2 => pins.adc2().set_mv(mv),
                3 => pins.adc3().set_mv(mv),
                _ => pins.adc4().set_mv(mv),
            }
        }
        let (vl, vr, pulses) = wheels_for_1ms(&mut self.a);
        self.a.run_us(8); // collect serial output
        let body = planner_core::rover::drive::Body::REFERENCE;
        let base = body.wheel_base_mm() as f64 / 1e3;
        let (q, h1) = sim_host::geom::differential_drive(self.p, self.h, vl, vr, base, TICK_S);
        if self.world.static_sweep_clearance(self.p, q) <= self.radius {
            self.collided = true;
        }
        self.path += self.p.dist(q);
        (self.p, self.h) = (q, h1);
        self.t += TICK_S;
        // Encoder edges for the wheel travel (at most one per millisecond
        // per wheel at this speed): a wheel that turns back over an edge it
        // just passed makes that edge again, and one that stops short of the
        // next makes none (the travel is not summed regardless of sign).
        let m_per_tick = body.um_per_tick() as f64 / 1e6;
        let was = (self.disc.0.floor(), self.disc.1.floor());
        self.disc.0 += vl * TICK_S / m_per_tick;
        self.disc.1 += vr * TICK_S / m_per_tick;
        if self.disc.0.floor() != was.0 {
            self.a.avr.pins().pd2().set_high();
        }
        if self.disc.1.floor() != was.1 {
            self.a.avr.pins().pd3().set_high();
        }
        self.a.avr.run_for(64u64);
        self.a.avr.pins().pd2().set_low();
        self.a.avr.pins().pd3().set_low();
        while let Some(i) = self.a.rx.iter().position(|&b| b == b'\n') {
            let line: Vec<u8> = self.a.rx.drain(..=i).collect();
            self.lines
                .push_back(String::from_utf8_lossy(&line).trim_end().to_string());
        }
        pulses
    }

    /// The next line the firmware sent, if any.
    pub fn take_line(&mut self) -> Option<String> {
        self.lines.pop_front()
    }
}

/// The console's link to the emulated rover: each line is sent to the
/// firmware, and reading one runs the closed loop until a line comes (at
/// most 10 emulated seconds).
impl sim_host::console::Link for EmulatedRover {
    fn send(&mut self, line: &str) -> Result<(), String> {
        self.a.send(format!("{line}\n").as_bytes());
        Ok(())
    }

    fn read_line(&mut self) -> Result<Option<String>, String> {
        for _ in 0..10_000 {
            if let Some(l) = self.take_line() {
                return Ok(Some(l));
            }
            self.tick();
        }
        Ok(None)
    }
}

/// [`drive_with`], the sensors on the rim or `set_back` behind it (the
/// firmware built alike).
fn drive_mounted(
    sc: &sim_host::scenario::Scenario,
    seed: u64,
    max_s: f64,
    unplug: Option<Unplug>,
    set_back: bool,
) -> LoopRun {
    let (mut r, pose) = EmulatedRover::new(sc, seed, unplug, set_back);
    assert_eq!(r.a.request(&pose).as_deref(), Some("OK"), "{pose}");
    let goal = sim_host::geom::V2::new(sc.goal[0], sc.goal[1]);
    let go = format!("G {} {}", (goal.x * 1e3).round(), (goal.y * 1e3).round());
    assert_eq!(r.a.request(&go).as_deref(), Some("OK"), "{go}");
    let mut steps = 0;
    let outcome = 'run: loop {
        if r.t > max_s {
            break LoopOutcome::Timeout;
        }
        r.tick();
        if r.collided {
            break LoopOutcome::Collision;
        }
        // Telemetry.
        while let Some(line) = r.take_line() {
            let Some(t) = sim_host::console::Record::parse(&line) else {
                continue;
            };
            steps += 1;
            match t.status {
                Status::Arrived => break 'run LoopOutcome::Reached,
                Status::Unreachable => break 'run LoopOutcome::Unreachable,
                Status::SensorFault => break 'run LoopOutcome::SensorFault,
                Status::Moving => {}
            }
        }
    };
    // The firmware stops the motors right after the telemetry line that
    // says why: give it 2 ms, then watch the PWM pins for 100 ms, the rover
    // moving as they say.
    let after_stop = matches!(
        outcome,
        LoopOutcome::Reached | LoopOutcome::Unreachable | LoopOutcome::SensorFault
    )
    .then(|| {
        let stopped_at = r.p;
        let mut high = 0;
        for ms in 0..102 {
            let pulses = r.tick();
            if ms >= 2 {
                high += pulses;
            }
        }
        (high, r.p.dist(stopped_at))
    });
    let stack_peak = after_stop.and_then(|_| r.a.stack_peak());
    LoopRun {
        outcome,
        seconds: r.t,
        path_m: r.path,
        steps,
        to_goal_m: r.p.dist(goal),
        after_stop,
        stack_peak,
        elf: r.elf,
    }
}
