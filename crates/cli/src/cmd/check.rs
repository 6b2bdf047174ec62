//! `nlvid check <study.toml>`: validate a study file and print every value
//! as the program reads it, in SI ([`nlvid_report::check`]).

use std::path::PathBuf;
use std::process::ExitCode;

use nlvid_report::check::{StudyCheck, check_study};

use super::{Context, Run};
use crate::output::emit;

pub(crate) use nlvid_report::check::section_typos;

/// Raw arguments of `nlvid check`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The study file (TOML).
    pub study: PathBuf,
    /// Treat warnings (strings that look like quantities but cannot be read) as errors.
    #[arg(long)]
    pub strict: bool,
}

/// What `check` found, and whether warnings fail it.
#[derive(Debug)]
pub struct Config {
    check: StudyCheck,
    strict: bool,
}

impl Run for Args {
    type Config = Config;

    fn validate(self, _ctx: &Context) -> anyhow::Result<Config> {
        let check = check_study(&self.study).map_err(anyhow::Error::from_boxed)?;
        Ok(Config {
            check,
            strict: self.strict,
        })
    }

    fn execute(c: Config, ctx: &Context) -> anyhow::Result<ExitCode> {
        emit(ctx.json, &c.check.to_json(), &c.check.text())?;
        for w in c.check.warnings.iter().filter(|_| !ctx.json) {
            eprintln!("warning: {w}");
        }
        if c.strict && !c.check.warnings.is_empty() {
            eprintln!("error: {} warning(s) with --strict", c.check.warnings.len());
            return Ok(ExitCode::FAILURE);
        }
        Ok(ExitCode::SUCCESS)
    }
}
