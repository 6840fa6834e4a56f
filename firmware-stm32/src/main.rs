//! # firmware-stm32
//!
//! The rover firmware for an STM32F411 (Nucleo-F411RE, WeAct Black Pill),
//! running the same `planner-core` as the simulator and the ATmega328P.
//! Two builds:
//!
//! - `board` (default): the real rover — 12-bit ADC on PA0–PA4 through the
//!   core's embedded-hal 0.2 adapter, TIM3 PWM for the motors, TIM4 and TIM2
//!   in encoder mode, USART1, SysTick and the cycle counter, wired to the
//!   core's rover application (`planner_core::rover::app`, the same as the
//!   ATmega328P's); defmt logs over RTT, independent watchdog. Pin map in
//!   [`board`].
//! - `qemu`: for `qemu-system-arm -M netduinoplus2` (an STM32F405, same
//!   Cortex-M4F), which has no RCC, a fake ADC and a cycle counter that
//!   reads 0: no clock set-up, the sensors come from a recorded trace
//!   through the core's scripted source, and each step's command and
//!   SysTick count go out over defmt-semihosting ([`emulated`]).
//!
//! Crates: `cortex-m-rt` (start-up, vector table), `stm32f4xx-hal` pinned at
//! 0.23.0 (its API changes between minors), `defmt` for logs (compact: the
//! strings stay on the host).
#![no_std]
#![no_main]

#[cfg(all(feature = "board", not(feature = "qemu")))]
mod board;
#[cfg(feature = "qemu")]
mod emulated;

#[cfg(all(feature = "board", feature = "qemu"))]
compile_error!("choose one of the features `board` and `qemu` (use --no-default-features)");

/// The planner's configuration, built and checked at compile time
/// (`planner-core`'s builder is a `const fn`): a bad one fails the build,
/// and the image holds the tables, not the code that computes them.
/// The sensors on the rim; with the `set-back` feature, behind it.
pub const CONFIG: planner_core::Config =
    match planner_core::ConfigBuilder::new(planner_core::AdcProfile::STM32_12BIT_3V3)
        .sensors_set_back(cfg!(feature = "set-back"))
        .build()
    {
        Ok(c) => c,
        Err(_) => panic!("the default configuration is refused"),
    };

#[cortex_m_rt::entry]
fn main() -> ! {
    #[cfg(feature = "qemu")]
    emulated::run();
    #[cfg(all(feature = "board", not(feature = "qemu")))]
    board::run();
}
