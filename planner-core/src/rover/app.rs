//! The rover application both firmwares run, as one state machine over the
//! board's parts: the serial requests of [`protocol`], the sensors'
//! warm-up, the turn-then-advance [`Executor`] with the planner's guard
//! during each advance, the telemetry line, and the stop on a fault.
//!
//! A firmware wires its drivers to five small traits ([`Motors`],
//! [`Encoders`], [`Sensors`], [`Clock`], [`Serial`]; [`Board`] gathers
//! them) and calls [`Rover::poll`] from its main loop, as often as it can.
//! The host tests drive the same code with mock parts.
//!
//! Each poll has two phases:
//! 1. **requests**: every byte received goes to the [`LineReader`]; each
//!    whole line is answered (`OK`, `ERR`, `D …`, `M …`);
//! 2. **control tick**, once per millisecond of the board's clock: the
//!    encoders' ticks into the odometry, the sensors' latest sweep, then
//!    - stopped: motors off;
//!    - idle executor: a planner step on the latest counts, its telemetry
//!      line, and either the next command or a stop (arrived, unreachable,
//!      sensor fault);
//!    - turning or advancing: the executor's duties, the guard looking at
//!      each new sweep at most every [`RoverConfig::guard_period_ms`].

use crate::eapf::command::{Guard, Output, Status};
use crate::eapf::sensors::{AdcProfile, RawCounts, SENSOR_WARMUP_MS};
use crate::eapf::Planner;
use crate::fixed::{Angle, Point, Pose};
use crate::rover::calibration::{Corrections, Source, STORED_BYTES};
use crate::rover::drive::{Body, Executor, ExecutorConfig, Odometry, Wheels};
use crate::rover::protocol::{self, write_counts, write_field, LineReader, Request};
use core::sync::atomic::{compiler_fence, Ordering};

/// The two motors.
pub trait Motors {
    /// Drive the wheels at these duties (both 0: motors off).
    fn set(&mut self, wheels: Wheels);
}

/// The two wheel encoders.
pub trait Encoders {
    /// Ticks of each wheel (left, right; forward positive) since the last
    /// call.
    fn take(&mut self) -> (i16, i16);
}

/// What the sensors have for a control tick.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sweep {
    /// No new sweep since the last call.
    Same,
    /// A sweep of all five channels completed since the last call.
    New(RawCounts),
    /// The converter failed: a sensor fault.
    Failed,
}

/// The five IR sensors behind their ADC.
pub trait Sensors {
    /// The latest sweep, if one completed since the last call.
    fn sweep(&mut self) -> Sweep;
}

/// Time since power-up.
pub trait Clock {
    /// Milliseconds (may wrap).
    fn millis(&mut self) -> u32;
    /// A free-running cycle counter, for the telemetry's step cycles (0
    /// where the board has none).
    fn cycles(&mut self) -> u32 {
        0
    }
}

/// The serial port of [`protocol`].
pub trait Serial {
    /// A received byte, if any (never blocks).
    fn read(&mut self) -> Option<u8>;
    /// Send one byte.
    fn write(&mut self, b: u8);
}

/// Every part the application drives, and what a board can report.
pub trait Board: Motors + Encoders + Sensors + Clock + Serial {
    /// The most stack used so far, bytes, for `M` (`None` answers `ERR`).
    fn stack_peak(&self) -> Option<u16> {
        None
    }
    /// Told what the application did, for a log (the STM32's defmt).
    fn log(&mut self, event: Event) {
        let _ = event;
    }
    /// Read the stored calibration into `bytes`; `false` where the board
    /// keeps none (then the datasheet's serves).
    fn load_calibration(&mut self, bytes: &mut [u8; STORED_BYTES]) -> bool {
        let _ = bytes;
        false
    }
    /// Store the calibration; `false` if the board cannot.
    fn store_calibration(&mut self, bytes: &[u8; STORED_BYTES]) -> bool {
        let _ = bytes;
        false
    }
}

