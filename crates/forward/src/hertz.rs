//! `model = "hertz-prony"`: the analytic Lee–Radok ramp-hold model
//! ([`HertzProny`], the exact kernel of [`crate::LeeRadok`]) with every
//! setting from the study, on an equally spaced output grid or on a graded
//! one (dense ramp, optionally log-spaced hold) that resolves a fast ramp
//! and fast relaxation with few points.

use nlvid_model::{FailureKind, ForwardModel, Relaxation, RunFailure, names};
use nlvid_study::{Bounds, Dimension, Section};

use crate::error::{ForwardError, Result};
use crate::lee_radok::LeeRadok;

/// How the output times are placed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum HertzGrid {
    /// `points` equally spaced times in (0, ramp + hold].
    Uniform,
    /// `ramp_points` equally spaced times in (0, ramp], the other
    /// `points − ramp_points` in (ramp, ramp + hold]: equally spaced, or,
    /// with `first_hold_step`, log-spaced in t − ramp from `first_hold_step`
    /// to `hold` (as `nlvid_inverse::ramp_hold_grid`).
    Graded {
        /// Output times on the ramp.
        ramp_points: usize,
        /// First time after the ramp's end [s] of a log-spaced hold.
        first_hold_step: Option<f64>,
    },
}

/// Settings of the analytic linear-viscoelastic Hertz ramp-hold model.
#[derive(Debug, Clone, PartialEq)]
pub struct HertzPronySpec {
    /// Probe (sphere) radius R [m].
    pub probe_radius: f64,
    /// Indentation rate during the ramp [m/s].
    pub rate: f64,
    /// Ramp duration [s].
    pub ramp: f64,
    /// Hold duration after the ramp [s].
    pub hold: f64,
    /// Output points m.
    pub points: usize,
    /// Where the m output times are.
    pub grid: HertzGrid,
}

impl HertzPronySpec {
    /// The settings `nlvid build --model hertz-prony` uses without a study:
    /// R = 5 µm, 1 µm/s for 1 s, 9 s hold, `points` output points.
    pub fn flag_defaults(points: usize) -> Self {
        Self {
            probe_radius: 5e-6,
            rate: 1e-6,
            ramp: 1.0,
            hold: 9.0,
            points,
            grid: HertzGrid::Uniform,
        }
    }

    /// Reads `probe_radius`, `rate`, `ramp`, `hold`, `points` and the
    /// optional `ramp_points`, `first_hold_step` from `[forward]`.
    ///
    /// # Errors
    /// Missing key, wrong unit or out-of-range value (file, line, key).
    pub fn from_section(s: &mut Section) -> Result<Self> {
        let pos = Bounds::positive();
        let probe_radius = s.req_quantity("probe_radius", Dimension::LENGTH, pos)?;
        let rate = s.req_quantity("rate", Dimension::VELOCITY, pos)?;
        let ramp = s.req_quantity("ramp", Dimension::TIME, pos)?;
        let hold = s.req_quantity("hold", Dimension::TIME, Bounds::non_negative())?;
        let points = s.req_usize("points", Bounds::closed(2.0, 1e7))?;
        let ramp_points = s.opt_usize("ramp_points", Bounds::closed(1.0, 1e7))?;
        let first_hold_step = s.opt_quantity("first_hold_step", Dimension::TIME, pos)?;
        let grid = match (ramp_points, first_hold_step) {
            (None, None) => HertzGrid::Uniform,
            (None, Some(_)) => {
                return Err(s
                    .invalid(
                        "first_hold_step",
                        "a log-spaced hold needs `ramp_points` too (output times on the ramp)",
                    )
                    .into());
            }
            (Some(r), first) => {
                let hold_points = points.saturating_sub(r);
                let min_hold = if first.is_some() { 2 } else { 1 };
                if hold_points < min_hold || hold <= 0.0 {
                    return Err(s
                        .invalid(
                            "ramp_points",
                            format!(
                                "{r} of the {points} points on the ramp leaves {hold_points} for \
                                 a hold of {hold} s: the hold needs at least {min_hold} (raise \
                                 `points` or lower `ramp_points`)"
                            ),
                        )
                        .into());
                }
                if let Some(f) = first.filter(|&f| f >= hold) {
                    return Err(s
                        .invalid(
                            "first_hold_step",
                            format!("{f} s is not shorter than the hold ({hold} s)"),
                        )
                        .into());
                }
                HertzGrid::Graded {
                    ramp_points: r,
                    first_hold_step: first,
                }
            }
        };
        Ok(Self {
            probe_radius,
            rate,
            ramp,
            hold,
            points,
            grid,
        })
    }

