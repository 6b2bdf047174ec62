//! Helpers shared by the CLI's end-to-end tests (each test binary uses a
//! subset, hence the `dead_code` allowance).
#![allow(dead_code, clippy::expect_used)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs the `nlvid` binary with `args` (logging off) and waits for it.
pub fn nlvid(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_nlvid"))
        .args(args)
        .env_remove("NLVID_LOG")
        .output()
        .expect("run nlvid")
}

/// Process output as text.
pub fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// `<system temp>/nlvid-<tag>-<pid>`, created (kept between tests of one run).
pub fn temp_dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("nlvid-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

/// `<cargo target tmp>/cli-<name>`, emptied and created.
pub fn scratch(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("cli-{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("scratch");
    d
}

/// A small hertz-prony build study (24 training and 6 checking runs; store
/// and export next to it), written to `dir/study.toml` (`dir` created);
/// returns the study's path.
pub fn build_study(dir: &Path) -> PathBuf {
    std::fs::create_dir_all(dir).expect("study dir");
    let p = dir.join("study.toml");
    std::fs::write(
        &p,
        r#"[forward]
model = "hertz-prony"
probe_radius = "2.5 um"
rate = "1 um/s"
ramp = "1 s"
hold = "9 s"
points = 120

[design]
n_train = 24
n_check = 6
seed = 11

[design.parameters]
G0 = { range = ["80 Pa", "4 kPa"], log = true }
g1 = { range = [0.01, 0.45] }
g2 = { range = [0.01, 0.45] }
tau1 = { range = ["0.01 s", "2 s"], log = true }
tau2 = { range = ["2 s", "40 s"], log = true }

[build]
store = "store"
export = "export"
"#,
    )
    .expect("write study");
    p
}

/// A study file read by each of the five readers that accept one (the
/// study with its lint and `[material]`, `[loading]`, a meta-model build
/// study, cohort settings, a simulate study): `Ok(())` or the reader's
/// message, for the parser robustness tests.
pub fn read_study_every_way(p: &Path) -> [Result<(), String>; 5] {
    [
        nlvid_study::Study::load(p)
            .and_then(|mut s| {
                s.lint();
                s.opt_read::<nlvid_material::MaterialSpec>("material")
                    .map(|_| ())
            })
            .map_err(|e| e.to_string()),
        nlvid_study::Study::load(p)
            .and_then(|mut s| {
                s.opt_read::<nlvid_material::LoadingSpec>("loading")
                    .map(|_| ())
            })
            .map_err(|e| e.to_string()),
        nlvid_surrogate::BuildStudy::load(p)
            .map(|_| ())
            .map_err(|e| e.to_string()),
        nlvid_report::settings::CohortSettings::load(p)
            .map(|_| ())
            .map_err(|e| e.to_string()),
        nlvid_study::Study::load(p)
            .map_err(|e| e.to_string())
            .and_then(|s| {
                nlvid_forward::SimulateStudy::from_study(s)
                    .map(|_| ())
                    .map_err(|e| e.to_string())
            }),
    ]
}
