//! Twelve rows on two cords (the user guide's `mine.csv`): too few to tell anything is left,
//! and every leave-one-cord-out fold fails. `analyze` must say what `diagnose` says (not
//! identified, not "nothing is left"), and a failed fold is never a cord predicted better.

use std::process::Command;

const MINE: &str = "capstan_diameter_mm,wrap_deg,run,step,t1_n,t2_n
12.7,360,1,1,1.00,2.13
12.7,360,1,2,2.01,4.31
12.7,360,1,3,4.02,8.68
12.7,360,2,1,0.99,2.08
12.7,360,2,2,2.00,4.23
12.7,360,2,3,4.02,8.64
12.7,720,1,1,0.99,4.37
12.7,720,1,2,1.99,8.76
12.7,720,1,3,4.07,17.75
12.7,720,2,1,0.99,4.70
12.7,720,2,2,1.97,9.12
12.7,720,2,3,4.00,18.51
";

#[test]
fn analyze_and_diagnose_agree_that_twelve_rows_are_too_few() {
    let dir = std::env::temp_dir().join(format!("capstan-small-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let data = dir.join("mine.csv");
    std::fs::write(&data, MINE).unwrap();
    let capstan = env!("CARGO_BIN_EXE_capstan");
    let d = Command::new(capstan)
        .arg("diagnose")
        .arg(&data)
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&d.stdout);
    assert!(said.contains("Not identified"), "{said}");
    let out = dir.join("report");
    let a = Command::new(capstan)
        .args(["analyze"])
        .arg(&data)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(a.status.success(), "{}", String::from_utf8_lossy(&a.stderr));
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("metrics.json")).unwrap()).unwrap();
    let headline = m["headline"]["sentences"].to_string();
    assert!(headline.contains("too few to tell"), "{headline}");
    assert!(
        !headline.contains("Nothing systematic is left"),
        "{headline}"
    );
    // Both folds failed: no cord is a held-out success, and none has a 0 N error.
    assert_eq!(m["gain"]["cords_predicted_better"], 0, "{}", m["gain"]);
    for c in m["held_out"].as_array().unwrap() {
        assert_eq!(c["extended_better"], false, "{c}");
        let ext = (c["rmse_t2_n"].as_array().unwrap().iter())
            .find(|p| p[0] == "extended")
            .unwrap();
        assert!(ext[1].is_null(), "{c}");
    }
}
