//! Does `capstan predict`'s 95 % prediction interval cover new cords? Leave each cord out,
//! analyse the rest (the whole analysis, its prediction model included), and predict the cord's
//! measured T2 at its measured T1 as the sensors read them: the share of its rows inside the
//! interval, over all rows, per cord and per tension band, with the interval's mean width.

use super::prediction::{predict, Query};
use super::{run, Options};
use capstan_data::Dataset;
use serde::Serialize;

/// The T2 bands the coverage is reported in, N (upper bounds; the last is open).
pub const BANDS_N: [f64; 3] = [5.0, 15.0, f64::INFINITY];

/// Rows inside the interval, of rows.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Share {
    /// What the rows are (a cord's label, a band).
    pub what: String,
    /// Rows predicted.
    pub rows: usize,
    /// Of which inside the 95 % prediction interval.
    pub inside: usize,
    /// Mean width of the interval over them, N.
    pub mean_width_n: f64,
}

impl Share {
    /// inside / rows.
    pub fn fraction(&self) -> f64 {
        self.inside as f64 / self.rows.max(1) as f64
    }

    fn add(&mut self, inside: bool, width: f64) {
        self.mean_width_n = (self.mean_width_n * self.rows as f64 + width) / (self.rows + 1) as f64;
        self.rows += 1;
        self.inside += usize::from(inside);
    }
}

/// The coverage of new cords.
#[derive(Clone, Debug, Serialize)]
pub struct Coverage {
    /// Every row of every cord.
    pub overall: Share,
    /// Per cord.
    pub per_cord: Vec<Share>,
    /// Per measured-T2 band.
    pub per_band: Vec<Share>,
    /// Cords whose analysis without them failed, with why.
    pub failed: Vec<(String, String)>,
}

/// Each cord of `ds` predicted by the analysis of the others (see the module docs).
pub fn coverage(ds: &Dataset, opts: Options) -> Coverage {
    let st = &ds.structure;
    let labels: Vec<String> = st
        .cords
        .iter()
        .map(|c| {
            let mut l = format!("D{}/{}deg", c.diameter_mm, c.wrap_deg);
            for x in &c.labels {
                l += &format!("/{x}");
            }
            l
        })
        .collect();
    let mut overall = Share {
        what: "all rows".into(),
        ..Share::default()
    };
    let mut per_band: Vec<Share> = BANDS_N
        .iter()
        .scan(0.0, |lo, &hi| {
            let what = if hi.is_finite() {
                format!("T2 {lo}–{hi} N")
            } else {
                format!("T2 ≥ {lo} N")
            };
            *lo = hi;
            Some(Share {
                what,
                ..Share::default()
            })
        })
        .collect();
    let mut per_cord = Vec::new();
    let mut failed = Vec::new();
    for (c, label) in labels.iter().enumerate() {
        let analysed = super::heldout::subset(ds, |i| st.cord_of_row[i] != c)
            .map_err(|e| e.to_string())
            .and_then(|d| run(&d, opts).map_err(|e| e.to_string()));
        let a = match analysed {
            Ok(a) => a,
            Err(why) => {
                failed.push((label.clone(), why));
                continue;
            }
        };
        let pm = &a.prediction_model;
        let mut share = Share {
            what: label.clone(),
            ..Share::default()
        };
        for (i, p) in ds.pairs.iter().enumerate() {
            if st.cord_of_row[i] != c {
                continue;
            }
            let q = Query {
                wrap_deg: p.wrap_deg,
                diameter_mm: p
                    .capstan_diameter_mm
                    .unwrap_or(capstan_physics::REF_DIAMETER_MM),
                drive_v: p.drive_v.unwrap_or(super::prediction::DEFAULT_DRIVE_V),
                t1_n: p.t1_n,
                as_measured: true,
            };
            let pr = predict(pm, &q);
            let inside = pr.t2_pi95.lo <= p.t2_n && p.t2_n <= pr.t2_pi95.hi;
            let width = pr.t2_pi95.hi - pr.t2_pi95.lo;
            share.add(inside, width);
            overall.add(inside, width);
            let band = BANDS_N.iter().position(|&hi| p.t2_n < hi).unwrap_or(0);
            per_band[band].add(inside, width);
        }
        per_cord.push(share);
    }
    Coverage {
        overall,
        per_cord,
        per_band,
        failed,
    }
}

impl Coverage {
    /// The coverage in lines: overall, per band, per cord.
    pub fn lines(&self) -> Vec<String> {
        let line = |s: &Share| {
            format!(
                "{:<18} {:>4}/{:<4} {:5.1} %   mean width {:.2} N",
                s.what,
                s.inside,
                s.rows,
                100.0 * s.fraction(),
                s.mean_width_n
            )
        };
        let mut out = vec![line(&self.overall)];
        out.extend(self.per_band.iter().map(line));
        out.extend(self.per_cord.iter().map(line));
        out.extend(
            self.failed
                .iter()
                .map(|(c, why)| format!("{c}: no prediction ({why})")),
        );
        out
    }
}
