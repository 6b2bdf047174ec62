//! The ridge move of the ensemble sampler (`ridge_fraction`, given to
//! [`Ensemble::with_ridge`](super::Ensemble::with_ridge)): the fast Prony
//! weight g1 is redrawn uniformly in its u coordinate while G0·(1 − g1)
//! and G0·g2 are kept: r = (1 − g1)/(1 − g1'), G0' = r·G0, g2' = g2/r.
//! Where τ1 lies below the shortest times the data resolve, G(t) for
//! t ≫ τ1 is G0(1 − g1) − G0 g2 (1 − e^{−t/τ2}), unchanged by the move: it
//! jumps along the ridge of the posterior in one step. A deterministic map
//! with an auxiliary uniform (Green 1995): (u, v) ↦ (u', u_g1) is an
//! involution, accepted with min(1, p(y)/p(x)·|J|), |J| =
//! r·φ_G0'(u)/φ_G0'(u') · Π (1/r)·φ_g2'(u)/φ_g2'(u') with φ the axis' map
//! u ↦ x (on a log G0 axis and a linear g2 axis |J| = 1/r). Tests (in
//! `ensemble`): `ridge_map_is_an_involution_with_its_jacobian`,
//! `ridge_move_keeps_a_uniform_prism`.

use nlvid_model::Parameter;

/// The ridge move of the module docs: which coordinates of u are the
/// scale G0, the fast weight g1 (redrawn) and the weights carried at
/// fixed G0·g_k (g2), each with its axis (the map u ↦ x of the domain).
#[derive(Debug, Clone, PartialEq)]
pub struct RidgeMove {
    /// Index in u and axis of the scale G0.
    pub scale: (usize, Parameter),
    /// Index in u and axis of the redrawn weight g1.
    pub fast: (usize, Parameter),
    /// Indices in u and axes of the weights kept at fixed G0·g_k.
    pub carried: Vec<(usize, Parameter)>,
    /// Index in u and axis of the fast weight's relaxation time τ1 (None:
    /// the domain has none).
    pub fast_time: Option<(usize, Parameter)>,
    /// What a ridge step does with τ1.
    pub time_move: RidgeTime,
}

/// What the ridge move does with the fast relaxation time τ1
/// ([`RidgeMove::time_move`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RidgeTime {
    /// τ1 kept: every ridge step is the g1 map ([`RidgeMove::propose`]).
    #[default]
    Kept,
    /// On half the ridge steps τ1 is redrawn uniformly in u as well,
    /// independently of g1 (measured, not better: docs/theory/inverse.md,
    /// session 19).
    Redrawn,
    /// Half the ridge steps are the viscous map instead
    /// ([`RidgeMove::propose_viscous`]): τ1 redrawn at fixed fast-term
    /// viscosity G0·g1·τ1.
    Viscous,
}

impl std::str::FromStr for RidgeTime {
    type Err = String;

    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "kept" => Ok(Self::Kept),
            "redrawn" => Ok(Self::Redrawn),
            "viscous" => Ok(Self::Viscous),
            _ => Err(format!(
                "ridge time `{s}`: expected `kept`, `redrawn` or `viscous`"
            )),
        }
    }
}

impl RidgeMove {
    /// The image of `x` (in u) with the fast weight's u set to `v` (and
    /// the fast time's u to `time`, if given and [`RidgeMove::fast_time`]
    /// is set: a swap with an auxiliary uniform, |J| unchanged), and ln |J|
    /// of the map (module docs); None when 1 − g1' ≤ 0 or a value is not
    /// finite (the move is then rejected).
    pub fn propose(&self, x: &[f64], v: f64, time: Option<f64>) -> Option<(Vec<f64>, f64)> {
        let (i, ref pf) = self.fast;
        let (g, g_new) = (pf.from_unit(x[i]), pf.from_unit(v));
        let r = (1.0 - g) / (1.0 - g_new);
        if !(r.is_finite() && r > 0.0 && 1.0 - g > 0.0) {
            return None;
        }
        let mut y = x.to_vec();
        y[i] = v;
        if let (Some((t, _)), Some(w)) = (&self.fast_time, time) {
            y[*t] = w;
        }
        let mut log_j = self.rescale(x, &mut y, &self.scale, r);
        for c in &self.carried {
            log_j += self.rescale(x, &mut y, c, 1.0 / r);
        }
        log_j.is_finite().then_some((y, log_j))
    }