/// How the rover drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RoverConfig {
    /// The wheels and encoders.
    pub body: Body,
    /// The turn-then-advance executor.
    pub executor: ExecutorConfig,
    /// Least time between two guard looks, ms. A look costs about a 1 ms
    /// tick on the ATmega328P; the sensors give a new sweep every ~38 ms
    /// and the rover covers 1.4 mm in 4 ms at full speed.
    pub guard_period_ms: u16,
    /// The sensors' ADC (for their calibration's datasheet counts).
    pub adc: AdcProfile,
}

impl RoverConfig {
    /// The reference rover ([`Body::REFERENCE`]), the default executor,
    /// a guard look every 4 ms, sensors on `adc`.
    pub const fn reference(adc: AdcProfile) -> RoverConfig {
        RoverConfig {
            body: Body::REFERENCE,
            executor: ExecutorConfig::DEFAULT,
            guard_period_ms: 4,
            adc,
        }
    }
}

/// A planner step as it ran.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Step {
    /// When, ms.
    pub ms: u32,
    /// The pose it planned from.
    pub pose: Pose,
    /// What the planner answered.
    pub output: Output,
    /// Its cycles, by [`Clock::cycles`] (interrupts during it included).
    pub cycles: u32,
}

/// What the application tells [`Board::log`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Event {
    /// The planner stepped.
    Stepped(Step),
    /// The sensors failed while driving: stopped.
    SensorFailed,
}

/// The application: planner, odometry, executor and request reader.
#[derive(Debug)]
pub struct Rover<'p> {
    /// Borrowed, not owned: a firmware builds its planner in place (on the
    /// ATmega328P a move is a second 1 KB copy on the stack).
    planner: &'p mut Planner,
    odometry: Odometry,
    executor: Executor,
    lines: LineReader,
    guard_period_ms: u16,
    driving: bool,
    /// The sensors have given their first output (kept once past: the
    /// clock wraps after 49 days).
    warm: bool,
    /// The last control tick, ms.
    last_tick_ms: u32,
    /// The last guard look, ms.
    last_guard_ms: u32,
    /// The latest sweep (`None` before the first and after a failure).
    counts: Option<RawCounts>,
    /// The latest sweep came after the guard's last look.
    unseen: bool,
    /// Each sensor's correction, and where they came from (the datasheet's
    /// curve: none, and the counts go to the planner as they are).
    tables: Corrections,
    source: Source,
}

impl<'p> Rover<'p> {
    /// A stopped rover at the origin, heading 0, planning with `planner`.
    pub fn new(planner: &'p mut Planner, cfg: RoverConfig) -> Self {
        Rover {
            planner,
            odometry: Odometry::new(cfg.body, Pose::default()),
            executor: Executor::new(cfg.executor),
            lines: LineReader::new(),
            guard_period_ms: cfg.guard_period_ms,
            driving: false,
            warm: false,
            last_tick_ms: 0,
            last_guard_ms: 0,
            counts: None,
            unseen: false,
            tables: Corrections::none(cfg.adc),
            source: Source::Datasheet,
        }
    }

    /// Read the calibration the board stored, if any: a corrupt or refused
    /// copy leaves the datasheet's in use. Once, at start-up. An erased
    /// store (every byte 0xff, as a new EEPROM or flash reads) holds none.
    pub fn load_calibration(&mut self, board: &mut impl Board) -> Source {
        let mut bytes = [0; STORED_BYTES];
        let stored = board.load_calibration(&mut bytes);
        self.source = if !stored || bytes.iter().all(|&b| b == 0xff) {
            Source::Datasheet
        } else if self.tables.load(&bytes).is_ok() {
            Source::Stored
        } else {
            Source::Corrupt
        };
        self.source
    }

    /// Where the sensors' calibration comes from.
    pub fn calibration(&self) -> Source {
        self.source
    }

    /// Drive to `goal` (what `G` does): forget the map, start driving.
    pub fn go(&mut self, goal: Point) {
        self.planner.set_goal(goal);
        self.executor.halt();
        self.driving = true;
    }

    /// Is it driving to a goal?
    pub fn is_driving(&self) -> bool {
        self.driving
    }

