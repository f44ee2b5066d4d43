//! The STM32F042K6's memory map: 32 KiB of flash at 0x0800_0000, 6 KiB of SRAM. Built for
//! another chip (feature `stm32f091` or `stm32f072`: this crate as the library of
//! `firmware/boards/stm32f091` or `firmware/boards/stm32f072`) it writes none: that crate's
//! build script writes its chip's, and a second `memory.x` on the link search path would
//! compete with it.

include!("../memory_x.rs");

fn main() {
    if std::env::var_os("CARGO_FEATURE_STM32F042").is_some() {
        write_memory_x(0x0800_0000, 32, 6);
    } else {
        println!("cargo:rerun-if-changed=build.rs");
    }
}
