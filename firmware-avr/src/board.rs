//! Pin map and wiring of the Arduino Uno class rover (ATmega328P, 16 MHz).
//!
//! | Uno pin | AVR pin | use |
//! |---|---|---|
//! | A0–A4 | PC0–PC4 (ADC0–4) | IR sensors at −40°, −20°, 0°, +20°, +40° (A0 = rightmost) |
//! | D6 | PD6 (OC0A) | left motor PWM → TB6612FNG PWMA (L298N ENA) |
//! | D7, D8 | PD7, PB0 | left motor direction → AIN1, AIN2 (IN1, IN2) |
//! | D5 | PD5 (OC0B) | right motor PWM → PWMB (ENB) |
//! | D9, D10 | PB1, PB2 | right motor direction → BIN1, BIN2 (IN3, IN4) |
//! | D4 | PD4 | driver standby (TB6612FNG STBY; high = enabled) |
//! | D2 | PD2 (INT0) | left wheel encoder, one channel, rising edges |
//! | D3 | PD3 (INT1) | right wheel encoder, one channel, rising edges |
//! | D0, D1 | PD0, PD1 (USART0) | serial: commands in, telemetry out, 115,200 8N1 |
//!
//! The sensors need 5 V and a 10 µF capacitor each near the connector (the
//! GP2Y0A21 draws current in bursts). AREF is AVCC (5 V): the core's
//! `AdcProfile::AVR_10BIT_5V` calibration assumes it.

/// CPU clock, Hz.
pub const F_CPU: u32 = 16_000_000;

pub type Dp = avr_device::atmega328p::Peripherals;

/// The peripherals, for interrupt handlers and the panic handler, which
/// cannot be handed the owned singleton. Each register block is only
/// touched by one part of the firmware (see the module docs).
pub fn steal() -> Dp {
    // SAFETY: register access is partitioned by module: ADC only in `adc`,
    // TC0/PORT direction pins only in `motors`, EXINT only in `encoders`,
    // TC1/TC2 only in `clock`, USART0 only in `serial`.
    unsafe { Dp::steal() }
}

/// Port B/D direction bits for the outputs above.
pub const DDRB_OUT: u8 = 0b0000_0111; // PB0, PB1, PB2
pub const DDRD_OUT: u8 = 0b1111_0010; // PD1 (TX), PD4, PD5, PD6, PD7
