//! DACE's `boxmin`: a Hooke–Jeeves pattern search on a multiplicative
//! scale inside the box `lo ≤ θ ≤ up` (Lophaven et al. 2002, §3.1 and
//! the toolbox source). It performs `kmax = 2` (p ≤ 2) or `min(p, 4)`
//! explore/move cycles and stops: it is reproducible and cheap but does not
//! locate the likelihood optimum. Kept so that results can be compared
//! with published DACE fits.

use crate::error::Result;

/// Result of a bounded θ search.
#[derive(Debug, Clone)]
pub struct SearchResult {
    /// Best θ found.
    pub theta: Vec<f64>,
    /// ψ(θ) at the best θ.
    pub psi: f64,
    /// Number of objective evaluations.
    pub evaluations: usize,
}

struct State<'f> {
    obj: &'f mut dyn FnMut(&[f64]) -> Result<f64>,
    nv: usize,
    lo: Vec<f64>,
    up: Vec<f64>,
    dd: Vec<f64>,
    ne: Vec<usize>,
}

impl State<'_> {
    fn f(&mut self, t: &[f64]) -> Result<f64> {
        self.nv += 1;
        (self.obj)(t)
    }
}

/// Run DACE's boxmin from `t0` in the box `[lo, up]` on objective `obj`
/// (ψ, `f64::INFINITY` where undefined).
pub fn boxmin(
    t0: &[f64],
    lo: &[f64],
    up: &[f64],
    obj: &mut dyn FnMut(&[f64]) -> Result<f64>,
) -> Result<SearchResult> {
    let p = t0.len();
    let mut t = t0.to_vec();
    let mut dd: Vec<f64> = (1..=p)
        .map(|i| 2f64.powf(i as f64 / (p as f64 + 2.0)))
        .collect();
    for i in 0..p {
        if up[i] == lo[i] {
            dd[i] = 1.0;
            t[i] = up[i];
        }
    }
    let ng: Vec<usize> = (0..p).filter(|&i| t[i] < lo[i] || up[i] < t[i]).collect();
    for &i in &ng {
        t[i] = (lo[i] * up[i].powi(7)).powf(1.0 / 8.0);
    }
    let ne: Vec<usize> = (0..p).filter(|&i| dd[i] != 1.0).collect();
    let mut st = State {
        obj,
        nv: 0,
        lo: lo.to_vec(),
        up: up.to_vec(),
        dd,
        ne,
    };
    let mut f = st.f(&t)?;
    if f.is_infinite() {
        return Ok(SearchResult {
            theta: t,
            psi: f,
            evaluations: st.nv,
        });
    }
    if ng.len() > 1 {
        // Try to improve the starting guess (DACE `start`).
        let (d0, d1) = (16.0, 2.0);
        let th = t.clone();
        let fh = f;
        let mut jdom = ng[0];
        for &j in &ng {
            let mut fk = fh;
            let mut dk: Vec<f64> = vec![1.0; p];
            for &i in &ng {
                dk[i] = 1.0 / d1;
            }
            dk[j] = 1.0 / d0;
            let alpha = ng
                .iter()
                .map(|&i| (st.lo[i] / th[i]).ln() / dk[i].ln())
                .fold(f64::INFINITY, f64::min)
                / 5.0;
            let v: Vec<f64> = dk.iter().map(|x| x.powf(alpha)).collect();
            let mut tk = th.clone();
            for _ in 0..4 {
                let tt: Vec<f64> = tk.iter().zip(&v).map(|(a, b)| a * b).collect();
                let ff = st.f(&tt)?;
                if ff <= fk {
                    tk = tt.clone();
                    fk = ff;
                    if ff <= f {
                        t = tt;
                        f = ff;
                        jdom = j;
                    }
                } else {
                    break;
                }
            }
        }
        if jdom > 0 {
            st.dd.swap(0, jdom);
        }
    }
    let kmax = if p <= 2 { 2 } else { p.min(4) };
    for _ in 0..kmax {
        let th = t.clone();
        explore(&mut st, &mut t, &mut f)?;
        pattern_move(&mut st, &th, &mut t, &mut f)?;
    }
    Ok(SearchResult {
        theta: t,
        psi: f,
        evaluations: st.nv,
    })
}

fn explore(st: &mut State<'_>, t: &mut Vec<f64>, f: &mut f64) -> Result<()> {
    for k in 0..st.ne.len() {
        let j = st.ne[k];
        let mut tt = t.clone();
        let dd = st.dd[j];
        let atbd;
        if t[j] == st.up[j] {
            atbd = true;
            tt[j] = t[j] / dd.sqrt();
        } else if t[j] == st.lo[j] {
            atbd = true;
            tt[j] = t[j] * dd.sqrt();
        } else {
            atbd = false;
            tt[j] = st.up[j].min(t[j] * dd);
        }
        let ff = st.f(&tt)?;
        if ff < *f {
            *t = tt;
            *f = ff;
        } else if !atbd {
            tt[j] = st.lo[j].max(t[j] / dd);
            let ff = st.f(&tt)?;
            if ff < *f {
                *t = tt;
                *f = ff;
            }
        }
    }
    Ok(())
}

fn pattern_move(st: &mut State<'_>, th: &[f64], t: &mut Vec<f64>, f: &mut f64) -> Result<()> {
    let p = t.len();
    let mut v: Vec<f64> = t.iter().zip(th).map(|(a, b)| a / b).collect();
    let rotate =
        |dd: &[f64], e: f64| -> Vec<f64> { (0..p).map(|i| dd[(i + 1) % p].powf(e)).collect() };
    if v.iter().all(|&x| x == 1.0) {
        st.dd = rotate(&st.dd, 0.2);
        return Ok(());
    }
    loop {
        let tt: Vec<f64> = (0..p)
            .map(|i| st.up[i].min(st.lo[i].max(t[i] * v[i])))
            .collect();
        let ff = st.f(&tt)?;
        let mut rept = true;
        let at_bound = (0..p).any(|i| tt[i] == st.lo[i] || tt[i] == st.up[i]);
        if ff < *f {
            *t = tt;
            *f = ff;
            v.iter_mut().for_each(|x| *x *= *x);
        } else {
            rept = false;
        }
        if at_bound {
            rept = false;
        }
        if !rept {
            break;
        }
    }
    st.dd = rotate(&st.dd, 0.25);
    Ok(())
}
