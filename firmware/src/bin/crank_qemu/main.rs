//! QEMU image of slider-crank joint-clearance estimation: the crank angular acceleration
//! (`crank_alpha`, rad/s², 10 kHz; other columns ignored) comes from the host file
//! `hil_input.csv` through semihosting; see [`CrankImage`] for its frames and
//! `edgekf_firmware::semihost` for the skeleton and exit codes.

#![no_std]
#![no_main]

use edgekf_firmware::systems::crank::CrankImage;

edgekf_firmware::qemu_image!(CrankImage);
