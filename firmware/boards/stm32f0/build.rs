//! The STM32F042K6's memory map: 32 KiB of flash at 0x0800_0000, 6 KiB of SRAM.

include!("../memory_x.rs");

fn main() {
    write_memory_x(0x0800_0000, 32, 6);
}
