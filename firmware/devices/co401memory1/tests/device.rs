#![allow(clippy::unwrap_used, clippy::indexing_slicing)]
//! The CO401Memory1 module end to end on RAM banks: the serial host protocol with every
//! datasheet example (corrected), SDO and PDO access to the memory, the bank status and its
//! emergencies, the supply guard and CAN monitoring.

use co401memory1::{BANK_SIZE, ConfigError, FixedBoard, Memory1};
use coforge_stack::device::{Device, HostPort};
use coforge_stack::frame::CanFrame;
use coforge_storage::ram::RamEeprom;

type Eeprom = RamEeprom<[u8; BANK_SIZE]>;
type Dev = Memory1<Eeprom, FixedBoard>;

const NODE: u16 = 5;

/// Node-ID 5 on the pins: ID0 and ID2 low.
fn board() -> FixedBoard {
    FixedBoard::new(NODE as u8)
}

struct Rig {
    dev: Dev,
    now_us: u64,
    sent: Vec<CanFrame>,
}

impl Rig {
    fn new() -> Rig {
        Self::with_banks([Eeprom::new(), Eeprom::new()])
    }

    fn with_banks(banks: [Eeprom; 2]) -> Rig {
        let mut dev = Memory1::new(banks, board()).unwrap();
        dev.start(0);
        let mut rig = Rig { dev, now_us: 0, sent: Vec::new() };
        rig.run(1_000);
        assert_eq!(rig.sent.first().map(|f| (f.id, f.payload().to_vec())), Some((0x700 + NODE, vec![0])), "boot-up first");
        rig
    }

    /// Advances time, collecting what the module sends.
    fn run(&mut self, us: u64) {
        let end = self.now_us + us;
        while self.now_us < end {
            self.now_us += 500;
            while let Some(f) = self.dev.poll(self.now_us) {
                self.sent.push(f);
            }
        }
    }

    fn take_sent(&mut self) -> Vec<CanFrame> {
        std::mem::take(&mut self.sent)
    }

    fn frame(&mut self, id: u16, data: &[u8]) {
        self.dev.on_frame(&CanFrame::data(id, data).unwrap(), self.now_us);
        self.run(1_000);
    }

    fn sdo(&mut self, request: [u8; 8]) -> [u8; 8] {
        let before = self.sent.len();
        self.frame(0x600 + NODE, &request);
        let new = self.sent.split_off(before);
        let (answers, others): (Vec<_>, Vec<_>) = new.into_iter().partition(|f| f.id == 0x580 + NODE);
        self.sent.extend(others);
        assert_eq!(answers.len(), 1, "one SDO answer");
        answers[0].data
    }

    fn download(&mut self, index: u16, sub: u8, data: &[u8]) -> Result<(), u32> {
        let [lo, hi] = index.to_le_bytes();
        let mut req = [0x23 | ((4 - data.len() as u8) << 2), lo, hi, sub, 0, 0, 0, 0];
        req[4..4 + data.len()].copy_from_slice(data);
        let a = self.sdo(req);
        match a[0] {
            0x60 => Ok(()),
            0x80 => Err(u32::from_le_bytes(a[4..8].try_into().unwrap())),
            c => panic!("unexpected SDO answer {c:#x}"),
        }
    }

    fn upload(&mut self, index: u16, sub: u8) -> Result<u32, u32> {
        let [lo, hi] = index.to_le_bytes();
        let a = self.sdo([0x40, lo, hi, sub, 0, 0, 0, 0]);
        let value = u32::from_le_bytes(a[4..8].try_into().unwrap());
        if a[0] == 0x80 { Err(value) } else { Ok(value) }
    }

    /// Sends `bytes` over the serial line 1 ms apart; returns every answer byte.
    fn serial(&mut self, bytes: &[u8]) -> Vec<u8> {
        let mut answer = Vec::new();
        for &b in bytes {
            self.now_us += 1_000;
            let mut out = [0; 16];
            self.dev.on_host_byte(b, self.now_us / 1000);
            let n = self.dev.host_output(self.now_us / 1000, &mut out);
            answer.extend_from_slice(&out[..n]);
        }
        self.run(1_000);
        answer
    }

    /// Lets the serial receiver see a pause longer than the resync time.
    fn pause(&mut self) {
        self.run(150_000);
    }

