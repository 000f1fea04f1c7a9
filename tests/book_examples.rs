//! The user guide (`docs/book`) checked against the program it describes.
//!
//! * Every ```` ```sh,run ```` block of a chapter runs as written, in order, in one empty
//!   directory per chapter, with this build's `capstan` first on `PATH`. It must succeed; a
//!   block marked ```` ```sh,run,fails ```` must fail. Plain ```` ```sh ```` blocks (install,
//!   hardware, minute-long commands) are shown, not run.
//! * A ```` ```text,output ```` block right after a run block is the shape of its output
//!   (stdout and stderr together): each of its lines must match a line of the output, in
//!   order. Blanks count as one; `…` stands for any text, and a line of `…` alone for any lines.
//! * The science chapter's table lists the catalogue, every effect once.
//! * Where the guide says code lives (`path`, `Name` in `path`), the path exists and the file
//!   names it.
//!
//! `mdbook test docs/book` runs the guide's Rust examples; `.ci/run` runs both.

use std::path::{Path, PathBuf};
use std::process::Command;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn book_src() -> PathBuf {
    repo().join("docs/book/src")
}

/// The chapters SUMMARY.md lists, in its order.
fn chapters() -> Vec<String> {
    let summary = std::fs::read_to_string(book_src().join("SUMMARY.md")).unwrap();
    summary
        .lines()
        .filter_map(|l| {
            let start = l.find("](")? + 2;
            let end = start + l[start..].find(')')?;
            Some(l[start..end].to_string())
        })
        .collect()
}

/// One runnable shell block and the output shape that follows it.
#[derive(Debug)]
struct Block {
    line: usize,
    script: String,
    fails: bool,
    shape: Vec<String>,
}

/// The fenced blocks of a chapter: (line of the fence, info words, body).
fn fences(text: &str) -> Vec<(usize, Vec<String>, String)> {
    let mut out = Vec::new();
    let mut open: Option<(usize, Vec<String>, String)> = None;
    for (i, line) in text.lines().enumerate() {
        let t = line.trim();
        match open.take() {
            None => {
                if let Some(info) = t.strip_prefix("```") {
                    let words = info.split(',').map(|w| w.trim().to_string()).collect();
                    open = Some((i + 1, words, String::new()));
                }
            }
            Some((at, words, mut body)) => {
                if t == "```" {
                    out.push((at, words, body));
                } else {
                    body.push_str(line);
                    body.push('\n');
                    open = Some((at, words, body));
                }
            }
        }
    }
    assert!(open.is_none(), "a fence is never closed");
    out
}

/// The chapter's run blocks, each with the output shape right after it (if any).
fn run_blocks(chapter: &str) -> Vec<Block> {
    let text = std::fs::read_to_string(book_src().join(chapter)).unwrap();
    let all = fences(&text);
    let mut blocks: Vec<Block> = Vec::new();
    for (k, (line, words, body)) in all.iter().enumerate() {
        let has = |w: &str| words.iter().any(|x| x == w);
        if words[0] == "sh" && has("run") {
            blocks.push(Block {
                line: *line,
                script: body.clone(),
                fails: has("fails"),
                shape: Vec::new(),
            });
        } else if words[0] == "text" && has("output") {
            let after_run = k > 0 && {
                let (_, prev, _) = &all[k - 1];
                prev[0] == "sh" && prev.iter().any(|w| w == "run")
            };
            assert!(
                after_run,
                "{chapter}:{line}: an output block must follow a `sh,run` block"
            );
            let last = blocks.last_mut().unwrap();
            last.shape = body.lines().map(str::to_string).collect();
        }
    }
    blocks
}

