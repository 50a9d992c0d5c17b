//! Host file access and exit codes through ARM semihosting (handled by QEMU). Test equipment
//! only: semihosting calls stop the core while the host serves them.

use crate::line_feed::{ByteSource, ChannelReader};
use cortex_m_semihosting::{nr, syscall, syscall1};

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

/// Opens the HIL input `hil_input.csv` in QEMU's working directory and locates `channels` in
/// its header, or ends QEMU with exit code 2 (no file) or 3 (no usable header), naming `image`
/// and the channels it needs.
pub fn open_channels<const M: usize>(image: &str, channels: [&'static str; M]) -> ChannelReader<HostFile, M> {
    let Some(file) = HostFile::open("hil_input.csv\0") else {
        cortex_m_semihosting::heprintln!("{}: cannot open hil_input.csv in QEMU's working directory", image);
        exit(2)
    };
    match ChannelReader::new(file, channels) {
        Ok(r) => r,
        Err(e) => {
            cortex_m_semihosting::heprint!("{}: hil_input.csv has no usable header (need", image);
            for c in channels {
                cortex_m_semihosting::heprint!(" {}", c);
            }
            cortex_m_semihosting::heprintln!(")");
            defmt::error!("bad header: {}", e);
            exit(3)
        }
    }
}

/// Defines a QEMU image's panic and HardFault handlers: each prints the image's `name` and the
/// cause over semihosting and ends QEMU with exit code 101 (panic) or 102 (HardFault), so a
/// HIL test fails with a readable message instead of hanging. The image must depend on
/// `cortex-m`, `cortex-m-rt` and `cortex-m-semihosting` (the `qemu` feature brings them).
///
/// ```ignore
/// edgekf_firmware::semihost_fault_handlers!("edgekf-rotor-qemu");
/// ```
#[macro_export]
macro_rules! semihost_fault_handlers {
    ($name:literal) => {
        #[panic_handler]
        fn panic(info: &core::panic::PanicInfo) -> ! {
            ::cortex_m::interrupt::disable();
            ::cortex_m_semihosting::heprintln!(concat!($name, " panicked: {}"), info);
            $crate::semihost::exit(101)
        }

        #[::cortex_m_rt::exception]
        unsafe fn HardFault(frame: &::cortex_m_rt::ExceptionFrame) -> ! {
            ::cortex_m_semihosting::heprintln!(concat!($name, " HardFault: {:?}"), frame);
            $crate::semihost::exit(102)
        }
    };
}
