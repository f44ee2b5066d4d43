//! The linker script for a 64 KiB-flash, 8 KiB-RAM Cortex-M0.

include!("../memory_x.rs");

fn main() {
    write_memory_x(0x0800_0000, 64, 8);
}