    fn emergencies(&mut self) -> Vec<[u8; 8]> {
        self.take_sent().into_iter().filter(|f| f.id == 0x80 + NODE).map(|f| f.data).collect()
    }
}

fn hex(s: &str) -> Vec<u8> {
    s.split_whitespace().map(|b| u8::from_str_radix(b, 16).unwrap()).collect()
}

#[test]
fn boots_with_the_pins_node_id_and_reports_the_cleared_blank_banks() {
    let mut rig = Rig::new();
    assert_eq!(rig.dev.config().node_id, 5);
    assert_eq!(rig.dev.config().can_bitrate_kbit, 1000);
    assert_eq!(rig.dev.config().serial_baud, 9600);
    // Blank EEPROMs are formatted: both banks say "cleared" (6000h bit 6).
    assert_eq!(rig.upload(0x6000, 1), Ok(0x40));
    assert_eq!(rig.upload(0x6000, 2), Ok(0x40));
    assert_eq!(rig.upload(0x2105, 0), Ok(0x03));
    assert!(rig.dev.board_mut().outputs.mem1_error && rig.dev.board_mut().outputs.mem2_error);
    // Node-ID code 0 (every ID pin high) is reserved.
    assert_eq!(Memory1::new([Eeprom::new(), Eeprom::new()], FixedBoard::new(0)).err(), Some(ConfigError::ReservedNodeId));
}

#[test]
fn every_datasheet_example_exchange_in_its_corrected_form() {
    let mut rig = Rig::new();
    // Read Status: 04 MS1 MS2 SOR Res.
    assert_eq!(rig.serial(&hex("00")), hex("04 40 40 03 00"));
    // Write Command Registers, ADR 1 and ADR 2 (ADR 2 = 6200h.2, erratum MEM-23).
    assert_eq!(rig.serial(&hex("12 01 91")), hex("11 01"));
    assert_eq!(rig.serial(&hex("12 02 91")), hex("11 01"));
    assert_eq!(rig.serial(&hex("00")), hex("04 00 00 00 00"));
    assert_eq!(rig.upload(0x6200, 2), Ok(0x91));
    // Write then Read Memory Array Data: 5012h.04 holds 0x23 (example 33 12 50 04, MEM-24).
    assert_eq!(rig.serial(&hex("44 12 50 04 23")), hex("41 01"));
    assert_eq!(rig.serial(&hex("33 12 50 04")), hex("32 01 23"));
    // Setup CAN Monitoring for 0x123, a frame with B1..B5, Read CAN data (C0, MEM-25).
    assert_eq!(rig.serial(&hex("83 00 23 01")), hex("81 01"));
    assert_eq!(rig.upload(0x1401, 1), Ok(0x123));
    rig.frame(0x123, &hex("B1 B2 B3 B4 B5"));
    assert!(rig.dev.outputs().new_can_data);
    assert_eq!(rig.upload(0x2105, 0), Ok(0x10));
    assert_eq!(rig.serial(&hex("C0")), hex("C6 01 B1 B2 B3 B4 B5"));
    assert!(!rig.dev.outputs().new_can_data);
    assert_eq!(rig.serial(&hex("C0")), hex("C1 00"), "nothing new: the abort answer");
    // Write CAN data: D5 23 01 B1 B2 B3 goes out as 0x123 B1 B2 B3.
    rig.take_sent();
    assert_eq!(rig.serial(&hex("D5 23 01 B1 B2 B3")), hex("D1 01"));
    let sent = rig.take_sent();
    assert!(sent.iter().any(|f| f.id == 0x123 && f.payload() == hex("B1 B2 B3").as_slice()), "{sent:?}");
    // ID 0 stops monitoring.
    assert_eq!(rig.serial(&hex("83 00 00 00")), hex("81 01"));
    rig.frame(0x123, &[1]);
    assert_eq!(rig.serial(&hex("C0")), hex("C1 00"));
}

