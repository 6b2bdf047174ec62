//! `nlvid build` without a study file: a design CSV run through a forward
//! model named on the command line (`hertz-prony`, the analytic LV Hertz
//! ramp-hold with the flag defaults of
//! [`nlvid_forward::HertzPronySpec::flag_defaults`]), exported with an
//! optional domain file for the fits.

use std::path::Path;

use nlvid_model::ForwardModel;

use crate::build::{Admissibility, BuildOptions};
use crate::error::{Result, SurrogateError};
use crate::study::{build_report, export_report, read_domain};
use crate::table::read_table;

/// A build given by flags only.
#[derive(Debug, Clone)]
pub struct FlagBuild<'a> {
    /// Design CSV (from `nlvid sample`).
    pub design: &'a Path,
    /// Domain file the design was sampled in (stored in the export's `meta.json`).
    pub domain: Option<&'a Path>,
    /// Forward model name: only `hertz-prony`.
    pub model: &'a str,
    /// hertz-prony: time points.
    pub points: usize,
    /// Store directory.
    pub store: &'a Path,
    /// Export directory.
    pub export: Option<&'a Path>,
    /// Admissibility filters of the export.
    pub filters: Admissibility,
}

impl FlagBuild<'_> {
    /// Builds the design into the store ([`build_report`]) and exports it
    /// ([`export_report`]); `say` gets each report.
    ///
    /// # Errors
    /// An unknown model, a design that is not 5 columns, a domain file that
    /// does not fit the model or the design; as [`build_report`] and
    /// [`export_report`]; `say` failing.
    pub fn run(
        &self,
        opts: &BuildOptions<'_>,
        say: &mut dyn FnMut(&str) -> std::io::Result<()>,
    ) -> Result<()> {
        let bad = |m: String| SurrogateError::InvalidSettings(m);
        let said = |r: std::io::Result<()>| r.map_err(crate::error::io_err("stdout"));
        let model = match self.model {
            "hertz-prony" => nlvid_forward::HertzPronySpec::flag_defaults(self.points)
                .build()
                .map_err(|e| bad(e.to_string()))?,
            other => {
                return Err(bad(format!(
                    "--model {other}: unknown forward model for flag-only use (available: \
                     hertz-prony; afm-fe and membrane are set up in a study file's [forward] \
                     section)"
                )));
            }
        };
        let design = read_table(self.design)?;
        if design.header.len() != 5 {
            return Err(bad(format!(
                "{}: hertz-prony needs 5 columns (G0, g1, g2, tau1, tau2), found {}",
                self.design.display(),
                design.header.len()
            )));
        }
        let names = model.parameter_names();
        let domain = (self.domain)
            .map(|p| read_domain(p, &names, &design.rows))
            .transpose()
            .map_err(|e| {
                bad(format!(
                    "--domain for --design {}: {e}",
                    self.design.display()
                ))
            })?;
        let text = build_report("design", &model, &design.rows, self.store, opts)?;
        said(say(&text))?;
        if let Some(dir) = self.export {
            said(say(&export_report(
                self.store,
                dir,
                &self.filters,
                domain.as_ref(),
            )?))?;
        }
        Ok(())
    }
}
