//! The report: one self-contained HTML page (figures inline as SVG, also
//! written next to it as files) for a cohort output directory.
//!
//! Sections: study (title, hash, forward model, the study file), data
//! overview (mean ± sd of the measured force and of the peak-normalised
//! force per group, as Figs. 5.3–5.8), per-cell fits (data vs fit), group
//! G(t) and G(t)/G(0) mean ± sd with the rank-sum p(t) (Figs. 5.14–5.19),
//! tables (per-cell parameters with units, misfits, flags, status; group
//! summary and tests), and the surrogate's checking errors when given.

use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};

use nlvid_stats::{Method, compare_groups, mean_sd};

use crate::cell::{CellResult, CellStatus};
use crate::cohort::{
    CohortRecord, parameter_names, read_cells, read_record, results_table, write_atomic,
};
use crate::error::{ReportError, Result};
use crate::figures::{
    Band, FitPanel, Line, RangeBand, band_chart, fits_chart, p_draws_chart, pvalue_chart,
    range_chart, range_panels,
};

/// Options of [`write_report`].
#[derive(Debug, Clone)]
pub struct ReportOptions {
    /// Output directory (default: `<cohort dir>/report`).
    pub out: Option<PathBuf>,
    /// CSV of the surrogate's checking errors (default:
    /// `<cohort dir>/surrogate_check.csv` if it exists).
    pub surrogate_check: Option<PathBuf>,
    /// Points of the uniform G(t) grid from 0 to the end of the hold.
    pub points: usize,
    /// p-value method (default: MATLAB `ranksum`, the thesis's tool).
    pub method: Method,
}

impl Default for ReportOptions {
    fn default() -> Self {
        Self {
            out: None,
            surrogate_check: None,
            points: 53,
            method: Method::MATLAB_RANKSUM,
        }
    }
}

/// The files written.
#[derive(Debug, Clone, PartialEq)]
pub struct ReportFiles {
    /// The HTML page.
    pub html: PathBuf,
    /// Figure ids (`fig-…`) present on the page, in order.
    pub figure_ids: Vec<String>,
    /// The SVG files written next to the page.
    pub svgs: Vec<PathBuf>,
}

impl ReportOptions {
    /// Checks, before any work, that `dir` is an output directory of
    /// `nlvid cohort`, that `out` can be written and that a given
    /// `surrogate_check` file exists.
    ///
    /// # Errors
    /// [`ReportError::InvalidSetting`] naming the path.
    pub fn check(&self, dir: &Path) -> Result<()> {
        if !dir.join("cohort.json").is_file() {
            return Err(ReportError::InvalidSetting(format!(
                "{}: not an output directory of `nlvid cohort` (no cohort.json)",
                dir.display()
            )));
        }
        if let Some(o) = &self.out {
            nlvid_study::check_output_dir(o)
                .map_err(|e| ReportError::InvalidSetting(e.to_string()))?;
        }
        match &self.surrogate_check {
            Some(p) if !p.is_file() => Err(ReportError::InvalidSetting(format!(
                "--surrogate-check {}: no such file",
                p.display()
            ))),
            _ => Ok(()),
        }
    }
}

impl ReportFiles {
    /// `nlvid --json report`: `html`, `figures` (ids), `svgs`.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "html": self.html.display().to_string(),
            "figures": self.figure_ids,
            "svgs": self.svgs.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
        })
    }

    /// One line: where the page is and how many figures it has.
    pub fn text(&self) -> String {
        format!(
            "report: {} ({} figures)\n",
            self.html.display(),
            self.figure_ids.len()
        )
    }
}

/// HTML-escapes text.
pub fn escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&#39;"),
            _ => o.push(c),
        }
    }
    o
}

fn sig(v: f64, digits: usize) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let mag = v.abs().log10().floor() as i32;
    if !(-3..6).contains(&mag) {
        return format!("{v:.prec$e}", prec = digits.saturating_sub(1));
    }
    let dec = (digits as i32 - 1 - mag).max(0) as usize;
    format!("{v:.dec$}")
}

