//! `nlvid membrane`: the semi-analytical fluid-filled membrane between plates
//! (thesis ch. II, §2.3) for one study, or `--reproduce thesis` to regenerate
//! the data and plots of Figs. 2.3–2.14 and Table 2.1.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, bail};
use clap::{Args, ValueEnum};
use nlvid_membrane::thesis::{Figure, SlopeRow};
use nlvid_membrane::{ControlKind, Geometry, Loading, MembraneRun, PipkinRogersParams, simulate};
use nlvid_protocol::{Quantity, programs};
use nlvid_study::{Bounds, Dimension, Study};

/// Arguments of `nlvid membrane`.
#[derive(Debug, Args)]
pub struct MembraneArgs {
    /// Study file with a `[membrane]` section (see docs/cli/membrane.md).
    #[arg(required_unless_present = "reproduce")]
    pub study: Option<PathBuf>,
    /// Regenerate a published data set instead of running a study.
    #[arg(long, value_enum)]
    pub reproduce: Option<Reproduce>,
    /// Output directory for CSV (and SVG) files.
    #[arg(long, default_value = "membrane-out")]
    pub out: PathBuf,
    /// Set from the global `--json` flag.
    #[arg(skip)]
    pub json: bool,
}

/// Published data sets.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum Reproduce {
    /// Figs. 2.3–2.14 and Table 2.1 of the thesis.
    Thesis,
}

/// Optional dimensional scales: r0, h0, C1, τ1.
#[derive(Debug, Clone, Copy)]
struct Scales {
    r0: f64,
    h0: f64,
    c1: f64,
    tau1: f64,
}

struct MembraneStudy {
    params: PipkinRogersParams,
    geometry: Geometry,
    loading: Loading,
    scales: Option<Scales>,
}

fn read_study(path: &Path) -> anyhow::Result<MembraneStudy> {
    let mut study = Study::load(path)?;
    let mut s = study.section("membrane")?;
    let rs = s.f64_or("rs", Bounds::closed_open(1.0, 3.0), 1.03)?;
    let nodes = s
        .opt_usize("nodes", Bounds::closed(8.0, 100_000.0))?
        .unwrap_or(64);
    let control = s
        .opt_enum(
            "control",
            &[
                ("displacement", ControlKind::Displacement),
                ("force", ControlKind::Force),
            ],
        )?
        .unwrap_or(ControlKind::Displacement);
    let program = s.req_str("program")?;
    let value = s.req_f64("value", Bounds::non_negative())?;
    let t_end = s.req_f64("t_end", Bounds::positive())?;
    let steps = s
        .opt_usize("steps", Bounds::closed(1.0, 1e7))?
        .unwrap_or(100);
    let prog = match program.as_str() {
        "step" => programs::step(Quantity::Dimensionless, value, t_end),
        "ramp" => {
            let rate = s.req_f64("rate", Bounds::positive())?;
            programs::constant_rate(Quantity::Dimensionless, rate, t_end)
        }
        "ramp-hold" => {
            let rate = s.req_f64("rate", Bounds::positive())?;
            programs::ramp_hold(
                Quantity::Dimensionless,
                value,
                rate,
                (t_end - value / rate).max(1e-9),
            )
        }
        "load-unload" => {
            let rate = s.req_f64("rate", Bounds::positive())?;
            let unload = s.req_f64("unload_rate", Bounds::positive())?;
            programs::load_unload(Quantity::Dimensionless, value, rate, unload, 0.0)
        }
        other => {
            return Err(s
                .invalid(
                    "program",
                    format!("unknown program `{other}` (step, ramp, ramp-hold, load-unload)"),
                )
                .into());
        }
    }
    .with_context(|| format!("{}: key `membrane.program`", path.display()))?;
    let profile_times = if s.has("profile_times") {
        s.req_f64s("profile_times", Bounds::non_negative())?
    } else {
        vec![t_end]
    };
    let mut m = s.subsection("material")?;
    let params = PipkinRogersParams {
        c1: 1.0,
        tau1: 1.0,
        gamma0: m.f64_or("gamma0", Bounds::non_negative(), 0.1)?,
        g1: m.f64_or("g1", Bounds::open_closed(0.0, 1.0), 1.0)?,
        g2: m.f64_or("g2", Bounds::open_closed(0.0, 1.0), 1.0)?,
        c: m.f64_or("c", Bounds::positive(), 1.0)?,
        a: m.f64_or("a", Bounds::non_negative(), 0.0)?,
    };
    m.finish()?;
    let scales = match s.opt_subsection("scale")? {
        Some(mut sc) => {
            let v = Scales {
                r0: sc.req_quantity("r0", Dimension::LENGTH, Bounds::positive())?,
                h0: sc.req_quantity("h0", Dimension::LENGTH, Bounds::positive())?,
                c1: sc.req_quantity("c1", Dimension::PRESSURE, Bounds::positive())?,
                tau1: sc.req_quantity("tau1", Dimension::TIME, Bounds::positive())?,
            };
            sc.finish()?;
            Some(v)
        }
        None => None,
    };
    s.finish()?;
    let times = (0..=steps)
        .map(|k| t_end * k as f64 / steps as f64)
        .collect();
    let loading = Loading::new(control, prog, times)?.with_profiles(&profile_times);
    Ok(MembraneStudy {
        params,
        geometry: Geometry { rs, nodes },
        loading,
        scales,
    })
}

