//! Coverage of the per-cell posteriors (issue 17), on the bundled demo
//! meta-model (the FE cell model `afm-fe`, examples/demo/metamodel; its
//! coverage was measured when the demo was `hertz-prony`):
//! `cells` synthetic cells with known parameters are written by the demo's
//! curve generator (`nlvid_report::demo::write_demo_data`, the forward
//! model itself, not the surrogate) with `noise` × peak force of Gaussian
//! noise, fitted by `nlvid cohort` with `[posterior]`, and the 90 %
//! credible intervals of G0, g1 + g2 and G(52 s) are checked against the
//! truth. Prints coverage, R̂ and timings; exits non-zero when a coverage
//! is outside 85–95 % or any R̂ > 1.01.
//!
//! ```text
//! cargo run --release -p nlvid-report --example posterior_coverage \
//!     [cells] [noise] [seeds] [prior] [key=value ...]
//! ```
//! (defaults 100, 0.02, 17; `seeds` is one seed, a list `17,18` or a
//! range `17..24` (inclusive): one independent cohort per seed, each
//! reported, then the coverage pooled over them and how many cohorts lie
//! in 85–95 % on all three summaries — with several seeds the exit status
//! judges the pooled coverage; `prior` draws the cells from the posteriors'
//! prior instead of the two groups' laws (`DemoSpec::from_prior`), where a
//! credible interval's coverage is nominal by construction; `key=value` pairs go into the study's
//! `[posterior]` section, e.g. `walkers=16 max_steps=2000`, the section's
//! own defaults otherwise; see docs/theory/inverse.md, "Posteriors on the
//! surrogate"). Prints each coverage with its binomial standard error, R̂
//! max, ESS min, wall and CPU time and the load average.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use nlvid_report::cohort::{RunOptions, discover, run_cohort};
use nlvid_report::demo::write_demo_data;
use nlvid_report::settings::CohortSettings;

mod coverage_cohort;