/// Mean ± sd over cells of per-grid-point values (cells with data only).
fn data_band(
    name: &str,
    cells: &[&CellResult],
    f: impl Fn(&CellResult, usize) -> f64,
) -> Option<Band> {
    let with: Vec<&&CellResult> = cells.iter().filter(|c| !c.data.is_empty()).collect();
    let first = with.first()?;
    let m = first.times.len();
    if with.len() < 2 || with.iter().any(|c| c.times.len() != m) {
        return None;
    }
    let mut mean = Vec::with_capacity(m);
    let mut sd = Vec::with_capacity(m);
    for j in 0..m {
        let v: Vec<f64> = with.iter().map(|c| f(c, j)).collect();
        let ms = mean_sd(name, &v).ok()?;
        mean.push(ms.mean);
        sd.push(ms.sd);
    }
    Some(Band {
        name: format!("{name} (n = {})", with.len()),
        x: first.times.clone(),
        mean,
        sd,
    })
}

struct Figure {
    id: String,
    file: String,
    caption: String,
    svg: String,
}

impl Figure {
    /// Appends the figure inline (SVG, caption, link to its file).
    fn html(&self, h: &mut String) {
        let _ = writeln!(
            h,
            "<figure id=\"{}\">{}<figcaption>{} (<a href=\"{}\">{}</a>)</figcaption></figure>",
            self.id,
            strip_xml_decl(&self.svg),
            escape(&self.caption),
            self.file,
            self.file
        );
    }
}

fn strip_xml_decl(svg: &str) -> &str {
    match svg.find("<svg") {
        Some(i) => &svg[i..],
        None => svg,
    }
}

fn read_csv_table(path: &Path) -> Result<(Vec<String>, Vec<Vec<String>>)> {
    let mut r = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_path(path)
        .map_err(|e| ReportError::io(path, e))?;
    let h = r
        .headers()
        .map_err(|e| ReportError::io(path, e))?
        .iter()
        .map(str::to_string)
        .collect();
    let mut rows = Vec::new();
    for rec in r.records() {
        let rec = rec.map_err(|e| ReportError::io(path, e))?;
        rows.push(rec.iter().map(str::to_string).collect());
    }
    Ok((h, rows))
}

fn html_table(out: &mut String, headers: &[String], rows: &[Vec<String>]) {
    out.push_str("<table>\n<thead><tr>");
    for h in headers {
        let _ = write!(out, "<th>{}</th>", escape(h));
    }
    out.push_str("</tr></thead>\n<tbody>\n");
    for r in rows {
        out.push_str("<tr>");
        for c in r {
            let _ = write!(out, "<td>{}</td>", escape(c));
        }
        out.push_str("</tr>\n");
    }
    out.push_str("</tbody></table>\n");
}

const STYLE: &str = "body{font-family:system-ui,sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;color:#222}\
h1{font-size:1.6em}h2{border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:2em}\
table{border-collapse:collapse;font-size:.85em;margin:1em 0}th,td{border:1px solid #ddd;padding:3px 6px;text-align:right}\
th{background:#f3f3f3}td:first-child,td:nth-child(2){text-align:left}\
figure{margin:1.5em 0}figcaption{font-size:.9em;color:#444;max-width:720px}\
.note{background:#fff8e1;border-left:4px solid #f0b400;padding:.5em 1em}\
.bad{background:#fdecea}.warn{background:#fff8e1}pre{background:#f6f6f6;padding:1em;overflow-x:auto;font-size:.85em}";

/// Writes the report of the cohort in `cohort_dir`.
///
/// # Errors
/// The directory is not a finished cohort output (no `cohort.json` or
/// `results.csv`), the results table is invalid, a figure cannot be drawn,
/// the output cannot be written.
pub fn write_report(cohort_dir: &Path, opts: &ReportOptions) -> Result<ReportFiles> {
    let record = read_record(cohort_dir)?;
    let cells = read_cells(cohort_dir)?;
    write_report_of(cohort_dir, &record, &cells, opts)
}

