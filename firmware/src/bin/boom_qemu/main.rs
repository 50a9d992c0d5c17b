//! QEMU image of boom tip vibration: the boom's channels (see [`BoomImage`]) come from the host
//! file `hil_input.csv` through semihosting; see `edgekf_firmware::semihost` for the skeleton
//! and exit codes.

#![no_std]
#![no_main]

use edgekf_firmware::systems::boom::BoomImage;

edgekf_firmware::qemu_image!(BoomImage);
