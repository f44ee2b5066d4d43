//! Static RAM of a node: the aim is CO401GW1's whole node (dictionary, every protocol
//! engine, SDO buffer, queues) within the 2 KiB of the MCU family the original chip ran on.
//! Measured on the host, where u64 and pointers are at least as large as on Cortex-M.

use coforge_stack::od::NoAppObjects;
use coforge_stack::store::NoStore;

#[test]
fn co401gw1_node_fits_2_kib() {
    let size = core::mem::size_of::<co401gw1::Node<NoAppObjects, NoStore>>();
    println!("size_of Node<co401gw1> = {size} bytes");
    assert!(size <= 2048, "Node<co401gw1> takes {size} bytes");
}

#[test]
fn every_node_size_is_reported() {
    let sizes = [
        ("co401memory1", core::mem::size_of::<co401memory1::Node<NoAppObjects, NoStore>>()),
        ("co401gw1", core::mem::size_of::<co401gw1::Node<NoAppObjects, NoStore>>()),
        ("cr3101", core::mem::size_of::<cr3101::Node<NoAppObjects, NoStore>>()),
        ("canopenia", core::mem::size_of::<canopenia::Node<NoAppObjects, NoStore>>()),
    ];
    for (name, size) in sizes {
        println!("size_of Node<{name}> = {size} bytes");
        // The dictionary alone is larger than the stack's fixed part (~1.1 KiB).
        assert!(size > 1024, "{name}");
    }
}
