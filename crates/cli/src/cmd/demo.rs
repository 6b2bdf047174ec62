//! `nlvid demo [--out DIR]`: runs cohort → compare → report on the bundled
//! synthetic study (`examples/demo`: two groups of 8 cells made by the
//! forward model from known parameters with noise, and its pre-built
//! meta-model; embedded in the binary and written to `OUT/example/` when
//! there is no `./examples/demo`) and prints where the report is. `--write-data` regenerates
//! the cells' curves from the study instead. See docs/cli/demo.md.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use nlvid_report::demo::{DemoSpec, run_demo, write_demo_data};

use super::{Context, Run};

/// Raw arguments of `nlvid demo`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Output directory: `cohort/` (fits, results.csv, compare CSVs),
    /// `cohort/report/index.html`.
    #[arg(long, default_value = "nlvid-demo")]
    pub out: PathBuf,
    /// The bundled example (study.toml, data/, metamodel/); default
    /// `examples/demo` in the current directory, else the copy embedded in
    /// this binary, written to `OUT/example/`.
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
        let demo = nlvid_report::demo::demo_dir(a.demo, || {
            crate::embedded_demo::write_to(&a.out.join("example"))
        })?;
        let study = demo.join("study.toml");
        if a.write_data {
            let spec = DemoSpec::default();
            let files = write_demo_data(&spec, &study, &demo.join("metamodel.toml"))?;
            crate::output::print_text(&files.text(&spec))?;
            return Ok(ExitCode::SUCCESS);
        }
        let n = nlvid_report::cohort::discover(&demo.join("data"))?.len();
        let bar = crate::progress::bar(n as u64, "cells");
        let tick = |_: &nlvid_report::cell::CellResult| bar.inc(1);
        let page = run_demo(&demo, &a.out, Some(&tick), &mut |t| {
            use std::io::Write as _;
            bar.suspend(|| std::io::stdout().lock().write_all(t.as_bytes()))
        })?;
        bar.finish_and_clear();
        say!(
            "done in {:.1} s. Report: {}",
            start.elapsed().as_secs_f64(),
            page.html.display()
        )?;
        Ok(ExitCode::SUCCESS)
    }
}
