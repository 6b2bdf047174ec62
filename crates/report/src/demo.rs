//! The bundled example: a seeded synthetic study of two groups of cells
//! whose AFM ramp-hold curves are made by the forward model from known
//! group distributions of (G0, g1, τ1, g2, τ2) inside the Table 5.3 domain,
//! with measurement noise. Same spec and seed → byte-identical files.
//!
//! Forward model: small-strain Lee–Radok (linear-viscoelastic Hertz,
//! rigid sphere, eq. 1.1 generalised with eq. 5.1); the FE model replaces
//! it when it lands.
//!
//! Files: `study.toml`, `data/<group>/<cell>.csv` (`time [s]`,
//! `piezo [um]`, `deflection [nm]`; 250 Hz for the first 2 s, 10 Hz after —
//! decimated to keep the repository small), `ground_truth.csv`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use nlvid_inverse::{Domain, LeeRadokHertz, Model};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::cohort::write_atomic;
use crate::error::{ReportError, Result};

/// A group's parameter distribution: G0 and τ's log-normal (median,
/// sd of ln), g's normal (mean, sd).
#[derive(Debug, Clone, PartialEq)]
pub struct GroupSpec {
    /// Group name (a folder name).
    pub name: String,
    /// G0: median (Pa) and sd of ln G0.
    pub g0: (f64, f64),
    /// g1: mean and sd.
    pub g1: (f64, f64),
    /// τ1: median (s) and sd of ln τ1.
    pub tau1: (f64, f64),
    /// g2: mean and sd.
    pub g2: (f64, f64),
    /// τ2: median (s) and sd of ln τ2.
    pub tau2: (f64, f64),
}

/// The synthetic study.
#[derive(Debug, Clone, PartialEq)]
pub struct DemoSpec {
    /// Groups.
    pub groups: Vec<GroupSpec>,
    /// Cells per group.
    pub cells_per_group: usize,
    /// Seed of parameters and noise.
    pub seed: u64,
    /// Noise sd as a fraction of each cell's peak force (on the deflection).
    pub noise: f64,
    /// Sphere radius, m.
    pub radius: f64,
    /// Cantilever k, N/m.
    pub spring_constant: f64,
    /// Indentation depth, m.
    pub depth: f64,
    /// Indentation rate, m/s.
    pub rate: f64,
    /// End of the hold, s.
    pub hold_end: f64,
    /// Multistart starts written into the study.
    pub starts: usize,
}

impl Default for DemoSpec {
    /// Two groups of 8 cells: `A-stiff` (G0 ≈ 2 kPa, relaxes ≈ 55 % by
    /// 52 s) and `B-soft` (G0 ≈ 0.9 kPa, ≈ 75 %), the direction of the
    /// benign vs malignant contrast of §5.4.2; 1 % force noise.
    fn default() -> Self {
        Self {
            groups: vec![
                GroupSpec {
                    name: "A-stiff".into(),
                    g0: (2000.0, 0.2),
                    g1: (0.30, 0.04),
                    tau1: (0.3, 0.3),
                    g2: (0.25, 0.04),
                    tau2: (10.0, 0.2),
                },
                GroupSpec {
                    name: "B-soft".into(),
                    g0: (900.0, 0.2),
                    g1: (0.40, 0.04),
                    tau1: (0.3, 0.3),
                    g2: (0.35, 0.04),
                    tau2: (10.0, 0.2),
                },
            ],
            cells_per_group: 8,
            seed: 20261122,
            noise: 0.01,
            radius: 2.5e-6,
            spring_constant: 0.12,
            depth: 2e-6,
            rate: 10e-6,
            hold_end: 52.0,
            starts: 8,
        }
    }
}

/// A generated cell's true parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct TrueCell {
    /// Group.
    pub group: String,
    /// Cell name (file stem).
    pub cell: String,
    /// (G0, g1, τ1, g2, τ2), SI.
    pub x: [f64; 5],
}

/// What [`write_demo`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct DemoFiles {
    /// The study file.
    pub study: PathBuf,
    /// The data folder (one sub-folder per group).
    pub data: PathBuf,
    /// The ground-truth table.
    pub truth: PathBuf,
    /// The true parameters.
    pub cells: Vec<TrueCell>,
}

