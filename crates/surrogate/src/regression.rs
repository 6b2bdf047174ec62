//! DACE regression models (Lophaven et al. 2002, §2.3): polynomials of
//! degree 0, 1, 2 in the normalised inputs, in the column order of
//! `regpoly0/1/2` so that β matches published values.

use serde::{Deserialize, Serialize};

/// Polynomial regression part `f(x)ᵀβ` of the Kriging model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Regression {
    /// Constant (`regpoly0`).
    Poly0,
    /// Linear (`regpoly1`): 1, x_1 … x_n.
    Poly1,
    /// Quadratic (`regpoly2`): 1, x, then x_k·x_l for k ≤ l, k outer.
    Poly2,
}

impl Regression {
    /// Name used on the command line and in model files.
    pub fn name(self) -> &'static str {
        match self {
            Regression::Poly0 => "poly0",
            Regression::Poly1 => "poly1",
            Regression::Poly2 => "poly2",
        }
    }

    /// Parse `poly0`, `regpoly1`, `0`, …
    pub fn parse(s: &str) -> Option<Self> {
        let s = s.trim().to_ascii_lowercase();
        let s = s.strip_prefix("reg").unwrap_or(&s);
        match s {
            "poly0" | "0" | "constant" => Some(Regression::Poly0),
            "poly1" | "1" | "linear" => Some(Regression::Poly1),
            "poly2" | "2" | "quadratic" => Some(Regression::Poly2),
            _ => None,
        }
    }

    /// Number of basis functions for `dim` inputs.
    pub fn n_terms(self, dim: usize) -> usize {
        match self {
            Regression::Poly0 => 1,
            Regression::Poly1 => 1 + dim,
            Regression::Poly2 => 1 + dim + dim * (dim + 1) / 2,
        }
    }

    /// Basis values `f(x)` written into `f` (length `n_terms`).
    pub fn eval(self, x: &[f64], f: &mut [f64]) {
        f[0] = 1.0;
        if self == Regression::Poly0 {
            return;
        }
        let n = x.len();
        f[1..=n].copy_from_slice(x);
        if self == Regression::Poly2 {
            let mut j = n + 1;
            for k in 0..n {
                for l in k..n {
                    f[j] = x[k] * x[l];
                    j += 1;
                }
            }
        }
    }

    /// Jacobian `∂f_j/∂x_k`, written row-major `df[k * n_terms + j]`
    /// (DACE's `df`, n × p).
    pub fn jacobian(self, x: &[f64], df: &mut [f64]) {
        let n = x.len();
        let p = self.n_terms(n);
        df.iter_mut().for_each(|v| *v = 0.0);
        if self == Regression::Poly0 {
            return;
        }
        for k in 0..n {
            df[k * p + 1 + k] = 1.0;
        }
        if self == Regression::Poly2 {
            let mut j = n + 1;
            for k in 0..n {
                for l in k..n {
                    // ∂(x_k x_l)/∂x_k = x_l, ∂/∂x_l = x_k (both when k = l)
                    df[k * p + j] += x[l];
                    df[l * p + j] += x[k];
                    j += 1;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jacobian_matches_central_differences() {
        let x = [0.3, -1.2, 0.7];
        for r in [Regression::Poly0, Regression::Poly1, Regression::Poly2] {
            let p = r.n_terms(3);
            let mut df = vec![0.0; 3 * p];
            r.jacobian(&x, &mut df);
            for k in 0..3 {
                let h = 1e-6;
                let (mut xp, mut xm) = (x, x);
                xp[k] += h;
                xm[k] -= h;
                let (mut fp, mut fm) = (vec![0.0; p], vec![0.0; p]);
                r.eval(&xp, &mut fp);
                r.eval(&xm, &mut fm);
                for j in 0..p {
                    let fd = (fp[j] - fm[j]) / (2.0 * h);
                    assert!((fd - df[k * p + j]).abs() < 1e-8);
                }
            }
        }
    }

    #[test]
    fn quadratic_terms_follow_regpoly2_order() {
        let mut f = vec![0.0; 6];
        Regression::Poly2.eval(&[2.0, 3.0], &mut f);
        assert_eq!(f, vec![1.0, 2.0, 3.0, 4.0, 6.0, 9.0]);
    }
}
