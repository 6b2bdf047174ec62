//! One run of a study's forward model at one parameter set — what
//! `nlvid simulate` and `nlvid membrane` compute. The study is the one
//! `nlvid build` reads: `[forward]` and `[protocol]` with the same keys and
//! defaults, plus `[parameters]` holding one value per model parameter
//! (the names of `[design.parameters]`, with units):
//!
//! ```toml
//! [parameters]              # afm-fe, hertz-prony: eq. 5.1
//! G0 = "1 kPa"
//! g1 = 0.3
//! g2 = 0.3
//! tau1 = "0.5 s"
//! tau2 = "10 s"
//! ```
//!
//! Sections of the other stages (`[design]`, `[build]`, `[fit]`, …) are
//! left to their commands. The sections of the former `nlvid simulate`
//! schema (`[geometry]`, `[cantilever]`, `[fem]`, `[material]` with `G0`)
//! and of the former `nlvid membrane` schema (`[membrane]`) are errors that
//! name the keys to use.

use nlvid_fem::afm::AfmRun;
use nlvid_membrane::MembraneRun;
use nlvid_model::Curve;
use nlvid_study::{Bounds, Dimension, Study};

use crate::error::{ForwardError, Result};
use crate::{ForwardSettings, ForwardSpec, fem_failure};

/// Sections of the other pipeline stages that may share the study file.
const OTHER_STAGES: [&str; 6] = ["design", "build", "fit", "probe", "material", "loading"];

/// Sections of the former schemas and where their keys went.
const MOVED: [(&str, &str); 5] = [
    (
        "geometry",
        "[geometry] is now part of [forward] (model = \"afm-fe\"): height, diameter, probe_radius",
    ),
    (
        "cantilever",
        "[cantilever] is now part of [forward]: `k` is `spring_constant`, `rigid = true` is \
         `cantilever = \"rigid\"`",
    ),
    (
        "fem",
        "[fem] is now part of [forward]: elements_per_side, `bias` is `mesh_bias`, bulk_ratio",
    ),
    (
        "membrane",
        "[membrane] is now [forward] model = \"membrane\" (radius, wall_thickness, rs, nodes, a), \
         the loading is [protocol] (SI units) and the material [parameters] (the model's \
         parameter names)",
    ),
    (
        "cell",
        "the parameter values are [parameters] (one key per model parameter)",
    ),
];

/// A study read for one forward run.
#[derive(Debug, Clone, PartialEq)]
pub struct SimulateStudy {
    /// `[forward]` (+ `[protocol]`).
    pub forward: ForwardSettings,
    /// Parameter names, in model order.
    pub names: Vec<String>,
    /// Their SI units (`"1"` when dimensionless).
    pub units: Vec<String>,
    /// The values of `[parameters]` (SI), in model order.
    pub values: Vec<f64>,
}

