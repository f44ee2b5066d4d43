//! The `Mode` enum: one variant per spec mode, or `Default` for a device without modes.

use coforge_spec::Device;
use proc_macro2::{Ident, Span, TokenStream};
use quote::quote;

pub struct Modes {
    /// (variant, spec mode name) in spec order.
    pub variants: Vec<(Ident, Option<String>)>,
}

impl Modes {
    pub fn of(d: &Device) -> Modes {
        let variants = if d.modes.is_empty() {
            vec![(Ident::new("Default", Span::call_site()), None)]
        } else {
            d.modes.iter().map(|m| (crate::naming::camel(&m.name), Some(m.name.clone()))).collect()
        };
        Modes { variants }
    }

    pub fn enum_tokens(&self) -> TokenStream {
        let names: Vec<&Ident> = self.variants.iter().map(|(v, _)| v).collect();
        let count = proc_macro2::Literal::usize_unsuffixed(names.len());
        let spec_names: Vec<String> = self.variants.iter().map(|(v, m)| m.clone().unwrap_or_else(|| v.to_string().to_lowercase())).collect();
        quote! {
            /// Operating modes of the device (the spec's `modes`).
            #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
            pub enum Mode { #(#names),* }

            impl Mode {
                pub const ALL: [Mode; #count] = [#(Mode::#names),*];
                /// The mode's name in the spec.
                pub const fn name(self) -> &'static str {
                    match self { #(Mode::#names => #spec_names),* }
                }
            }
        }
    }

    /// A `match mode { .. }` selecting one expression per mode.
    pub fn select(&self, per_mode: &[TokenStream]) -> TokenStream {
        let arms = self.variants.iter().zip(per_mode).map(|((v, _), e)| quote!(Mode::#v => #e));
        quote!(match mode { #(#arms),* })
    }

    /// One `static PREFIX_MODE: [ty; n]` per distinct table of `per_mode` (the items of each
    /// mode's table), named after the first mode that has it, and the `match mode` returning
    /// each mode's `&PREFIX_MODE`: rustc does not merge identical statics, so modes with equal
    /// tables share one.
    pub fn tables(&self, prefix: &str, ty: &TokenStream, per_mode: &[Vec<TokenStream>]) -> (Vec<TokenStream>, TokenStream) {
        self.tables_as(prefix, ty, per_mode, |name| quote!(&#name))
    }

    /// [`Modes::tables`], each mode's arm being `arm(static's name)`.
    pub fn tables_as(
        &self,
        prefix: &str,
        ty: &TokenStream,
        per_mode: &[Vec<TokenStream>],
        arm: impl Fn(&Ident) -> TokenStream,
    ) -> (Vec<TokenStream>, TokenStream) {
        let mut statics = Vec::new();
        // (the items as text, the static's name) of each table emitted so far.
        let mut emitted: Vec<(String, Ident)> = Vec::new();
        let mut refs = Vec::new();
        for ((variant, _), items) in self.variants.iter().zip(per_mode) {
            let key = quote!(#(#items),*).to_string();
            let name = match emitted.iter().find(|(k, _)| *k == key) {
                Some((_, name)) => name.clone(),
                None => {
                    let name = Ident::new(&format!("{prefix}_{}", variant.to_string().to_uppercase()), Span::call_site());
                    let count = proc_macro2::Literal::usize_unsuffixed(items.len());
                    statics.push(quote!(static #name: [#ty; #count] = [#(#items),*];));
                    emitted.push((key, name.clone()));
                    name
                }
            };
            refs.push(arm(&name));
        }
        (statics, self.select(&refs))
    }
}
