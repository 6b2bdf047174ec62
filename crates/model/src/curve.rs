//! The one curve type: sample times plus named channels with SI units
//! (force, indentation, piezo height, plate displacement, contact area, …).
//! Measured curves, simulated runs, predictions and plotted series are all
//! a [`Curve`]; instrument readers fill it, writers print it with
//! unit-suffixed headers (`force_N`).

use serde::{Deserialize, Serialize};

use crate::error::{ModelError, Result};

/// One named channel of a [`Curve`], one value per sample time.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Channel {
    /// Name (`force`, `indentation`, …).
    pub name: String,
    /// SI unit (`N`, `m`, `1`, …).
    pub unit: String,
    /// Values (SI), one per time.
    pub values: Vec<f64>,
}

impl Channel {
    /// Column header with the unit as suffix: `force_N`, `strain` (for "1").
    pub fn header(&self) -> String {
        unit_suffixed(&self.name, &self.unit)
    }
}

/// The one naming rule for a quantity in CSV headers and JSON keys: the
/// name with its SI unit as suffix (`force_N`, `G0_Pa`, `k_N_per_m`); a
/// dimensionless quantity (unit `1` or none) keeps its bare name.
pub fn unit_suffixed(name: &str, unit: &str) -> String {
    if unit == "1" || unit.is_empty() {
        name.to_string()
    } else {
        format!("{name}_{}", unit.replace('/', "_per_"))
    }
}

/// Named parameters `(name, value, unit)` as a JSON object with
/// [`unit_suffixed`] keys: `{"G0_Pa": 1000, "g1": 0.3, "tau1_s": 0.5}`.
///
/// ```
/// let p = nlvid_model::parameters_json(&[("G0".into(), 1e3, "Pa".into()), ("g1".into(), 0.3, "1".into())]);
/// assert_eq!(p.to_string(), r#"{"G0_Pa":1000.0,"g1":0.3}"#);
/// ```
pub fn parameters_json(params: &[(String, f64, String)]) -> serde_json::Value {
    params
        .iter()
        .map(|(n, v, u)| (unit_suffixed(n, u), serde_json::Value::from(*v)))
        .collect::<serde_json::Map<_, _>>()
        .into()
}

/// Sample times (s, strictly increasing, finite) and channels of equal
/// length.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Curve {
    time: Vec<f64>,
    channels: Vec<Channel>,
}

impl Curve {
    /// A curve with no channels yet.
    ///
    /// # Errors
    /// [`ModelError::Curve`] naming the first sample whose time is not
    /// finite or not after the previous one.
    pub fn new(time: Vec<f64>) -> Result<Self> {
        if let Some(i) = time.iter().position(|t| !t.is_finite()) {
            return Err(ModelError::Curve(format!(
                "time at sample {} is {} (not finite)",
                i + 1,
                time[i]
            )));
        }
        if let Some(i) = time.windows(2).position(|w| w[1] <= w[0]) {
            return Err(ModelError::Curve(format!(
                "time is not increasing at sample {}: {} s after {} s",
                i + 2,
                time[i + 1],
                time[i]
            )));
        }
        Ok(Self {
            time,
            channels: Vec::new(),
        })
    }

    /// Adds a channel.
    ///
    /// # Errors
    /// [`ModelError::Curve`] when its length differs from the times', the
    /// name is taken, or a value is not finite (naming the sample).
    pub fn with(mut self, name: &str, unit: &str, values: Vec<f64>) -> Result<Self> {
        if self.channel(name).is_some() {
            return Err(ModelError::Curve(format!(
                "channel `{name}` is given twice"
            )));
        }
        self.check_values(name, &values)?;
        self.channels.push(Channel {
            name: name.to_string(),
            unit: unit.to_string(),
            values,
        });
        Ok(self)
    }

    /// Replaces the values of an existing channel (same name and unit),
    /// e.g. a measured channel with noise added.
    ///
    /// # Errors
    /// [`ModelError::Curve`] when there is no such channel, or as
    /// [`Curve::with`] for the length and the values.
    pub fn replace(&mut self, name: &str, values: Vec<f64>) -> Result<()> {
        self.check_values(name, &values)?;
        let channel = self
            .channels
            .iter_mut()
            .find(|c| c.name == name)
            .ok_or_else(|| ModelError::Curve(format!("no channel `{name}` to replace")))?;
        channel.values = values;
        Ok(())
    }

