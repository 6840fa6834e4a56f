//! # firmware-avr
//!
//! The rover firmware for an ATmega328P (Arduino Uno class) at 16 MHz: five
//! IR sensors sampled in the background, wheel-encoder odometry, the
//! turn-then-advance executor and the EAPF planner of `planner-core`, a
//! text protocol on the serial port, and a watchdog. Pin map in [`board`],
//! serial protocol in `planner_core::rover::protocol`.
//!
//! Board code is a thin register-level layer on `avr-device` (avr-hal is not
//! on crates.io): one module per peripheral. Everything the rover decides is
//! in `planner-core`, the same code the simulator and the STM32 run.
//! `ufmt` formats the telemetry (core::fmt would cost several KB of flash).
#![no_std]
#![no_main]
#![feature(abi_avr_interrupt)]

mod adc;
mod board;
mod clock;
mod encoders;
mod motors;
mod progmem;
mod serial;
mod stack;
mod timed;

use planner_core::rover::drive::{Body, Executor, ExecutorConfig, Odometry, Wheels};
use planner_core::rover::protocol::{self, Request, SensorField};
use planner_core::{Angle, Config, Guard, IrSensors, Planner, Point, Pose, Status};
use serial::Serial;
use ufmt::{uwrite, uwriteln};

/// How often the guard checks the way ahead during an advance, ms.
const GUARD_PERIOD_MS: u32 = 4;

/// Goal set at build time, a command line such as `"G 2000 1500"` (optional;
/// `G` over serial otherwise).
const BUILD_GOAL: Option<&str> = option_env!("ROVER_GOAL");

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    // Safe stop: driver to standby, both motors off; the watchdog resets.
    avr_device::interrupt::disable();
    let dp = board::steal();
    dp.PORTD.portd().write(|w| unsafe { w.bits(0) });
    dp.PORTB.portb().write(|w| unsafe { w.bits(0) });
    loop {}
}

fn status_letter(s: Status) -> char {
    match s {
        Status::Moving => 'M',
        Status::Arrived => 'A',
        Status::Unreachable => 'U',
        Status::SensorFault => 'F',
    }
}

/// Enable the watchdog: reset after 0.5 s without `wdr`.
fn watchdog_on(dp: &board::Dp) {
    avr_device::interrupt::free(|_| {
        avr_device::asm::wdr();
        dp.WDT.wdtcsr().write(|w| unsafe { w.bits(0x18) }); // WDCE | WDE
        dp.WDT.wdtcsr().write(|w| unsafe { w.bits(0x0d) }); // WDE, 0.5 s
    });
}

