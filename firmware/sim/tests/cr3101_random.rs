#![allow(clippy::unwrap_used, clippy::indexing_slicing)]
//! CR3101 under bounded random input: SDO writes and reads of every card-backed object with
//! random sub-indices and lengths, RPDO frames of random lengths, NMT commands, time jumps, and
//! the card pulled and put back. Nothing may panic, and whatever happened, the card must stay a
//! clean FAT volume whose configuration file the device reads back.

use coforge_sim::cr3101::{SimBoard, SimCr3101};
use coforge_sim::devices::Console;
use coforge_sim::storage::Eeprom;
use coforge_stack::device::Device;
use coforge_stack::frame::CanFrame;
use coforge_stack::od::Side;
use coforge_stack::store::BlockStore;
use cr3101::card::settings::{self, Settings};

mod card_tools;
use card_tools::{copy_out, fsck_clean, image};

const NODE: u8 = 0x20;

/// An object CR3101 serves from its card or clock, or one of its settings.
fn index(rng: &mut fastrand::Rng) -> u16 {
    let file = 0x100 * rng.u64(..8) as u16;
    match rng.u64(..6) {
        0 => [0x2000, 0x2001, 0x2002, 0x2003, 0x2010, 0x20F5][rng.u64(..6) as usize],
        1 => 0x3000 + file + rng.u64(..7) as u16,
        2 => 0x3010 + file + rng.u64(..8) as u16,
        3 | 4 => 0x5000 + file,
        _ => 0x3003 + file,
    }
}

/// Values that make sense more often than uniform bytes would.
fn data(rng: &mut fastrand::Rng) -> Vec<u8> {
    let len = [1, 2, 4, 4, 0, 3, 8, 11, 12][rng.u64(..9) as usize];
    let pick = rng.u64(..4);
    (0..len)
        .map(|i| match pick {
            0 => rng.u64(..) as u8,
            1 => [0x01, 0x02, 0x03, 0x10, 0x55, 0][rng.u64(..6) as usize],
            2 if i == 0 => rng.u64(..64) as u8,
            2 => 0,
            _ => b"ABCDEFGH_1"[rng.u64(..10) as usize],
        })
        .collect()
}

fn run(seed: u64) {
    let path = image(&format!("random-{seed}"));
    let mut d = SimCr3101::new(SimBoard::new(Some(path.to_path_buf())).unwrap(), BlockStore::new(Eeprom::new(4096), 0), NODE);
    let mut rng = fastrand::Rng::with_seed(seed);
    let mut now = 0_u64;
    d.start(now);
    let mut in_slot = true;
    for _ in 0..800 {
        now += rng.u64(..30_000);
        match rng.u64(..10) {
            0..=3 => {
                let (i, sub) = (index(&mut rng), rng.u64(..17) as u8);
                let _ = Device::node_mut(&mut d).write(i, sub, &data(&mut rng), Side::Bus);
            }
            4 => {
                let mut buf = [0; 16];
                let _ = Device::node_mut(&mut d).read(index(&mut rng), rng.u64(..17) as u8, 0, &mut buf, Side::Bus);
            }
            5 | 6 => {
                let id = [0x200, 0x300, 0x400, 0x500][rng.u64(..4) as usize] + u16::from(NODE);
                let payload: Vec<u8> = (0..rng.u64(..9)).map(|_| rng.u64(..) as u8).collect();
                d.on_frame(&CanFrame::data(id, &payload).unwrap(), now);
            }
            7 => d.on_frame(&CanFrame::data(0, &[[0x01, 0x80, 0x02, 0x82][rng.u64(..4) as usize], NODE]).unwrap(), now),
            8 => {
                in_slot = !in_slot;
                d.console(if in_slot { "card insert" } else { "card remove" }).unwrap();
            }
            _ => {}
        }
        while d.poll(now).is_some() {}
    }
    d.console("card remove").unwrap();
    while d.poll(now + 200_000).is_some() {}
    assert!(fsck_clean(&path), "seed {seed}: fsck.fat -n finds the card clean");
    let config = copy_out(&path, settings::FILE_NAME);
    let config: [u8; settings::LEN] = config.try_into().unwrap_or_else(|c: Vec<u8>| panic!("seed {seed}: CANMEM.CFG of {} bytes", c.len()));
    assert!(Settings::decode(&config).is_some(), "seed {seed}: the configuration file reads back");
}

#[test]
fn random_input_never_breaks_the_card_or_its_configuration() {
    for seed in 1..=40 {
        run(seed);
    }
}
