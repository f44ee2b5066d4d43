#![allow(clippy::unwrap_used, clippy::indexing_slicing)]
//! The CO401GW1 chip end to end: the boot phase, every host command with the datasheet's
//! examples, the unsolicited telegrams, the process image and its views, DS401 events, the
//! pins and the error states of the outputs.

use co401gw1::{FixedBoard, Gw1};
use coforge_stack::device::{Device, HostPort};
use coforge_stack::frame::CanFrame;
use coforge_stack::nmt::NmtState;
use coforge_stack::node::BusState;
use coforge_stack::store::NoStore;

type Chip = Gw1<FixedBoard, NoStore>;

const NODE: u16 = 5;

struct Rig {
    chip: Chip,
    now_us: u64,
    sent: Vec<CanFrame>,
    host: Vec<u8>,
}

impl Rig {
    /// A chip at node-ID `node` (0: ID pins all high) in mixed or digital-only mode, powered
    /// on, in its boot phase.
    fn boot(node: u8, mixed: bool) -> Rig {
        let mut chip = Gw1::new(FixedBoard::new(node, mixed), NoStore);
        chip.start(0);
        let mut rig = Rig { chip, now_us: 0, sent: Vec::new(), host: Vec::new() };
        rig.run(1_000);
        rig
    }

    /// A chip at node-ID 5, enabled with `02 00`, its boot-up telegram and answer taken.
    fn enabled(mixed: bool) -> Rig {
        let mut rig = Rig::boot(NODE as u8, mixed);
        assert_eq!(rig.command(&[0x02, 0x00]), [0x02, 0x00]);
        assert_eq!(rig.take_sent().first().map(|f| (f.id, f.payload().to_vec())), Some((0x700 + NODE, vec![0])));
        rig
    }

    /// Advances time, collecting what the chip sends on the bus and to the host.
    fn run(&mut self, us: u64) {
        let end = self.now_us + us;
        while self.now_us < end {
            self.now_us += 500;
            while let Some(f) = self.chip.poll(self.now_us) {
                self.sent.push(f);
            }
            let mut out = [0; 64];
            let n = self.chip.host_output(self.now_us / 1000, &mut out);
            self.host.extend_from_slice(&out[..n]);
        }
    }

    fn take_sent(&mut self) -> Vec<CanFrame> {
        std::mem::take(&mut self.sent)
    }

    fn take_host(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.host)
    }

    /// Sends a telegram as a continuous stream (1 ms per byte) and returns what the host
    /// received in the next 5 ms.
    fn command(&mut self, bytes: &[u8]) -> Vec<u8> {
        self.take_host();
        for &b in bytes {
            self.chip.on_host_byte(b, self.now_us / 1000);
            self.run(1_000);
        }
        self.run(5_000);
        self.take_host()
    }

    fn frame(&mut self, id: u16, data: &[u8]) {
        self.chip.on_frame(&CanFrame::data(id, data).unwrap(), self.now_us);
        self.run(1_000);
    }

    /// An expedited SDO download from the bus; the answer's first 4 bytes.
    fn sdo_write(&mut self, index: u16, sub: u8, data: &[u8]) -> Vec<u8> {
        let [lo, hi] = index.to_le_bytes();
        let mut req = [0x23 | ((4 - data.len() as u8) << 2), lo, hi, sub, 0, 0, 0, 0];
        req[4..4 + data.len()].copy_from_slice(data);
        self.take_sent();
        self.frame(0x600 + NODE, &req);
        let answer = self.take_sent().into_iter().find(|f| f.id == 0x580 + NODE).unwrap();
        answer.payload().to_vec()
    }

    fn sdo_read(&mut self, index: u16, sub: u8) -> Vec<u8> {
        let [lo, hi] = index.to_le_bytes();
        self.take_sent();
        self.frame(0x600 + NODE, &[0x40, lo, hi, sub, 0, 0, 0, 0]);
        let answer = self.take_sent().into_iter().find(|f| f.id == 0x580 + NODE).unwrap();
        answer.payload().to_vec()
    }

    fn start_node(&mut self) {
        self.frame(0x000, &[0x01, NODE as u8]);
        assert_eq!(self.chip.node().state(), NmtState::Operational);
    }
}

