//! The report's section quoting `capstan diagnose` on the same data.

use super::html::esc;
use crate::analysis::diagnosis::{verdict, Call, DiagnoseQuote};
use crate::diagnose::words::parameter;
use std::fmt::Write as _;

/// How many candidates of each call the table shows.
const TOP: usize = 4;

fn call_table(h: &mut String, c: &Call) {
    let d = &c.result;
    let _ = write!(
        h,
        "<p><code>{}</code> (<code>{}</code>): <b>{}</b>.</p><table><tr><th>candidate</th><th>level</th><th>parameter ± SE</th><th>ΔBIC against none</th><th>supported</th></tr>",
        esc(c.call),
        esc(c.command),
        esc(&verdict(d))
    );
    for k in d.candidates.iter().take(TOP) {
        let level = serde_json::to_value(k.level).ok();
        let _ = write!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{:.1}</td><td>{}</td></tr>",
            k.effect,
            level.as_ref().and_then(|v| v.as_str()).unwrap_or(""),
            esc(&k
                .parameters
                .iter()
                .next()
                .map_or(String::new(), |(n, v)| parameter(n, *v, k.parameter_se))),
            k.delta_bic,
            if k.supported { "yes" } else { "no" }
        );
    }
    h.push_str("</table>");
    if !d.not_testable.is_empty() {
        let nt: Vec<String> = d
            .not_testable
            .iter()
            .map(|n| format!("{} ({})", n.effect, esc(&n.reason)))
            .collect();
        let _ = write!(h, "<p>Not testable: {}.</p>", nt.join(", "));
    }
}

/// The section: both calls with their top candidates, then how they relate to the analysis.
pub fn section(h: &mut String, q: &DiagnoseQuote) {
    let d = &q.default.result;
    let _ = write!(h, "<h2>What <code>capstan diagnose</code> finds on the same data</h2><p>The diagnosis (src/diagnose) is run by <code>capstan analyze</code> on the same data set; ΔBIC is against plain Euler-Eytelwein (negative: the effect is supported), a candidate is supported below {:.0} (shape within runs) or {:.0} (between runs and cords) and outside the rig's resolution. Cord-to-cord scatter of mu {:.1} %, run-to-run {:.1} %.</p>",
        d.thresholds.within_run, d.thresholds.between, d.scatter.cord_pct, d.scatter.run_pct);
    call_table(h, &q.default);
    if let Some(p) = &q.protocol_times {
        call_table(h, p);
    }
    let _ = write!(h, "<p class=\"note\">{}</p>", esc(&q.relation));
}
