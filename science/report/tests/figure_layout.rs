//! Every figure laid out for its size: at one journal column (85 mm, tick labels at 8 pt) and
//! at a page's width (170 mm, 9 pt), every text of every figure file inside its canvas and clear
//! of every other text, as resvg lays the text out (the boxes its PNG and PDF draw) with the
//! fonts of a fresh Debian machine (DejaVu Sans) and with this machine's; and every file of
//! its physical size (the SVG's width in mm, the PNG's pixels and pHYs, the PDF's page).

use capstan_engine::analysis::{closed_loop::SimCurve, Analysis};
use capstan_report::check::{
    fresh_machine_fonts, pdf_page_pt, png_info, svg_size_mm, system_fonts, text_problems,
};
use capstan_report::export::{figure_files, standalone_svg, FigureOptions, Format, MAX_HEIGHT_MM};
use capstan_report::figures::{self, tracking, Figure};
use capstan_tracking::{BodePoint, Trace};
use std::path::Path;
use std::sync::OnceLock;

fn thesis() -> &'static Analysis {
    static A: OnceLock<Analysis> = OnceLock::new();
    A.get_or_init(|| {
        capstan_engine::analysis::run(&capstan_data::thesis_dataset(), Default::default()).unwrap()
    })
}

/// A closed loop for the figure: each cord's measured amplification by T1 (the figure's layout
/// is under test, not the simulation).
fn closed_loop(a: &Analysis) -> Vec<SimCurve> {
    (0..a.obs.groups.len())
        .map(|g| {
            let mut v: Vec<(f64, f64)> = a
                .obs
                .rows_of_group(g)
                .into_iter()
                .map(|i| (a.obs.rows[i].t1_n, a.obs.rows[i].t2_n / a.obs.rows[i].t1_n))
                .collect();
            v.sort_by(|p, q| p.0.total_cmp(&q.0));
            (g, v)
        })
        .collect()
}

/// Two force-control runs: steps, then a sine sweep with its Bode points.
fn force_runs() -> (Vec<Trace>, Vec<Vec<BodePoint>>) {
    let mut traces = Vec::new();
    let mut bodes = Vec::new();
    for run in 0..2 {
        let mut t = Trace::default();
        for i in 0..6000 {
            let ts = i as f64 * 0.01;
            let target = 10.0 + 5.0 * ((ts / 10.0).floor() % 3.0);
            let measured = target - 0.5 * (-(ts % 10.0) * 3.0).exp() + 0.05 * (ts * 7.0).sin();
            t.push(ts, target, measured + run as f64 * 0.1);
        }
        traces.push(t);
        bodes.push(
            [0.1, 0.2, 0.5, 1.0, 2.0, 5.0]
                .iter()
                .map(|&f: &f64| {
                    let gain = 1.0 / (1.0 + (f / 1.5).powi(2)).sqrt();
                    BodePoint {
                        freq_hz: f,
                        t_s: 0.0,
                        cycles: 4,
                        target_amp_n: 2.0,
                        measured_amp_n: 2.0 * gain,
                        gain,
                        gain_db: 20.0 * gain.log10(),
                        phase_deg: -(f / 1.5).atan().to_degrees(),
                        residual_pct: 1.0,
                    }
                })
                .collect(),
        );
    }
    (traces, bodes)
}

/// Every figure the report draws (the analysis's and force control's) at `opts`' layout.
fn every_figure(opts: &FigureOptions) -> Vec<Figure> {
    let a = thesis();
    let layout = opts.layout();
    let cl = closed_loop(a);
    let mut figs = figures::all(a, Some(&cl), &layout).unwrap();
    let (traces, bodes) = force_runs();
    let labels = ["run 1", "run 2"];
    let runs: Vec<tracking::RunTrace> = (0..2)
        .map(|k| tracking::RunTrace {
            label: labels[k],
            trace: &traces[k],
            bode: &bodes[k],
        })
        .collect();
    figs.push(tracking::target_vs_measured(&runs, &layout).unwrap());
    figs.push(tracking::bode_plot(&runs, &layout).unwrap().unwrap());
    figs
}

/// The two sizes of the issue: a journal column at 8 pt and a page at 9 pt.
fn sizes() -> [FigureOptions; 2] {
    [(85.0, 8.0), (170.0, 9.0)].map(|(width_mm, font_pt)| FigureOptions {
        formats: vec![Format::Svg, Format::Png, Format::Pdf],
        width_mm,
        font_pt,
        numbers: false,
    })
}

