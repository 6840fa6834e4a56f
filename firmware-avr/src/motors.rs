//! Two DC motors on a TB6612FNG (or L298N): Timer0 fast PWM at 7.8 kHz on
//! OC0A (left) and OC0B (right), two direction pins per motor. A duty of
//! zero sets both direction pins low (driver output off) and disconnects
//! the PWM pin, so a stopped motor gets no pulse at all.

use crate::board::Dp;
use crate::encoders;
use planner_core::rover::drive::Wheels;

const COM0A1: u8 = 1 << 7;
const COM0B1: u8 = 1 << 5;
const FAST_PWM: u8 = 0b11;
const CS_DIV8: u8 = 0b010;
const STBY: u8 = 1 << 4; // PD4
const AIN1: u8 = 1 << 7; // PD7
const AIN2: u8 = 1 << 0; // PB0
const BIN1: u8 = 1 << 1; // PB1
const BIN2: u8 = 1 << 2; // PB2

/// Configure the timer and pins; motors off, driver enabled.
pub fn init(dp: &Dp) {
    dp.TC0.tccr0a().write(|w| unsafe { w.bits(FAST_PWM) });
    dp.TC0.tccr0b().write(|w| unsafe { w.bits(CS_DIV8) });
    set(dp, Wheels::STOP);
    dp.PORTD
        .portd()
        .modify(|r, w| unsafe { w.bits(r.bits() | STBY) });
}

/// Apply wheel duties (−255 … 255).
pub fn set(dp: &Dp, wheels: Wheels) {
    let (l, r) = (wheels.left.clamp(-255, 255), wheels.right.clamp(-255, 255));
    dp.TC0
        .ocr0a()
        .write(|w| unsafe { w.bits(l.unsigned_abs() as u8) });
    dp.TC0
        .ocr0b()
        .write(|w| unsafe { w.bits(r.unsigned_abs() as u8) });
    let mut com = FAST_PWM;
    if l != 0 {
        com |= COM0A1;
    }
    if r != 0 {
        com |= COM0B1;
    }
    dp.TC0.tccr0a().write(|w| unsafe { w.bits(com) });
    let pd = if l > 0 { AIN1 } else { 0 };
    let pb =
        if l < 0 { AIN2 } else { 0 } | if r > 0 { BIN1 } else { 0 } | if r < 0 { BIN2 } else { 0 };
    dp.PORTD
        .portd()
        .modify(|rd, w| unsafe { w.bits((rd.bits() & !AIN1 & !(1 << 6) & !(1 << 5)) | pd) });
    dp.PORTB
        .portb()
        .modify(|rd, w| unsafe { w.bits((rd.bits() & !(AIN2 | BIN1 | BIN2)) | pb) });
    encoders::set_directions(l.signum() as i8, r.signum() as i8);
}
