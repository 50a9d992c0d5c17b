//! Stack high-water mark by painting: fill the free RAM between the end of static data and the
//! current stack pointer with a pattern at boot, and later find the deepest word the stack
//! overwrote. Measures what the run actually used (interrupts included), not a static bound.

use core::ptr::{addr_of, read_volatile, write_volatile};

const PATTERN: u32 = 0xC0FF_EE55;
/// Bytes below the current stack pointer left unpainted (the painting function's own frame).
const MARGIN: usize = 64;

extern "C" {
    // Provided by cortex-m-rt's link.x: end of .bss/.uninit, and the initial stack pointer.
    static __sheap: u32;
    static _stack_start: u32;
}

fn bounds() -> (usize, usize) {
    // Only the addresses of the linker symbols are taken; nothing is read through them.
    (addr_of!(__sheap) as usize, addr_of!(_stack_start) as usize)
}

/// Paints the unused stack. Call first thing in `main`.
#[inline(never)]
pub fn paint() {
    let sp: usize;
    // SAFETY: reads the stack pointer register, no memory access.
    unsafe { core::arch::asm!("mov {}, sp", out(reg) sp) };
    let (bottom, _) = bounds();
    let mut p = (bottom + 3) & !3;
    while p + 4 <= sp.saturating_sub(MARGIN) {
        // SAFETY: [bottom, sp − MARGIN) is RAM between static data and the live stack, owned by
        // nobody yet (no heap in this firmware).
        unsafe { write_volatile(p as *mut u32, PATTERN) };
        p += 4;
    }
}

/// `(used, total)` stack bytes: the deepest extent reached so far and the space available.
pub fn high_water() -> (u32, u32) {
    let (bottom, top) = bounds();
    let mut p = (bottom + 3) & !3;
    // SAFETY: reads RAM inside [bottom, top), all of it mapped.
    while p < top && unsafe { read_volatile(p as *const u32) } == PATTERN {
        p += 4;
    }
    ((top - p) as u32, (top - bottom) as u32)
}
