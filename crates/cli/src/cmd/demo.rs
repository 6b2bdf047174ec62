//! `nlvid demo [--out DIR]`: runs cohort → compare → report on the bundled
//! synthetic study (`examples/demo`: two groups of 8 cells made by the
//! forward model from known parameters with noise, and its pre-built
//! meta-model) and prints where the report is. `--write-data` regenerates
//! the cells' curves from the study instead. See docs/cli/demo.md.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use nlvid_report::cohort;
use nlvid_report::demo::{DemoSpec, write_demo_data};
use nlvid_report::report::{ReportOptions, write_report_of};
use nlvid_report::settings::CohortSettings;

use super::{Context, Run};
use crate::say;

/// Raw arguments of `nlvid demo`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Output directory: `cohort/` (fits, results.csv, compare CSVs),
    /// `cohort/report/index.html`.
    #[arg(long, default_value = "nlvid-demo")]
    pub out: PathBuf,
    /// The bundled example (study.toml, data/, metamodel/); default
    /// `examples/demo` in the current directory, else in the source tree
    /// this binary was built from.
    #[arg(long)]
    pub demo: Option<PathBuf>,
    /// Only (re)write the demo's cell curves (data/, ground_truth.csv) with
    /// the forward model of its metamodel.toml; used by
    /// examples/demo/regenerate.sh.
    #[arg(long)]
    pub write_data: bool,
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

    fn execute(a: Args, _ctx: &Context) -> anyhow::Result<ExitCode> {
        let start = Instant::now();
        let built = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/demo"));
        let demo = nlvid_report::demo::demo_dir(a.demo, &built)?;
        let study = demo.join("study.toml");
        let data = demo.join("data");
        if a.write_data {
            let spec = DemoSpec::default();
            let files = write_demo_data(&spec, &study, &demo.join("metamodel.toml"))?;
            say!(
                "wrote {} groups × {} cells from known parameters into {} (truth: {})",
                spec.groups.len(),
                spec.cells_per_group,
                files.data.display(),
                files.truth.display()
            )?;
            return Ok(ExitCode::SUCCESS);
        }
        let settings = CohortSettings::load(&study)?;
        let cells = cohort::discover(&data)?;
        say!(
            "1. bundled study {}: {} cells made by the forward model from known parameters \
             (truth: {})",
            study.display(),
            cells.len(),
            demo.join("ground_truth.csv").display()
        )?;
        if let Some(f) = &settings.surrogate {
            say!(
                "   fitted on the pre-built meta-model {} of `{}`",
                f.model.display(),
                f.forward
            )?;
        }
        let out = a.out.join("cohort");
        say!(
            "2. nlvid cohort {} {} --out {}",
            study.display(),
            data.display(),
            out.display()
        )?;
        let run = super::cohort::run_with_progress(&settings, &study, &data, &cells, &out)?;
        crate::output::print_text(&run.text())?;
        // The results table and the report use the cells in memory.
        let table = cohort::results_table(&run.cells)?;
        let results = out.join("results.csv");
        say!("3. nlvid compare {}", results.display())?;
        let times = nlvid_protocol::grid::uniform(0.0, settings.hold_end, 53)?;
        let cmp = nlvid_report::compare::compare(&results, table, None, &times, "matlab", &out)?;
        crate::output::print_text(&cmp.text())?;
        say!("4. nlvid report {}", out.display())?;
        let page = write_report_of(&out, &run.record, &run.cells, &ReportOptions::default())?;
        say!(
            "done in {:.1} s. Report: {}",
            start.elapsed().as_secs_f64(),
            page.html.display()
        )?;
        Ok(ExitCode::SUCCESS)
    }
}
