//! `dictionary_proofs` (under `cfg(kani)`): for every mode of the device, a Kani harness that
//! any write (symbolic index, sub-index, data of up to [`DATA`] bytes, side, NMT state) keeps
//! the dictionary's rules, and one that any read does: the properties of
//! `coforge_stack::od::properties`, which the verification crate also runs on random inputs.

use crate::modes::Modes;
use crate::{Options, dec};
use coforge_spec::model::Device;
use proc_macro2::TokenStream;
use quote::{format_ident, quote};

/// Data bytes a symbolic write carries: every fixed-size entry of up to 4 bytes, one byte
/// more to reach "too long", and strings cut short.
pub const DATA: usize = 5;

/// The value buffer of `coforge_stack::od::properties` (`BUF`): the longest loop of a constant
/// length the harnesses reach.
const READ_BUF: usize = 16;

/// The harnesses' loop bound: Kani unrolls every loop up to it and proves (unwinding
/// assertions) that none runs longer. The loops whose length depends on the symbolic entry are
/// the search of its allowed values, the data bytes and the table's binary searches (fewer
/// steps than the read buffer has bytes for any table of up to 65,536 runs).
fn unwind(device: &Device) -> usize {
    let longest_values = device.objects.iter().flat_map(|o| &o.entries).filter_map(|e| e.values.as_ref().map(Vec::len)).max().unwrap_or(0);
    READ_BUF.max(longest_values).max(DATA) + 1
}

/// The harnesses of the device's dictionary, two per mode (`cargo xtask kani` counts them so:
/// `DICTIONARY_HARNESSES_PER_MODE` in xtask/src/kani.rs). They use kissat, in Kani's bundle,
/// as the bank harnesses do: every dictionary read harness verified with it in 2.5 min at most.
pub fn proofs_module(device: &Device, modes: &Modes, options: &Options) -> TokenStream {
    let stack = &options.stack;
    let unwind = dec(unwind(device) as u64);
    let harnesses = modes.variants.iter().map(|(variant, _)| {
        let name = variant.to_string().to_lowercase();
        let write = format_ident!("write_keeps_the_rules_{}", name);
        let read = format_ident!("read_keeps_the_rules_{}", name);
        let n = dec(DATA as u64);
        quote! {
            /// Any write keeps the dictionary's rules (`prop_write_is_checked`), on this
            /// mode's table over a value image of any bytes (`ImageCells`: the device's
            /// app-backed objects left out; `tests/dictionary_properties.rs` in the
            /// verification crate shows the generated dictionary answers as it does).
            #[kani::proof]
            #[kani::unwind(#unwind)]
            #[kani::solver(kissat)]
            fn #write() {
                let mut cells = image_cells(super::Mode::#variant);
                let data: [u8; #n] = kani::any();
                let len: usize = kani::any_where(|l: &usize| *l <= #n);
                let ctx = #stack::od::AccessContext { nmt: any_state(), can_enabled: kani::any() };
                #stack::od::properties::prop_write_is_checked(&mut cells, kani::any(), kani::any(), &data[..len], any_side(), &ctx);
            }

            /// Any read keeps the dictionary's rules (`prop_read_is_checked`), whatever the
            /// values.
            #[kani::proof]
            #[kani::unwind(#unwind)]
            #[kani::solver(kissat)]
            fn #read() {
                let mut cells = image_cells(super::Mode::#variant);
                #stack::od::properties::prop_read_is_checked(&mut cells, kani::any(), kani::any(), any_side());
            }
        }
    });
    quote! {
        /// Kani harnesses over this dictionary (`cargo kani`; see verification/README.md).
        #[cfg(kani)]
        mod dictionary_proofs {
            /// `mode`'s table over a value image of any bytes.
            fn image_cells(mode: super::Mode) -> #stack::od::properties::ImageCells<{ ::core::mem::size_of::<super::Values>() }> {
                #stack::od::properties::ImageCells::new(super::od::entries(mode), &super::od::LIMITS, kani::any())
            }

            fn any_side() -> #stack::od::Side {
                match kani::any::<u8>() % 3 {
                    0 => #stack::od::Side::Bus,
                    1 => #stack::od::Side::Host,
                    _ => #stack::od::Side::Device,
                }
            }

            fn any_state() -> #stack::od::NmtState {
                match kani::any::<u8>() % 3 {
                    0 => #stack::od::NmtState::PreOperational,
                    1 => #stack::od::NmtState::Operational,
                    _ => #stack::od::NmtState::Stopped,
                }
            }

            #(#harnesses)*
        }
    }
}
