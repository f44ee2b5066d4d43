//! The hooks a manager device needs, through the generated `app::Typed`: CANopenIA takes its
//! 2,217-byte configuration file into 1F50h.2 through the generated node's 4-byte SDO
//! buffer, streamed to its `Hooks`, and hears every write of its entries.

use canopenia::app::{Hooks, Typed};
use coforge_stack::frame::CanFrame;
use coforge_stack::node::Node;
use coforge_stack::od::{ReadLen, SdoAbort, WriteSource};
use coforge_stack::store::NoStore;

const ID: u8 = 0x70;

/// CANopenIA's configuration loader: 1F50h.2 streams into `incoming`.
#[derive(Debug, Default)]
struct Loader {
    incoming: Vec<u8>,
    loaded: Vec<u8>,
    aborts: usize,
    written: Vec<(u16, u8, usize, WriteSource)>,
}

impl Hooks for Loader {
    fn read_program_data(&mut self, _: u8, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        coforge_stack::od::read_slice(&self.loaded, offset, buf)
    }

    fn write_program_data(&mut self, _: u8, data: &[u8]) -> Result<(), SdoAbort> {
        self.loaded = data.to_vec();
        Ok(())
    }

    fn read_program_control(&mut self, _: u8) -> Result<u8, SdoAbort> {
        Ok(1)
    }

    fn write_program_control(&mut self, _: u8, _: u8) -> Result<(), SdoAbort> {
        Ok(())
    }

    fn written(&mut self, index: u16, sub: u8, data: &[u8], by: WriteSource) {
        self.written.push((index, sub, data.len(), by));
    }

    const STREAMING: bool = true;

    fn streams(&mut self, index: u16, sub: u8) -> bool {
        (index, sub) == (0x1F50, 2)
    }

    fn write_part(&mut self, _: u16, _: u8, offset: usize, data: &[u8], last: bool) -> Result<(), SdoAbort> {
        assert_eq!(offset, self.incoming.len());
        self.incoming.extend_from_slice(data);
        if last {
            self.loaded = std::mem::take(&mut self.incoming);
        }
        Ok(())
    }

    fn abort_stream(&mut self, _: u16, _: u8) {
        self.incoming.clear();
        self.aborts += 1;
    }
}

type Ia = canopenia::Node<Typed<Loader>, NoStore>;

/// The SDO answer to one request.
fn sdo(n: &mut Ia, request: [u8; 8]) -> [u8; 8] {
    n.on_frame(&CanFrame::data(0x600 + u16::from(ID), &request).expect("a frame"), 0);
    let answers: Vec<[u8; 8]> = std::iter::from_fn(|| n.poll(0)).filter(|f| f.id == 0x580 + u16::from(ID)).map(|f| f.data).collect();
    assert_eq!(answers.len(), 1, "{answers:?}");
    answers[0]
}

#[test]
fn canopenia_streams_its_configuration_file_through_a_4_byte_buffer() {
    assert_eq!(canopenia::od::MAX_WRITE_SIZE, 4, "the buffer the generated node has");
    let mut n: Ia = Node::of_dictionary(canopenia::Mode::ALL[0], ID, Typed(Loader::default()), NoStore);
    n.start(0);
    std::iter::from_fn(|| n.poll(0)).for_each(drop);
    let file: Vec<u8> = (0..2217_u32).map(|i| (i * 7 + i / 11) as u8).collect();
    let [s0, s1, s2, s3] = (file.len() as u32).to_le_bytes();
    assert_eq!(sdo(&mut n, [0x21, 0x50, 0x1F, 2, s0, s1, s2, s3]), [0x60, 0x50, 0x1F, 2, 0, 0, 0, 0]);
    let chunks: Vec<&[u8]> = file.chunks(7).collect();
    for (i, chunk) in chunks.iter().enumerate() {
        let mut f = [0; 8];
        f[0] = (i as u8 & 1) << 4 | (7 - chunk.len() as u8) << 1 | u8::from(i + 1 == chunks.len());
        f[1..1 + chunk.len()].copy_from_slice(chunk);
        assert_eq!(sdo(&mut n, f)[0], 0x20 | (i as u8 & 1) << 4, "segment {i}");
    }
    let loader = &n.od().app.0;
    assert_eq!(loader.loaded, file, "complete and in order");
    assert_eq!(loader.aborts, 0);
    assert_eq!(loader.written, [(0x1F50, 2, 0, WriteSource::Sdo)], "indicated once complete");
    // An ordinary entry's write is indicated with its data; an aborted stream is voided.
    assert_eq!(sdo(&mut n, [0x2F, 0x51, 0x1F, 1, 1, 0, 0, 0]), [0x60, 0x51, 0x1F, 1, 0, 0, 0, 0]);
    assert_eq!(n.od().app.written.last(), Some(&(0x1F51, 1, 1, WriteSource::Sdo)));
    assert_eq!(sdo(&mut n, [0x21, 0x50, 0x1F, 2, s0, s1, s2, s3])[0], 0x60);
    n.on_frame(&CanFrame::data(0x000, &[0x82, ID]).expect("a frame"), 0);
    assert_eq!(n.od().app.aborts, 1, "reset communication dropped the transfer");
    assert_eq!(n.od().app.loaded, file, "the last complete file stays");
}
