//! The cells of a cohort input: a folder of group sub-folders, or a
//! manifest CSV (group, file, optional geometry columns of App. B.2).

use std::fs;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::{ReportError, Result};

/// One cell to fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CellInput {
    /// Group name.
    pub group: String,
    /// File as named in the input (relative to the folder or manifest).
    pub file: String,
    /// Path to read.
    pub path: PathBuf,
    /// Geometry measurements from the manifest (App. B.2), if any.
    #[serde(default)]
    pub geometry: Geometry,
    /// Curve of an instrument file holding several (force map, QI): each is a cell;
    /// `None` for CSV and single-curve files.
    #[serde(default)]
    pub curve: Option<usize>,
}

/// True for the curve files a cohort reads: `*.csv` and the instrument files of
/// [`nlvid_afm::batch::AFM_EXTENSIONS`].
fn is_cell_file(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"))
        || nlvid_afm::batch::is_afm_file(path)
}

/// One cell per curve of a multi-curve instrument file (`file#i`); anything else, and
/// a file that cannot be opened (its cell then fails with the reason), as it is.
fn per_curve(cell: CellInput) -> Vec<CellInput> {
    let is_jpk = nlvid_afm::batch::is_afm_file(&cell.path)
        && !cell
            .path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("ibw"));
    if !is_jpk {
        return vec![cell];
    }
    let Ok(bytes) = fs::read(&cell.path) else {
        return vec![cell];
    };
    let name = cell.path.display().to_string();
    let n = nlvid_afm::JpkArchive::open(&bytes, &name, &nlvid_afm::ReadOptions::default())
        .map_or(1, |a| a.len());
    if n <= 1 {
        return vec![cell];
    }
    (0..n)
        .map(|i| CellInput {
            file: format!("{}#{i}", cell.file),
            curve: Some(i),
            ..cell.clone()
        })
        .collect()
}

/// A cell's geometry measurements as given in a manifest (App. B.2).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Geometry {
    /// JPK approach curves on the cell and on the nearby glass (same
    /// z-stepper position): columns `height_cell_curve`, `height_glass_curve`.
    pub height_curves: Option<(PathBuf, PathBuf)>,
    /// Two distances on an optical image, m: columns `d1_um`, `d2_um`
    /// (or `d1_m`, `d2_m`).
    pub image_distances: Option<(f64, f64)>,
}

/// Where `nlvid cohort` writes when not told: `<study stem>-cohort` in
/// the current directory.
pub fn default_out(study: &Path) -> PathBuf {
    let stem = study
        .file_stem()
        .map_or_else(|| "study".into(), |s| s.to_string_lossy().into_owned());
    PathBuf::from(format!("{stem}-cohort"))
}

/// The cells of a cohort input: a folder whose sub-folders are the groups
/// (each `*.csv` or instrument file in them, searched recursively, a cell, each curve of a force map a
/// cell), instrument files directly in the folder forming a group named after it,
/// or a manifest CSV with columns `group` and `file` (relative to the manifest's
/// directory) and optionally the geometry columns of [`Geometry`]. Other files are
/// skipped. Sorted by group, file.
///
/// # Errors
/// Unreadable folder or manifest, a manifest row without group or file
/// (naming the line), a missing data file, duplicate cells, no cells.
pub fn discover(input: &Path) -> Result<Vec<CellInput>> {
    let mut cells = if input.is_dir() {
        from_folder(input)?
    } else {
        from_manifest(input)?
    };
    cells.sort_by(|a, b| (&a.group, &a.file).cmp(&(&b.group, &b.file)));
    if let Some(w) = cells
        .windows(2)
        .find(|w| w[0].group == w[1].group && w[0].file == w[1].file)
    {
        return Err(ReportError::Data {
            path: input.to_path_buf(),
            line: 0,
            message: format!(
                "cell `{}` of group `{}` is listed twice",
                w[0].file, w[0].group
            ),
        });
    }
    if cells.is_empty() {
        return Err(ReportError::Data {
            path: input.to_path_buf(),
            line: 0,
            message: "no cells: expected group sub-folders with *.csv or instrument files \
                      (.jpk-force, .jpk-force-map, .jpk-qi-data, .jpk-qi-series, .ibw), \
                      instrument files in the folder itself, or a manifest with columns \
                      group,file"
                .into(),
        });
    }
    Ok(cells)
}