    /// One value per time, each finite.
    fn check_values(&self, name: &str, values: &[f64]) -> Result<()> {
        if values.len() != self.time.len() {
            return Err(ModelError::Curve(format!(
                "channel `{name}` has {} values for {} times",
                values.len(),
                self.time.len()
            )));
        }
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(ModelError::Curve(format!(
                "channel `{name}` at sample {} (t = {} s) is {}",
                i + 1,
                self.time[i],
                values[i]
            )));
        }
        Ok(())
    }

    /// Sample times (s).
    pub fn time(&self) -> &[f64] {
        &self.time
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.time.len()
    }

    /// True when there are no samples.
    pub fn is_empty(&self) -> bool {
        self.time.is_empty()
    }

    /// All channels, in the order added.
    pub fn channels(&self) -> &[Channel] {
        &self.channels
    }

    /// A channel by name.
    pub fn channel(&self, name: &str) -> Option<&Channel> {
        self.channels.iter().find(|c| c.name == name)
    }

    /// A channel's values by name.
    pub fn values(&self, name: &str) -> Option<&[f64]> {
        self.channel(name).map(|c| c.values.as_slice())
    }

    /// The curve as JSON: `{"time_s": [...], "<header>": [...], ...}`, the
    /// headers of [`Curve::to_csv`].
    pub fn to_json(&self) -> serde_json::Value {
        let mut m = serde_json::Map::new();
        m.insert("time_s".into(), serde_json::Value::from(self.time.clone()));
        for c in &self.channels {
            m.insert(c.header(), serde_json::Value::from(c.values.clone()));
        }
        serde_json::Value::Object(m)
    }

    /// CSV text: `time_s` then one column per channel, unit-suffixed
    /// headers, values printed so that they read back bit for bit.
    pub fn to_csv(&self) -> String {
        let mut out = String::from("time_s");
        for c in &self.channels {
            out.push(',');
            out.push_str(&c.header());
        }
        out.push('\n');
        for (i, t) in self.time.iter().enumerate() {
            out.push_str(&number(*t));
            for c in &self.channels {
                out.push(',');
                out.push_str(&number(c.values[i]));
            }
            out.push('\n');
        }
        out
    }
}

/// Shortest text that reads back to exactly `x`: plain for 1e-4 ≤ |x| <
/// 1e15 and 0 (`0`, `1`, `10.5`), exponent form otherwise (`2.5e-9`).
fn number(x: f64) -> String {
    if x == 0.0 || (1e-4..1e15).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_increasing_time_and_bad_values_name_the_sample() {
        let e = Curve::new(vec![0.0, 1.0, 1.0]).expect_err("repeated time");
        assert!(e.to_string().contains("sample 3"), "{e}");
        let e = Curve::new(vec![0.0, f64::NAN]).expect_err("NaN time");
        assert!(e.to_string().contains("sample 2"), "{e}");
        let c = Curve::new(vec![0.0, 1.0]).expect("times");
        let e = c.clone().with("force", "N", vec![1.0]).expect_err("length");
        assert!(e.to_string().contains("1 values for 2 times"), "{e}");
        let e = c
            .with("force", "N", vec![1.0, f64::INFINITY])
            .expect_err("inf");
        assert!(e.to_string().contains("sample 2 (t = 1 s)"), "{e}");
    }

    #[test]
    fn csv_has_unit_suffixed_headers_and_reads_back_exactly() {
        let c = Curve::new(vec![0.0, 0.1])
            .and_then(|c| c.with("force", "N", vec![0.0, 1.0 / 3.0e9]))
            .and_then(|c| c.with("indentation", "m", vec![0.0, 2e-7]))
            .and_then(|c| c.with("relative", "1", vec![1.0, 0.5]))
            .expect("curve");
        let csv = c.to_csv();
        let mut lines = csv.lines();
        assert_eq!(lines.next(), Some("time_s,force_N,indentation_m,relative"));
        let second: Vec<f64> = lines
            .nth(1)
            .expect("row")
            .split(',')
            .map(|v| v.parse().expect("number"))
            .collect();
        assert_eq!(second, vec![0.1, 1.0 / 3.0e9, 2e-7, 0.5]);
        assert_eq!(c.values("force").map(|v| v[1]), Some(1.0 / 3.0e9));
    }

    #[test]
    fn replace_keeps_name_and_unit_and_checks_the_values() {
        let mut c = Curve::new(vec![0.0, 1.0])
            .and_then(|c| c.with("force", "N", vec![0.0, 1.0]))
            .expect("curve");
        c.replace("force", vec![2.0, 3.0]).expect("replace");
        assert_eq!(c.values("force"), Some(&[2.0, 3.0][..]));
        assert_eq!(c.channels()[0].header(), "force_N");
        let e = c.replace("force", vec![1.0]).expect_err("length");
        assert!(e.to_string().contains("1 values for 2 times"), "{e}");
        let e = c.replace("force", vec![1.0, f64::NAN]).expect_err("NaN");
        assert!(e.to_string().contains("sample 2"), "{e}");
        let e = c.replace("area", vec![1.0, 1.0]).expect_err("missing");
        assert!(e.to_string().contains("no channel `area`"), "{e}");
        assert_eq!(c.values("force"), Some(&[2.0, 3.0][..]));
    }
}
