//! Host file access, exit codes and the QEMU images' entry skeleton, through ARM semihosting
//! (handled by QEMU). Test equipment only: semihosting calls stop the core while the host
//! serves them.
//!
//! Every QEMU image is [`qemu_image!`](crate::qemu_image!) over its system's
//! [`HilImage`]: paint the stack, open `hil_input.csv`, start, measure start-up's stack and
//! repaint, run ([`crate::hil::run`]), then the `stack` and `done` frames and exit 0. Exit
//! codes: 2 no input file, 3 no usable header, 4 the sensor or estimator did not start, 101
//! panic, 102 HardFault.

use crate::frame::{Defmt, Done, FrameSink, StackFrame};
use crate::hil::{HilError, HilImage};
use crate::line_feed::ByteSource;
use crate::stack;
use cortex_m_semihosting::{heprint, heprintln, nr, syscall, syscall1};

/// An open host file.
pub struct HostFile(usize);

impl HostFile {
    /// Opens `path` (NUL-terminated, relative to QEMU's working directory) for binary reading.
    pub fn open(path: &str) -> Option<Self> {
        if !path.ends_with('\0') {
            return None;
        }
        // SAFETY: SYS_OPEN reads `path.len() - 1` bytes from a valid, NUL-terminated string.
        let fd = unsafe { syscall!(OPEN, path.as_ptr(), nr::open::R_BINARY, path.len() - 1) } as isize;
        (fd >= 0).then_some(HostFile(fd as usize))
    }
}

impl ByteSource for HostFile {
    fn read_bytes(&mut self, buf: &mut [u8]) -> usize {
        // SAFETY: SYS_READ writes at most `buf.len()` bytes into `buf`; it returns the number of
        // bytes NOT read.
        let not_read = unsafe { syscall!(READ, self.0, buf.as_mut_ptr(), buf.len()) };
        buf.len().saturating_sub(not_read)
    }
}

impl Drop for HostFile {
    fn drop(&mut self) {
        // SAFETY: closes a handle this value owns.
        unsafe {
            syscall!(CLOSE, self.0);
        }
    }
}

/// Ends the QEMU process with `code` (SYS_EXIT_EXTENDED, so any code, not just 0/1).
pub fn exit(code: u32) -> ! {
    let block = [0x20026u32, code]; // ADP_Stopped_ApplicationExit
                                    // SAFETY: SYS_EXIT_EXTENDED reads the two-word parameter block.
    unsafe {
        syscall1(0x20, block.as_ptr() as usize);
    }
    loop {
        cortex_m::asm::wfi();
    }
}

/// The HIL input, in QEMU's working directory.
const INPUT: &str = "hil_input.csv\0";

/// A QEMU image's whole run (see the module docs); never returns.
pub fn run_image<I: HilImage>() -> !
where
    I::StartError: defmt::Format,
{
    stack::paint();
    let Some(file) = HostFile::open(INPUT) else {
        heprintln!("{}: cannot open hil_input.csv in QEMU's working directory", I::NAME);
        defmt::error!("no input file");
        exit(2)
    };
    let mut storage = I::STORAGE;
    // Matched by reference: the node stays where `start` built it (moving it out of the
    // `Result` would put a second copy of it, several KB for the rotor, on this frame).
    let mut started = I::start(file, &mut storage);
    let node = match &mut started {
        Ok(node) => node,
        Err(HilError::Header(e)) => {
            heprint!("{}: hil_input.csv has no usable header (need", I::NAME);
            for c in I::COLUMNS {
                heprint!(" {}", c);
            }
            heprintln!(")");
            defmt::error!("bad header: {}", e);
            exit(3)
        }
        Err(HilError::Start(e)) => {
            heprintln!("{}: the node did not start", I::NAME);
            defmt::error!("start failed: {}", e);
            exit(4)
        }
    };
    I::started(node, &mut Defmt);
    // Start-up (the compiled-in model's set-up, the header) is measured on its own, then the
    // stack is repainted so that the end-of-run figure is the main loop's own.
    let (boot, _) = stack::high_water();
    stack::paint();
    crate::hil::run::<I, _>(node, &mut Defmt);
    let (used, total) = stack::high_water();
    Defmt.frame(&StackFrame { boot, used, total });
    Defmt.frame(&Done {});
    exit(0)
}

/// Defines a QEMU image: its entry point ([`run_image`] over the [`HilImage`] `$image`) and its
/// fault handlers. The binary must depend on `cortex-m`, `cortex-m-rt` and
/// `cortex-m-semihosting` (the `qemu` feature brings them); the defmt logger is this module's.
///
/// ```ignore
/// edgekf_firmware::qemu_image!(edgekf_firmware::systems::rotor::RotorImage);
/// ```
#[macro_export]
macro_rules! qemu_image {
    ($image:ty) => {
        #[::cortex_m_rt::entry]
        fn main() -> ! {
            $crate::semihost::run_image::<$image>()
        }

        $crate::semihost_fault_handlers!(<$image as $crate::hil::HilImage>::NAME);
    };
}

