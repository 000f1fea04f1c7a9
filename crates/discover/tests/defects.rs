//! Regressions from the adversarial read of s33 (/work/coord/s33/adversarial.md): each data set
//! here is a `capstan simulate` output the read used, kept as a fixture so the defect it showed
//! stays fixed. Common options (`$CAT`): `--noise thesis --effect contact_heating=0.0067
//! --effect t2_offset=-0.9 --threads 1`.

use capstan_discover::{discover, Discovery, Options};
use capstan_engine::evidence::adequacy::LackOfFit;

fn run(name: &str) -> Discovery {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name);
    let data = capstan_data::load_pairs(&path).expect("fixture");
    discover(&data, &Options::default(), &mut |_, _| {})
}

/// 1 − (after/before)² of the lack of fit's systematic ratio.
fn share(before: &Option<LackOfFit>, after: &Option<LackOfFit>) -> f64 {
    let (b, a) = (
        before.as_ref().expect("before").systematic_ratio,
        after.as_ref().expect("after").systematic_ratio,
    );
    1.0 - (a / b).powi(2)
}

/// D1: a later term's partial share is measured against what the terms before it left, not
/// against what the catalogue alone left. `$CAT --unmodelled t1_tare_diameter=1.8 --seed 4`:
/// term 1 (`t1_offset_diameter`) removes 82 % of the catalogue's lack of fit; `settling` was
/// proposed second on the cumulative 90 %, though it removes 46 % of what term 1 left.
#[test]
fn d1_a_later_partial_term_is_judged_on_what_is_left() {
    let d = run("tare_catalogue_seed4.csv");
    assert_eq!(d.terms.first().map(|t| t.name), Some("t1_offset_diameter"));
    let mut before = d.lack_of_fit_before.clone();
    for t in &d.terms {
        if t.partial {
            let s = share(&before, &t.lack_of_fit_after);
            assert!(
                s >= 0.8,
                "{} partial on a share of {s:.2} of what was left",
                t.name
            );
        }
        before = t.lack_of_fit_after.clone();
    }
    assert!(
        d.terms.iter().all(|t| t.name != "settling"),
        "{}",
        d.verdict
    );
    let settling = d.declined.iter().find(|x| x.name == "settling");
    if let Some(x) = settling {
        assert!(x.reason.contains("partial mimic"), "{}", x.reason);
    }
}
