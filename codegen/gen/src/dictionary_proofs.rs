//! `dictionary_proofs` (under `cfg(kani)`): Kani harnesses that every access keeps the
//! dictionary's rules, the properties of `coforge_stack::od::properties`, which the
//! verification crate also runs on random inputs.
//!
//! Writes are split by object: per mode, one harness per object the mode's table lists (its
//! index concrete, or any of its copies; sub-index, data of up to [`DATA`] bytes, side, NMT
//! state and node-ID symbolic), and one for every index and sub-index the table lacks.
//! Together they cover any write. Why not one harness with a symbolic index: the value a
//! write reaches is then a pointer into any field of the dictionary, and CBMC models every
//! read and write through it against all of them (13 GB for CO401Memory1 alone). With the
//! object fixed, the lookup and the dispatch fold to constants. Reads stay one harness per
//! mode: they change nothing and verify whole.

use crate::entries::listed_objects;
use crate::modes::Modes;
use crate::{Options, dec, hex};
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

/// How many harnesses [`proofs_module`] emits for `device`: per mode, a write harness per
/// listed object, one for missing entries and a read harness (`cargo xtask kani` checks that
/// Kani lists as many).
pub fn harness_count(device: &Device) -> usize {
    let modes = Modes::of(device);
    modes.variants.iter().map(|(_, mode)| listed_objects(device, mode.as_deref()).len() + 2).sum()
}

/// The harnesses of the device's dictionary.
pub fn proofs_module(device: &Device, modes: &Modes, options: &Options) -> TokenStream {
    let stack = &options.stack;
    let unwind = dec(unwind(device) as u64);
    let harnesses = modes.variants.iter().map(|(variant, mode)| {
        let name = variant.to_string().to_lowercase();
        let objects = listed_objects(device, mode.as_deref()).into_iter().map(|(index, copies)| {
            let harness = format_ident!("write_keeps_the_rules_{}_{:04x}", name, index);
            let doc = match copies {
                0 => format!(" Any write to {index:04X}h keeps the dictionary's rules."),
                n => format!(" Any write to {index:04X}h..{:04X}h keeps the dictionary's rules.", u32::from(index) + u32::from(n)),
            };
            let (index, copies) = (hex(index.into(), 4), dec(copies.into()));
            quote! {
                #[doc = #doc]
                #[kani::proof]
                #[kani::unwind(#unwind)]
                fn #harness() {
                    write_object(super::Mode::#variant, #index, #copies);
                }
            }
        });
        let missing = format_ident!("write_keeps_the_rules_{}_missing", name);
        let read = format_ident!("read_keeps_the_rules_{}", name);
        quote! {
            #(#objects)*

            /// Any write to an index or sub-index the table lacks is refused as missing.
            #[kani::proof]
            #[kani::unwind(#unwind)]
            fn #missing() {
                write_missing(super::Mode::#variant);
            }

            /// Any read keeps the dictionary's rules (`prop_read_is_checked`).
            #[kani::proof]
            #[kani::unwind(#unwind)]
            fn #read() {
                let mut od = super::Od::new(super::Mode::#variant, any_node_id(), #stack::od::NoAppObjects);
                #stack::od::properties::prop_read_is_checked(&mut od, kani::any(), kani::any(), any_side());
            }
        }
    });
    let n = dec(DATA as u64);
    quote! {
        /// Kani harnesses over this dictionary (`cargo kani`; see verification/README.md).
        #[cfg(kani)]
        mod dictionary_proofs {
            use #stack::od::EntryAccess;

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

            fn any_node_id() -> u8 {
                kani::any_where(|id: &u8| (1..=127).contains(id))
            }

            /// `prop_write_is_checked` for any write (sub-index, data, side, NMT state, CAN
            /// enabled or not) to `od` at `index`.
            fn any_write<D: EntryAccess>(od: &mut D, index: u16, sub: u8) {
                let data: [u8; #n] = kani::any();
                let len: usize = kani::any_where(|l: &usize| *l <= #n);
                let ctx = #stack::od::AccessContext { nmt: any_state(), can_enabled: kani::any() };
                #stack::od::properties::prop_write_is_checked(od, index, sub, &data[..len], any_side(), &ctx);
            }

            /// Any write to the object at `first` or one of its `copies`, in `mode`.
            fn write_object(mode: super::Mode, first: u16, copies: u16) {
                let index = first + kani::any_where(|k: &u16| *k <= copies);
                let mut od = super::Od::new(mode, any_node_id(), #stack::od::NoAppObjects);
                any_write(&mut od, index, kani::any());
            }

            /// The tables of `mode` without the values: what a write the lookup refuses
            /// reaches of the dictionary, since `EntryAccess::write` looks the entry up
            /// before anything else.
            struct Lookup(super::Mode, #stack::od::NoAppObjects);

            impl EntryAccess for Lookup {
                type App = #stack::od::NoAppObjects;

                fn entries(&self) -> &'static [#stack::od::EntryInfo] {
                    super::od::entries(self.0)
                }

                fn limits(&self) -> &'static [#stack::od::Limits] {
                    &[]
                }

                fn field(&mut self, _: &#stack::od::EntryInfo, _: u8) -> Option<&mut dyn #stack::value::OdValue> {
                    None
                }

                fn app(&mut self) -> &mut Self::App {
                    &mut self.1
                }
            }

            /// Any write to an index or sub-index `mode`'s table lacks.
            fn write_missing(mode: super::Mode) {
                let mut od = Lookup(mode, #stack::od::NoAppObjects);
                let (index, sub): (u16, u8) = (kani::any(), kani::any());
                kani::assume(od.entry(index, sub).is_err());
                any_write(&mut od, index, sub);
            }

            #(#harnesses)*
        }
    }
}
