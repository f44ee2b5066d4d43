//! `pdo::rpdos(mode)` / `pdo::tpdos(mode)`: the default PDOs of each mode.

use crate::Options;
use crate::modes::Modes;
use coforge_spec::model::{Device, Pdo, PdoDir, in_mode};
use proc_macro2::TokenStream;
use quote::{format_ident, quote};

fn pdo_tokens(p: &Pdo, stack: &TokenStream) -> TokenStream {
    let number = crate::dec(p.number.into());
    // Validation guarantees `constant + $NODEID` or a constant that fits 32 bits.
    let offset = p.cob_id.node_id_offset().ok().flatten();
    let base = offset.or_else(|| p.cob_id.eval(&Default::default(), None).ok()).unwrap_or(0);
    let base = crate::hex(u64::try_from(base).unwrap_or(0), 8);
    let plus_node_id = offset.is_some();
    let (tt, inhibit, event, sync) =
        (crate::dec(p.transmission_type.into()), crate::dec(p.inhibit_time.into()), crate::dec(p.event_timer.into()), crate::dec(p.sync_start.into()));
    let mapping = p.map.iter().map(|m| crate::hex(m.encoded().into(), 8));
    let bits = p.map.iter().map(|m| crate::dec(m.bits.into()));
    let message = format!("{}{} maps more than 64 bits", p.dir.name(), p.number);
    quote! {
        {
            // Backstop for the spec check `pdo-mapping-size`.
            const _: () = assert!(0 #(+ #bits)* <= 64, #message);
            #stack::pdo::PdoDefault {
                number: #number,
                cob_id: #stack::pdo::CobIdDefault { base: #base, plus_node_id: #plus_node_id },
                transmission_type: #tt,
                inhibit_time: #inhibit,
                event_timer: #event,
                sync_start: #sync,
                mapping: &[#(#mapping),*],
            }
        }
    }
}

pub fn pdo_module(d: &Device, modes: &Modes, options: &Options) -> TokenStream {
    let stack = &options.stack;
    let mut statics = Vec::new();
    let mut selects = Vec::new();
    for (dir, fname) in [(PdoDir::Rx, "rpdos"), (PdoDir::Tx, "tpdos")] {
        let per_mode: Vec<Vec<TokenStream>> = modes
            .variants
            .iter()
            .map(|(_, mode)| d.pdo.pdos.iter().filter(|p| p.dir == dir && in_mode(&p.modes, mode.as_deref())).map(|p| pdo_tokens(p, stack)).collect())
            .collect();
        let (tables, select) = modes.tables(&fname.to_uppercase(), &quote!(#stack::pdo::PdoDefault), &per_mode);
        statics.extend(tables);
        let f = format_ident!("{}", fname);
        let doc = format!("The default {}s of `mode`, by number.", dir.name());
        selects.push(quote! {
            #[doc = #doc]
            pub fn #f(mode: Mode) -> &'static [#stack::pdo::PdoDefault] { #select }
        });
    }
    // Runtime PDO slots per direction: the most communication objects of one direction in a mode.
    let slots = modes
        .variants
        .iter()
        .flat_map(|(_, mode)| [PdoDir::Rx, PdoDir::Tx].map(|dir| d.pdo.pdos.iter().filter(|p| p.dir == dir && in_mode(&p.modes, mode.as_deref())).count()))
        .max()
        .unwrap_or(0);
    let slots = crate::dec(slots as u64);
    quote! {
        /// Default PDO configuration, generated from the spec.
        pub mod pdo {
            use super::Mode;
            /// PDOs per direction the node keeps state for.
            pub const SLOTS: usize = #slots;
            #(#statics)*
            #(#selects)*
        }
    }
}
