//! `capstan plan` as a user meets it: the JSON contract, the files it writes, its refusals.

use std::process::{Command, Output};

fn capstan(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_capstan"))
        .args(args)
        .output()
        .expect("capstan runs")
}

#[test]
fn plan_on_the_thesis_data_keeps_the_json_contract_and_writes_its_files() {
    let dir = std::env::temp_dir().join(format!("capstan-plan-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = dir.join("plan");
    let o = capstan(&[
        "plan",
        "--json",
        "--reps",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("one JSON object");
    for key in [
        "hypotheses",
        "candidates",
        "recommended",
        "current_design",
        "method",
        "elapsed_s",
    ] {
        assert!(v.get(key).is_some(), "no {key}");
    }
    // The thesis data leave one hypothesis open: the effects they name.
    assert_eq!(v["hypotheses"][0]["label"], "t2_offset+contact_heating");
    let c = &v["candidates"][0];
    for key in [
        "protocol",
        "rig_hours",
        "p_decide_worst",
        "rig_commands",
        "physical_changes",
    ] {
        assert!(c.get(key).is_some(), "candidate without {key}");
    }
    let r = &v["recommended"];
    for key in [
        "protocol",
        "rig_commands",
        "physical_changes",
        "simulate_args",
        "rig_hours",
        "p_decide_worst",
    ] {
        assert!(r.get(key).is_some(), "recommendation without {key}");
    }
    let p = v["current_design"]["p_decide_worst"].as_f64().unwrap();
    assert!((0.0..=1.0).contains(&p));
    // 10 cords x 6 runs x (12 levels of 10 s and the trigger, + 60 s between runs): ~3.2 h.
    let hours = v["current_design"]["rig_hours"].as_f64().unwrap();
    assert!((2.5..4.0).contains(&hours), "{hours}");
    // The simulate arguments reproduce the protocol and nothing else.
    let args: Vec<&str> = r["simulate_args"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a.as_str().unwrap())
        .collect();
    assert!(
        args.contains(&"--order") && args.contains(&"--wraps"),
        "{args:?}"
    );
    assert!(!args
        .iter()
        .any(|a| ["--effect", "--noise", "--seed", "--out"].contains(a)));
    // The same plan in the files.
    let saved: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("plan.json")).unwrap()).unwrap();
    assert_eq!(saved["hypotheses"], v["hypotheses"]);
    assert!(std::fs::read_to_string(out.join("plan.txt"))
        .unwrap()
        .contains("open hypotheses"));
}

#[test]
fn plan_refuses_bad_options_before_simulating() {
    for args in [
        vec!["plan", "--hours", "0"],
        vec!["plan", "--hours", "nan"],
        vec!["plan", "--reps", "0"],
        vec!["plan", "/no/such/file.csv"],
    ] {
        let o = capstan(&args);
        assert!(!o.status.success(), "{args:?} accepted");
        assert!(!o.stderr.is_empty());
    }
}
