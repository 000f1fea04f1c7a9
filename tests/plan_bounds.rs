//! `capstan plan` on data larger than any rig campaign, and under a signal: the work is bounded
//! by a stated rule, and a signal ends it within seconds with status 130 (adversarial pass on
//! issue 42: a 720-cord file ran past 9 minutes, SIGTERM was ignored for 420 s).

use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn fresh(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("capstan-plan-bounds-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// 720 cords: the thesis's 10 (diameter, wrap) cords 72 times over, each its first run only,
/// scaled by 0.3 % per copy (8,640 rows).
fn seven_hundred_twenty_cords(dir: &std::path::Path) -> PathBuf {
    let mut text = String::from("cord,capstan_diameter_mm,wrap_deg,drive_v,run,step,t1_n,t2_n\n");
    let rows: Vec<Vec<&str>> = (capstan_data::THESIS_CSV.lines().skip(1))
        .map(|l| l.split(',').collect())
        .filter(|f: &Vec<&str>| f[3] == "1")
        .collect();
    for k in 0..72 {
        let s = 1.0 + 0.003 * k as f64;
        for f in &rows {
            let (t1, t2): (f64, f64) = (f[5].parse().unwrap(), f[6].parse().unwrap());
            text += &format!(
                "K{k}D{}W{},{},{},{},1,{},{:.6},{:.6}\n",
                f[0],
                f[1],
                f[0],
                f[1],
                f[2],
                f[4],
                t1 * s,
                t2 * s
            );
        }
    }
    let path = dir.join("c720.csv");
    std::fs::write(&path, text).unwrap();
    path
}

/// Wait for `child` up to `limit`; its status code (killed and None past the limit).
fn finish(child: &mut std::process::Child, limit: Duration) -> Option<i32> {
    let t0 = Instant::now();
    while t0.elapsed() < limit {
        if let Some(s) = child.try_wait().unwrap() {
            return s.code();
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let _ = child.kill();
    let _ = child.wait();
    None
}

#[test]
fn a_720_cord_file_is_planned_on_a_bounded_campaign_and_says_so() {
    let dir = fresh("720");
    let data = seven_hundred_twenty_cords(&dir);
    let out = dir.join("plan.json");
    let mut child = Command::new(env!("CARGO_BIN_EXE_capstan"))
        .args(["plan", data.to_str().unwrap(), "--reps", "1", "--json"])
        .stdout(std::fs::File::create(&out).unwrap())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // ~30 s in a debug build on a loaded machine; before the bound it ran for many minutes.
    let code = finish(&mut child, Duration::from_secs(300));
    assert_eq!(code, Some(0), "the plan did not finish in 300 s");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    for c in v["candidates"].as_array().unwrap() {
        let d = &c["protocol"];
        let cords = ["wraps_deg", "diameters_mm", "drive_v"]
            .iter()
            .map(|k| d[k].as_array().unwrap().len())
            .product::<usize>();
        let runs = cords * d["runs_per_cord"].as_u64().unwrap() as usize;
        // The largest variants double the bounded design (twice the runs, two voltages).
        assert!(runs <= 2 * 120, "{}: {runs} runs", c["name"]);
    }
    let current = &v["candidates"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["name"] == "current design")
        .unwrap()["protocol"];
    // 10 cords, 12 runs each: 120 runs (the data's 720 runs were planned as 240 before).
    assert_eq!(current["runs_per_cord"], 12, "{current}");
    let assumed = v["assumed"].to_string();
    assert!(assumed.contains("at most 120 runs"), "{assumed}");
    let why = v["first"]["why"].as_str().unwrap();
    assert!(
        why.contains("720 cords") && why.contains("not asked"),
        "{why}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[cfg(unix)]
#[test]
fn sigterm_ends_a_plan_within_seconds_with_status_130() {
    let dir = fresh("term");
    let data = seven_hundred_twenty_cords(&dir);
    let mut child = Command::new(env!("CARGO_BIN_EXE_capstan"))
        .args(["plan", data.to_str().unwrap()])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Well inside the simulation of the first protocol (8 campaigns of 120 runs).
    std::thread::sleep(Duration::from_secs(6));
    assert!(
        child.try_wait().unwrap().is_none(),
        "the plan ended before the signal"
    );
    let ok = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(ok.success());
    let t0 = Instant::now();
    let code = finish(&mut child, Duration::from_secs(30));
    let took = t0.elapsed();
    let mut err = String::new();
    use std::io::Read as _;
    let _ = child.stderr.take().unwrap().read_to_string(&mut err);
    assert_eq!(code, Some(130), "{err}");
    // It stops within one campaign, or exits 3 s after the signal whatever it is computing.
    assert!(
        took < Duration::from_secs(6),
        "{took:?} after SIGTERM: {err}"
    );
    assert!(err.contains("SIGTERM"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
