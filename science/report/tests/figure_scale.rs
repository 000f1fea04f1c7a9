//! Figures that scale with the data: with 60 and with 720 cords (every one of its own
//! diameter, wrap and drive voltage), no figure file is taller than a page (225 mm), so the
//! PNG's pixels (and the memory that renders them) and the PDF's page are bounded whatever the
//! data, every figure still keeps its text apart, and a caption says which cords a figure draws
//! when it cannot draw them all.

use capstan_report::check::{pdf_page_pt, png_info, svg_size_mm, system_fonts, text_problems};
use capstan_report::export::{figure_files, FigureOptions, Format, MAX_HEIGHT_MM, PNG_DPI};

/// A pairs CSV of `diameters` × `wraps` × `voltages` cords, `runs` runs each, twelve steps of
/// T1 from 1 to 12 N, T2 by Euler-Eytelwein (mu 0.12, a few % apart from cord to cord) with a
/// small deterministic scatter.
fn design(diameters: &[f64], wraps: &[f64], voltages: &[f64], runs: usize) -> String {
    let mut s = String::from("capstan_diameter_mm,wrap_deg,drive_v,run,step,t1_n,t2_n\n");
    let mut k = 0u64;
    for &d in diameters {
        for &w in wraps {
            for &v in voltages {
                k += 1;
                let mu = 0.12 * (1.0 + 0.03 * ((k * 7919 % 23) as f64 / 11.0 - 1.0));
                for run in 1..=runs {
                    for step in 1..=12 {
                        let t1 = step as f64;
                        let wobble =
                            0.01 * (((k as f64) * 1.3 + step as f64 * 0.7 + run as f64).sin());
                        let t2 = t1 * (mu * w.to_radians()).exp() * (1.0 + wobble);
                        s.push_str(&format!("{d},{w},{v},{run},{step},{t1},{t2:.4}\n"));
                    }
                }
            }
        }
    }
    s
}

fn check(csv: &str, cords: usize) {
    let ds = capstan_data::read_pairs(csv.as_bytes(), "generated").unwrap();
    let a = capstan_engine::analysis::run(&ds, Default::default()).unwrap();
    assert_eq!(a.obs.groups.len(), cords);
    let fonts = system_fonts();
    for (width_mm, font_pt) in [(85.0, 8.0), (170.0, 9.0)] {
        let opts = FigureOptions {
            formats: vec![Format::Svg, Format::Png, Format::Pdf],
            width_mm,
            font_pt,
            numbers: true,
        };
        let figs = capstan_report::figures::all(&a, None, &opts.layout()).unwrap();
        let amp = figs.iter().find(|f| f.id == "amp_vs_t1").unwrap();
        assert!(
            amp.caption
                .contains(&format!("of the {cords} cords are drawn")),
            "{}",
            amp.caption
        );
        let files = figure_files(&figs, &opts).unwrap();
        let most_px = (MAX_HEIGHT_MM / 25.4 * PNG_DPI).ceil() as u32;
        for f in &files {
            match f.name.rsplit_once('.').unwrap().1 {
                "svg" => {
                    let svg = std::str::from_utf8(&f.bytes).unwrap();
                    let (w, h) = svg_size_mm(svg).unwrap();
                    assert!(w == width_mm && h <= MAX_HEIGHT_MM, "{}: {h} mm", f.name);
                    let p = text_problems(svg, &fonts, 0.5).unwrap();
                    assert!(
                        p.is_empty(),
                        "{} at {width_mm} mm: {}",
                        f.name,
                        p.join("\n")
                    );
                }
                "png" => {
                    let (w, h) = png_info(&f.bytes).unwrap().px;
                    // At most 2008 × 2658 px: 21 MB of pixels to render, whatever the data.
                    assert!(h <= most_px && w <= 2008, "{}: {w}×{h} px", f.name);
                }
                "pdf" => {
                    let (_, h) = pdf_page_pt(&f.bytes).unwrap();
                    // 225 mm is 638 pt: far inside PDF's 14,400 pt page limit.
                    assert!(h <= MAX_HEIGHT_MM / 25.4 * 72.0 + 0.5, "{}: {h} pt", f.name);
                }
                _ => unreachable!(),
            }
        }
    }
}

#[test]
fn sixty_cords_fit_a_page() {
    check(
        &design(
            &[12.7, 19.05, 25.4],
            &[270.0, 360.0, 450.0, 630.0, 720.0],
            &[4.0, 7.0, 10.0, 13.0],
            2,
        ),
        60,
    );
}

/// 720 cords, each at its own diameter and wrap, are slow to analyse unoptimised (the figure
/// files of 60 cords cover the same code): with CAPSTAN_FIGURES=full (CI) or in release.
#[test]
fn seven_hundred_twenty_cords_fit_a_page() {
    if std::env::var("CAPSTAN_FIGURES").is_err() && cfg!(debug_assertions) {
        eprintln!(
            "skipped: set CAPSTAN_FIGURES=full (or test in release) for the 720-cord figures"
        );
        return;
    }
    let diameters: Vec<f64> = (0..72).map(|k| 10.0 + 0.25 * k as f64).collect();
    let wraps: Vec<f64> = (0..10).map(|k| 180.0 + 90.0 * k as f64).collect();
    check(&design(&diameters, &wraps, &[10.0], 1), 720);
}
