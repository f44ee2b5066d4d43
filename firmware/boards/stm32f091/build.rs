//! The STM32F091RC's memory map: 256 KiB of flash at 0x0800_0000, 32 KiB of SRAM.

include!("../memory_x.rs");

fn main() {
    write_memory_x(0x0800_0000, 256, 32);
}
