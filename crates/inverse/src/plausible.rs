//! Plausibility of a measured curve before it is fitted: values beyond any
//! AFM instrument's range, single-sample spikes, an inverted sign
//! convention, and curves that never make contact. Each finding names the
//! file line of the sample and a reason; a fit of such data is refused
//! rather than reported with advice about the domain.

use crate::measured::MeasuredCurve;

/// Largest force an AFM cantilever measures, N: stiff levers (≤ 100 N/m)
/// deflect at most ≈ 10 µm.
pub const MAX_FORCE: f64 = 1e-3;
/// Largest piezo travel or indentation, m (AFM scanners: ≤ 100 µm; plate
/// rigs: ≤ 1 mm).
pub const MAX_LENGTH: f64 = 1e-3;
/// A spike exceeds both neighbours by this many robust noise scales …
const SPIKE_SCALES: f64 = 50.0;
/// … and by this fraction of the curve's robust force range.
const SPIKE_RANGE: f64 = 0.5;

/// One implausible feature of a measured curve.
#[derive(Debug, Clone, PartialEq)]
pub struct Implausible {
    /// 1-based line of the file the sample is on.
    pub line: usize,
    /// What is wrong, in words.
    pub reason: String,
}

impl std::fmt::Display for Implausible {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "line {}: {}", self.line, self.reason)
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn quantile(v: &[f64], q: f64) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s.get(((s.len() - 1) as f64 * q).round() as usize)
        .copied()
        .unwrap_or(0.0)
}

impl MeasuredCurve {
    /// The implausible features of this curve, in the order: out of range,
    /// spikes, inverted sign, no contact (empty when it looks like a
    /// measurement).
    pub fn implausible(&self) -> Vec<Implausible> {
        let line = |i: usize| self.lines.get(i).copied().unwrap_or(i + 2);
        let mut out = Vec::new();
        let f = self.force();
        // Beyond the instrument's range.
        let ranges = [
            ("force", f, MAX_FORCE, "N"),
            ("displacement", self.displacement(), MAX_LENGTH, "m"),
        ];
        for (what, v, max, unit) in ranges {
            if let Some(i) = v.iter().position(|x| x.abs() > max) {
                out.push(Implausible {
                    line: line(i),
                    reason: format!(
                        "{what} {:.3e} {unit} is beyond any instrument's range (|{what}| ≤ {max:e} {unit})",
                        v[i]
                    ),
                });
            }
        }
        if !out.is_empty() || f.len() < 3 {
            return out;
        }
        // Single-sample spikes: far from both neighbours, in the same direction.
        let noise = 1.4826 * median(f.windows(2).map(|w| (w[1] - w[0]).abs()).collect());
        let range = quantile(f, 0.95) - quantile(f, 0.05);
        let limit = (SPIKE_SCALES * noise).max(SPIKE_RANGE * range);
        for i in 1..f.len() - 1 {
            let (a, b) = (f[i] - f[i - 1], f[i] - f[i + 1]);
            if a * b > 0.0 && a.abs().min(b.abs()) > limit && limit > 0.0 {
                out.push(Implausible {
                    line: line(i),
                    reason: format!(
                        "single-sample spike: force {:.3e} N between {:.3e} N and {:.3e} N",
                        f[i],
                        f[i - 1],
                        f[i + 1]
                    ),
                });
            }
        }
        let Some(ind) = self.indentation() else {
            return out;
        };
        // Inverted sign: where the probe is pressed deepest, the force pulls.
        let deepest = ind
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map(|(i, _)| i);
        let (fmin, fmax) = f
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
                (lo.min(x), hi.max(x))
            });
        if let Some(i) = deepest
            && f[i] < 0.0
            && -fmin > 2.0 * fmax.max(0.0)
        {
            out.push(Implausible {
                line: line(i),
                reason: format!(
                    "the force is {:.3e} N (pulling) where the indentation is largest: is the \
                     deflection's sign convention inverted?",
                    f[i]
                ),
            });
        }
        if ind.iter().all(|d| *d <= 0.0) {
            out.push(Implausible {
                line: line(0),
                reason: "the indentation Z − d is never positive: the curve never makes contact \
                         (or the piezo's sign convention is reversed)"
                    .into(),
            });
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    /// A clean ramp-hold: indentation up to 1 µm in 1 s, force relaxing.
    fn curve() -> MeasuredCurve {
        let n = 200;
        let time: Vec<f64> = (0..n).map(|i| i as f64 * 0.05).collect();
        let ind: Vec<f64> = time.iter().map(|t| 1e-6 * t.min(1.0)).collect();
        let force: Vec<f64> = time
            .iter()
            .zip(&ind)
            .enumerate()
            .map(|(i, (t, d))| {
                let relax = if *t > 1.0 {
                    0.5 + 0.5 * (-(t - 1.0)).exp()
                } else {
                    1.0
                };
                // ±0.5 % deterministic noise.
                5e-9 * (d / 1e-6).powf(1.5) * relax + 2.5e-11 * ((i * 7919 % 13) as f64 / 6.0 - 1.0)
            })
            .collect();
        let displacement = ind.iter().zip(&force).map(|(d, f)| d + f / 0.1).collect();
        MeasuredCurve::from_columns(
            Path::new("c.csv"),
            (2..n + 2).collect(),
            (time, displacement, force),
            Some(ind),
            None,
        )
        .expect("curve")
    }

    /// `c` with its force changed by `f`.
    fn with_force(mut c: MeasuredCurve, f: impl Fn(&mut Vec<f64>)) -> MeasuredCurve {
        let mut force = c.force().to_vec();
        f(&mut force);
        c.curve.replace("force", force).expect("force");
        c
    }

    #[test]
    fn a_clean_curve_passes() {
        assert_eq!(curve().implausible(), vec![]);
    }

    #[test]
    fn each_defect_is_named_with_its_line() {
        let c = with_force(curve(), |f| f[40] = 1e300);
        let e = c.implausible();
        assert_eq!(e.len(), 1);
        assert_eq!(e[0].line, 42);
        assert!(e[0].reason.contains("beyond any instrument"), "{e:?}");

        let c = with_force(curve(), |f| f[60] = 4e-8); // 8× the peak, one sample
        let e = c.implausible();
        assert_eq!(e.len(), 1, "{e:?}");
        assert_eq!(e[0].line, 62);
        assert!(e[0].reason.contains("spike"));

        let c = with_force(curve(), |f| f.iter_mut().for_each(|f| *f = -*f));
        let e = c.implausible();
        assert!(
            e.iter().any(|x| x.reason.contains("sign convention")),
            "{e:?}"
        );

        let mut c = curve();
        let n = c.force().len();
        c.curve
            .replace("indentation", vec![-1e-7; n])
            .expect("indentation");
        let e = c.implausible();
        assert!(
            e.iter().any(|x| x.reason.contains("never makes contact")),
            "{e:?}"
        );
    }
}