    /// The odometry's pose.
    pub fn pose(&self) -> Pose {
        self.odometry.pose()
    }

    /// The planner.
    pub fn planner(&self) -> &Planner {
        self.planner
    }

    /// Answer the requests received, then run the control tick if the
    /// board's clock has moved on since the last.
    #[cfg_attr(target_arch = "avr", inline(never))]
    pub fn poll(&mut self, board: &mut impl Board) {
        let now = board.millis();
        while let Some(b) = board.read() {
            if let Some(req) = self.lines.feed(b, now) {
                self.answer(board, req);
            }
        }
        if now != self.last_tick_ms {
            self.last_tick_ms = now;
            self.tick(board, now);
        }
    }

    fn stop(&mut self, board: &mut impl Board) {
        self.executor.halt();
        self.driving = false;
        board.set(Wheels::STOP);
    }

    /// Answer one line (`None`: not a command).
    #[inline(never)]
    fn answer(&mut self, board: &mut impl Board, req: Option<Request>) {
        let reply: &[u8] = match req {
            Some(Request::Goal(x, y)) => {
                self.go(Point::new(x, y));
                b"OK\n"
            }
            Some(Request::Pose(x, y, deg)) if !self.driving => {
                self.odometry.set_pose(Pose {
                    position: Point::new(x, y),
                    heading: Angle::from_deg(deg),
                });
                b"OK\n"
            }
            Some(Request::Stop) => {
                self.stop(board);
                b"OK\n"
            }
            // Not a command: it may have been a stop (`protocol`).
            None => {
                self.stop(board);
                b"ERR\n"
            }
            Some(Request::Sensors) => match self.counts {
                Some(raw) => {
                    let read = planner_counts(&self.tables, self.source, &raw);
                    protocol::write_sensor_line(
                        self.planner.config(),
                        &raw,
                        &read,
                        &mut sink(board),
                    );
                    return;
                }
                None => b"ERR\n",
            },
            // Stored only while stopped: a store blocks the loop (an
            // EEPROM byte takes 3.4 ms, a flash sector's erase seconds).
            Some(Request::Calibrate(sensor, k)) if !self.driving => {
                match self.tables.set(sensor.into(), k) {
                    Err(_) => b"ERR\n",
                    // In use from now on, stored or not.
                    Ok(()) => {
                        self.source = Source::Stored;
                        if board.store_calibration(&self.tables.to_bytes()) {
                            b"OK\n"
                        } else {
                            b"ERR\n"
                        }
                    }
                }
            }
            Some(Request::Memory) => match board.stack_peak() {
                Some(peak) => {
                    write_bytes(board, b"M stack_peak=");
                    protocol::write_number(peak.into(), &mut sink(board));
                    board.write(b'\n');
                    return;
                }
                None => b"ERR\n",
            },
            // `P` and `K` while driving; `R` (the replay binary's).
            Some(Request::Pose(..) | Request::Calibrate(..) | Request::Replay(..)) => b"ERR\n",
        };
        write_bytes(board, reply);
    }

    /// One control tick at `now`, ms.
    fn tick(&mut self, board: &mut impl Board, now: u32) {
        let (left, right) = board.take();
        self.odometry.update(left, right);
        self.warm = self.warm || now >= SENSOR_WARMUP_MS;
        if !self.take_sweep(board) && self.driving {
            self.stop(board);
            board.log(Event::SensorFailed);
            return;
        }
        if !self.driving {
            board.set(Wheels::STOP);
            return;
        }
        let pose = self.odometry.pose();
        if self.executor.is_idle() {
            let (true, Some(raw)) = (self.warm, &self.counts) else {
                // Warming up: wait, motors off.
                board.set(Wheels::STOP);
                return;
            };
            let read = planner_counts(&self.tables, self.source, raw);
            let (output, cycles) = timed_step(self.planner, board, pose, &read);
            let step = Step {
                ms: now,
                pose,
                output,
                cycles,
            };
            write_telemetry(&mut sink(board), &step, self.source, &read);
            board.log(Event::Stepped(step));
            if step.output.status != Status::Moving {
                // Arrived, unreachable or a sensor fault: safe stop.
                self.stop(board);
                return;
            }
            self.executor.start(step.output.command);
        }
        let (wheels, look) = self.advance(now, pose);
        board.set(wheels);
        if let Some(look) = look {
            write_look(&mut sink(board), &look);
        }
    }

