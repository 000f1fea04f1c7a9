//! Shared by the `capstan condition` tests: the command, a scratch directory, a seeded
//! logger noise, and the simulated rig's own runs (firmware pairs and raw series).
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// `capstan ARGS`.
pub fn capstan(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_capstan"))
        .args(args)
        .output()
        .expect("capstan runs")
}

/// `capstan condition FILE --out OUT --wrap-deg 360` and `more`.
pub fn condition_at(file: &Path, out: &Path, more: &[&str]) -> Output {
    let mut a = vec![
        "condition",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--wrap-deg",
        "360",
    ];
    a.extend(more);
    capstan(&a)
}

/// A fresh directory `capstan-cond-PID-NAME` in the system's temp directory.
pub fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("capstan-cond-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A seeded normal deviate stream (xorshift + Box-Muller), for the logger's noise.
pub struct Noise(pub u64);

impl Noise {
    pub fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    pub fn normal(&mut self) -> f64 {
        let (a, b) = (self.uniform(), self.uniform());
        (-2.0 * a.ln()).sqrt() * (2.0 * std::f64::consts::PI * b).cos()
    }
}

/// The rows of a CSV after its header, split at commas.
pub fn csv_rows(path: &Path) -> Vec<Vec<String>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(String::from).collect())
        .collect()
}

/// (step, T1, T2) firmware pairs of one run.
pub type FwPairs = Vec<(u32, f64, f64)>;
/// (t, T1, T2) raw samples of one run (100 Hz, s from the trigger, N).
pub type Raw = Vec<(f64, f64, f64)>;

/// Simulate `runs` runs in `order` (360°, 12.7 mm, seed 7, `more` options): each run's
/// firmware pairs and raw samples.
pub fn simulate_runs(dir: &Path, order: &str, runs: usize, more: &[&str]) -> Vec<(FwPairs, Raw)> {
    let out = dir.join("sim");
    let n = runs.to_string();
    let mut args = vec![
        "simulate",
        "--out",
        out.to_str().unwrap(),
        "--runs",
        &n,
        "--wraps",
        "360",
        "--diameters",
        "12.7",
        "--order",
        order,
        "--seed",
        "7",
    ];
    args.extend(more);
    let o = capstan(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let pairs = csv_rows(&out.join("pairs.csv"));
    (1..=runs)
        .map(|r| {
            let fw = pairs
                .iter()
                .filter(|p| p[3] == r.to_string())
                .map(|p| {
                    (
                        p[4].parse().unwrap(),
                        p[6].parse().unwrap(),
                        p[7].parse().unwrap(),
                    )
                })
                .collect();
            let raw = csv_rows(&out.join(format!("raw/d12.7_w360_v10_run{r}.csv")))
                .iter()
                .map(|c| {
                    (
                        c[0].parse().unwrap(),
                        c[3].parse().unwrap(),
                        c[4].parse().unwrap(),
                    )
                })
                .collect();
            (fw, raw)
        })
        .collect()
}