#[test]
fn malformed_frames_get_the_negative_answer_and_the_receiver_resyncs_after_a_pause() {
    let mut rig = Rig::new();
    // Outside the non-volatile data area, sub 0, and a wrong length: negative answers.
    assert_eq!(rig.serial(&hex("33 00 10 00")), hex("32 00 00"));
    assert_eq!(rig.serial(&hex("33 00 50 00")), hex("32 00 00"));
    assert_eq!(rig.serial(&hex("33 00 50 81")), hex("32 00 00"));
    assert_eq!(rig.serial(&hex("44 00 60 01 07")), hex("41 00"), "6000h is not host-writable");
    assert_eq!(rig.serial(&hex("31 00")), hex("32 00 00"));
    assert_eq!(rig.serial(&hex("12 03 91")), hex("11 00"), "no command register 3");
    assert_eq!(rig.serial(&hex("83 01 23 01")), hex("81 00"), "register 1 is not defined");
    assert_eq!(rig.serial(&hex("83 00 05 06")), hex("81 00"), "0x605: this node's own SDO requests");
    assert_eq!(rig.serial(&hex("D2 00 08")), hex("D1 00"), "identifier above 0x7FF");
    // An unknown command and a malformed Read Status have no answer.
    assert_eq!(rig.serial(&hex("F0")), hex(""));
    assert_eq!(rig.serial(&hex("01 00")), hex(""));
    // A frame cut short, then a pause: the next byte starts a new frame.
    let errors = rig.dev.host_errors();
    assert_eq!(rig.serial(&hex("44 12 50")), hex(""));
    rig.pause();
    assert_eq!(rig.serial(&hex("00")), hex("04 40 40 03 00"));
    assert!(rig.dev.host_errors() > errors);
    // Garbage that happens to frame (a 15-byte unknown command) is swallowed, then a pause.
    assert_eq!(rig.serial(&[0xEF, 1, 2, 3]), hex(""));
    rig.pause();
    assert_eq!(rig.serial(&hex("33 00 50 01")), hex("32 01 00"));
    // Nothing stored was touched by any of it.
    assert_eq!(rig.upload(0x5000, 1), Ok(0));
}

#[test]
fn data_written_over_serial_reads_back_over_sdo_and_the_other_way_round() {
    let mut rig = Rig::new();
    assert_eq!(rig.serial(&hex("44 3F 50 80 A5")), hex("41 01"));
    assert_eq!(rig.upload(0x503F, 0x80), Ok(0xA5));
    assert_eq!(rig.download(0x5001, 1, &[0x5A]), Ok(()));
    assert_eq!(rig.serial(&hex("33 01 50 01")), hex("32 01 5A"));
    assert_eq!(rig.upload(0x5001, 0), Ok(128));
    assert_eq!(rig.upload(0x5C00, 1), Ok(0xA5 + 0x5A));
    assert_eq!(rig.upload(0x5C00, 2), Ok(0xA5 + 0x5A));
    assert_eq!(rig.download(0x5040, 1, &[1]), Err(0x0602_0000));
    assert_eq!(rig.download(0x5000, 0x81, &[1]), Err(0x0609_0011));
}

#[test]
fn low_supply_refuses_every_memory_write_and_sends_the_voltage_emergencies() {
    let mut rig = Rig::new();
    rig.serial(&hex("12 01 91"));
    rig.serial(&hex("12 02 91"));
    rig.download(0x5000, 1, &[0x11]).unwrap();
    rig.take_sent();
    rig.dev.board_mut().supply_mv = 14_000;
    rig.run(1_000);
    assert_eq!(rig.emergencies(), [hex("00 10 01 00 40 00 00 00").try_into().unwrap()] as [[u8; 8]; 1]);
    assert_eq!(rig.upload(0x5F00, 0), Ok(14_000));
    assert_eq!(rig.download(0x5000, 1, &[0x22]), Err(0x0800_0022));
    assert_eq!(rig.serial(&hex("44 00 50 01 22")), hex("41 00"));
    assert_eq!(rig.upload(0x5000, 1), Ok(0x11), "nothing stored changed");
    assert_eq!(rig.upload(0x2105, 0).map(|v| v & 0x80), Ok(0x80));
    assert!(rig.dev.outputs().voltage_low);
    // Critical: both codes ORed (0x40 | 0x80).
    rig.dev.board_mut().supply_mv = 10_000;
    rig.run(1_000);
    assert_eq!(rig.emergencies(), [hex("00 10 01 00 C0 00 00 00").try_into().unwrap()] as [[u8; 8]; 1]);
    // Back to normal: two "error reset" frames, writes work again.
    rig.dev.board_mut().supply_mv = 24_000;
    rig.run(1_000);
    let resets = rig.emergencies();
    assert_eq!(resets.len(), 2);
    assert!(resets.iter().all(|f| f[0] == 0 && f[1] == 0));
    assert_eq!(rig.download(0x5000, 1, &[0x22]), Ok(()));
    assert!(!rig.dev.outputs().voltage_low);
}