#[test]
fn boot_phase_sends_boot_up_every_250_ms_and_ignores_the_bus() {
    let mut rig = Rig::boot(NODE as u8, true);
    rig.run(1_000_000);
    let host = rig.take_host();
    // At 0, 250, 500, 750 and 1000 ms.
    assert_eq!(host, [0x01, 0x00].repeat(5));
    rig.frame(0x600 + NODE, &[0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0]);
    rig.frame(0x000, &[0x01, 0x00]);
    assert!(rig.take_sent().is_empty(), "CAN is off");
    // 50 00 answers boot-up (00) until enable.
    assert_eq!(rig.command(&[0x50, 0x00]), [0x50, 0x01, 0x00]);
}

#[test]
fn enable_starts_can_and_stops_the_boot_up_telegram() {
    let mut rig = Rig::enabled(true);
    rig.run(1_000_000);
    assert!(rig.take_host().is_empty(), "no boot-up telegram after enable");
    assert_eq!(rig.command(&[0x50, 0x00]), [0x50, 0x01, 0x7F], "datasheet example: pre-operational");
    // Repeated: confirmed again, nothing changes (erratum GW1-49).
    assert_eq!(rig.command(&[0x02, 0x00]), [0x02, 0x00]);
    assert!(rig.take_sent().is_empty());
    // The alternate enable does not exist in mixed mode.
    assert_eq!(rig.command(&[0x02, 0x81]), []);
}

#[test]
fn a_programmable_node_id_is_set_by_the_host_before_enable() {
    let mut rig = Rig::boot(0, true);
    assert_eq!(rig.command(&[0x02, 0x00]), [], "no valid node-ID yet: refused");
    assert_eq!(rig.command(&[0x20, 0x04, 0x0B, 0x10, 0x00, 0x80]), [], "128 is no node-ID");
    assert_eq!(rig.command(&[0x20, 0x04, 0x0B, 0x10, 0x00, 0x22]), [0x20, 0x00]);
    assert_eq!(rig.command(&[0x02, 0x00]), [0x02, 0x00]);
    let sent = rig.take_sent();
    assert_eq!(sent.first().map(|f| f.id), Some(0x722), "boot-up with the host's node-ID");
    // $NODEID defaults follow it.
    assert_eq!(rig.chip.node().od().tpdo1_comm.cob_id_used_by_tpdo, 0x1A2);
    assert_eq!(rig.command(&[0x20, 0x04, 0x0B, 0x10, 0x00, 0x23]), [], "100Bh only before enable");
}

#[test]
fn the_id_pins_decide_unless_all_high() {
    let mut rig = Rig::boot(NODE as u8, true);
    assert_eq!(rig.command(&[0x20, 0x04, 0x0B, 0x10, 0x00, 0x22]), [], "erratum GW1-48");
    assert_eq!(rig.chip.node_id_for_enable(), Some(5));
}

#[test]
fn datasheet_examples_serial_number_write_and_read() {
    let mut rig = Rig::boot(NODE as u8, true);
    assert_eq!(rig.command(&[0x20, 0x07, 0x18, 0x10, 0x04, 0x78, 0x56, 0x34, 0x12]), [0x20, 0x00]);
    assert_eq!(rig.command(&[0x21, 0x03, 0x18, 0x10, 0x04]), [0x21, 0x07, 0x18, 0x10, 0x04, 0x78, 0x56, 0x34, 0x12]);
    rig.command(&[0x02, 0x00]);
    // After enable 1018h.4 is the host's no more.
    assert_eq!(rig.command(&[0x20, 0x07, 0x18, 0x10, 0x04, 1, 2, 3, 4]), []);
    assert_eq!(rig.sdo_read(0x1018, 4)[4..8], [0x78, 0x56, 0x34, 0x12]);
}

#[test]
fn the_host_write_rule_refuses_with_no_answer() {
    let mut rig = Rig::enabled(true);
    let errors = rig.chip.host_errors();
    // Below 3000h: no (1017h heartbeat); 2102h and 2E01h: yes; above 3000h: yes.
    assert_eq!(rig.command(&[0x20, 0x05, 0x17, 0x10, 0x00, 0x64, 0x00]), []);
    assert_eq!(rig.command(&[0x20, 0x04, 0x02, 0x21, 0x00, 0x00]), [0x20, 0x00]);
    assert_eq!(rig.command(&[0x20, 0x04, 0x01, 0x2E, 0x02, 0x01]), [0x20, 0x00]);
    assert_eq!(rig.command(&[0x20, 0x04, 0x02, 0x60, 0x01, 0x0F]), [0x20, 0x00]);
    // A read of a missing object, PDO3, garbage.
    assert_eq!(rig.command(&[0x21, 0x03, 0x22, 0x22, 0x00]), []);
    assert_eq!(rig.command(&[0x32, 0x00]), []);
    assert_eq!(rig.command(&[0x77, 0x00]), []);
    assert_eq!(rig.chip.host_errors(), errors + 4);
}

