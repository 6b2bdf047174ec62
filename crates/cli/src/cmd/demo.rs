//! `nlvid demo [--out DIR]`: writes the bundled synthetic study (two groups
//! of 8 cells, known parameters, noise), then runs cohort → compare →
//! report on it and prints where the report is. See docs/cli/demo.md.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use nlvid_report::cohort;
use nlvid_report::demo::{DemoSpec, write_demo};
use nlvid_report::report::{ReportOptions, write_report};
use nlvid_report::settings::CohortSettings;

use super::{Context, Run};

/// Raw arguments of `nlvid demo`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Output directory: `study/` (the synthetic study), `cohort/` (fits,
    /// results.csv, compare CSVs), `cohort/report/index.html`.
    #[arg(long, default_value = "nlvid-demo")]
    pub out: PathBuf,
    /// Only write the synthetic study (study.toml, data/, ground_truth.csv)
    /// into --out; this is how examples/demo/ is made.
    #[arg(long)]
    pub study_only: bool,
}

impl Run for Args {
    type Config = Args;

    fn validate(self, ctx: &Context) -> anyhow::Result<Args> {
        if ctx.json {
            anyhow::bail!(
                "`nlvid demo` prints a walk-through; use --json with cohort, compare or report"
            );
        }
        Ok(self)
    }

    fn execute(a: Args, ctx: &Context) -> anyhow::Result<ExitCode> {
        let start = Instant::now();
        let spec = DemoSpec::default();
        let study_dir = if a.study_only {
            a.out.clone()
        } else {
            a.out.join("study")
        };
        let files = write_demo(&spec, &study_dir)?;
        println!(
            "1. synthetic study: {} groups × {} cells from known parameters (truth: {})",
            spec.groups.len(),
            spec.cells_per_group,
            files.truth.display()
        );
        if a.study_only {
            println!("wrote {}", study_dir.display());
            return Ok(ExitCode::SUCCESS);
        }
        let settings = CohortSettings::load(&files.study)?;
        let cells = cohort::discover(&files.data)?;
        let out = a.out.join("cohort");
        println!(
            "2. nlvid cohort {} {} --out {}",
            files.study.display(),
            files.data.display(),
            out.display()
        );
        let run =
            super::cohort::run_with_progress(&settings, &files.study, &files.data, &cells, &out)?;
        super::cohort::print_outcome(&settings, &out, &run, false)?;
        let results = out.join("results.csv");
        println!("3. nlvid compare {}", results.display());
        super::compare::Args {
            results,
            groups: None,
            t_end: settings.hold_end,
            points: 53,
            method: "matlab".into(),
            out_dir: None,
        }
        .run(ctx)?;
        println!("4. nlvid report {}", out.display());
        let page = write_report(&out, &ReportOptions::default())?;
        println!(
            "done in {:.1} s. Report: {}",
            start.elapsed().as_secs_f64(),
            page.html.display()
        );
        Ok(ExitCode::SUCCESS)
    }
}
