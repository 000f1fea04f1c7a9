//! The simulator's pairs in the data schema: `host_sim`'s rows (one per conditioned step) as
//! `capstan_data` pairs, the one conversion `capstan simulate` and the generated cases share.

use capstan_data::Pair;
use capstan_sim::campaign::PairRow;

/// The simulator's rows as pairs of the CSV schema: what `capstan simulate` writes to
/// `pairs.csv`, and what the generated cases read back.
pub fn to_pairs(rows: &[PairRow]) -> Vec<Pair> {
    rows.iter()
        .map(|r| Pair {
            capstan_diameter_mm: Some(r.capstan_diameter_mm),
            wrap_deg: r.wrap_deg,
            drive_v: Some(r.drive_v),
            run: Some(r.run as f64),
            step: Some(r.step as f64),
            time_s: Some(r.time_s),
            t1_n: r.t1_n,
            t2_n: r.t2_n,
            extra: Vec::new(),
            labels: Vec::new(),
        })
        .collect()
}
