//! Runtime cost of generated code on the host: dictionary access through the generated
//! dispatch, and deframing + decoding of each device's datasheet frames (per frame and per
//! byte). Cortex-M instruction counts come with the board images.

use coforge_link::{Deframer, Message, SerialCodec};
use coforge_stack::od::{AccessContext, EntryAccess, NmtState, NoAppObjects, Side};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;

const OP: AccessContext = AccessContext { nmt: NmtState::Operational, can_enabled: true };

fn dictionary(c: &mut Criterion) {
    let mut od = co401gw1::Od::new(co401gw1::Mode::Mixed, 5, NoAppObjects);
    let mut buf = [0_u8; 8];
    c.bench_function("od/co401gw1/read_1018_1", |b| b.iter(|| od.read(black_box(0x1018), black_box(1), 0, &mut buf, Side::Bus)));
    c.bench_function("od/co401gw1/write_1017", |b| b.iter(|| od.write(black_box(0x1017), 0, black_box(&[0xE8, 0x03]), Side::Bus, &OP)));
    c.bench_function("od/co401gw1/read_6000_8", |b| b.iter(|| od.read(black_box(0x6000), black_box(8), 0, &mut buf, Side::Bus)));
    c.bench_function("od/co401gw1/refused_write_1000", |b| b.iter(|| od.write(black_box(0x1000), 0, black_box(&[0; 4]), Side::Bus, &OP)));
}

/// Deframes and decodes one frame with codec `C`; returns whether it decoded.
fn decode_once<C: SerialCodec>(bytes: &[u8]) -> bool {
    let mut d = C::decoder();
    let mut ok = false;
    for (i, &b) in bytes.iter().enumerate() {
        if let Some(Ok(f)) = d.push(b, i as u32) {
            ok = C::HostToDevice::decode(&f).is_ok() || C::DeviceToHost::decode(&f).is_ok();
        }
    }
    ok
}

fn codecs(c: &mut Criterion) {
    let frames: [(&str, &[u8]); 3] = [
        ("co401memory1/write_memory", &[0x44, 0x12, 0x50, 0x04, 0xAB]),
        ("co401gw1/read_od_answer", &[0x21, 0x07, 0x18, 0x10, 0x04, 0x78, 0x56, 0x34, 0x12]),
        ("canopenia/read_local", &[0x11, 0x04, 0x52, 0x00, 0x5F, 0x02, 0x96, 0x2F]),
    ];
    let mut group = c.benchmark_group("decode");
    for (name, bytes) in frames {
        group.throughput(Throughput::Bytes(bytes.len() as u64));
        group.bench_function(name, |b| {
            b.iter(|| match name.split('/').next() {
                Some("co401memory1") => decode_once::<co401memory1::serial::Codec>(black_box(bytes)),
                Some("co401gw1") => decode_once::<co401gw1::serial::Codec>(black_box(bytes)),
                _ => decode_once::<canopenia::serial::Codec>(black_box(bytes)),
            })
        });
    }
    group.finish();
}

/// One request into a CO401GW1 node in Operational, through to the frames it answers with.
fn node(c: &mut Criterion) {
    use coforge_verification::node::requests;
    let mut n = requests::node(255);
    c.bench_function("node/co401gw1/sdo_expedited_upload", |b| b.iter(|| requests::sdo_upload(black_box(&mut n))));
    c.bench_function("node/co401gw1/sdo_expedited_download", |b| b.iter(|| requests::sdo_download(black_box(&mut n))));
    c.bench_function("node/co401gw1/rpdo", |b| b.iter(|| requests::rpdo(black_box(&mut n))));
    let mut t = 0;
    c.bench_function("node/co401gw1/tpdo_event", |b| {
        b.iter(|| {
            t += 1;
            requests::tpdo_event(black_box(&mut n), t)
        })
    });
    let mut s = requests::node(1);
    c.bench_function("node/co401gw1/sync_2_tpdos", |b| b.iter(|| requests::sync(black_box(&mut s))));
    println!("size_of Node<co401gw1> = {} bytes", core::mem::size_of::<requests::GwNode>());
}

criterion_group!(benches, dictionary, codecs, node);
criterion_main!(benches);