/// Defines a QEMU image's panic and HardFault handlers: each prints the image's `name` and the
/// cause over semihosting and ends QEMU with exit code 101 (panic) or 102 (HardFault), so a
/// HIL test fails with a readable message instead of hanging. The image must depend on
/// `cortex-m`, `cortex-m-rt` and `cortex-m-semihosting` (the `qemu` feature brings them).
///
/// ```ignore
/// edgekf_firmware::semihost_fault_handlers!("edgekf-bench");
/// ```
#[macro_export]
macro_rules! semihost_fault_handlers {
    ($name:expr) => {
        // Under the no-panic proof, `panic-never` supplies the handler.
        #[cfg(not(feature = "no-panic-proof"))]
        #[panic_handler]
        fn panic(info: &core::panic::PanicInfo) -> ! {
            ::cortex_m::interrupt::disable();
            ::cortex_m_semihosting::heprintln!("{} panicked: {}", $name, info);
            $crate::semihost::exit(101)
        }

        #[::cortex_m_rt::exception]
        unsafe fn HardFault(frame: &::cortex_m_rt::ExceptionFrame) -> ! {
            ::cortex_m_semihosting::heprintln!("{} HardFault: {:?}", $name, frame);
            $crate::semihost::exit(102)
        }
    };
}

/// The QEMU images' defmt global logger: defmt frames to semihosting stdout, as
/// `defmt-semihosting` writes them, but without its panics (a frame begun inside another, by a
/// defmt call in a `Format` impl, is dropped; an unpaired call is ignored), so that the images
/// pass the no-panic proof.
mod logger {
    use core::cell::UnsafeCell;
    use core::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
    use cortex_m::register::primask;
    use cortex_m_semihosting::hio::{hstdout, HostStream};

    #[defmt::global_logger]
    struct Logger;

    /// The encoder, its output and the interrupt state to restore; only touched between
    /// `acquire` and `release`, with interrupts off.
    struct State {
        encoder: defmt::Encoder,
        out: Option<HostStream>,
        interrupts_were_on: bool,
    }

    struct Shared {
        taken: AtomicBool,
        /// Frames begun while `taken`, being dropped.
        nested: AtomicUsize,
        state: UnsafeCell<State>,
    }

    // SAFETY: `state` is accessed only by the holder of `taken`, with interrupts disabled, on a
    // single core.
    unsafe impl Sync for Shared {}

    static SHARED: Shared = Shared {
        taken: AtomicBool::new(false),
        nested: AtomicUsize::new(0),
        state: UnsafeCell::new(State { encoder: defmt::Encoder::new(), out: None, interrupts_were_on: false }),
    };

    fn emit(out: &mut Option<HostStream>, bytes: &[u8]) {
        if let Some(h) = out {
            let _ = h.write_all(bytes);
        }
    }

    // SAFETY: frames are serialised by `taken` with interrupts disabled.
    unsafe impl defmt::Logger for Logger {
        fn acquire() {
            let interrupts_were_on = primask::read().is_active();
            cortex_m::interrupt::disable();
            if SHARED.taken.load(Ordering::Relaxed) {
                // Re-entered: the outer frame keeps the logger (and interrupts off), this one
                // is dropped.
                let n = SHARED.nested.load(Ordering::Relaxed);
                SHARED.nested.store(n.wrapping_add(1), Ordering::Relaxed);
                return;
            }
            SHARED.taken.store(true, Ordering::Relaxed);
            // SAFETY: we hold `taken` with interrupts disabled.
            let s = unsafe { &mut *SHARED.state.get() };
            s.interrupts_were_on = interrupts_were_on;
            if s.out.is_none() {
                s.out = hstdout().ok();
            }
            let State { encoder, out, .. } = s;
            encoder.start_frame(|b| emit(out, b));
        }

        unsafe fn flush() {}

        unsafe fn release() {
            let n = SHARED.nested.load(Ordering::Relaxed);
            if n != 0 {
                SHARED.nested.store(n - 1, Ordering::Relaxed);
                return;
            }
            if !SHARED.taken.load(Ordering::Relaxed) {
                return;
            }
            // SAFETY: we hold `taken` with interrupts disabled.
            let s = unsafe { &mut *SHARED.state.get() };
            let State { encoder, out, interrupts_were_on } = s;
            encoder.end_frame(|b| emit(out, b));
            let restore = *interrupts_were_on;
            SHARED.taken.store(false, Ordering::Relaxed);
            if restore {
                // SAFETY: restores the state `acquire` found.
                unsafe { cortex_m::interrupt::enable() }
            }
        }

        unsafe fn write(bytes: &[u8]) {
            if !SHARED.taken.load(Ordering::Relaxed) || SHARED.nested.load(Ordering::Relaxed) != 0 {
                return;
            }
            // SAFETY: we hold `taken` with interrupts disabled.
            let s = unsafe { &mut *SHARED.state.get() };
            let State { encoder, out, .. } = s;
            encoder.write(bytes, |b| emit(out, b));
        }
    }
}
