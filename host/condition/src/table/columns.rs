//! A header's columns: each cell's name, the run it belongs to (Logger Pro's `Run 2: Time`),
//! and its unit (`Force (N)`, `T1 [kgf]`, `t1_n`, or a units line), converted to s or N, or
//! refused by name (volts, counts, a unit nobody knows); and which column plays which role
//! (time, T1, T2, trigger, run), found by name or given by name or 1-based index.

use crate::error::Error;

/// What a column's unit is.
#[derive(Clone, Debug, PartialEq)]
pub enum Unit {
    /// No unit in the header (read as s for time, N for a force, and said).
    None,
    /// A time: the factor to s.
    Time(f64),
    /// A force: the factor to N.
    Force(f64),
    /// A mass read as its weight (g, kg: gram- and kilogram-force): the factor to N.
    Mass(f64),
    /// Volts: a sensor's output, not a force.
    Voltage,
    /// ADC counts.
    Counts,
    /// Something else, as written.
    Other(String),
}

impl Unit {
    fn of(text: &str) -> Unit {
        const G0: f64 = 9.806_65;
        let u = text.trim();
        let l = u.to_ascii_lowercase();
        match l.as_str() {
            "" => Unit::None,
            "s" | "sec" | "secs" | "second" | "seconds" => Unit::Time(1.0),
            "ms" | "msec" => Unit::Time(1e-3),
            "us" | "µs" | "μs" => Unit::Time(1e-6),
            "min" | "mins" | "minutes" => Unit::Time(60.0),
            "h" | "hr" | "hours" => Unit::Time(3600.0),
            "n" | "newton" | "newtons" => Unit::Force(1.0),
            "kn" => Unit::Force(1e3),
            "dan" => Unit::Force(10.0),
            "lbf" | "lb" | "lbs" => Unit::Force(4.448_221_615_260_5),
            "ozf" | "oz" => Unit::Force(0.278_013_850_953_781_2),
            "kgf" | "kp" => Unit::Force(G0),
            "gf" => Unit::Force(G0 * 1e-3),
            "kg" => Unit::Mass(G0),
            "g" => Unit::Mass(G0 * 1e-3),
            "v" | "volt" | "volts" | "mv" => Unit::Voltage,
            "counts" | "count" | "adc" | "lsb" => Unit::Counts,
            // mN against MN: a logger writes mN for millinewtons.
            _ if u == "mN" => Unit::Force(1e-3),
            _ => Unit::Other(u.to_string()),
        }
    }

    /// The factor to s, for a time column.
    pub fn to_s(&self) -> Option<f64> {
        match self {
            Unit::None => Some(1.0),
            Unit::Time(k) => Some(*k),
            _ => None,
        }
    }

    /// The factor to N, for a force column.
    pub fn to_n(&self) -> Option<f64> {
        match self {
            Unit::None => Some(1.0),
            Unit::Force(k) | Unit::Mass(k) => Some(*k),
            _ => None,
        }
    }

    /// Why a column in this unit cannot be a force (`None`: it can).
    pub fn not_a_force(&self) -> Option<String> {
        match self {
            Unit::Voltage => Some(
                "in volts: a sensor's output, not a force; convert it with the sensor's \
                 calibration (N per V) first, or log the force in newtons"
                    .into(),
            ),
            Unit::Counts => Some(
                "in ADC counts, not a force: give the column in newtons (our raw.csv has \
                 t1_n and t2_n)"
                    .into(),
            ),
            Unit::Time(_) => Some("a time, not a force".into()),
            Unit::Other(u) => Some(format!(
                "in `{u}`, a unit capstan does not know for a force (N, mN, kN, daN, gf, g, \
                 kgf, kg, lbf, lb, ozf)"
            )),
            _ => None,
        }
    }

    /// Why a column in this unit cannot be a time (`None`: it can).
    pub fn not_a_time(&self) -> Option<String> {
        match self {
            Unit::None | Unit::Time(_) => None,
            Unit::Other(u) => Some(format!(
                "in `{u}`, a unit capstan does not know for a time (s, ms, us, min, h)"
            )),
            _ => Some("not a time".into()),
        }
    }
}

/// One header cell.
#[derive(Clone, Debug)]
pub struct Col {
    /// As written.
    pub text: String,
    /// The run it belongs to: the text before a `:` (Logger Pro's `Run 2: Time (s)`).
    pub run: Option<String>,
    /// The name without the run and unit, lower case, letters and digits only.
    pub base: String,
    /// The unit.
    pub unit: Unit,
}

