//! The lm3s6965's memory map: 256 KiB of flash at 0, 64 KiB of SRAM.

include!("../memory_x.rs");

fn main() {
    write_memory_x(0, 256, 64);
}
