//! The acceptance figures of the planted-truth scorer ([`crate::score`]): what share of each
//! class of cases is answered right, against the issue's targets.

use crate::cases::Class;
use crate::score::Outcome;
use capstan_engine::evidence::Level;

/// Thresholds of the acceptance figures.
#[derive(Clone, Copy, Debug)]
pub struct Targets {
    /// Single effects named, at least.
    pub single: f64,
    /// Parameters within 25 % of the named single effects, at least.
    pub parameters: f64,
    /// Pairs named exactly, at least.
    pub pairs: f64,
    /// Outside the catalogue flagged, at least.
    pub outside: f64,
    /// Clean sets with an alarm, at most.
    pub clean_alarms: f64,
    /// Right single/pair calls that carry a rival, at most.
    pub rival_doubts: f64,
    /// Calls of one effect in place of another that report the planted one as a rival, at
    /// least.
    pub rival_catches: f64,
}

impl Targets {
    /// The issue's targets.
    pub const ISSUE: Targets = Targets {
        single: 0.90,
        parameters: 0.90,
        pairs: 0.75,
        outside: 0.80,
        clean_alarms: 0.05,
        // The issue sets no target for rivals.
        rival_doubts: 1.0,
        rival_catches: 0.0,
    };

    /// What the diagnosis reaches on every master seed measured (99, 20260522, 2718281828:
    /// docs/README-diagnose.md): the line the full test holds on any seed (on the test seed,
    /// with [`Targets::ISSUE`] as well).
    pub const MEASURED: Targets = Targets {
        single: 0.85,
        parameters: 0.90,
        pairs: 0.75,
        outside: 0.90,
        clean_alarms: 0.05,
        // 5.9-8.1 % and 75-100 % (5/6, 3/4, 7/7) on the three seeds.
        rival_doubts: 0.10,
        rival_catches: 0.50,
    };
}

/// The acceptance figures.
#[derive(Clone, Debug, Default)]
pub struct Metrics {
    /// Single effects (sizes that matter) named exactly.
    pub single: (usize, usize),
    /// Of those, parameters within 25 %.
    pub single_parameters: (usize, usize),
    /// Small single effects named exactly (reported, not a target).
    pub small: (usize, usize),
    /// Pairs named exactly.
    pub pairs: (usize, usize),
    /// Outside effects flagged unexplained.
    pub outside: (usize, usize),
    /// Outside effects given a catalogue name without the flag.
    pub outside_named: (usize, usize),
    /// Clean sets with anything named or flagged.
    pub clean_alarms: (usize, usize),
    /// Single effects and pairs named right that carry a rival (a doubt they did not need).
    pub rival_doubts: (usize, usize),
    /// Single effects and pairs named wrong with a set of the right size (one effect in
    /// place of another), every planted effect missed a within-run one (rivals are within-run
    /// effects), that report each missed planted effect as a rival of a wrong found one.
    pub rival_catches: (usize, usize),
    /// Runs the firmware stopped (a planted physics it reads as a fault), of the designs' runs:
    /// reported, not a target (the sets are scored as the smaller sets they are).
    pub runs_lost: (usize, usize),
}

fn frac(x: (usize, usize)) -> f64 {
    if x.1 == 0 {
        f64::NAN
    } else {
        x.0 as f64 / x.1 as f64
    }
}

