//! The planner's configuration, built at compile time and kept in program
//! memory.
//!
//! `planner-core`'s builder is a `const fn`: the default configuration is
//! built and checked by the compiler (a bad one fails the build), so the
//! image holds its tables instead of the code that computes them. A
//! constant read at run time would be copied into the 2 KB of RAM by the
//! start-up code; `avr-progmem` keeps it in flash, and [`config`] copies it
//! out once, into the planner.

use avr_progmem::progmem;
use core::mem::{size_of, MaybeUninit};
use planner_core::{AdcProfile, Config, ConfigBuilder};

/// The default configuration for the ATmega328P's 10-bit ADC at 5 V.
const DEFAULT: Config = match ConfigBuilder::new(AdcProfile::AVR_10BIT_5V).build() {
    Ok(c) => c,
    Err(_) => panic!("the default configuration is refused"),
};

progmem! {
    static progmem CONFIG: Config = DEFAULT;
}

/// The configuration, read out of flash byte by byte: `ProgMem::load` takes
/// at most 255 bytes, and a configuration is larger (five calibration
/// tables).
#[inline(always)]
pub fn config() -> Config {
    let mut out = MaybeUninit::<Config>::uninit();
    let src = CONFIG.as_ptr().cast::<u8>();
    let dst = out.as_mut_ptr().cast::<u8>();
    for i in 0..size_of::<Config>() {
        // SAFETY: `src` is the `progmem!` static, a `Config` in program
        // memory, and `i` is within it; `dst + i` is within `out`.
        unsafe { dst.add(i).write(avr_progmem::raw::read_byte(src.add(i))) };
    }
    // SAFETY: every byte of `out` was copied from a valid `Config`, a
    // `Copy` type.
    unsafe { out.assume_init() }
}