#[avr_device::entry]
fn main() -> ! {
    stack::paint();
    let Some(dp) = board::Dp::take() else {
        // Only possible if `main` ran twice: stay stopped.
        loop {
            avr_device::asm::wdr();
        }
    };
    dp.PORTB
        .ddrb()
        .write(|w| unsafe { w.bits(board::DDRB_OUT) });
    dp.PORTD
        .ddrd()
        .write(|w| unsafe { w.bits(board::DDRD_OUT) });
    motors::init(&dp);
    encoders::init(&dp);
    clock::init(&dp);
    serial::init(&dp);
    adc::start(&dp);
    watchdog_on(&dp);
    // SAFETY: every shared static is behind an interrupt-free Mutex.
    unsafe { avr_device::interrupt::enable() };

    let mut out = Serial;
    // Used in place (by reference), never moved: a move is a second
    // 1 KB copy on the stack. Built with no configuration, then the
    // default one loaded out of flash over it (see `progmem`): a
    // configuration built as a value was a 480-byte copy on the stack, its
    // deepest point (`tests/src/stack_bound.rs`).
    let mut planner = Planner::new(Config::UNSET, Point::new(0, 0));
    planner.load_config(progmem::load_config);
    let planner = &mut planner;
    let mut odometry = Odometry::new(Body::REFERENCE, Pose::default());
    let mut executor = Executor::new(ExecutorConfig::default());
    let mut sensors = adc::BackgroundAdc::new();
    let mut driving = false;
    if let Some(Request::Goal(x, y)) = BUILD_GOAL.and_then(|g| protocol::parse(g.as_bytes())) {
        planner.set_goal(Point::new(x, y));
        driving = true;
    }
    let _ = uwriteln!(out, "READY");

    let mut lines = protocol::LineReader::new();
    let mut last_ms = clock::millis();
    let mut last_sweep = adc::sweeps().wrapping_sub(1);
    let mut last_guard_ms = last_ms.wrapping_sub(GUARD_PERIOD_MS);
    loop {
        avr_device::asm::wdr();
        // Commands.
        let now = clock::millis();
        while let Some(b) = serial::read() {
            let Some(req) = lines.feed(b, now) else {
                continue;
            };
            match req {
                Some(Request::Goal(x, y)) => {
                    planner.set_goal(Point::new(x, y));
                    executor.halt();
                    driving = true;
                }
                Some(Request::Pose(x, y, deg)) if !driving => {
                    odometry.set_pose(Pose {
                        position: Point::new(x, y),
                        heading: Angle::from_deg(deg),
                    });
                }
                Some(Request::Stop) => {
                    executor.halt();
                    driving = false;
                    motors::set(&dp, Wheels::STOP);
                }
                // Not a command: it may have been a stop (`protocol`).
                None => {
                    executor.halt();
                    driving = false;
                    motors::set(&dp, Wheels::STOP);
                    let _ = uwriteln!(out, "ERR");
                    continue;
                }
                Some(Request::Memory) => {
                    let _ = uwriteln!(out, "M stack_peak={}", stack::peak() as u32);
                    continue;
                }
                Some(Request::Sensors) => {
                    // The counts, then what the planner reads from each.
                    let raw = adc::latest();
                    serial::write(b'D');
                    for c in raw {
                        let _ = uwrite!(out, " {}", c as u32);
                    }
                    for f in protocol::sensor_readings(planner.config(), &raw) {
                        serial::write(b' ');
                        match f {
                            SensorField::Number(n) => {
                                let _ = uwrite!(out, "{}", n as u32);
                            }
                            SensorField::Sign(c) => serial::write(c),
                        }
                    }
                    serial::write(b'\n');
                    continue;
                }
                _ => {
                    let _ = uwriteln!(out, "ERR");
                    continue;
                }
            }
            let _ = uwriteln!(out, "OK");
        }

        // Control tick, 1 kHz.
        let now = clock::millis();
        if now == last_ms {
            continue;
        }
        last_ms = now;
        let (l, r) = encoders::take();
        odometry.update(l, r);
        if !driving {
            motors::set(&dp, Wheels::STOP);
            continue;
        }
        let pose = odometry.pose();
        if executor.is_idle() {
            let Ok(raw) = sensors.read_raw() else {
                // The sensors are still warming up: wait, motors off.
                motors::set(&dp, Wheels::STOP);
                continue;
            };
            let (step, cycles) = timed::step(planner, pose, &raw);
            let _ = uwriteln!(
                out,
                "T {} {} {} {} {} {} {} {}",
                now,
                // Two integer widths only (u32, i32): ufmt links one
                // formatter per type, ~220 bytes of flash each.
                pose.position.x as i32,
                pose.position.y as i32,
                pose.heading.0 as u32,
                status_letter(step.status),
                step.command.heading.0 as u32,
                step.command.step_mm as u32,
                cycles
            );
            if step.status != Status::Moving {
                // Arrived, unreachable or a sensor fault: safe stop.
                driving = false;
                motors::set(&dp, Wheels::STOP);
                continue;
            }
            executor.start(step.command);
        }
        // A guard look (it also keeps the flank points) costs about a control
        // tick (`cargo test --release -p rover-tests --test avr_firmware --
        // --nocapture` prints its cycles): run it every GUARD_PERIOD_MS on
        // fresh counts. The sensors themselves update every ~38 ms; the rover
        // covers 1.4 mm in 4 ms at full speed.
        let sweep = adc::sweeps();
        let due = now.wrapping_sub(last_guard_ms) >= GUARD_PERIOD_MS && sweep != last_sweep;
        let wheels = executor.tick(pose, odometry.travelled_mm(), |remaining| {
            if due {
                last_guard_ms = now;
                last_sweep = sweep;
                planner.guard_raw(&adc::latest(), remaining)
            } else {
                Guard::Continue
            }
        });
        motors::set(&dp, wheels);
    }
}
