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

/// Optional dimensional scales: r0, h0, G10 = G1(0), τ1.
#[derive(Debug, Clone, Copy)]
struct Scales {
    r0: f64,
    h0: f64,
    g10: f64,
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
    // One name, one quantity (docs/theory/model.md): g1, g2 name Prony
    // weights elsewhere; here they are eq. 2.56's long-term fractions.
    for k in ["g1", "g2"] {
        m.renamed(
            k,
            &format!("{k}_long_term"),
            "eq. 2.56's long-term fraction G(∞)/G(0); `g1`, `g2` name Prony weights",
        )?;
    }
    for k in ["C1", "G10"] {
        m.renamed(
            k,
            "[membrane.scale] G10",
            "the material is dimensionless (G10 = G1(0) = 1, eq. 2.47); a modulus sets the scale",
        )?;
    }
    let params = PipkinRogersParams {
        g10: 1.0,
        tau1: 1.0,
        gamma0: m.f64_or("gamma0", Bounds::non_negative(), 0.1)?,
        g1: m.f64_or("g1_long_term", Bounds::open_closed(0.0, 1.0), 1.0)?,
        g2: m.f64_or("g2_long_term", Bounds::open_closed(0.0, 1.0), 1.0)?,
        c: m.f64_or("c", Bounds::positive(), 1.0)?,
        a: m.f64_or("a", Bounds::non_negative(), 0.0)?,
    };
    m.finish()?;
    let scales = match s.opt_subsection("scale")? {
        Some(mut sc) => {
            for k in ["c1", "C1"] {
                sc.renamed(
                    k,
                    "G10",
                    "ch. II's stress scale is G1(0) = G10; `C1` names the constant of eq. 4.1",
                )?;
            }
            let v = Scales {
                r0: sc.req_quantity("r0", Dimension::LENGTH, Bounds::positive())?,
                h0: sc.req_quantity("h0", Dimension::LENGTH, Bounds::positive())?,
                g10: sc.req_quantity("G10", Dimension::PRESSURE, Bounds::positive())?,
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
        "t0,D_over_r0,H1_over_r0,F_over_G10h0r0,p_r0_over_G10h0,psi_c_rad,lambda0,a_over_r0,r_eq_over_r0,min_tension_over_G10h0",
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
                r.force * c.g10 * c.h0 * c.r0,
                r.pressure * c.g10 * c.h0 / c.r0,
                r.contact_radius * c.r0
            );
        }
        s.push('\n');
    }
    s
}

fn profile_csv(sol: &nlvid_membrane::Solution) -> String {
    let mut s = String::from(
        "psi_rad,rho_over_r0,eta_over_r0,lambda1,lambda2,sigma1_over_G10,sigma2_over_G10,T1_over_G10h0,T2_over_G10h0,theta_rad,in_contact\n",
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
            "t0 = {:.4}: D/r0 = {:.5}, F/(G10 h0 r0) = {:.6}, ψc = {:.5} rad, p = {:.5}; wrote {} files to {}",
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
        let svg = nlvid_membrane::plot::svg(f).with_context(|| format!("drawing {}", f.id))?;
        write_atomic(&args.out.join(format!("{}.svg", f.id)), &svg)?;
        files.push(format!("{}.csv", f.id));
        files.push(format!("{}.svg", f.id));
    }
    let mut t = String::from(
        "D_over_r0,unloading_rate,model,thesis_slope,tangent_slope,secant_slope_dD_0.01,secant_over_2_div_thesis\n",
    );
    for r in &rows {
        let _ = writeln!(
            t,
            "{},{},{},{},{},{},{}",
            r.d_max,
            r.unload_rate,
            r.model,
            r.thesis.map(|v| v.to_string()).unwrap_or_default(),
            r.slope,
            r.secant,
            r.ratio.map(|v| v.to_string()).unwrap_or_default()
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
        println!(
            "Table 2.1 (initial unloading slope dF̄/dD̄: tangent over the first step, secant over ΔD/r0 = 0.01; ratio = secant/2 ÷ thesis):"
        );
        for r in &rows {
            println!(
                "  D/r0 = {:.2}, s_u = {:.1}, {:<10} thesis {:>7}  tangent {:8.2}  secant {:8.2}  ratio {}",
                r.d_max,
                r.unload_rate,
                r.model,
                r.thesis.map(|v| v.to_string()).unwrap_or("-".into()),
                r.slope,
                r.secant,
                r.ratio.map(|v| format!("{v:.3}")).unwrap_or("-".into())
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
