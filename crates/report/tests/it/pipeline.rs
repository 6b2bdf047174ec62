//! End-to-end: the bundled demo (study + pre-built meta-model, curves
//! regenerated here by the data generator) → cohort on the meta-model
//! (interrupted and resumed) → results table → group statistics → report.
//! The ground truth of the synthetic study is the independent reference.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use nlvid_model::Relaxation;
use nlvid_report::cell::CellStatus;
use nlvid_report::cohort::{self, RunOptions};
use nlvid_report::demo::{DemoSpec, write_demo_data};
use nlvid_report::report::{ReportOptions, write_report};
use nlvid_report::settings::CohortSettings;
use nlvid_stats::{Method, rank_sum, read_results, relaxation_amounts};

fn repo_demo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/demo")
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("dir");
    for e in std::fs::read_dir(from).expect("read dir") {
        let p = e.expect("entry").path();
        let dest = to.join(p.file_name().expect("name"));
        if p.is_dir() {
            copy_dir(&p, &dest);
        } else {
            std::fs::copy(&p, &dest).expect("copy");
        }
    }
}

/// The committed study and meta-model in `dir`, with the cells' curves
/// written by the generator.
fn demo_in(dir: &Path) -> nlvid_report::demo::DemoFiles {
    let repo = repo_demo();
    std::fs::create_dir_all(dir).expect("dir");
    for f in ["study.toml", "metamodel.toml"] {
        std::fs::copy(repo.join(f), dir.join(f)).expect("copy study");
    }
    copy_dir(&repo.join("metamodel"), &dir.join("metamodel"));
    write_demo_data(
        &DemoSpec::default(),
        &dir.join("study.toml"),
        &dir.join("metamodel.toml"),
    )
    .expect("demo data")
}

fn scratch(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("report-{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("scratch dir");
    d
}

struct Fixture {
    demo: PathBuf,
    out: PathBuf,
    truth: Vec<nlvid_report::demo::TrueCell>,
}

/// The default demo (8 + 8 cells) plus one broken cell, fitted once.
fn fixture() -> &'static Fixture {
    static F: OnceLock<Fixture> = OnceLock::new();
    F.get_or_init(|| {
        let root = scratch("fixture");
        let demo = root.join("demo");
        let files = demo_in(&demo);
        // A cell whose recording stops after 10 s: must be listed as failed.
        let short = std::fs::read_to_string(demo.join("data/B-soft/b-soft-01.csv")).expect("csv");
        let cut: String = short
            .lines()
            .take_while(|l| !l.starts_with("10.0000"))
            .map(|l| format!("{l}\n"))
            .collect();
        std::fs::write(demo.join("data/B-soft/b-soft-short.csv"), cut).expect("write");
        let out = root.join("out");
        let settings = CohortSettings::load(&files.study).expect("settings");
        let cells = cohort::discover(&files.data).expect("discover");
        let run = cohort::run_cohort(
            &settings,
            &files.study,
            &files.data,
            &cells,
            &out,
            &RunOptions::default(),
        )
        .expect("cohort");
        assert_eq!(run.pending, 0);
        assert_eq!(run.fitted, 17);
        Fixture {
            demo,
            out,
            truth: files.cells,
        }
    })
}

#[test]
fn demo_recovers_its_group_ordering_with_p_below_0_05() {
    let f = fixture();
    let table = read_results(&f.out.join("results.csv")).expect("results");
    assert_eq!(table.cells.len(), 16, "16 usable cells");
    assert_eq!(
        table.excluded.len(),
        1,
        "the short recording is listed, not dropped"
    );
    assert!(
        table.excluded[0].reason.contains("covers"),
        "{}",
        table.excluded[0].reason
    );
    let a: Vec<Relaxation> = table.group("A-stiff");
    let b: Vec<Relaxation> = table.group("B-soft");
    let t_end = 52.0;
    let g = |c: &[Relaxation], t: f64| c.iter().map(|p| p.value(t)).collect::<Vec<_>>();
    let m = Method::MATLAB_RANKSUM;
    // Known ordering (DemoSpec::default): A stiffer at 0 and 52 s, relaxes less.
    let tests = [
        (
            "G(0)",
            rank_sum(&g(&a, 0.0), &g(&b, 0.0), m).expect("test"),
            1.0,
        ),
        (
            "G(52 s)",
            rank_sum(&g(&a, t_end), &g(&b, t_end), m).expect("test"),
            1.0,
        ),
        (
            "relaxation",
            rank_sum(
                &relaxation_amounts(&a, t_end),
                &relaxation_amounts(&b, t_end),
                m,
            )
            .expect("test"),
            -1.0,
        ),
    ];
    for (what, t, sign) in tests {
        assert!(t.p < 0.05, "{what}: p = {}", t.p);
        // Direction: U1 above its mean n1 n2 / 2 means A ranks higher.
        let centre = 0.5 * (a.len() * b.len()) as f64;
        assert!(
            sign * (t.u1 - centre) > 0.0,
            "{what}: wrong direction, U1 = {}",
            t.u1
        );
    }
}

