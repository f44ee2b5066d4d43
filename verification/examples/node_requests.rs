//! `node_requests <request> <count>`: runs one request `count` times, for instruction counts
//! under callgrind (`cargo xtask bench-node` subtracts a run with count 0).

use coforge_verification::node::requests::{self, GwNode};
use std::hint::black_box;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (Some(which), Some(count)) = (args.get(1), args.get(2).and_then(|c| c.parse::<u64>().ok())) else {
        eprintln!("usage: node_requests <sdo_upload|sdo_download|rpdo|tpdo_event|sync> <count>");
        std::process::exit(2);
    };
    let mut node: GwNode = requests::node(if which == "sync" { 1 } else { 255 });
    let mut sent = 0;
    for i in 0..count {
        sent += match which.as_str() {
            "sdo_upload" => requests::sdo_upload(black_box(&mut node)),
            "sdo_download" => requests::sdo_download(black_box(&mut node)),
            "rpdo" => requests::rpdo(black_box(&mut node)),
            "tpdo_event" => requests::tpdo_event(black_box(&mut node), i),
            "sync" => requests::sync(black_box(&mut node)),
            other => {
                eprintln!("unknown request `{other}`");
                std::process::exit(2);
            }
        };
    }
    println!("{which}: {count} requests, {sent} frames sent; size_of Node<co401gw1> = {} bytes", core::mem::size_of::<GwNode>());
}
