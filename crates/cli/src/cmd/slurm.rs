//! `nlvid slurm STUDY --out DIR`: the study's meta-model build as a Slurm
//! job array plus a merge job (scripts and submission live in
//! [`nlvid_surrogate::slurm`]); `nlvid slurm --status DIR` reports the tasks.

use std::path::{PathBuf, absolute};
use std::process::ExitCode;

use anyhow::Context as _;
use nlvid_surrogate::slurm::{self, SlurmSettings};

use super::{Context, Run};
use crate::output::emit;

/// Raw arguments of `nlvid slurm` (defaults: docs/cli/slurm.md).
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Study file with `[forward]`, `[design]`, `[build]` (checked first).
    #[arg(required_unless_present = "status")]
    pub study: Option<PathBuf>,
    /// Job directory, on a file system every compute node can write.
    #[arg(long, required_unless_present = "status")]
    pub out: Option<PathBuf>,
    /// Report the tasks of a job directory and what to do next.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["study", "out", "submit"])]
    pub status: Option<PathBuf>,
    /// Array tasks = shards [8].
    #[arg(long)]
    pub array_size: Option<usize>,
    /// At most this many tasks at once (`%k`).
    #[arg(long)]
    pub throttle: Option<usize>,
    /// CPUs per task [1].
    #[arg(long)]
    pub cpus_per_task: Option<usize>,
    /// Time limit per task, Slurm syntax [1:00:00].
    #[arg(long)]
    pub time: Option<String>,
    /// Memory per task (e.g. 2G).
    #[arg(long)]
    pub mem: Option<String>,
    /// Partition.
    #[arg(long)]
    pub partition: Option<String>,
    /// Account.
    #[arg(long)]
    pub account: Option<String>,
    /// Node-local scratch for the task stores, e.g. '$TMPDIR'.
    #[arg(long)]
    pub scratch: Option<String>,
    /// `module load` this before the build (repeatable).
    #[arg(long = "module")]
    pub modules: Vec<String>,
    /// Requeues of a task whose nlvid is killed [3].
    #[arg(long)]
    pub max_requeue: Option<usize>,
    /// With --scratch: copy runs back every this many seconds [600].
    #[arg(long)]
    pub sync_every: Option<u64>,
    /// Export directory of the merge job [OUT/export].
    #[arg(long)]
    pub export: Option<PathBuf>,
    /// The nlvid the tasks run [this program].
    #[arg(long)]
    pub nlvid: Option<PathBuf>,
    /// Submit with sbatch and print the job ids.
    #[arg(long)]
    pub submit: bool,
    /// With --submit: only these array indices (e.g. 3,7).
    #[arg(long, requires = "submit")]
    pub tasks: Option<String>,
}

/// Validated `nlvid slurm`.
#[derive(Debug)]
pub enum Config {
    /// `--status DIR`.
    Status(PathBuf),
    /// Write (and submit) the scripts.
    Write(Box<SlurmSettings>, bool, Option<String>),
}

impl Run for Args {
    type Config = Config;

    fn validate(self, _ctx: &Context) -> anyhow::Result<Config> {
        if let Some(d) = self.status {
            return Ok(Config::Status(d));
        }
        let (Some(study), Some(out)) = (self.study, self.out) else {
            anyhow::bail!("give a study file and --out DIR, or --status DIR");
        };
        nlvid_surrogate::BuildStudy::load(&study)?;
        let nlvid = match self.nlvid {
            Some(p) => p,
            None => std::env::current_exe().context("locating this nlvid program")?,
        };
        let mut s = SlurmSettings::new(absolute(&study)?, absolute(nlvid)?, absolute(out)?);
        if let Some(e) = self.export {
            s.export = absolute(e)?;
        }
        s.array_size = self.array_size.unwrap_or(s.array_size);
        s.throttle = self.throttle;
        s.cpus_per_task = self.cpus_per_task.unwrap_or(s.cpus_per_task);
        s.time = self.time.unwrap_or(s.time);
        (s.mem, s.partition, s.account, s.scratch) =
            (self.mem, self.partition, self.account, self.scratch);
        s.modules = self.modules;
        s.max_requeue = self.max_requeue.unwrap_or(s.max_requeue);
        s.sync_every = self.sync_every.unwrap_or(s.sync_every);
        s.validate()?;
        Ok(Config::Write(Box::new(s), self.submit, self.tasks))
    }

    fn execute(config: Config, ctx: &Context) -> anyhow::Result<ExitCode> {
        let (s, submit, tasks) = match config {
            Config::Status(dir) => {
                let st = slurm::status(&dir)?;
                emit(ctx.json, &st.to_json(), &format!("{st}\n"))?;
                // Status 1 until the merge job has finished.
                return Ok(ExitCode::from(u8::from(!st.merged)));
            }
            Config::Write(s, submit, tasks) => (s, submit, tasks),
        };
        for w in s.warnings() {
            eprintln!("warning: {w}");
        }
        let files = slurm::write(&s)?;
        let ids = submit
            .then(|| slurm::submit(&s, tasks.as_deref(), "sbatch".as_ref()))
            .transpose()?;
        let text = files.text(ids.as_ref());
        emit(ctx.json, &files.to_json(ids.as_ref()), &text)?;
        Ok(ExitCode::SUCCESS)
    }
}
