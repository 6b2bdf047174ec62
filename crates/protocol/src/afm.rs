//! The AFM two-step indentation script (§5.2.2, Fig. 5.2; App. A.1.2,
//! Fig. A.1) and the cantilever relations F = k·d, δ = Z − d.
//!
//! Sign convention: the piezo position `Z` and the deflection `d` are
//! positive toward the sample, measured from the engaged position (Z = 0 at
//! the start of step 2), so the indentation `δ = Z − d` is positive into
//! the cell and a repulsive force `F = k·d` is positive.
//!
//! Reading of the thesis text (the figure itself is not in our copy):
//! - Step 1 ramps the deflection set point by δd at `v` (1 nm/s, δd = 4 nm
//!   in ch. V; 5 nm in App. A) — force control, `F_set = k·δd` ≈ 0.3–0.5 nN —
//!   then holds (15 s in App. A; ch. V gives no hold, default 0).
//! - Step 2 moves the piezo: cycle 1 goes 0 → `depth` (2 µm; 3 µm in
//!   App. A) → `depth − retract` (1 µm back); "these positions were
//!   repeated", so cycles 2, 3 go `depth − retract` → `depth` →
//!   `depth − retract`; each cycle uses one rate for both legs (10, 5,
//!   1 µm/s). Then a ramp at 10 µm/s back to `final_depth` (= `depth`) and a
//!   50 s hold. With the ch. V values step 2 lasts 0.3 + 0.4 + 2 + 0.1 + 50 =
//!   52.8 s, consistent with the thesis's "end of the loading, t = 52 s".

use crate::program::check_positive;
use crate::{Label, Leg, Program, ProgramBuilder, ProtocolError, Quantity, Result};

/// A cantilever of stiffness `k` (N/m): F = k·d, δ = Z − d (§5.2.2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cantilever {
    k: f64,
}

impl Cantilever {
    /// A cantilever of spring constant `k` in N/m (thesis: 0.120, 0.083,
    /// 0.080 N/m).
    ///
    /// # Errors
    /// `k` not finite and > 0.
    pub fn new(k: f64) -> Result<Self> {
        check_positive("k", k)?;
        Ok(Self { k })
    }

    /// Spring constant, N/m.
    pub fn k(&self) -> f64 {
        self.k
    }

    /// Force from deflection, F = k·d (§5.2.2).
    pub fn force(&self, deflection: f64) -> f64 {
        self.k * deflection
    }

    /// Deflection from force, d = F/k.
    pub fn deflection(&self, force: f64) -> f64 {
        force / self.k
    }

    /// Indentation from piezo position and force, δ = Z − F/k.
    pub fn indentation_from_force(&self, piezo: f64, force: f64) -> f64 {
        indentation(piezo, self.deflection(force))
    }
}

/// Indentation of the sample, δ = Z − d (§5.2.2).
pub fn indentation(piezo: f64, deflection: f64) -> f64 {
    piezo - deflection
}

/// Step 1 of the script: force-controlled engagement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Engage {
    /// Set-point force reached at the end of the ramp, N.
    pub setpoint_force: f64,
    /// Duration of the set-point ramp, s.
    pub ramp_time: f64,
    /// Hold at the set point before step 2, s (0: none).
    pub hold: f64,
}

impl Engage {
    /// From the script's deflection set point: ramp the deflection by
    /// `delta_d` (m) at `velocity` (m/s) on a cantilever `k` (N/m), then hold.
    /// Ch. V: δd = 4 nm, 1 nm/s, k = 0.12 N/m → 0.48 nN over 4 s.
    ///
    /// # Errors
    /// Any argument not finite and > 0 (`hold` may be 0).
    pub fn from_deflection(k: f64, delta_d: f64, velocity: f64, hold: f64) -> Result<Self> {
        let c = Cantilever::new(k)?;
        check_positive("delta_d", delta_d)?;
        check_positive("velocity", velocity)?;
        let e = Self {
            setpoint_force: c.force(delta_d),
            ramp_time: delta_d / velocity,
            hold,
        };
        e.check()?;
        Ok(e)
    }

    fn check(&self) -> Result<()> {
        check_positive("setpoint_force", self.setpoint_force)?;
        check_positive("ramp_time", self.ramp_time)?;
        if !(self.hold.is_finite() && self.hold >= 0.0) {
            return Err(ProtocolError::Parameter {
                name: "engage hold",
                value: self.hold,
                reason: "must be finite and ≥ 0",
            });
        }
        Ok(())
    }

