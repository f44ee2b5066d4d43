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
}