impl Metrics {
    /// The figures of `outcomes`.
    pub fn of(outcomes: &[Outcome]) -> Metrics {
        let count = |class: Class, f: &dyn Fn(&Outcome) -> bool| {
            let of: Vec<&Outcome> = outcomes.iter().filter(|o| o.class == class).collect();
            (of.iter().filter(|o| f(o)).count(), of.len())
        };
        let named: Vec<&Outcome> = outcomes
            .iter()
            .filter(|o| matches!(o.class, Class::Single | Class::Pair))
            .collect();
        let right: Vec<&Outcome> = named.iter().copied().filter(|o| o.correct()).collect();
        let swapped: Vec<&Outcome> = named
            .iter()
            .copied()
            .filter(|o| !o.correct() && !o.unexplained && o.found.len() == o.truth.len())
            .filter(|o| {
                o.missed()
                    .iter()
                    .all(|k| capstan_engine::evidence::candidates::level(*k) == Level::WithinRun)
            })
            .collect();
        let count_of = |of: &[&Outcome], f: &dyn Fn(&Outcome) -> bool| {
            (of.iter().filter(|o| f(o)).count(), of.len())
        };
        let named_singles: Vec<&Outcome> = outcomes
            .iter()
            .filter(|o| o.class == Class::Single && o.correct())
            .collect();
        Metrics {
            runs_lost: outcomes
                .iter()
                .fold((0, 0), |(a, b), o| (a + o.runs_short.0, b + o.runs_short.1)),
            single: count(Class::Single, &|o| o.correct()),
            single_parameters: (
                named_singles.iter().filter(|o| o.parameters_ok()).count(),
                named_singles.len(),
            ),
            small: count(Class::SmallSingle, &|o| o.correct()),
            pairs: count(Class::Pair, &|o| o.correct()),
            outside: count(Class::Outside, &|o| o.unexplained),
            outside_named: count(Class::Outside, &|o| !o.unexplained && !o.found.is_empty()),
            clean_alarms: count(Class::Clean, &|o| o.alarm()),
            rival_doubts: count_of(&right, &|o| !o.rivals.is_empty()),
            rival_catches: count_of(&swapped, &|o| {
                let truth = o.truth_kinds();
                o.missed()
                    .iter()
                    .all(|t| o.rivals.iter().any(|r| r.1 == *t && !truth.contains(&r.0)))
            }),
        }
    }

    /// Why the figures fail the issue's targets (empty: they pass).
    pub fn failures(&self) -> Vec<String> {
        self.failures_against(&Targets::ISSUE)
    }

    /// Why the figures fail `t` (empty: they pass).
    pub fn failures_against(&self, t: &Targets) -> Vec<String> {
        let mut why = Vec::new();
        let mut check = |ok: bool, what: &str, x: (usize, usize), limit: f64, sign: &str| {
            if !ok {
                why.push(format!(
                    "{what} {}/{} {sign} {:.0} %",
                    x.0,
                    x.1,
                    100.0 * limit
                ));
            }
        };
        check(
            frac(self.single) >= t.single,
            "single effects named",
            self.single,
            t.single,
            "<",
        );
        check(
            frac(self.single_parameters) >= t.parameters,
            "parameters within 25 % of named single effects",
            self.single_parameters,
            t.parameters,
            "<",
        );
        check(
            frac(self.pairs) >= t.pairs,
            "pairs named",
            self.pairs,
            t.pairs,
            "<",
        );
        check(
            frac(self.outside) >= t.outside,
            "outside flagged",
            self.outside,
            t.outside,
            "<",
        );
        check(
            frac(self.clean_alarms) <= t.clean_alarms,
            "clean sets with an alarm",
            self.clean_alarms,
            t.clean_alarms,
            ">",
        );
        check(
            self.rival_doubts.1 == 0 || frac(self.rival_doubts) <= t.rival_doubts,
            "right calls with a rival",
            self.rival_doubts,
            t.rival_doubts,
            ">",
        );
        check(
            self.rival_catches.1 == 0 || frac(self.rival_catches) >= t.rival_catches,
            "one effect in place of another with the truth as its rival",
            self.rival_catches,
            t.rival_catches,
            "<",
        );
        why
    }

    /// The figures as a short table.
    pub fn table(&self) -> String {
        let row = |what: &str, x: (usize, usize), target: &str| {
            format!(
                "{what:<44} {:>4}/{:<4} {:>6.1} %   {target}\n",
                x.0,
                x.1,
                100.0 * frac(x)
            )
        };
        row(
            "single effects named (sizes that matter)",
            self.single,
            "≥ 90 %",
        ) + &row("  parameter within 25 %", self.single_parameters, "≥ 90 %")
            + &row(
                "small single effects named",
                self.small,
                "(detection limit)",
            )
            + &row("pairs: both named, nothing else", self.pairs, "≥ 75 %")
            + &row("outside the catalogue: unexplained", self.outside, "≥ 80 %")
            + &row(
                "outside: named without the flag",
                self.outside_named,
                "(should be 0)",
            )
            + &row(
                "clean: anything named or flagged",
                self.clean_alarms,
                "≤ 5 %",
            )
            + &row(
                "right single/pair calls with a rival",
                self.rival_doubts,
                "(a doubt not needed)",
            )
            + &row(
                "one effect in place of another: truth a rival",
                self.rival_catches,
                "(the doubt that was needed)",
            )
            + &row(
                "runs the firmware stopped (e.g. cord_break)",
                self.runs_lost,
                "(scored as the smaller sets)",
            )
    }
}