    /// Keep the latest sweep; `false` if the sensors failed.
    fn take_sweep(&mut self, board: &mut impl Board) -> bool {
        match board.sweep() {
            Sweep::Same => true,
            Sweep::New(raw) => {
                self.counts = Some(raw);
                self.unseen = true;
                true
            }
            Sweep::Failed => {
                self.counts = None;
                false
            }
        }
    }

    /// The executor's duties; the guard looks at a sweep it has not seen
    /// when a look is due.
    /// A look that changed what the planner keeps (its flank points) is
    /// returned, to be logged: a replay of the run needs it, and no other.
    #[cfg_attr(target_arch = "avr", inline(never))]
    fn advance(&mut self, now: u32, pose: Pose) -> (Wheels, Option<Look>) {
        let due =
            self.unseen && now.wrapping_sub(self.last_guard_ms) >= self.guard_period_ms.into();
        let (planner, counts) = (&mut *self.planner, &self.counts);
        let (unseen, last_guard_ms) = (&mut self.unseen, &mut self.last_guard_ms);
        let (tables, source) = (&self.tables, self.source);
        let mut kept = None;
        let wheels = self
            .executor
            .tick(pose, self.odometry.travelled_mm(), |remaining_mm| {
                match (due, counts) {
                    (true, Some(raw)) => {
                        *unseen = false;
                        *last_guard_ms = now;
                        let read = planner_counts(tables, source, raw);
                        let before = planner.flank().changes();
                        let guard = planner.guard_raw(&read, remaining_mm);
                        if planner.flank().changes() != before {
                            kept = Some(Look {
                                remaining_mm,
                                counts: read,
                            });
                        }
                        guard
                    }
                    _ => Guard::Continue,
                }
            });
        (wheels, kept)
    }
}

/// A guard look: the step still to go and the counts it read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Look {
    /// The step still to go, mm.
    pub remaining_mm: u16,
    /// The counts the planner read.
    pub counts: RawCounts,
}

/// `g <remaining_mm> <c0> … <c4>` ([`protocol`]).
fn write_look(out: &mut dyn FnMut(u8), look: &Look) {
    out(b'g');
    write_field(out, look.remaining_mm.into());
    write_counts(out, &look.counts);
    out(b'\n');
}

/// The counts the planner reads for the sensors' `raw` counts: through
/// each sensor's own calibration, if there is one.
fn planner_counts(tables: &Corrections, source: Source, raw: &RawCounts) -> RawCounts {
    match source {
        Source::Stored => tables.apply(raw),
        Source::Datasheet | Source::Corrupt => *raw,
    }
}

/// A planner step and its cycles. The fences and `black_box`es keep the
/// compiler from moving work across the two cycle reads.
#[cfg_attr(target_arch = "avr", inline(never))]
fn timed_step(
    planner: &mut Planner,
    clock: &mut impl Clock,
    pose: Pose,
    raw: &RawCounts,
) -> (Output, u32) {
    let t0 = clock.cycles();
    compiler_fence(Ordering::SeqCst);
    let output = planner.step_raw(core::hint::black_box(pose), core::hint::black_box(raw));
    let output = core::hint::black_box(output);
    compiler_fence(Ordering::SeqCst);
    (output, clock.cycles().wrapping_sub(t0))
}

/// The board's serial output as the one closure type that the writers of
/// [`protocol`] take (`dyn`: an image holds one copy of each writer, and of
/// the closure's table, which the AVR keeps in RAM).
fn sink(board: &mut impl Serial) -> impl FnMut(u8) + '_ {
    move |b| board.write(b)
}

