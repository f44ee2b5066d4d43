//! The STM32F091RC's memory map: 256 KiB of flash at 0x0800_0000, 32 KiB of SRAM. The image
//! links into the first 240 KiB: the last 16 KiB (0x0803_C000) hold CANopenIA's configuration
//! files (`coforge_board_stm32f0::config_flash`).

include!("../memory_x.rs");

fn main() {
    write_memory_x(0x0800_0000, 240, 32);
}
