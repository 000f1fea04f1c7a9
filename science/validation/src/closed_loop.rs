//! Close the loop: the firmware run against the simulated plant (`capstan_sim::campaign`) with the
//! extended model as the plant's friction law (each cord with its own fitted mu factor and the
//! causes the evidence engine named), on the thesis campaign, one run per cord.

use capstan_engine::analysis::closed_loop::{evenly, SimCurve, Summary};
use capstan_engine::analysis::Analysis;
use capstan_engine::fit::par::par_map;
use capstan_sim::campaign::{run_campaign, CampaignConfig};

/// The closed-loop simulation of every cord.
#[derive(Clone, Debug)]
pub struct ClosedLoop {
    /// One curve per cord.
    pub curves: Vec<SimCurve>,
    /// What was simulated (for `metrics.json`).
    pub summary: Summary,
}

/// The most cords simulated: a data set with more gets this many, evenly spaced in the cord
/// order (each run takes ~30 ms; the thesis has 10 cords).
pub const MAX_CORDS: usize = 12;

/// Simulate one run per cord with the cord's extended model (cords on up to `threads` threads;
/// at most [`MAX_CORDS`] cords).
pub fn run(a: &Analysis, threads: usize) -> Result<ClosedLoop, crate::ValidationError> {
    let groups = evenly(a.obs.groups.len(), MAX_CORDS);
    let runs = par_map(&groups, threads, |&g| {
        let grp = &a.obs.groups[g];
        let cfg = CampaignConfig {
            diameters_mm: vec![grp.diameter_mm],
            wraps_deg: vec![grp.wrap_deg],
            runs: 1,
            model: a.extended_fit.model(Some(g)),
            sensor_noise: false,
            ..CampaignConfig::default()
        };
        run_campaign(&cfg).map_err(|cause| crate::ValidationError::ClosedLoop {
            cord: grp.label.clone(),
            cause: Box::new(cause),
        })
    });
    let mut curves = Vec::new();
    let mut n = 0usize;
    for (&g, res) in groups.iter().zip(runs) {
        let res = res?;
        let mut pts: Vec<(f64, f64)> = res.rows.iter().map(|r| (r.t1_n, r.t2_n / r.t1_n)).collect();
        pts.sort_by(|x, y| x.0.total_cmp(&y.0));
        n += res.rows.len();
        curves.push((g, pts));
    }
    Ok(ClosedLoop {
        curves,
        summary: Summary {
            runs: groups.len(),
            cords: a.obs.groups.len(),
            runs_per_cord: 1,
            pairs: n,
            plant: "capstan_sim::campaign with the extended model per cord (sensor noise off)",
            cords_note: if groups.len() < a.obs.groups.len() {
                format!(
                    "{} of {} cords simulated, evenly spaced in the cord order",
                    groups.len(),
                    a.obs.groups.len()
                )
            } else {
                "every cord simulated".to_string()
            },
        },
    })
}
