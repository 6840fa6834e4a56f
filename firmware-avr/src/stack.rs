//! Peak stack measurement by painting: at start the free RAM between the
//! end of the static data and the stack is filled with a pattern; the
//! deepest byte the stack has overwritten since then marks the peak.

const PAINT: u8 = 0xc5;
const RAM_END: usize = 0x08ff;

extern "C" {
    /// End of .data/.bss/.noinit, from avr-libc's linker script.
    static mut __heap_start: u8;
}

fn heap_start() -> usize {
    core::ptr::addr_of!(__heap_start) as usize
}

fn sp() -> usize {
    // SPL/SPH are memory-mapped at 0x5D/0x5E.
    unsafe { core::ptr::read_volatile(0x5d as *const u16) as usize }
}

/// Paint the free RAM below the current stack pointer (keeping a margin
/// for this function's own frame). Call first thing in `main`.
#[inline(always)]
pub fn paint() {
    let end = sp().saturating_sub(16);
    let mut a = heap_start();
    while a < end {
        unsafe { core::ptr::write_volatile(a as *mut u8, PAINT) };
        a += 1;
    }
}

/// Bytes of stack used at the deepest point so far.
pub fn peak() -> u16 {
    let mut a = heap_start();
    while a <= RAM_END && unsafe { core::ptr::read_volatile(a as *const u8) } == PAINT {
        a += 1;
    }
    (RAM_END + 1 - a) as u16
}