    /// The viscous map: τ1's u set to `v` (a swap with an auxiliary
    /// uniform), the fast modulus G0·g1 scaled by τ1/τ1' so that the
    /// fast term's viscosity η1 = G0·g1·τ1 is kept, with G0·(1 − g1) and
    /// G0·g_k: G0' = G0(1 − g1) + G0 g1 τ1/τ1', g1' = G0 g1 τ1/(τ1' G0'),
    /// g_k' = G0 g_k/G0'. A term with τ1 well below the ramp's duration
    /// acts on the data as a dashpot of viscosity η1 in parallel with the
    /// rest (eq. 5.1's G(t) integrated against a slow strain rate), so this
    /// map follows the ridge τ1 ↓, g1 ↑, G0 ↑ that the posterior runs along
    /// to τ1's bound (docs/theory/inverse.md, session 19). In the
    /// coordinates (a, b, c_k) = (G0(1 − g1), G0 g1, G0 g_k) the map is
    /// b ↦ b τ1/τ1', and ∂(a, b, c)/∂(G0, g1, g) has determinant
    /// G0^{1+n} (n carried weights), so |∂x'/∂x| = (τ1/τ1')·(G0/G0')^{1+n},
    /// times each axis' φ'(u)/φ'(u'). Returns the image and ln |J|; None
    /// without a fast time, when a value leaves its axis' range or is not
    /// finite (the move is then rejected).
    pub fn propose_viscous(&self, x: &[f64], v: f64) -> Option<(Vec<f64>, f64)> {
        let (t, ref pt) = *self.fast_time.as_ref()?;
        let (i, ref pf) = self.fast;
        let (s, ref ps) = self.scale;
        let (tau, tau_new) = (pt.from_unit(x[t]), pt.from_unit(v));
        let (g0, g1) = (ps.from_unit(x[s]), pf.from_unit(x[i]));
        let fast_new = g0 * g1 * tau / tau_new;
        let g0_new = g0 * (1.0 - g1) + fast_new;
        let mut y = x.to_vec();
        y[t] = v;
        let mut log_j = (tau / tau_new).ln();
        // x_j ↦ `new` on axis (j, p): u_j' and ln φ'(u_j) − ln φ'(u_j').
        let mut set = |(j, p): &(usize, Parameter), new: f64| {
            let u_new = p.to_unit(new);
            y[*j] = u_new;
            p.dx_du(x[*j]).ln() - p.dx_du(u_new).ln()
        };
        log_j += set(&self.scale, g0_new) + set(&self.fast, fast_new / g0_new);
        for c in &self.carried {
            let gk = c.1.from_unit(x[c.0]);
            log_j += set(c, g0 * gk / g0_new);
        }
        log_j += (1 + self.carried.len()) as f64 * (g0 / g0_new).ln();
        let inside = y.iter().all(|u| (0.0..=1.0).contains(u));
        (inside && log_j.is_finite()).then_some((y, log_j))
    }

    /// Sets u_j in `y` for x_j scaled by f on axis `(j, p)`, returning
    /// ln |∂u'/∂u| = ln f + ln φ'(u) − ln φ'(u').
    fn rescale(&self, x: &[f64], y: &mut [f64], (j, p): &(usize, Parameter), f: f64) -> f64 {
        let u_new = p.to_unit(f * p.from_unit(x[*j]));
        y[*j] = u_new;
        f.ln() + p.dx_du(x[*j]).ln() - p.dx_du(u_new).ln()
    }
}
