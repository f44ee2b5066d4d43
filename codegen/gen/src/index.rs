//! `index::*`: one constant per object, so device code names objects, not numbers.

use coforge_spec::model::Device;
use proc_macro2::TokenStream;
use quote::{format_ident, quote};
use std::collections::BTreeMap;

pub fn index_module(d: &Device) -> TokenStream {
    // One constant per index (its first definition over the modes).
    let mut by_index = BTreeMap::new();
    for o in &d.objects {
        by_index.entry(o.index).or_insert(o);
    }
    let consts = by_index.values().map(|o| {
        let name = format_ident!("{}", o.ident.to_uppercase());
        let value = crate::hex(o.index.into(), 4);
        let doc = format!(" {:04X}h {}", o.index, o.name);
        quote!(#[doc = #doc] pub const #name: u16 = #value;)
    });
    quote! {
        /// Every object's index, by its identifier in the spec.
        pub mod index {
            #(#consts)*
        }
    }
}
