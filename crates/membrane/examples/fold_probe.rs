//! Probe of the ψc-controlled problem near the end of a slow QLV unloading
//! (D_max = 0.28, s_u = 1/5): D(ψc) and F(ψc) at the next time.
use nlvid_membrane::*;
fn main() -> Result<()> {
    let p = PipkinRogersParams {
        g1: 0.2,
        g2: 0.2,
        c: 1.0,
        ..Default::default()
    };
    let (dmax, su) = (0.28, 0.2);
    let args: Vec<String> = std::env::args().collect();
    let t_stop: f64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(1.113);
    let mut s = MembraneSolver::new(p.check()?, Geometry::default(), 1.0)?;
    let n = 200;
    let te = dmax + dmax / su;
    let mut times: Vec<f64> = (0..=n).map(|k| dmax * k as f64 / n as f64).collect();
    times.extend((1..=400).map(|k| dmax + (te - dmax) * k as f64 / 400.0));
    let mut last = 0.0;
    for &t in &times {
        if t > t_stop + 1e-12 {
            break;
        }
        let d = if t <= dmax { t } else { dmax - su * (t - dmax) };
        let sol = s.advance(t, Control::Displacement(d))?;
        last = t;
        if t > t_stop - 0.01 {
            println!(
                "t {t:.5} D {:.6} F {:.6} psic {:.6}",
                sol.displacement, sol.force, sol.psi_c
            );
        }
    }
    let tn = last + (te - dmax) / 400.0;
    for k in 0..=30 {
        let psi = 0.24 + 0.003 * k as f64;
        match s.equilibrium(tn, Control::ContactAngle(psi)) {
            Ok(sol) => println!(
                "psi {psi:.4} D {:.6} F {:.6} p {:.5} lam0 {:.6} minT {:.4}",
                sol.displacement,
                sol.force,
                sol.pressure,
                sol.lambda0,
                sol.profile
                    .iter()
                    .fold(f64::INFINITY, |m, v| m.min(v.t1).min(v.t2))
            ),
            Err(e) => println!("psi {psi:.4} error {e}"),
        }
    }
    Ok(())
}
