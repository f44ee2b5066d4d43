//! `emcy::emergencies(mode)`: the spec's emergencies as the stack's `EmcyDefault`, one
//! constant per emergency so device code raises them by name, and `emcy::by_name` /
//! `emcy::name_of` for hosts (the names are only in images that call these).

use crate::Options;
use crate::modes::Modes;
use coforge_spec::model::{Device, Emergency, NmtEffect, in_mode};
use proc_macro2::TokenStream;
use quote::{format_ident, quote};

fn emergency(e: &Emergency, stack: &TokenStream) -> TokenStream {
    let code = crate::hex(e.code.into(), 4);
    let register = crate::hex(e.error_register.into(), 2);
    // Bytes the spec marks as varying (`xx`) start as zero; the device fills them in.
    let manufacturer = e.manufacturer.map(|b| crate::hex(b.unwrap_or(0).into(), 2));
    let reaction = match e.nmt {
        NmtEffect::None => quote!(None),
        NmtEffect::ErrorBehavior => quote!(ErrorBehaviour),
        NmtEffect::PreOperational => quote!(PreOperational),
        NmtEffect::Stopped => quote!(Stopped),
    };
    let event = match e.event {
        Some(ev) => {
            let v = format_ident!("{}", format!("{ev:?}"));
            quote!(Some(#stack::emcy::EmcyEvent::#v))
        }
        None => quote!(None),
    };
    let enabled_by = match e.enabled_by {
        Some(i) => {
            let i = crate::hex(i.into(), 4);
            quote!(Some(#i))
        }
        None => quote!(None),
    };
    quote! {
        #stack::emcy::EmcyDefault {
            code: #code,
            register: #register,
            manufacturer: [#(#manufacturer),*],
            reaction: #stack::emcy::Reaction::#reaction,
            event: #event,
            enabled_by: #enabled_by,
        }
    }
}

pub fn emcy_module(d: &Device, modes: &Modes, options: &Options) -> TokenStream {
    let stack = &options.stack;
    // One constant per distinct name; a name defined per mode keeps its first definition.
    let mut seen = std::collections::BTreeSet::new();
    let consts: Vec<TokenStream> = d
        .emergencies
        .iter()
        .filter(|e| seen.insert(e.name.clone()))
        .map(|e| {
            let c = format_ident!("{}", e.name.to_uppercase());
            let doc = format!(" {:04X}h: {}", e.code, e.description);
            let value = emergency(e, stack);
            quote!(#[doc = #doc] pub const #c: #stack::emcy::EmcyDefault = #value;)
        })
        .collect();
    let per_mode: Vec<Vec<TokenStream>> = modes
        .variants
        .iter()
        .map(|(_, mode)| d.emergencies.iter().filter(|e| in_mode(&e.modes, mode.as_deref())).map(|e| emergency(e, stack)).collect())
        .collect();
    let (statics, select) = modes.tables("EMCY", &quote!(#stack::emcy::EmcyDefault), &per_mode);
    // The spec names, in the order of each mode's table.
    let names: Vec<Vec<TokenStream>> = modes
        .variants
        .iter()
        .map(|(_, mode)| {
            d.emergencies
                .iter()
                .filter(|e| in_mode(&e.modes, mode.as_deref()))
                .map(|e| {
                    let name = &e.name;
                    quote!(#name)
                })
                .collect()
        })
        .collect();
    let (name_statics, select_names) = modes.tables("NAMES", &quote!(&str), &names);
    quote! {
        /// The spec's emergencies.
        pub mod emcy {
            use super::Mode;
            #(#consts)*
            #(#statics)*
            #(#name_statics)*
            /// The emergencies of `mode`.
            pub fn emergencies(mode: Mode) -> &'static [#stack::emcy::EmcyDefault] { #select }
            /// The spec names of the emergencies of `mode`, in the order of [`emergencies`].
            fn names(mode: Mode) -> &'static [&'static str] { #select_names }
            /// The emergency of `mode` the spec calls `name` (hosts: fault injection).
            pub fn by_name(mode: Mode, name: &str) -> Option<#stack::emcy::EmcyDefault> {
                let at = names(mode).iter().position(|n| *n == name)?;
                emergencies(mode).get(at).copied()
            }
            /// The spec name of `e`, one of the emergencies of `mode`.
            pub fn name_of(mode: Mode, e: &#stack::emcy::EmcyDefault) -> Option<&'static str> {
                let at = emergencies(mode).iter().position(|x| x == e)?;
                names(mode).get(at).copied()
            }
        }
    }
}
