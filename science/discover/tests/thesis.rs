//! `capstan discover` on the thesis data: the JSON contract, and what it finds (the spike's
//! answer, reproduced by this implementation: nothing in the library explains what the
//! catalogue leaves: the strongest added term, a T2 reading error at low force, is shared by the
//! replicate runs but short of the search's bar, and the strongest swap, a heating law with one
//! step of memory in the place of contact heating, does not help held-out cords).

use capstan_discover::{discover, Options};

#[test]
fn thesis_nothing_in_the_library_explains_it() {
    let data = capstan_data::thesis_dataset();
    let d = discover(&data, &Options::default(), &mut |_, _| {});
    let v: serde_json::Value = serde_json::from_str(&d.to_json()).expect("json");
    // The contract's keys.
    for k in [
        "catalogue_effects",
        "terms",
        "unexplained_after",
        "residual_pattern",
        "elapsed_s",
    ] {
        assert!(v.get(k).is_some(), "missing {k}");
    }
    assert!(v["data"]["structure"]["statement"].is_string());
    // Strongest first, as diagnose and analyze name them.
    assert_eq!(
        v["catalogue_effects"],
        serde_json::json!(["t2_offset", "contact_heating"])
    );
    assert_eq!(v["terms"], serde_json::json!([]));
    // What the catalogue leaves is cord-to-cord scatter (judged with the cords as the units),
    // not an unexplained pattern: nothing for a term to explain, and none is proposed.
    assert_eq!(v["unexplained_after"], serde_json::json!(false));
    assert_eq!(v["residual_pattern"], serde_json::Value::Null);
    // The strongest added term (ΔBIC −13.1) passed note-26's bar for additions alone (−12.5),
    // not the joint search's (−14.9 with 27 terms, which pays for the swaps and the mu bump's centres tried too). The
    // replicate runs do share it (s41's gate: the runs' scores on the other runs' cell means,
    // one-sided t, p < 0.01): the pattern is there, too weak for the search's bar. (Note-26
    // measured it unstable over cords, 29 %, held-out ratio 0.986 [0.95, 1.02].)
    let top = &d.search.screen[0];
    assert_eq!(top.name, "t2_lowforce");
    assert!(
        top.delta_bic < -12.5 && top.delta_bic > d.search.first_bar,
        "{}",
        top.delta_bic
    );
    let rep = top.replicate.as_ref().expect("replicate cells");
    assert!(rep.p < 0.01 && rep.passed, "{rep:?}");
    // The same sign and size on what the runs share.
    assert!(
        rep.theta_shared < 0.0 && (rep.share - 1.0).abs() < 0.3,
        "{rep:?}"
    );
    // s32's statistic on the cell means (the run's own row in, the search's whole bar): far
    // short of it, as s32-s35 reported (−2.2).
    assert!(rep.delta_bic > -5.0, "{rep:?}");
    // The joint search's strongest move is a swap: a heating law with one step of memory
    // (`load_memory_prev`) in the place of the catalogue's contact heating. It is stable over
    // cords but does not help held-out cords, so it is declined too.
    let swap = &d.declined[0];
    assert_eq!(swap.name, "load_memory_prev");
    let x = swap.displaced.as_ref().expect("a swap");
    assert_eq!(x.effect, "contact_heating");
    assert!(x.delta_bic_swap < d.search.first_bar, "{x:?}");
    assert!(swap.stability.expect("stability") >= 0.5);
    let r = swap.loco_rmse_ratio.as_ref().expect("held-out ratio");
    assert!(
        r.value >= 1.0 && r.ci95.lo < 1.0 && r.ci95.hi > 1.0,
        "{r:?}"
    );
    assert!(
        swap.reason.contains("does not help held-out cords"),
        "{}",
        swap.reason
    );
    // The failed swap gives way to the catalogue as selected, whose best addition is the step's
    // second try: its bar is 2·ln 2 stricter, and t2_lowforce is short of it (s33).
    let next = &d.declined[1];
    assert_eq!(next.name, "t2_lowforce");
    let bar2 = d.search.first_bar - 2.0 * 2f64.ln();
    assert!(next.delta_bic > bar2, "{} vs {bar2}", next.delta_bic);
    assert!(next.reason.contains("not the search's"), "{}", next.reason);
    // The joint search may put a term in the place of either within-run catalogue effect, and
    // pays for every model it tries (terms × (1 + effects)), the mu bump once per centre tried.
    assert_eq!(d.search.displaceable, vec!["contact_heating", "t2_offset"]);
    let models = d.search.tried + Options::default().bump_centres - 1;
    assert_eq!(d.search.models_per_step, 3.0 * models as f64);
    // Adhesion wants the wrong physical sign and is never a candidate.
    let adh = d
        .search
        .screen
        .iter()
        .find(|s| s.name == "adhesion")
        .expect("adhesion");
    assert!(!adh.sign_ok);
}

#[test]
fn a_term_planted_in_the_thesis_design_is_found_with_its_dependence() {
    // The thesis's own T1 and design; T2 from the catalogue pair fitted to it plus a T1 tare
    // that differs by capstan (t1_offset_diameter, 0.6 N), with run scatter and noise.
    use capstan_physics::{Effect, EffectKind, Model, Operating};
    let mut data = capstan_data::thesis_dataset();
    let mut rng = capstan_rng::Rng::new(7);
    let mut run_mu = std::collections::HashMap::new();
    for p in data.pairs.iter_mut() {
        let d_mm = p.capstan_diameter_mm.unwrap_or(12.7);
        let key = (
            p.wrap_deg.to_bits(),
            d_mm.to_bits(),
            p.run.unwrap_or(1.0).to_bits(),
        );
        let mu = *run_mu
            .entry(key)
            .or_insert_with(|| 0.143 * (1.0 + 0.04 * rng.normal()));
        let m = Model::euler_eytelwein(mu)
            .with_effect(Effect {
                kind: EffectKind::ContactHeating,
                value: 0.0067,
            })
            .with_effect(Effect {
                kind: EffectKind::T2Offset,
                value: -0.9,
            });
        let mut op = Operating::from_wrap_deg(p.wrap_deg);
        op.diameter_mm = d_mm;
        let tare = -0.6 * (d_mm - 19.05) / 19.05;
        // Steady load memory: H = L·τ for the heating (solved by a few passes).
        let t1c = p.t1_n + tare;
        let mut t2 = m.predict_t2_n(t1c, &op);
        for _ in 0..20 {
            op.load_memory_ns = (t2 + 0.9 - t1c).max(0.0) * capstan_physics::HEAT_TAU_S;
            t2 = m.predict_t2_n(t1c, &op);
        }
        p.t2_n = t2 + 0.05 * rng.normal() + 0.002 * t2 * rng.normal();
    }
    let d = discover(&data, &Options::default(), &mut |_, _| {});
    let names: Vec<&str> = d.terms.iter().map(|t| t.name).collect();
    let right = d.terms.iter().any(|t| {
        t.name == "t1_offset_diameter"
            || t.rivals
                .iter()
                .any(|r| r.name == "t1_offset_diameter" || r.name == "t2_offset_diameter")
    });
    assert!(right, "proposed {names:?}; declined {:?}", d.declined);
}