fn write_bytes(board: &mut impl Serial, bytes: &[u8]) {
    for &b in bytes {
        board.write(b);
    }
}

/// `T <ms> <x_mm> <y_mm> <heading> <status> <cmd_heading> <step_mm> <cycles> <cal> <c0> … <c4>`
/// ([`protocol`]), a byte at a time to `out`.
fn write_telemetry(out: &mut dyn FnMut(u8), step: &Step, cal: Source, counts: &RawCounts) {
    let position = step.pose.position;
    let command = step.output.command;
    out(b'T');
    write_field(out, step.ms);
    for v in [position.x, position.y] {
        out(b' ');
        protocol::write_signed(v, out);
    }
    write_field(out, step.pose.heading.0.into());
    out(b' ');
    out(step.output.status.letter());
    write_field(out, command.heading.0.into());
    write_field(out, command.step_mm.into());
    write_field(out, step.cycles);
    out(b' ');
    out(cal.letter());
    write_counts(out, counts);
    out(b'\n');
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eapf::config::ConfigBuilder;
    use crate::eapf::sensors::{AdcProfile, Reading};
    use std::string::String;
    use std::vec::Vec;

    /// The reference rover on the ATmega328P's ADC.
    const CFG: RoverConfig = RoverConfig::reference(AdcProfile::AVR_10BIT_5V);

    /// Counts that read "nothing in range", with a little noise.
    const CLEAR: u16 = 57;

    /// A rover in open space: the wheels turn the encoders as commanded
    /// (no slip), the sensors see nothing and sweep every 38 ms, bytes
    /// arrive when the test queues them.
    struct Mock {
        ms: u32,
        wheels: Wheels,
        /// Duty accumulated, per wheel, towards the next tick.
        acc: (i32, i32),
        /// What the sensors give from this time on, ms: counts, or a failure.
        fault_at_ms: Option<(u32, Option<u16>)>,
        sweeps: u32,
        /// The board's storage for the calibration, if it has one.
        stored: Option<[u8; STORED_BYTES]>,
        rx: Vec<u8>,
        tx: Vec<u8>,
        events: Vec<Event>,
    }

    impl Mock {
        fn new() -> Self {
            Mock {
                ms: 0,
                wheels: Wheels::STOP,
                acc: (0, 0),
                fault_at_ms: None,
                sweeps: 0,
                stored: None,
                rx: Vec::new(),
                tx: Vec::new(),
                events: Vec::new(),
            }
        }

        /// A board whose rover has driven towards (3000, 0) mm for 0.8 s.
        fn driving(rover: &mut Rover) -> Mock {
            let mut board = Mock::new();
            board.send("G 3000 0\n");
            board.run(rover, 800, false);
            assert!(rover.is_driving() && board.wheels != Wheels::STOP);
            board
        }

        fn send(&mut self, line: &str) {
            self.rx.extend_from_slice(line.as_bytes());
        }

        /// Everything sent so far, and forget it.
        fn sent(&mut self) -> String {
            String::from_utf8(core::mem::take(&mut self.tx)).unwrap()
        }

        /// Poll once a millisecond until `until_ms`, or until the rover
        /// stops driving with `stop_early`; the events logged.
        fn run(&mut self, rover: &mut Rover, until_ms: u32, stop_early: bool) -> Vec<Event> {
            while self.ms < until_ms {
                self.ms += 1;
                rover.poll(self);
                if stop_early && !rover.is_driving() {
                    break;
                }
            }
            core::mem::take(&mut self.events)
        }
    }

    impl Motors for Mock {
        fn set(&mut self, wheels: Wheels) {
            self.wheels = wheels;
        }
    }

    impl Encoders for Mock {
        /// 256 duty-ms make a tick: about 0.8 m/s at the cruise duty.
        fn take(&mut self) -> (i16, i16) {
            self.acc.0 += i32::from(self.wheels.left);
            self.acc.1 += i32::from(self.wheels.right);
            let ticks = (self.acc.0 / 256, self.acc.1 / 256);
            self.acc.0 -= ticks.0 * 256;
            self.acc.1 -= ticks.1 * 256;
            (ticks.0 as i16, ticks.1 as i16)
        }
    }

    impl Sensors for Mock {
        fn sweep(&mut self) -> Sweep {
            if !self.ms.is_multiple_of(38) {
                return Sweep::Same;
            }
            self.sweeps += 1;
            match self.fault_at_ms {
                Some((at, None)) if self.ms >= at => Sweep::Failed,
                Some((at, Some(c))) if self.ms >= at => Sweep::New([c; 5]),
                _ => Sweep::New([CLEAR + (self.sweeps % 5) as u16; 5]),
            }
        }
    }

    impl Clock for Mock {
        fn millis(&mut self) -> u32 {
            self.ms
        }
    }

    impl Serial for Mock {
        fn read(&mut self) -> Option<u8> {
            (!self.rx.is_empty()).then(|| self.rx.remove(0))
        }
        fn write(&mut self, b: u8) {
            self.tx.push(b);
        }
    }

    impl Board for Mock {
        fn log(&mut self, event: Event) {
            self.events.push(event);
        }
        fn load_calibration(&mut self, bytes: &mut [u8; STORED_BYTES]) -> bool {
            self.stored.map(|s| *bytes = s).is_some()
        }
        fn store_calibration(&mut self, bytes: &[u8; STORED_BYTES]) -> bool {
            self.stored = Some(*bytes);
            true
        }
    }

    fn planner() -> Planner {
        let cfg = ConfigBuilder::new(AdcProfile::AVR_10BIT_5V)
            .build()
            .unwrap();
        for c in CLEAR..CLEAR + 5 {
            assert_eq!(cfg.calibration.reading(c), Reading::Clear);
        }
        Planner::new(cfg, Point::new(0, 0))
    }

    /// Field `n` of each telemetry line in `sent`.
    fn telemetry_fields(sent: &str, n: usize) -> std::vec::Vec<&str> {
        sent.lines()
            .filter(|l| l.starts_with("T "))
            .map(|l| l.split(' ').nth(n).unwrap())
            .collect()
    }

    /// The telemetry lines' status letters.
    fn statuses(sent: &str) -> String {
        telemetry_fields(sent, 5).concat()
    }

    fn steps(events: &[Event]) -> Vec<Step> {
        events
            .iter()
            .filter_map(|e| match e {
                Event::Stepped(s) => Some(*s),
                Event::SensorFailed => None,
            })
            .collect()
    }

    #[test]
    fn a_goal_is_driven_to_then_the_motors_stop() {
        let mut p = planner();
        let mut rover = Rover::new(&mut p, CFG);
        let mut board = Mock::new();
        board.send("P 100 -50 90\nG 700 300\n");
        let events = board.run(&mut rover, 30_000, true);
        let sent = board.sent();
        assert!(sent.starts_with("OK\nOK\n"), "{sent}");
        let steps = steps(&events);
        // No step before the sensors' first output.
        assert!(steps[0].ms >= SENSOR_WARMUP_MS, "{:?}", steps[0]);
        assert_eq!(steps[0].pose.position, Point::new(100, -50));
        let last = steps.last().unwrap();
        assert_eq!(last.output.status, Status::Arrived, "{sent}");
        let (dx, dy) = last.pose.position.to(Point::new(700, 300));
        assert!(dx * dx + dy * dy < 200 * 200, "{:?}", last.pose);
        let letters = statuses(&sent);
        assert_eq!(letters.len(), steps.len());
        assert!(letters.ends_with('A') && letters[..letters.len() - 1].chars().all(|c| c == 'M'));
        // Each telemetry line is its step's, with the counts it read (the
        // first sweep's, at 38 ms).
        let first = sent.lines().find(|l| l.starts_with("T ")).unwrap();
        let s = steps[0];
        let c = CLEAR + 1;
        assert_eq!(
            first,
            std::format!(
                "T {} 100 -50 {} M {} {} 0 - {c} {c} {c} {c} {c}",
                s.ms,
                s.pose.heading.0,
                s.output.command.heading.0,
                s.output.command.step_mm
            )
        );
        assert_eq!(board.wheels, Wheels::STOP);
        // Stopped: no more steps, motors stay off.
        assert!(board.run(&mut rover, board.ms + 500, false).is_empty());
        assert_eq!(board.wheels, Wheels::STOP);
    }

    #[test]
    fn a_sensor_fault_mid_run_stops_the_rover() {
        // An unplugged sensor reads 0: the planner's fault status.
        let mut p = planner();
        let mut rover = Rover::new(&mut p, CFG);
        let mut board = Mock::new();
        board.fault_at_ms = Some((1_000, Some(0)));
        board.send("G 3000 0\n");
        let events = board.run(&mut rover, 5_000, true);
        assert!(!rover.is_driving());
        let last = *steps(&events).last().unwrap();
        assert_eq!(last.output.status, Status::SensorFault);
        assert!(last.ms >= 1_000);
        assert_eq!(board.wheels, Wheels::STOP);
        assert!(statuses(&board.sent()).ends_with('F'));

        // The converter fails: stopped at once, whatever the executor did.
        let mut p = planner();
        let mut rover = Rover::new(&mut p, CFG);
        let mut board = Mock::new();
        board.fault_at_ms = Some((1_000, None));
        board.send("G 3000 0\n");
        let events = board.run(&mut rover, 5_000, true);
        assert_eq!(events.last(), Some(&Event::SensorFailed));
        assert_eq!(board.ms, 1_026, "the first sweep at or after 1 s");
        assert_eq!(board.wheels, Wheels::STOP);
        // And `D` has no counts to show.
        board.sent();
        board.send("D\n");
        board.run(&mut rover, board.ms + 1, false);
        assert_eq!(board.sent(), "ERR\n");
    }

    #[test]
    fn a_line_that_is_not_a_command_stops_the_rover() {
        let mut p = planner();
        let mut rover = Rover::new(&mut p, CFG);
        let mut board = Mock::driving(&mut rover);
        board.sent();
        board.send("G 30x0 0\n");
        board.ms += 1;
        rover.poll(&mut board);
        assert_eq!(board.sent(), "ERR\n");
        assert!(!rover.is_driving());
        assert_eq!(board.wheels, Wheels::STOP);
        assert!(board.run(&mut rover, 2_000, false).is_empty());
        assert_eq!(board.wheels, Wheels::STOP);
    }

    #[test]
    fn a_stop_stops_the_motors_in_the_same_poll() {
        let mut p = planner();
        let mut rover = Rover::new(&mut p, CFG);
        let mut board = Mock::driving(&mut rover);
        let pose = rover.pose();
        board.sent();
        board.send("S\n");
        // Within the same millisecond: the request alone.
        rover.poll(&mut board);
        assert_eq!(board.sent(), "OK\n");
        assert_eq!(board.wheels, Wheels::STOP);
        assert!(board.run(&mut rover, 2_000, false).is_empty());
        assert_eq!(board.wheels, Wheels::STOP);
        // The encoders' last ticks are integrated, no more.
        let (dx, dy) = pose.position.to(rover.pose().position);
        assert!(dx * dx + dy * dy <= 4, "{pose:?} {:?}", rover.pose());
    }

    #[test]
    fn requests_are_answered_in_every_state() {
        let mut p = planner();
        let mut rover = Rover::new(&mut p, CFG);
        let mut board = Mock::new();
        // No sweep yet: no counts to show; this board reports no stack.
        board.send("D\nM\n");
        board.run(&mut rover, 1, false);
        assert_eq!(board.sent(), "ERR\nERR\n");
        board.run(&mut rover, 40, false);
        board.send("D\nR 1 2\n");
        board.run(&mut rover, 41, false);
        let mut d = Vec::new();
        let clear = [CLEAR + 1; 5];
        protocol::write_sensor_line(rover.planner().config(), &clear, &clear, &mut |b| d.push(b));
        assert_eq!(
            board.sent(),
            std::format!("{}ERR\n", String::from_utf8(d).unwrap())
        );
        // The pose may not change while driving.
        board.send("G 500 0\nP 0 0 0\n");
        board.run(&mut rover, 42, false);
        assert_eq!(board.sent(), "OK\nERR\n");
        assert!(rover.is_driving());
    }

    /// The `K` line for `sensor` whose counts are `percent` of the
    /// datasheet's at each card distance, as the console fits it.
    fn k_line(sensor: usize, percent: u32) -> String {
        use crate::rover::calibration::{datasheet_row, fit};
        let row =
            datasheet_row(AdcProfile::AVR_10BIT_5V).map(|c| (u32::from(c) * percent / 100) as u16);
        let k = fit(AdcProfile::AVR_10BIT_5V, &row).unwrap();
        std::format!("K {sensor} {} {}\n", k.gain_q8, k.offset)
    }

    #[test]
    fn a_calibration_is_kept_stored_and_used_after_a_restart() {
        let adc = AdcProfile::AVR_10BIT_5V;
        let mut p = planner();
        let mut rover = Rover::new(&mut p, CFG);
        let mut board = Mock::new();
        assert_eq!(rover.load_calibration(&mut board), Source::Datasheet);
        // Refused: a gain no sensor needs, an unknown sensor.
        board.send("K 0 900 0\nK 0 256 9999\n");
        board.send(&k_line(5, 100));
        board.run(&mut rover, 1, false);
        assert_eq!(board.sent(), "ERR\nERR\nERR\n");
        assert_eq!(board.stored, None);
        // Sensor 2 reads 20 % high: refused while driving, taken stopped.
        board.send("G 3000 0\n");
        board.send(&k_line(2, 120));
        board.send("S\n");
        board.send(&k_line(2, 120));
        board.run(&mut rover, 2, false);
        assert_eq!(board.sent(), "OK\nERR\nOK\nOK\n");
        let stored = board.stored.expect("stored");

        // Power cycle: a new rover on the same board reads it back, and the
        // planner reads sensor 2's count as the datasheet's.
        let mut p = planner();
        let mut rover = Rover::new(&mut p, CFG);
        let mut board = Mock::new();
        board.stored = Some(stored);
        assert_eq!(rover.load_calibration(&mut board), Source::Stored);
        // A card at 200 mm: the datasheet's count there, and sensor 2's.
        let at_200 = adc.counts_for_mv(1_390);
        let strong = (u32::from(at_200) * 120 / 100) as u16;
        board.fault_at_ms = Some((0, Some(strong)));
        board.run(&mut rover, 40, false);
        board.send("D\n");
        board.run(&mut rover, 41, false);
        let sent = board.sent();
        let f: Vec<&str> = sent.split_whitespace().collect();
        assert_eq!(f[1..6], [strong.to_string().as_str(); 5], "{sent}");
        let mm = |i: usize| f[6 + i].parse::<u16>().unwrap();
        assert!(mm(2).abs_diff(200) <= 10, "{sent}");
        assert!(
            mm(0) < 185,
            "the others read the count as the datasheet's sensor: {sent}"
        );
        // And each telemetry line says so.
        assert_eq!(calibration_letters(&mut rover, &mut board), "C");

        // A corrupt copy: the datasheet's curve, flagged.
        let mut bad = stored;
        bad[5] ^= 1;
        let mut p = planner();
        let mut rover = Rover::new(&mut p, CFG);
        let mut board = Mock::new();
        board.stored = Some(bad);
        assert_eq!(rover.load_calibration(&mut board), Source::Corrupt);
        assert_eq!(calibration_letters(&mut rover, &mut board), "!");
    }

    /// The calibration letters of the telemetry lines over 0.2 s of
    /// driving, each letter once.
    fn calibration_letters(rover: &mut Rover, board: &mut Mock) -> String {
        board.send("G 3000 0\n");
        let until = board.ms + 200;
        board.run(rover, until, false);
        let sent = board.sent();
        let mut letters = telemetry_fields(&sent, 9);
        letters.dedup();
        letters.concat()
    }
}
