//! `cargo run --release -p capstan-discover --example discover_thesis [CSV]`: the search on the
//! bundled thesis data (or a pairs CSV), as JSON.
fn main() {
    let data = match std::env::args().nth(1) {
        Some(p) => capstan_data::load_pairs(std::path::Path::new(&p)).expect("read"),
        None => capstan_data::thesis_dataset(),
    };
    let d = capstan_discover::discover(&data, &Default::default(), &mut |_, _| {});
    println!("{}", d.to_json());
}
