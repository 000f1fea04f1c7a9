//! The simulated board as a library: made once in its directory (its hidden truth written,
//! its options refused before anything is written), locked while in use, and run by replay
//! (the same records again, bit for bit; an edited journal refused with its file and line).

use capstan_rig::record::Record;
use capstan_sim::session::Step;
use capstan_simboard::{
    steps, BenchError, SimBoard, SimError, SimOptions, Truth, JOURNAL_TXT, MAX_SENSITIVITY_ERROR,
    SIM_JSON, TRUTH_JSON,
};
use std::path::{Path, PathBuf};

/// A fresh, absent directory for one test's board.
fn fresh(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("capstan-simboard-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn options(dir: &Path) -> SimOptions {
    SimOptions {
        dir: Some(dir.to_path_buf()),
        ..SimOptions::default()
    }
}

/// Open the board, with what it said.
fn open(o: &SimOptions) -> (Result<SimBoard, SimError>, Vec<String>) {
    let mut said = Vec::new();
    let board = SimBoard::open(o, &mut |l| said.push(l));
    (board, said)
}

#[test]
fn a_new_board_says_so_once_and_keeps_its_hidden_sensor_errors_beside_it() {
    let dir = fresh("new");
    let (board, said) = open(&options(&dir));
    let board = board.unwrap();
    assert_eq!(said.len(), 1, "{said:?}");
    assert!(said[0].contains("a new simulated board") && said[0].contains(TRUTH_JSON));
    // The seed's defaults: the thesis's μ, one full wrap, quiet noise.
    let c = board.config();
    assert_eq!((c.seed, c.wrap_deg, c.noise.as_str()), (1, 360.0, "quiet"));
    assert!((c.mu - 0.115).abs() < 1e-12, "{}", c.mu);
    // Each sensor's sensitivity is off by a drawn factor within ±12 %, not both the same, and
    // the truth file gives N per count as the nominal 0.015 N/count over that factor.
    let f = c.sensitivity_factors();
    for k in f {
        assert!((k - 1.0).abs() <= MAX_SENSITIVITY_ERROR, "{f:?}");
    }
    assert_ne!(f[0], f[1]);
    let truth: Truth =
        serde_json::from_str(&std::fs::read_to_string(dir.join(TRUTH_JSON)).unwrap()).unwrap();
    assert!(
        (truth.t1.vs_nominal * f[0] - 1.0).abs() < 1e-9,
        "{:?}",
        truth.t1
    );
    assert!(
        (truth.t1.n_per_count - 0.015 / f[0]).abs() < 1e-12,
        "{:?}",
        truth.t1
    );
    // Zeros near the nominal 400 counts (spread 30 counts sd).
    assert!(
        (truth.t2.zero_counts - 400.0).abs() < 150.0,
        "{:?}",
        truth.t2
    );
    drop(board);
    // Opened again: nothing new to say; the same options are no other rig.
    let (again, said) = open(&SimOptions {
        seed: Some(1),
        ..options(&dir)
    });
    assert!(again.is_ok() && said.is_empty(), "{said:?}");
}

#[test]
fn refused_options_leave_no_directory_and_another_rig_is_refused_on_an_existing_board() {
    let dir = fresh("refused");
    let (r, said) = open(&SimOptions {
        mu: Some(5.0),
        ..options(&dir)
    });
    assert!(matches!(r, Err(SimError::Mu(m)) if m == 5.0));
    assert!(said.is_empty() && !dir.exists());
    let (r, _) = open(&SimOptions {
        effects: vec!["no_such_effect=1".into()],
        ..options(&dir)
    });
    assert!(matches!(r, Err(SimError::Effect { .. })), "{:?}", r.err());
    assert!(!dir.exists());
    let (r, _) = open(&SimOptions {
        dir: None,
        ..SimOptions::default()
    });
    assert!(matches!(r, Err(SimError::NoDir)));
    // Made with μ 0.2; then asked for μ 0.3 on it.
    open(&SimOptions {
        mu: Some(0.2),
        ..options(&dir)
    })
    .0
    .unwrap();
    let (r, _) = open(&SimOptions {
        mu: Some(0.3),
        ..options(&dir)
    });
    let e = r.err().unwrap();
    assert!(matches!(e, SimError::OtherRig(_)), "{e}");
    assert!(e.to_string().contains("\"mu\":0.2"), "{e}");
    // A directory that holds something else is not taken for a board.
    let other = fresh("other");
    std::fs::create_dir_all(&other).unwrap();
    std::fs::write(other.join("notes.txt"), "mine").unwrap();
    let (r, _) = open(&options(&other));
    assert!(matches!(r, Err(SimError::NotABoard(_))));
    assert!(!other.join(SIM_JSON).exists());
}

#[test]
fn one_command_at_a_time_holds_the_board() {
    let dir = fresh("lock");
    let first = open(&options(&dir)).0.unwrap();
    let (second, _) = open(&options(&dir));
    assert!(matches!(second, Err(SimError::InUse(_))));
    drop(first);
    assert!(open(&options(&dir)).0.is_ok());
}

#[test]
fn a_file_or_a_foreign_directory_is_refused_as_what_it_is() {
    let file = fresh("file");
    std::fs::write(&file, "not a board").unwrap();
    let (board, _) = open(&options(&file));
    let err = board.err().unwrap();
    assert!(matches!(err, SimError::NotADirectory(_)), "{err}");
    assert!(err.to_string().contains("a file, not a directory"), "{err}");
    assert_eq!(
        std::fs::read_to_string(&file).unwrap(),
        "not a board",
        "the file is left as it was"
    );

    let foreign = fresh("foreign");
    std::fs::create_dir_all(&foreign).unwrap();
    std::fs::write(foreign.join("notes.txt"), "mine").unwrap();
    let (board, _) = open(&options(&foreign));
    assert!(matches!(board, Err(SimError::NotABoard(_))));
}

#[test]
fn the_board_answers_a_command_and_its_replay_makes_the_same_records_again() {
    let dir = fresh("replay");
    let mut board = open(&options(&dir)).0.unwrap();
    let first = board.send("show").unwrap();
    assert!(
        first
            .iter()
            .any(|e| matches!(e.record, Record::Settings(_))),
        "show reports the settings: {first:?}"
    );
    let last_seq = first.last().unwrap().seq;
    drop(board);
    assert_eq!(
        std::fs::read_to_string(dir.join(JOURNAL_TXT)).unwrap(),
        "send show\nwait 2000\n"
    );
    // The next command replays the first, then goes on: its records follow on.
    let mut board = open(&options(&dir)).0.unwrap();
    let next = board.send("show").unwrap();
    assert_eq!(next.first().unwrap().seq, last_seq + 1);
    // A twin board (same seed) given the same bench makes the same records, bit for bit.
    let twin_dir = fresh("replay-twin");
    let mut twin = open(&options(&twin_dir)).0.unwrap();
    let twin_first = twin.send("show").unwrap();
    let bits = |es: &[capstan_simboard::Event]| format!("{es:?}");
    assert_eq!(bits(&twin_first), bits(&first));
    drop((board, twin));
    // An edited journal is refused where it was edited.
    let journal = dir.join(JOURNAL_TXT);
    let mut text = std::fs::read_to_string(&journal).unwrap();
    text.push_str("fly away\n");
    std::fs::write(&journal, text).unwrap();
    let e = open(&options(&dir)).0.err().unwrap();
    assert!(matches!(e, SimError::Journal { line: 5, .. }), "{e}");
    assert!(
        e.to_string()
            .starts_with(&format!("{}:5:1: not a bench step", journal.display())),
        "{e}"
    );
}

#[test]
fn a_bench_action_is_its_steps_or_a_typed_refusal() {
    let w = |s: &str| s.split(' ').map(String::from).collect::<Vec<_>>();
    let (load, said) = steps::bench(&w("load t2 9.80665")).unwrap();
    assert_eq!(
        load,
        [
            Step::Hang(capstan_rig::hal::Channel::T2, 9.80665),
            Step::Wait(steps::SETTLE_MS)
        ]
    );
    assert!(said.contains("9.80665 N hangs on T2"), "{said}");
    assert_eq!(steps::bench(&w("wait 1.5")).unwrap().0, [Step::Wait(1500)]);
    assert_eq!(
        steps::bench(&w("load t3 1")).unwrap_err(),
        BenchError::Channel("t3".into())
    );
    assert_eq!(
        steps::bench(&w("load t1 250")).unwrap_err(),
        BenchError::Weight("250".into())
    );
    assert_eq!(steps::bench(&w("fly")).unwrap_err(), BenchError::Usage);
}
