//! Paraboloidal Hertz fit of every curve in the given files and folders, in parallel
//! (rayon; `RAYON_NUM_THREADS` sets the threads): one CSV row per curve on stdout, one
//! line per failure and a summary on stderr. The batch benchmark of issue 14.
//!
//! `cargo run --release -p nlvid-afm --example batch_hertz -- R_M PATH...`

use std::path::PathBuf;
use std::time::Instant;

use nlvid_afm::{ContactMethod, FitRange, HertzSettings, ReadOptions, fit_curve, for_each_curve};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let radius: f64 = args
        .next()
        .ok_or("usage: batch_hertz R_M PATH...")?
        .parse()?;
    let inputs: Vec<PathBuf> = args.map(PathBuf::from).collect();
    let settings = HertzSettings::new(radius, 0.5);
    let t0 = Instant::now();
    let batch = for_each_curve(&inputs, &ReadOptions::default(), |c| {
        fit_curve(c, &settings, FitRange::Full, ContactMethod::default())
    })?;
    let elapsed = t0.elapsed();
    println!("file,curve,E_Pa,contact_point_m,offset_N,rmse_N,points,warnings");
    for r in &batch.rows {
        let f = &r.value.fit;
        println!(
            "{},{},{:e},{:e},{:e},{:e},{},{}",
            r.file.display(),
            r.curve.map_or(String::new(), |i| i.to_string()),
            f.youngs_modulus,
            f.contact_point,
            f.offset,
            f.rmse,
            f.n_points,
            r.value.warnings.len()
        );
    }
    for f in &batch.failures {
        eprintln!("failed: {f}");
    }
    eprintln!(
        "{} curves fitted, {} failed, {} files ignored in {:.3} s on {} threads",
        batch.rows.len(),
        batch.failures.len(),
        batch.ignored.len(),
        elapsed.as_secs_f64(),
        rayon::current_num_threads()
    );
    Ok(())
}