#[test]
fn write_tpdo_data_fills_the_mapped_objects_and_views_share_the_bytes() {
    let mut rig = Rig::enabled(true);
    // The datasheet's first example: three bytes into TPDO1 (default mapping 6000h.1..8).
    assert_eq!(rig.command(&[0x30, 0x03, 0x12, 0x34, 0x56]), [0x30, 0x00]);
    let od = rig.chip.node().od();
    // Byte 0 is IN0..IN7 (hardware inputs enabled, all pins high: 0); bytes 1 and 2 are the host's.
    assert_eq!(od.app.inputs[..4], [0x00, 0x34, 0x56, 0x00]);
    assert_eq!(rig.sdo_read(0x6100, 2)[4..6], [0x56, 0x00], "word 1 = bytes 2 and 3");
    assert_eq!(rig.sdo_read(0x6120, 1)[4..8], [0x00, 0x34, 0x56, 0x00]);
    // TPDO2 (analog inputs 6401h.1..4) exists in mixed mode; TPDO5 does not.
    assert_eq!(rig.command(&[0x31, 0x08, 0x01, 0x00, 0x02, 0x00, 0x03, 0x00, 0xFF, 0xFF]), [0x31, 0x00]);
    assert_eq!(rig.chip.node().od().read_analog_input.items, [1, 2, 3, -1]);
    assert_eq!(rig.command(&[0x34, 0x01, 0x00]), []);
}

#[test]
fn read_rpdo_data_and_its_unsolicited_telegram() {
    let mut rig = Rig::enabled(true);
    rig.start_node();
    rig.frame(0x200 + NODE, &[0x12, 0x34, 0x56, 0x78, 0, 0, 0, 0]);
    assert!(rig.take_host().is_empty(), "2E01h.1 = 0: nothing unsolicited");
    assert_eq!(rig.command(&[0x40, 0x00]), [0x40, 0x08, 0x12, 0x34, 0x56, 0x78, 0, 0, 0, 0]);
    assert_eq!(rig.command(&[0x20, 0x05, 0x01, 0x2E, 0x01, 0x01, 0x00]), [0x20, 0x00]);
    // The same data again: nothing; new data: 40 08 ...
    rig.frame(0x200 + NODE, &[0x12, 0x34, 0x56, 0x78, 0, 0, 0, 0]);
    assert!(rig.take_host().is_empty());
    rig.frame(0x200 + NODE, &[0x99, 0, 0, 0, 0, 0, 0, 0]);
    assert_eq!(rig.take_host(), [0x40, 0x08, 0x99, 0, 0, 0, 0, 0, 0, 0]);
    // RPDO2 (bit 1) is not enabled.
    rig.frame(0x300 + NODE, &[1, 0, 2, 0, 3, 0, 4, 0]);
    assert!(rig.take_host().is_empty());
    assert_eq!(rig.command(&[0x41, 0x00]), [0x41, 0x08, 1, 0, 2, 0, 3, 0, 4, 0]);
    // OUT0..OUT7 show 6200h.1 = 0x99 inverted (active low).
    assert_eq!(rig.chip.board().output_levels, !0x99);
}

