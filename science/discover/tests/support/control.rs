//! The mixed sets' controls: every mixed set made again without its outside physics (the same
//! seed, design and catalogue effects; the planted size 0).
//!
//! What the engine names on the control is what the catalogue alone can name at that design and
//! noise: the ceiling of "the effect named" beside outside physics. Where the control names the
//! third effect and the mixed set does not, the outside physics (or the term found for it) took
//! it; where the control does not name it either, the design cannot. A term proposed on a
//! control is a false term on a catalogue-only set with a third effect.

use super::{search, simulate, tag, variety, Options, Outcome};
use capstan_validation::discover_cases::{DiscoverCase, Group};

/// A mixed set's control, scored.
#[derive(Clone, Debug)]
pub struct Control {
    /// The engine names the third effect (and no proposed term took its place).
    pub named: bool,
    /// A term is proposed: a false term, nothing outside the catalogue was planted.
    pub false_term: bool,
}

/// Simulate and search the control of every mixed set among `cases` and attach it to its
/// outcome in `out` (the same order as `cases`).
pub fn attach(
    seed: u64,
    cases: &[DiscoverCase],
    out: &mut [Outcome],
    opts: &Options,
    threads: usize,
) {
    let mixed: Vec<usize> = (0..cases.len())
        .filter(|&i| cases[i].kind.group == Group::Mixed)
        .collect();
    if mixed.is_empty() {
        return;
    }
    let controls: Vec<DiscoverCase> = mixed
        .iter()
        .map(|&i| {
            let mut c = cases[i].clone();
            c.scale(0.0);
            c
        })
        .collect();
    let data = simulate(seed, &controls, &tag(variety(), 0.0), threads);
    for (&i, c) in mixed.iter().zip(search(&controls, &data, opts, threads)) {
        out[i].describe += &format!(
            " | control (no outside physics): effect named {}, terms {:?}",
            c.effect_named, c.proposed
        );
        out[i].control = Some(Control {
            named: c.effect_named,
            false_term: !c.proposed.is_empty(),
        });
    }
}

/// The controls in one paragraph: how often the engine names each third effect without the
/// outside physics, and with it; the false terms on the controls.
pub fn summary(out: &[Outcome]) -> String {
    let with: Vec<&Outcome> = out.iter().filter(|o| o.control.is_some()).collect();
    if with.is_empty() {
        return String::new();
    }
    let mut effects: Vec<&str> = Vec::new();
    for o in &with {
        let e = extra_of(o);
        if !effects.contains(&e) {
            effects.push(e);
        }
    }
    let per: Vec<String> = effects
        .iter()
        .map(|e| {
            let o: Vec<&&Outcome> = with.iter().filter(|o| extra_of(o) == *e).collect();
            let n = |f: &dyn Fn(&Outcome) -> bool| o.iter().filter(|x| f(x)).count();
            format!(
                "{e} {} / {} of {}",
                n(&|x| x.control_named()),
                n(&|x| x.effect_named),
                o.len()
            )
        })
        .collect();
    let n = |f: &dyn Fn(&Outcome) -> bool| with.iter().filter(|x| f(x)).count();
    format!(
        "\nmixed sets' controls (each set again without its outside physics): the engine names the third effect in {} of {} without it and in {} with it (without / with: {}); named on the control but not beside the outside physics: {}; terms proposed on the controls (false terms): {} of {}.\n",
        n(&|x| x.control_named()),
        with.len(),
        n(&|x| x.effect_named),
        per.join("; "),
        n(&|x| x.control_named() && !x.effect_named),
        n(&|x| x.control.as_ref().is_some_and(|c| c.false_term)),
        with.len()
    )
}

/// A mixed set's third effect, by name (from its label: "mixed (outside ± size + effect value)").
fn extra_of(o: &Outcome) -> &str {
    o.label
        .split(" + ")
        .nth(1)
        .and_then(|r| r.split_whitespace().next())
        .unwrap_or("?")
}
