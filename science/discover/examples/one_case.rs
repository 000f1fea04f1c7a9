//! `cargo run --release -p capstan-discover --example one_case -- SEED KIND INDEX [OUT.csv]`:
//! one planted set, simulated, searched, printed as JSON (and its pairs written, if asked);
//! the varied designs unless `CAPSTAN_DISCOVER_DESIGN=thesis` (or `updown`).
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let seed: u64 = a[1].parse().expect("seed");
    let kind = capstan_validation::discover_cases::KINDS
        .iter()
        .find(|k| k.name == a[2])
        .expect("kind");
    let index: u64 = a[3].parse().expect("index");
    use capstan_validation::discover_cases::Variety;
    let variety = match std::env::var("CAPSTAN_DISCOVER_DESIGN").as_deref() {
        Ok("thesis") => Variety::Thesis,
        Ok("updown") => Variety::ThesisUpDown,
        _ => Variety::Varied,
    };
    let mut c = capstan_validation::discover_cases::draw(seed, kind, index, variety);
    if let Some(x) = std::env::var("CAPSTAN_DISCOVER_SCALE")
        .ok()
        .and_then(|v| v.parse().ok())
    {
        c.scale(x);
    }
    eprintln!("{} {:+.3}", c.label(), c.size);
    if std::env::var("CAPSTAN_NO_WANDER").is_ok() {
        c.case.config.plant.disturbances.mu_wander_sd = 0.0;
    }
    if std::env::var("CAPSTAN_NO_ZERO").is_ok() {
        c.case.config.plant.disturbances.zero_error_sd_n = 0.0;
    }
    if std::env::var("CAPSTAN_QUIET").is_ok() {
        // The same set without the thesis rig's scatter and wander (a diagnostic).
        c.case.config.plant.disturbances = Default::default();
        c.case.config.scatter_pct = 0.0;
        c.case.config.run_scatter_pct = Some(0.0);
    }
    let (data, _) = c.case.generate().expect("simulate");
    if let Some(p) = a.get(4) {
        let mut f = std::fs::File::create(p).expect("create");
        capstan_data::write_pairs_to(&mut f, &data.pairs).expect("write");
    }
    let d = capstan_discover::discover(&data, &Default::default(), &mut |_, _| {});
    println!("{}", d.to_json());
}
