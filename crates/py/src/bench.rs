//! The Rust side of the binding-overhead benchmark
//! (crates/py/benchmarks/overhead.py): the same library calls as
//! `MetaModel.predict` and `fit_hertz`, `n` times in a Rust loop, timed in
//! Rust. Not part of the public API (leading underscore).

use std::hint::black_box;
use std::time::Instant;

use pyo3::prelude::*;

use crate::arrays::{quantity, vector};
use crate::errors::IntoPy;
use crate::metamodel::MetaModel;

/// Seconds for `n` predictions at the point `x` (with the MSE when `mse`)
/// through the Rust API.
#[pyfunction]
#[pyo3(signature = (model, x, n, mse = false))]
fn _bench_predict(
    py: Python<'_>,
    model: PyRef<'_, MetaModel>,
    x: &Bound<'_, PyAny>,
    n: usize,
    mse: bool,
) -> PyResult<f64> {
    let x = vector(x, "x")?;
    let xv = x.values();
    let k = &model.named.model;
    py.detach(|| -> nlvid_surrogate::Result<f64> {
        let t0 = Instant::now();
        for _ in 0..n {
            if mse {
                black_box(k.predict_full(black_box(&xv))?);
            } else {
                black_box(k.predict(black_box(&xv))?);
            }
        }
        Ok(t0.elapsed().as_secs_f64())
    })
    .py()
}

/// Seconds for `n` Hertz fits of `force` against `separation` through the
/// Rust API.
#[pyfunction]
fn _bench_fit_hertz(
    py: Python<'_>,
    separation: &Bound<'_, PyAny>,
    force: &Bound<'_, PyAny>,
    tip_radius: &Bound<'_, PyAny>,
    n: usize,
) -> PyResult<f64> {
    let (s, f) = (vector(separation, "separation")?, vector(force, "force")?);
    let settings = nlvid_afm::HertzSettings::new(
        quantity(tip_radius, "tip_radius", nlvid_study::Dimension::LENGTH)?,
        0.5,
    );
    let (sv, fv) = (s.values(), f.values());
    py.detach(|| -> nlvid_afm::Result<f64> {
        let t0 = Instant::now();
        for _ in 0..n {
            black_box(nlvid_afm::fit_hertz(
                black_box(&sv),
                black_box(&fv),
                &settings,
            )?);
        }
        Ok(t0.elapsed().as_secs_f64())
    })
    .py()
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_bench_predict, m)?)?;
    m.add_function(wrap_pyfunction!(_bench_fit_hertz, m)?)?;
    Ok(())
}
