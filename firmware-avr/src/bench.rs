//! What the bench binaries (`f32-step`, `costs`) share: start the clock
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

/// Timers and serial on, the control tick off; the default configuration.
pub fn start() -> Config {
    let Some(dp) = board::Dp::take() else { halt() };
    clock::init(&dp);
    clock::stop_tick(&dp);
    serial::init(&dp);
    // SAFETY: every shared static is behind an interrupt-free Mutex.
    unsafe { avr_device::interrupt::enable() };
    progmem::config()
}
