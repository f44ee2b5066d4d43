//! The STM32F072CB's memory map: 128 KiB of flash at 0x0800_0000, 16 KiB of SRAM at
//! 0x2000_0000 (DS9826, RM0091). The image links into the whole of both.

include!("../memory_x.rs");

fn main() {
    write_memory_x(0x0800_0000, 128, 16);
}
