//! Wheel encoders on INT0 (left) and INT1 (right): one channel each, rising
//! edges counted. A single channel cannot tell direction, so each tick
//! counts in the direction the motor was last driven (a coasting wheel
//! keeps its sign) — the usual choice on hobby rovers with one-channel
//! encoders.

use crate::board::Dp;
use avr_device::interrupt::{self, Mutex};
use core::cell::Cell;

static COUNTS: Mutex<Cell<(i16, i16)>> = Mutex::new(Cell::new((0, 0)));
static DIRS: Mutex<Cell<(i8, i8)>> = Mutex::new(Cell::new((1, 1)));

/// Rising edges on INT0 and INT1, both enabled.
pub fn init(dp: &Dp) {
    dp.EXINT.eicra().write(|w| unsafe { w.bits(0b1111) });
    dp.EXINT.eifr().write(|w| unsafe { w.bits(0b11) });
    dp.EXINT.eimsk().write(|w| unsafe { w.bits(0b11) });
}

/// Record the commanded directions (0 keeps the last sign).
pub fn set_directions(left: i8, right: i8) {
    interrupt::free(|cs| {
        let d = DIRS.borrow(cs);
        let (mut l, mut r) = d.get();
        if left != 0 {
            l = left;
        }
        if right != 0 {
            r = right;
        }
        d.set((l, r));
    });
}

/// Ticks since the last call (left, right), signed.
pub fn take() -> (i16, i16) {
    interrupt::free(|cs| COUNTS.borrow(cs).replace((0, 0)))
}

#[avr_device::interrupt(atmega328p)]
fn INT0() {
    interrupt::free(|cs| {
        let c = COUNTS.borrow(cs);
        let (l, r) = c.get();
        c.set((l.wrapping_add(DIRS.borrow(cs).get().0 as i16), r));
    });
}

#[avr_device::interrupt(atmega328p)]
fn INT1() {
    interrupt::free(|cs| {
        let c = COUNTS.borrow(cs);
        let (l, r) = c.get();
        c.set((l, r.wrapping_add(DIRS.borrow(cs).get().1 as i16)));
    });
}
