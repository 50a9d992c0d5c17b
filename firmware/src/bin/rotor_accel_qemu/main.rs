//! QEMU image of rotor virtual sensing from accelerometers: two virtual ADXL355s (x and y at
//! node 5, x and y at node 32) fed from the host file `hil_input.csv` (columns `n5_ax, n5_ay,
//! n32_ax, n32_ay` in m/s²; others ignored) through semihosting, read through the driver in
//! FIFO blocks; see [`RotorAccelImage`] for its frames and `edgekf_firmware::semihost` for the
//! skeleton and exit codes.

#![no_std]
#![no_main]

use edgekf_firmware::systems::rotor::accel::RotorAccelImage;

edgekf_firmware::qemu_image!(RotorAccelImage);