fn normal(rng: &mut ChaCha8Rng) -> f64 {
    // Box–Muller; u1 in (0, 1].
    let u1: f64 = 1.0 - rng.random::<f64>();
    let u2: f64 = rng.random();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// Draws a cell of `g` inside the Table 5.3 domain (redraws otherwise).
fn draw(g: &GroupSpec, domain: &Domain, rng: &mut ChaCha8Rng) -> Result<[f64; 5]> {
    for _ in 0..1000 {
        let x = [
            g.g0.0 * (g.g0.1 * normal(rng)).exp(),
            g.g1.0 + g.g1.1 * normal(rng),
            g.tau1.0 * (g.tau1.1 * normal(rng)).exp(),
            g.g2.0 + g.g2.1 * normal(rng),
            g.tau2.0 * (g.tau2.1 * normal(rng)).exp(),
        ];
        // Stay 2 % (scaled) inside the bounds: a truth on a bound is a
        // different test.
        let u = domain.to_unit(&x);
        if u.iter().all(|u| (0.02..=0.98).contains(u)) && domain.contains(&x, 0.0) {
            return Ok(x);
        }
    }
    Err(ReportError::InvalidSetting(format!(
        "group `{}`: its distribution rarely falls inside the Table 5.3 domain",
        g.name
    )))
}

/// Sample times: 250 Hz to 2 s, then 10 Hz to the end of the hold.
pub fn sample_times(hold_end: f64) -> Vec<f64> {
    let mut t: Vec<f64> = (0..500).map(|i| i as f64 / 250.0).collect();
    let n = ((hold_end - 2.0) * 10.0).round() as usize;
    t.extend((0..=n).map(|i| 2.0 + i as f64 / 10.0));
    t
}

/// The study file text of a demo.
pub fn study_toml(spec: &DemoSpec) -> String {
    format!(
        "# Synthetic demo study written by `nlvid demo` (crate nlvid-report, demo.rs).\n\
         # Forward model: small-strain Lee–Radok; the FE model replaces it when it lands.\n\
         title = \"nlvid demo: two synthetic groups of {n} cells\"\n\
         seed = 1\n\n\
         [probe]\nradius = \"{r} um\"\npoisson = 0.5\n\n\
         [afm]\nspring_constant = \"{k} N/m\"\ntime_column = \"time\"\n\
         piezo_column = \"piezo\"\ndeflection_column = \"deflection\"\n\n\
         [protocol]\nramp = \"{ramp} s\"\nhold_end = \"{end} s\"\n\n\
         [fit]\nmodel = \"lee-radok\"\nstarts = {starts}\nramp_points = 40\nhold_points = 120\n\
         first_hold_step = \"1 ms\"\nconstraint_epsilon = 0.01\nsuspicious_misfit = 0.05\n",
        n = spec.cells_per_group,
        r = spec.radius * 1e6,
        k = spec.spring_constant,
        // Rounded to 1 ns so the study file reads `0.2 s`, not `0.19999999999999998 s`.
        ramp = (spec.depth / spec.rate * 1e9).round() / 1e9,
        end = spec.hold_end,
        starts = spec.starts,
    )
}

/// Writes the demo study into `dir` (created).
///
/// # Errors
/// Unwritable directory; a group distribution outside the domain.
pub fn write_demo(spec: &DemoSpec, dir: &Path) -> Result<DemoFiles> {
    let domain = Domain::prony2_table_5_3(0.01)?;
    let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
    let t = sample_times(spec.hold_end);
    let delta: Vec<f64> = t.iter().map(|&s| (spec.rate * s).min(spec.depth)).collect();
    let model = LeeRadokHertz::new(domain.clone(), t.clone(), &delta, spec.radius, 0.5)?;
    let data = dir.join("data");
    let mut cells = Vec::new();
    let mut truth = String::from("group,cell,G0_Pa,g1,tau1_s,g2,tau2_s,G_end_Pa,relaxation_end\n");
    for g in &spec.groups {
        for i in 0..spec.cells_per_group {
            let x = draw(g, &domain, &mut rng)?;
            let f = model.response(&x)?;
            let peak = f.iter().fold(0.0f64, |a, &b| a.max(b));
            let mut csv = String::from("time [s],piezo [um],deflection [nm]\n");
            for ((tj, dj), fj) in t.iter().zip(&delta).zip(&f) {
                let d_true = fj / spec.spring_constant;
                let z = dj + d_true;
                let d_meas = (fj + spec.noise * peak * normal(&mut rng)) / spec.spring_constant;
                let _ = writeln!(csv, "{tj:.4},{:.6},{:.4}", z * 1e6, d_meas * 1e9);
            }
            let cell = format!("{}-{:02}", g.name.to_lowercase(), i + 1);
            write_atomic(
                &data.join(&g.name).join(format!("{cell}.csv")),
                csv.as_bytes(),
            )?;
            let ginf = 1.0 - x[1] - x[3];
            let g_end = x[0]
                * (ginf
                    + x[1] * (-spec.hold_end / x[2]).exp()
                    + x[3] * (-spec.hold_end / x[4]).exp());
            let _ = writeln!(
                truth,
                "{},{cell},{},{},{},{},{},{},{}",
                g.name,
                x[0],
                x[1],
                x[2],
                x[3],
                x[4],
                g_end,
                1.0 - g_end / x[0]
            );
            cells.push(TrueCell {
                group: g.name.clone(),
                cell,
                x,
            });
        }
    }
    let study = dir.join("study.toml");
    write_atomic(&study, study_toml(spec).as_bytes())?;
    let truth_path = dir.join("ground_truth.csv");
    write_atomic(&truth_path, truth.as_bytes())?;
    Ok(DemoFiles {
        study,
        data,
        truth: truth_path,
        cells,
    })
}