fn write_atomic(path: &Path, text: &str) -> anyhow::Result<()> {
    crate::output::write_atomic(path, text.as_bytes())
}

fn history_csv(run: &MembraneRun, sc: Option<Scales>) -> String {
    let mut s = String::from(
        "t0,D_over_r0,H1_over_r0,F_over_C1h0r0,p_r0_over_C1h0,psi_c_rad,lambda0,a_over_r0,r_eq_over_r0,min_tension_over_C1h0",
    );
    if sc.is_some() {
        s.push_str(",t_s,D_m,F_N,p_Pa,a_m");
    }
    s.push('\n');
    for r in &run.history {
        let _ = write!(
            s,
            "{},{},{},{},{},{},{},{},{},{}",
            r.time,
            r.displacement,
            r.h1,
            r.force,
            r.pressure,
            r.psi_c,
            r.lambda0,
            r.contact_radius,
            r.equator_radius,
            r.min_tension
        );
        if let Some(c) = sc {
            let _ = write!(
                s,
                ",{},{},{},{},{}",
                r.time * c.tau1,
                r.displacement * c.r0,
                r.force * c.c1 * c.h0 * c.r0,
                r.pressure * c.c1 * c.h0 / c.r0,
                r.contact_radius * c.r0
            );
        }
        s.push('\n');
    }
    s
}

fn profile_csv(sol: &nlvid_membrane::Solution) -> String {
    let mut s = String::from(
        "psi_rad,rho_over_r0,eta_over_r0,lambda1,lambda2,sigma1_over_C1,sigma2_over_C1,T1_over_C1h0,T2_over_C1h0,theta_rad,in_contact\n",
    );
    for v in &sol.profile {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{}",
            v.psi,
            v.rho,
            v.eta,
            v.lambda1,
            v.lambda2,
            v.sigma1,
            v.sigma2,
            v.t1,
            v.t2,
            v.theta,
            u8::from(v.psi <= sol.psi_c)
        );
    }
    s
}

