//! Compares the `slsqp` and `cobyla` crates on bounded, linearly
//! constrained test problems with known optima (docs/theory/inverse.md).
//!
//! Run: `cargo run -p nlvid-inverse --release --example compare_optimisers`

use std::time::Instant;

use nlvid_inverse::{
    Experiment, LeeRadokHertz, Misfit, Model, feasible_starts, ramp_hold_grid,
    ramp_hold_indentation,
};
use nlvid_model::Domain;

/// f(u, ∇f) or c(u, ∇c) in scaled coordinates.
type ScaledFn<'a> = Box<dyn Fn(&[f64], Option<&mut [f64]>) -> f64 + 'a>;

/// A problem in scaled coordinates u ∈ [0, 1]ⁿ with a constraint c(u) ≤ 0.
struct Problem<'a> {
    name: &'static str,
    n: usize,
    f: ScaledFn<'a>,
    /// (c(u), ∇c) with c ≤ 0 feasible.
    c: ScaledFn<'a>,
    u_star: Vec<f64>,
    f_star: f64,
    starts: Vec<Vec<f64>>,
}

struct Tally {
    success: usize,
    evals: usize,
    seconds: f64,
}

/// Runs `minimize` (start, evaluation counter → end point) from every start
/// of `p`: successes, evaluations and time.
fn tally(p: &Problem, minimize: impl Fn(&[f64], &std::cell::Cell<usize>) -> Vec<f64>) -> Tally {
    let mut t = Tally {
        success: 0,
        evals: 0,
        seconds: 0.0,
    };
    for u0 in &p.starts {
        let count = std::cell::Cell::new(0usize);
        let start = Instant::now();
        let u = minimize(u0, &count);
        t.seconds += start.elapsed().as_secs_f64();
        t.evals += count.get();
        t.success += usize::from(hit(p, &u));
    }
    t
}

fn run_slsqp(p: &Problem) -> Tally {
    tally(p, |u0, count| {
        let f = |u: &[f64], g: Option<&mut [f64]>, _: &mut ()| {
            count.set(count.get() + 1);
            (p.f)(u, g)
        };
        let c = |u: &[f64], g: Option<&mut [f64]>, _: &mut ()| (p.c)(u, g);
        let cons: Vec<&dyn slsqp::Func<()>> = vec![&c];
        let tols = slsqp::StopTols {
            ftol_rel: 1e-10,
            xtol_abs: vec![1e-7; p.n],
            ..Default::default()
        };
        let out = slsqp::minimize(f, u0, &vec![(0.0, 1.0); p.n], &cons, (), 2000, Some(tols));
        match out {
            Ok((_, u, _)) | Err((_, u, _)) => u,
        }
    })
}

fn run_cobyla(p: &Problem) -> Tally {
    tally(p, |u0, count| {
        let f = |u: &[f64], _: &mut ()| {
            count.set(count.get() + 1);
            (p.f)(u, None)
        };
        let c = |u: &[f64], _: &mut ()| -(p.c)(u, None);
        let cons: Vec<&dyn cobyla::Func<()>> = vec![&c];
        let tols = cobyla::StopTols {
            ftol_rel: 1e-10,
            xtol_abs: vec![1e-7; p.n],
            ..Default::default()
        };
        let out = cobyla::minimize(
            f,
            u0,
            &vec![(0.0, 1.0); p.n],
            &cons,
            (),
            2000,
            cobyla::RhoBeg::All(0.1),
            Some(tols),
        );
        match out {
            Ok((_, u, _)) | Err((_, u, _)) => u,
        }
    })
}

