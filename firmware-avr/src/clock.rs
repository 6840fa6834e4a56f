//! Time: Timer2 gives a 1 kHz control tick (CTC, 16 MHz / 64 / 250), and
//! Timer1 runs free at the CPU clock as a cycle counter for measuring the
//! planner step (its overflow interrupt extends it to 32 bits).

use crate::board::{steal, Dp};
use avr_device::interrupt::{self, Mutex};
use core::cell::Cell;

static MILLIS: Mutex<Cell<u32>> = Mutex::new(Cell::new(0));
static OVERFLOWS: Mutex<Cell<u16>> = Mutex::new(Cell::new(0));

/// Start both timers.
pub fn init(dp: &Dp) {
    dp.TC2.tccr2a().write(|w| unsafe { w.bits(0b10) }); // CTC
    dp.TC2.ocr2a().write(|w| unsafe { w.bits(249) });
    dp.TC2.tccr2b().write(|w| unsafe { w.bits(0b100) }); // clk/64
    dp.TC2.timsk2().write(|w| unsafe { w.bits(0b10) }); // OCIE2A
    dp.TC1.tccr1a().write(|w| unsafe { w.bits(0) });
    dp.TC1.tccr1b().write(|w| unsafe { w.bits(0b001) }); // clk/1
    dp.TC1.timsk1().write(|w| unsafe { w.bits(0b1) }); // TOIE1
}

/// Stop the control tick (replay mode).
pub fn stop_tick(dp: &Dp) {
    dp.TC2.timsk2().write(|w| unsafe { w.bits(0) });
}

/// Restart the control tick.
pub fn start_tick(dp: &Dp) {
    dp.TC2.timsk2().write(|w| unsafe { w.bits(0b10) });
}

#[avr_device::interrupt(atmega328p)]
fn TIMER2_COMPA() {
    interrupt::free(|cs| {
        let m = MILLIS.borrow(cs);
        m.set(m.get().wrapping_add(1));
    });
}

#[avr_device::interrupt(atmega328p)]
fn TIMER1_OVF() {
    interrupt::free(|cs| {
        let o = OVERFLOWS.borrow(cs);
        o.set(o.get().wrapping_add(1));
    });
}

/// Milliseconds since start.
pub fn millis() -> u32 {
    interrupt::free(|cs| MILLIS.borrow(cs).get())
}

/// CPU cycles since start (wraps after 268 s), exact.
pub fn cycles() -> u32 {
    interrupt::free(|cs| {
        let dp = steal();
        let mut ovf = OVERFLOWS.borrow(cs).get();
        let mut lo = dp.TC1.tcnt1().read().bits();
        // An overflow pending but not yet serviced belongs to this count.
        if dp.TC1.tifr1().read().bits() & 1 != 0 {
            lo = dp.TC1.tcnt1().read().bits();
            ovf = ovf.wrapping_add(1);
        }
        ((ovf as u32) << 16) | lo as u32
    })
}