pub(super) fn normalise(s: &str) -> String {
    s.chars()
        .filter(|c| c.is_alphanumeric())
        .flat_map(char::to_lowercase)
        .collect()
}

impl Col {
    /// A header cell: `Name (unit)`, `Name [unit]`, `name_unit` (t1_n, time_s), or a name
    /// with the unit on a line of its own (`unit_line`); any of them after `Run N: `.
    pub fn parse(text: &str, unit_line: Option<&str>) -> Col {
        let t = text.trim();
        let (run, rest) = match t.split_once(':') {
            Some((r, n)) if !r.trim().is_empty() && !n.trim().is_empty() => {
                (Some(r.trim().to_string()), n.trim())
            }
            _ => (None, t),
        };
        let (name, unit) = if let Some(u) = unit_line.filter(|u| !u.trim().is_empty()) {
            (rest.to_string(), Unit::of(u))
        } else if let Some(open) = rest
            .rfind(['(', '['])
            .filter(|_| rest.ends_with([')', ']']))
        {
            (
                rest[..open].trim().to_string(),
                Unit::of(&rest[open + 1..rest.len() - 1]),
            )
        } else if let Some((n, u)) = rest
            .rsplit_once('_')
            .filter(|(n, u)| !n.is_empty() && !matches!(Unit::of(u), Unit::Other(_)))
        {
            (n.to_string(), Unit::of(u))
        } else {
            (rest.to_string(), Unit::None)
        };
        Col {
            text: t.to_string(),
            run,
            base: normalise(&name),
            unit,
        }
    }
}

/// Header names of each role (normalised).
pub const TIME_NAMES: [&str; 7] = [
    "time",
    "t",
    "times",
    "timestamp",
    "xvalue",
    "elapsed",
    "elapsedtime",
];
/// T1's names.
pub const T1_NAMES: [&str; 11] = [
    "t1",
    "tension1",
    "force1",
    "f1",
    "force",
    "forcet1",
    "tensiont1",
    "load1",
    "loadt1",
    "channel1",
    "ch1",
];
/// T2's names.
pub const T2_NAMES: [&str; 10] = [
    "t2",
    "tension2",
    "force2",
    "f2",
    "forcet2",
    "tensiont2",
    "load2",
    "loadt2",
    "channel2",
    "ch2",
];

/// How a role's column was asked for.
#[derive(Clone, Debug, PartialEq)]
pub enum Ask {
    /// Found by the role's names.
    Auto,
    /// By name, in every run block (`Time`, `Force 2`).
    Name(String),
    /// One column of the file: a 1-based index, or a name with its run (`Run 2: Time`).
    Exact(usize),
}

impl Ask {
    /// What `--time-column` and its kin say: a number is a 1-based column index; a name with
    /// `Run N:` one run's column; another name a column of that name in every run.
    pub fn of(given: Option<&str>, cols: &[Col], flag: &str) -> Result<Ask, Error> {
        let Some(g) = given.map(str::trim) else {
            return Ok(Ask::Auto);
        };
        if let Ok(k) = g.parse::<usize>() {
            if k == 0 || k > cols.len() {
                column_error!(
                    "{flag} {g}: the header has columns 1 to {} ({})",
                    cols.len(),
                    list(cols)
                );
            }
            return Ok(Ask::Exact(k - 1));
        }
        let want = Col::parse(g, None);
        if want.run.is_some() {
            let hits: Vec<usize> = (0..cols.len())
                .filter(|&i| {
                    normalise(&cols[i].text) == normalise(g)
                        || (cols[i].run.as_deref().map(normalise)
                            == want.run.as_deref().map(normalise)
                            && cols[i].base == want.base)
                })
                .collect();
            return match hits.as_slice() {
                [i] => Ok(Ask::Exact(*i)),
                [] => column_error!("{flag} {g}: no such column (the header has {})", list(cols)),
                _ => column_error!(
                    "{flag} {g}: {} columns have that name: give its number (1 to {})",
                    hits.len(),
                    cols.len()
                ),
            };
        }
        // The whole header text (`Force 2 (N)`) or the name without unit (`Force 2`).
        if !cols
            .iter()
            .any(|c| c.base == want.base || normalise(&c.text) == normalise(g))
        {
            column_error!("{flag} {g}: no such column (the header has {})", list(cols));
        }
        Ok(Ask::Name(g.to_string()))
    }
}

/// The header's columns, for a message.
pub fn list(cols: &[Col]) -> String {
    cols.iter()
        .enumerate()
        .map(|(i, c)| format!("{} `{}`", i + 1, c.text))
        .collect::<Vec<_>>()
        .join(", ")
}

