//! Spec model -> Rust tokens. The `device!` macro is a thin wrapper around [`generate`];
//! keeping generation in an ordinary library makes it testable and printable
//! (`coforge dump`).
//!
//! Generated per device:
//! - `Mode`: the device's operating modes (`Mode::Default` for a device without modes);
//! - `od::entries(mode)`: the sorted [`EntryInfo`] table, identical sub-entries merged into
//!   runs, value limits in one table (`od::LIMITS`) the runs index;
//! - `pdo::rpdos(mode)` / `pdo::tpdos(mode)`: the default PDOs, with compile-time checks that
//!   every mapping fits a CAN frame;
//! - `Od<A>`: the typed dictionary and its `EntryAccess`/`NodeDictionary` dispatch;
//! - `emcy::*`: the spec's emergencies (`emcy::by_name` / `emcy::name_of` for hosts);
//!   `serial::*`: the host protocol's codecs;
//! - `index::*`: every object's index by name; `app::Hooks`: one typed hook per app-backed
//!   object (group), routed by `app::Typed<H>`;
//! - `node_config`: the node settings of the spec's `node:` section;
//! - `hardware::*`: decoders of the configuration pins (node-ID, bit rates, configuration);
//! - identity constants and the `Node<A, S>` alias.
//!
//! [`EntryInfo`]: https://docs.rs/coforge-stack
#![forbid(unsafe_code)]

mod app;
mod dictionary;
mod dictionary_proofs;
mod emcy;
mod entries;
mod hardware;
mod index;
mod modes;
mod naming;
mod pdos;
mod serial;
pub mod serial_proofs;

use coforge_spec::Device;
use proc_macro2::{Literal, Span, TokenStream};
use quote::quote;
use std::path::Path;

/// A hex literal such as `0x1018`: generated code reads like the datasheet.
pub(crate) fn hex(value: u64, digits: usize) -> TokenStream {
    let lit = syn::LitInt::new(&format!("0x{value:0digits$X}"), Span::call_site());
    quote!(#lit)
}

/// An unsuffixed decimal literal.
pub(crate) fn dec(value: u64) -> Literal {
    Literal::u64_unsuffixed(value)
}

/// Where the generated code finds the runtime crate.
#[derive(Debug, Clone)]
pub struct Options {
    /// Path of `coforge-stack` as the generated code sees it.
    pub stack: TokenStream,
}

impl Default for Options {
    fn default() -> Self {
        Options { stack: quote!(::coforge_stack) }
    }
}

/// The whole generated module body for one device.
pub fn generate(device: &Device, options: &Options) -> TokenStream {
    let modes = modes::Modes::of(device);
    let mode_enum = modes.enum_tokens();
    let id = &device.identity;
    let name = &id.name;
    let (vendor_id, product_code, revision) = (hex(id.vendor_id.into(), 8), hex(id.product_code.into(), 8), hex(id.revision.into(), 8));
    let profile = dec(id.profile.into());
    let od = entries::od_module(device, &modes, options);
    let pdo = pdos::pdo_module(device, &modes, options);
    let dictionary = dictionary::dictionary(device, &modes, options);
    let serial = serial::serial_module(device, options);
    let emcy = emcy::emcy_module(device, &modes, options);
    let hardware = hardware::hardware_module(device);
    let index = index::index_module(device);
    let app = app::app_module(device, options);
    let dictionary_proofs = dictionary_proofs::proofs_module(device, &modes, options);
    let stack = &options.stack;
    quote! {
        /// Device name from the spec.
        pub const NAME: &str = #name;
        pub const VENDOR_ID: u32 = #vendor_id;
        pub const PRODUCT_CODE: u32 = #product_code;
        pub const REVISION: u32 = #revision;
        /// CiA device profile number.
        pub const PROFILE: u16 = #profile;
        #mode_enum
        #od
        #pdo
        #dictionary
        #emcy
        #serial
        #hardware
        #index
        #app
        #dictionary_proofs

        /// The device's CANopen node: its dictionary, parameter store `S` and app objects `A`.
        pub type Node<A, S> = #stack::node::Node<Od<A>, S, { od::MAX_WRITE_SIZE }, { pdo::SLOTS }>;
    }
}

/// What `device!("path")` expands to: the generated code plus a dependency on the spec file,
/// so that editing the spec rebuilds the crate. `Err` carries the rendered diagnostics
/// (with `file:line:col`), which the macro turns into `compile_error!`.
pub fn expand(spec: &str, manifest_dir: &Path, options: &Options) -> Result<TokenStream, String> {
    let path = manifest_dir.join(spec);
    let text = std::fs::read_to_string(&path).map_err(|e| format!("coforge: cannot read spec {}: {e}", path.display()))?;
    let loaded = coforge_spec::load_str(spec, &text);
    let Some(device) = loaded.device() else { return Err(loaded.render_diagnostics()) };
    let body = generate(device, options);
    let tracked = path.display().to_string();
    Ok(quote! {
        const _: &[u8] = include_bytes!(#tracked);
        #body
    })
}

/// Generated code as formatted Rust source (`coforge dump`).
pub fn pretty(tokens: TokenStream) -> Result<String, String> {
    let file: syn::File = syn::parse2(tokens).map_err(|e| format!("generated code does not parse: {e}"))?;
    Ok(prettyplease::unparse(&file))
}
