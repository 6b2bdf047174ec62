//! The bundled example's data generator: two groups of cells whose AFM
//! ramp-hold curves are made by the study's forward model from known group
//! distributions of (G0, g1, g2, τ1, τ2) inside the Table 5.3 domain, with
//! measurement noise. Same study, spec and seed → byte-identical files.
//!
//! The meta-model's study (`examples/demo/metamodel.toml`) names the
//! forward model in its `[forward]` section; the same section drives
//! `nlvid build`, so the meta-model the cohort fits on and the curves it
//! fits are made by one model (see `examples/demo/regenerate.sh`). The
//! curves come from the curve writer `nlvid_forward::curves` (`afm-fe`: the
//! FE cell model at the sample times; `hertz-prony`: the analytic Lee–Radok
//! ramp-hold).
//!
//! Files written next to the study: `data/<group>/<cell>.csv` (`time [s]`,
//! `piezo [um]`, `deflection [nm]`; `fast_rate` Hz until `fast_until`,
//! `slow_rate` Hz after — decimated to keep the repository small) and
//! `ground_truth.csv`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use nlvid_forward::{ForwardSettings, ForwardSpec, HertzGrid, HertzPronySpec, Noise};
use nlvid_model::Domain;
use nlvid_study::Study;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::cohort::write_atomic;
use crate::error::{ReportError, Result};
use crate::settings::CohortSettings;

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
    /// g2: mean and sd.
    pub g2: (f64, f64),
    /// τ1: median (s) and sd of ln τ1.
    pub tau1: (f64, f64),
    /// τ2: median (s) and sd of ln τ2.
    pub tau2: (f64, f64),
}

impl GroupSpec {
    /// Draws a cell of this group inside the Table 5.3 domain (redraws
    /// otherwise), 2 % (scaled) inside every bound. The normal deviates are
    /// drawn in the order G0, g1, τ1, g2, τ2 (that of the committed demo
    /// data) and returned in the parameter order G0, g1, g2, τ1, τ2.
    ///
    /// # Errors
    /// A law that rarely falls inside the domain (1000 draws tried).
    pub fn draw(&self, domain: &Domain, rng: &mut ChaCha8Rng) -> Result<[f64; 5]> {
        for _ in 0..1000 {
            let g0 = self.g0.0 * (self.g0.1 * normal(rng)).exp();
            let g1 = self.g1.0 + self.g1.1 * normal(rng);
            let tau1 = self.tau1.0 * (self.tau1.1 * normal(rng)).exp();
            let g2 = self.g2.0 + self.g2.1 * normal(rng);
            let tau2 = self.tau2.0 * (self.tau2.1 * normal(rng)).exp();
            let x = [g0, g1, g2, tau1, tau2];
            // Stay 2 % (scaled) inside the bounds: a truth on a bound is a
            // different test.
            let u = domain.to_unit(&x);
            if u.iter().all(|u| (0.02..=0.98).contains(u)) && domain.contains(&x, 0.0) {
                return Ok(x);
            }
        }
        Err(ReportError::InvalidSetting(format!(
            "group `{}`: its distribution rarely falls inside the Table 5.3 domain",
            self.name
        )))
    }
}

/// The synthetic cells (the study file holds probe, cantilever, protocol
/// and forward model).
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
    /// Sampling rate until `fast_until`, Hz.
    pub fast_rate: f64,
    /// End of the fast sampling, s.
    pub fast_until: f64,
    /// Sampling rate after `fast_until`, Hz.
    pub slow_rate: f64,
    /// Draw every cell from the posteriors' prior — uniform on the Table 5.3
    /// domain in its own coordinates (log-uniform on log axes), with its
    /// linear constraint — instead of from its group's law (the groups
    /// then only name folders): the cohort on which a credible interval's
    /// coverage is nominal by construction.
    pub from_prior: bool,
}

