//! What the bench binaries (`replay`, `f32-step`, `costs`) share: start the clock
//! and the serial line with interrupts on, no control tick, and the default
//! configuration; stop (spin) where the firmware would have nothing to do.

use crate::{board, clock, progmem, serial};
use planner_core::Config;

/// Spin for ever (a bench has no motors to stop).
pub fn halt() -> ! {
    loop {
        avr_device::asm::nop();
    }
}

/// Timers and serial on, the control tick off.
pub fn init() {
    let Some(dp) = board::Dp::take() else { halt() };
    clock::init(&dp);
    clock::stop_tick(&dp);
    serial::init(&dp);
    // SAFETY: every shared static is behind an interrupt-free Mutex.
    unsafe { avr_device::interrupt::enable() };
}

/// [`init`], and the default configuration as a value.
#[allow(dead_code)] // the benches'; `replay` loads it in place
pub fn start() -> Config {
    init();
    progmem::config()
}

/// The serial port as a `ufmt` writer, for the benches' text lines.
pub struct Serial;

impl ufmt::uWrite for Serial {
    type Error = core::convert::Infallible;
    fn write_str(&mut self, s: &str) -> Result<(), Self::Error> {
        serial::write_all(s.as_bytes());
        Ok(())
    }
}
