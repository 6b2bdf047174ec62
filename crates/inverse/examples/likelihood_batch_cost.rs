//! Cost of the surrogate's part of one posterior likelihood evaluation
//! (issue 17, docs/theory/inverse.md "Fourth round"): c(x) and v(x) at 64
//! points of the demo meta-model (N = 970 sites), one point at a time
//! (`mse_scale` + `output_coordinate_values`, the sampler before session
//! 10), in batches (`coordinates_and_mse_scales`) or, with `screen`, the
//! coordinates alone in batches of 32 (`output_coordinate_batch`, the
//! screen of delayed acceptance: no variance); `lik-gauss` / `lik-student`:
//! the screen with the likelihood's Woodbury form, Gaussian or with the
//! Student-t surrogate error integrated out. For instruction
//! counts run it under callgrind, collecting the timed function only:
//!
//! ```text
//! valgrind --tool=callgrind '--toggle-collect=likelihood_batch_cost::*_path' \
//!     target/release/examples/likelihood_batch_cost [one|32|64|screen|lik-gauss|lik-student]
//! ```
//! Without valgrind it also prints the CPU seconds per point over 20 repeats.

use std::path::Path;

use nlvid_inverse::posterior::CurveLikelihood;
use nlvid_inverse::{Coordinates, Model, load_kriging_surrogate};
use nlvid_surrogate::KrigingModel;

#[inline(never)]
fn one_path(k: &KrigingModel, pts: &[Vec<f64>]) -> f64 {
    pts.iter()
        .map(|p| k.mse_scale(p).expect("v(x)") + k.output_coordinate_values(p).expect("c(x)")[1])
        .sum()
}

#[inline(never)]
fn batch_path(k: &KrigingModel, pts: &[Vec<f64>], b: usize) -> f64 {
    pts.chunks(b)
        .map(|c| {
            let (cs, vs) = k.coordinates_and_mse_scales(c, 1).expect("batch");
            vs.iter().sum::<f64>() + cs[0][1]
        })
        .sum()
}

/// The whole screen stage of delayed acceptance: c(x) in batches of 32
/// and the likelihood's Woodbury form, Gaussian or with the Student-t
/// error integrated out (`heavy_tails`).
#[inline(never)]
fn lik_screen_path(lik: &CurveLikelihood<'_>, pts: &[Vec<f64>], v: &[f64]) -> f64 {
    pts.chunks(32)
        .zip(v.chunks(32))
        .map(|(c, v)| lik.screen_values(c, v).expect("screen").expect("PCA")[0])
        .sum()
}

#[inline(never)]
fn screen_path(k: &KrigingModel, pts: &[Vec<f64>]) -> f64 {
    pts.chunks(32)
        .map(|c| k.output_coordinate_batch(c, 1).expect("screen")[0][1])
        .sum()
}

fn main() {
    let mode = std::env::args().nth(1).unwrap_or_else(|| "32".into());
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/demo/metamodel");
    let s = load_kriging_surrogate(
        &dir.join("model.json"),
        &dir.join("meta.json"),
        Coordinates::Physical,
    )
    .expect("demo meta-model");
    let k = s.kriging();
    let pts: Vec<Vec<f64>> = (0..64)
        .map(|i| {
            let t = f64::from(i) / 64.0;
            vec![
                800.0 + 2000.0 * t,
                0.1 + 0.5 * t,
                0.3 - 0.2 * t,
                0.05 + t,
                3.0 + 20.0 * t,
            ]
        })
        .collect();
    // The MSE factors (Cholesky of R) are built once, outside the count.
    let _ = k.mse_scale(&pts[0]).expect("v(x)");
    let data = s.response(&pts[7]).expect("curve");
    let noise = 0.02 * data.iter().fold(0.0f64, |a, &b| a.max(b));
    let gauss = CurveLikelihood::new(&s, &data, noise, false, false).expect("likelihood");
    let student = CurveLikelihood::new(&s, &data, noise, true, false).expect("likelihood");
    let variances = gauss.calibrated_variances(&pts).expect("v");
    let run = || match mode.as_str() {
        "one" => one_path(k, &pts),
        "screen" => screen_path(k, &pts),
        "lik-gauss" => lik_screen_path(&gauss, &pts, &variances),
        "lik-student" => lik_screen_path(&student, &pts, &variances),
        b => batch_path(k, &pts, b.parse().unwrap_or(32)),
    };
    let clock = cpu_time::ProcessTime::now();
    let mut v = 0.0;
    for _ in 0..20 {
        v += run();
    }
    let per = clock.elapsed().as_secs_f64() / (20.0 * pts.len() as f64);
    println!("{mode}: {:.1} us CPU per point (sum {v:.6e})", per * 1e6);
}
