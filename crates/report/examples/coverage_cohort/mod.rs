//! The synthetic cohort both posterior examples (`posterior_coverage`,
//! `posterior_diagnose`) draw their cells from: two broad groups spanning
//! much of the Table 5.3 domain, so the coverage study sees well- and
//! badly-determined cells alike.

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