#[test]
fn recovered_moduli_match_the_ground_truth_per_cell() {
    let f = fixture();
    let cells = cohort::read_cells(&f.out).expect("cells");
    for t in &f.truth {
        let c = cells
            .iter()
            .find(|c| c.cell == t.cell)
            .expect("every true cell has a result");
        assert_eq!(c.status, CellStatus::Ok, "{}: {}", c.cell, c.reason);
        // Parameters by name; the truth in the order G0, g1, g2, tau1, tau2.
        let p = |n: &str| c.parameter(n).expect("fitted parameter");
        let x = [p("G0"), p("g1"), p("g2"), p("tau1"), p("tau2")];
        let shear = |x: &[f64], s: f64| {
            x[0] * (1.0 - x[1] - x[2] + x[1] * (-s / x[3]).exp() + x[2] * (-s / x[4]).exp())
        };
        // 1 % force noise, FE curves fitted on the FE meta-model (checking
        // error: median 0.27 %, max 12.5 % at G0 = 82 Pa, far from these
        // cells; metamodel/check.json): G(t) within 5 % at 1, 10 and 52 s
        // (worst cell today 2.1 %). G(0) is an extrapolation here — the 1 s
        // ramp is longer than τ1 (0.6 s median), so the data never show the
        // unrelaxed modulus — and gets 10 % (worst cell today: 4.6 %).
        for (s, tol) in [(0.0, 0.10), (1.0, 0.05), (10.0, 0.05), (52.0, 0.05)] {
            let (fit, truth) = (shear(&x, s), shear(&t.x, s));
            assert!(
                (fit / truth - 1.0).abs() < tol,
                "{} G({s}) = {fit} vs true {truth}",
                t.cell
            );
        }
        assert!(c.misfit.expect("misfit") < 0.02, "{}", c.cell);
    }
}

/// One meaning of G0 from the fit to the comparison: the cohort's fitted
/// parameters (named `G0`, `g1`, …) and the results table `nlvid compare`
/// reads back give the same `nlvid_model::Relaxation` (shortest round-trip
/// numbers: bit for bit), and that G(t) is eq. 5.1 by hand with G0 as the
/// shear modulus (no factor 2 between the stages).
#[test]
fn the_fit_and_the_results_table_give_one_g_of_t() {
    let f = fixture();
    let cells = cohort::read_cells(&f.out).expect("cells");
    let table = read_results(&f.out.join("results.csv")).expect("results");
    let mut checked = 0;
    for c in cells.iter().filter(|c| c.status == CellStatus::Ok) {
        let names: Vec<&str> = c.parameters.iter().map(|p| p.name.as_str()).collect();
        let x: Vec<f64> = c.parameters.iter().map(|p| p.value).collect();
        let fitted = Relaxation::from_named(&names, &x).expect("a Prony cell");
        let row = table
            .cells
            .iter()
            .find(|r| r.cell == c.cell)
            .expect("every fitted cell is in results.csv");
        assert_eq!(row.relaxation, fitted, "{}", c.cell);
        let at = |n: &str| x[names.iter().position(|m| *m == n).expect("named")];
        for t in [0.0, 1.0, 52.0] {
            let by_hand = at("G0")
                * (1.0 - at("g1") - at("g2")
                    + at("g1") * (-t / at("tau1")).exp()
                    + at("g2") * (-t / at("tau2")).exp());
            assert!(
                (row.relaxation.value(t) / by_hand - 1.0).abs() < 1e-12,
                "{} G({t})",
                c.cell
            );
        }
        checked += 1;
    }
    assert_eq!(checked, 16);
}

