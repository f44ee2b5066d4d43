//! canopenia: what its generated code costs in flash (see `src/probe.rs`): its node and serial codecs.
#![no_std]
#![no_main]

use coforge_stack::node::Node;
use coforge_stack::od::NoAppObjects;
use coforge_stack::store::NoStore;
use core::hint::black_box;
use panic_halt as _;

#[cortex_m_rt::entry]
fn main() -> ! {
    // In .bss (a `MaybeUninit` static), so the size report shows its static RAM and no copy
    // of it in flash.
    let node = Node::of_dictionary(black_box(canopenia::Mode::ALL[0]), black_box(1), NoAppObjects, NoStore);
    let Some(node) = cortex_m::singleton!(: canopenia::Node<NoAppObjects, NoStore> = node) else {
        loop {
            cortex_m::asm::wfi()
        }
    };
    probe::run_with_codec::<_, canopenia::serial::Codec>(node)
}