fn squeeze(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Whether `line` has the shape `pattern` (`…` any text; anchored at both ends).
fn matches(pattern: &str, line: &str) -> bool {
    let (pattern, line) = (squeeze(pattern), squeeze(line));
    let parts: Vec<&str> = pattern.split('…').collect();
    let (first, last) = (parts[0], parts[parts.len() - 1]);
    if parts.len() == 1 {
        return line == pattern;
    }
    if !line.starts_with(first) {
        return false;
    }
    let mut at = first.len();
    for part in &parts[1..parts.len() - 1] {
        match line[at..].find(part) {
            Some(i) => at += i + part.len(),
            None => return false,
        }
    }
    line.len() >= at + last.len() && line.ends_with(last)
}

/// The first line of `shape` that no line of `output` matches in order, if any.
fn unmatched<'a>(shape: &'a [String], output: &str) -> Option<&'a str> {
    let mut lines = output.lines();
    for p in shape {
        if squeeze(p).is_empty() || squeeze(p) == "…" {
            continue;
        }
        if !lines.any(|l| matches(p, l)) {
            return Some(p);
        }
    }
    None
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("capstan-book-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Run a chapter's blocks in order in one directory; the number run.
fn run_chapter(chapter: &str) -> usize {
    let blocks = run_blocks(chapter);
    if blocks.is_empty() {
        return 0;
    }
    let dir = tmp(chapter.trim_end_matches(".md"));
    let bin = PathBuf::from(env!("CARGO_BIN_EXE_capstan"));
    let path = format!(
        "{}:{}",
        bin.parent().unwrap().display(),
        std::env::var("PATH").unwrap_or_default()
    );
    for b in &blocks {
        let out = Command::new("bash")
            .arg("-c")
            .arg(format!("exec 2>&1\nset -eu\n{}", b.script))
            .current_dir(&dir)
            .env("PATH", &path)
            .output()
            .expect("bash runs");
        let output = String::from_utf8_lossy(&out.stdout);
        let at = format!("docs/book/src/{chapter}:{}", b.line);
        assert_eq!(
            out.status.success(),
            !b.fails,
            "{at}: the block {} ({})\n{}--- output\n{output}",
            if b.fails { "succeeded" } else { "failed" },
            out.status,
            b.script
        );
        if let Some(p) = unmatched(&b.shape, &output) {
            panic!(
                "{at}: no line of the output has the shape `{p}` (in order)\n{}--- output\n{output}",
                b.script
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    blocks.len()
}

#[test]
fn the_guides_commands_run_as_written_and_print_what_it_shows() {
    let mut run = 0;
    for chapter in chapters() {
        run += run_chapter(&chapter);
    }
    // The tutorial's steps are all here: analyse, figures, predict, own data.
    let tutorial: String = run_blocks("tutorial.md")
        .iter()
        .map(|b| b.script.clone())
        .collect();
    for step in [
        "capstan analyze --out report",
        "capstan analyze --figures",
        "capstan predict --from report/metrics.json",
        "capstan diagnose mine.csv",
    ] {
        assert!(tutorial.contains(step), "the tutorial runs `{step}`");
    }
    assert!(run >= 10, "only {run} blocks ran");
}

#[test]
fn output_shapes_match_as_documented() {
    assert!(matches("capstan …", "capstan 0.1.0"));
    assert!(!matches("capstan …", "xcapstan 0.1.0"));
    assert!(matches("figure-1-….pdf", "figure-1-gain.pdf"));
    assert!(!matches("figure-1-….pdf", "figure-1-gain.png"));
    assert!(matches(
        "t2_offset … found",
        "  t2_offset   -79.4  x  found"
    ));
    assert!(!matches("t2_offset … found", "  t2_offset   t2_offset (x)"));
    assert!(matches("a  b", "a b"));
    let shape = ["one …".to_string(), "…".to_string(), "three".to_string()];
    assert_eq!(unmatched(&shape, "one 1\ntwo\nthree\n"), None);
    assert_eq!(unmatched(&shape, "three\none 1\n"), Some("three"));
}

#[test]
fn the_science_chapter_lists_the_whole_catalogue() {
    let text = std::fs::read_to_string(book_src().join("science.md")).unwrap();
    let listed: Vec<&str> = text
        .lines()
        .filter_map(|l| l.strip_prefix("| `")?.split('`').next())
        .collect();
    let catalogue: Vec<&str> = capstan_physics::EffectKind::ALL
        .iter()
        .map(|k| k.name())
        .collect();
    assert_eq!(listed, catalogue, "the table, in the catalogue's order");
}

/// Backticked repository paths in a chapter's text (not its code blocks): a `/` and no
/// blank, no placeholder.
fn paths_named(text: &str) -> Vec<(String, Option<String>)> {
    let mut out = Vec::new();
    let mut in_code = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            in_code = !in_code;
            continue;
        }
        if in_code {
            continue;
        }
        let spans: Vec<&str> = line.split('`').skip(1).step_by(2).collect();
        for (i, span) in spans.iter().enumerate() {
            // Placeholders, formulas, and the files the commands write (a `DIR`, `CASE` or
            // output directory of the guide's examples) are not repository paths.
            let written = ["target/", "runs/", "raw/", "report/"];
            let placeholder = span.contains(['*', '~', '<', '…', ' '])
                || span.split('/').any(|c| c == "DIR" || c == "CASE")
                || span.starts_with(char::is_numeric)
                || written
                    .iter()
                    .any(|w| span.starts_with(w) || *span == &w[..w.len() - 1]);
            if !span.contains('/') || placeholder {
                continue;
            }
            // `Name` in `path`: the file must name it.
            let named = i.checked_sub(1).and_then(|j| {
                let before = format!("`{}` in `{span}`", spans[j]);
                line.contains(&before)
                    .then(|| spans[j].rsplit("::").next().unwrap().to_string())
            });
            out.push((span.trim_end_matches('/').to_string(), named));
        }
    }
    out
}

#[test]
fn where_the_guide_says_code_lives_it_does() {
    let mut checked = 0;
    for chapter in chapters() {
        // The tutorial's paths are the files its commands write.
        if chapter == "tutorial.md" {
            continue;
        }
        let text = std::fs::read_to_string(book_src().join(&chapter)).unwrap();
        for (path, name) in paths_named(&text) {
            let file = repo().join(&path);
            assert!(
                Path::new(&file).exists(),
                "docs/book/src/{chapter}: `{path}` does not exist"
            );
            if let Some(name) = name {
                let body = std::fs::read_to_string(&file).unwrap();
                assert!(
                    body.contains(&name),
                    "docs/book/src/{chapter}: `{path}` does not name `{name}`"
                );
            }
            checked += 1;
        }
    }
    assert!(checked >= 50, "only {checked} paths named");
}
