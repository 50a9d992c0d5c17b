//! QEMU image of rotor virtual sensing: the four proximity probes' readings come from the host
//! file `hil_input.csv` (columns `n5_x, n5_y, n32_x, n32_y` in m; others ignored) through
//! semihosting; see [`RotorImage`] for its frames and `edgekf_firmware::semihost` for the
//! skeleton and exit codes.

#![no_std]
#![no_main]

use edgekf_firmware::systems::rotor::RotorImage;

edgekf_firmware::qemu_image!(RotorImage);
