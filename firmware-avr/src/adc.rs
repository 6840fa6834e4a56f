//! Interrupt-driven sampling of the five IR channels in the background: the
//! conversion-complete interrupt stores the result, moves the multiplexer to
//! the next channel and starts the next conversion. One sweep of the five
//! takes 5 × 13 ADC clocks at 125 kHz = 520 µs, much faster than the sensors
//! update (38 ms), so no blocking averaging is needed.

use crate::board::{steal, Dp};
use avr_device::interrupt::{self, Mutex};
use core::cell::Cell;
use planner_core::{RawCounts, SENSOR_COUNT};

/// Latest counts per channel, and how many full sweeps have completed.
static LATEST: Mutex<Cell<RawCounts>> = Mutex::new(Cell::new([0; SENSOR_COUNT]));
static SWEEPS: Mutex<Cell<u16>> = Mutex::new(Cell::new(0));
static CHANNEL: Mutex<Cell<u8>> = Mutex::new(Cell::new(0));

const REFS_AVCC: u8 = 1 << 6;
const ADEN: u8 = 1 << 7;
const ADSC: u8 = 1 << 6;
const ADIE: u8 = 1 << 3;
const ADPS_128: u8 = 0b111;

/// Start sampling channel 0 onwards.
pub fn start(dp: &Dp) {
    dp.ADC.didr0().write(|w| unsafe { w.bits(0x1f) });
    dp.ADC.admux().write(|w| unsafe { w.bits(REFS_AVCC) });
    dp.ADC
        .adcsra()
        .write(|w| unsafe { w.bits(ADEN | ADSC | ADIE | ADPS_128) });
}

#[avr_device::interrupt(atmega328p)]
fn ADC() {
    let dp = steal();
    let value = dp.ADC.adc().read().bits();
    interrupt::free(|cs| {
        let ch = CHANNEL.borrow(cs).get();
        let mut all = LATEST.borrow(cs).get();
        all[ch as usize % SENSOR_COUNT] = value;
        LATEST.borrow(cs).set(all);
        let next = if ch as usize + 1 >= SENSOR_COUNT {
            let s = SWEEPS.borrow(cs);
            s.set(s.get().wrapping_add(1));
            0
        } else {
            ch + 1
        };
        CHANNEL.borrow(cs).set(next);
        dp.ADC
            .admux()
            .write(|w| unsafe { w.bits(REFS_AVCC | next) });
    });
    dp.ADC
        .adcsra()
        .write(|w| unsafe { w.bits(ADEN | ADSC | ADIE | ADPS_128) });
}

/// Number of completed sweeps (wraps): a changed value means fresh counts.
pub fn sweeps() -> u16 {
    interrupt::free(|cs| SWEEPS.borrow(cs).get())
}

/// The latest counts of all five channels, read atomically.
pub fn latest() -> RawCounts {
    interrupt::free(|cs| LATEST.borrow(cs).get())
}
