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

/// Stop the control tick (the replay and bench binaries).
#[allow(dead_code)] // not the firmware's
pub fn stop_tick(dp: &Dp) {
    dp.TC2.timsk2().write(|w| unsafe { w.bits(0) });
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

/// A raw reading of the cycle counter, resolved by [`Stamp::cycles`]
/// after a timed span: the reading runs the same instructions whatever the
/// counter holds, so that every span costs the same (the resolution
/// branches on the value, and would put 6 or 7 cycles into a span).
#[derive(Clone, Copy)]
pub struct Stamp {
    lo: u16,
    pending: u8,
    overflows: u16,
}

/// Read the cycle counter (interrupts on or off).
pub fn stamp() -> Stamp {
    interrupt::free(|cs| {
        let dp = steal();
        // Counter first, then the overflow flag: see `Stamp::cycles`.
        let lo = dp.TC1.tcnt1().read().bits();
        let pending = dp.TC1.tifr1().read().bits();
        let overflows = OVERFLOWS.borrow(cs).get();
        Stamp {
            lo,
            pending,
            overflows,
        }
    })
}

impl Stamp {
    /// CPU cycles since start (wraps after 268 s), exact. An overflow
    /// pending but not yet serviced belongs to the count if the counter
    /// was read after it (low), not just before it (high): with interrupts
    /// off one pending overflow is counted this way, so a span timed with
    /// interrupts off must stay below 65,536 cycles.
    pub fn cycles(self) -> u32 {
        let late = self.pending & 1 != 0 && self.lo < 0x8000;
        let ovf = self.overflows.wrapping_add(u16::from(late));
        ((ovf as u32) << 16) | self.lo as u32
    }
}
