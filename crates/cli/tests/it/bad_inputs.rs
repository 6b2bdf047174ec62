//! The catalogue of bad inputs (`tests/bad_inputs/catalogue.txt`): every
//! case runs `nlvid` on a broken study, data file or command line and must
//! end with a clear message — the expected exit status, `error:` on stderr
//! with the expected text, no panic, within the time limit (nothing hangs
//! or grows without bound), and nothing written that a case says must not
//! exist (outputs are checked before any computation).
//!
//! Format of a case (blocks separated by `=== name`):
//! ```text
//! === material: wrong unit
//! run: material {dir}/s.toml          (several `run:` lines: each must fail alike)
//! code: 1
//! stderr: `material.C1`               (several: all must appear)
//! once: os error 2                    (must appear exactly once)
//! absent: {dir}/store                 (must not exist afterwards)
//! --- s.toml                          (a file written into {dir}; `\x` escapes none)
//! [material]
//! ...
//! ```
//! `{dir}` is the case's scratch directory, `{examples}` the repository's
//! `examples/`. Arguments are split on whitespace; `"…"` keeps spaces.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::common;

/// Longest any case may run (debug build, loaded machine).
const LIMIT: Duration = Duration::from_secs(60);

#[derive(Debug, Default)]
struct Case {
    name: String,
    runs: Vec<String>,
    code: Option<i32>,
    stderr: Vec<String>,
    once: Vec<String>,
    absent: Vec<String>,
    files: Vec<(String, String)>,
}

fn parse(text: &str) -> Vec<Case> {
    let mut cases: Vec<Case> = Vec::new();
    let mut file: Option<(String, String)> = None;
    for line in text.lines() {
        if let Some(name) = line.strip_prefix("=== ") {
            if let (Some(c), Some(f)) = (cases.last_mut(), file.take()) {
                c.files.push(f);
            }
            cases.push(Case {
                name: name.trim().to_string(),
                ..Case::default()
            });
            continue;
        }
        let Some(c) = cases.last_mut() else { continue };
        if let Some(name) = line.strip_prefix("--- ") {
            if let Some(f) = file.take() {
                c.files.push(f);
            }
            file = Some((name.trim().to_string(), String::new()));
        } else if let Some((_, body)) = file.as_mut() {
            body.push_str(line);
            body.push('\n');
        } else if let Some(v) = line.strip_prefix("run: ") {
            c.runs.push(v.trim().to_string());
        } else if let Some(v) = line.strip_prefix("code: ") {
            c.code = Some(v.trim().parse().expect("code"));
        } else if let Some(v) = line.strip_prefix("stderr: ") {
            c.stderr.push(v.trim().to_string());
        } else if let Some(v) = line.strip_prefix("once: ") {
            c.once.push(v.trim().to_string());
        } else if let Some(v) = line.strip_prefix("absent: ") {
            c.absent.push(v.trim().to_string());
        } else {
            assert!(
                line.trim().is_empty() || line.starts_with('#'),
                "catalogue: stray line `{line}` in case {}",
                c.name
            );
        }
    }
    if let (Some(c), Some(f)) = (cases.last_mut(), file.take()) {
        c.files.push(f);
    }
    cases
}

/// Whitespace-separated words; `"…"` keeps its spaces.
fn words(s: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut quoted = false;
    for ch in s.chars() {
        match ch {
            '"' => quoted = !quoted,
            c if c.is_whitespace() && !quoted => {
                if !cur.is_empty() {
                    out.push(std::mem::take(&mut cur));
                }
            }
            c => cur.push(c),
        }
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

fn run_with_limit(args: &[String], dir: &Path) -> (Option<i32>, String, Duration) {
    let start = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_nlvid"))
        .args(args)
        .current_dir(dir)
        .env("NLVID_NO_PROGRESS", "1")
        .env_remove("NLVID_LOG")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn nlvid");
    let mut err = child.stderr.take().expect("stderr");
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = std::io::Read::read_to_string(&mut err, &mut s);
        s
    });
    loop {
        if let Some(st) = child.try_wait().expect("wait") {
            return (st.code(), reader.join().unwrap(), start.elapsed());
        }
        if start.elapsed() > LIMIT {
            let _ = child.kill();
            let _ = child.wait();
            return (None, reader.join().unwrap(), start.elapsed());
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

#[test]
fn every_bad_input_gets_a_clear_message() {
    let catalogue = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad_inputs/catalogue.txt");
    let text = std::fs::read_to_string(&catalogue).unwrap();
    let examples = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .canonicalize()
        .unwrap();
    let root = common::scratch("bad-inputs");
    let cases = parse(&text);
    let mut failures = Vec::new();
    let mut runs = 0;
    for (k, case) in cases.iter().enumerate() {
        assert!(!case.runs.is_empty(), "case {} has no `run:`", case.name);
        let dir = root.join(format!("case{k:03}"));
        std::fs::create_dir_all(&dir).unwrap();
        let subst = |s: &str| {
            s.replace("{dir}", &dir.display().to_string())
                .replace("{examples}", &examples.display().to_string())
        };
        for (name, body) in &case.files {
            let p: PathBuf = dir.join(name);
            std::fs::create_dir_all(p.parent().unwrap()).unwrap();
            std::fs::write(&p, subst(body)).unwrap();
        }
        for run in &case.runs {
            runs += 1;
            let args: Vec<String> = words(&subst(run));
            let (code, err, took) = run_with_limit(&args, &dir);
            let mut why = Vec::new();
            if code.is_none() {
                why.push(format!("killed after {took:?} (hang or runaway)"));
            }
            if code == Some(0) {
                why.push("accepted (exit 0)".into());
            }
            if let (Some(want), Some(got)) = (case.code, code)
                && want != got
            {
                why.push(format!("exit {got}, expected {want}"));
            }
            if err.contains("panicked") || err.contains("RUST_BACKTRACE") {
                why.push("panicked".into());
            }
            if !err.contains("error") {
                why.push("no `error` on stderr".into());
            }
            for s in &case.stderr {
                if !err.contains(&subst(s)) {
                    why.push(format!("stderr lacks `{s}`"));
                }
            }
            for s in &case.once {
                let n = err.matches(s.as_str()).count();
                if n != 1 {
                    why.push(format!("`{s}` appears {n} times"));
                }
            }
            for a in &case.absent {
                if Path::new(&subst(a)).exists() {
                    why.push(format!("{a} was created"));
                }
            }
            if !why.is_empty() {
                failures.push(format!(
                    "[{}] nlvid {}: {}\n    stderr: {}",
                    case.name,
                    args.join(" "),
                    why.join("; "),
                    err.trim().replace('\n', "\n            ")
                ));
            }
        }
    }
    assert!(
        runs >= 100,
        "the catalogue should hold at least 100 runs, has {runs}"
    );
    assert!(
        failures.is_empty(),
        "{} of {runs} bad inputs not handled clearly:\n{}",
        failures.len(),
        failures.join("\n")
    );
}