    /// Set-point force F(t) of step 1, from 0 at t = 0.
    ///
    /// # Errors
    /// Invalid parameters.
    pub fn program(&self) -> Result<Program> {
        self.check()?;
        let mut b = ProgramBuilder::new(Quantity::Force, 0.0).ramp_over(
            self.setpoint_force,
            self.ramp_time,
            Label::Engage,
        )?;
        if self.hold > 0.0 {
            b = b.hold(self.hold, Label::EngageHold)?;
        }
        b.build()
    }
}

/// The AFM two-step script: engagement under force control, then the piezo
/// program of ramp-reverse cycles, a ramp and a hold (Fig. 5.2).
#[derive(Debug, Clone, PartialEq)]
pub struct AfmScript {
    /// Step 1.
    pub engage: Engage,
    /// Rate of each ramp-reverse cycle, m/s (one entry per cycle).
    pub cycle_rates: Vec<f64>,
    /// Piezo travel of the first loading leg, m.
    pub depth: f64,
    /// Retraction of each reversal leg, m (0 < retract ≤ depth).
    pub retract: f64,
    /// Rate of the final ramp, m/s.
    pub final_rate: f64,
    /// Piezo position reached by the final ramp, m (thesis: `depth`).
    pub final_depth: f64,
    /// Hold at `final_depth`, s.
    pub hold: f64,
}

impl AfmScript {
    /// The ch. V script (§5.2.2): δd = 4 nm at 1 nm/s on `k`, no engage
    /// hold; cycles at 10, 5, 1 µm/s between 2 µm and 1 µm; 10 µm/s ramp to
    /// 2 µm; 50 s hold.
    ///
    /// # Errors
    /// `k` not finite and > 0.
    pub fn thesis_ch5(k: f64) -> Result<Self> {
        Ok(Self {
            engage: Engage::from_deflection(k, 4e-9, 1e-9, 0.0)?,
            cycle_rates: vec![10e-6, 5e-6, 1e-6],
            depth: 2e-6,
            retract: 1e-6,
            final_rate: 10e-6,
            final_depth: 2e-6,
            hold: 50.0,
        })
    }

    /// The App. A.1.2 script: δd = 5 nm at 1 nm/s, 15 s engage hold, first
    /// leg 3 µm, otherwise as [`AfmScript::thesis_ch5`].
    ///
    /// # Errors
    /// `k` not finite and > 0.
    pub fn thesis_app_a(k: f64) -> Result<Self> {
        Ok(Self {
            engage: Engage::from_deflection(k, 5e-9, 1e-9, 15.0)?,
            depth: 3e-6,
            final_depth: 3e-6,
            ..Self::thesis_ch5(k)?
        })
    }

    /// Check every parameter; the error names the first bad one.
    ///
    /// # Errors
    /// See [`ProtocolError::Parameter`].
    pub fn check(&self) -> Result<()> {
        self.engage.check()?;
        for &r in &self.cycle_rates {
            check_positive("cycle rate", r)?;
        }
        check_positive("depth", self.depth)?;
        check_positive("retract", self.retract)?;
        if self.retract > self.depth {
            return Err(ProtocolError::Parameter {
                name: "retract",
                value: self.retract,
                reason: "must not exceed depth (the piezo would leave the engaged position)",
            });
        }
        check_positive("final_rate", self.final_rate)?;
        check_positive("final_depth", self.final_depth)?;
        check_positive("hold", self.hold)?;
        Ok(())
    }

    /// Piezo position Z(t) of step 2, t = 0 at its start (Fig. 5.2).
    ///
    /// # Errors
    /// Invalid parameters (see [`AfmScript::check`]).
    pub fn piezo(&self) -> Result<Program> {
        self.check()?;
        let low = self.depth - self.retract;
        let mut b = ProgramBuilder::new(Quantity::Displacement, 0.0);
        for (i, &rate) in self.cycle_rates.iter().enumerate() {
            let cycle = i + 1;
            b = b.ramp_to(
                self.depth,
                rate,
                Label::RampReverse {
                    cycle,
                    leg: Leg::Load,
                },
            )?;
            b = b.ramp_to(
                low,
                rate,
                Label::RampReverse {
                    cycle,
                    leg: Leg::Unload,
                },
            )?;
        }
        if b.value() != self.final_depth {
            b = b.ramp_to(self.final_depth, self.final_rate, Label::Ramp)?;
        }
        b.hold(self.hold, Label::Hold)?.build()
    }

    /// Set-point force of step 1 (see [`Engage::program`]).
    ///
    /// # Errors
    /// Invalid parameters.
    pub fn engage_program(&self) -> Result<Program> {
        self.engage.program()
    }

    /// Duration of step 1, s (step 2 starts this long after the engage ramp
    /// begins).
    pub fn engage_duration(&self) -> f64 {
        self.engage.ramp_time + self.engage.hold
    }
}