#[test]
fn every_figure_keeps_its_text_inside_the_canvas_and_off_other_text() {
    let fresh = fresh_machine_fonts(Path::new("/usr/share/fonts/truetype/dejavu"));
    if fresh.is_none() {
        assert!(
            std::env::var("CI").is_err(),
            "DejaVu Sans is not in /usr/share/fonts/truetype/dejavu (apt-get install fonts-dejavu-core)"
        );
        eprintln!(
            "skipping the fresh-machine fonts: no DejaVu Sans in /usr/share/fonts/truetype/dejavu"
        );
    }
    let system = system_fonts();
    let fonts: Vec<(&str, _)> = fresh
        .into_iter()
        .map(|f| ("DejaVu Sans only", f))
        .chain([("this machine's fonts", system)])
        .collect();
    let mut problems = Vec::new();
    let mut checked = 0;
    for opts in sizes() {
        let figs = every_figure(&opts);
        assert_eq!(figs.len(), 8, "every figure of both reports");
        for (k, f) in figs.iter().enumerate() {
            for number in [None, Some(k + 1)] {
                let svg = standalone_svg(f, number, Some(opts.width_mm));
                for (name, db) in &fonts {
                    for p in text_problems(&svg, db, 0.5).unwrap() {
                        problems.push(format!("{} at {} mm, {name}: {p}", f.id, opts.width_mm));
                    }
                    checked += 1;
                }
            }
        }
    }
    assert!(checked >= 32);
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn every_figure_file_has_its_physical_size() {
    for opts in sizes() {
        let figs = every_figure(&opts);
        let files = figure_files(&figs, &opts).unwrap();
        assert_eq!(files.len(), 3 * figs.len());
        let mm = opts.width_mm;
        for f in &files {
            let stem = f.name.rsplit_once('.').unwrap().0.to_string();
            let svg = &files
                .iter()
                .find(|x| x.name == format!("{stem}.svg"))
                .unwrap()
                .bytes;
            let (w_mm, h_mm) = svg_size_mm(std::str::from_utf8(svg).unwrap()).unwrap();
            assert!(w_mm == mm && h_mm > 20.0, "{}: {w_mm}×{h_mm} mm", f.name);
            assert!(h_mm <= MAX_HEIGHT_MM, "{}: {h_mm} mm tall", f.name);
            match f.name.rsplit_once('.').unwrap().1 {
                "png" => {
                    let info = png_info(&f.bytes).unwrap();
                    let ((w, h), ppm) = (info.px, info.per_metre);
                    // 85 mm at 300 dpi: 1004 px; 170 mm: 2008 px; 300 dpi = 11811 px/m.
                    assert_eq!(w, (mm / 25.4 * 300.0).round() as u32, "{}", f.name);
                    assert_eq!(ppm, Some((11811, 11811)), "{}", f.name);
                    let h_png_mm = f64::from(h) / 11811.0 * 1000.0;
                    assert!((h_png_mm - h_mm).abs() < 0.2, "{}: {h_png_mm} mm", f.name);
                }
                "pdf" => {
                    let (w, h) = pdf_page_pt(&f.bytes).unwrap();
                    // 85 mm = 240.94 pt; 170 mm = 481.89 pt.
                    assert!((w - mm / 25.4 * 72.0).abs() < 0.05, "{}: {w} pt", f.name);
                    assert!((h - h_mm / 25.4 * 72.0).abs() < 0.1, "{}: {h} pt", f.name);
                }
                _ => {}
            }
        }
    }
}

/// A closed-loop curve that ends short of the cord's measured T1 is said so in the caption (with
/// the cord and the two tensions); curves that reach the data add nothing.
#[test]
fn the_closed_loop_caption_says_where_a_simulated_run_ends_short() {
    let a = thesis();
    let layout = FigureOptions::default().layout();
    let full = closed_loop(a);
    let caption = |cl: &[capstan_engine::analysis::closed_loop::SimCurve]| {
        let figs = figures::all(a, Some(cl), &layout).unwrap();
        figs.into_iter()
            .find(|f| f.id == "closed_loop")
            .unwrap()
            .caption
    };
    assert!(!caption(&full).contains("ends short"), "{}", caption(&full));
    // Every cord simulated: laid out as figure 3, the experiment's diameter × wrap table.
    assert!(
        caption(&full).contains("One row per capstan diameter, one column per wrap."),
        "{}",
        caption(&full)
    );
    // Cord 0's run cut at 60 % of its measured T1: one cord short, named with its tensions.
    let top = |v: &[(f64, f64)]| v.iter().map(|p| p.0).fold(0.0f64, f64::max);
    let mut cut = full.clone();
    let measured = top(&cut[0].1);
    cut[0].1.retain(|p| p.0 <= 0.6 * measured);
    let c = caption(&cut);
    assert!(c.contains("At 1 of the 10 cords shown"), "{c}");
    assert!(
        c.contains(&format!("T1 {:.1} N of {measured:.1} N", top(&cut[0].1))),
        "{c}"
    );
    // Its T2 beside the rig's, and why the plant stops lower: the over-force limit.
    let t2_sim = (cut[0].1.iter()).map(|p| p.0 * p.1).fold(0.0f64, f64::max);
    let t2_measured = (a.obs.rows_of_group(cut[0].0).into_iter())
        .map(|i| a.obs.rows[i].t2_n)
        .fold(0.0f64, f64::max);
    assert!(
        c.contains(&format!("T2 {t2_sim:.1} N of {t2_measured:.1} N")),
        "{c}"
    );
    assert!(c.contains("over-force limit"), "{c}");
}

/// A text's position (x, y, px) and what it says of a cord (a wrap in degrees, a diameter).
type At<T> = (f64, f64, T);

/// The first lines of figure 3's panel titles ("270°, D =" or "270°, D = 12.7 mm") as (x, y,
/// wrap in degrees), and the (x, y, diameter text) of every text naming a diameter.
fn cord_titles(svg: &str) -> (Vec<At<f64>>, Vec<At<String>>) {
    let (mut titles, mut diameters) = (Vec::new(), Vec::new());
    for t in svg.split("<text ").skip(1) {
        let attr = |n: &str| -> f64 {
            let s = t.split(&format!("{n}=\"")).nth(1).unwrap();
            s[..s.find('"').unwrap()].parse().unwrap()
        };
        let body = &t[t.find('>').unwrap() + 1..t.find("</text>").unwrap()];
        if !t.contains("font-weight=\"bold\"") {
            continue;
        }
        if let Some((wrap, _)) = body.split_once("°,") {
            titles.push((attr("x"), attr("y"), wrap.parse().unwrap()));
        }
        for d in ["12.7", "25.4"] {
            if body.contains(d) {
                diameters.push((attr("x"), attr("y"), d.to_string()));
            }
        }
    }
    (titles, diameters)
}

/// The distinct values of `v`, sorted.
fn levels(v: impl Iterator<Item = f64>) -> Vec<f64> {
    let mut l: Vec<f64> = v.collect();
    l.sort_by(f64::total_cmp);
    l.dedup();
    l
}

/// Figure 3 (amplification per cord) draws the thesis's cords as the experiment's table: on
/// the page (170 mm, at 8 and 9 pt) a row per diameter and a column per wrap (5 × 2, not 4
/// across and wrapping to the next row mid-diameter); in an 85 mm column a column per
/// diameter and a row per wrap; every text inside its canvas and clear of the others.
#[test]
fn figure_3_lays_the_cords_out_as_wrap_by_diameter() {
    let a = thesis();
    let wraps = [270.0, 360.0, 450.0, 630.0, 720.0];
    let fonts = system_fonts();
    for (width_mm, font_pt) in [(170.0, 8.0), (170.0, 9.0), (85.0, 8.0)] {
        let opts = FigureOptions {
            width_mm,
            font_pt,
            ..FigureOptions::default()
        };
        let figs = figures::all(a, None, &opts.layout()).unwrap();
        let f = figs.iter().find(|f| f.id == "amp_vs_t1").unwrap();
        let (titles, diameters) = cord_titles(&f.chart.svg);
        assert_eq!(titles.len(), 10, "every cord at {width_mm} mm");
        let (xs, ys) = (
            levels(titles.iter().map(|t| t.0)),
            levels(titles.iter().map(|t| t.1)),
        );
        // The axis along which the wraps run, and the one along which the diameters do.
        let wide = width_mm > 100.0;
        let (wrap_axis, d_axis) = if wide { (&xs, &ys) } else { (&ys, &xs) };
        assert_eq!(
            (wrap_axis.len(), d_axis.len()),
            (5, 2),
            "{width_mm} mm, {font_pt} pt: columns at {xs:?}, rows at {ys:?}"
        );
        for t in &titles {
            let k = wrap_axis
                .iter()
                .position(|&v| v == if wide { t.0 } else { t.1 });
            assert_eq!(wraps[k.unwrap()], t.2, "{width_mm} mm: {t:?}");
        }
        // 12.7 mm before 25.4 mm: above it on the page, left of it in a column.
        let pos = |d: &str| {
            let v: Vec<f64> = diameters
                .iter()
                .filter(|x| x.2 == d)
                .map(|x| if wide { x.1 } else { x.0 })
                .collect();
            assert_eq!(v.len(), 5, "{d} at {width_mm} mm");
            (
                v.iter().cloned().fold(f64::MAX, f64::min),
                v.iter().cloned().fold(f64::MIN, f64::max),
            )
        };
        assert!(
            pos("12.7").1 < pos("25.4").0,
            "{width_mm} mm: {diameters:?}"
        );
        assert!(f.caption.contains(if wide {
            "One row per capstan diameter, one column per wrap."
        } else {
            "One column per capstan diameter, one row per wrap."
        }));
        let svg = standalone_svg(f, None, Some(width_mm));
        let problems = text_problems(&svg, &fonts, 0.5).unwrap();
        assert!(
            problems.is_empty(),
            "{width_mm} mm, {font_pt} pt: {problems:?}"
        );
        let (_, h_mm) = svg_size_mm(&svg).unwrap();
        assert!(h_mm <= MAX_HEIGHT_MM, "{h_mm} mm");
    }
    // Too narrow for a panel per diameter (40 mm): the reflowed grid, one panel across.
    let narrow = FigureOptions {
        width_mm: 40.0,
        ..FigureOptions::default()
    };
    let figs = figures::all(a, None, &narrow.layout()).unwrap();
    let f = figs.iter().find(|f| f.id == "amp_vs_t1").unwrap();
    let (titles, _) = cord_titles(&f.chart.svg);
    assert_eq!(levels(titles.iter().map(|t| t.0)).len(), 1, "{titles:?}");
    assert!(!f.caption.contains("One row per") && !f.caption.contains("One column per"));
}
