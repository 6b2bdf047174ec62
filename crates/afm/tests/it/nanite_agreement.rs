//! Paraboloidal Hertz fits of the public JPK curves against nanite 4.2.3 fitting the same
//! points with the same model (issue 14: within 0.5 %). nanite's values were computed by
//! tests/data/nanite_hertz.py on the points printed by the `hertz_points` example and are
//! stored in tests/data/nanite_hertz.csv (see tests/data/README.md).

use crate::common;

use common::*;
use nlvid_afm::{
    ContactMethod, FitRange, ForceCurve, HertzSettings, ReadOptions, fit_approach,
    prepare_approach, read_jpk_each,
};

struct Row {
    file: String,
    curve: Option<usize>,
    radius: f64,
    points: usize,
    e_nanite: f64,
    contact_nanite: f64,
    sse_nanite: f64,
}

fn rows() -> Vec<Row> {
    let text = std::fs::read_to_string(data("nanite_hertz.csv")).expect("csv");
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).expect(name);
    let (file, curve, radius, points, e, cp, sse) = (
        col("file"),
        col("curve"),
        col("radius_m"),
        col("points"),
        col("E_nanite_Pa"),
        col("contact_point_nanite_m"),
        col("sse_nanite_N2"),
    );
    lines
        .map(|l| {
            let v: Vec<&str> = l.split(',').collect();
            let num = |i: usize| v[i].parse::<f64>().expect("number");
            Row {
                file: v[file].to_string(),
                curve: (!v[curve].is_empty()).then(|| v[curve].parse().expect("curve")),
                radius: num(radius),
                points: v[points].parse().expect("points"),
                e_nanite: num(e),
                contact_nanite: num(cp),
                sse_nanite: num(sse),
            }
        })
        .collect()
}

fn curve_of(row: &Row) -> ForceCurve {
    let (name, bytes) = match row.file.split_once('!') {
        Some((_, inner)) => fig5d()
            .into_iter()
            .find(|(n, _)| n == inner)
            .expect("curve in the fig. 5d archive"),
        None => (
            row.file.clone(),
            std::fs::read(data(&row.file)).expect("data file"),
        ),
    };
    read_jpk_each(&bytes, &name, &ReadOptions::default())
        .expect("file")
        .into_iter()
        .find(|(i, _)| *i == row.curve)
        .expect("curve index")
        .1
        .expect("curve reads")
}

#[test]
fn hertz_e_agrees_with_nanite_on_every_public_curve() {
    let rows = rows();
    assert_eq!(rows.len(), 27, "every Hertz-fittable public curve");
    let mut worst: f64 = 0.0;
    for row in &rows {
        let c = curve_of(row);
        let a = prepare_approach(&c, ContactMethod::default()).expect("approach");
        assert_eq!(a.force.len(), row.points, "{} {:?}", row.file, row.curve);
        let fit = fit_approach(&a, &HertzSettings::new(row.radius, 0.5), FitRange::Full)
            .expect("fit")
            .fit;
        let d = rel(fit.youngs_modulus, row.e_nanite);
        worst = worst.max(d);
        assert!(
            d < 0.005,
            "{} {:?}: E {} vs nanite {} ({d:e})",
            row.file,
            row.curve,
            fit.youngs_modulus,
            row.e_nanite
        );
        // Same optimum, not just close: nlvid's residual is never above nanite's.
        let sse = fit.rmse.powi(2) * fit.n_points as f64;
        assert!(
            sse <= row.sse_nanite * (1.0 + 1e-9),
            "{} {:?}: SSE {sse:e} vs nanite {:e}",
            row.file,
            row.curve,
            row.sse_nanite
        );
        assert!((fit.contact_point - row.contact_nanite).abs() < 1e-8);
    }
    eprintln!("largest relative difference from nanite: {worst:e}");
}
