//! Dense output: values between the converged steps (issue 15: curves at
//! the sample times).
//!
//! Within one stage (one smooth segment of the loading) a step record is
//! interpolated by the cubic through the four nearest records of that
//! stage, counting the last record before the stage as its start point
//! (the state is continuous across a stage boundary, its rate is not, so no
//! polynomial reaches across one). Near the stage ends the four points are
//! shifted inward; with fewer points the degree drops.
//!
//! Step control ([`interpolation_error`]): after each step, the difference
//! between the quadratic through the last three records and the cubic
//! through the last four, f[t₀,t₁,t₂,t₃] (t − t₁)(t − t₂)(t − t₃), bounds
//! the error of the quadratic on the last interval [t₂, t₃]; the
//! interpolant used is the cubic, one order better. `Model::run_stage`
//! keeps this estimate below `Settings::output_tolerance` × |F|.

use crate::StepRecord;

/// Lagrange interpolation through `(ts[i], ys[i])` at `t`.
fn lagrange(ts: &[f64], ys: &[f64], t: f64) -> f64 {
    let mut sum = 0.0;
    for i in 0..ts.len() {
        let mut w = 1.0;
        for j in 0..ts.len() {
            if i != j {
                w *= (t - ts[j]) / (ts[i] - ts[j]);
            }
        }
        sum += w * ys[i];
    }
    sum
}

/// Largest difference on [t₂, t₃] between the cubic through the four
/// points and the quadratic through the last three:
/// |f[t₀,…,t₃]| max |(t − t₁)(t − t₂)(t − t₃)|.
pub(crate) fn interpolation_error(ts: [f64; 4], ys: [f64; 4]) -> f64 {
    // Third divided difference.
    let d1: Vec<f64> = (0..3)
        .map(|i| (ys[i + 1] - ys[i]) / (ts[i + 1] - ts[i]))
        .collect();
    let d2: Vec<f64> = (0..2)
        .map(|i| (d1[i + 1] - d1[i]) / (ts[i + 2] - ts[i]))
        .collect();
    let d3 = (d2[1] - d2[0]) / (ts[3] - ts[0]);
    // max |ω| on [t₂, t₃], ω = (t − t₁)(t − t₂)(t − t₃) vanishing at both
    // ends: at a root of ω' = 3t² − 2 s₁ t + s₂ inside the interval.
    let omega_at = |t: f64| ((t - ts[1]) * (t - ts[2]) * (t - ts[3])).abs();
    let s1 = ts[1] + ts[2] + ts[3];
    let s2 = ts[1] * ts[2] + ts[1] * ts[3] + ts[2] * ts[3];
    let disc = (s1 * s1 - 3.0 * s2).max(0.0).sqrt();
    let omega = [(s1 - disc) / 3.0, (s1 + disc) / 3.0]
        .into_iter()
        .filter(|&t| t > ts[2] && t < ts[3])
        .map(omega_at)
        .fold(0.0f64, f64::max);
    (d3 * omega).abs()
}

/// The range of records that stage `stage` interpolates over: its own
/// records and the one before (its start point).
fn stage_window(records: &[StepRecord], k: usize) -> (usize, usize) {
    let stage = records[k].stage;
    let mut lo = k;
    while lo > 0 && records[lo - 1].stage == stage {
        lo -= 1;
    }
    let lo = lo.saturating_sub(1);
    let mut hi = k;
    while hi + 1 < records.len() && records[hi + 1].stage == stage {
        hi += 1;
    }
    (lo, hi)
}

/// `value` of the records at time `t` (dense output, module docs): the
/// cubic within the stage that contains t; the first or last record's
/// value outside the recorded times.
pub fn interpolate_records(
    records: &[StepRecord],
    t: f64,
    value: impl Fn(&StepRecord) -> f64,
) -> f64 {
    let Some(first) = records.first() else {
        return f64::NAN;
    };
    if t <= first.time {
        return value(first);
    }
    // First record at or after t.
    let k = records.partition_point(|r| r.time < t);
    let Some(last) = records.last() else {
        return f64::NAN;
    };
    if k >= records.len() {
        return value(last);
    }
    if records[k].time == t {
        return value(&records[k]);
    }
    let (lo, hi) = stage_window(records, k);
    // Four points around [t_{k−1}, t_k], shifted into [lo, hi].
    let n = (hi - lo + 1).min(4);
    let mut start = k.saturating_sub(2).max(lo);
    if start + n > hi + 1 {
        start = hi + 1 - n;
    }
    let ts: Vec<f64> = records[start..start + n].iter().map(|r| r.time).collect();
    let ys: Vec<f64> = records[start..start + n].iter().map(&value).collect();
    lagrange(&ts, &ys, t)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(time: f64, stage: usize, f: f64) -> StepRecord {
        StepRecord {
            time,
            probe_w: 0.0,
            free_end: f64::NAN,
            contact_force: f,
            plane_force: 0.0,
            base_force: 0.0,
            penetration: 0.0,
            cavity_pressure: f64::NAN,
            cavity_volume: f64::NAN,
            iterations: 0,
            stage,
        }
    }

    #[test]
    fn cubic_within_a_stage_is_exact_for_cubics_and_stops_at_stage_ends() {
        let p = |t: f64| 1.0 + 2.0 * t - t * t + 0.5 * t * t * t;
        let mut records = vec![record(0.0, 0, p(0.0))];
        for t in [0.1, 0.3, 0.35, 0.7, 1.0] {
            records.push(record(t, 1, p(t)));
        }
        // A second stage with a kink: linear from the stage start.
        records.push(record(1.5, 2, p(1.0) + 1.0));
        records.push(record(2.0, 2, p(1.0) + 2.0));
        for t in [0.05, 0.2, 0.33, 0.5, 0.9] {
            let f = interpolate_records(&records, t, |r| r.contact_force);
            assert!((f - p(t)).abs() < 1e-13, "t = {t}: {f} vs {}", p(t));
        }
        // Stage 2 uses its own points and its start point only: exact for
        // the linear continuation.
        let f = interpolate_records(&records, 1.25, |r| r.contact_force);
        assert!((f - (p(1.0) + 0.5)).abs() < 1e-13, "{f}");
    }

    #[test]
    fn estimate_is_the_cubic_minus_quadratic_difference() {
        // For a cubic the quadratic's error on the last interval is exactly
        // the estimate's expression; compare with a brute-force maximum.
        let f = |t: f64| t * t * t;
        let ts = [0.0, 0.5, 1.0, 2.0];
        let ys = ts.map(f);
        let est = interpolation_error(ts, ys);
        let mut worst: f64 = 0.0;
        for k in 0..=1000 {
            let t = 1.0 + k as f64 / 1000.0;
            let q = lagrange(&ts[1..], &ys[1..], t);
            worst = worst.max((q - f(t)).abs());
        }
        assert!((est / worst - 1.0).abs() < 0.01, "{est} vs {worst}");
    }
}
