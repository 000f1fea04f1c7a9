//! Close the loop: the firmware run against the simulated plant (`host_sim::campaign`) with the
//! extended model as the plant's friction law (each cord with its own fitted mu factor, the
//! contact heating and the T1-path loss), on the thesis campaign, one run per cord.

use super::Analysis;
use host_sim::campaign::{run_campaign, CampaignConfig};
use serde_json::{json, Value};

/// Simulated amplification curves (cord index, (T1, T2/T1)) and a summary.
pub fn run(a: &Analysis) -> anyhow::Result<(Vec<(usize, Vec<(f64, f64)>)>, Value)> {
    let mut curves = Vec::new();
    let mut n = 0usize;
    for (g, grp) in a.obs.groups.iter().enumerate() {
        let cfg = CampaignConfig {
            diameters_mm: vec![grp.diameter_mm],
            wraps_deg: vec![grp.wrap_deg],
            runs: 1,
            model: a.extended_fit.model(Some(g)),
            sensor_noise: false,
            ..CampaignConfig::default()
        };
        let res = run_campaign(&cfg)
            .map_err(|e| anyhow::anyhow!("closed loop, cord {}: {e:?}", grp.label))?;
        let mut pts: Vec<(f64, f64)> = res.rows.iter().map(|r| (r.t1_n, r.t2_n / r.t1_n)).collect();
        pts.sort_by(|x, y| x.0.total_cmp(&y.0));
        n += res.rows.len();
        curves.push((g, pts));
    }
    Ok((
        curves,
        json!({"runs": a.obs.groups.len(), "runs_per_cord": 1, "pairs": n, "plant": "host_sim::campaign with the extended model per cord (sensor noise off)"}),
    ))
}
