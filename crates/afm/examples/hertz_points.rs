//! Print, for every curve of the given JPK files (and of ZIP archives of them), the points
//! a paraboloidal Hertz fit uses — separation (m) and baseline-corrected force (N) of the
//! prepared approach — with nlvid's fit, one JSON object per line. Used to fit the same
//! points with nanite (crates/afm/tests/data/nanite_hertz.py).
//!
//! `cargo run -p nlvid-afm --example hertz_points -- R_M FILE...`

use std::io::{Cursor, Read};

use nlvid_afm::{
    ContactMethod, FitRange, HertzSettings, ReadOptions, fit_approach, prepare_approach,
    read_jpk_each,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let radius: f64 = args
        .next()
        .ok_or("usage: hertz_points R_M FILE...")?
        .parse()?;
    let settings = HertzSettings::new(radius, 0.5);
    for path in args {
        let bytes = std::fs::read(&path)?;
        let mut inputs = Vec::new();
        if path.ends_with(".zip") {
            let mut zip = zip::ZipArchive::new(Cursor::new(&bytes))?;
            for i in 0..zip.len() {
                let mut f = zip.by_index(i)?;
                if f.name().ends_with(".jpk-force") {
                    let mut b = Vec::new();
                    f.read_to_end(&mut b)?;
                    inputs.push((format!("{path}!{}", f.name()), b));
                }
            }
            inputs.sort();
        } else {
            inputs.push((path.clone(), bytes));
        }
        for (name, b) in inputs {
            for (curve, c) in read_jpk_each(&b, &name, &ReadOptions::default())? {
                let row = c.and_then(|c| {
                    let a = prepare_approach(&c, ContactMethod::default())?;
                    let f = fit_approach(&a, &settings, FitRange::Full)?;
                    Ok((a, f))
                });
                let curve = curve.map_or("null".to_string(), |i| i.to_string());
                match row {
                    Ok((a, f)) => println!(
                        "{{\"file\":{name:?},\"curve\":{curve},\"radius\":{radius:e},\"contact_estimate\":{:e},\"E\":{:e},\"contact_point\":{:e},\"offset\":{:e},\"separation\":[{}],\"force\":[{}]}}",
                        a.contact.separation,
                        f.fit.youngs_modulus,
                        f.fit.contact_point,
                        f.fit.offset,
                        join(&a.separation),
                        join(&a.force)
                    ),
                    Err(e) => eprintln!("{name} curve {curve}: {e}"),
                }
            }
        }
    }
    Ok(())
}

fn join(v: &[f64]) -> String {
    v.iter()
        .map(|x| format!("{x:e}"))
        .collect::<Vec<_>>()
        .join(",")
}
