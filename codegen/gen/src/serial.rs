//! `serial`: the framing's configuration and decoder, per direction an enum of the
//! protocol's commands with typed fields, `decode(&Frame)` and `encode(&mut [u8])`, and
//! `Codec`, the whole protocol as one `coforge_link::SerialCodec` for generic code.

use crate::Options;
use crate::naming::{camel, ident as field_ident};
use coforge_spec::model::{Command, Device, Direction, FieldType, Framing, LengthCounts, Serial};
use proc_macro2::{Ident, Span, TokenStream};
use quote::{format_ident, quote};

/// The Rust type of a field (tails borrow the frame).
fn field_type(ty: FieldType) -> TokenStream {
    match ty {
        FieldType::Unsigned(1) => quote!(u8),
        FieldType::Unsigned(2) => quote!(u16),
        FieldType::Unsigned(_) => quote!(u32),
        FieldType::Signed(1) => quote!(i8),
        FieldType::Signed(2) => quote!(i16),
        FieldType::Signed(_) => quote!(i32),
        FieldType::Bytes(n) => {
            let n = crate::dec(n.into());
            quote!([u8; #n])
        }
        FieldType::Tail { .. } => quote!(&'a [u8]),
    }
}

fn framing_tokens(framing: &Framing, max_data: usize) -> (TokenStream, TokenStream, TokenStream) {
    let link = quote!(::coforge_link);
    match framing {
        Framing::NibbleLength { resync_pause_ms } => (
            quote! {
                pub const FRAMING: #link::nibble::NibbleConfig = #link::nibble::NibbleConfig { resync_pause_ms: #resync_pause_ms };
                /// The streaming decoder of this protocol.
                pub type Decoder = #link::nibble::NibbleDecoder;
            },
            quote!(#link::nibble::encode(code, data, out)),
            quote!(Decoder::new(FRAMING)),
        ),
        Framing::LengthByte { inter_byte_timeout_ms, resync_pause_ms, extension_threshold } => {
            let n = crate::dec(max_data.max(1) as u64);
            (
                quote! {
                    pub const FRAMING: #link::length_byte::LengthByteConfig = #link::length_byte::LengthByteConfig {
                        inter_byte_timeout_ms: #inter_byte_timeout_ms,
                        resync_pause_ms: #resync_pause_ms,
                        extension_threshold: #extension_threshold,
                    };
                    /// The streaming decoder of this protocol, sized for its longest command.
                    pub type Decoder = #link::length_byte::LengthByteDecoder<#n>;
                },
                quote! {
                    match length_code {
                        Some(x) => #link::length_byte::encode_extension(&FRAMING, code, x, out),
                        None => #link::length_byte::encode(&FRAMING, code, data, out),
                    }
                },
                quote!(Decoder::new(FRAMING)),
            )
        }
        Framing::StartLengthCrc { start_byte, start_bits, length_bytes, length_counts, max_payload, crc } => {
            let (poly, init, xor) = (crate::hex(crc.poly, 4), crate::hex(crc.init, 4), crate::hex(crc.xor_out, 4));
            let (refin, refout, le, cs, cl) = (crc.reflect_in, crc.reflect_out, crc.little_endian, crc.covers_start, crc.covers_length);
            let bits = match start_bits {
                Some(b) => {
                    let (n, c, l) = (crate::hex(b.network.into(), 2), crate::hex(b.crc.into(), 2), crate::hex(b.long_length.into(), 2));
                    quote!(Some(#link::start_crc::StartBits { network: #n, crc: #c, long_length: #l }))
                }
                None => quote!(None),
            };
            let counts = match length_counts {
                LengthCounts::Payload => quote!(Payload),
                LengthCounts::PayloadAndCrc => quote!(PayloadAndCrc),
                LengthCounts::Frame => quote!(Frame),
            };
            let start = crate::hex((*start_byte).into(), 2);
            let n = crate::dec((*max_payload).into());
            (
                quote! {
                    static CRC: #link::crc::Crc16 = #link::crc::Crc16::new(#link::crc::CrcParams { poly: #poly, init: #init, reflect_in: #refin, reflect_out: #refout, xor_out: #xor });
                    pub const FRAMING: #link::start_crc::StartCrcConfig = #link::start_crc::StartCrcConfig {
                        start_byte: #start,
                        start_bits: #bits,
                        length_bytes: #length_bytes,
                        length_counts: #link::start_crc::LengthCounts::#counts,
                        max_payload: #max_payload,
                        crc: &CRC,
                        crc_little_endian: #le,
                        crc_covers_start: #cs,
                        crc_covers_length: #cl,
                        inter_byte_timeout_ms: None,
                    };
                    /// The streaming decoder of this protocol, sized for its largest payload.
                    pub type Decoder = #link::start_crc::StartCrcDecoder<#n>;
                },
                quote!(#link::start_crc::encode(&FRAMING, code, data, out)),
                quote!(Decoder::new(FRAMING)),
            )
        }
    }
}

/// How a field is read from `data` and written to `buf`.
fn field_codec(ty: FieldType, at: u32, big_endian: bool, name: &Ident) -> (TokenStream, TokenStream) {
    let link = quote!(::coforge_link::fields);
    let at_l = crate::dec(at.into());
    if let FieldType::Unsigned(n @ (1 | 2 | 4)) | FieldType::Signed(n @ (1 | 2 | 4)) = ty {
        // As wide as its Rust type: the bytes themselves, no 64-bit assembly (one field is
        // a few instructions on the serial path).
        let rt = field_type(ty);
        let n = crate::dec(n.into());
        let (from, to) = if big_endian { (quote!(from_be_bytes), quote!(to_be_bytes)) } else { (quote!(from_le_bytes), quote!(to_le_bytes)) };
        return (quote!(#rt::#from(#link::read_bytes::<#n>(data, #at_l))), quote!(#link::write_bytes(&mut buf, #at_l, &#name.#to())));
    }
    match ty {
        FieldType::Unsigned(n) => {
            let n = crate::dec(n.into());
            let rt = field_type(ty);
            (quote!(#link::read_uint(data, #at_l, #n, #big_endian) as #rt), quote!(#link::write_uint(&mut buf, #at_l, #n, #big_endian, u64::from(*#name))))
        }
        FieldType::Signed(n) => {
            let n = crate::dec(n.into());
            let rt = field_type(ty);
            (
                quote!(#link::read_int(data, #at_l, #n, #big_endian) as #rt),
                quote!(#link::write_uint(&mut buf, #at_l, #n, #big_endian, i64::from(*#name) as u64)),
            )
        }
        FieldType::Bytes(_) => (quote!(#link::read_bytes(data, #at_l)), quote!(#link::write_bytes(&mut buf, #at_l, &#name[..]))),
        FieldType::Tail { .. } => (quote!(data.get(#at_l..).unwrap_or(&[])), quote!(#link::write_bytes(&mut buf, #at_l, #name))),
    }
}

/// The lifetime of a direction's enum: `<'a>` if a command's tail borrows the frame.
fn lifetime(cmds: &[&Command]) -> TokenStream {
    let borrows = cmds.iter().any(|c| c.fields.iter().any(|f| matches!(f.ty, FieldType::Tail { .. })));
    if borrows { quote!(<'a>) } else { quote!() }
}

fn direction_enum(cmds: &[&Command], enum_name: &Ident) -> TokenStream {
    if cmds.is_empty() {
        // No command goes this way: an enum without values keeps `Codec` complete.
        return quote! {
            #[derive(Debug, Clone, Copy, PartialEq, Eq)]
            pub enum #enum_name {}

            impl<'a> ::coforge_link::Message<'a> for #enum_name {
                fn decode(frame: &::coforge_link::Frame<'a>) -> Result<Self, ::coforge_link::fields::DecodeError> {
                    Err(::coforge_link::fields::DecodeError::UnknownCommand { code: frame.code })
                }
                fn encode(&self, _: &mut [u8]) -> Result<usize, ::coforge_link::EncodeError> {
                    match *self {}
                }
                fn name(&self) -> &'static str {
                    match *self {}
                }
            }
        };
    }
    let lt = lifetime(cmds);
    let mut variants = Vec::new();
    let mut decode_arms = Vec::new();
    let mut encode_arms = Vec::new();
    let mut name_arms = Vec::new();
    for c in cmds {
        let v = camel(&c.name);
        let doc = format!(" `{}` ({:?}): {}", c.name, c.kind, c.description.split_whitespace().collect::<Vec<_>>().join(" "));
        let mut decls = Vec::new();
        let mut names = Vec::new();
        let mut reads = Vec::new();
        let mut writes = Vec::new();
        if let Some(p) = &c.code_param {
            let f = field_ident(&p.name);
            decls.push(quote!(#f: u8));
            let shift = p.mask.trailing_zeros();
            let mask = crate::hex(p.mask.into(), 2);
            reads.push(quote!(#f: (frame.code & #mask) >> #shift));
            names.push(f);
        }
        for field in &c.fields {
            let f = field_ident(&field.name);
            let ty = field_type(field.ty);
            decls.push(quote!(#f: #ty));
            let (read, write) = field_codec(field.ty, field.at, field.big_endian, &f);
            reads.push(quote!(#f: #read));
            writes.push(write);
            names.push(f);
        }
        let variant_decl = if decls.is_empty() { quote!(#[doc = #doc] #v) } else { quote!(#[doc = #doc] #v { #(#decls),* }) };
        variants.push(variant_decl);
        // Decoding: the code (with its parameter bits), the length code, then the length.
        let code = crate::hex(c.code.into(), 2);
        let code_test = match &c.code_param {
            None => quote!(frame.code == #code),
            Some(p) => {
                let mask = crate::hex(p.mask.into(), 2);
                let shift = p.mask.trailing_zeros();
                let allowed: Vec<u8> = c.codes().iter().map(|x| ((x & p.mask) >> shift) as u8).collect();
                quote!(frame.code & !#mask == #code & !#mask && [#(#allowed),*].contains(&((frame.code & #mask) >> #shift)))
            }
        };
        let lc = match c.length_code {
            Some(x) => {
                let x = crate::hex(x.into(), 2);
                quote!(Some(#x))
            }
            None => quote!(None),
        };
        // A length code stands for the whole length: any data length passes.
        let (min, max) = match c.length_code {
            Some(_) => (quote!(0), quote!(usize::MAX)),
            None => {
                let (min, max) = (crate::dec(c.length.0.into()), crate::dec(c.length.1.into()));
                (quote!(#min), quote!(#max))
            }
        };
        let build = if decls.is_empty() { quote!(Self::#v) } else { quote!(Self::#v { #(#reads),* }) };
        let number = crate::dec(decode_arms.len() as u64);
        decode_arms.push((quote!(#code_test && frame.length_code == #lc), quote!((#number, #min, #max)), number, build));
        // Encoding: fields into a buffer, then the framing.
        let code_expr = match &c.code_param {
            None => quote!(#code),
            Some(p) => {
                let f = field_ident(&p.name);
                let mask = crate::hex(p.mask.into(), 2);
                let shift = p.mask.trailing_zeros();
                quote!((#code & !#mask) | ((*#f << #shift) & #mask))
            }
        };
        let fixed = crate::dec(c.fixed_size().into());
        let len = match c.tail() {
            Some(t) => {
                let f = field_ident(&t.name);
                let max_tail = crate::dec(match t.ty {
                    FieldType::Tail { max } => max.into(),
                    _ => 0,
                });
                quote! {{
                    if #f.len() > #max_tail {
                        return Err(::coforge_link::EncodeError::DataTooLong { max: #max_tail });
                    }
                    #fixed + #f.len()
                }}
            }
            None => quote!(#fixed),
        };
        let pattern = if names.is_empty() { quote!(Self::#v) } else { quote!(Self::#v { #(#names),* }) };
        // One framing call per command: a fixed length is a constant there, so the copy into
        // the frame is a few stores, not a `memcpy` call.
        encode_arms.push(quote! {
            #pattern => {
                #(#writes;)*
                let len = #len;
                put_frame(#code_expr, #lc, buf.get(..len).unwrap_or(&[]), out)
            }
        });
        let name = &c.name;
        let name_pattern = if names.is_empty() { quote!(Self::#v) } else { quote!(Self::#v { .. }) };
        name_arms.push(quote!(#name_pattern => #name));
    }
    // Decoding in two steps, so that the length check and its error exist once: which
    // command (the first whose code and length code match) with its length range, then its
    // fields. The last command is the catch-all arm of the second match.
    let tests = decode_arms.iter().map(|(test, found, _, _)| quote!(if #test { #found }));
    let builds = decode_arms
        .iter()
        .enumerate()
        .map(|(i, (_, _, number, build))| if i + 1 == decode_arms.len() { quote!(_ => #build) } else { quote!(#number => #build) });
    quote! {
        #[derive(Debug, Clone, Copy, PartialEq, Eq)]
        pub enum #enum_name #lt { #(#variants),* }

        impl #lt #enum_name #lt {
            /// The command a decoded frame carries.
            pub fn decode(frame: &::coforge_link::Frame #lt) -> Result<Self, ::coforge_link::fields::DecodeError> {
                let data = frame.data;
                let (command, min, max): (u8, usize, usize) = #(#tests else)* {
                    return Err(::coforge_link::fields::DecodeError::UnknownCommand { code: frame.code });
                };
                if !(min..=max).contains(&data.len()) {
                    return Err(::coforge_link::fields::DecodeError::Length { min, max, got: data.len() });
                }
                Ok(match command { #(#builds),* })
            }

            /// Writes the whole frame into `out`; returns its length.
            #[allow(unused_mut, unused_variables)]
            pub fn encode(&self, out: &mut [u8]) -> Result<usize, ::coforge_link::EncodeError> {
                // The fields go into one buffer, then through the framing.
                let mut buf = [0_u8; MAX_DATA];
                match self { #(#encode_arms),* }
            }

            /// The command's name in the spec.
            pub fn name(&self) -> &'static str {
                match self { #(#name_arms),* }
            }
        }

        impl<'a> ::coforge_link::Message<'a> for #enum_name #lt {
            fn decode(frame: &::coforge_link::Frame<'a>) -> Result<Self, ::coforge_link::fields::DecodeError> {
                Self::decode(frame)
            }
            fn encode(&self, out: &mut [u8]) -> Result<usize, ::coforge_link::EncodeError> {
                Self::encode(self, out)
            }
            fn name(&self) -> &'static str {
                Self::name(self)
            }
        }
    }
}

/// The bits of the protocol's error-code field, one constant each (none without `error_bits`).
fn error_bits(serial: &Serial) -> TokenStream {
    if serial.error_bits.is_empty() {
        return quote!();
    }
    let ty = if serial.error_bits.iter().any(|b| b.bit >= 16) { quote!(u32) } else { quote!(u16) };
    let bits = serial.error_bits.iter().map(|b| {
        let name = format_ident!("{}", b.name.to_uppercase());
        let doc = format!("Bit {}: {}", b.bit, b.description);
        let bit = crate::dec(u64::from(b.bit));
        quote! {
            #[doc = #doc]
            pub const #name: #ty = 1 << #bit;
        }
    });
    quote! {
        /// The bits of the error-code field of the answers (the spec's `error_bits`).
        pub mod errors {
            #(#bits)*
        }
    }
}

pub fn serial_module(d: &Device, _options: &Options) -> TokenStream {
    let Some(serial) = &d.serial else { return quote!() };
    let max_data = serial.commands.iter().map(|c| c.length.1 as usize).max().unwrap_or(0).max(1);
    let (framing, put, new_decoder) = framing_tokens(&serial.framing, max_data);
    let commands = |dir| serial.commands.iter().filter(|c| c.direction == dir).collect::<Vec<&Command>>();
    let (to_device, to_host) = (commands(Direction::HostToDevice), commands(Direction::DeviceToHost));
    let dirs =
        [direction_enum(&to_device, &Ident::new("HostToDevice", Span::call_site())), direction_enum(&to_host, &Ident::new("DeviceToHost", Span::call_site()))];
    let (to_device_lt, to_host_lt) = (lifetime(&to_device), lifetime(&to_host));
    let max = crate::dec(max_data as u64);
    let proofs = crate::serial_proofs::proofs_module(serial);
    let errors = error_bits(serial);
    quote! {
        /// The serial protocol: framing, decoder and typed commands, generated from the spec.
        pub mod serial {
            #framing

            /// A fresh decoder for this protocol.
            pub fn decoder() -> Decoder {
                #new_decoder
            }

            /// The most data bytes any command carries.
            pub const MAX_DATA: usize = #max;

            #[allow(unused_variables)]
            fn put_frame(code: u8, length_code: Option<u8>, data: &[u8], out: &mut [u8]) -> Result<usize, ::coforge_link::EncodeError> {
                #put
            }

            #errors

            #(#dirs)*

            /// The protocol as one type, for code generic over devices.
            #[derive(Debug, Clone, Copy, Default)]
            pub struct Codec;

            impl ::coforge_link::SerialCodec for Codec {
                type Decoder = Decoder;
                type HostToDevice<'a> = HostToDevice #to_device_lt;
                type DeviceToHost<'a> = DeviceToHost #to_host_lt;

                fn decoder() -> Decoder {
                    decoder()
                }
            }

            #proofs
        }
    }
}
