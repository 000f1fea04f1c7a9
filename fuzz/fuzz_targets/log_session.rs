//! Any bytes through a whole `capstan log` session (decoder, run bookkeeping, the CSV files,
//! the summary): it must never panic, and what it writes must read back.
#![no_main]

use capstan_log::{LogOptions, Logger, SetupFlags, Stop};
use capstan_link::Firmware;
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
    let dir = std::env::temp_dir().join(format!("capstan-fuzz-{}", std::process::id()));
    let opts = LogOptions {
        out_dir: dir.clone(),
        overwrite: true,
        save_stream: false,
        setup: SetupFlags::default(),
        progress: false,
        allow_empty: true,
        kept_after_failure: |_| {},
    };
    let mut logger =
        Logger::create(fw, opts, "fuzz", Box::new(|_| {})).expect("temp dir is writable");
    logger.feed(data).expect("files are writable");
    let summary = logger
        .finish(&Stop::EndOfStream)
        .expect("summary is written");
    let _ = summary.human(&dir);
    // pairs.csv always reads back as the analysis reads it (incomplete rows go to
    // pairs-incomplete.csv). The only refusals allowed: no rows, or a value beyond what a rig
    // can measure (the reader's documented limits; the logger writes what it received).
    if let Err(e) = capstan_data::load_pairs(&dir.join("pairs.csv")) {
        let e = e.to_string();
        let allowed = [
            "no data rows",
            "beyond any force sensor",
            "must be within",
            "must be at most",
            "must be greater than 0",
        ];
        assert!(allowed.iter().any(|a| e.contains(a)), "{e}");
    }
});
