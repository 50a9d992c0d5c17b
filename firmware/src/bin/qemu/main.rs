//! QEMU image (`qemu-system-arm -M netduinoplus2`): the real ADXL355 driver and main loop on a
//! virtual ADXL355 whose samples come from the host file `hil_input.csv` (semihosting, relative
//! to QEMU's working directory); see [`OscillatorImage`] for its frames and
//! `edgekf_firmware::semihost` for the skeleton and exit codes.

#![no_std]
#![no_main]

use edgekf_firmware::systems::oscillator::OscillatorImage;

edgekf_firmware::qemu_image!(OscillatorImage);
