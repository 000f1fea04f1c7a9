//! The force-control documentation holds the runs' numbers (issue 43): every table row of
//! `docs/README-force.md` and the drive's figures in `docs/README-sim.md` are remade here from
//! the same runs the documented commands make (same rig, seeds and noise), and must appear in
//! the docs verbatim. A change that moves a number fails here until the docs say it. And the
//! thesis fit the force rig is built on is the one `capstan analyze` fits to the bundled data.

use capstan_sim::force::{self as hf, ForceRig};
use capstan_sim::noise::NoiseProfile;
use capstan_sim::plant::rng::derive_seed;
use capstan_sim::two_control::{run_two_control, TwoControlConfig, TRACKING_WINDOW};
use capstan_tracking::{bandwidth, bode, Bandwidth};

fn doc(name: &str) -> String {
    std::fs::read_to_string(format!("{}/docs/{name}", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

/// Every line must be in the doc; the missing ones are printed (to paste, after checking).
fn holds(doc_name: &str, lines: &[String]) {
    let text = doc(doc_name);
    let missing: Vec<&String> = lines
        .iter()
        .filter(|l| !text.contains(l.as_str()))
        .collect();
    for l in &missing {
        eprintln!("{l}");
    }
    assert!(
        missing.is_empty(),
        "docs/{doc_name} lacks {} lines (above)",
        missing.len()
    );
}

/// `capstan simulate --mode force --noise thesis --compare`: run 1's seed of seed 1.
#[test]
fn the_side_by_side_table_is_the_runs() {
    let base = ForceRig {
        seed: derive_seed(1, &[1]),
        noise: NoiseProfile::Thesis,
        ..ForceRig::default()
    };
    let c = hf::standard(&base, hf::THESIS_EE_MU as f32, 20.0).unwrap();
    let lines: Vec<String> = c
        .rows
        .iter()
        .map(|r| {
            let ss: Vec<String> = r
                .steps
                .iter()
                .map(|s| format!("{:+.2} %", s.ss_error_pct))
                .collect();
            let rise: Vec<f64> = r.steps.iter().filter_map(|s| s.rise_s).collect();
            let settle = r
                .steps
                .iter()
                .filter_map(|s| s.settling_s)
                .fold(0.0, f64::max);
            let lo = rise.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = rise.iter().copied().fold(0.0, f64::max);
            format!(
                "| {} | {} | {} | {:.1} % | {lo:.2}–{hi:.2} | {settle:.2} |",
                r.controller.name(),
                r.cord.name(),
                ss.join(" | "),
                r.worst_overshoot_pct()
            )
        })
        .collect();
    holds("README-force.md", &lines);
}

/// `capstan simulate --mode force --noise thesis --profile steps,sine`: run 2 (the sweep).
#[test]
fn the_bandwidth_is_the_sweeps() {
    let mut rig = ForceRig {
        seed: derive_seed(1, &[2]),
        noise: NoiseProfile::Thesis,
        ..ForceRig::default()
    };
    rig.force.profile = capstan_rig::ForceProfile::Sine;
    rig.force.levels_n = [15.0, 5.0, 0.0, 0.0];
    (
        rig.force.sine_hz,
        rig.force.sine_to_hz,
        rig.force.sine_steps,
    ) = (0.3, 20.0, 10);
    let out = hf::run_force(&rig).unwrap();
    let p = bode(&hf::trace_of(&out.log));
    let mut lines: Vec<String> = p
        .iter()
        .map(|x| {
            format!(
                "| {:.2} | {:.3} | {:+.2} | {:.1} | {:.1} |",
                x.freq_hz, x.gain, x.gain_db, x.phase_deg, x.residual_pct
            )
        })
        .collect();
    match bandwidth(&p) {
        Bandwidth::Within { freq_hz, phase_deg } => lines.push(format!(
            "−3 dB at **{freq_hz:.2} Hz**, phase **{phase_deg:.0}°** there"
        )),
        b => panic!("{b:?}"),
    }
    holds("README-force.md", &lines);
}

fn channel_lines(n: usize) -> Vec<String> {
    let r = run_two_control(&hf::channels(n)).unwrap();
    let mut lines = Vec::new();
    for (k, ch) in r.channels.iter().enumerate() {
        let st = capstan_tracking::steps(&hf::trace_of(&ch.log), TRACKING_WINDOW);
        let targets: Vec<String> = st.iter().map(|s| format!("{}", s.target_n)).collect();
        let ss = st.iter().map(|s| s.ss_error_pct.abs()).fold(0.0, f64::max);
        let os = st.iter().map(|s| s.overshoot_pct).fold(0.0, f64::max);
        lines.push(format!(
            "| {n} | {} | {} | {ss:.2} % | {os:.1} % |",
            k + 1,
            targets.join(", ")
        ));
    }
    let d = r.drive;
    let fin = |x: f64| if x.is_finite() { x.abs() } else { 0.0 };
    let (peak, after, rpm) = r
        .force_crosstalk
        .iter()
        .fold((0.0f64, 0.0f64, 0.0f64), |a, x| {
            (
                a.0.max(fin(x.peak_dev_rel())),
                a.1.max(fin(x.observer_t2_after_n / x.observer_t2_before_n - 1.0)),
                a.2.max(fin(x.d_rpm_rel())),
            )
        });
    lines.push(format!(
        "| {n} | {:.2} A / {:.1} W | {:.2} A / {:.2} W | {:.2} W | {} | {:.2} % | {:.2} % | {:.1} % |",
        d.peak_current_a,
        d.peak_power_w,
        d.running_current_a,
        d.running_power_w,
        d.mean_power_w,
        r.force_crosstalk.len(),
        100.0 * peak,
        100.0 * after,
        100.0 * rpm
    ));
    lines
}

/// `capstan simulate --two-control --mode force --noise thesis --wraps 720,720[,720,720]`.
#[test]
fn two_and_four_channels_in_the_docs_are_the_runs() {
    let mut lines = channel_lines(2);
    lines.extend(channel_lines(4));
    holds("README-force.md", &lines);
}

/// `capstan simulate --two-control`: the drive's figures in the two-control section, and the
/// three filters behind the figures the docs once gave.
#[test]
fn the_two_control_drive_figures_are_the_runs() {
    let r = run_two_control(&TwoControlConfig::default()).unwrap();
    let d = r.drive;
    let mut lines = vec![format!(
        "peak {:.2} A / {:.1} W (the spin-up's inrush, from the plant every 1 ms; {:.2} A / {:.1} W on the 10 ms series), at most {:.2} A / {:.2} W while running, {:.2} W mean while driven",
        d.peak_current_a,
        d.peak_power_w,
        r.peak_current_a(),
        r.peak_power_w(),
        d.running_current_a,
        d.running_power_w,
        d.mean_power_w
    )];
    for tau_ms in [0.0, 10.0] {
        let mut cfg = TwoControlConfig::default();
        cfg.plant.motor.amp_filter_tau_s = tau_ms * 1e-3;
        let r = run_two_control(&cfg).unwrap();
        lines.push(format!(
            "| {tau_ms:.0} ms | {:.2} A / {:.1} W | {:.2} A / {:.1} W |",
            r.peak_current_a(),
            r.peak_power_w(),
            r.drive.peak_current_a,
            r.drive.peak_power_w
        ));
    }
    holds("README-sim.md", &lines);
}

/// The constants of the force rig's cord and law are `capstan analyze`'s fit of the bundled
/// thesis data.
#[test]
fn the_thesis_fit_is_the_analysiss() {
    let ds = capstan_data::thesis_dataset();
    let a = capstan_engine::analysis::run(&ds, Default::default()).unwrap();
    // The extended model's population values: the parameter table's first rows (what the
    // headline quotes). `capstan rig load-model` loads predict's population-averaged law
    // instead (the better guess for a new cord): the feedback makes up the difference.
    let ext = &a.extended;
    let v = |n: &str| {
        (ext.values.iter())
            .find(|x| x.name == n)
            .map_or(f64::NAN, |x| x.value)
    };
    let close = |a: f64, b: f64| (a / b - 1.0).abs() < 1e-6;
    assert!(close(v("mu"), hf::THESIS_FIT_MU), "{}", v("mu"));
    assert!(close(v("heat_per_ns"), hf::THESIS_FIT_HEAT_PER_NS));
    // The heating's time constant is fixed, the same in every model.
    let tau = a.prediction_model.values["heat_tau_s"];
    assert!(close(tau, hf::THESIS_FIT_HEAT_TAU_S), "{tau}");
    assert!(close(v("t2_offset_n"), hf::THESIS_FIT_T2_OFFSET_N));
    let ee = a.baseline_fit.model(None).law.mu;
    assert!(close(ee, hf::THESIS_EE_MU), "{ee}");
}
