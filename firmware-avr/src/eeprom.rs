//! The ATmega328P's 1 KB EEPROM: the sensors' calibration, kept over power
//! cycles (`planner_core::rover::calibration`).

use crate::board::Dp;
use avr_device::interrupt;

/// Where the stored calibration starts.
pub const CALIBRATION_AT: u16 = 0;

/// Wait for the last write to finish (3.4 ms each on the chip).
fn idle(dp: &Dp) {
    while dp.EEPROM.eecr().read().eepe().bit_is_set() {
        avr_device::asm::wdr();
    }
}

/// The byte at `at`.
fn read_byte(dp: &Dp, at: u16) -> u8 {
    idle(dp);
    dp.EEPROM.eear().write(|w| unsafe { w.bits(at) });
    dp.EEPROM.eecr().write(|w| w.eere().set_bit());
    dp.EEPROM.eedr().read().bits()
}

/// Fill `out` from `at` on.
pub fn read(dp: &Dp, at: u16, out: &mut [u8]) {
    for (a, b) in (at..).zip(out.iter_mut()) {
        *b = read_byte(dp, a);
    }
}

/// Write `bytes` from `at` on, each only if it differs (a write takes
/// 3.4 ms and wears the cell).
pub fn update(dp: &Dp, at: u16, bytes: &[u8]) {
    for (a, &b) in (at..).zip(bytes.iter()) {
        if read_byte(dp, a) == b {
            continue;
        }
        dp.EEPROM.eedr().write(|w| unsafe { w.bits(b) });
        // EEMPE, then EEPE within four cycles (the datasheet's timed
        // sequence, §8.6.3): two `sbi`s on EECR (I/O 0x1f), no interrupt
        // between them.
        interrupt::free(|_| unsafe {
            core::arch::asm!("sbi 0x1f, 2", "sbi 0x1f, 1");
        });
    }
    idle(dp);
}
