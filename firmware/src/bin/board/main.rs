//! STM32F411 board image: ADXL355 on I2C1 (PB8 = SCL, PB9 = SDA, 400 kHz, address 0x1D with
//! ASEL low), core at 84 MHz from the internal oscillator, defmt over RTT (probe-rs).
//!
//! One poll per FIFO watermark period (16 samples at 1 kHz = 16 ms), paced by SysTick. The
//! loop never ends; a failed start is reported and retried every second.

#![no_std]
#![no_main]

use cortex_m_rt::{entry, exception, ExceptionFrame};
use defmt_rtt as _;
use edgekf_firmware::adxl355::Adxl355;
use edgekf_firmware::stack;
use edgekf_firmware::systems::oscillator::{self, NodeConfig};
use stm32f4xx_hal::i2c::{DutyCycle, I2c, Mode};
use stm32f4xx_hal::rcc::Config;
use stm32f4xx_hal::{pac, prelude::*};

#[entry]
fn main() -> ! {
    stack::paint();
    let (Some(dp), Some(cp)) = (pac::Peripherals::take(), cortex_m::peripheral::Peripherals::take()) else {
        defmt::error!("peripherals already taken");
        halt()
    };
    let mut rcc = dp.RCC.freeze(Config::hsi().sysclk(84.MHz()));
    let gpiob = dp.GPIOB.split(&mut rcc);
    let mut delay = cp.SYST.delay(&rcc.clocks);
    let i2c = I2c::new(dp.I2C1, (gpiob.pb8, gpiob.pb9), Mode::fast(400.kHz(), DutyCycle::Ratio2to1), &mut rcc);

    let config = NodeConfig::default();
    let sensor = config.source.sensor;
    let period_us = (1.0e6 * sensor.fifo_watermark as f32 / 3.0 / sensor.odr.hz()) as u32;
    let mut adxl = Adxl355::new_i2c(i2c, config.address);
    let mut node = loop {
        match oscillator::start(adxl, &config) {
            Ok(node) => break node,
            Err((e, back)) => {
                defmt::error!("start failed: {}; retrying in 1 s", defmt::Debug2Format(&e));
                delay.delay_ms(1000);
                adxl = back;
            }
        }
    };
    defmt::info!("edgekf board: odr={=f32} Hz, poll every {=u32} us", sensor.odr.hz(), period_us);
    loop {
        delay.delay_us(period_us);
        // The oscillator reports every poll.
        let Some(r) = node.poll() else { continue };
        defmt::info!(
            "blk {=u32} amp={=f32} N x={=f32} m irms={=f32} nis={=f32}",
            r.block,
            r.force_amplitude,
            r.displacement,
            r.innovation_rms,
            r.nis_mean
        );
        if r.block % 64 == 0 {
            let (used, total) = stack::high_water();
            defmt::info!("health {} stack {=u32}/{=u32} B", node.health(), used, total);
        }
    }
}

fn halt() -> ! {
    loop {
        cortex_m::asm::wfi();
    }
}

// Under the no-panic proof, `panic-never` supplies the handler.
#[cfg(not(feature = "no-panic-proof"))]
#[panic_handler]
fn panic(_info: &core::panic::PanicInfo) -> ! {
    defmt::error!("panic");
    cortex_m::asm::udf()
}

#[exception]
unsafe fn HardFault(_frame: &ExceptionFrame) -> ! {
    defmt::error!("HardFault");
    cortex_m::asm::udf()
}