impl SimulateStudy {
    /// Reads `[forward]`, `[protocol]` and `[parameters]`, then checks the
    /// study for unknown sections.
    ///
    /// # Errors
    /// Missing or invalid keys (file, line, key); a section of a former
    /// schema, naming the keys that replace it; a model that cannot be
    /// built from the settings.
    pub fn from_study(mut study: Study) -> Result<Self> {
        for (old, message) in MOVED {
            if study.has(old) {
                return Err(study.root().invalid(old, message).into());
            }
        }
        let forward = ForwardSettings::from_study(&mut study)?;
        let model = forward.build()?;
        let (names, units) = (model.parameter_names(), model.parameter_units());
        if !study.has("parameters") {
            let hint = if study.has("material") {
                " ([material] is read by `nlvid material`, not by the forward models)"
            } else {
                ""
            };
            return Err(study
                .root()
                .invalid(
                    "parameters",
                    format!(
                        "missing section [parameters]: one value per parameter of `{}` ({}){hint}",
                        model_name(&forward.spec),
                        names.join(", ")
                    ),
                )
                .into());
        }
        let mut p = study.section("parameters")?;
        let mut values = Vec::with_capacity(names.len());
        for (name, unit) in names.iter().zip(&units) {
            let v = match unit.as_str() {
                "Pa" => p.req_quantity(name, Dimension::PRESSURE, Bounds::positive())?,
                "s" => p.req_quantity(name, Dimension::TIME, Bounds::positive())?,
                _ => p.req_f64(name, Bounds::non_negative())?,
            };
            values.push(v);
        }
        // Models parametrised by G(t) of eq. 5.1 (G0, g_k, tau_k): the
        // weights must leave a non-negative long-term modulus — refused
        // here, before any run, with the key.
        if names.iter().any(|n| n == nlvid_model::names::G0)
            && let Err(e) = nlvid_model::Relaxation::from_named(&names, &values)
        {
            return Err(p.invalid("g1", e.to_string()).into());
        }
        p.finish()?;
        for other in OTHER_STAGES {
            study.root().skip(other);
        }
        let _ = study.root().opt_str("title")?;
        study.finish()?;
        Ok(Self {
            forward,
            names,
            units,
            values,
        })
    }

    /// `(name, value, unit)` of every parameter.
    pub fn parameters(&self) -> Vec<(String, f64, String)> {
        self.names
            .iter()
            .zip(&self.values)
            .zip(&self.units)
            .map(|((n, v), u)| (n.clone(), *v, u.clone()))
            .collect()
    }
}

fn model_name(spec: &ForwardSpec) -> &'static str {
    spec.name()
}

/// The result of one run.
#[derive(Debug, Clone)]
pub enum Simulation {
    /// The AFM finite-element model: forces, deflection, indentation,
    /// solver statistics and the deformed mesh.
    AfmFe(Box<AfmRun>),
    /// The membrane solver: the dimensionless history and profiles, with
    /// the scales (r0 m, h0 m, G1(0) Pa) of eq. 2.47.
    Membrane {
        /// The run.
        run: MembraneRun,
        /// r0, h0, G1(0).
        scales: (f64, f64, f64),
    },
    /// Any other model: its response on its grid.
    Response(Curve),
}

impl SimulateStudy {
    /// The model's name in `[forward] model`.
    pub fn model(&self) -> &'static str {
        model_name(&self.forward.spec)
    }

    /// Runs the model once at the study's parameters; the membrane keeps
    /// profiles at the solve times nearest to `profile_times` (s).
    ///
    /// # Errors
    /// The run fails (non-convergence, wrinkling, …), with the model's
    /// message and the time where known.
    pub fn run(&self, profile_times: &[f64]) -> Result<Simulation> {
        let failed = |message: String| ForwardError::Setting {
            model: self.model(),
            message,
        };
        match &self.forward.spec {
            ForwardSpec::AfmFe(spec) => {
                // Parameters in `names::PRONY2` order (G0 the shear modulus).
                let params =
                    nlvid_model::Relaxation::from_named(&nlvid_model::names::PRONY2, &self.values)
                        .map_err(|e| failed(e.to_string()))?;
                // A single run is all that is going on: its element loop
                // uses both cores (bitwise the serial result, fem crate
                // test `parallel_element_loop_is_bitwise_serial`).
                let mut setup = spec.setup()?;
                setup.settings.threads = std::thread::available_parallelism()
                    .map_or(1, std::num::NonZeroUsize::get)
                    .min(2);
                nlvid_fem::afm::run(&params, &setup)
                    .map(|r| Simulation::AfmFe(Box::new(r)))
                    .map_err(|e| failed(fem_failure(&e).to_string()))
            }
            ForwardSpec::Membrane(spec) => {
                let model = spec.build()?;
                let run = model
                    .run_full(&self.values, profile_times)
                    .map_err(|e| failed(e.to_string()))?;
                let scales = model
                    .scales(&self.values)
                    .map_err(|e| failed(e.to_string()))?;
                Ok(Simulation::Membrane { run, scales })
            }
            ForwardSpec::CapsuleFe(spec) => {
                let (curve, _notes) = spec
                    .build()?
                    .run_curve(&self.values)
                    .map_err(|e| failed(e.to_string()))?;
                Ok(Simulation::Response(curve))
            }
            ForwardSpec::HertzProny(_) => {
                let model = self.forward.build()?;
                let force = model.run(&self.values).map_err(|e| failed(e.to_string()))?;
                Curve::new(model.time_grid().to_vec())
                    .and_then(|c| c.with("force", "N", force))
                    .map(Simulation::Response)
                    .map_err(|e| failed(e.to_string()))
            }
        }
    }
}

