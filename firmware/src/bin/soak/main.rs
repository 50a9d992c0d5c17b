//! The numerical soak on the Cortex-M4F under QEMU: the soaks of `edgekf_firmware::soak`, the
//! very code the host soak runs, for as many steps as the host file `hil_input.csv` asks (one
//! line per soak, `name steps`), each reported as a `soak` frame, then `done`. The HIL test
//! compares the frames bit for bit with the host's run of the same soaks and steps.
//!
//! Exit codes: 2 no input file, 3 no soak named in it, 101 panic, 102 HardFault.

#![no_std]
#![no_main]

use edgekf_firmware::frame::{Defmt, Done, FrameSink, StackFrame};
use edgekf_firmware::line_feed::ByteSource;
use edgekf_firmware::semihost::{exit, HostFile};
use edgekf_firmware::{soak, stack};

/// The plan's largest size, bytes.
const PLAN: usize = 1024;

#[cortex_m_rt::entry]
fn main() -> ! {
    stack::paint();
    let Some(mut file) = HostFile::open("hil_input.csv\0") else {
        cortex_m_semihosting::heprintln!("edgekf-soak: cannot open hil_input.csv in QEMU's working directory");
        exit(2)
    };
    let mut plan = [0u8; PLAN];
    let mut len = 0;
    while let Some(rest) = plan.get_mut(len..) {
        let n = file.read_bytes(rest);
        if n == 0 {
            break;
        }
        len = len.saturating_add(n);
    }
    let mut ran = 0u32;
    soak::parse_plan(plan.get(..len).unwrap_or(&[]), |index, steps| {
        if let Some(frame) = soak::run(index, steps) {
            Defmt.frame(&frame);
            ran = ran.saturating_add(1);
        }
    });
    if ran == 0 {
        cortex_m_semihosting::heprintln!("edgekf-soak: hil_input.csv names no soak (lines `name steps`)");
        exit(3)
    }
    let (used, total) = stack::high_water();
    Defmt.frame(&StackFrame { boot: 0, used, total });
    Defmt.frame(&Done {});
    exit(0)
}

edgekf_firmware::semihost_fault_handlers!("edgekf-soak");
