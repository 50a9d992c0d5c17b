//! QEMU image of rotor virtual sensing: the four proximity probes' readings come from the host
//! file `hil_input.csv` (columns `n5_x, n5_y, n32_x, n32_y` in m; others ignored) through
//! semihosting; every sample's disk-node displacements and unbalance forces go out as defmt
//! frames. Exit codes: 0 done, 2 no input file, 3 bad header, 101 panic, 102 HardFault.

#![no_std]
#![no_main]

use cortex_m_rt::entry;
use defmt_semihosting as _;
use edgekf_firmware::rotor::{RotorEstimator, CHANNELS};
use edgekf_firmware::semihost::{exit, open_channels};
use edgekf_firmware::stack;

#[entry]
fn main() -> ! {
    stack::paint();
    let mut reader = open_channels("edgekf-rotor-qemu", CHANNELS);
    let mut est = RotorEstimator::new();
    let (boot_stack, _) = stack::high_water();
    stack::paint();
    let mut k = 0u32;
    while let Some(line) = reader.next_values() {
        let r = est.step(line.ok());
        defmt::info!(
            "rot {=u32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32}",
            k,
            r.disk[0],
            r.disk[1],
            r.disk[2],
            r.disk[3],
            r.force[0],
            r.force[1],
            r.force[2],
            r.force[3],
            r.nis
        );
        k += 1;
    }
    let h = est.health();
    defmt::info!("rotor {=u32} {=u32} {=u32} {=u32}", k, reader.bad_lines(), h.covariance_resets, h.refused_updates);
    let (loop_stack, total) = stack::high_water();
    defmt::info!("stack {=u32} {=u32} {=u32}", boot_stack, loop_stack, total);
    defmt::info!("done");
    exit(0)
}

edgekf_firmware::semihost_fault_handlers!("edgekf-rotor-qemu");