impl Simulation {
    /// The time history as one curve in SI: for `afm-fe` piezo, deflection,
    /// force, indentation; for the membrane plate displacement D, half
    /// height H1, force F, pressure p, contact angle ψc, crown stretch λ0,
    /// contact radius a, equatorial radius and the smallest tension.
    ///
    /// # Errors
    /// A non-finite value in the run (named by channel and time).
    pub fn curve(&self) -> Result<Curve> {
        let bad = |e: nlvid_model::ModelError| ForwardError::Setting {
            model: "simulate",
            message: e.to_string(),
        };
        match self {
            Simulation::AfmFe(r) => Curve::new(r.time.clone())
                .and_then(|c| c.with("piezo", "m", r.piezo.clone()))
                .and_then(|c| c.with("deflection", "m", r.deflection.clone()))
                .and_then(|c| c.with("force", "N", r.force.clone()))
                .and_then(|c| c.with("indentation", "m", r.indentation.clone()))
                .map_err(bad),
            Simulation::Membrane {
                run,
                scales: (r0, h0, g10),
            } => {
                let col = |f: &dyn Fn(&nlvid_membrane::StepRecord) -> f64, scale: f64| {
                    run.history.iter().map(|r| f(r) * scale).collect::<Vec<_>>()
                };
                let (force, stress, tension) = (g10 * h0 * r0, g10 * h0 / r0, g10 * h0);
                Curve::new(col(&|r| r.time, 1.0))
                    .and_then(|c| c.with("displacement", "m", col(&|r| r.displacement, *r0)))
                    .and_then(|c| c.with("half_height", "m", col(&|r| r.h1, *r0)))
                    .and_then(|c| c.with("force", "N", col(&|r| r.force, force)))
                    .and_then(|c| c.with("pressure", "Pa", col(&|r| r.pressure, stress)))
                    .and_then(|c| c.with("contact_angle", "rad", col(&|r| r.psi_c, 1.0)))
                    .and_then(|c| c.with("crown_stretch", "1", col(&|r| r.lambda0, 1.0)))
                    .and_then(|c| c.with("contact_radius", "m", col(&|r| r.contact_radius, *r0)))
                    .and_then(|c| c.with("equator_radius", "m", col(&|r| r.equator_radius, *r0)))
                    .and_then(|c| c.with("min_tension", "N/m", col(&|r| r.min_tension, tension)))
                    .map_err(bad)
            }
            Simulation::Response(c) => Ok(c.clone()),
        }
    }

