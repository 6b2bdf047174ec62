//! Exploration of Table 2.1 / Figs. 2.13–2.14: full load–unload curves with
//! tension histories, written as CSV to the directory given as first argument.
//!
//! `cargo run --release -p nlvid-membrane --example unload_explore -- OUT [nsteps_unload]`
use nlvid_membrane::*;
use std::io::Write;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let out = std::path::PathBuf::from(args.get(1).map(String::as_str).unwrap_or("unload_out"));
    let nu: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(400);
    let nl: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(200);
    // "compress": accept compression in the contact region (thesis-like).
    let compress = args.get(4).map(String::as_str) == Some("compress");
    let only: Option<&str> = args.get(5).map(String::as_str);
    std::fs::create_dir_all(&out).map_err(|e| MembraneError::Input {
        name: "out",
        value: 0.0,
        reason: e.to_string(),
    })?;
    let base = PipkinRogersParams::default();
    let cases = [
        (
            "NLE",
            PipkinRogersParams {
                g1: 1.0,
                g2: 1.0,
                ..base
            },
        ),
        (
            "QLV",
            PipkinRogersParams {
                g1: 0.2,
                g2: 0.2,
                c: 1.0,
                ..base
            },
        ),
        (
            "NLVc1",
            PipkinRogersParams {
                g1: 0.2,
                g2: 0.6,
                c: 1.0,
                ..base
            },
        ),
        (
            "NLVc05",
            PipkinRogersParams {
                g1: 0.2,
                g2: 0.6,
                c: 0.5,
                ..base
            },
        ),
    ];
    for dmax in [0.28, 0.78] {
        for su in [1.0, 0.2] {
            for (name, p) in &cases {
                if *name == "NLE" && su < 0.5 {
                    continue;
                }
                if only.is_some_and(|o| !format!("{name}_D{dmax}_su{su}").contains(o)) {
                    continue;
                }
                let tp = dmax;
                let te = tp + dmax / su;
                let mut solver = MembraneSolver::new(p.check()?, Geometry::default(), 1.0)?;
                solver.allow_compression_in_contact = compress;
                let mut times: Vec<f64> = (0..=nl).map(|k| tp * k as f64 / nl as f64).collect();
                times.extend((1..=nu).map(|k| tp + (te - tp) * k as f64 / nu as f64));
                let fname = out.join(format!("{name}_D{dmax}_su{su}.csv"));
                let mut f = std::fs::File::create(&fname).map_err(|e| MembraneError::Input {
                    name: "out",
                    value: 0.0,
                    reason: e.to_string(),
                })?;
                writeln!(
                    f,
                    "t,D,F,psi_c,p,lambda0,min_t1,psi_min_t1,min_t2,psi_min_t2,t1_crown,t2_eq"
                )
                .ok();
                let mut note = String::new();
                for &t in &times {
                    let d = if t <= tp { t } else { dmax - su * (t - tp) };
                    match solver.advance(t, Control::Displacement(d)) {
                        Ok(s) => {
                            let (mut m1, mut p1, mut m2, mut p2) =
                                (f64::INFINITY, 0.0, f64::INFINITY, 0.0);
                            for v in &s.profile {
                                if v.t1 < m1 {
                                    m1 = v.t1;
                                    p1 = v.psi;
                                }
                                if v.t2 < m2 {
                                    m2 = v.t2;
                                    p2 = v.psi;
                                }
                            }
                            let last = s.profile.last().map(|v| v.t2).unwrap_or(f64::NAN);
                            writeln!(
                                f,
                                "{t},{},{},{},{},{},{m1},{p1},{m2},{p2},{},{last}",
                                s.record.displacement,
                                s.record.force,
                                s.record.psi_c,
                                s.record.pressure,
                                s.record.lambda0,
                                s.profile[0].t1
                            )
                            .ok();
                        }
                        Err(e) => {
                            note = format!("stopped at t = {t}, D = {d}: {e}");
                            break;
                        }
                    }
                }
                println!(
                    "{name} D={dmax} su={su}: {}",
                    if note.is_empty() { "complete" } else { &note }
                );
            }
        }
    }
    Ok(())
}
