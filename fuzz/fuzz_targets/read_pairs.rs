//! Any bytes as a pairs CSV (what `analyze` and `diagnose` read): refused with a located
//! message or read, never a panic or unbounded memory; what is read writes back and reads
//! back the same.
#![no_main]

use capstan_data::{check_capstan_data, read_pairs, write_pairs_to};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(ds) = read_pairs(data, "fuzz.csv") else {
        return;
    };
    let _ = check_capstan_data(&ds);
    // Written with the schema's writer (standard columns only), it reads back to the same
    // numbers; text labels (which may be what tells two runs apart) are not written, so a set
    // with them is not written back.
    if !ds.label_columns.is_empty() {
        return;
    }
    let mut out = Vec::new();
    write_pairs_to(&mut out, &ds.pairs).expect("writing to memory");
    let again = read_pairs(&out[..], "again.csv").expect("what was written reads back");
    assert_eq!(again.pairs.len(), ds.pairs.len());
    for (a, b) in ds.pairs.iter().zip(&again.pairs) {
        assert_eq!(
            (a.wrap_deg, a.t1_n, a.t2_n, a.run, a.step, a.time_s),
            (b.wrap_deg, b.t1_n, b.t2_n, b.run, b.step, b.time_s)
        );
    }
});
