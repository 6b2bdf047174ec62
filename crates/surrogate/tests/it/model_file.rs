//! The model file keeps what prediction needs and leaves out the n × n
//! Cholesky factor of R (and F̃, G): a loaded model rebuilds them from the
//! sites, θ and the nugget, so its MSE (DACE report eq. 2.20) and the MSE's
//! gradient equal the fitted model's — the fitted model's factors come from
//! the θ search's own factorisation, the loaded one's from a fresh one.

#![allow(clippy::unwrap_used)]

use nlvid_surrogate::faer::Mat;
use nlvid_surrogate::{Correlation, KrigingModel, KrigingSettings, Regression, ThetaSearch};

/// n sites of a 3-D Halton sequence and m = 40 curve outputs
/// y(t) = x0·exp(−t·x1) + x2·t on t ∈ [0, 1] (a PCA of a few components).
fn data(n: usize) -> (Mat<f64>, Mat<f64>) {
    let halton = |mut i: usize, b: usize| {
        let (mut f, mut r) = (1.0, 0.0);
        while i > 0 {
            f /= b as f64;
            r += f * (i % b) as f64;
            i /= b;
        }
        r
    };
    let x = Mat::from_fn(n, 3, |i, k| halton(i + 1, [2, 3, 5][k]));
    let m = 40;
    let y = Mat::from_fn(n, m, |i, j| {
        let t = j as f64 / (m - 1) as f64;
        (1.0 + x[(i, 0)]) * (-t * 2.0 * x[(i, 1)]).exp() + x[(i, 2)] * t
    });
    (x, y)
}

fn fitted(n: usize) -> KrigingModel {
    let (x, y) = data(n);
    let mut set = KrigingSettings::new(Regression::Poly1, Correlation::Gauss, 3);
    set.theta = ThetaSearch::Fixed(vec![2.0, 3.0, 1.5]);
    set.pca_energy = Some(0.999999);
    // A nugget far above DACE's (10+n)·eps: a rebuild that forgot it would
    // give a visibly different MSE.
    set.nugget = 1e-5;
    set.auto_nugget = false;
    KrigingModel::fit(x.as_ref(), y.as_ref(), &set).expect("fit")
}

/// Points inside and between the sites.
const POINTS: [[f64; 3]; 3] = [[0.31, 0.62, 0.17], [0.5, 0.5, 0.5], [0.93, 0.08, 0.71]];

fn assert_same_mse(a: &KrigingModel, b: &KrigingModel) {
    for x in POINTS {
        let (pa, pb) = (a.predict_full(&x).unwrap(), b.predict_full(&x).unwrap());
        assert_eq!(pa.y, pb.y, "prediction at {x:?}");
        for (what, u, v) in [("mse", &pa.mse, &pb.mse), ("dmse", &pa.dmse, &pb.dmse)] {
            let scale = u.iter().fold(0.0f64, |s, w| s.max(w.abs()));
            assert!(scale > 0.0, "{what} at {x:?} is zero");
            for (p, q) in u.iter().zip(v) {
                assert!(
                    (p - q).abs() <= 1e-9 * scale,
                    "{what} at {x:?}: {p} (fitted) vs {q} (loaded)"
                );
            }
        }
        let (fa, fb) = (a.mse_factor(&x).unwrap(), b.mse_factor(&x).unwrap());
        assert!((fa - fb).abs() <= 1e-9 * fa, "φ at {x:?}: {fa} vs {fb}");
    }
}

#[test]
fn a_loaded_model_rebuilds_the_mse_factors_and_the_file_holds_no_n_by_n_matrix() {
    let n = 120;
    let m = fitted(n);
    assert!(m.pca.as_ref().expect("PCA").n_components < 10);
    let text = serde_json::to_string(&m).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    for key in ["c", "ft", "g"] {
        assert!(v.get(key).is_none(), "the file holds `{key}`");
    }
    let numbers = text.split([',', '[']).count();
    assert!(
        numbers < n * n / 4,
        "{numbers} numbers in the file; C alone has n² = {}",
        n * n
    );
    let back: KrigingModel = serde_json::from_str(&text).unwrap();
    assert_same_mse(&m, &back);
}

/// A file written before the factors were left out (with `c`, `ft`, `g`)
/// still loads; the stored matrices are not used (here: nonsense values).
#[test]
fn an_older_file_with_the_factors_still_loads() {
    let m = fitted(60);
    let mut v = serde_json::to_value(&m).unwrap();
    let obj = v.as_object_mut().unwrap();
    obj.insert("c".into(), serde_json::json!([1.0, 2.0]));
    obj.insert("ft".into(), serde_json::json!([3.0]));
    obj.insert("g".into(), serde_json::json!([4.0]));
    let back: KrigingModel = serde_json::from_value(v).unwrap();
    assert_same_mse(&m, &back);
}