/// The Hertz baseline of a viscoelastic half-space: on the ramp the
/// Lee–Radok force lies between the elastic forces of G(t) and G(0), so the
/// fitted E (ν = 0.5) must lie between 3·G(t_ramp) and 3·G(0) of the true
/// parameters (2 % margin for the noise and the fitted contact point).
/// The bound is a theorem for the Lee–Radok curve, not for the demo's FE
/// cell (finite height on a substrate, large strain: there E_Hertz/3G(1 s)
/// is 0.96–1.19), so the demo's cells are written here with the analytic
/// `hertz-prony` model (same truth, noise and sampling) and the baseline
/// (`cell::hertz_baseline`, what the cohort runs) is fitted to each.
#[test]
fn hertz_baseline_lies_between_the_true_instantaneous_and_ramp_end_moduli() {
    let dir = scratch("hertz-bound");
    std::fs::copy(repo_demo().join("study.toml"), dir.join("study.toml")).expect("study");
    copy_dir(&repo_demo().join("metamodel"), &dir.join("metamodel"));
    std::fs::write(
        dir.join("lee-radok.toml"),
        "[forward]\nmodel = \"hertz-prony\"\nprobe_radius = \"2.5 um\"\nrate = \"2 um/s\"\n\
         ramp = \"1 s\"\nhold = \"51 s\"\npoints = 520\n",
    )
    .expect("forward study");
    let files = write_demo_data(
        &DemoSpec::default(),
        &dir.join("study.toml"),
        &dir.join("lee-radok.toml"),
    )
    .expect("Lee–Radok curves");
    let settings = CohortSettings::load(&files.study).expect("settings");
    let cal = nlvid_inverse::Calibration {
        deflection_sensitivity: None,
        spring_constant: settings.spring_constant.expect("k"),
    };
    let cols = nlvid_inverse::AfmColumns {
        time: settings.time_column.clone(),
        piezo: settings.piezo_column.clone(),
        deflection: settings.deflection_column.clone(),
    };
    for t in &files.cells {
        let path = files.data.join(&t.group).join(format!("{}.csv", t.cell));
        let curve = nlvid_inverse::read_afm_csv(&path, &cols, &cal).expect("demo curve");
        let delta = curve
            .indentation()
            .map(<[f64]>::to_vec)
            .expect("indentation");
        let h = nlvid_report::cell::hertz_baseline(&settings, &curve, &delta)
            .expect("Hertz baseline fitted");
        let x = t.x;
        let g = |s: f64| {
            x[0] * (1.0 - x[1] - x[2] + x[1] * (-s / x[3]).exp() + x[2] * (-s / x[4]).exp())
        };
        let (lo, hi) = (3.0 * g(1.0), 3.0 * g(0.0));
        assert!(
            h.youngs_modulus > 0.98 * lo && h.youngs_modulus < 1.02 * hi,
            "{}: E_Hertz = {} outside [3G(1 s), 3G(0)] = [{lo}, {hi}]",
            t.cell,
            h.youngs_modulus
        );
        assert!(h.window.contains("loading ramp"), "{}", h.window);
    }
}

#[test]
fn interrupted_then_resumed_run_gives_the_same_table_as_an_uninterrupted_one() {
    let f = fixture();
    let study = f.demo.join("study.toml");
    let data = f.demo.join("data");
    let settings = CohortSettings::load(&study).expect("settings");
    let cells = cohort::discover(&data).expect("discover");
    let out = scratch("resume");
    let run = |opts: &RunOptions, what: &str| {
        cohort::run_cohort(&settings, &study, &data, &cells, &out, opts).expect(what)
    };
    let first = run(
        &RunOptions {
            max_new_fits: Some(5),
            on_cell: None,
        },
        "first part",
    );
    assert_eq!(first.fitted, 5);
    assert_eq!(first.pending, 12);
    assert!(
        !out.join("results.csv").exists(),
        "no table from an unfinished run"
    );
    // What a kill can leave behind: a stray temporary file (the rename
    // never happened) and a damaged result file; both must be ignored.
    let pending = cells
        .iter()
        .find(|c| !cohort::cell_result_path(&out, c).exists())
        .expect("a pending cell");
    let p = cohort::cell_result_path(&out, pending);
    std::fs::write(&p, b"{\"group\": \"B-so").expect("damaged file");
    std::fs::write(p.with_file_name(".x.json.999.tmp"), b"partial").expect("tmp");

    let second = run(&RunOptions::default(), "resume");
    assert_eq!((second.reused, second.fitted, second.pending), (5, 12, 0));
    let resumed = std::fs::read(out.join("results.csv")).expect("resumed table");
    let straight = std::fs::read(f.out.join("results.csv")).expect("table");
    assert_eq!(
        String::from_utf8_lossy(&resumed),
        String::from_utf8_lossy(&straight)
    );
    // A third run fits nothing.
    let third = run(&RunOptions::default(), "again");
    assert_eq!((third.reused, third.fitted), (17, 0));
}

