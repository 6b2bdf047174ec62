//! One-step quadrature of the hereditary integrals.
//!
//! Every hereditary integral in this crate is a sum over Prony terms of
//! `H_k(t) = ∫_0^t (1/τ_k) exp(−(t−s)/τ_k) A(s) ds` for some tensor-valued
//! `A(s)` (eq. 2.1 with D.3–D.4; eqs. 4.2–4.3). It obeys the exact recursion
//! `H_k(t_{n+1}) = e^{−Δt/τ_k} H_k(t_n) + ∫_{t_n}^{t_{n+1}} …`, so the history
//! costs O(number of terms) per step. The remaining one-step integral is
//! approximated by `β0 A_n + β1 A_{n+1}` with weights from a [`HistoryRule`].

/// How `A(s)` is treated on one step `[t_n, t_{n+1}]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum HistoryRule {
    /// `A` linear in time on the step, exponential integrated exactly
    /// (second order; exact for steps and for piecewise-linear `A`, so the
    /// step identities hold to rounding for any Δt). Default.
    #[default]
    ExponentialLinear,
    /// The thesis's trapezoidal rule, eq. 2.48 (second order while Δt ≪ τ;
    /// the recursion reproduces the O(steps) sum of eq. 2.48 to rounding).
    Trapezoid,
}

/// Step weights of one Prony term.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct StepWeights {
    /// `exp(−Δt/τ)`, applied to `H(t_n)`.
    pub decay: f64,
    /// Weight of `A(t_n)`.
    pub beta0: f64,
    /// Weight of `A(t_{n+1})`.
    pub beta1: f64,
}

impl HistoryRule {
    pub(crate) fn weights(self, dt: f64, tau: f64) -> StepWeights {
        let x = dt / tau;
        let decay = (-x).exp();
        match self {
            HistoryRule::Trapezoid => StepWeights {
                decay,
                beta0: 0.5 * x * decay,
                beta1: 0.5 * x,
            },
            HistoryRule::ExponentialLinear => {
                // β1 = 1 − (1 − e^{−x})/x, β0 = (1 − e^{−x})/x − e^{−x}.
                let one_minus = -(-x).exp_m1();
                let (beta1, q) = if x < 1e-3 {
                    let b1 = x * (0.5 - x * (1.0 / 6.0 - x * (1.0 / 24.0 - x / 120.0)));
                    (b1, 1.0 - b1)
                } else {
                    let q = one_minus / x;
                    (1.0 - q, q)
                };
                StepWeights {
                    decay,
                    beta0: q - decay,
                    beta1,
                }
            }
        }
    }
}

/// Advances every term of `prony` over one step: writes
/// `H_k(t_{n+1}) = E H_k(t_n) + β0 A_n + β1 A_{n+1}` to `h_out` and returns
/// `(−Σ g_k (E H_k(t_n) + β0 A_n), Σ g_k β1_k)`: the part frozen at `t_n`
/// and the weight of the current `A_{n+1}`.
#[inline]
pub(crate) fn advance(
    rule: HistoryRule,
    prony: &nlvid_model::Prony,
    dt: f64,
    (h_n, a_n): (&[crate::Mat3], &crate::Mat3),
    a_new: &crate::Mat3,
    h_out: &mut Vec<crate::Mat3>,
) -> (crate::Mat3, f64) {
    h_out.resize(prony.len(), crate::Mat3::zeros());
    advance_with(
        rule,
        prony,
        dt,
        |k| h_n[k],
        a_n,
        |k, old, beta1| {
            h_out[k] = old + a_new * beta1;
        },
    )
}

/// The step-constant part of [`advance`], for points in lanes
/// ([`crate::Lane`]): `H_k(t_n)` read by `h_n(k)`; for each term
/// `old_k = E_k H_k(t_n) + β0_k A_n` and `β1_k` go to `step_out(k, ·, ·)`
/// (so `H_k(t_{n+1}) = old_k + A_{n+1} β1_k`, formed by the caller when
/// `A_{n+1}` is known); returns `(−Σ g_k old_k, Σ g_k β1_k)`. Nothing
/// here depends on `A_{n+1}`. The step weights and `Σ g_k β1_k` depend on
/// Δt and the series only, so they are the same in every lane.
#[inline(always)]
pub(crate) fn advance_with<T: crate::Lane>(
    rule: HistoryRule,
    prony: &nlvid_model::Prony,
    dt: f64,
    h_n: impl Fn(usize) -> nalgebra::Matrix3<T>,
    a_n: &nalgebra::Matrix3<T>,
    mut step_out: impl FnMut(usize, nalgebra::Matrix3<T>, f64),
) -> (nalgebra::Matrix3<T>, f64) {
    // The weights copied out of the memo, so the loop below is not a
    // closure (a closure stays a separate function, compiled outside the
    // element kernel's SIMD dispatch); series longer than `SHORT` read them
    // from a vector.
    const SHORT: usize = 8;
    let n = prony.len();
    let mut short = [StepWeights::default(); SHORT];
    let long: Vec<StepWeights> = with_series_weights(rule, prony, dt, |w| {
        if n <= SHORT {
            short[..n].copy_from_slice(w);
            Vec::new()
        } else {
            w.to_vec()
        }
    });
    let weights = if n <= SHORT { &short[..n] } else { &long[..] };
    let mut frozen = nalgebra::Matrix3::zeros();
    let mut sum_b1 = 0.0;
    for (k, (term, w)) in prony.terms().iter().zip(weights).enumerate() {
        let old = h_n(k) * T::splat(w.decay) + a_n * T::splat(w.beta0);
        frozen -= old * T::splat(term.weight);
        step_out(k, old, w.beta1);
        sum_b1 += term.weight * w.beta1;
    }
    (frozen, sum_b1)
}

