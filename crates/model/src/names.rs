//! Parameter names and what each one means: one name, one physical
//! quantity, in every study key, meta-model column, fit table and command.
//!
//! The cell model of ch. V has the parameters [`PRONY2`] in the order
//! `G0, g1, g2, tau1, tau2`: the modulus, then the Prony weights, then the
//! relaxation times (the order of the study keys `g = [...]`,
//! `tau = [...]`). Table 5.3 lists the same five as (G0, g1, τ1, g2, τ2);
//! nlvid uses one order everywhere and never permutes.

/// Instantaneous shear modulus G(0) = G0 of eq. 5.1 (Pa).
pub const G0: &str = "G0";
/// Mooney–Rivlin constant C1 of eq. 4.1 (Pa); G0 = 2(C1 + C2).
pub const C1: &str = "C1";
/// Mooney–Rivlin constant C2 of eq. 4.1 (Pa).
pub const C2: &str = "C2";
/// Mooney–Rivlin ratio α = C2/C1 of eq. 4.1 (dimensionless).
pub const ALPHA: &str = "alpha";
/// Ch. II's instantaneous Pipkin–Rogers modulus G1(0) of eqs. 2.53–2.56
/// (Pa), which §2.5 calls "C1 = G1(0)". Eq. 2.53 carries a factor 2, so
/// G10 is the eq. 4.1 constant C1 of the instantaneous Mooney–Rivlin
/// response (small-strain shear modulus 2(G10 + G20)); the "C1" of eq. 2.4,
/// which has no factor 2, is 2 G10 (`docs/theory/model.md`).
pub const G10: &str = "G10";
/// Ch. II's instantaneous Mooney–Rivlin parameter γ0 = G2(0)/G1(0).
pub const GAMMA0: &str = "gamma0";

/// Cell height H (m): the FE cell model's geometry as a meta-model input
/// (`[forward] geometry = "inputs"`, issue 17); Table 5.2 / App. B.2 (setup 1
/// mean 12.22 µm).
pub const HEIGHT: &str = "H";
/// Cell base diameter D (m), the second geometry input beside [`HEIGHT`]
/// (setup 1 mean 28.88 µm).
pub const DIAMETER: &str = "D";
/// The geometry inputs [`HEIGHT`], [`DIAMETER`], in the order the FE cell
/// model appends them after [`PRONY2`].
pub const GEOMETRY: [&str; 2] = [HEIGHT, DIAMETER];
/// SI units of [`GEOMETRY`].
pub const GEOMETRY_UNITS: [&str; 2] = ["m", "m"];

/// The five cell parameters of ch. V (eq. 5.1, Table 5.3) in nlvid's order.
pub const PRONY2: [&str; 5] = [G0, "g1", "g2", "tau1", "tau2"];
/// SI units of [`PRONY2`] (`"1"` for dimensionless).
pub const PRONY2_UNITS: [&str; 5] = ["Pa", "1", "1", "s", "s"];

/// The six capsule-wall parameters of ch. IV (eqs. 4.1–4.3, Table 4.1) in
/// nlvid's order — modulus, Mooney–Rivlin ratio, weights, times:
/// `C1` (eq. 4.1, Pa), `alpha` = C2/C1, `g1`, `g2`, `tau1`, `tau2`. The
/// thesis lists them as x(C1, α, g1, τ1, g2, τ2); nlvid never permutes.
pub const CAPSULE: [&str; 6] = [C1, ALPHA, "g1", "g2", "tau1", "tau2"];
/// SI units of [`CAPSULE`].
pub const CAPSULE_UNITS: [&str; 6] = ["Pa", "1", "1", "1", "s", "s"];

/// Name of the k-th (1-based) Prony weight: `g1`, `g2`, …
pub fn weight(k: usize) -> String {
    format!("g{k}")
}

/// Name of the k-th (1-based) relaxation time: `tau1`, `tau2`, …
pub fn time(k: usize) -> String {
    format!("tau{k}")
}

/// The SI unit of a conventional parameter name (`"1"` when
/// dimensionless), or `None` for a name outside the vocabulary.
pub fn unit(name: &str) -> Option<&'static str> {
    match name {
        G0 | C1 | C2 | G10 => Some("Pa"),
        ALPHA | GAMMA0 => Some("1"),
        HEIGHT | DIAMETER => Some("m"),
        _ if indexed(name, "tau") => Some("s"),
        _ if indexed(name, "g") => Some("1"),
        _ => None,
    }
}

/// What a conventional parameter name means, in words (for tables, help
/// and errors), or `None` for a name outside the vocabulary.
pub fn describe(name: &str) -> Option<String> {
    Some(match name {
        G0 => "instantaneous shear modulus G(0) of eq. 5.1".into(),
        C1 => "Mooney–Rivlin C1 of eq. 4.1 (G0 = 2(C1 + C2))".into(),
        C2 => "Mooney–Rivlin C2 of eq. 4.1".into(),
        ALPHA => "Mooney–Rivlin ratio C2/C1 of eq. 4.1".into(),
        G10 => "ch. II instantaneous modulus G1(0) of eqs. 2.53–2.56".into(),
        GAMMA0 => "ch. II Mooney–Rivlin parameter G2(0)/G1(0)".into(),
        HEIGHT => "cell height H (Table 5.2, App. B.2)".into(),
        DIAMETER => "cell base diameter D (Table 5.2, App. B.2)".into(),
        _ if indexed(name, "tau") => format!("relaxation time of Prony term {}", &name[3..]),
        _ if indexed(name, "g") => format!("weight of Prony term {} (eq. 4.2)", &name[1..]),
        _ => return None,
    })
}

/// `prefix` followed by a positive integer (`g1`, `tau12`).
fn indexed(name: &str, prefix: &str) -> bool {
    name.strip_prefix(prefix).is_some_and(|rest| {
        !rest.is_empty() && rest.bytes().all(|b| b.is_ascii_digit()) && !rest.starts_with('0')
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_cell_parameter_has_the_unit_listed_beside_it() {
        for (name, u) in PRONY2
            .iter()
            .zip(PRONY2_UNITS)
            .chain(CAPSULE.iter().zip(CAPSULE_UNITS))
            .chain(GEOMETRY.iter().zip(GEOMETRY_UNITS))
        {
            assert_eq!(unit(name), Some(u), "{name}");
            assert!(describe(name).is_some(), "{name}");
        }
    }

    #[test]
    fn names_outside_the_vocabulary_are_not_guessed() {
        for name in ["g", "tau", "g0", "tau01", "gamma", "E", "c1"] {
            assert_eq!(unit(name), None, "{name}");
        }
        assert_eq!(unit(&weight(12)), Some("1"));
        assert_eq!(unit(&time(3)), Some("s"));
    }
}
