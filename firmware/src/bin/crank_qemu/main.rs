//! QEMU image of slider-crank joint-clearance estimation: the crank angular acceleration
//! (`crank_alpha`, rad/s², 10 kHz; other columns ignored) comes from the host file
//! `hil_input.csv` through semihosting; after every 0.25 s window the joint and clearance for the
//! recording so far go out as defmt frames, and the whole recording's at the end. Lines that do
//! not parse or hold a non-finite value are skipped and counted.
//!
//! Frames: per window `win <window> <lines> <joint 0|1|2> <clearance m> <scores A B C>
//! <clearance per joint A B C>`; at the end `feat <the ten ln-features>`, `crank <joint>
//! <clearance> <scores> <per joint> <windows> <lines> <skipped> <bad lines>`, `stack <start-up>
//! <loop> <available>` (bytes), `done`.
//! Exit codes: 0 done, 2 no input file, 3 bad header, 4 estimator failed to start, 101 panic,
//! 102 HardFault.

#![no_std]
#![no_main]

use cortex_m_rt::entry;
use cortex_m_semihosting::heprintln;
use defmt_semihosting as _;
use edgekf_firmware::crank::{release_law, CrankNode, Storage, CHANNELS, WINDOW};
use edgekf_firmware::semihost::{exit, open_channels};
use edgekf_firmware::stack;

#[entry]
fn main() -> ! {
    stack::paint();
    let mut reader = open_channels("edgekf-crank-qemu", CHANNELS);
    let mut storage: Storage = [0.0; WINDOW - 1];
    let mut node = match CrankNode::new(&mut storage) {
        Ok(n) => n,
        Err(e) => {
            heprintln!("edgekf-crank-qemu: the estimator did not start");
            defmt::error!("start failed: {}", e);
            exit(4)
        }
    };
    let (boot_stack, _) = stack::high_water();
    stack::paint();
    while let Some(line) = reader.next_values() {
        if let Some(r) = node.step(line.ok().map(|[a]| a)) {
            let e = r.estimate;
            defmt::info!(
                "win {=u32} {=u32} {=u8} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=u8}",
                r.window,
                r.samples,
                e.joint as u8,
                e.clearance,
                e.scores[0],
                e.scores[1],
                e.scores[2],
                e.per_joint[0],
                e.per_joint[1],
                e.per_joint[2],
                release_law(&e)
            );
        }
    }
    let f = node.features();
    defmt::info!(
        "feat {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32}",
        f[0],
        f[1],
        f[2],
        f[3],
        f[4],
        f[5],
        f[6],
        f[7],
        f[8],
        f[9]
    );
    let e = node.estimate();
    defmt::info!(
        "crank {=u8} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=u8} {=u32} {=u32} {=u32} {=u32}",
        e.joint as u8,
        e.clearance,
        e.scores[0],
        e.scores[1],
        e.scores[2],
        e.per_joint[0],
        e.per_joint[1],
        e.per_joint[2],
        release_law(&e),
        node.windows(),
        node.samples(),
        node.skipped(),
        reader.bad_lines()
    );
    let (loop_stack, total) = stack::high_water();
    defmt::info!("stack {=u32} {=u32} {=u32}", boot_stack, loop_stack, total);
    defmt::info!("done");
    exit(0)
}

edgekf_firmware::semihost_fault_handlers!("edgekf-crank-qemu");
