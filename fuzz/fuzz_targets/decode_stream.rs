//! Any bytes, in chunks of any size, through the stream decoder with the recorded firmware's
//! table: it must never panic, abort or hang.
#![no_main]

use capstan_link::{Decoder, Firmware};
use libfuzzer_sys::fuzz_target;
use std::sync::OnceLock;

static FW: OnceLock<Firmware> = OnceLock::new();

fuzz_target!(|data: &[u8]| {
    let fw = FW.get_or_init(|| {
        Firmware::from_elf_bytes(
            include_bytes!("../../tests/data/qemu-fw.elf"),
            "qemu-fw.elf",
        )
        .expect("the recorded ELF loads")
    });
    // The first byte sets the chunk size: a stream arrives in pieces of any size.
    let Some((&c, stream)) = data.split_first() else {
        return;
    };
    let mut d = Decoder::new(fw);
    let (mut events, mut bad) = (Vec::new(), Vec::new());
    for chunk in stream.chunks(c as usize % 97 + 1) {
        d.push(chunk, &mut events, &mut bad);
    }
    let _ = d.finish();
    assert_eq!(
        d.records + d.messages + d.bad_frames,
        d.frames_seen,
        "every frame is accounted for"
    );
});