    /// The output times: (0, ramp + hold], increasing, ending at ramp + hold.
    pub fn times(&self) -> Vec<f64> {
        let end = self.ramp + self.hold;
        let uniform = |start: f64, length: f64, n: usize| {
            (1..=n).map(move |i| start + length * i as f64 / n as f64)
        };
        match self.grid {
            HertzGrid::Uniform => uniform(0.0, end, self.points).collect(),
            HertzGrid::Graded {
                ramp_points,
                first_hold_step,
            } => {
                let n_hold = self.points - ramp_points;
                let mut t: Vec<f64> = uniform(0.0, self.ramp, ramp_points).collect();
                match first_hold_step {
                    None => t.extend(uniform(self.ramp, self.hold, n_hold)),
                    Some(first) => {
                        let (l0, l1) = (first.ln(), self.hold.ln());
                        t.extend((0..n_hold - 1).map(|j| {
                            self.ramp + (l0 + (l1 - l0) * j as f64 / (n_hold - 1) as f64).exp()
                        }));
                        t.push(end);
                    }
                }
                t
            }
        }
    }

    /// Indentation δ(t) of the nominal ramp-hold (m): `rate · min(t, ramp)`,
    /// 0 before contact.
    pub fn indentation(&self, t: f64) -> f64 {
        self.rate * t.clamp(0.0, self.ramp)
    }

    /// The model on [`Self::times`]. On the uniform grid its identity is
    /// that of [`HertzProny::new`] with the same settings.
    ///
    /// # Errors
    /// Settings the kernel refuses ([`LeeRadok::ramp_hold`]); never for
    /// settings read by [`Self::from_section`].
    pub fn build(&self) -> Result<HertzProny> {
        let end = self.ramp + self.hold;
        let base = identity(self.probe_radius, self.rate, self.ramp, self.points, end);
        let identity = match self.grid {
            HertzGrid::Uniform => base,
            HertzGrid::Graded {
                ramp_points,
                first_hold_step,
            } => {
                let hold = match first_hold_step {
                    None => "uniform".to_string(),
                    Some(f) => format!("log from {f:e}"),
                };
                format!("{base}+grid(ramp_points={ramp_points},hold={hold})")
            }
        };
        HertzProny::on_grid(
            self.probe_radius,
            self.rate,
            self.ramp,
            self.times(),
            identity,
        )
    }
}

/// The identity string of the uniform-grid model: its settings and the
/// last of its m times, `end·m/m` (unchanged since the model was evaluated
/// by quadrature: same model, same settings, so existing run stores stay
/// valid).
fn identity(radius: f64, rate: f64, ramp: f64, m: usize, end: f64) -> String {
    let last = end * m as f64 / m as f64;
    format!("HertzProny(R={radius:e},v={rate:e},tr={ramp:e},m={m},tend={last:e})")
}

/// Linear-viscoelastic Hertz indentation by a rigid sphere (ν = ½), ramp at
/// constant rate then hold, through the exact Lee–Radok kernel
/// ([`LeeRadok::ramp_hold`]):
/// `F(t) = (16/3)√R ∫₀ᵗ G(t − s) d(δ^{3/2})/ds ds` with the two-term Prony
/// G(t) of eq. 5.1; parameters [`names::PRONY2`] = `[G0, g1, g2, τ1, τ2]`
/// (Pa, 1, 1, s, s). Microseconds per run.
#[derive(Debug, Clone)]
pub struct HertzProny {
    kernel: LeeRadok,
    radius: f64,
    rate: f64,
    ramp_time: f64,
    identity: String,
}

impl HertzProny {
    /// Probe of radius R (m), ramp at `rate` (m/s) for `ramp_time` (s), then
    /// hold until `end_time`; `m` equally spaced output times in
    /// (0, end_time].
    ///
    /// # Errors
    /// [`ForwardError::Setting`] for non-positive settings or m = 0.
    pub fn new(radius: f64, rate: f64, ramp_time: f64, end_time: f64, m: usize) -> Result<Self> {
        if m == 0 || !(end_time > 0.0) {
            return Err(ForwardError::Setting {
                model: "hertz-prony",
                message: format!(
                    "need at least one output time and end time > 0, got m = {m}, end = {end_time} s"
                ),
            });
        }
        let times = (1..=m).map(|i| end_time * i as f64 / m as f64).collect();
        Self::on_grid(
            radius,
            rate,
            ramp_time,
            times,
            identity(radius, rate, ramp_time, m, end_time),
        )
    }

