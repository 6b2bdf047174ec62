//! One `[fit]` schema for `nlvid fit` and `nlvid cohort`: the same study
//! file is accepted by both or refused by both, and `[fit.protocol]` is
//! read the same way (optional in both; checked where given).
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests

use std::path::PathBuf;

use nlvid_report::settings::{CohortSettings, FitSettings, Protocol, ProtocolKind};

const LEE_RADOK: &str = r#"title = "schema"
[probe]
radius = "2.5 um"
[fit]
model = "lee-radok"
ramp = "1 s"
hold_end = "52 s"
[fit.calibration]
spring_constant = "0.12 N/m"
"#;

const SURROGATE: &str = r#"title = "schema"
[probe]
radius = "2.5 um"
[fit]
model = "surrogate"
surrogate = "model.json"
meta = "meta.json"
ramp = "1 s"
hold_end = "52 s"
[fit.calibration]
spring_constant = "0.12 N/m"
"#;

const PROTOCOL: &str = "[fit.protocol]\nrate = \"2.16 um/s\"\namplitude = \"2.16 um\"\n";

/// Writes `text` as a study next to dummy meta-model files; returns its path.
fn study(name: &str, text: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("nlvid-fit-protocol-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("model.json"), "{}").unwrap();
    std::fs::write(dir.join("meta.json"), r#"{"model": "hertz-prony"}"#).unwrap();
    let path = dir.join("study.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// The protocol each command read, or both errors' text.
fn both(name: &str, text: &str) -> Result<(Option<Protocol>, Option<Protocol>), (String, String)> {
    let path = study(name, text);
    let fit = FitSettings::load(&path);
    let cohort = CohortSettings::load(&path);
    match (fit, cohort) {
        (Ok(f), Ok(c)) => {
            assert_eq!(f.experiments.len(), 1);
            Ok((f.experiments[0].protocol, c.protocol))
        }
        (Err(f), Err(c)) => Err((f.to_string(), c.to_string())),
        (f, c) => panic!("{name}: fit {:?} but cohort {:?}", f.err(), c.err()),
    }
}

#[test]
fn both_commands_read_the_protocol_alike() {
    let expected = Protocol {
        kind: ProtocolKind::RampHold,
        rate: 2.16e-6,
        amplitude: 2.16e-6,
        tolerance: nlvid_inverse::ProtocolTolerance::default(),
    };
    for (name, base) in [("lee-radok", LEE_RADOK), ("surrogate", SURROGATE)] {
        let (f, c) = both(name, &format!("{base}{PROTOCOL}")).expect("accepted by both");
        let (f, c) = (f.expect("fit protocol"), c.expect("cohort protocol"));
        assert!(
            (f.rate - expected.rate).abs() < 1e-18
                && (f.amplitude - expected.amplitude).abs() < 1e-18
        );
        assert_eq!(f.tolerance, expected.tolerance);
        assert_eq!(f, c, "{name}");
    }
    // Optional with the analytic model: absent in both.
    assert_eq!(
        both("lee-radok-none", LEE_RADOK).expect("accepted"),
        (None, None)
    );
}

#[test]
fn both_commands_refuse_the_same_protocol_errors() {
    // An unknown key, a missing key, a non-positive rate.
    for (name, section) in [
        (
            "typo",
            "[fit.protocol]\nrates = \"2 um/s\"\namplitude = \"2 um\"\n",
        ),
        ("no-amplitude", "[fit.protocol]\nrate = \"2 um/s\"\n"),
        (
            "negative",
            "[fit.protocol]\nrate = \"-2 um/s\"\namplitude = \"2 um\"\n",
        ),
    ] {
        let (f, c) = both(name, &format!("{LEE_RADOK}{section}")).expect_err(name);
        for e in [&f, &c] {
            assert!(e.contains("fit.protocol"), "{name}: {e}");
        }
    }
}