#[test]
fn report_page_contains_every_figure_and_every_cell() {
    let f = fixture();
    let dir = scratch("report");
    let files = write_report(
        &f.out,
        &ReportOptions {
            out: Some(dir.clone()),
            ..ReportOptions::default()
        },
    )
    .expect("report");
    let html = std::fs::read_to_string(&files.html).expect("html");
    let expected = [
        "fig-force",
        "fig-force-normalised",
        "fig-fits",
        "fig-modulus",
        "fig-modulus-normalised",
        "fig-pvalues",
    ];
    assert_eq!(files.figure_ids, expected);
    for id in expected {
        let at = html
            .find(&format!("<figure id=\"{id}\">"))
            .unwrap_or_else(|| panic!("figure {id} missing"));
        let rest = &html[at..];
        let end = rest.find("</figure>").expect("closed figure");
        let fig = &rest[..end];
        assert!(
            fig.contains("<svg") && fig.contains("</svg>"),
            "{id} has no inline SVG"
        );
        // Plotted data: at least one polyline/path with many points.
        assert!(fig.matches(' ').count() > 200, "{id} looks empty");
    }
    assert_eq!(files.svgs.len(), expected.len());
    for p in &files.svgs {
        let s = std::fs::read_to_string(p).expect("svg file");
        assert!(s.contains("<svg"), "{}", p.display());
    }
    for t in &f.truth {
        assert!(
            html.contains(&format!("<td>{}</td>", t.cell)),
            "{} not in the table",
            t.cell
        );
    }
    assert!(html.contains("b-soft-short") && html.contains("failed"));
    assert!(
        html.contains("Kriging meta-model") && html.contains("afm-fe("),
        "the meta-model and the forward model it stands for are stated"
    );
    assert!(
        html.contains("Hertz E (Pa)") && html.contains("loading ramp"),
        "Hertz baseline column"
    );
    assert!(html.contains("Surrogate checking errors"));
}

#[test]
fn the_committed_demo_is_what_the_generator_writes() {
    // The fixture's curves (16 FE runs) are the generator's output.
    let dir = &fixture().demo;
    let repo = repo_demo();
    let mut checked = 0;
    let mut rels = vec!["ground_truth.csv".to_string()];
    for g in ["A-stiff", "B-soft"] {
        for i in 1..=8 {
            rels.push(format!("data/{g}/{}-{i:02}.csv", g.to_lowercase()));
        }
    }
    for rel in &rels {
        let a = std::fs::read(dir.join(rel)).expect("generated");
        let b = std::fs::read(repo.join(rel)).expect("examples/demo is committed");
        assert!(a == b, "{rel} differs from the generator's output");
        checked += 1;
    }
    assert_eq!(checked, 17);
}

