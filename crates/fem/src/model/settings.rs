//! Solver settings of a model: Newton, line search, time stepping, dense
//! output, contact penalty, threads.

/// Solver settings.
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    /// Use the F-bar element (true) or the plain displacement element.
    pub fbar: bool,
    /// Residual tolerance relative to the gross internal force, tested
    /// only after at least one Newton correction (a predictor is never
    /// accepted as it stands). Default 1e-9; the AFM cell model uses 3e-5
    /// ([`crate::afm::AfmSetup::thesis_setup1`], docs/theory/fem.md
    /// "Session 23").
    pub rtol: f64,
    /// Absolute residual tolerance (N): a step also counts as converged when
    /// the residual norm is below it. 0 (the default) disables it; set it
    /// to ≈ rtol × the run's peak force when the load passes through zero
    /// (contact separation), where `rtol` × the vanishing current force is
    /// below round-off.
    pub atol: f64,
    /// Newton iterations allowed per attempt.
    pub max_iterations: usize,
    /// Step reductions allowed in the line search (each to between 0.1
    /// and 0.5 of the last trial, by the residual model of
    /// `backtrack_step`).
    pub line_search: usize,
    /// Contact penalty ε = penalty · G / h (G from the material at F = I,
    /// h the local surface spacing): penetration ≈ p h / (penalty G).
    pub penalty: f64,
    /// Step growth factor after an easy step (≤ `easy_iterations`).
    pub growth: f64,
    /// Newton iterations below which a step counts as easy.
    pub easy_iterations: usize,
    /// Step reduction factor after a failed attempt.
    pub cutback: f64,
    /// Smallest step, as a fraction of the stage duration.
    pub min_step_fraction: f64,
    /// Extrapolate the last increment as the Newton predictor.
    pub extrapolate: bool,
    /// Tangent (Euler) predictor for a step that moves the probe (a
    /// prescribed displacement, the spring's free end or the applied
    /// force): the increment
    /// K Δu = −(∂R/∂λ) Δλ with the last factorised tangent (one
    /// back-substitution), instead of extrapolating the last increment.
    pub tangent_predictor: bool,
    /// The material tangent is symmetric: factorise with LDLᵀ (LU
    /// fallback); false forces LU.
    pub symmetric: bool,
    /// Largest rise of the residual norm accepted for a full Newton step
    /// (× the previous norm); above it, the line search halves the step
    /// until the residual decreases.
    pub residual_growth: f64,
    /// Residual-only trial points near convergence: when the residual norm
    /// is within this factor of the tolerance, the Newton step is expected
    /// to converge (quadratic convergence), so its trial points are assembled
    /// without the tangent and the tangent is assembled only if the accepted
    /// point turns out not converged (then, with `chord_contraction`, a
    /// chord step may follow instead). 0 disables. Default 1e5 (session 3:
    /// 1e4 without chord steps; with them 1e5 measured best on the thesis
    /// run and the elastic dome at `rtol` 1e-9, docs/theory/fem.md
    /// "Speed"); the AFM cell model, at `rtol` 3e-5, disables it.
    pub lazy_tangent: f64,
    /// Chord steps near convergence: after a residual-only (lazy)
    /// assembly that is not converged but shows the residual contracted by
    /// at least this factor in the last step, the next correction reuses
    /// the last factors (no tangent assembly, no factorisation) and is kept
    /// only if it contracts the residual by this factor again; otherwise
    /// the tangent is assembled at that point. 0 disables. Default 0.1.
    pub chord_contraction: f64,
    /// Dense output: largest estimated interpolation error of the probe
    /// (or plane) force between steps, relative to the force (floor
    /// 1e-7 G L²); steps that exceed `output_rejection` × it are redone
    /// smaller, and the next step is sized for it (module `dense`). 0
    /// disables. Default 2e-4.
    pub output_tolerance: f64,
    /// Dense output: a converged step whose estimated interpolation error
    /// exceeds this multiple of `output_tolerance` is rejected and redone
    /// smaller (the next step is sized for 0.9× the tolerance either
    /// way). Default 2.5 (session 12; 1.5 before): the estimate bounds
    /// the error of the quadratic while the written curve is the cubic, and
    /// at 1.5 one step in 8–16 was redone (docs/theory/fem.md, "Speed").
    pub output_rejection: f64,
    /// Threads for the element loop (material updates); 0 or 1 = serial. The
    /// result is bitwise the same for any number (element outputs are
    /// computed in parallel, then added in element order). The loop
    /// evaluates four elements at a time, one per SIMD lane, where the
    /// element kind and material have a lane form (the axisymmetric Q4 with
    /// this crate's cell materials; docs/theory/fem.md, "Session 20"),
    /// bitwise the one-element results; threaded, one group of four per
    /// task. (No setting of its own: a field here would enter the models'
    /// identity, and with it the study hash of every run store, for a choice
    /// that changes no result.)
    pub threads: usize,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            fbar: true,
            rtol: 1e-9,
            atol: 0.0,
            max_iterations: 14,
            line_search: 6,
            penalty: 100.0,
            growth: 1.5,
            easy_iterations: 4,
            cutback: 0.25,
            min_step_fraction: 1e-6,
            extrapolate: true,
            tangent_predictor: true,
            symmetric: true,
            residual_growth: 1.0,
            lazy_tangent: 1e5,
            chord_contraction: 0.1,
            output_tolerance: 2e-4,
            output_rejection: 2.5,
            threads: 1,
        }
    }
}
