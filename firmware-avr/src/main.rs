//! # firmware-avr
//!
//! The rover firmware for an ATmega328P (Arduino Uno class) at 16 MHz: five
//! IR sensors sampled in the background, wheel encoders, two motors, the
//! serial port and a watchdog, wired to `planner-core`'s rover application
//! (`planner_core::rover::app`: requests, executor, guard, telemetry, the
//! EAPF planner), the same code the STM32 runs. Pin map in [`board`],
//! serial protocol in `planner_core::rover::protocol`.
//!
//! Board code is a thin register-level layer on `avr-device` (avr-hal is not
//! on crates.io): one module per peripheral.
#![no_std]
#![no_main]
#![feature(abi_avr_interrupt)]
#![feature(asm_experimental_arch)]

mod adc;
mod board;
mod clock;
mod eeprom;
mod encoders;
mod motors;
mod progmem;
mod serial;
mod stack;

use planner_core::rover::app::{self, Board, Rover, RoverConfig, Sweep};
use planner_core::rover::calibration::STORED_BYTES;
use planner_core::rover::drive::Wheels;
use planner_core::rover::protocol::{self, Request};
use planner_core::{AdcProfile, Config, Planner, Point};

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

/// Enable the watchdog: reset after 0.5 s without `wdr`.
fn watchdog_on(dp: &board::Dp) {
    avr_device::interrupt::free(|_| {
        avr_device::asm::wdr();
        dp.WDT.wdtcsr().write(|w| unsafe { w.bits(0x18) }); // WDCE | WDE
        dp.WDT.wdtcsr().write(|w| unsafe { w.bits(0x0d) }); // WDE, 0.5 s
    });
}

/// The Uno's parts, as the rover application sees them.
struct Uno {
    dp: board::Dp,
    /// The ADC's sweep count at the last look.
    last_sweep: u16,
}

impl app::Motors for Uno {
    fn set(&mut self, wheels: Wheels) {
        motors::set(&self.dp, wheels);
    }
}

impl app::Encoders for Uno {
    fn take(&mut self) -> (i16, i16) {
        encoders::take()
    }
}

impl app::Sensors for Uno {
    fn sweep(&mut self) -> Sweep {
        let sweeps = adc::sweeps();
        if sweeps == self.last_sweep {
            return Sweep::Same;
        }
        self.last_sweep = sweeps;
        Sweep::New(adc::latest())
    }
}

impl app::Clock for Uno {
    fn millis(&mut self) -> u32 {
        clock::millis()
    }
    fn cycles(&mut self) -> u32 {
        clock::stamp().cycles()
    }
}

impl app::Serial for Uno {
    fn read(&mut self) -> Option<u8> {
        serial::read()
    }
    fn write(&mut self, b: u8) {
        serial::write(b);
    }
}

impl Board for Uno {
    fn stack_peak(&self) -> Option<u16> {
        Some(stack::peak())
    }
    fn load_calibration(&mut self, bytes: &mut [u8; STORED_BYTES]) -> bool {
        eeprom::read(&self.dp, eeprom::CALIBRATION_AT, bytes);
        true
    }
    fn store_calibration(&mut self, bytes: &[u8; STORED_BYTES]) -> bool {
        eeprom::update(&self.dp, eeprom::CALIBRATION_AT, bytes);
        true
    }
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

    // Used in place (by reference), never moved: a move is a second
    // 1 KB copy on the stack. Built with no configuration, then the
    // default one loaded out of flash over it (see `progmem`): a
    // configuration built as a value was a 480-byte copy on the stack, its
    // deepest point (`tests/src/stack_bound.rs`).
    let mut planner = Planner::new(Config::UNSET, Point::new(0, 0));
    planner.load_config(progmem::load_config);
    let mut rover = Rover::new(
        &mut planner,
        RoverConfig::reference(AdcProfile::AVR_10BIT_5V),
    );
    let mut uno = Uno {
        dp,
        last_sweep: adc::sweeps(),
    };
    rover.load_calibration(&mut uno);
    if let Some(Request::Goal(x, y)) = BUILD_GOAL.and_then(|g| protocol::parse(g.as_bytes())) {
        rover.go(Point::new(x, y));
    }
    serial::write_all(b"READY\n");
    loop {
        avr_device::asm::wdr();
        rover.poll(&mut uno);
    }
}