impl Default for DemoSpec {
    /// Two groups of 8 cells: `A-stiff` (G0 ≈ 2 kPa, relaxes ≈ 55 % by
    /// 52 s) and `B-soft` (G0 ≈ 0.9 kPa, ≈ 75 %), the direction of the
    /// benign vs malignant contrast of §5.4.2; 1 % force noise; 100 Hz for
    /// the first 2 s, then 10 Hz.
    fn default() -> Self {
        Self {
            groups: vec![
                GroupSpec {
                    name: "A-stiff".into(),
                    g0: (2000.0, 0.2),
                    g1: (0.30, 0.04),
                    g2: (0.25, 0.04),
                    tau1: (0.6, 0.3),
                    tau2: (10.0, 0.2),
                },
                GroupSpec {
                    name: "B-soft".into(),
                    g0: (900.0, 0.2),
                    g1: (0.40, 0.04),
                    g2: (0.35, 0.04),
                    tau1: (0.6, 0.3),
                    tau2: (10.0, 0.2),
                },
            ],
            cells_per_group: 8,
            seed: 20261122,
            noise: 0.01,
            fast_rate: 100.0,
            fast_until: 2.0,
            slow_rate: 10.0,
            from_prior: false,
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
    /// (G0, g1, g2, τ1, τ2), SI (`nlvid_model::names::PRONY2`).
    pub x: [f64; 5],
}

/// What [`write_demo_data`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct DemoFiles {
    /// The study file (read, not written).
    pub study: PathBuf,
    /// The data folder (one sub-folder per group).
    pub data: PathBuf,
    /// The ground-truth table.
    pub truth: PathBuf,
    /// The true parameters.
    pub cells: Vec<TrueCell>,
}

impl DemoFiles {
    /// One line on what was written for `spec` (`nlvid demo --write-data`).
    pub fn text(&self, spec: &DemoSpec) -> String {
        format!(
            "wrote {} groups × {} cells from known parameters into {} (truth: {})\n",
            spec.groups.len(),
            spec.cells_per_group,
            self.data.display(),
            self.truth.display()
        )
    }
}

fn normal(rng: &mut ChaCha8Rng) -> f64 {
    nlvid_forward::curves::standard_normal(rng)
}

/// Draws a cell of `g` ([`GroupSpec::draw`]). With `from_prior` (the [`DemoSpec`] field) the cell is drawn from the
/// prior instead: u uniform in [0.02, 0.98]^5, redrawn until inside the
/// domain's constraints.
fn draw(
    g: &GroupSpec,
    from_prior: bool,
    domain: &Domain,
    rng: &mut ChaCha8Rng,
) -> Result<[f64; 5]> {
    if from_prior {
        for _ in 0..1000 {
            let u: Vec<f64> = (0..5).map(|_| 0.02 + 0.96 * rng.random::<f64>()).collect();
            let x = domain.from_unit(&u);
            if domain.contains(&x, 0.0) {
                return Ok([x[0], x[1], x[2], x[3], x[4]]);
            }
        }
        return Err(ReportError::InvalidSetting(
            "the prior's constraints leave almost no room in the Table 5.3 domain".into(),
        ));
    }
    g.draw(domain, rng)
}

/// The `[forward]` section of the study at `path`, read by
/// `nlvid_forward` (the reader `nlvid build` uses), with its probe radius,
/// loading ramp and protocol end [m, s, s].
///
/// # Errors
/// A missing section or key (naming file, line, key), or a model the curve
/// writer cannot drive (membrane).
fn load_forward(path: &Path) -> Result<(ForwardSettings, f64, f64, f64)> {
    let mut study = Study::load(path)?;
    let fwd = ForwardSettings::from_study(&mut study)
        .map_err(|e| ReportError::InvalidSetting(e.to_string()))?;
    let bad = |e: nlvid_forward::ForwardError| ReportError::InvalidSetting(e.to_string());
    let (radius, ramp, end) = match &fwd.spec {
        ForwardSpec::HertzProny(h) => (h.probe_radius, h.ramp, h.ramp + h.hold),
        ForwardSpec::AfmFe(a) => {
            // The loading ramp is the piezo program's first segment.
            let piezo = a.setup().map_err(bad)?.piezo;
            let ramp = piezo.get(1).map_or(0.0, |p| p.0);
            let end = piezo.last().map_or(0.0, |p| p.0);
            (a.probe_radius, ramp, end)
        }
        ForwardSpec::Membrane(_) | ForwardSpec::CapsuleFe(_) => {
            return Err(ReportError::InvalidSetting(format!(
                "{}: [forward] {}: the demo data generator writes AFM curves \
                 (afm-fe, hertz-prony)",
                path.display(),
                fwd.spec.name()
            )));
        }
    };
    Ok((fwd, radius, ramp, end))
}

/// Sample times of a cell's file (a subset of the fine model grid of
/// spacing 1/`fast_rate`): every point until `fast_until`, then every
/// `fast_rate/slow_rate`-th. Returns the fine grid size and the kept indices.
fn sampling(spec: &DemoSpec, t_end: f64) -> Result<(usize, Vec<usize>)> {
    let n = (t_end * spec.fast_rate).round() as usize;
    let step = (spec.fast_rate / spec.slow_rate).round() as usize;
    if n < 2 || step < 1 {
        return Err(ReportError::InvalidSetting(format!(
            "demo sampling: {} Hz over {t_end} s, then {} Hz",
            spec.fast_rate, spec.slow_rate
        )));
    }
    let fast = (spec.fast_until * spec.fast_rate).round() as usize;
    // Index i is time (i + 1)/fast_rate.
    let keep = (0..n)
        .filter(|&i| i < fast || (i + 1) % step == 0 || i + 1 == n)
        .collect();
    Ok((n, keep))
}

/// Writes `data/` and `ground_truth.csv` next to the cohort study `study`
/// (cantilever, columns, fitted window) with the forward model of the
/// `[forward]` section of `forward` (the meta-model's study,
/// `metamodel.toml` in the demo).
///
/// # Errors
/// An unreadable study, a forward model the generator cannot drive, a
/// group distribution outside the domain, an unwritable directory.
pub fn write_demo_data(spec: &DemoSpec, study: &Path, forward: &Path) -> Result<DemoFiles> {
    let settings = CohortSettings::load(study)?;
    let (fwd, probe_radius, ramp, t_end) = load_forward(forward)?;
    if (settings.radius / probe_radius - 1.0).abs() > 1e-12 {
        return Err(ReportError::InvalidSetting(format!(
            "{}: probe.radius = {} m but {} has forward.probe_radius = {} m",
            study.display(),
            settings.radius,
            forward.display(),
            probe_radius
        )));
    }
    let dir = study.parent().map(Path::to_path_buf).unwrap_or_default();
    let domain = Domain::table_5_3(settings.constraint_epsilon)?;
    if (settings.ramp - ramp).abs() > 1e-9 * ramp || settings.hold_end > t_end * (1.0 + 1e-12) {
        return Err(ReportError::InvalidSetting(format!(
            "{}: the fitted window (ramp {} s, hold_end {} s) must match the forward model's \
             ramp ({ramp} s) and end within its protocol ({t_end} s)",
            study.display(),
            settings.ramp,
            settings.hold_end,
        )));
    }
    let (fine, keep) = sampling(spec, t_end)?;
    // Sample times: 0, then the kept points of the fine grid
    // (i + 1)/fast_rate; hertz-prony runs on that fine grid.
    let fwd = match fwd.spec {
        ForwardSpec::HertzProny(h) => ForwardSettings {
            spec: ForwardSpec::HertzProny(HertzPronySpec {
                points: fine,
                grid: HertzGrid::Uniform,
                ..h
            }),
            ..fwd
        },
        _ => fwd,
    };
    let model = fwd
        .build()
        .map_err(|e| ReportError::InvalidSetting(format!("forward model: {e}")))?;
    domain
        .check_names(&model.parameter_names())
        .map_err(|e| ReportError::InvalidSetting(format!("forward model: {e}")))?;
    let times: Vec<f64> = std::iter::once(0.0)
        .chain(keep.iter().map(|&j| t_end * (j + 1) as f64 / fine as f64))
        .collect();
    let k = settings.spring_constant.ok_or_else(|| {
        ReportError::InvalidSetting(
            "the demo writes CSV curves: its study needs [fit.calibration] spring_constant".into(),
        )
    })?;
    // One seeded stream, cell by cell: the parameters, then the noise of
    // every sample (the order of the committed demo data). The parameters
    // are drawn first (skipping the noise deviates) so that the noise-free
    // curves can run in parallel; the stream is then replayed.
    let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
    let mut cells = Vec::new();
    for g in &spec.groups {
        for i in 0..spec.cells_per_group {
            let x = draw(g, spec.from_prior, &domain, &mut rng)?;
            for _ in &times {
                normal(&mut rng);
            }
            cells.push(TrueCell {
                group: g.name.clone(),
                cell: format!("{}-{:02}", g.name.to_lowercase(), i + 1),
                x,
            });
        }
    }
    let sets: Vec<Vec<f64>> = cells.iter().map(|c| c.x.to_vec()).collect();
    let clean = Noise {
        relative: 0.0,
        seed: spec.seed,
    };
    let mut curves = nlvid_forward::afm_curves(&fwd, &sets, &times, k, clean)
        .map_err(|e| ReportError::InvalidSetting(format!("forward model: {e}")))?;
    let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
    for (g, curve) in spec
        .groups
        .iter()
        .flat_map(|g| std::iter::repeat_n(g, spec.cells_per_group))
        .zip(&mut curves)
    {
        draw(g, spec.from_prior, &domain, &mut rng)?;
        nlvid_forward::curves::add_noise_from(curve, spec.noise, &mut rng, k)
            .map_err(|e| ReportError::InvalidSetting(format!("forward model: {e}")))?;
    }
    let data = dir.join("data");
    let mut truth = String::from("group,cell,G0_Pa,g1,g2,tau1_s,tau2_s,G_end_Pa,relaxation_end\n");
    for (c, curve) in cells.iter().zip(&curves) {
        write_atomic(
            &data.join(&c.group).join(format!("{}.csv", c.cell)),
            nlvid_forward::measured_csv(curve).as_bytes(),
        )?;
        let x = c.x;
        // G(t) of eq. 5.1 through the one Prony type, by parameter name.
        let g_end = nlvid_inverse::relaxation(&domain, &x)?.value(settings.hold_end);
        let _ = writeln!(
            truth,
            "{},{},{},{},{},{},{},{},{}",
            c.group,
            c.cell,
            x[0],
            x[1],
            x[2],
            x[3],
            x[4],
            g_end,
            1.0 - g_end / x[0]
        );
    }
    let truth_path = dir.join("ground_truth.csv");
    write_atomic(&truth_path, truth.as_bytes())?;
    Ok(DemoFiles {
        study: study.to_path_buf(),
        data,
        truth: truth_path,
        cells,
    })
}

/// The bundled example: `given`, else `examples/demo` in the current
/// directory, else what `fallback` provides (the binary's embedded copy,
/// written out; `crates/cli/src/embedded_demo.rs`).
///
/// # Errors
/// `fallback`'s error.
pub fn demo_dir(
    given: Option<PathBuf>,
    fallback: impl FnOnce() -> Result<PathBuf>,
) -> Result<PathBuf> {
    if let Some(d) = given {
        return Ok(d);
    }
    let here = PathBuf::from("examples/demo");
    if here.join("study.toml").is_file() {
        return Ok(here);
    }
    fallback()
}

/// Runs the bundled example in `demo` end to end into `out`: `nlvid cohort`
/// (into `out/cohort`, `on_cell` after each cell), `nlvid compare` on the
/// cells in memory, `nlvid report`; each step and its outcome are handed to
/// `say` as text. Returns the report's files.
///
/// # Errors
/// A bad bundled study, unwritable outputs, or `say` failing.
pub fn run_demo(
    demo: &Path,
    out: &Path,
    on_cell: Option<&(dyn Fn(&crate::cell::CellResult) + Sync)>,
    say: &mut dyn FnMut(&str) -> std::io::Result<()>,
) -> Result<crate::report::ReportFiles> {
    let io = ReportError::Output;
    let (study, data) = (demo.join("study.toml"), demo.join("data"));
    let settings = CohortSettings::load(&study)?;
    let cells = crate::cohort::discover(&data)?;
    let mut text = format!(
        "1. bundled study {}: {} cells made by the forward model from known parameters \
         (truth: {})\n",
        study.display(),
        cells.len(),
        demo.join("ground_truth.csv").display()
    );
    if let Some(f) = &settings.surrogate {
        let _ = writeln!(
            text,
            "   fitted on the pre-built meta-model {} of `{}` (its full identity: `model` in {})",
            f.model.display(),
            f.forward_name(),
            f.meta.display()
        );
    }
    let cohort_dir = out.join("cohort");
    let _ = writeln!(
        text,
        "2. nlvid cohort {} {} --out {}",
        study.display(),
        data.display(),
        cohort_dir.display()
    );
    say(&text).map_err(io)?;
    let opts = crate::cohort::RunOptions {
        max_new_fits: None,
        on_cell,
    };
    let run = crate::cohort::run_cohort(&settings, &study, &data, &cells, &cohort_dir, &opts)?;
    // The results table and the report use the cells in memory.
    let table = crate::cohort::results_table(&run.cells)?;
    let results = cohort_dir.join("results.csv");
    say(&format!(
        "{}3. nlvid compare {}\n",
        run.text(),
        results.display()
    ))
    .map_err(io)?;
    let times: Vec<f64> = (0..53)
        .map(|i| settings.hold_end * i as f64 / 52.0)
        .collect();
    let cmp = crate::compare::compare(&results, table, None, &times, "matlab", &cohort_dir)?;
    say(&format!(
        "{}4. nlvid report {}\n",
        cmp.text(),
        cohort_dir.display()
    ))
    .map_err(io)?;
    let opts = crate::report::ReportOptions::default();
    crate::report::write_report_of(&cohort_dir, &run.record, &run.cells, &opts)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Cells drawn from the prior fill the domain in its own coordinates:
    /// every u inside [0.02, 0.98], g1 + g2 within the constraint, each
    /// axis's mean near ½ and its range near the margins (2000 draws;
    /// uniform on a box cut by g1 + g2 ≤ 0.99 keeps G0, τ1, τ2 uniform);
    /// the group's own law is not used.
    #[test]
    fn cells_from_the_prior_are_uniform_on_the_domain() {
        let domain = Domain::table_5_3(0.01).unwrap();
        let group = DemoSpec::default().groups[0].clone();
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let n = 2000;
        let us: Vec<Vec<f64>> = (0..n)
            .map(|_| domain.to_unit(&draw(&group, true, &domain, &mut rng).unwrap()))
            .collect();
        for u in &us {
            assert!(u.iter().all(|u| (0.02..=0.98).contains(u)), "{u:?}");
            assert!(domain.contains(&domain.from_unit(u), 0.0), "{u:?}");
        }
        for axis in [0, 3, 4] {
            let mean = us.iter().map(|u| u[axis]).sum::<f64>() / n as f64;
            // sd of the mean of U(0.02, 0.98): 0.96/√(12 n) = 0.0062.
            assert!((mean - 0.5).abs() < 0.025, "axis {axis}: mean {mean}");
            let lo = us.iter().map(|u| u[axis]).fold(1.0, f64::min);
            let hi = us.iter().map(|u| u[axis]).fold(0.0, f64::max);
            assert!(lo < 0.03 && hi > 0.97, "axis {axis}: [{lo}, {hi}]");
        }
    }

    #[test]
    fn sampling_keeps_every_fast_sample_then_every_tenth() {
        let spec = DemoSpec::default();
        let (n, keep) = sampling(&spec, 52.0).unwrap();
        assert_eq!(n, 5200);
        // 200 samples in (0, 2] s, then 10 Hz to 52 s: 500 more.
        assert_eq!(keep.len(), 200 + 500);
        assert_eq!(*keep.last().unwrap(), 5199);
        assert_eq!(keep[199], 199);
        assert_eq!(keep[200], 209);
    }
}
