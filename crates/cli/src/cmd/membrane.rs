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
use crate::output::{next_to, print_json, print_text, provenance, write_atomic};

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
    #[arg(long, value_delimiter = ',', value_parser = |s: &str| quantity(s.trim(), Dimension::TIME))]
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
    let (name, prov) = (study.name().to_string(), provenance(&study));
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
        .unwrap_or_else(|| next_to(path, "membrane"));
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
    let files = json!({ "files": files, "out": out });
    super::simulate::report(json, &name, &prov, &sim, &run, files, &wrote)?;
    Ok(ExitCode::SUCCESS)
}

fn run_reproduce(args: &MembraneArgs, json: bool) -> anyhow::Result<ExitCode> {
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("membrane-thesis"));
    let (figs, rows, notes) = nlvid_membrane::thesis::reproduce().context("reproducing ch. II")?;
    create(&out)?;
    let mut files = Vec::new();
    for f in &figs {
        let svg = nlvid_membrane::plot::svg(f).with_context(|| format!("drawing {}", f.id))?;
        for (ext, text) in [("csv", f.to_csv()), ("svg", svg)] {
            write_atomic(&out.join(format!("{}.{ext}", f.id)), text.as_bytes())?;
            files.push(format!("{}.{ext}", f.id));
        }
    }
    let table = nlvid_membrane::table2_1_csv(&rows);
    write_atomic(&out.join("table2_1.csv"), table.as_bytes())?;
    let notes_text: String = notes.iter().map(|n| format!("{n}\n")).collect();
    write_atomic(&out.join("notes.txt"), notes_text.as_bytes())?;
    files.extend(["table2_1.csv".to_string(), "notes.txt".into()]);
    for n in &notes {
        eprintln!("note: {n}");
    }
    if json {
        // Dimensionless quantities of eq. 2.47, named as the CSV columns.
        let table: Vec<_> = rows
            .iter()
            .map(|r| {
                json!({
                    "D_over_r0": r.d_max, "unloading_rate": r.unload_rate, "model": r.model,
                    "thesis_slope": r.thesis, "tangent_slope": r.slope,
                    "secant_slope_dD_0.01": r.secant, "secant_over_2_div_thesis": r.ratio,
                })
            })
            .collect();
        return print_json(
            &json!({ "files": files, "table2_1": table, "notes": notes, "out": out }),
        )
        .map(|()| ExitCode::SUCCESS);
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