/// One role's column among `idx` (the columns of one run block) of `cols`.
pub struct Role<'a> {
    /// `time`, `T1`, ...
    pub name: &'a str,
    /// `--time-column`, ...
    pub flag: &'a str,
    /// Its header names.
    pub names: &'a [&'a str],
    /// Why a column cannot play it (`None`: it can).
    pub refuse: fn(&Unit) -> Option<String>,
}

/// The role's column in the block `idx`, as `ask` says.
pub fn pick(cols: &[Col], idx: &[usize], ask: &Ask, role: &Role) -> Result<usize, Error> {
    let named = |i: usize| match ask {
        Ask::Name(n) => {
            let want = Col::parse(n, None);
            cols[i].base == want.base || normalise(&cols[i].text) == normalise(n)
        }
        _ => role.names.contains(&cols[i].base.as_str()),
    };
    let checked = |i: usize| match (role.refuse)(&cols[i].unit) {
        Some(why) if *ask == Ask::Auto => column_error!(
            "which column is {}? column {} `{}` is named so, but it is {why}",
            role.name,
            i + 1,
            cols[i].text
        ),
        Some(why) => column_error!(
            "{}: column {} `{}` is {why}",
            role.flag,
            i + 1,
            cols[i].text
        ),
        None => Ok(i),
    };
    if let Ask::Exact(i) = ask {
        return checked(*i);
    }
    let hits: Vec<usize> = idx.iter().copied().filter(|&i| named(i)).collect();
    let fit: Vec<usize> = hits
        .iter()
        .copied()
        .filter(|&i| (role.refuse)(&cols[i].unit).is_none())
        .collect();
    let block = list(&idx.iter().map(|&i| cols[i].clone()).collect::<Vec<_>>());
    match (fit.as_slice(), hits.as_slice()) {
        ([i], _) => Ok(*i),
        ([], [i]) => checked(*i),
        ([], []) => column_error!(
            "which column is {}? none is named so: give {} NAME or NUMBER (the header has {})",
            role.name,
            role.flag,
            list(cols)
        ),
        ([], _) => column_error!(
            "which column is {}? {} are named so but none is {}: give {} NAME or NUMBER",
            role.name,
            hits.iter()
                .map(|&i| format!("`{}` ({})", cols[i].text, (role.refuse)(&cols[i].unit).unwrap_or_default()))
                .collect::<Vec<_>>()
                .join(", "),
            if role.name == "time" { "a time" } else { "a force" },
            role.flag
        ),
        _ => column_error!(
            "which column is {}? several could be ({}): give {} NAME or NUMBER (the columns: {block})",
            role.name,
            fit.iter()
                .map(|&i| format!("`{}`", cols[i].text))
                .collect::<Vec<_>>()
                .join(", "),
            role.flag
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_runs_and_units_are_read_from_any_header_form() {
        let c = Col::parse("Run 2: Force 2 (lbf)", None);
        assert_eq!(
            (c.run.as_deref(), c.base.as_str()),
            (Some("Run 2"), "force2")
        );
        assert!((c.unit.to_n().unwrap() - 4.448_221_615_260_5).abs() < 1e-12);
        let c = Col::parse("t1_n", None);
        assert_eq!((c.base.as_str(), c.unit.to_n()), ("t1", Some(1.0)));
        let c = Col::parse("Load cell A [kg]", None);
        assert_eq!(c.unit, Unit::Mass(9.806_65));
        let c = Col::parse("Force", Some("mN"));
        assert_eq!(c.unit.to_n(), Some(1e-3));
        let c = Col::parse("Force 1 (V)", None);
        assert!(c.unit.not_a_force().unwrap().contains("volts"));
        assert_eq!(Col::parse("Time (ms)", None).unit.to_s(), Some(1e-3));
        assert_eq!(Col::parse("t1_counts", None).unit, Unit::Counts);
    }

    #[test]
    fn a_volts_column_is_refused_by_its_unit_not_as_missing() {
        let cols: Vec<Col> = ["Time (s)", "Force 1 (V)", "Force 2 (V)"]
            .iter()
            .map(|t| Col::parse(t, None))
            .collect();
        let role = Role {
            name: "T1",
            flag: "--t1-column",
            names: &T1_NAMES,
            refuse: Unit::not_a_force,
        };
        let e = pick(&cols, &[0, 1, 2], &Ask::Auto, &role)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(
                "which column is T1? column 2 `Force 1 (V)` is named so, but it is in volts"
            ),
            "{e}"
        );
    }
}
