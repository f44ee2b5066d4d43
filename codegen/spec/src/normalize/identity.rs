//! The `device:` identity and the `node:` settings.

use super::{Cx, span};
use crate::diag::Span;
use crate::expr::Vars;
use crate::model::{Identity, NodeSettings, NodeSpans};
use crate::raw::{self, Num, S};

pub(super) fn identity(cx: &mut Cx<'_>, d: &S<raw::Device>) -> Identity {
    let none = Vars::new();
    let v = &d.value;
    let u32_of = |cx: &mut Cx<'_>, n: &Num, what: &str| cx.int_in::<u32>(n, &none, what, 0, 0xFFFF_FFFF).unwrap_or(0);
    Identity {
        name: v.name.value.clone(),
        ident: v.ident.as_ref().map_or_else(|| device_ident(&v.name.value), |i| i.value.clone()),
        vendor: v.vendor.value.clone(),
        vendor_id: u32_of(cx, &v.vendor_id, "vendor_id"),
        product_code: u32_of(cx, &v.product_code, "product_code"),
        revision: u32_of(cx, &v.revision, "revision"),
        profile: cx.int_in::<u16>(&v.profile, &none, "profile", 0, 0xFFFF).unwrap_or(0),
        description: v.description.clone().unwrap_or_default(),
        sdo_block_transfer: v.sdo_block_transfer.unwrap_or(true),
        datasheet_title: v.datasheet.value.title.clone(),
        datasheet_version: v.datasheet.value.version.clone(),
        datasheet_file: v.datasheet.value.file.clone(),
        span: span(d),
    }
}

/// `CO401Memory1` -> `co401memory1`, `CR3101 CANmem` -> `cr3101_canmem`: file and crate names.
fn device_ident(name: &str) -> String {
    let mut out = String::new();
    for c in name.chars() {
        if c.is_ascii_alphanumeric() {
            out.push(c.to_ascii_lowercase());
        } else if !out.is_empty() && !out.ends_with('_') {
            out.push('_');
        }
    }
    out.trim_end_matches('_').to_string()
}

/// `node:` -> the node settings and the positions of their object indices. Absent keys keep
/// the CiA 301 default ([`NodeSettings::default`]).
pub(super) fn node_settings(cx: &mut Cx<'_>, n: &S<raw::Node>) -> (NodeSettings, NodeSpans) {
    let none = Vars::new();
    let v = &n.value;
    let defaults = NodeSettings::default();
    let mut object = |n: &Option<Num>, key: &str| -> (Option<u16>, Span) {
        match n {
            Some(n) => (cx.int_in::<u16>(n, &none, key, 1, 0xFFFF), span(n)),
            None => (None, Span::NONE),
        }
    };
    let (restart_time_object, restart_span) = object(&v.restart_time_object, "restart_time_object");
    let (bootup_object, bootup_span) = object(&v.bootup_object, "bootup_object");
    let (startup_object, startup_span) = object(&v.startup_object, "startup_object");
    let (remapping_object, remapping_span) = object(&v.remapping_object, "remapping_object");
    let settings = NodeSettings {
        restart_time_object,
        bootup_object,
        startup_object,
        rpdo_deadline_monitoring: v.rpdo_deadline_monitoring.unwrap_or(defaults.rpdo_deadline_monitoring),
        combine_emcy_codes: v.combine_emcy_codes.unwrap_or(defaults.combine_emcy_codes),
        auto_save: v.auto_save.unwrap_or(defaults.auto_save),
        listed_emergencies_only: v.listed_emergencies_only.unwrap_or(defaults.listed_emergencies_only),
        tpdo_on_write: v.tpdo_on_write.unwrap_or(defaults.tpdo_on_write),
        remapping_object,
    };
    let spans = NodeSpans { restart_time_object: restart_span, bootup_object: bootup_span, startup_object: startup_span, remapping_object: remapping_span };
    (settings, spans)
}
