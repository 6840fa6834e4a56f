//! USART0 at 115,200 baud 8N1 (U2X, UBRR 16: 2.1 % error, within the
//! receiver's tolerance). Received bytes go into a 64-byte queue from the
//! receive interrupt, so nothing is lost while the planner runs; sending is
//! blocking (a telemetry line takes about 4 ms).

use crate::board::{steal, Dp, F_CPU};
use avr_device::interrupt::{self, Mutex};
use core::cell::RefCell;
use heapless::Deque;

static RX: Mutex<RefCell<Deque<u8, 64>>> = Mutex::new(RefCell::new(Deque::new()));

const RXC0: u8 = 1 << 7;
const UDRE0: u8 = 1 << 5;
const U2X0: u8 = 1 << 1;
const RXCIE0: u8 = 1 << 7;
const RXEN0: u8 = 1 << 4;
const TXEN0: u8 = 1 << 3;
const EIGHT_N_1: u8 = 0b0000_0110;

/// Enable receiver (with interrupt) and transmitter.
pub fn init(dp: &Dp) {
    dp.USART0.ucsr0a().write(|w| unsafe { w.bits(U2X0) });
    // Double speed: UBRR = F_CPU / (8 · baud) − 1 = 16.4 → 16.
    const UBRR: u16 = (F_CPU / (8 * 115_200) - 1) as u16;
    dp.USART0.ubrr0().write(|w| unsafe { w.bits(UBRR) });
    dp.USART0.ucsr0c().write(|w| unsafe { w.bits(EIGHT_N_1) });
    dp.USART0
        .ucsr0b()
        .write(|w| unsafe { w.bits(RXCIE0 | RXEN0 | TXEN0) });
}

#[avr_device::interrupt(atmega328p)]
fn USART_RX() {
    let dp = steal();
    while dp.USART0.ucsr0a().read().bits() & RXC0 != 0 {
        let b = dp.USART0.udr0().read().bits();
        // A full queue drops the byte: the line parser then reports an error.
        interrupt::free(|cs| {
            if let Ok(mut q) = RX.borrow(cs).try_borrow_mut() {
                let _ = q.push_back(b);
            }
        });
    }
}

/// The next received byte, if any.
pub fn read() -> Option<u8> {
    interrupt::free(|cs| RX.borrow(cs).try_borrow_mut().ok()?.pop_front())
}

/// The next received byte, waiting for it (resetting the watchdog).
#[allow(dead_code)] // the replay and bench binaries'
pub fn read_blocking() -> u8 {
    loop {
        if let Some(b) = read() {
            return b;
        }
        avr_device::asm::wdr();
    }
}

/// A little-endian `u16` from the next two bytes (blocking).
#[allow(dead_code)] // the replay and bench binaries'
pub fn read_u16_le() -> u16 {
    let lo = read_blocking() as u16;
    lo | (read_blocking() as u16) << 8
}

/// Send bytes.
pub fn write_all(bytes: &[u8]) {
    for &b in bytes {
        write(b);
    }
}

/// Send one byte.
pub fn write(b: u8) {
    let dp = steal();
    while dp.USART0.ucsr0a().read().bits() & UDRE0 == 0 {}
    dp.USART0.udr0().write(|w| unsafe { w.bits(b) });
}
