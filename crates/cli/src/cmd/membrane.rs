//! `nlvid membrane`: the fluid-filled membrane between plates (thesis ch.
//! II, §2.3) for one study — the `membrane` forward model of `[forward]`
//! and `[protocol]` at the values of `[parameters]`, the study `nlvid
//! simulate` and `nlvid build` read — with its profiles; or `--reproduce
//! thesis` to regenerate the data and plots of Figs. 2.3–2.14 and Table 2.1.
//! See docs/cli/membrane.md.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, bail};
use clap::{Args, ValueEnum};
use nlvid_forward::{ForwardSpec, SimulateStudy};
use nlvid_study::{Dimension, Study};
use serde_json::json;

use crate::args::quantity;
use crate::output::{print_json, print_text, write_atomic};

/// Arguments of `nlvid membrane`.
#[derive(Debug, Args)]
pub struct MembraneArgs {
    /// Study file with `[forward] model = "membrane"`, `[protocol]` and
    /// `[parameters]` (see docs/cli/membrane.md).
    #[arg(required_unless_present = "reproduce")]
    pub study: Option<PathBuf>,
    /// Regenerate a published data set instead of running a study.
    #[arg(long, value_enum, conflicts_with = "study")]
    pub reproduce: Option<Reproduce>,
    /// Output directory, created if missing (default: `<study stem>.membrane`
    /// next to the study; `membrane-thesis` for --reproduce).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Times at which profiles are written, e.g. `--profile-times "0 s,10 s"`
    /// (default: the last solve time).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true, value_parser = |s: &str| quantity(s.trim(), Dimension::TIME))]
    pub profile_times: Option<Vec<f64>>,
}

/// Published data sets.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum Reproduce {
    /// Figs. 2.3–2.14 and Table 2.1 of the thesis.
    Thesis,
}

fn create(dir: &Path) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))
}

fn run_study(args: &MembraneArgs, path: &Path, json: bool) -> anyhow::Result<ExitCode> {
    let study = Study::load(path)?;
    let (name, prov) = (study.name().to_string(), study.provenance());
    let sim = SimulateStudy::from_study(study)?;
    let ForwardSpec::Membrane(spec) = &sim.forward.spec else {
        bail!(
            "{name}: [forward] model = \"{}\"; `nlvid membrane` runs model = \"membrane\" \
             (use `nlvid simulate` for the other models)",
            sim.model()
        );
    };
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| nlvid_study::next_to(path, "membrane"));
    nlvid_study::check_output_dir(&out)?;
    let profile_times = args.profile_times.clone();
    let run = sim
        .run(&profile_times.unwrap_or_else(|| vec![spec.program.end()]))
        .with_context(|| format!("study {name}"))?;
    create(&out)?;
    write_atomic(&out.join("history.csv"), run.curve()?.to_csv().as_bytes())?;
    let mut files = vec!["history.csv".to_string()];
    for (time, csv) in run.profiles_csv() {
        files.push(format!("profile_t{time:.4}s.csv"));
        write_atomic(&out.join(&files[files.len() - 1]), csv.as_bytes())?;
    }
    let wrote = format!("{} files in {}", files.len(), out.display());
    let files = (json!({ "files": files, "out": out }), &*wrote);
    print_text(&run.report(json, &sim, (&name, &prov), files)?)?;
    Ok(ExitCode::SUCCESS)
}

fn run_reproduce(args: &MembraneArgs, json: bool) -> anyhow::Result<ExitCode> {
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("membrane-thesis"));
    nlvid_study::check_output_dir(&out)?;
    let (figs, rows, notes) = nlvid_membrane::thesis::reproduce().context("reproducing ch. II")?;
    create(&out)?;
    let mut files = Vec::new();
    for (name, text) in nlvid_membrane::reproduction_files(&figs, &rows, &notes)? {
        write_atomic(&out.join(&name), text.as_bytes())?;
        files.push(name);
    }
    for n in &notes {
        eprintln!("note: {n}");
    }
    if json {
        let doc = json!({ "files": files, "table2_1": rows, "notes": notes, "out": out });
        return print_json(&doc).map(|()| ExitCode::SUCCESS);
    }
    print_text(&nlvid_membrane::table2_1_text(&rows))?;
    say!("wrote {} files to {}", files.len(), out.display())?;
    Ok(ExitCode::SUCCESS)
}

/// Run `nlvid membrane`.
///
/// # Errors
/// A bad study, a failed run, unwritable outputs.
pub fn run(args: MembraneArgs, json: bool) -> anyhow::Result<ExitCode> {
    match (&args.reproduce, &args.study) {
        (Some(Reproduce::Thesis), _) => run_reproduce(&args, json),
        (None, Some(p)) => run_study(&args, &p.clone(), json),
        (None, None) => bail!("give a study file or --reproduce thesis"),
    }
}
