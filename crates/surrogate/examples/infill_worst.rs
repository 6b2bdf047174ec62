//! Where does an adaptive-infill build miss? For a study with
//! `[design.infill]` and its store, fits the round's Kriging model
//! ([`InfillSettings::kriging_settings`]) to the first `n` stored training
//! runs that pass the filters and prints the worst admissible checking
//! runs: eq. 4.4 error, the predicted error e(x) of the infill criterion at
//! the same point, the distance to the nearest training run (unit cube)
//! and the parameters.
//!
//! ```text
//! cargo run --release -p nlvid-surrogate --example infill_worst -- STUDY STORE [n] [worst]
//! ```

use std::path::PathBuf;

use nlvid_surrogate::BuildStudy;
use nlvid_surrogate::check::summarise;
use nlvid_surrogate::infill::{checking_set, fit_kept};
use nlvid_surrogate::load;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let study = PathBuf::from(args.get(1).ok_or("STUDY")?);
    let store = PathBuf::from(args.get(2).ok_or("STORE")?);
    let n: usize = args.get(3).map_or(Ok(usize::MAX), |s| s.parse())?;
    let worst: usize = args.get(4).map_or(Ok(10), |s| s.parse())?;
    let bs = BuildStudy::load(&study)?;
    let infill = bs
        .settings
        .design
        .infill
        .clone()
        .ok_or("the study has no [design.infill]")?;
    let domain = bs.settings.design.domain.clone();
    let filters = &bs.settings.filters;
    let mut mm = load(&store.join("train"), filters)?;
    // Keep the runs of the first n design points.
    let keep: Vec<usize> = (0..mm.x.len()).filter(|&i| mm.index[i] < n).collect();
    mm.x = keep.iter().map(|&i| mm.x[i].clone()).collect();
    mm.y = keep.iter().map(|&i| mm.y[i].clone()).collect();
    let design = mm.meta.design.clone();
    let (cx, cy) = checking_set(&store.join("check"), filters)?;
    let model = fit_kept(&mm, &infill.kriging_settings(&domain))?;
    let preds: Vec<Vec<f64>> = cx
        .iter()
        .map(|x| model.predict(x))
        .collect::<Result<_, _>>()?;
    let sm = summarise(&cy, &preds)?;
    let pv = model.process_variance();
    let units: Vec<Vec<f64>> = design.iter().take(n).map(|x| domain.to_unit(x)).collect();
    println!(
        "{} admissible training runs of the first {} design points; {} checking runs; max {:.3} %, median {:.3} %",
        mm.x.len(),
        n.min(design.len()),
        cx.len(),
        100.0 * sm.max,
        100.0 * sm.median
    );
    let mut order: Vec<usize> = (0..cx.len()).collect();
    order.sort_by(|&a, &b| sm.rmse[b].total_cmp(&sm.rmse[a]));
    println!("check  err%  pred%  nearest  G0 g1 g2 tau1 tau2  u");
    for &i in order.iter().take(worst) {
        let u = domain.to_unit(&cx[i]);
        let near = units
            .iter()
            .map(|t| t.iter().zip(&u).map(|(a, b)| (a - b).powi(2)).sum::<f64>())
            .fold(f64::INFINITY, f64::min)
            .sqrt();
        let phi = model.variance_point(&cx[i])?.phi;
        let pred = (phi.max(0.0) * model.error_weight(&cx[i], &preds[i], &pv)?).sqrt();
        let x = &cx[i];
        println!(
            "{i:4} {:6.3} {:6.3} {near:6.3}  {:7.1} {:.3} {:.3} {:.4} {:6.2}  {:?}",
            100.0 * sm.rmse[i],
            100.0 * pred,
            x[0],
            x[1],
            x[2],
            x[3],
            x[4],
            u.iter()
                .map(|v| (v * 100.0).round() / 100.0)
                .collect::<Vec<_>>()
        );
    }
    Ok(())
}