#[test]
fn a_corrupt_bank_is_repaired_reported_by_emcy_and_tpdo_and_cleared_by_rpdo_command() {
    let mut rig = Rig::new();
    rig.serial(&hex("12 01 91"));
    rig.serial(&hex("12 02 91"));
    rig.download(0x5002, 3, &[0x77]).unwrap();
    rig.frame(0x000, &[0x01, NODE as u8]);
    rig.take_sent();
    // Corrupt byte 5002h.3 (address 2 * 128 + 2) in bank 2.
    let addr = 2 * (128 + 4) + 2;
    rig.dev.node_mut().od_mut().app.banks_mut().banks_mut()[1].as_bytes_mut()[addr] = 0x78;
    assert_eq!(rig.upload(0x5002, 3), Ok(0x77));
    rig.run(1_000);
    let sent = rig.take_sent();
    let emcy: Vec<_> = sent.iter().filter(|f| f.id == 0x80 + NODE).map(|f| f.data).collect();
    assert_eq!(emcy, [hex("00 10 01 00 20 00 00 00").try_into().unwrap()] as [[u8; 8]; 1]);
    let tpdo: Vec<_> = sent.iter().filter(|f| f.id == 0x180 + NODE).map(|f| f.payload().to_vec()).collect();
    assert!(tpdo.contains(&vec![0x00, 0x30]), "TPDO1 carries 6000h.1/.2: {tpdo:?}");
    assert!(rig.dev.outputs().mem2_error);
    // RPDO1 carries the command bytes: 0x91 for bank 2 clears its status and the emergency.
    rig.frame(0x200 + NODE, &[0x00, 0x91]);
    assert_eq!(rig.upload(0x6000, 2), Ok(0));
    let emcy = rig.emergencies();
    assert_eq!(emcy.len(), 1);
    assert_eq!(&emcy[0][..3], &[0, 0, 0]);
    assert!(!rig.dev.outputs().mem2_error);
    assert_eq!(rig.dev.node().od().app.banks().banks()[1].as_bytes()[addr], 0x77);
}

#[test]
fn a_power_cut_image_is_recovered_at_start_up() {
    let mut rig = Rig::new();
    rig.download(0x5000, 1, &[9]).unwrap();
    let banks = rig.dev.node().od().app.banks().banks().clone();
    // Bank 1 torn: its begin marker says a write was in progress.
    let mut torn = banks.clone();
    torn[0].as_bytes_mut()[128] ^= 0xFF;
    let mut rig = Rig::with_banks(torn);
    assert_eq!(rig.upload(0x5000, 1), Ok(9));
    assert_eq!(rig.upload(0x6000, 1), Ok(0x30));
    assert_eq!(rig.upload(0x6000, 2), Ok(0));
    assert_eq!(rig.dev.node().od().app.banks().banks()[0].as_bytes()[..132], banks[0].as_bytes()[..132]);
}

#[test]
fn an_nmt_reset_forgets_the_emergencies_but_the_conditions_raise_them_again() {
    let mut rig = Rig::new();
    rig.take_sent();
    rig.frame(0x000, &[0x81, NODE as u8]);
    rig.run(2_000);
    let sent = rig.take_sent();
    assert!(sent.iter().any(|f| f.id == 0x700 + NODE && f.payload() == [0]), "boot-up after the reset");
    let emcy: Vec<_> = sent.iter().filter(|f| f.id == 0x80 + NODE).map(|f| f.data).collect();
    // Both banks still report "cleared": bank 1's code, then both ORed.
    assert_eq!(emcy, [hex("00 10 01 00 10 00 00 00").try_into().unwrap(), hex("00 10 01 00 30 00 00 00").try_into().unwrap()] as [[u8; 8]; 2]);
    assert_eq!(rig.upload(0x1001, 0), Ok(0x01));
}

