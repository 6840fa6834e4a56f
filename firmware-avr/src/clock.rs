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
    /// Timer1's flags read just before and just after the counter.
    before: u8,
    after: u8,
    overflows: u16,
}

/// Read the cycle counter (interrupts on or off).
pub fn stamp() -> Stamp {
    interrupt::free(|cs| {
        let dp = steal();
        // The overflow flag on both sides of the counter: see
        // `Stamp::cycles`.
        let before = dp.TC1.tifr1().read().bits();
        let lo = dp.TC1.tcnt1().read().bits();
        let after = dp.TC1.tifr1().read().bits();
        let overflows = OVERFLOWS.borrow(cs).get();
        Stamp {
            lo,
            before,
            after,
            overflows,
        }
    })
}

impl Stamp {
    /// CPU cycles since start (wraps after 268 s), exact with one overflow
    /// pending and not yet serviced, as there is at most in a span timed
    /// with interrupts off below 65,536 cycles ([`arm_lap`] says whether it
    /// was). Pending before the counter was read, the overflow belongs to
    /// the count; raised between the two flag reads, it does if the counter
    /// was read after it (low), not just before it (high).
    pub fn cycles(self) -> u32 {
        // In bits, without a branch: the same cycles whatever the values
        // (the profiler's check that a timed step is the step,
        // `tests/tests/avr_profile.rs`, counts this call). TOV1 is bit 0.
        let low = ((self.lo >> 15) as u8) ^ 1;
        let late = (self.before | (self.after & low)) & 1;
        let ovf = self.overflows.wrapping_add(u16::from(late));
        ((ovf as u32) << 16) | self.lo as u32
    }
}

/// Timer1's compare flag A, which [`arm_lap`] uses.
const OCF1A: u8 = 1 << 1;

/// Arm the lap flag for a span timed with interrupts off: [`lapped`] is
/// true once the counter has come round to where it is now, 65,536 cycles
/// on (less the few of this call), after which one pending overflow no
/// longer tells how many there were. Timer1 runs in normal mode, where
/// `OCR1A` takes a write at once; the flag is cleared after the write,
/// once the counter is past it.
#[allow(dead_code)] // the replay binary's
pub fn arm_lap() {
    let dp = steal();
    let now = dp.TC1.tcnt1().read().bits();
    dp.TC1.ocr1a().write(|w| unsafe { w.bits(now) });
    // A flag is cleared by writing one to it.
    dp.TC1.tifr1().write(|w| unsafe { w.bits(OCF1A) });
}

/// Whether the counter has come round since [`arm_lap`].
#[allow(dead_code)] // the replay binary's
pub fn lapped() -> bool {
    steal().TC1.tifr1().read().bits() & OCF1A != 0
}