/// Writes the report of a cohort whose record and cell results are already
/// in memory (as [`crate::cohort::run_cohort`] returns them), sorted by
/// group then file.
///
/// # Errors
/// As [`write_report`].
pub fn write_report_of(
    cohort_dir: &Path,
    record: &CohortRecord,
    cells: &[CellResult],
    opts: &ReportOptions,
) -> Result<ReportFiles> {
    let results_path = cohort_dir.join("results.csv");
    if !results_path.is_file() {
        return Err(ReportError::io(
            &results_path,
            "missing: the cohort run is not finished; run `nlvid cohort` again to complete it",
        ));
    }
    let table = results_table(cells)?;
    let s = &record.settings;
    let out_dir = opts
        .out
        .clone()
        .unwrap_or_else(|| cohort_dir.join("report"));
    fs::create_dir_all(&out_dir).map_err(|e| ReportError::io(&out_dir, e))?;
    let t_end = s.hold_end;
    let times = uniform_grid(t_end, opts.points)?;

    // Group order: as in the results table (sorted names).
    let groups: Vec<String> = {
        let mut g: Vec<String> = cells.iter().map(|c| c.group.clone()).collect();
        g.dedup();
        g
    };
    let by_group =
        |g: &str| -> Vec<&CellResult> { cells.iter().filter(|c| c.group == g).collect() };
    let mut figures = Vec::new();

    // Data overview (Figs. 5.3–5.8): measured force and peak-normalised force.
    let force_bands: Vec<Band> = groups
        .iter()
        .filter_map(|g| data_band(g, &by_group(g), |c, j| c.data[j] * 1e9))
        .collect();
    let norm_bands: Vec<Band> = groups
        .iter()
        .filter_map(|g| {
            data_band(g, &by_group(g), |c, j| {
                c.data[j] / c.peak_force.unwrap_or(f64::NAN)
            })
        })
        .collect();
    if !force_bands.is_empty() {
        figures.push(Figure {
            id: "fig-force".into(),
            file: "force.svg".into(),
            caption: "Measured force–time curves, mean ± sd per group (cf. Figs. 5.3–5.5).".into(),
            svg: band_chart(
                "force.svg",
                "Force vs time",
                "t (s)",
                "F (nN)",
                &force_bands,
            )?,
        });
        figures.push(Figure {
            id: "fig-force-normalised".into(),
            file: "force_normalised.svg".into(),
            caption: format!(
                "Peak-normalised force F/F_peak, mean ± sd per group (cf. Figs. 5.6–5.8); \
                 1 − F(t_end)/F_peak at t_end = {t_end} s is the relaxation column of the tables."
            ),
            svg: band_chart(
                "force_normalised.svg",
                "Peak-normalised force",
                "t (s)",
                "F / F_peak",
                &norm_bands,
            )?,
        });
    }

    // Per-cell fits.
    let panels: Vec<FitPanel> = cells
        .iter()
        .filter(|c| !c.data.is_empty())
        .map(|c| FitPanel {
            title: format!(
                "{} / {}{}",
                c.group,
                c.cell,
                match c.status {
                    CellStatus::Ok => String::new(),
                    st => format!(" [{}]", st.as_str()),
                }
            ),
            group_index: groups.iter().position(|g| *g == c.group).unwrap_or(0),
            x: c.times.clone(),
            data: c.data.iter().map(|f| f * 1e9).collect(),
            fit: c.fit.iter().map(|f| f * 1e9).collect(),
        })
        .collect();
    if !panels.is_empty() {
        figures.push(Figure {
            id: "fig-fits".into(),
            file: "fits.svg".into(),
            caption: "Each cell: measured force (grey) and the fitted model (colour), F in nN \
                      against t in s."
                .into(),
            svg: fits_chart("fits.svg", "F (nN)", &panels, 4)?,
        });
    }

    // Group G(t) (Figs. 5.14–5.19): groups with at least two fitted cells.
    let mut usable_table = table;
    let usable: Vec<String> = usable_table
        .groups()
        .into_iter()
        .filter(|g| usable_table.group(g).len() >= 2)
        .collect();
    usable_table.cells.retain(|c| usable.contains(&c.group));
    let pair = (usable.len() >= 2).then(|| (usable[0].as_str(), usable[1].as_str()));
    let cmp = compare_groups(&usable_table, pair, &times, opts.method)?;
    let mut g_bands = Vec::new();
    let mut n_bands = Vec::new();
    for gs in &cmp.groups {
        let gc = &gs.curves;
        let label = format!("{} (n = {})", gc.name, gc.n);
        g_bands.push(Band {
            name: label.clone(),
            x: times.clone(),
            mean: gc.shear.iter().map(|m| m.mean).collect(),
            sd: gc.shear.iter().map(|m| m.sd).collect(),
        });
        n_bands.push(Band {
            name: label,
            x: times.clone(),
            mean: gc.normalised.iter().map(|m| m.mean).collect(),
            sd: gc.normalised.iter().map(|m| m.sd).collect(),
        });
    }
    if !g_bands.is_empty() {
        figures.push(Figure {
            id: "fig-modulus".into(),
            file: "modulus.svg".into(),
            caption: "Relaxation modulus G(t) of eq. 5.1 from the fitted parameters, mean ± sd \
                      per group (cf. Figs. 5.14–5.19); E(t) = 3G(t)."
                .into(),
            svg: band_chart("modulus.svg", "G(t)", "t (s)", "G (Pa)", &g_bands)?,
        });
        figures.push(Figure {
            id: "fig-modulus-normalised".into(),
            file: "modulus_normalised.svg".into(),
            caption: "Normalised relaxation modulus G(t)/G(0), mean ± sd per group.".into(),
            svg: band_chart(
                "modulus_normalised.svg",
                "G(t) / G(0)",
                "t (s)",
                "G(t)/G(0)",
                &n_bands,
            )?,
        });
    }
    let mut tests_rows = Vec::new();
    if let Some(p) = &cmp.pair {
        let (a, b) = (&p.a, &p.b);
        let x: Vec<f64> = p.over_time.iter().map(|r| r.t).collect();
        figures.push(Figure {
            id: "fig-pvalues".into(),
            file: "pvalues.svg".into(),
            caption: format!(
                "Two-sided Wilcoxon rank-sum p-value between {a} and {b} at each time \
                 (MATLAB ranksum rules), on G(t) (= on E(t)) and on G(t)/G(0) (= on the \
                 relaxation amount)."
            ),
            svg: pvalue_chart(
                "pvalues.svg",
                &format!("p(t): {a} vs {b}"),
                &[
                    Line {
                        name: "p on G(t)".into(),
                        x: x.clone(),
                        y: p.over_time.iter().map(|r| r.shear.p).collect(),
                    },
                    Line {
                        name: "p on G(t)/G(0)".into(),
                        x,
                        y: p.over_time.iter().map(|r| r.normalised.p).collect(),
                    },
                ],
            )?,
        });
        for k in &p.contrasts {
            let (scale, unit) = if k.unit.is_empty() {
                (100.0, "%")
            } else {
                (1.0, k.unit)
            };
            let ms = |m: &nlvid_stats::MeanSd| {
                format!(
                    "{} ± {} {unit}",
                    sig(scale * m.mean, 4),
                    sig(scale * m.sd, 3)
                )
            };
            tests_rows.push(vec![
                k.quantity.clone(),
                ms(&k.a),
                ms(&k.b),
                sig(k.test.p, 4),
                k.test.used.to_string(),
                format!("{:+.3}", k.effect.rank_biserial),
            ]);
        }
    }

    // Posteriors (issue 17): per-cell credible bands, group-mean bands,
    // p(t) over draws.
    let post = posterior_parts(record, cells, &times, &groups, cmp.pair.as_ref())?;
    figures.extend(post.figures);

    // ---- page ------------------------------------------------------------
    let mut h = String::new();
    let title = escape(&s.title);
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <title>{title} — nlvid report</title><style>{STYLE}</style></head><body>\n\
         <h1>{title}</h1>\n"
    );
    let n_ok = cells.iter().filter(|c| c.status == CellStatus::Ok).count();
    let n_sus = cells
        .iter()
        .filter(|c| c.status == CellStatus::Suspicious)
        .count();
    let n_fail = cells
        .iter()
        .filter(|c| c.status == CellStatus::Failed)
        .count();
    let _ = write!(
        h,
        "<p class=\"note\"><b>Forward model:</b> {}.</p>\n\
         <p>{} cells in {} group(s): {n_ok} fitted, {n_sus} suspicious, {n_fail} failed. \
         Study <code>{}</code>, sha256 <code>{}</code>.</p>\n",
        escape(s.model.describe()),
        cells.len(),
        groups.len(),
        escape(&record.study.display().to_string()),
        escape(&s.study_hash),
    );
    h.push_str("<h2 id=\"study\">Study</h2>\n");
    let _ = writeln!(
        h,
        "<p>Sphere radius R = {} µm, ν = {}, cantilever k: {}; fitted window: \
         ramp to {} s, hold to {} s; {} multistart SLSQP starts per cell (seed {}), \
         Table 5.3 parameter domain with g1 + g2 ≤ 1 − {}; misfit of eq. 5.3; a cell \
         whose misfit exceeds {} is marked suspicious.</p>",
        sig(s.radius * 1e6, 4),
        s.poisson,
        s.spring_constant
            .map_or_else(|| "each file's own".to_string(), |k| format!("{k} N/m")),
        s.ramp,
        s.hold_end,
        s.starts,
        s.seed,
        s.constraint_epsilon,
        s.suspicious_misfit
    );
    if let Ok(text) = fs::read_to_string(&record.study) {
        let _ = writeln!(
            h,
            "<details><summary>study file</summary><pre>{}</pre></details>",
            escape(&text)
        );
    }
    let section = |h: &mut String, id: &str, title: &str, figs: &[&str]| {
        let _ = writeln!(h, "<h2 id=\"{id}\">{title}</h2>");
        for f in figures.iter().filter(|f| figs.contains(&f.id.as_str())) {
            f.html(h);
        }
    };
    section(
        &mut h,
        "data",
        "Data overview",
        &["fig-force", "fig-force-normalised"],
    );
    section(&mut h, "fits", "Per-cell fits", &["fig-fits"]);
    section(
        &mut h,
        "groups",
        "Group relaxation modulus",
        &["fig-modulus", "fig-modulus-normalised", "fig-pvalues"],
    );
    if !tests_rows.is_empty() {
        let head = [
            "quantity".to_string(),
            usable[0].clone(),
            usable[1].clone(),
            "p".into(),
            "p method".into(),
            "rank-biserial".into(),
        ];
        h.push_str("<h3>Group comparison (Wilcoxon rank-sum, two-sided)</h3>\n");
        html_table(&mut h, &head, &tests_rows);
    }

    if !post.rows.is_empty() {
        uncertainty_section(&mut h, &figures, &post.rows, post.level, t_end);
    }
    h.push_str("<h2 id=\"tables\">Per-cell results</h2>\n");
    let mut head = vec!["group".to_string(), "cell".into()];
    let pnames = parameter_names(cells).unwrap_or_default();
    for (n, u) in &pnames {
        head.push(if u.is_empty() {
            n.clone()
        } else {
            format!("{n} ({u})")
        });
    }
    head.extend(
        [
            "misfit",
            "peak force (nN)",
            "relaxation (%)",
            "Hertz E (Pa)",
            "Hertz window",
        ]
        .map(String::from),
    );
    let has_height = cells.iter().any(|c| c.cell_height.is_some());
    let has_diameter = cells.iter().any(|c| c.base_diameter.is_some());
    if has_height {
        head.push("height H (µm)".into());
    }
    if has_diameter {
        head.push("base diameter (µm)".into());
    }
    head.extend(["status", "reason / flags"].map(String::from));
    h.push_str("<table>\n<thead><tr>");
    for c in &head {
        let _ = write!(h, "<th>{}</th>", escape(c));
    }
    h.push_str("</tr></thead>\n<tbody>\n");
    let opt =
        |v: Option<f64>, scale: f64, d: usize| v.map_or_else(String::new, |x| sig(x * scale, d));
    for c in cells {
        let class = match c.status {
            CellStatus::Ok => "",
            CellStatus::Suspicious => " class=\"warn\"",
            CellStatus::Failed => " class=\"bad\"",
        };
        let mut row = vec![c.group.clone(), c.cell.clone()];
        for (n, _) in &pnames {
            row.push(opt(c.parameter(n), 1.0, 4));
        }
        row.push(opt(c.misfit, 1.0, 3));
        row.push(opt(c.peak_force, 1e9, 4));
        row.push(opt(c.relaxation, 100.0, 3));
        row.push(opt(c.hertz.as_ref().map(|h| h.youngs_modulus), 1.0, 4));
        row.push(
            c.hertz
                .as_ref()
                .map_or_else(String::new, |h| h.window.clone()),
        );
        if has_height {
            row.push(opt(c.cell_height, 1e6, 4));
        }
        if has_diameter {
            row.push(opt(c.base_diameter, 1e6, 4));
        }
        row.push(c.status.as_str().into());
        let mut notes = Vec::new();
        if !c.reason.is_empty() {
            notes.push(c.reason.clone());
        }
        notes.extend(c.flags.iter().cloned());
        row.push(notes.join("; "));
        let _ = write!(h, "<tr{class}>");
        for v in row {
            let _ = write!(h, "<td>{}</td>", escape(&v));
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</tbody></table>\n");
    let _ = writeln!(
        h,
        "<p>Machine-readable: <code>{}</code> (format of docs/cli/compare.md).</p>",
        escape(&results_path.display().to_string())
    );

    h.push_str("<h2 id=\"surrogate\">Surrogate checking errors</h2>\n");
    if let Some(f) = &s.surrogate {
        surrogate_section(&mut h, f)?;
    }
    let check = opts.surrogate_check.clone().or_else(|| {
        let p = cohort_dir.join("surrogate_check.csv");
        p.is_file().then_some(p)
    });
    match check {
        Some(p) => {
            let (hd, rows) = read_csv_table(&p)?;
            let _ = writeln!(
                h,
                "<p>From <code>{}</code>.</p>",
                escape(&p.display().to_string())
            );
            html_table(&mut h, &hd, &rows);
        }
        None if s.surrogate.is_some() => {}
        None => {
            let _ = writeln!(
                h,
                "<p>No surrogate was used: every cell was fitted with the forward model \
                 itself ({}), so there are no checking errors to show. Give the surrogate's \
                 checking-error CSV with <code>--surrogate-check FILE</code> (or place it as \
                 <code>surrogate_check.csv</code> in the cohort directory).</p>",
                escape(s.model.describe())
            );
        }
    }
    let _ = write!(
        h,
        "<hr><p style=\"font-size:.8em;color:#666\">nlvid {} — report of <code>{}</code></p>\n\
         </body></html>\n",
        env!("CARGO_PKG_VERSION"),
        escape(&cohort_dir.display().to_string())
    );

    let mut svgs = Vec::new();
    for f in &figures {
        let p = out_dir.join(&f.file);
        write_atomic(&p, f.svg.as_bytes())?;
        svgs.push(p);
    }
    let html = out_dir.join("index.html");
    write_atomic(&html, h.as_bytes())?;
    Ok(ReportFiles {
        html,
        figure_ids: figures.iter().map(|f| f.id.clone()).collect(),
        svgs,
    })
}

/// The report's posterior figures and the rows of its interval table.
struct PosteriorParts {
    figures: Vec<Figure>,
    rows: Vec<Vec<String>>,
    level: f64,
}

/// Figures and table rows of the cells' posteriors (empty without any).
fn posterior_parts(
    record: &CohortRecord,
    cells: &[CellResult],
    times: &[f64],
    groups: &[String],
    pair: Option<&nlvid_stats::PairComparison>,
) -> Result<PosteriorParts> {
    let mut out = PosteriorParts {
        figures: Vec::new(),
        rows: Vec::new(),
        level: 0.9,
    };
    let with: Vec<&CellResult> = cells.iter().filter(|c| c.posterior.is_some()).collect();
    let (Some(first), Some(files)) = (with.first(), record.settings.surrogate.as_ref()) else {
        return Ok(out);
    };
    let level = first.posterior.as_ref().map_or(0.9, |p| p.level);
    out.level = level;
    let pct = sig(100.0 * level, 3);
    let domain = nlvid_inverse::read_meta(&files.meta)?.domain;
    let gi = |g: &str| groups.iter().position(|x| x == g).unwrap_or(0);
    let mut panels = Vec::new();
    for c in &with {
        let Some(p) = &c.posterior else { continue };
        let names: Vec<&str> = c.parameters.iter().map(|q| q.name.as_str()).collect();
        let values: Vec<f64> = c.parameters.iter().map(|q| q.value).collect();
        let point: Vec<f64> = nlvid_model::Relaxation::from_named(&names, &values)
            .map(|r| p.band.times.iter().map(|&t| r.value(t)).collect())
            .unwrap_or_default();
        panels.push((
            RangeBand {
                name: format!("{} / {}", c.group, c.cell),
                colour_index: gi(&c.group),
                x: p.band.times.clone(),
                lower: p.band.lower.clone(),
                median: p.band.median.clone(),
                upper: p.band.upper.clone(),
            },
            point,
        ));
        let iv = |i: &nlvid_inverse::posterior::Interval, scale: f64| {
            format!(
                "{} [{}, {}]",
                sig(scale * i.median, 4),
                sig(scale * i.lower, 4),
                sig(scale * i.upper, 4)
            )
        };
        out.rows.push(vec![
            c.group.clone(),
            c.cell.clone(),
            iv(&p.g0, 1.0),
            iv(&p.g_sum, 1.0),
            iv(&p.g_end, 1.0),
            sig(p.noise_sd * 1e9, 3),
            format!("{:.4}", p.rhat_max),
            format!("{:.0}", p.ess_min),
            c.status.as_str().into(),
        ]);
    }
    out.figures.push(Figure {
        id: "fig-cell-posteriors".into(),
        file: "cell_posteriors.svg".into(),
        caption: format!(
            "Each cell: posterior median of G(t) (colour) inside its {pct} % credible band, and \
             the point-estimate G(t) of the fit (grey), G in Pa against t in s."
        ),
        svg: range_panels("cell_posteriors.svg", "G (Pa)", &panels, 4)?,
    });
    let bands = crate::uncertainty::group_bands(cells, &domain, times, level)?;
    if !bands.is_empty() {
        let rb: Vec<RangeBand> = bands
            .iter()
            .map(|b| RangeBand {
                name: format!("{} (n = {}, {pct} % band of the mean)", b.group, b.cells),
                colour_index: gi(&b.group),
                x: b.times.clone(),
                lower: b.lower.clone(),
                median: b.median.clone(),
                upper: b.upper.clone(),
            })
            .collect();
        out.figures.push(Figure {
            id: "fig-group-posterior".into(),
            file: "group_posterior.svg".into(),
            caption: format!(
                "Group mean G(t) with its {pct} % credible band from the cells' posteriors: how \
                 well the mean of these cells is known given each cell's measurement noise and \
                 the meta-model's error (not the spread between cells, which is the ± sd band \
                 of the figure above)."
            ),
            svg: range_chart(
                "group_posterior.svg",
                "Group mean G(t)",
                "t (s)",
                "G (Pa)",
                &rb,
            )?,
        });
    }
    if let Some(pc) = pair
        && let Some(pd) = crate::uncertainty::p_over_draws(cells, &domain, times, &pc.a, &pc.b)?
    {
        let draws = RangeBand {
            name: format!("p over {} posterior draws: median, 5–95 %", pd.draws),
            colour_index: 0,
            x: pd.times.clone(),
            lower: pd.p05.clone(),
            median: pd.p50.clone(),
            upper: pd.p95.clone(),
        };
        let point = Line {
            name: "p on the point estimates (thesis)".into(),
            x: pc.over_time.iter().map(|r| r.t).collect(),
            y: pc.over_time.iter().map(|r| r.shear.p).collect(),
        };
        let below_end = pd.frac_below_005.last().copied().unwrap_or(f64::NAN);
        out.figures.push(Figure {
            id: "fig-p-draws".into(),
            file: "p_draws.svg".into(),
            caption: format!(
                "Wilcoxon rank-sum p(t) on G(t) between {} and {}: on the fitted point \
                 estimates (dashed, the thesis's test) and recomputed for every joint posterior \
                 draw of all cells (band: 5–95 % of p over draws, line: median). Where the whole \
                 band lies below 0.05 the difference does not hinge on how well single cells \
                 are determined; at t = {} s, {} % of the draws give p < 0.05.",
                pc.a,
                pc.b,
                sig(*times.last().unwrap_or(&0.0), 4),
                sig(100.0 * below_end, 3)
            ),
            svg: p_draws_chart(
                "p_draws.svg",
                &format!("p(t) over posterior draws: {} vs {}", pc.a, pc.b),
                &draws,
                &point,
            )?,
        });
    }
    Ok(out)
}

/// The page's uncertainty section: what the posteriors are, the figures,
/// and the per-cell interval table.
fn uncertainty_section(
    h: &mut String,
    figures: &[Figure],
    rows: &[Vec<String>],
    level: f64,
    t_end: f64,
) {
    let pct = sig(100.0 * level, 3);
    let _ = writeln!(
        h,
        "<h2 id=\"uncertainty\">Uncertainty: posteriors on the meta-model</h2>\n\
         <p>Beyond the thesis (which reports one best fit per cell), every fitted cell's \
         parameters were sampled from their posterior on the meta-model: a flat prior on the \
         meta-model's parameter domain (log-uniform on its log axes, with g1 + g2 ≤ 1 − ε), and \
         a Gaussian likelihood whose variance is the curve's measurement noise (estimated from \
         the curve itself, column <i>noise</i>) plus the meta-model's own Kriging error at that \
         parameter set. An interval [a, b] below means: given this curve, this model and this \
         prior, the quantity lies between a and b with probability {pct} %. A wide interval \
         marks a parameter the curve does not pin down (§4.4.2). R̂ (split, ≤ 1.01 wanted) and \
         the effective sample size (ESS) say whether the sampler ran long enough.</p>"
    );
    for f in figures.iter().filter(|f| {
        ["fig-cell-posteriors", "fig-group-posterior", "fig-p-draws"].contains(&f.id.as_str())
    }) {
        f.html(h);
    }
    let head = [
        "group".to_string(),
        "cell".into(),
        "G0 (Pa)".into(),
        "g1 + g2".into(),
        format!("G({} s) (Pa)", sig(t_end, 4)),
        "noise (nN)".into(),
        "R̂ max".into(),
        "ESS min".into(),
        "status".into(),
    ];
    let _ = writeln!(
        h,
        "<h3>Per-cell credible intervals</h3>\n<p>Posterior median [{pct} % equal-tailed \
         credible interval]; columns <code>post_*</code> of results.csv.</p>"
    );
    html_table(h, &head, rows);
}

/// The meta-model the cells were fitted on: its files, the forward model it
/// stands for, and its checking errors (eq. 4.4) when the study names them.
fn surrogate_section(h: &mut String, f: &crate::settings::SurrogateFiles) -> Result<()> {
    let _ = writeln!(
        h,
        "<p>Every cell was fitted on the Kriging meta-model <code>{}</code> (time grid and \
         inputs: <code>{}</code>) of the forward model <code>{}</code>.</p>",
        escape(&f.model.display().to_string()),
        escape(&f.meta.display().to_string()),
        escape(&f.forward)
    );
    let Some(p) = &f.check else {
        h.push_str("<p>The study names no checking-error file (<code>fit.check</code>).</p>\n");
        return Ok(());
    };
    let bytes = fs::read(p).map_err(|e| ReportError::io(p, e))?;
    let v: serde_json::Value = serde_json::from_slice(&bytes).map_err(|e| ReportError::Data {
        path: p.clone(),
        line: e.line() as u64,
        message: format!("not the JSON of `nlvid surrogate check`: {e}"),
    })?;
    let num = |k: &str| v.get(k).and_then(serde_json::Value::as_f64);
    let n = v.get("rmse").and_then(|r| r.as_array()).map_or(0, Vec::len);
    let (Some(min), Some(median), Some(max)) = (num("min"), num("median"), num("max")) else {
        return Err(ReportError::Data {
            path: p.clone(),
            line: 0,
            message:
                "keys `min`, `median`, `max` (output of `nlvid --json surrogate check`) missing"
                    .into(),
        });
    };
    let head = ["checking cases", "min (%)", "median (%)", "max (%)"].map(String::from);
    let row = vec![
        n.to_string(),
        sig(100.0 * min, 3),
        sig(100.0 * median, 3),
        sig(100.0 * max, 3),
    ];
    let _ = writeln!(
        h,
        "<p>Range-normalised RMSE (eq. 4.4) of the meta-model against the forward model on \
         its checking design, from <code>{}</code>:</p>",
        escape(&p.display().to_string())
    );
    html_table(h, &head, &[row]);
    Ok(())
}

/// Uniform grid 0 … t_end with `points` points.
fn uniform_grid(t_end: f64, points: usize) -> Result<Vec<f64>> {
    if points < 2 || t_end.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Err(ReportError::InvalidSetting(format!(
            "the G(t) grid needs >= 2 points and t_end > 0 (got {points}, {t_end} s)"
        )));
    }
    Ok((0..points)
        .map(|i| t_end * i as f64 / (points - 1) as f64)
        .collect())
}