    /// The same model on any strictly increasing grid, with the identity
    /// the caller gives (it enters the build's study hash).
    ///
    /// # Errors
    /// As [`LeeRadok::ramp_hold`].
    pub fn on_grid(
        radius: f64,
        rate: f64,
        ramp_time: f64,
        times: Vec<f64>,
        identity: String,
    ) -> Result<Self> {
        Ok(Self {
            kernel: LeeRadok::ramp_hold(radius, 0.5, rate, ramp_time, times)?,
            radius,
            rate,
            ramp_time,
            identity,
        })
    }

    /// The kernel (for its Jacobian, [`LeeRadok::force_and_jacobian`]).
    pub fn kernel(&self) -> &LeeRadok {
        &self.kernel
    }

    /// Probe radius R (m).
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// Indentation rate on the ramp (m/s).
    pub fn rate(&self) -> f64 {
        self.rate
    }

    /// Ramp duration (s).
    pub fn ramp_time(&self) -> f64 {
        self.ramp_time
    }
}

impl ForwardModel for HertzProny {
    fn parameter_names(&self) -> Vec<String> {
        names::PRONY2.map(String::from).to_vec()
    }
    fn parameter_units(&self) -> Vec<String> {
        names::PRONY2_UNITS.map(String::from).to_vec()
    }
    fn time_grid(&self) -> &[f64] {
        self.kernel.times()
    }
    fn identity(&self) -> String {
        self.identity.clone()
    }
    fn conditions(&self) -> Option<nlvid_model::BuildConditions> {
        let end = self.kernel.times().last().copied().unwrap_or(0.0);
        let key = |q: &str, k: &str| (q.to_string(), format!("[forward] {k}"));
        Some(nlvid_model::BuildConditions {
            model: "hertz-prony".into(),
            probe_radius_m: Some(self.radius),
            ramp_time_s: Some(self.ramp_time),
            hold_time_s: Some((end - self.ramp_time).max(0.0)),
            depth_m: Some(self.rate * self.ramp_time),
            end_time_s: end,
            cell_height_m: None,
            cell_diameter_m: None,
            keys: vec![
                key("probe_radius_m", "probe_radius"),
                key("ramp_time_s", "ramp"),
                key("hold_time_s", "hold"),
                key("depth_m", "rate (depth = rate × ramp)"),
                key("end_time_s", "hold (grid end = ramp + hold)"),
            ],
        })
    }
    fn run(&self, p: &[f64]) -> std::result::Result<Vec<f64>, RunFailure> {
        let g = Relaxation::from_named(&names::PRONY2, p)
            .map_err(|e| RunFailure::new(FailureKind::InvalidParameters, e.to_string()))?;
        if g.g0() <= 0.0 {
            return Err(RunFailure::new(
                FailureKind::InvalidParameters,
                format!("G0 must be > 0, got {} Pa", g.g0()),
            ));
        }
        Ok(self.kernel.force(&g))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nlvid_study::Study;

    fn spec(extra: &str) -> std::result::Result<HertzPronySpec, String> {
        let mut st = Study::parse(
            "s.toml",
            &(crate::hertz_forward_toml("2.5 um", "10 um/s", "0.2 s", "1.8 s", 10) + extra),
        )
        .map_err(|e| e.to_string())?;
        let mut s = st.section("forward").map_err(|e| e.to_string())?;
        s.skip("model");
        let spec = HertzPronySpec::from_section(&mut s).map_err(|e| e.to_string())?;
        s.finish().map_err(|e| e.to_string())?;
        Ok(spec)
    }

    #[test]
    fn log_graded_grid_is_uniform_on_the_ramp_and_geometric_on_the_hold() {
        let s = spec("ramp_points = 4\nfirst_hold_step = \"1 ms\"\n").unwrap();
        let t = s.times();
        assert_eq!(t.len(), 10);
        for (i, want) in [0.05, 0.1, 0.15, 0.2].iter().enumerate() {
            assert!((t[i] - want).abs() < 1e-15, "t[{i}] = {}", t[i]);
        }
        // t − ramp = 1 ms · r^j, r = (1.8 s / 1 ms)^(1/5), j = 0 … 5.
        let r = (1.8f64 / 1e-3).powf(0.2);
        for j in 0..6 {
            let want = 0.2 + 1e-3 * r.powi(j);
            assert!(
                (t[4 + j as usize] / want - 1.0).abs() < 1e-12,
                "hold point {j}"
            );
        }
        assert_eq!(t[9], 2.0);
        assert!(t.windows(2).all(|w| w[1] > w[0]));
    }

    #[test]
    fn graded_forces_are_the_uniform_models_at_the_same_times_and_hertz_when_elastic() {
        // Uniform hold: times 0.1, 0.2 | 0.4, 0.6, …, 2.0 — every one a time
        // of the 20-point uniform model.
        let graded = spec("ramp_points = 2\n").unwrap();
        assert_eq!(graded.times().len(), 11 - 1);
        let model = HertzPronySpec {
            points: 11,
            ..graded.clone()
        }
        .build()
        .unwrap();
        let uniform = HertzProny::new(2.5e-6, 10e-6, 0.2, 2.0, 20).unwrap();
        let p = [1500.0, 0.4, 0.3, 0.03, 5.0];
        let (fg, fu) = (model.run(&p).unwrap(), uniform.run(&p).unwrap());
        assert_eq!(model.time_grid().len(), 11);
        for (t, f) in model.time_grid().iter().zip(&fg) {
            let i = uniform
                .time_grid()
                .iter()
                .position(|u| (u - t).abs() < 1e-12)
                .unwrap_or_else(|| panic!("{t} not on the uniform grid"));
            assert!((f / fu[i] - 1.0).abs() < 1e-12, "t = {t}: {f} vs {}", fu[i]);
        }
        // g1 = g2 = 0: F = (16/3) G0 √R δ^{3/2}, δ = v·min(t, ramp).
        let log = spec("ramp_points = 4\nfirst_hold_step = \"1 ms\"\n")
            .unwrap()
            .build()
            .unwrap();
        let f = log.run(&[1500.0, 0.0, 0.0, 0.03, 5.0]).unwrap();
        for (t, f) in log.time_grid().iter().zip(&f) {
            let delta = 10e-6 * t.min(0.2);
            let hertz = 16.0 / 3.0 * 1500.0 * 2.5e-6f64.sqrt() * delta.powf(1.5);
            assert!((f / hertz - 1.0).abs() < 1e-10, "t = {t}: {f} vs {hertz}");
        }
    }

    #[test]
    fn the_grid_is_part_of_the_identity_and_the_uniform_model_is_unchanged() {
        let uniform = spec("").unwrap().build().unwrap();
        let plain = HertzProny::new(2.5e-6, 10e-6, 0.2, 2.0, 10).unwrap();
        assert_eq!(uniform.identity(), plain.identity());
        assert_eq!(uniform.time_grid(), plain.time_grid());
        let ids = [
            "ramp_points = 4\n",
            "ramp_points = 5\n",
            "ramp_points = 4\nfirst_hold_step = \"1 ms\"\n",
            "ramp_points = 4\nfirst_hold_step = \"2 ms\"\n",
        ]
        .map(|e| spec(e).unwrap().build().unwrap().identity());
        for (i, a) in ids.iter().enumerate() {
            assert_ne!(a, &plain.identity());
            for b in &ids[i + 1..] {
                assert_ne!(a, b);
            }
        }
    }

    #[test]
    fn the_identity_of_the_bundled_demo_meta_model_is_kept() {
        // examples/demo/metamodel/meta.json records this string (built when
        // the model was evaluated by quadrature); the exact kernel is the
        // same model, so stores and meta-models of it stay valid.
        let m = HertzProny::new(2.5e-6, 2e-6, 1.0, 52.0, 520).unwrap();
        assert_eq!(
            m.identity(),
            "HertzProny(R=2.5e-6,v=2e-6,tr=1e0,m=520,tend=5.2e1)"
        );
    }

    #[test]
    fn bad_parameters_are_a_typed_failure() {
        let m = HertzProny::new(5e-6, 1e-6, 1.0, 4.0, 8).unwrap();
        for p in [
            vec![800.0, 0.7, 0.6, 1.0, 2.0],
            vec![0.0, 0.3, 0.3, 1.0, 2.0],
            vec![800.0, 0.3, 0.3, -1.0, 2.0],
            vec![800.0, 0.3, 0.3, 1.0],
        ] {
            let e = m.run(&p).unwrap_err();
            assert_eq!(e.kind, FailureKind::InvalidParameters, "{p:?}: {e}");
        }
        assert!(HertzProny::new(5e-6, 1e-6, 1.0, 4.0, 0).is_err());
    }

    #[test]
    fn bad_grids_name_the_key() {
        let e = spec("first_hold_step = \"1 ms\"\n").unwrap_err();
        assert!(
            e.contains("forward.first_hold_step") && e.contains("needs `ramp_points`"),
            "{e}"
        );
        let e = spec("ramp_points = 10\n").unwrap_err();
        assert!(
            e.contains("s.toml:8") && e.contains("forward.ramp_points"),
            "{e}"
        );
        let e = spec("ramp_points = 9\nfirst_hold_step = \"1 ms\"\n").unwrap_err();
        assert!(e.contains("leaves 1 for a hold"), "{e}");
        let e = spec("ramp_points = 4\nfirst_hold_step = \"2 s\"\n").unwrap_err();
        assert!(e.contains("not shorter than the hold"), "{e}");
    }
}