fn main() -> ExitCode {
    match run() {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::FAILURE,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run() -> Result<bool, Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let cells: usize = args.get(1).map_or(Ok(100), |s| s.parse())?;
    let noise: f64 = args.get(2).map_or(Ok(0.02), |s| s.parse())?;
    let seeds = parse_seeds(args.get(3).map_or("17", String::as_str))?;
    let from_prior = args.iter().skip(4).any(|k| k == "prior");
    let keys: Vec<String> = args
        .iter()
        .skip(4)
        .filter(|k| *k != "prior")
        .cloned()
        .collect();
    if let Some(bad) = keys.iter().find(|k| !k.contains('=')) {
        return Err(format!("argument {bad}: expected key=value for [posterior]").into());
    }
    // NLVID_COVERAGE_DUMP=FILE: one row per cell and summary with the
    // truth and the interval, for looking at where the truths fall.
    let mut dump = match std::env::var_os("NLVID_COVERAGE_DUMP") {
        Some(path) => Some(std::fs::File::create(path)?),
        None => None,
    };
    if let Some(f) = dump.as_mut() {
        writeln!(f, "seed,cell,summary,truth,lower,median,upper,rungs")?;
    }
    let mut cohorts = Vec::new();
    for &seed in &seeds {
        let c = cohort(cells, noise, seed, from_prior, &keys, dump.as_mut())?;
        cohorts.push((seed, c));
    }
    if let [(_, one)] = cohorts.as_slice() {
        return Ok(one.within_targets());
    }
    Ok(print_pooled(&cohorts))
}

/// What one cohort gave: cells with a posterior, how many of them each
/// summary's interval covers (G0, g1 + g2, G(t_end)), cells above R̂ 1.01.
struct CohortCoverage {
    n: usize,
    cover: [usize; 3],
    unconverged: usize,
}

impl CohortCoverage {
    /// Every coverage in 85–95 % and every R̂ ≤ 1.01 (the issue's targets).
    fn within_targets(&self) -> bool {
        self.n > 0
            && self.unconverged == 0
            && self
                .cover
                .iter()
                .all(|&c| (0.85..=0.95).contains(&(c as f64 / self.n as f64)))
    }
}

/// `17`, `17,18,20` or `17..24` (inclusive).
fn parse_seeds(arg: &str) -> Result<Vec<u64>, Box<dyn std::error::Error>> {
    let seeds: Vec<u64> = match arg.split_once("..") {
        Some((a, b)) => (a.parse::<u64>()?..=b.parse::<u64>()?).collect(),
        None => arg.split(',').map(str::parse).collect::<Result<_, _>>()?,
    };
    if seeds.is_empty() {
        return Err(format!("seeds {arg}: none").into());
    }
    Ok(seeds)
}

/// One line per cohort, then the coverage pooled over all cells with its
/// binomial standard error; true when the pooled coverages lie in 85–95 %
/// and no cell is above R̂ 1.01.
fn print_pooled(cohorts: &[(u64, CohortCoverage)]) -> bool {
    println!("\ncohort   G0      g1 + g2  G(t_end)  all three in 85-95 %  cells above R-hat 1.01");
    let (mut n, mut cover, mut unconverged, mut inside) = (0, [0usize; 3], 0, 0);
    for (seed, c) in cohorts {
        let pct = |k: usize| 100.0 * c.cover[k] as f64 / c.n.max(1) as f64;
        println!(
            "seed {seed:<3} {:5.1} %  {:5.1} %  {:5.1} %    {:<20}  {}",
            pct(0),
            pct(1),
            pct(2),
            if c.within_targets() { "yes" } else { "no" },
            c.unconverged
        );
        n += c.n;
        unconverged += c.unconverged;
        inside += usize::from(c.within_targets());
        for k in 0..3 {
            cover[k] += c.cover[k];
        }
    }
    let mut ok = n > 0 && unconverged == 0;
    for (k, name) in ["G0", "g1 + g2", "G(t_end)"].iter().enumerate() {
        let frac = cover[k] as f64 / n.max(1) as f64;
        let se = (frac * (1.0 - frac) / n.max(1) as f64).sqrt();
        println!(
            "pooled over {} cohorts: the 90 % interval of {name} covers {} / {n} = {:.1} % ± {:.1} %",
            cohorts.len(),
            cover[k],
            100.0 * frac,
            100.0 * se
        );
        ok &= (0.85..=0.95).contains(&frac);
    }
    println!(
        "{inside} of {} cohorts within 85-95 % on all three; {unconverged} of {n} cells above R-hat 1.01",
        cohorts.len()
    );
    ok
}

/// Writes, fits and samples the cohort of `seed` and prints its coverage,
/// R̂, sampler counts and timings.
fn cohort(
    cells: usize,
    noise: f64,
    seed: u64,
    from_prior: bool,
    keys: &[String],
    mut dump: Option<&mut std::fs::File>,
) -> Result<CohortCoverage, Box<dyn std::error::Error>> {
    let demo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/demo");
    let demo = std::fs::canonicalize(&demo)?;
    let dir = std::env::temp_dir().join(format!("nlvid-coverage-{}-{seed}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let study = write_study(&dir, &demo, keys)?;
    let spec = nlvid_report::demo::DemoSpec {
        from_prior,
        ..coverage_cohort::wide_groups(cells, seed, noise)
    };
    let files = write_demo_data(&spec, &study, &demo.join("metamodel.toml"))?;
    let settings = CohortSettings::load(&study)?;
    let inputs = discover(&files.data)?;
    let t0 = Instant::now();
    let cpu_clock = cpu_time::ProcessTime::now();
    let run = run_cohort(
        &settings,
        &study,
        &files.data,
        &inputs,
        &dir.join("out"),
        &RunOptions::default(),
    )?;
    let seconds = t0.elapsed().as_secs_f64();
    let cpu = cpu_clock.elapsed().as_secs_f64();
    let domain = nlvid_inverse::read_meta(&demo.join("metamodel/meta.json"))?.domain;
    let (mut n, mut cover) = (0usize, [0usize; 3]);
    let mut rhat_max = 0.0f64;
    let mut rhat3_max = 0.0f64;
    let mut unconverged = 0usize;
    let mut ess_min = f64::INFINITY;
    let (mut proposals, mut tempered, mut kept) = (0usize, 0usize, Vec::new());
    let mut evaluations = 0usize;
    let (mut tempered_proposals, mut tempered_evaluations) = (0usize, 0usize);
    let mut misses = Vec::new();
    for c in &run.cells {
        let Some(p) = &c.posterior else {
            println!(
                "{} {}: no posterior ({} {})",
                c.group,
                c.cell,
                c.status.as_str(),
                c.reason
            );
            continue;
        };
        let truth = files
            .cells
            .iter()
            .find(|t| t.cell == c.cell && t.group == c.group)
            .ok_or("cell without truth")?;
        let g = nlvid_inverse::relaxation(&domain, &truth.x)?;
        let want = [g.g0(), 1.0 - g.prony().long_term_weight(), g.value(p.t_end)];
        let got = [p.g0, p.g_sum, p.g_end];
        n += 1;
        if let Some(f) = dump.as_deref_mut() {
            for k in 0..3 {
                writeln!(
                    f,
                    "{seed},{},{},{:e},{:e},{:e},{:e},{}",
                    c.cell,
                    ["G0", "g_sum", "G_end"][k],
                    want[k],
                    got[k].lower,
                    got[k].median,
                    got[k].upper,
                    p.rungs
                )?;
            }
        }
        for k in 0..3 {
            if got[k].covers(want[k]) {
                cover[k] += 1;
            } else {
                misses.push(format!(
                    "{}:{} [{:.4e}, {:.4e}] vs {:.4e}",
                    c.cell,
                    ["G0", "g_sum", "G_end"][k],
                    got[k].lower,
                    got[k].upper,
                    want[k]
                ));
            }
        }
        if p.rhat_max > 1.01 || p.rungs > 1 {
            println!(
                "  {} R-hat {:.4} ESS {:.0} acceptance {:.2} kept {} rungs {} (swaps {:.2}); truth \
                 {:?}; G0 {:?}",
                c.cell,
                p.rhat_max,
                p.ess_min,
                p.acceptance,
                p.kept_steps,
                p.rungs,
                p.swap_acceptance,
                truth.x,
                p.g0
            );
        }
        rhat_max = rhat_max.max(p.rhat_max);
        rhat3_max = rhat3_max.max(p.g0.rhat).max(p.g_sum.rhat).max(p.g_end.rhat);
        unconverged += usize::from(!(p.rhat_max <= 1.01));
        ess_min = ess_min.min(p.ess_min);
        proposals += p.proposals;
        evaluations += p.evaluations;
        tempered += usize::from(p.rungs > 1);
        if p.rungs > 1 {
            tempered_proposals += p.proposals;
            tempered_evaluations += p.evaluations;
        }
        kept.push(p.kept_steps);
    }
    kept.sort_unstable();
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    println!(
        "{n} cells with posteriors of {} ({} fitted); noise {noise} x peak; seed {seed}",
        run.cells.len(),
        run.fitted
    );
    for (k, name) in ["G0", "g1 + g2", "G(t_end)"].iter().enumerate() {
        let frac = cover[k] as f64 / n.max(1) as f64;
        let se = (frac * (1.0 - frac) / n.max(1) as f64).sqrt();
        println!(
            "coverage of the 90 % interval of {name}: {} / {n} = {:.1} % ± {:.1} % (binomial se)",
            cover[k],
            100.0 * frac,
            100.0 * se
        );
    }
    println!(
        "largest split R-hat {rhat_max:.4} over every parameter and summary ({unconverged} cells \
         above 1.01), {rhat3_max:.4} over G0, g1 + g2, G(t_end); smallest ESS {ess_min:.0}"
    );
    println!(
        "sampler: {proposals} proposals in all ({:.0} per cell), {evaluations} evaluated in full \
         ({:.1} %), {tempered} cells tempered; kept steps per walker: median {}, largest {}",
        proposals as f64 / n.max(1) as f64,
        100.0 * evaluations as f64 / proposals.max(1) as f64,
        kept.get(kept.len() / 2).copied().unwrap_or(0),
        kept.last().copied().unwrap_or(0)
    );
    println!(
        "tempered cells: {tempered_proposals} proposals ({:.1} % of all), {tempered_evaluations} \
         evaluated in full ({:.1} % of all full evaluations)",
        100.0 * tempered_proposals as f64 / proposals.max(1) as f64,
        100.0 * tempered_evaluations as f64 / evaluations.max(1) as f64
    );
    println!(
        "cohort (fit + posterior) wall time {seconds:.1} s, {:.2} s per cell on {} threads; CPU \
         {cpu:.1} s ({:.2} s per cell); load average at the end {}",
        seconds / run.cells.len().max(1) as f64,
        rayon::current_num_threads(),
        cpu / run.cells.len().max(1) as f64,
        load.trim()
    );
    for m in misses.iter().take(20) {
        println!("  miss {m}");
    }
    std::fs::remove_dir_all(&dir)?;
    Ok(CohortCoverage {
        n,
        cover,
        unconverged,
    })
}

/// The demo's cohort study with absolute meta-model paths and `[posterior]`.
fn write_study(
    dir: &Path,
    demo: &Path,
    keys: &[String],
) -> Result<PathBuf, Box<dyn std::error::Error>> {
    let posterior = format!(
        "[posterior]\nlevel = 0.9\n{}\n",
        keys.iter()
            .map(|kv| kv.replacen('=', " = ", 1))
            .collect::<Vec<_>>()
            .join("\n")
    );
    coverage_cohort::write_study(dir, demo, &posterior)
}
