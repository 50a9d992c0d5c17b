//! QEMU image of underwater-vehicle thruster health: the vehicle's channels (see
//! [`UuvImage`]) come from the host file `hil_input.csv` through semihosting; see
//! `edgekf_firmware::semihost` for the skeleton and exit codes.

#![no_std]
#![no_main]

use edgekf_firmware::systems::uuv::UuvImage;

edgekf_firmware::qemu_image!(UuvImage);
