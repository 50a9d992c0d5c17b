//! QEMU image of rotor virtual sensing: the four proximity probes' readings come from the host
//! file `hil_input.csv` (columns `n5_x, n5_y, n32_x, n32_y` in m; others ignored) through
//! semihosting; every sample's disk-node displacements and unbalance forces go out as defmt
//! frames. Exit codes: 0 done, 2 no input file, 3 bad header, 101 panic, 102 HardFault.

#![no_std]
#![no_main]

use cortex_m_rt::entry;
use cortex_m_semihosting::heprintln;
use defmt_semihosting as _;
use edgekf_firmware::line_feed::ChannelReader;
use edgekf_firmware::rotor::{RotorEstimator, CHANNELS};
use edgekf_firmware::semihost::{exit, HostFile};
use edgekf_firmware::stack;

#[entry]
fn main() -> ! {
    stack::paint();
    let Some(file) = HostFile::open("hil_input.csv\0") else {
        heprintln!("edgekf-rotor-qemu: cannot open hil_input.csv in QEMU's working directory");
        exit(2)
    };
    let mut reader = match ChannelReader::new(file, CHANNELS) {
        Ok(r) => r,
        Err(e) => {
            heprintln!("edgekf-rotor-qemu: hil_input.csv has no usable header (need n5_x, n5_y, n32_x, n32_y)");
            defmt::error!("bad header: {}", e);
            exit(3)
        }
    };
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
