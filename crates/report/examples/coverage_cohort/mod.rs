//! The synthetic cohort both posterior examples (`posterior_coverage`,
//! `posterior_diagnose`) draw their cells from: two broad groups spanning
//! much of the Table 5.3 domain, so the coverage study sees well- and
//! badly-determined cells alike.

use std::path::{Path, PathBuf};

use nlvid_report::demo::{DemoSpec, GroupSpec};

/// `cells` cells in two groups (rounded up to an even count), seeded,
/// with relative noise `noise` (0 for noise-free curves).
pub fn wide_groups(cells: usize, seed: u64, noise: f64) -> DemoSpec {
    DemoSpec {
        groups: vec![
            GroupSpec {
                name: "wide-a".into(),
                g0: (1500.0, 0.5),
                g1: (0.30, 0.12),
                g2: (0.30, 0.12),
                tau1: (0.3, 0.7),
                tau2: (10.0, 0.4),
            },
            GroupSpec {
                name: "wide-b".into(),
                g0: (600.0, 0.5),
                g1: (0.40, 0.12),
                g2: (0.25, 0.12),
                tau1: (0.6, 0.7),
                tau2: (8.0, 0.4),
            },
        ],
        cells_per_group: cells.div_ceil(2),
        seed,
        noise,
        ..DemoSpec::default()
    }
}

/// The demo's cohort study in `dir` with absolute meta-model paths, and
/// `extra` (e.g. a `[posterior]` section) appended when not empty.
#[allow(dead_code)] // `posterior_sbc` uses the groups only
pub fn write_study(
    dir: &Path,
    demo: &Path,
    extra: &str,
) -> Result<PathBuf, Box<dyn std::error::Error>> {
    std::fs::create_dir_all(dir)?;
    let text = std::fs::read_to_string(demo.join("study.toml"))?;
    let mm = demo.join("metamodel");
    let text = text.replace("\"metamodel/", &format!("\"{}/", mm.display()));
    let text = if extra.is_empty() {
        text
    } else {
        format!("{text}\n{extra}")
    };
    let study = dir.join("study.toml");
    std::fs::write(&study, text)?;
    Ok(study)
}