pub(crate) fn sorted_entries(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut v: Vec<PathBuf> = fs::read_dir(dir)
        .map_err(|e| ReportError::io(dir, e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    v.sort();
    Ok(v)
}

fn from_folder(dir: &Path) -> Result<Vec<CellInput>> {
    let mut cells = Vec::new();
    let name_of = |p: &Path| {
        p.file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    };
    let top = name_of(dir);
    for sub in sorted_entries(dir)? {
        if sub.is_file() && nlvid_afm::batch::is_afm_file(&sub) {
            cells.extend(per_curve(CellInput {
                group: top.clone(),
                file: name_of(&sub),
                path: sub.clone(),
                geometry: Geometry::default(),
                curve: None,
            }));
        }
        if !sub.is_dir() {
            continue;
        }
        let group = name_of(&sub);
        // the one batch input reader (also of `nlvid inspect` and `nlvid fit`)
        let found = nlvid_afm::expand_inputs(std::slice::from_ref(&sub), is_cell_file);
        if let Some(f) = found.failures.first() {
            return Err(ReportError::io(&f.file, f.error.to_string()));
        }
        for f in found.files {
            let rel = f.strip_prefix(&sub).unwrap_or(&f).to_string_lossy();
            cells.extend(per_curve(CellInput {
                group: group.clone(),
                file: format!("{group}/{rel}"),
                path: f.clone(),
                geometry: Geometry::default(),
                curve: None,
            }));
        }
    }
    Ok(cells)
}

fn from_manifest(path: &Path) -> Result<Vec<CellInput>> {
    let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mut rdr = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_path(path)
        .map_err(|e| ReportError::io(path, e))?;
    let headers = rdr.headers().map_err(|e| ReportError::io(path, e))?.clone();
    let col = |name: &str| {
        headers
            .iter()
            .position(|h| h == name)
            .ok_or_else(|| ReportError::Data {
                path: path.to_path_buf(),
                line: 1,
                message: format!("manifest has no column `{name}` (needs group,file)"),
            })
    };
    let (gi, fi) = (col("group")?, col("file")?);
    let find = |name: &str| headers.iter().position(|h| h == name);
    let curves = (find("height_cell_curve"), find("height_glass_curve"));
    let (dist, dist_scale) = match (find("d1_um"), find("d2_um"), find("d1_m"), find("d2_m")) {
        (Some(a), Some(b), _, _) => (Some((a, b, "d1_um", "d2_um")), 1e-6),
        (_, _, Some(a), Some(b)) => (Some((a, b, "d1_m", "d2_m")), 1.0),
        _ => (None, 1.0),
    };
    if curves.0.is_some() != curves.1.is_some() {
        return Err(ReportError::Data {
            path: path.to_path_buf(),
            line: 1,
            message: "cell height needs both columns height_cell_curve and height_glass_curve"
                .into(),
        });
    }
    let mut cells = Vec::new();
    for rec in rdr.records() {
        let rec = rec.map_err(|e| ReportError::io(path, e))?;
        let line = rec.position().map_or(0, |p| p.line());
        let get = |i: usize, what: &str| match rec.get(i) {
            Some(s) if !s.is_empty() => Ok(s.to_string()),
            _ => Err(ReportError::Data {
                path: path.to_path_buf(),
                line,
                message: format!("empty `{what}`"),
            }),
        };
        let (group, file) = (get(gi, "group")?, get(fi, "file")?);
        let p = base.join(&file);
        if !p.is_file() {
            return Err(ReportError::Data {
                path: path.to_path_buf(),
                line,
                message: format!("column `file`: no such file {}", p.display()),
            });
        }
        let mut geometry = Geometry::default();
        if let (Some(ci), Some(gi)) = curves {
            let (c, g) = (rec.get(ci).unwrap_or(""), rec.get(gi).unwrap_or(""));
            if !c.is_empty() || !g.is_empty() {
                let cp = base.join(get(ci, "height_cell_curve")?);
                let gp = base.join(get(gi, "height_glass_curve")?);
                for (p, name) in [(&cp, "height_cell_curve"), (&gp, "height_glass_curve")] {
                    if !p.is_file() {
                        return Err(ReportError::Data {
                            path: path.to_path_buf(),
                            line,
                            message: format!("column `{name}`: no such file {}", p.display()),
                        });
                    }
                }
                geometry.height_curves = Some((cp, gp));
            }
        }
        if let Some((a, b, na, nb)) = dist {
            let num = |i: usize, name: &str| -> Result<Option<f64>> {
                match rec.get(i).unwrap_or("") {
                    "" => Ok(None),
                    v => v.parse::<f64>().map(Some).map_err(|_| ReportError::Data {
                        path: path.to_path_buf(),
                        line,
                        message: format!("column `{name}`: `{v}` is not a number"),
                    }),
                }
            };
            match (num(a, na)?, num(b, nb)?) {
                (Some(x), Some(y)) => {
                    geometry.image_distances = Some((x * dist_scale, y * dist_scale))
                }
                (None, None) => {}
                _ => {
                    return Err(ReportError::Data {
                        path: path.to_path_buf(),
                        line,
                        message: format!("give both `{na}` and `{nb}` or neither"),
                    });
                }
            }
        }
        cells.extend(per_curve(CellInput {
            group,
            file,
            path: p,
            geometry,
            curve: None,
        }));
    }
    Ok(cells)
}
