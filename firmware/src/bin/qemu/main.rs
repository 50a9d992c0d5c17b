//! QEMU image (`qemu-system-arm -M netduinoplus2`): the real ADXL355 driver and main loop on a
//! virtual ADXL355 whose samples come from the host file `hil_input.csv` (semihosting, relative
//! to QEMU's working directory). Estimates and health go out as defmt frames on semihosting
//! stdout; plain-text errors on stderr. Exit codes: 0 done, 2 no input file, 3 bad header,
//! 4 sensor or model failed to start, 101 panic, 102 HardFault.

#![no_std]
#![no_main]

use cortex_m_rt::entry;
use cortex_m_semihosting::heprintln;
use defmt_semihosting as _;
use edgekf_firmware::line_feed::LineFeed;
use edgekf_firmware::node::{Node, NodeConfig};
use edgekf_firmware::semihost::{exit, HostFile};
use edgekf_firmware::stack;
use edgekf_firmware::virtual_adxl355::VirtualAdxl355;

const INPUT: &str = "hil_input.csv\0";

#[entry]
fn main() -> ! {
    stack::paint();
    let Some(file) = HostFile::open(INPUT) else {
        heprintln!("edgekf-qemu: cannot open hil_input.csv in QEMU's working directory");
        defmt::error!("no input file");
        exit(2)
    };
    let feed = match LineFeed::new(file) {
        Ok(f) => f,
        Err(e) => {
            heprintln!("edgekf-qemu: hil_input.csv has no usable header (need t,ax,ay,az)");
            defmt::error!("bad header: {}", e);
            exit(3)
        }
    };
    let config = NodeConfig::default();
    let mut node = match Node::start(VirtualAdxl355::new(feed), config) {
        Ok(n) => n,
        Err((e, _bus)) => {
            heprintln!("edgekf-qemu: node failed to start");
            defmt::error!("start failed: {}", e);
            exit(4)
        }
    };
    defmt::info!("start odr={=f32} watermark={=u8}", config.sensor.odr.hz(), config.sensor.fifo_watermark);
    // Start-up (model discretisation and Riccati solve in f64) is the deepest part; measure it,
    // then repaint so the end-of-run figure is the steady loop's own.
    let (boot_stack, _) = stack::high_water();
    stack::paint();
    // One watermark period per poll, until the data has run out and the FIFO is drained.
    while node.bus_mut().advance_period() > 0 || !node.bus().is_exhausted() {
        let r = node.poll();
        defmt::info!(
            "blk {=u32} {=u16} {=u16} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32}",
            r.block,
            r.read,
            r.missing,
            r.displacement,
            r.velocity,
            r.force_cos,
            r.force_sin,
            r.force_amplitude,
            r.innovation_rms,
            r.nis_mean
        );
    }
    let h = node.health();
    defmt::info!(
        "health {=u32} {=u32} {=u32} {=u32} {=u32} {=u32} {=u32} {=u32} {=u32} {=u32} {=u32}",
        h.blocks,
        h.samples,
        h.bus_errors,
        h.nacks,
        h.recovered,
        h.failed_polls,
        h.fifo_overruns,
        h.skipped_entries,
        h.saturated,
        h.stuck,
        h.bridged
    );
    let e = node.estimator_counters();
    defmt::info!(
        "estimator {=u32} {=u32} {=u32} {=u32} {=u32}",
        e.steps,
        e.missing,
        e.gated,
        e.filter.covariance_resets,
        e.filter.refused_updates
    );
    let bus = node.bus();
    let v = bus.counters();
    defmt::info!(
        "feed {=u32} {=u32} {=u32}",
        bus.feed().lines(),
        bus.feed().bad_lines(),
        bus.feed().columns().ignored() as u32
    );
    defmt::info!("virtual {=u32} {=u32} {=u32}", v.samples_loaded, v.nacks_sent, v.overrun_entries);
    let (loop_stack, total) = stack::high_water();
    defmt::info!("stack {=u32} {=u32} {=u32}", boot_stack, loop_stack, total);
    defmt::info!("done");
    exit(0)
}

edgekf_firmware::semihost_fault_handlers!("edgekf-qemu");