fn run_study(args: &MembraneArgs, path: &Path) -> anyhow::Result<ExitCode> {
    let st = read_study(path)?;
    let run = simulate(&st.params, &st.geometry, &st.loading)
        .with_context(|| format!("study {}", path.display()))?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    write_atomic(&args.out.join("history.csv"), &history_csv(&run, st.scales))?;
    let mut files = vec!["history.csv".to_string()];
    for sol in &run.profiles {
        let name = format!("profile_t{:.4}.csv", sol.time);
        write_atomic(&args.out.join(&name), &profile_csv(sol))?;
        files.push(name);
    }
    let last = run.history.last().copied();
    if args.json {
        let summary = serde_json::json!({
            "study": path.display().to_string(),
            "params": st.params,
            "geometry": st.geometry,
            "steps": run.history.len(),
            "final": last,
            "files": files,
            "out": args.out.display().to_string(),
        });
        println!("{}", serde_json::to_string_pretty(&summary)?);
    } else if let Some(l) = last {
        println!(
            "t0 = {:.4}: D/r0 = {:.5}, F/(C1 h0 r0) = {:.6}, ψc = {:.5} rad, p = {:.5}; wrote {} files to {}",
            l.time,
            l.displacement,
            l.force,
            l.psi_c,
            l.pressure,
            files.len(),
            args.out.display()
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// A minimal SVG line plot (no font or system dependencies).
fn svg_plot(f: &Figure) -> String {
    let (w, h, ml, mr, mt, mb) = (720.0, 480.0, 70.0, 200.0, 40.0, 50.0);
    let pts = f.series.iter().flat_map(|s| s.x.iter().zip(&s.y));
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for (x, y) in pts {
        if x.is_finite() && y.is_finite() {
            x0 = x0.min(*x);
            x1 = x1.max(*x);
            y0 = y0.min(*y);
            y1 = y1.max(*y);
        }
    }
    if x1.partial_cmp(&x0) != Some(std::cmp::Ordering::Greater) {
        x1 = x0 + 1.0;
    }
    if y1.partial_cmp(&y0) != Some(std::cmp::Ordering::Greater) {
        y1 = y0 + 1.0;
    }
    let px = |x: f64| ml + (x - x0) / (x1 - x0) * (w - ml - mr);
    let py = |y: f64| h - mb - (y - y0) / (y1 - y0) * (h - mt - mb);
    let colors = [
        "#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf",
    ];
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"sans-serif\" font-size=\"12\">\n\
         <rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n\
         <text x=\"{}\" y=\"20\" text-anchor=\"middle\" font-size=\"14\">{}</text>\n\
         <rect x=\"{ml}\" y=\"{mt}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"black\"/>\n",
        w / 2.0,
        xml(&f.title),
        w - ml - mr,
        h - mt - mb
    );
    for k in 0..=4 {
        let fx = x0 + (x1 - x0) * k as f64 / 4.0;
        let fy = y0 + (y1 - y0) * k as f64 / 4.0;
        let _ = writeln!(
            s,
            "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{}</text>",
            px(fx),
            h - mb + 16.0,
            num(fx)
        );
        let _ = writeln!(
            s,
            "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">{}</text>",
            ml - 4.0,
            py(fy) + 4.0,
            num(fy)
        );
    }
    let _ = writeln!(
        s,
        "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{}</text>",
        (ml + w - mr) / 2.0,
        h - 10.0,
        xml(&f.x_label)
    );
    let _ = writeln!(
        s,
        "<text x=\"14\" y=\"{:.1}\" transform=\"rotate(-90 14 {:.1})\" text-anchor=\"middle\">{}</text>",
        h / 2.0,
        h / 2.0,
        xml(&f.y_label)
    );
    for (i, ser) in f.series.iter().enumerate() {
        let c = colors[i % colors.len()];
        if ser.x.len() == 1 {
            let _ = writeln!(
                s,
                "<circle cx=\"{:.2}\" cy=\"{:.2}\" r=\"4\" fill=\"{c}\"/>",
                px(ser.x[0]),
                py(ser.y[0])
            );
        } else {
            let path: Vec<String> = ser
                .x
                .iter()
                .zip(&ser.y)
                .map(|(x, y)| format!("{:.2},{:.2}", px(*x), py(*y)))
                .collect();
            let _ = writeln!(
                s,
                "<polyline fill=\"none\" stroke=\"{c}\" stroke-width=\"1.5\" points=\"{}\"/>",
                path.join(" ")
            );
        }
        let ly = mt + 14.0 * i as f64 + 10.0;
        let _ = writeln!(
            s,
            "<line x1=\"{}\" y1=\"{ly}\" x2=\"{}\" y2=\"{ly}\" stroke=\"{c}\" stroke-width=\"2\"/>",
            w - mr + 8.0,
            w - mr + 28.0
        );
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{}\" font-size=\"10\">{}</text>",
            w - mr + 32.0,
            ly + 4.0,
            xml(&ser.label)
        );
    }
    s.push_str("</svg>\n");
    s
}

fn num(v: f64) -> String {
    if v != 0.0 && (v.abs() >= 1e4 || v.abs() < 1e-2) {
        format!("{v:.2e}")
    } else {
        format!("{v:.3}")
    }
}

fn xml(t: &str) -> String {
    t.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

fn figure_csv(f: &Figure) -> String {
    let mut s = String::from("series,x,y\n");
    for ser in &f.series {
        for (x, y) in ser.x.iter().zip(&ser.y) {
            let _ = writeln!(s, "\"{}\",{},{}", ser.label.replace('"', "'"), x, y);
        }
    }
    s
}

fn run_reproduce(args: &MembraneArgs) -> anyhow::Result<ExitCode> {
    let (figs, rows, notes): (Vec<Figure>, Vec<SlopeRow>, Vec<String>) =
        nlvid_membrane::thesis::reproduce().context("reproducing ch. II")?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let mut files = Vec::new();
    for f in &figs {
        write_atomic(&args.out.join(format!("{}.csv", f.id)), &figure_csv(f))?;
        write_atomic(&args.out.join(format!("{}.svg", f.id)), &svg_plot(f))?;
        files.push(format!("{}.csv", f.id));
        files.push(format!("{}.svg", f.id));
    }
    let mut t = String::from("D_over_r0,unloading_rate,model,thesis_slope,slope\n");
    for r in &rows {
        let _ = writeln!(
            t,
            "{},{},{},{},{}",
            r.d_max,
            r.unload_rate,
            r.model,
            r.thesis.map(|v| v.to_string()).unwrap_or_default(),
            r.slope
        );
    }
    write_atomic(&args.out.join("table2_1.csv"), &t)?;
    files.push("table2_1.csv".into());
    let notes_text: String = notes.iter().map(|n| format!("{n}\n")).collect();
    write_atomic(&args.out.join("notes.txt"), &notes_text)?;
    files.push("notes.txt".into());
    for n in &notes {
        eprintln!("note: {n}");
    }
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(
                &serde_json::json!({ "files": files, "table2_1": rows, "notes": notes, "out": args.out.display().to_string() })
            )?
        );
    } else {
        println!("Table 2.1 (initial unloading slope dF/dD over the first unloading step):");
        for r in &rows {
            println!(
                "  D/r0 = {:.2}, s_u = {:.1}, {:<10} thesis {:>7}  ours {:8.2}",
                r.d_max,
                r.unload_rate,
                r.model,
                r.thesis.map(|v| v.to_string()).unwrap_or("-".into()),
                r.slope
            );
        }
        println!("wrote {} files to {}", files.len(), args.out.display());
    }
    Ok(ExitCode::SUCCESS)
}

/// Run `nlvid membrane`.
pub fn run(args: MembraneArgs) -> anyhow::Result<ExitCode> {
    match (&args.reproduce, &args.study) {
        (Some(Reproduce::Thesis), _) => run_reproduce(&args),
        (None, Some(p)) => run_study(&args, &p.clone()),
        (None, None) => bail!("give a study file or --reproduce thesis"),
    }
}