/// Loads the page in headless Chromium: the rendered DOM must hold every
/// figure's SVG, and a full-page screenshot is written to
/// `target/tmp/report-chromium/report.png` (looked at by hand, see
/// docs/theory/report.md). Skipped (with a message) without Chromium.
#[test]
fn report_opens_in_headless_chromium() {
    let chromium = Path::new("/usr/bin/chromium");
    if !chromium.exists() {
        eprintln!("SKIPPED: /usr/bin/chromium not installed (apt-get install -y chromium)");
        return;
    }
    let f = fixture();
    let dir = scratch("chromium");
    let files = write_report(
        &f.out,
        &ReportOptions {
            out: Some(dir.join("page")),
            ..ReportOptions::default()
        },
    )
    .expect("report");
    let url = format!(
        "file://{}",
        files.html.canonicalize().expect("abs path").display()
    );
    let run = |extra: &[String]| {
        let profile = dir.join(format!("profile-{}", extra.len()));
        let out = std::process::Command::new(chromium)
            .args([
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--no-first-run",
                "--hide-scrollbars",
            ])
            .arg(format!("--user-data-dir={}", profile.display()))
            .args(extra)
            .arg(&url)
            .output()
            .expect("chromium runs");
        assert!(
            out.status.success(),
            "chromium: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        out
    };
    let dom = String::from_utf8_lossy(&run(&["--dump-dom".to_string()]).stdout).into_owned();
    for id in &files.figure_ids {
        let at = dom
            .find(&format!("id=\"{id}\""))
            .unwrap_or_else(|| panic!("rendered DOM lacks {id}"));
        assert!(dom[at..].contains("<svg"), "{id} has no SVG in the DOM");
    }
    assert_eq!(dom.matches("<svg").count(), files.figure_ids.len());
    let png = dir.join("report.png");
    run(&[
        format!("--screenshot={}", png.display()),
        "--window-size=1200,5200".to_string(),
    ]);
    let bytes = std::fs::read(&png).expect("screenshot written");
    assert!(bytes.starts_with(b"\x89PNG\r\n\x1a\n"), "not a PNG");
    assert!(
        bytes.len() > 50_000,
        "screenshot suspiciously small: {} bytes",
        bytes.len()
    );
}

/// A manifest with the App. B.2 geometry columns: the base diameter is
/// √(d1·d2) and the height is what `nlvid_afm` computes from the two JPK
/// curves (or, if it cannot, a flag on the cell, which still counts).
#[test]
fn a_manifest_with_geometry_columns_fills_height_and_diameter() {
    let f = fixture();
    let dir = scratch("manifest");
    let afm = Path::new(env!("CARGO_MANIFEST_DIR")).join("../afm/tests/data");
    std::fs::copy(
        f.demo.join("data/A-stiff/a-stiff-01.csv"),
        dir.join("a.csv"),
    )
    .expect("copy");
    std::fs::copy(
        f.demo.join("data/A-stiff/a-stiff-02.csv"),
        dir.join("b.csv"),
    )
    .expect("copy");
    let cell = afm.join("fmt-jpk-sr_cell1-0008.jpk-force");
    let glass = afm.join("fmt-jpk-fd_spot3-0192.jpk-force");
    std::fs::write(
        dir.join("manifest.csv"),
        format!(
            "group,file,height_cell_curve,height_glass_curve,d1_um,d2_um\n\
             A,a.csv,{},{},12,27\nA,b.csv,,,,\n",
            cell.display(),
            glass.display()
        ),
    )
    .expect("manifest");
    let study = f.demo.join("study.toml");
    let settings = CohortSettings::load(&study).expect("settings");
    let cells = cohort::discover(&dir.join("manifest.csv")).expect("discover");
    let out = dir.join("out");
    cohort::run_cohort(
        &settings,
        &study,
        &dir.join("manifest.csv"),
        &cells,
        &out,
        &RunOptions::default(),
    )
    .expect("cohort");
    let res = cohort::read_cells(&out).expect("cells");
    let a = res.iter().find(|c| c.file == "a.csv").expect("a");
    let b = res.iter().find(|c| c.file == "b.csv").expect("b");
    assert_eq!(a.status, CellStatus::Ok, "{}", a.reason);
    assert!((a.base_diameter.expect("diameter") - 18e-6).abs() < 1e-15);
    let direct = nlvid_afm::read_force_curve(&cell).and_then(|c| {
        let g = nlvid_afm::read_force_curve(&glass)?;
        nlvid_afm::geometry::cell_height_from_curves(&c, &g, nlvid_afm::ContactMethod::default())
    });
    match direct {
        Ok(h) => assert_eq!(a.cell_height, Some(h)),
        Err(_) => {
            assert!(a.cell_height.is_none());
            assert!(
                a.flags.iter().any(|f| f.contains("cell height")),
                "{:?}",
                a.flags
            );
        }
    }
    assert!(b.cell_height.is_none() && b.base_diameter.is_none());
    let table = std::fs::read_to_string(out.join("results.csv")).expect("table");
    assert!(
        table
            .lines()
            .next()
            .expect("header")
            .contains("cell_height_m,base_diameter_m")
    );
    assert!(
        table.contains(&format!(",{},", 18e-6f64)) || table.contains(",0.000018,"),
        "{table}"
    );
}
