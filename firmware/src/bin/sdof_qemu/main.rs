//! QEMU image of the base-excited mount (feature `sdof`, a test system): the real ADXL355
//! driver and main loop on a virtual ADXL355 fed from the host file `hil_input.csv`; see
//! [`SdofImage`] for its frames and `edgekf_firmware::semihost` for the skeleton and exit codes.

#![no_std]
#![no_main]

use edgekf_firmware::systems::sdof::SdofImage;

edgekf_firmware::qemu_image!(SdofImage);