/// Identifiers unique within the process (never 0): [`fresh_ids`].
static NEXT_ID_BLOCK: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

/// Identifiers taken from the global counter at once by each thread.
const ID_BLOCK: u64 = 1 << 20;

thread_local! {
    /// This thread's unused identifiers `next..end`.
    static IDS: std::cell::Cell<(u64, u64)> = const { std::cell::Cell::new((0, 0)) };
}

/// `N` identifiers never returned before in this process (on any thread)
/// and never 0: a thread takes blocks of [`ID_BLOCK`] from one atomic
/// counter, so a call costs a thread-local increment.
#[inline]
pub(crate) fn fresh_ids<const N: usize>() -> [u64; N] {
    IDS.with(|ids| {
        let (mut next, mut end) = ids.get();
        if end - next < N as u64 {
            let block = NEXT_ID_BLOCK.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            next = block * ID_BLOCK;
            end = next + ID_BLOCK;
        }
        ids.set((next + N as u64, end));
        std::array::from_fn(|i| next + i as u64)
    })
}

/// Entries of the per-thread memo of [`HistoryRule::weights`].
const MEMO: usize = 4;

/// The step weights of every term of one Prony series for one (rule, Δt).
struct MemoEntry {
    rule: HistoryRule,
    dt: u64,
    taus: Vec<u64>,
    weights: Vec<StepWeights>,
}

thread_local! {
    /// The step weights of the last series computed on this thread: a
    /// finite-element assembly evaluates every material point with the same
    /// Δt and series, so `exp`/`expm1` are computed once per step and term
    /// instead of once per point (≈ 5 % of the AFM run), and the memo is
    /// consulted once per point for all terms. Values are bitwise those of
    /// [`HistoryRule::weights`]; the key is the exact (rule, Δt, τ_1…τ_n).
    static WEIGHTS: std::cell::RefCell<(Vec<MemoEntry>, usize)> =
        const { std::cell::RefCell::new((Vec::new(), 0)) };
}

/// Calls `f` with [`HistoryRule::weights`] of every term of `prony`, in
/// term order, through the per-thread memo.
#[inline]
pub(crate) fn with_series_weights<R>(
    rule: HistoryRule,
    prony: &nlvid_model::Prony,
    dt: f64,
    f: impl FnOnce(&[StepWeights]) -> R,
) -> R {
    let terms = prony.terms();
    let dt_bits = dt.to_bits();
    WEIGHTS.with(|memo| {
        let mut memo = memo.borrow_mut();
        let (entries, next) = &mut *memo;
        let n = entries.len();
        // Newest entry first: the current step's series was stored last.
        for k in 1..=n {
            let e = &entries[(*next + n - k) % n];
            if e.dt == dt_bits
                && e.rule == rule
                && e.taus.len() == terms.len()
                && e.taus
                    .iter()
                    .zip(terms)
                    .all(|(t, term)| *t == term.tau.to_bits())
            {
                return f(&e.weights);
            }
        }
        let entry = MemoEntry {
            rule,
            dt: dt_bits,
            taus: terms.iter().map(|t| t.tau.to_bits()).collect(),
            weights: terms.iter().map(|t| rule.weights(dt, t.tau)).collect(),
        };
        let slot = if n < MEMO {
            entries.push(entry);
            n
        } else {
            entries[*next] = entry;
            *next
        };
        *next = (slot + 1) % MEMO;
        f(&entries[slot].weights)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn memoised_weights_equal_direct_weights() {
        let rules = [HistoryRule::ExponentialLinear, HistoryRule::Trapezoid];
        // More distinct keys than memo entries (series of 1–3 terms, some
        // sharing a τ), revisited in another order.
        for pass in 0..3 {
            for k in 0..(3 * MEMO) {
                let dt = 0.01 * (k % 5) as f64 + 1e-3 * pass as f64;
                let pairs: Vec<(f64, f64)> =
                    (0..=(k % 3)).map(|i| (0.1, 0.5 + (k + i) as f64)).collect();
                let prony = nlvid_model::Prony::new("G", &pairs).expect("valid");
                for rule in rules {
                    let direct: Vec<StepWeights> = pairs
                        .iter()
                        .map(|&(_, tau)| rule.weights(dt, tau))
                        .collect();
                    with_series_weights(rule, &prony, dt, |w| assert_eq!(w, &direct[..]));
                }
            }
        }
    }

    #[test]
    fn exponential_linear_weights_integrate_linear_data_exactly() {
        // ∫_0^Δt (1/τ) e^{−(Δt−u)/τ} (p + q u/Δt) du, closed form by hand.
        for &(dt, tau) in &[
            (1e-6, 1.0),
            (2e-4, 0.3),
            (0.5, 0.2),
            (3.0, 0.01),
            (0.0, 1.0),
        ] {
            let w = HistoryRule::ExponentialLinear.weights(dt, tau);
            let (p, q) = (0.7, -1.3);
            let x: f64 = dt / tau;
            let exact_const = -(-x).exp_m1();
            let exact_lin = if x > 0.0 { 1.0 - exact_const / x } else { 0.0 };
            let exact = p * exact_const + q * exact_lin;
            let got = w.beta0 * p + w.beta1 * (p + q);
            assert!(
                (got - exact).abs() < 1e-13 * (1.0 + exact.abs()),
                "{dt} {tau}"
            );
        }
    }
}
