//! Which Prony parameters can a 2 % noisy ramp-hold curve pin down?
//! Prints singular values of the value-scaled sensitivity, the condition
//! number and 95 % relative half-widths at the fitted optimum.
//!
//! Run: `cargo run -p nlvid-inverse --release --example identifiability_lee_radok`

use nlvid_inverse::{
    Experiment, LeeRadokHertz, Misfit, Model, MultiStart, SensitivityScaling, identifiability,
    ramp_hold_grid, ramp_hold_indentation,
};
use nlvid_model::Domain;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let domain = Domain::table_5_3(0.01)?;
    let t = ramp_hold_grid(0.2, 199, 52.0, 4895, 1e-3)?;
    let delta = ramp_hold_indentation(&t, 10e-6, 2e-6);
    let cases = [
        ("slow tau1", [1000.0, 0.4, 0.3, 0.5, 10.0]),
        (
            "fast tau1 (0.012 s << 0.2 s ramp)",
            [1000.0, 0.4, 0.3, 0.012, 10.0],
        ),
        ("small g2", [1000.0, 0.4, 0.02, 0.5, 10.0]),
        ("g1 + g2 = 0.98", [1000.0, 0.6, 0.38, 0.5, 10.0]),
    ];
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    println!(
        "| case | singular values | condition | 95 % half-width / value (G0, g1, tau1, g2, tau2) |"
    );
    println!("|---|---|---|---|");
    for (name, x) in cases {
        let m = LeeRadokHertz::new(domain.clone(), t.clone(), &delta, 2.5e-6, 0.5)?;
        let clean = m.response(&x)?;
        let peak = clean.iter().cloned().fold(0.0, f64::max);
        let data = clean
            .iter()
            .map(|y| {
                let u1: f64 = 1.0 - rng.random::<f64>();
                let u2: f64 = rng.random();
                y + 0.02 * peak * (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
            })
            .collect();
        let misfit = Misfit::new(vec![Experiment::new("RH", m, data, None)?])?;
        let fit = MultiStart::new().with_starts(8)?.fit(&misfit)?;
        let id = identifiability(&misfit, &fit.best.x, SensitivityScaling::Value)?;
        let sv: Vec<String> = id
            .singular_values
            .iter()
            .map(|s| format!("{s:.2e}"))
            .collect();
        let hw: Vec<String> = id
            .relative_half_widths()
            .iter()
            .map(|w| format!("{:.1} %", 100.0 * w))
            .collect();
        println!(
            "| {name} | {} | {:.1e} | {} |",
            sv.join(", "),
            id.condition_number,
            hw.join(", ")
        );
    }
    Ok(())
}
