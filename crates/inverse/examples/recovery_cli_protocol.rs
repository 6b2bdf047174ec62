//! Is the CLI recovery limited by the protocol or by the surrogate?
//! The ten seeded cases of `crates/cli/tests/it/fit.rs::ten_seeded_cases_…`
//! (same draws, same noise) fitted on the *real* model — Lee–Radok Hertz,
//! no surrogate — with the CLI's protocol (R = 5 µm, 1 µm/s for 1 s, hold
//! to 10 s) and its 100 grid points (0.1 … 10 s, via 0/1 weights on a
//! 1-ms Lee–Radok grid). Data from `nlvid_forward::HertzProny` (the same
//! kernel in its exact ramp-hold form; the fit's model samples δ^{3/2}
//! piecewise linearly) + 2 % noise.
//! Run: `cargo run -p nlvid-inverse --release --example recovery_cli_protocol`

use nlvid_forward::HertzProny;
use nlvid_inverse::{Experiment, LeeRadokHertz, Misfit, MultiStart, Result};
use nlvid_model::{Domain, ForwardModel};

/// SplitMix64 + Box–Muller, as in the CLI test.
struct Normal(u64);

impl Normal {
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        ((z >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    fn sample(&mut self) -> f64 {
        let (u1, u2) = (self.uniform(), self.uniform());
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

fn main() -> Result<()> {
    let domain = Domain::table_5_3(0.01)?;
    let fine: Vec<f64> = (0..=1000).map(|i| i as f64 * 0.01).collect();
    let delta: Vec<f64> = fine.iter().map(|t| 1e-6 * t.min(1.0)).collect();
    // The surrogate grid 0.1, 0.2, …, 10 s: every 10th fine point but t = 0.
    let weights: Vec<f64> = (0..=1000)
        .map(|i| if i > 0 && i % 10 == 0 { 1.0 } else { 0.0 })
        .collect();
    let hp = HertzProny::new(5e-6, 1e-6, 1.0, 10.0, 1000)
        .map_err(|e| nlvid_inverse::InverseError::InvalidSetting(e.to_string()))?;
    let mut rng = Normal(20261122);
    let log_uniform = |r: &mut Normal, lo: f64, hi: f64| lo * (hi / lo).powf(r.uniform());
    let (mut ok_issue, mut ok_g10, mut reached) = (0, 0, 0);
    for case in 0..10u64 {
        let (g1, g2) = loop {
            let (a, b) = (0.01 + 0.99 * rng.uniform(), 0.01 + 0.99 * rng.uniform());
            if a + b <= 0.99 {
                break (a, b);
            }
        };
        let g0 = log_uniform(&mut rng, 80.0, 4000.0);
        let tau1 = log_uniform(&mut rng, 0.01, 2.0);
        let tau2 = log_uniform(&mut rng, 2.0, 40.0);
        let mut clean = vec![0.0];
        clean.extend(
            hp.run(&[g0, g1, g2, tau1, tau2])
                .map_err(|e| nlvid_inverse::InverseError::InvalidSetting(e.to_string()))?,
        );
        let peak = clean.iter().copied().fold(0.0, f64::max);
        let mut noise = Normal(100 + case);
        let data: Vec<f64> = clean
            .iter()
            .map(|f| f + 0.02 * peak * noise.sample())
            .collect();
        let model = LeeRadokHertz::new(domain.clone(), fine.clone(), &delta, 5e-6, 0.5)?;
        let misfit = Misfit::new(vec![Experiment::new(
            "RH",
            model,
            data,
            Some(weights.clone()),
        )?])?;
        let truth = [g0, g1, g2, tau1, tau2];
        let at_truth = misfit.value(&truth)?;
        let fit = MultiStart::new()
            .with_starts(8)?
            .with_seed(1)
            .fit(&misfit)?;
        let x = &fit.best.x;
        let (gt, gf) = (
            nlvid_inverse::relaxation(&domain, &truth)?,
            nlvid_inverse::relaxation(&domain, x)?,
        );
        let e_g0 = x[0] / g0 - 1.0;
        let e_sum = x[1] + x[2] - g1 - g2;
        let e52 = gf.value(52.0) / gt.value(52.0) - 1.0;
        let e10 = gf.value(10.0) / gt.value(10.0) - 1.0;
        let pass = e_g0.abs() <= 0.05 && e_sum.abs() <= 0.03;
        ok_issue += usize::from(pass && e52.abs() <= 0.05);
        ok_g10 += usize::from(pass && e10.abs() <= 0.05);
        reached += usize::from(fit.best.misfit <= at_truth * (1.0 + 1e-6));
        println!(
            "case {case}: G0 {:+.1} %, Δsum {e_sum:+.3}, G(52) {:+.1} %, G(10) {:+.1} %; misfit {:.3} % (truth {:.3} %)",
            100.0 * e_g0,
            100.0 * e52,
            100.0 * e10,
            100.0 * fit.best.misfit,
            100.0 * at_truth
        );
    }
    println!(
        "real model, CLI protocol: recovered (G0 5 %, sum 0.03, G(52 s) 5 %) {ok_issue}/10; \
         with G(10 s) {ok_g10}/10; optimiser at or below the truth's misfit {reached}/10"
    );
    Ok(())
}