    /// Peak, final and smallest force (N) — for afm-fe the peak over every
    /// solver step, which the output grid may miss — and the curve's last
    /// row by column header (`final`), plus the solver's counts for afm-fe.
    ///
    /// # Errors
    /// As [`Simulation::curve`].
    pub fn summary_json(&self) -> Result<serde_json::Value> {
        let curve = self.curve()?;
        let force = curve.values("force").unwrap_or_default();
        let peak = match self {
            Simulation::AfmFe(r) => r.peak_force,
            _ => force.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        };
        let min = force.iter().copied().fold(f64::INFINITY, f64::min);
        let last: serde_json::Map<String, serde_json::Value> = curve
            .time()
            .last()
            .map(|t| ("time_s".to_string(), serde_json::json!(t)))
            .into_iter()
            .chain(
                curve
                    .channels()
                    .iter()
                    .filter_map(|c| c.values.last().map(|v| (c.header(), serde_json::json!(v)))),
            )
            .collect();
        let mut v = serde_json::json!({
            "peak_force_N": peak, "final_force_N": force.last(), "min_force_N": min,
            "final": last,
        });
        if let Simulation::AfmFe(r) = self {
            v["solver"] = serde_json::json!({
                "elements": r.elements, "steps": r.steps, "cutbacks": r.cutbacks,
                "newton_iterations": r.iterations, "wall_time_s": r.wall_seconds,
            });
        }
        Ok(v)
    }

    /// The run as one JSON document (`nlvid simulate --json`, `nlvid
    /// membrane --json`): `provenance`, `model`, `parameters` (unit-suffixed
    /// keys), `curve`, the [`Simulation::summary_json`] keys, then the keys
    /// of `extra` (where the files went).
    ///
    /// # Errors
    /// As [`Simulation::curve`].
    pub fn to_json(
        &self,
        sim: &SimulateStudy,
        provenance: serde_json::Value,
        extra: serde_json::Value,
    ) -> Result<serde_json::Value> {
        let mut doc = serde_json::json!({
            "provenance": provenance,
            "model": sim.model(),
            "parameters": nlvid_model::parameters_json(&sim.parameters()),
            "curve": self.curve()?.to_json(),
        });
        for more in [self.summary_json()?, extra] {
            for (k, v) in more.as_object().into_iter().flatten() {
                doc[k] = v.clone();
            }
        }
        Ok(doc)
    }

    /// What `nlvid simulate` / `nlvid membrane` print for the run of study
    /// `name`: with `json`, [`Simulation::to_json`] with `files` as one
    /// pretty JSON document; else [`Simulation::summary_text`] and `wrote`
    /// (where the files went). Ends with a newline.
    ///
    /// # Errors
    /// As [`Simulation::curve`].
    pub fn report(
        &self,
        json: bool,
        sim: &SimulateStudy,
        (name, provenance): (&str, &serde_json::Value),
        (files, wrote): (serde_json::Value, &str),
    ) -> Result<String> {
        if json {
            let doc = self.to_json(sim, provenance.clone(), files)?;
            let text = serde_json::to_string_pretty(&doc).map_err(|e| ForwardError::Setting {
                model: "simulate",
                message: e.to_string(),
            })?;
            return Ok(text + "\n");
        }
        Ok(format!("{} → {wrote}\n", self.summary_text(name)?))
    }

    /// The summary for people: for afm-fe the solver's counts, then the
    /// peak, final and smallest force.
    ///
    /// # Errors
    /// As [`Simulation::curve`].
    pub fn summary_text(&self, name: &str) -> Result<String> {
        let v = self.summary_json()?;
        let f = |k: &str| v[k].as_f64().unwrap_or(f64::NAN);
        let mut s = String::new();
        if let Simulation::AfmFe(r) = self {
            s.push_str(&format!(
                "{name}: {} elements, {} steps ({} cut-backs, {} Newton iterations) in {:.2} s\n",
                r.elements, r.steps, r.cutbacks, r.iterations, r.wall_seconds
            ));
        }
        s.push_str(&format!(
            "peak force {:.4e} N, final force {:.4e} N, min force {:.4e} N",
            f("peak_force_N"),
            f("final_force_N"),
            f("min_force_N")
        ));
        Ok(s)
    }

