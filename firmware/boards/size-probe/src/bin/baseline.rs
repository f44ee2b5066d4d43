//! The runtime alone: what every image pays before any device code.
#![no_std]
#![no_main]

use panic_halt as _;

#[cortex_m_rt::entry]
fn main() -> ! {
    loop {
        core::hint::black_box(0_u8);
    }
}