#[test]
fn nmt_state_and_emergencies_are_reported_when_enabled() {
    let mut rig = Rig::enabled(true);
    assert_eq!(rig.command(&[0x20, 0x04, 0x01, 0x2E, 0x02, 0x01]), [0x20, 0x00]);
    assert_eq!(rig.command(&[0x20, 0x04, 0x01, 0x2E, 0x03, 0x01]), [0x20, 0x00]);
    rig.frame(0x000, &[0x01, 0x00]);
    assert_eq!(rig.take_host(), [0x50, 0x01, 0x05], "one telegram for the start");
    rig.frame(0x000, &[0x01, 0x00]);
    assert_eq!(rig.take_host(), [0x50, 0x01, 0x05], "an NMT frame without a state change");
    // EMY0# low: the datasheet's critical emergency, to the bus and to the host.
    rig.chip.board_mut().emergency_levels = 0b10;
    rig.run(2_000);
    let emcy: Vec<_> = rig.take_sent().into_iter().filter(|f| f.id == 0x80 + NODE).collect();
    assert_eq!(emcy.first().map(|f| f.payload().to_vec()), Some(vec![0x10, 0x23, 0x01, 0x00, 0x01, 0x00, 0x00, 0x00]));
    let host = rig.take_host();
    assert_eq!(host[..10], [0x51, 0x08, 0x10, 0x23, 0x01, 0x00, 0x01, 0x00, 0x00, 0x00]);
    // 1029h.2 = 0: an application error takes an operational node to pre-operational.
    assert_eq!(rig.chip.node().state(), NmtState::PreOperational);
    assert_eq!(host[10..], [0x50, 0x01, 0x7F]);
    assert_eq!(rig.chip.node().od().status_register, 0x01);
    // EMY1# too: the OR of both codes in bytes 3..7.
    rig.chip.board_mut().emergency_levels = 0b00;
    rig.run(2_000);
    let emcy: Vec<_> = rig.take_sent().into_iter().filter(|f| f.id == 0x80 + NODE).collect();
    assert_eq!(emcy.first().map(|f| f.payload().to_vec()), Some(vec![0x00, 0x10, 0x01, 0x00, 0x11, 0x00, 0x00, 0x00]));
    assert_eq!(rig.chip.node().od().status_register, 0x11);
}

#[test]
fn digital_inputs_send_tpdo1_through_the_masks_only_on_change() {
    let mut rig = Rig::enabled(true);
    rig.start_node();
    rig.take_sent();
    // IN0 goes low: 6000h.1 bit 0 set; 6006h.1 = FFh (any change): TPDO1, from the very
    // poll that read the pins.
    rig.chip.board_mut().input_levels = 0xFE;
    let first = rig.chip.poll(rig.now_us).unwrap();
    assert_eq!((first.id, first.payload()[0]), (0x180 + NODE, 0x01));
    rig.run(2_000);
    assert!(rig.take_sent().iter().all(|f| f.id != 0x180 + NODE), "one TPDO per change");
    // The same data from the host: no event.
    assert_eq!(rig.command(&[0x30, 0x08, 0x01, 0, 0, 0, 0, 0, 0, 0]), [0x30, 0x00]);
    assert!(rig.take_sent().iter().all(|f| f.id != 0x180 + NODE));
    // 6005h off: no event.
    rig.sdo_write(0x6005, 0, &[0]);
    rig.chip.board_mut().input_levels = 0xFF;
    rig.run(2_000);
    assert!(rig.take_sent().iter().all(|f| f.id != 0x180 + NODE));
}

#[test]
fn analog_inputs_wait_for_6423() {
    let mut rig = Rig::enabled(true);
    rig.start_node();
    rig.take_sent();
    assert_eq!(rig.command(&[0x31, 0x08, 0x10, 0x00, 0, 0, 0, 0, 0, 0]), [0x31, 0x00]);
    rig.run(100_000);
    assert!(rig.take_sent().iter().all(|f| f.id != 0x280 + NODE), "6423h is FALSE by default");
    // Its 1000 ms event timer still sends it.
    rig.run(1_000_000);
    assert!(rig.take_sent().iter().any(|f| f.id == 0x280 + NODE));
    rig.sdo_write(0x6423, 0, &[1]);
    assert_eq!(rig.command(&[0x31, 0x08, 0x20, 0x00, 0, 0, 0, 0, 0, 0]), [0x31, 0x00]);
    let tpdo2: Vec<_> = rig.take_sent().into_iter().filter(|f| f.id == 0x280 + NODE).collect();
    assert_eq!(tpdo2.len(), 1);
    assert_eq!(tpdo2[0].payload()[..2], [0x20, 0x00]);
}

