//! The planner's configuration, built at compile time and kept in program
//! memory.
//!
//! `planner-core`'s builder is a `const fn`: the default configuration is
//! built and checked by the compiler (a bad one fails the build), so the
//! image holds its tables instead of the code that computes them. A
//! constant read at run time would be copied into the 2 KB of RAM by the
//! start-up code; `avr-progmem` keeps it in flash, and [`load_config`] copies
//! it out once, over the planner's own (the benches take a value, [`config`]).

use avr_progmem::progmem;
use core::mem::{size_of, MaybeUninit};
use planner_core::{AdcProfile, Config, ConfigBuilder};

/// The default configuration for the ATmega328P's 10-bit ADC at 5 V, the
/// sensors on the rim (with the `set-back` feature, behind it).
const DEFAULT: Config = match ConfigBuilder::new(AdcProfile::AVR_10BIT_5V)
    .sensors_set_back(cfg!(feature = "set-back"))
    .build()
{
    Ok(c) => c,
    Err(_) => panic!("the default configuration is refused"),
};

progmem! {
    static progmem CONFIG: Config = DEFAULT;
}

/// Copy the configuration's bytes out of flash to `dst`, one at a time:
/// `ProgMem::load` takes at most 255 bytes, and a configuration is larger
/// (five calibration tables).
///
/// # Safety
///
/// `dst` must be valid for writes of `size_of::<Config>()` bytes.
#[inline(always)]
unsafe fn copy_to(dst: *mut u8) {
    let src = CONFIG.as_ptr().cast::<u8>();
    for i in 0..size_of::<Config>() {
        // SAFETY: `src` is the `progmem!` static, a `Config` in program
        // memory, and `i` is within it; the caller vouches for `dst + i`.
        unsafe { dst.add(i).write(avr_progmem::raw::read_byte(src.add(i))) };
    }
}

/// Write the configuration over `into`, in place: a `Config` returned by
/// value would be a 480-byte copy on the stack beside the planner being
/// built, which was the stack's deepest point (`tests/src/stack_bound.rs`).
#[allow(dead_code)] // the firmware's; the benches take a value
#[inline(always)]
pub fn load_config(into: &mut Config) {
    // SAFETY: `into` is a whole `Config`. Every byte written is one of a
    // valid `Config` (a `Copy` type of integers and `bool`s), and nothing
    // reads `*into` before all are.
    unsafe { copy_to((into as *mut Config).cast()) }
}

/// The configuration as a value, for the benches.
#[allow(dead_code)] // the benches'; the firmware loads it in place
#[inline(always)]
pub fn config() -> Config {
    let mut out = MaybeUninit::<Config>::uninit();
    // SAFETY: `out` has room for a `Config`; once every byte of a valid
    // `Config` (a `Copy` type) is copied in, it is one.
    unsafe {
        copy_to(out.as_mut_ptr().cast());
        out.assume_init()
    }
}