fn hit(p: &Problem, u: &[f64]) -> bool {
    let f = (p.f)(u, None);
    let dx = u
        .iter()
        .zip(&p.u_star)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    (f - p.f_star).abs() <= 1e-6 * (1.0 + p.f_star.abs()) && dx <= 1e-3 && (p.c)(u, None) <= 1e-8
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let n_starts = 20;
    let box_domain = |n: usize| {
        Domain::new(
            (0..n)
                .map(|i| {
                    nlvid_model::Parameter::new(
                        &format!("u{i}"),
                        "",
                        0.0,
                        1.0,
                        nlvid_model::Scale::Linear,
                    )
                })
                .collect(),
        )
    };

    // 1. Weighted quadratic, optimum on u0 + u2 = 1 (KKT closed form).
    let cq = [1.0, 4.0, 2.0, 0.5, 8.0];
    let pq = [0.8, 0.3, 0.6, 0.7, 0.45];
    let lambda = 2.0 * (pq[0] + pq[2] - 1.0) / (1.0 / cq[0] + 1.0 / cq[2]);
    let mut uq = pq.to_vec();
    uq[0] -= lambda / (2.0 * cq[0]);
    uq[2] -= lambda / (2.0 * cq[2]);
    let fq = |u: &[f64], g: Option<&mut [f64]>| {
        if let Some(g) = g {
            for i in 0..5 {
                g[i] = 2.0 * cq[i] * (u[i] - pq[i]);
            }
        }
        (0..5).map(|i| cq[i] * (u[i] - pq[i]).powi(2)).sum()
    };
    let quad_star = fq(&uq, None);
    let sum_c = |u: &[f64], g: Option<&mut [f64]>| {
        if let Some(g) = g {
            g.fill(0.0);
            g[0] = 1.0;
            g[2] = 1.0;
        }
        u[0] + u[2] - 1.0
    };
    let d5 = box_domain(5)?.with_sum_constraint(&["u0", "u2"], 1.0)?;

    // 2. Rosenbrock 5-D on x = 4u - 2 ∈ [-2, 2], constraint x0 + x1 <= 2.5
    //    (inactive at the optimum x = 1).
    let fr = |u: &[f64], g: Option<&mut [f64]>| {
        let x: Vec<f64> = u.iter().map(|v| 4.0 * v - 2.0).collect();
        let mut f = 0.0;
        let mut gx = [0.0; 5];
        for i in 0..4 {
            f += 100.0 * (x[i + 1] - x[i] * x[i]).powi(2) + (1.0 - x[i]).powi(2);
            gx[i] += -400.0 * x[i] * (x[i + 1] - x[i] * x[i]) - 2.0 * (1.0 - x[i]);
            gx[i + 1] += 200.0 * (x[i + 1] - x[i] * x[i]);
        }
        if let Some(g) = g {
            for i in 0..5 {
                g[i] = 4.0 * gx[i];
            }
        }
        f
    };
    let rosen_c = |u: &[f64], g: Option<&mut [f64]>| {
        if let Some(g) = g {
            g.fill(0.0);
            g[0] = 4.0;
            g[1] = 4.0;
        }
        (4.0 * u[0] - 2.0) + (4.0 * u[1] - 2.0) - 2.5
    };

    // 3. Noise-free Lee–Radok recovery (misfit 0 at the truth).
    let domain = Domain::table_5_3(0.01)?;
    let t = ramp_hold_grid(0.2, 199, 52.0, 4895, 1e-3)?;
    let delta = ramp_hold_indentation(&t, 10e-6, 2e-6);
    let model = LeeRadokHertz::new(domain.clone(), t, &delta, 2.5e-6, 0.5)?;
    let x_true = [650.0, 0.45, 0.35, 0.08, 9.0];
    let data = model.response(&x_true)?;
    let misfit = Misfit::new(vec![Experiment::new("RH", model, data, None)?])?;
    let fl = |u: &[f64], g: Option<&mut [f64]>| {
        let x = domain.from_unit(u);
        match g {
            Some(g) => match misfit.value_and_gradient(&x) {
                Ok((v, gx)) => {
                    for (k, p) in domain.params().iter().enumerate() {
                        g[k] = gx[k] * p.dx_du(u[k]);
                    }
                    v
                }
                Err(_) => f64::INFINITY,
            },
            None => misfit.value(&x).unwrap_or(f64::INFINITY),
        }
    };
    let prony_c = |u: &[f64], g: Option<&mut [f64]>| {
        let x = domain.from_unit(u);
        if let Some(g) = g {
            g.fill(0.0);
            g[1] = domain.params()[1].dx_du(u[1]);
            g[3] = domain.params()[3].dx_du(u[3]);
        }
        x[1] + x[3] - 0.99
    };

    let problems = vec![
        Problem {
            name: "weighted quadratic, active constraint (5-D)",
            n: 5,
            f: Box::new(fq),
            c: Box::new(sum_c),
            u_star: uq,
            f_star: quad_star,
            starts: feasible_starts(&d5, n_starts, 1)?,
        },
        Problem {
            name: "Rosenbrock, inactive constraint (5-D)",
            n: 5,
            f: Box::new(fr),
            c: Box::new(rosen_c),
            u_star: vec![0.75; 5],
            f_star: 0.0,
            starts: feasible_starts(&box_domain(5)?, n_starts, 2)?,
        },
        Problem {
            name: "Lee-Radok Prony recovery, no noise (5-D, m = 5095)",
            n: 5,
            f: Box::new(fl),
            c: Box::new(prony_c),
            u_star: domain.to_unit(&x_true),
            f_star: 0.0,
            starts: feasible_starts(&domain, n_starts, 3)?
                .iter()
                .map(|x| domain.to_unit(x))
                .collect(),
        },
    ];

    println!("| problem | optimiser | success / starts | evaluations per run | time per run |");
    println!("|---|---|---|---|---|");
    for p in &problems {
        for (name, tally) in [
            ("SLSQP (gradient)", run_slsqp(p)),
            ("COBYLA (no gradient)", run_cobyla(p)),
        ] {
            println!(
                "| {} | {} | {}/{} | {:.0} | {:.3} ms |",
                p.name,
                name,
                tally.success,
                p.starts.len(),
                tally.evals as f64 / p.starts.len() as f64,
                1e3 * tally.seconds / p.starts.len() as f64
            );
        }
    }
    Ok(())
}