#[test]
fn bus_off_goes_out_on_recovery_with_the_active_warning_ored_in() {
    use coforge_stack::node::BusState;
    let mut rig = Rig::new();
    rig.serial(&hex("12 01 91"));
    rig.serial(&hex("12 02 91"));
    rig.take_sent();
    rig.dev.on_bus_state(BusState::Warning, rig.now_us);
    rig.run(1_000);
    assert_eq!(rig.emergencies(), [hex("00 81 11 00 00 00 00 40").try_into().unwrap()] as [[u8; 8]; 1]);
    rig.dev.on_bus_state(BusState::BusOff, rig.now_us);
    rig.run(1_000);
    assert!(rig.take_sent().is_empty(), "nothing leaves a bus-off controller");
    rig.dev.on_bus_state(BusState::Active, rig.now_us);
    rig.run(2_000);
    let emcy = rig.emergencies();
    // Erratum MEM-20: the bus-off frame with the warning's code ORed in (0xC0000000).
    assert_eq!(emcy.first(), Some(&hex("40 81 11 00 00 00 00 C0").try_into().unwrap()), "{emcy:02x?}");
    assert_eq!(emcy.last().map(|f| (f[0], f[1], f[2])), Some((0, 0, 0)), "all cleared at the end: {emcy:02x?}");
}

#[test]
fn a_block_lost_in_both_banks_is_refused_on_both_sides_never_returned() {
    let mut rig = Rig::new();
    rig.download(0x5003, 1, &[0x33]).unwrap();
    let addr = 3 * (128 + 4);
    for bank in rig.dev.node_mut().od_mut().app.banks_mut().banks_mut() {
        bank.as_bytes_mut()[addr] ^= 0x01;
    }
    let mut lost = Rig::with_banks(rig.dev.node().od().app.banks().banks().clone());
    assert_eq!(lost.upload(0x5003, 1), Err(0x0606_0000), "hardware error, not garbage");
    assert_eq!(lost.serial(&hex("33 03 50 02")), hex("32 00 00"));
    assert_eq!(lost.upload(0x6000, 1).map(|s| s & 0x10), Ok(0x10));
    assert_eq!(lost.upload(0x6000, 2).map(|s| s & 0x10), Ok(0x10));
    // Other blocks are unaffected.
    assert_eq!(lost.upload(0x5004, 1), Ok(0));
}

#[test]
fn block_transfer_is_refused_as_an_unknown_command_and_segmented_transfer_still_works() {
    // MEM-38: the datasheet does not offer SDO block transfer.
    let mut rig = Rig::new();
    let abort = |index: u16, sub: u8| {
        let [lo, hi] = index.to_le_bytes();
        [0x80, lo, hi, sub, 0x01, 0x00, 0x04, 0x05]
    };
    // Block upload initiate of 1008h (blksize 127), block download initiate of 5000h.1.
    assert_eq!(rig.sdo([0xA4, 0x08, 0x10, 0x00, 0x7F, 0x00, 0x00, 0x00]), abort(0x1008, 0));
    assert_eq!(rig.sdo([0xC6, 0x00, 0x50, 0x01, 0x01, 0x00, 0x00, 0x00]), abort(0x5000, 1));
    // The server is idle again: a segmented upload of the device name runs to its end.
    let init = rig.sdo([0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0]);
    assert_eq!(init[0], 0x41, "segmented upload initiate response: {init:02X?}");
    let mut name = Vec::new();
    let mut toggle = 0;
    loop {
        let seg = rig.sdo([0x60 | toggle, 0, 0, 0, 0, 0, 0, 0]);
        assert_eq!(seg[0] & 0xF0, toggle, "segment response {seg:02X?}");
        let unused = usize::from((seg[0] >> 1) & 7);
        name.extend_from_slice(&seg[1..8 - unused]);
        if seg[0] & 1 == 1 {
            break;
        }
        toggle ^= 0x10;
    }
    assert_eq!(u32::from_le_bytes(init[4..8].try_into().unwrap()) as usize, name.len());
    // Nothing was stored by the refused download.
    assert_eq!(rig.upload(0x5000, 1), Ok(0));
}

#[test]
fn a_supply_drop_between_polls_already_refuses_the_next_write() {
    // The guard samples the supply when a write arrives, not only in `poll`.
    let mut rig = Rig::new();
    rig.download(0x5000, 1, &[0x11]).unwrap();
    rig.dev.board_mut().supply_mv = 14_000;
    // No poll between the drop and the SDO request.
    assert_eq!(rig.download(0x5000, 1, &[0x22]), Err(0x0800_0022));
    rig.dev.board_mut().supply_mv = 24_000;
    assert_eq!(rig.upload(0x5000, 1), Ok(0x11), "nothing stored changed");
}
