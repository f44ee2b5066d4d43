//! `device!("path/to/spec.yaml")`: the spec's generated code, in place.
//!
//! The path is relative to the invoking crate's `Cargo.toml`. The spec is tracked: editing it
//! rebuilds the crate. An invalid spec becomes a `compile_error!` carrying coforge's
//! diagnostics with the YAML `file:line:col`. All generation lives in `coforge-codegen`.
#![forbid(unsafe_code)]

use proc_macro::TokenStream;
use quote::quote_spanned;
use std::path::PathBuf;

#[proc_macro]
pub fn device(input: TokenStream) -> TokenStream {
    let path = syn::parse_macro_input!(input as syn::LitStr);
    let manifest_dir = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap_or_default());
    match coforge_codegen::expand(&path.value(), &manifest_dir, &coforge_codegen::Options::default()) {
        Ok(tokens) => tokens.into(),
        Err(diagnostics) => {
            let message = format!("invalid coforge spec:\n{diagnostics}");
            quote_spanned!(path.span() => compile_error!(#message);).into()
        }
    }
}