#[test]
fn critical_errors_force_the_outputs() {
    let mut rig = Rig::enabled(true);
    rig.start_node();
    rig.frame(0x200 + NODE, &[0x0F, 0x0F, 0, 0, 0, 0, 0, 0]);
    // 5200h = 1 (default), 6206h = FFh, 6207h = 0: on EMY0# 6200h is overwritten with 0.
    rig.chip.board_mut().emergency_levels = 0b10;
    rig.run(2_000);
    assert!(rig.chip.in_error_state());
    assert_eq!(rig.chip.node().od().app.outputs[..2], [0, 0]);
    assert_eq!(rig.chip.board().output_levels, 0xFF);
    rig.chip.board_mut().emergency_levels = 0b11;
    rig.run(2_000);
    assert!(!rig.chip.in_error_state());

    // 5200h = 0: 6200h keeps its data, the pins show the error state while it lasts.
    let mut rig = Rig::enabled(true);
    rig.sdo_write(0x5200, 0, &[0]);
    rig.sdo_write(0x6207, 1, &[0xF0]);
    rig.start_node();
    rig.frame(0x200 + NODE, &[0x0F, 0, 0, 0, 0, 0, 0, 0]);
    rig.chip.on_bus_state(BusState::BusOff, rig.now_us);
    rig.run(1_000);
    assert_eq!(rig.chip.node().od().app.outputs[0], 0x0F);
    assert_eq!(rig.chip.board().output_levels, !0xF0);
    rig.chip.on_bus_state(BusState::Active, rig.now_us);
    rig.run(1_000);
    assert_eq!(rig.chip.board().output_levels, !0x0F);
}

#[test]
fn an_nmt_reset_is_reported_with_the_hosts_2e01() {
    let mut rig = Rig::boot(NODE as u8, true);
    assert_eq!(rig.command(&[0x20, 0x04, 0x01, 0x2E, 0x02, 0x01]), [0x20, 0x00]);
    rig.command(&[0x02, 0x00]);
    // Reset node reloads 2E01h before the chip sees the NMT command: it is reported anyway.
    rig.frame(0x000, &[0x81, NODE as u8]);
    assert_eq!(rig.take_host(), [0x50, 0x01, 0x7F]);
    assert_eq!(rig.chip.node().od().gateway_transfer_control.auto_send_nmt_state, 1);
}

#[test]
fn host_configuration_survives_nmt_resets() {
    let mut rig = Rig::boot(NODE as u8, true);
    assert_eq!(rig.command(&[0x20, 0x07, 0x18, 0x10, 0x04, 0x78, 0x56, 0x34, 0x12]), [0x20, 0x00]);
    assert_eq!(rig.command(&[0x20, 0x04, 0x02, 0x62, 0x01, 0xFF]), [0x20, 0x00]);
    rig.command(&[0x02, 0x00]);
    rig.frame(0x000, &[0x81, NODE as u8]);
    assert_eq!(rig.chip.node().od().identity_object.serial_number, 0x12345678);
    assert_eq!(rig.chip.node().od().polarity_output_8_bit.items[0], 0xFF);
    rig.frame(0x000, &[0x82, NODE as u8]);
    assert_eq!(rig.chip.node().od().identity_object.serial_number, 0x12345678);
}

#[test]
fn digital_only_mode_has_pdo5_and_the_alternate_identifiers() {
    let mut rig = Rig::boot(NODE as u8, false);
    assert_eq!(rig.command(&[0x02, 0x81]), [0x02, 0x00]);
    let od = rig.chip.node().od();
    assert_eq!(od.tpdo5_comm.cob_id_used_by_tpdo, 0x280 + u32::from(NODE));
    assert_eq!(od.rpdo5_comm.cob_id_used_by_rpdo, 0x300 + u32::from(NODE));
    assert_eq!(od.device_type, 0x00030191, "erratum GW1-44");
    assert_eq!(rig.command(&[0x34, 0x02, 0xAA, 0xBB]), [0x34, 0x00]);
    assert_eq!(rig.chip.node().od().app.inputs[8..10], [0xAA, 0xBB]);
    assert_eq!(rig.command(&[0x31, 0x00]), [], "no PDO2 in digital-only mode");
    // Sub 0 of the views: 16 bytes, 8 words, 4 double words each way.
    for (index, count) in [(0x6000, 16), (0x6100, 8), (0x6120, 4), (0x6200, 16), (0x6300, 8), (0x6320, 4)] {
        assert_eq!(rig.sdo_read(index, 0)[4], count, "{index:04X}h sub 0");
    }
}

#[test]
fn mixed_mode_has_eight_bytes_each_way() {
    let mut rig = Rig::enabled(true);
    for (index, count) in [(0x6000, 8), (0x6100, 4), (0x6120, 2), (0x6200, 8), (0x6300, 4), (0x6320, 2)] {
        assert_eq!(rig.sdo_read(index, 0)[4], count, "{index:04X}h sub 0");
    }
    assert_eq!(rig.sdo_read(0x6000, 9)[..4], [0x80, 0x00, 0x60, 0x09], "no 9th byte");
    assert_eq!(rig.chip.node().od().device_type, 0x000F0191);
}