    /// afm-fe: the deformed mesh at the end of the run, `node,r_m,z_m`
    /// rows then the element connectivity (counter-clockwise) as `#`
    /// comment lines; `None` for the other models.
    pub fn mesh_csv(&self) -> Option<String> {
        let Simulation::AfmFe(r) = self else {
            return None;
        };
        let mut csv = String::from("node,r_m,z_m\n");
        for (i, p) in r.deformed_nodes.iter().enumerate() {
            csv.push_str(&format!("{i},{:e},{:e}\n", p[0], p[1]));
        }
        csv.push_str("# elements: node indices, counter-clockwise\n");
        for e in &r.elements_connectivity {
            csv.push_str(&format!("# {},{},{},{}\n", e[0], e[1], e[2], e[3]));
        }
        Some(csv)
    }

    /// The membrane profiles kept by the run, as `(time s, CSV)`: one row
    /// per material node, `psi_rad, rho_m, eta_m, lambda1, lambda2,
    /// sigma1_Pa, sigma2_Pa, T1_N_per_m, T2_N_per_m, theta_rad, in_contact`.
    /// Empty for the other models.
    pub fn profiles_csv(&self) -> Vec<(f64, String)> {
        let Simulation::Membrane {
            run,
            scales: (r0, h0, g10),
        } = self
        else {
            return Vec::new();
        };
        run.profiles
            .iter()
            .map(|sol| {
                let mut s = String::from(
                    "psi_rad,rho_m,eta_m,lambda1,lambda2,sigma1_Pa,sigma2_Pa,T1_N_per_m,T2_N_per_m,theta_rad,in_contact\n",
                );
                for v in &sol.profile {
                    s.push_str(&format!(
                        "{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{}\n",
                        v.psi,
                        v.rho * r0,
                        v.eta * r0,
                        v.lambda1,
                        v.lambda2,
                        v.sigma1 * g10,
                        v.sigma2 * g10,
                        v.t1 * g10 * h0,
                        v.t2 * g10 * h0,
                        v.theta,
                        u8::from(v.psi <= sol.record.psi_c)
                    ));
                }
                (sol.record.time, s)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn study(text: &str) -> Result<SimulateStudy> {
        SimulateStudy::from_study(Study::parse("s.toml", text).expect("toml"))
    }

    fn hertz() -> String {
        crate::hertz_forward_toml("5 um", "1 um/s", "1 s", "9 s", 50)
    }

    #[test]
    fn parameters_are_read_by_the_models_names_with_units() {
        let s = study(&format!(
            "{}[parameters]\nG0 = \"1.2 kPa\"\ng1 = 0.3\ng2 = 0.2\ntau1 = \"100 ms\"\ntau2 = \"5 s\"\n\
             [design]\nn_train = 3\n",
            hertz()
        ))
        .expect("study");
        assert_eq!(s.values, [1200.0, 0.3, 0.2, 0.1, 5.0]);
        let Simulation::Response(c) = s.run(&[]).expect("run") else {
            panic!("hertz-prony gives its response");
        };
        assert_eq!(c.len(), 50);
        let e = study(&format!("{}[parameters]\nG0 = \"1.2 kPa\"\n", hertz())).expect_err("g1");
        assert!(e.to_string().contains("`parameters.g1`"), "{e}");
    }

    #[test]
    fn sections_of_the_former_schemas_name_the_keys_that_replace_them() {
        let e = study(&format!("{}[cantilever]\nk = \"0.1 N/m\"\n", hertz())).expect_err("old");
        assert!(e.to_string().contains("`spring_constant`"), "{e}");
        let e = study(&format!("{}[fem]\nbias = 4\n", hertz())).expect_err("old");
        assert!(e.to_string().contains("`mesh_bias`"), "{e}");
        let e = study(&format!("{}[membrane]\nrs = 1.03\n", hertz())).expect_err("old");
        assert!(e.to_string().contains("[parameters]"), "{e}");
        let e = study(&format!("{}[material]\nG0 = \"1 kPa\"\n", hertz())).expect_err("none");
        assert!(
            e.to_string().contains("missing section [parameters]"),
            "{e}"
        );
        assert!(e.to_string().contains("G0, g1, g2, tau1, tau2"), "{e}");
    }
}
