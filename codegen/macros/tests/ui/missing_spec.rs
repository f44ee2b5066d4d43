coforge_macros::device!("../../../../spec/no-such-device.yaml");

fn main() {}
