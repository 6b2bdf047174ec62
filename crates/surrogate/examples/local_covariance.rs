//! Scores a local (x-dependent) surrogate-error covariance against the
//! global one on the meta-model's own leave-one-out residuals
//! (`KrigingModel::local_covariance_score`): the mean log density per site
//! of each site's standardised LOO residual under the covariance built from
//! the other sites' residuals near it.
//!
//! ```text
//! cargo run --release -p nlvid-surrogate --example local_covariance -- examples/demo/metamodel/model.json
//! ```
use nlvid_surrogate::KrigingModel;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "examples/demo/metamodel/model.json".into());
    let km: KrigingModel = serde_json::from_slice(&std::fs::read(&path)?)?;
    let cal = km.variance_calibration()?;
    println!("calibration alpha {:.4e} beta {:.4}", cal.alpha, cal.beta);
    let global = km.local_covariance_score(&cal, 0.0, 0.0)?;
    println!("global Sigma_CV: mean log density {global:.4}");
    for power in [3.0, 10.0, 30.0, 100.0, 300.0] {
        for prior in [0.0, 3.0, 10.0, 30.0] {
            let s = km.local_covariance_score(&cal, power, prior)?;
            println!(
                "power {power:5} prior sites {prior:4}: {s:.4} ({:+.4})",
                s - global
            );
        }
    }
    Ok(())
}
