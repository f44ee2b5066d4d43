//! The linker script for a 128 KiB-flash, 32 KiB-RAM Cortex-M0 (the STM32F091 class): room for
//! the largest device, CANopenIA with its manager and engines. The probe measures; whether an
//! image fits its chip is `cargo xtask dist`'s check against each board's real map.

include!("../memory_x.rs");

fn main() {
    write_memory_x(0x0800_0000, 128, 32);
}