#[test]
fn remapping_follows_2102() {
    let mut rig = Rig::boot(NODE as u8, true);
    assert_eq!(rig.command(&[0x20, 0x04, 0x02, 0x21, 0x00, 0x00]), [0x20, 0x00]);
    rig.command(&[0x02, 0x00]);
    // CiA 301: a mapping changes only while its PDO is invalid.
    assert_eq!(rig.sdo_write(0x1800, 1, &(0x8000_0185_u32).to_le_bytes())[0], 0x60);
    assert_eq!(rig.sdo_write(0x1A00, 0, &[0]), [0x80, 0x00, 0x1A, 0x00, 0x21, 0x00, 0x00, 0x08]);
    assert_eq!(rig.sdo_read(0x1A00, 0)[4], 8, "unchanged");
    let mut rig = Rig::enabled(true);
    assert_eq!(rig.sdo_write(0x1800, 1, &(0x8000_0185_u32).to_le_bytes())[0], 0x60);
    assert_eq!(rig.sdo_write(0x1A00, 0, &[0])[0], 0x60, "2102h = 1: remapping allowed");
}

#[test]
fn remapped_pdos_carry_the_host_data_as_mapped() {
    // 2102h = 1 (default): RPDO1 remapped to a dummy byte, 6200h.2 and 6200h.1; TPDO1 to
    // 6000h.3 and 6000h.2.
    let mut rig = Rig::enabled(true);
    assert_eq!(rig.sdo_write(0x1400, 1, &(0x8000_0205_u32).to_le_bytes())[0], 0x60);
    assert_eq!(rig.sdo_write(0x1600, 0, &[0])[0], 0x60);
    for (sub, word) in [(1, 0x0005_0008_u32), (2, 0x6200_0208), (3, 0x6200_0108)] {
        assert_eq!(rig.sdo_write(0x1600, sub, &word.to_le_bytes())[0], 0x60, "1600h.{sub}");
    }
    assert_eq!(rig.sdo_write(0x1600, 0, &[3])[0], 0x60);
    assert_eq!(rig.sdo_write(0x1400, 1, &(0x205_u32).to_le_bytes())[0], 0x60);
    assert_eq!(rig.sdo_write(0x1800, 1, &(0x8000_0185_u32).to_le_bytes())[0], 0x60);
    assert_eq!(rig.sdo_write(0x1A00, 0, &[0])[0], 0x60);
    for (sub, word) in [(1, 0x6000_0308_u32), (2, 0x6000_0208)] {
        assert_eq!(rig.sdo_write(0x1A00, sub, &word.to_le_bytes())[0], 0x60, "1A00h.{sub}");
    }
    assert_eq!(rig.sdo_write(0x1A00, 0, &[2])[0], 0x60);
    assert_eq!(rig.sdo_write(0x1800, 1, &(0x185_u32).to_le_bytes())[0], 0x60);
    rig.start_node();
    // The dummy byte is dropped, the others land in 6200h.2 and 6200h.1; `40` reads them
    // back in the mapping's order, the dummy as zero.
    rig.frame(0x200 + NODE, &[0xEE, 0x22, 0x11]);
    assert_eq!(rig.command(&[0x40, 0x00]), [0x40, 0x03, 0x00, 0x22, 0x11]);
    // `30` fills 6000h.3 and 6000h.2 in the mapping's order; TPDO1 carries them.
    rig.take_sent();
    assert_eq!(rig.command(&[0x30, 0x02, 0x33, 0x22]), [0x30, 0x00]);
    let tpdo: Vec<_> = rig.take_sent().into_iter().filter(|f| f.id == 0x180 + NODE).map(|f| f.payload().to_vec()).collect();
    assert_eq!(tpdo, [vec![0x33, 0x22]]);
}

#[test]
fn leds_and_watchdog_follow_the_state() {
    let mut rig = Rig::boot(NODE as u8, true);
    assert!(!rig.chip.board().run_lit && !rig.chip.board().error_lit, "dark before enable");
    let wd = rig.chip.board().watchdog;
    rig.run(10_000);
    assert_ne!(rig.chip.board().watchdog, wd, "the watchdog toggles");
    rig.command(&[0x02, 0x00]);
    rig.start_node();
    // Operational: lit 95 % of the time.
    let lit = (0..200).filter(|t| rig.chip.indicators(1_000 + t).0).count();
    assert_eq!(lit, 190);
}
