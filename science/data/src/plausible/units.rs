//! Whole columns in a unit no capstan rig's data are in: refused (tensions in grams, wraps in
//! radians or turns), or warned about where they could be right (tensions all tiny, pairs
//! minutes apart).

use super::{
    line_of_row, log_gain, median, MU_MAX, PAIR_INTERVAL_MAX_S, RIG_TENSION_MAX_N,
    RIG_TENSION_SMALL_N,
};
use crate::Dataset;

/// Whole columns that look unusual but could be right: tensions all tiny, pairs far apart.
pub(super) fn column_warnings(ds: &Dataset) -> Vec<String> {
    let mut out = Vec::new();
    let largest = ds
        .pairs
        .iter()
        .map(|p| p.t1_n.abs().max(p.t2_n.abs()))
        .fold(0.0, f64::max);
    if largest < RIG_TENSION_SMALL_N {
        out.push(format!(
            "every tension is below {RIG_TENSION_SMALL_N} N (the largest is {largest:.4} N), \
             under ten counts of a rig's sensor: were they logged in kN (×1000 gives N)?"
        ));
    }
    if let Some(dt) = pair_interval_s(ds).filter(|&dt| dt > PAIR_INTERVAL_MAX_S) {
        out.push(format!(
            "the pairs of a run are {dt:.0} s apart (median of time_s steps within runs), a \
             protocol dwells seconds: is time_s in milliseconds (÷1000 gives s)?"
        ));
    }
    out
}

/// The median time between successive pairs of a run, s (runs from any source).
fn pair_interval_s(ds: &Dataset) -> Option<f64> {
    if !ds.has_column("time_s") {
        return None;
    }
    let st = &ds.structure;
    let mut last: Vec<Option<f64>> = vec![None; st.run_cord.len()];
    let mut steps = Vec::new();
    for (i, p) in ds.pairs.iter().enumerate() {
        let (Some(t), Some(&r)) = (p.time_s, st.run_of_row.get(i)) else {
            continue;
        };
        if let Some(prev) = last[r].filter(|&prev| t > prev) {
            steps.push(t - prev);
        }
        last[r] = Some(t);
    }
    median(steps)
}

/// A column in a unit no capstan rig's data are in: the tensions beyond
/// [`RIG_TENSION_MAX_N`] (grams?), or the median row's friction coefficient beyond [`MU_MAX`]
/// (wraps in radians or turns?): the line and column to name, and the sentence.
pub fn unit_mistake(ds: &Dataset) -> Option<(u64, usize, String)> {
    let col = |name: &str| {
        ds.header
            .iter()
            .position(|h| h == name)
            .map_or(0, |c| c + 1)
    };
    let (mut worst, mut at, mut which) = (0.0f64, 0usize, "t1_n");
    for (i, p) in ds.pairs.iter().enumerate() {
        for (v, name) in [(p.t1_n, "t1_n"), (p.t2_n, "t2_n")] {
            if v.abs() > worst {
                (worst, at, which) = (v.abs(), i, name);
            }
        }
    }
    if worst > RIG_TENSION_MAX_N {
        return Some((
            line_of_row(ds, at),
            col(which),
            format!(
                "{which} = {worst} N: no bench capstan rig reads above {RIG_TENSION_MAX_N} N (the \
                 thesis rig's sensors end at ~55 N); were the tensions logged in grams (÷101.97 \
                 gives N: {:.2} N here) or another unit? Convert the column to newtons",
                worst / 101.971_621
            ),
        ));
    }
    let mu = median(
        ds.pairs
            .iter()
            .filter_map(|p| log_gain(p).map(|g| g / p.wrap_rad()))
            .collect(),
    )?;
    if mu <= MU_MAX {
        return None;
    }
    let (i, widest) = ds
        .pairs
        .iter()
        .enumerate()
        .map(|(i, p)| (i, p.wrap_deg))
        .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
    let guess = if widest <= 4.0 * std::f64::consts::PI + 1e-9 {
        format!(
            "radians? (×57.296 gives degrees: {:.0} deg here)",
            widest.to_degrees()
        )
    } else if widest <= 10.0 {
        format!(
            "turns? (×360 gives degrees: {:.0} deg here)",
            widest * 360.0
        )
    } else {
        "another unit than degrees?".to_string()
    };
    Some((
        line_of_row(ds, i),
        col("wrap_deg"),
        format!(
            "the wraps give a friction coefficient mu = {mu:.3} (median row, ln(T2/T1) over the \
             wrap), and no cord on a drum reaches {MU_MAX}: are the wraps (at most {widest:.4} \
             \"deg\") in {guess}"
        ),
    ))
}
