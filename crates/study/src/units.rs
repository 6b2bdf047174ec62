//! Physical dimensions, units with SI prefixes, and the quantity parser.
//!
//! A quantity is written `"<number> <unit>"`, e.g. `"12.22 um"`, `"0.12 N/m"`,
//! `"5 mm/s"`, `"2.94 kPa"`, `"50 s"`, `"40 nm/V"`, `"30 deg"`. The unit is a
//! product of unit symbols, each with an optional SI prefix and an optional
//! integer exponent (`m^2`, `s^-1`), joined by `*`, `·`, a space, or a single
//! trailing `/` chain (`N/m`, `m/s/s`). After a `/` only further `/` may follow:
//! `N/m s` is ambiguous and rejected — write `N s/m` or `N/m/s`.

use std::fmt;

/// A physical dimension as integer exponents of the base quantities
/// length (m), mass (kg), time (s), electric current (A) and plane angle (rad).
///
/// Angle is kept as its own base so that an angle key demands an angle unit
/// (`deg`, `rad`) and a bare number is never silently read as radians.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct Dimension {
    /// Exponent of length (m).
    pub length: i8,
    /// Exponent of mass (kg).
    pub mass: i8,
    /// Exponent of time (s).
    pub time: i8,
    /// Exponent of electric current (A).
    pub current: i8,
    /// Exponent of plane angle (rad).
    pub angle: i8,
}

impl Dimension {
    /// Builds a dimension from its exponents (length, mass, time, current, angle).
    pub const fn new(length: i8, mass: i8, time: i8, current: i8, angle: i8) -> Self {
        Self {
            length,
            mass,
            time,
            current,
            angle,
        }
    }
    /// A pure number (ratios, stretches, Poisson's ratio, Prony weights).
    pub const NONE: Self = Self::new(0, 0, 0, 0, 0);
    /// Length, m.
    pub const LENGTH: Self = Self::new(1, 0, 0, 0, 0);
    /// Area, m².
    pub const AREA: Self = Self::new(2, 0, 0, 0, 0);
    /// Volume, m³.
    pub const VOLUME: Self = Self::new(3, 0, 0, 0, 0);
    /// Mass, kg.
    pub const MASS: Self = Self::new(0, 1, 0, 0, 0);
    /// Time, s.
    pub const TIME: Self = Self::new(0, 0, 1, 0, 0);
    /// Frequency or rate, 1/s (Hz).
    pub const FREQUENCY: Self = Self::new(0, 0, -1, 0, 0);
    /// Velocity, m/s (piezo speed, plate speed).
    pub const VELOCITY: Self = Self::new(1, 0, -1, 0, 0);
    /// Force, N.
    pub const FORCE: Self = Self::new(1, 1, -2, 0, 0);
    /// Force rate, N/s.
    pub const FORCE_RATE: Self = Self::new(1, 1, -3, 0, 0);
    /// Pressure or stress (moduli C1, E, G), Pa.
    pub const PRESSURE: Self = Self::new(-1, 1, -2, 0, 0);
    /// Force per length, N/m: membrane tension or moduli, spring constants.
    pub const TENSION: Self = Self::new(0, 1, -2, 0, 0);
    /// Spring constant (cantilever stiffness), N/m — same dimension as [`Self::TENSION`].
    pub const STIFFNESS: Self = Self::TENSION;
    /// Energy, J.
    pub const ENERGY: Self = Self::new(2, 1, -2, 0, 0);
    /// Dynamic viscosity, Pa·s.
    pub const VISCOSITY: Self = Self::new(-1, 1, -1, 0, 0);
    /// Electric current, A.
    pub const CURRENT: Self = Self::new(0, 0, 0, 1, 0);
    /// Voltage, V = kg m² s⁻³ A⁻¹.
    pub const VOLTAGE: Self = Self::new(2, 1, -3, -1, 0);
    /// Length per voltage, m/V (AFM deflection sensitivity).
    pub const LENGTH_PER_VOLTAGE: Self = Self::new(-1, -1, 3, 1, 0);
    /// Plane angle, rad.
    pub const ANGLE: Self = Self::new(0, 0, 0, 0, 1);

    /// Product of two dimensions.
    pub const fn mul(self, o: Self) -> Self {
        Self::new(
            self.length + o.length,
            self.mass + o.mass,
            self.time + o.time,
            self.current + o.current,
            self.angle + o.angle,
        )
    }

    /// Quotient of two dimensions.
    pub const fn div(self, o: Self) -> Self {
        self.mul(o.powi(-1))
    }

    /// Integer power of a dimension.
    pub const fn powi(self, p: i8) -> Self {
        Self::new(
            self.length * p,
            self.mass * p,
            self.time * p,
            self.current * p,
            self.angle * p,
        )
    }

    /// A name for well-known dimensions ("length", "pressure or stress", …).
    pub fn name(self) -> Option<&'static str> {
        NAMED.iter().find(|n| n.0 == self).map(|n| n.1)
    }

    /// The SI unit this crate converts to, e.g. `"N/m"`, or base exponents
    /// such as `"kg m^-1 s^-3"` for dimensions without a common name.
    pub fn si_unit(self) -> String {
        if let Some(n) = NAMED.iter().find(|n| n.0 == self) {
            return n.2.to_string();
        }
        let mut parts = Vec::new();
        for (sym, e) in [
            ("kg", self.mass),
            ("m", self.length),
            ("s", self.time),
            ("A", self.current),
            ("rad", self.angle),
        ] {
            match e {
                0 => {}
                1 => parts.push(sym.to_string()),
                _ => parts.push(format!("{sym}^{e}")),
            }
        }
        parts.join(" ")
    }

    /// A unit a user would typically write for this dimension, for hints.
    pub fn example_unit(self) -> String {
        NAMED
            .iter()
            .find(|n| n.0 == self)
            .map(|n| n.3.to_string())
            .unwrap_or_else(|| self.si_unit())
    }
}

impl fmt::Display for Dimension {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.name(), *self == Self::NONE) {
            (_, true) => f.write_str("dimensionless number"),
            (Some(n), false) => write!(f, "{n} ({})", self.si_unit()),
            (None, false) => write!(f, "quantity in {}", self.si_unit()),
        }
    }
}

/// (dimension, name, SI unit printed, unit suggested in hints)
const NAMED: &[(Dimension, &str, &str, &str)] = &[
    (Dimension::NONE, "dimensionless number", "", "0.3"),
    (Dimension::LENGTH, "length", "m", "um"),
    (Dimension::AREA, "area", "m^2", "um^2"),
    (Dimension::VOLUME, "volume", "m^3", "um^3"),
    (Dimension::MASS, "mass", "kg", "mg"),
    (Dimension::TIME, "time", "s", "s"),
    (Dimension::FREQUENCY, "frequency or rate", "1/s", "Hz"),
    (Dimension::VELOCITY, "velocity", "m/s", "um/s"),
    (Dimension::FORCE, "force", "N", "nN"),
    (Dimension::FORCE_RATE, "force rate", "N/s", "nN/s"),
    (Dimension::PRESSURE, "pressure or stress", "Pa", "kPa"),
    (Dimension::TENSION, "force per length", "N/m", "N/m"),
    (Dimension::ENERGY, "energy", "J", "J"),
    (Dimension::VISCOSITY, "viscosity", "Pa s", "Pa s"),
    (Dimension::CURRENT, "electric current", "A", "mA"),
    (Dimension::VOLTAGE, "voltage", "V", "V"),
    (
        Dimension::LENGTH_PER_VOLTAGE,
        "length per voltage",
        "m/V",
        "nm/V",
    ),
    (Dimension::ANGLE, "angle", "rad", "deg"),
];

/// A unit symbol: its factor to SI, its dimension, whether SI prefixes apply.
struct UnitDef {
    symbol: &'static str,
    /// Decimal part of the factor to SI (g → -3), applied exactly.
    pow10: i32,
    /// Remaining factor (deg → π/180, min → 60), 1 for decimal units.
    factor: f64,
    dim: Dimension,
    prefixable: bool,
}

#[rustfmt::skip]
const UNITS: &[UnitDef] = &[
    UnitDef { symbol: "m", pow10: 0, factor: 1.0, dim: Dimension::LENGTH, prefixable: true },
    UnitDef { symbol: "g", pow10: -3, factor: 1.0, dim: Dimension::MASS, prefixable: true },
    UnitDef { symbol: "s", pow10: 0, factor: 1.0, dim: Dimension::TIME, prefixable: true },
    UnitDef { symbol: "min", pow10: 0, factor: 60.0, dim: Dimension::TIME, prefixable: false },
    UnitDef { symbol: "h", pow10: 0, factor: 3600.0, dim: Dimension::TIME, prefixable: false },
    UnitDef { symbol: "Hz", pow10: 0, factor: 1.0, dim: Dimension::FREQUENCY, prefixable: true },
    UnitDef { symbol: "N", pow10: 0, factor: 1.0, dim: Dimension::FORCE, prefixable: true },
    UnitDef { symbol: "Pa", pow10: 0, factor: 1.0, dim: Dimension::PRESSURE, prefixable: true },
    UnitDef { symbol: "J", pow10: 0, factor: 1.0, dim: Dimension::ENERGY, prefixable: true },
    UnitDef { symbol: "A", pow10: 0, factor: 1.0, dim: Dimension::CURRENT, prefixable: true },
    UnitDef { symbol: "V", pow10: 0, factor: 1.0, dim: Dimension::VOLTAGE, prefixable: true },
    UnitDef { symbol: "rad", pow10: 0, factor: 1.0, dim: Dimension::ANGLE, prefixable: true },
    UnitDef { symbol: "deg", pow10: 0, factor: std::f64::consts::PI / 180.0, dim: Dimension::ANGLE, prefixable: false },
    UnitDef { symbol: "°", pow10: 0, factor: std::f64::consts::PI / 180.0, dim: Dimension::ANGLE, prefixable: false },
    UnitDef { symbol: "%", pow10: -2, factor: 1.0, dim: Dimension::NONE, prefixable: false },
    UnitDef { symbol: "1", pow10: 0, factor: 1.0, dim: Dimension::NONE, prefixable: false },
];

/// SI prefixes; `u`, `µ` (micro sign) and `μ` (Greek mu) all mean 1e-6.
const PREFIXES: &[(&str, i32)] = &[
    ("p", -12),
    ("n", -9),
    ("u", -6),
    ("\u{b5}", -6),
    ("\u{3bc}", -6),
    ("m", -3),
    ("c", -2),
    ("k", 3),
    ("M", 6),
    ("G", 9),
];

/// Why a quantity string could not be read.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum UnitError {
    /// Nothing but whitespace.
    #[error("empty quantity")]
    Empty,
    /// The text does not start with a number.
    #[error("`{0}` does not start with a number")]
    BadNumber(String),
    /// The number is NaN or infinite, or overflows after conversion to SI.
    #[error("value is not a finite number")]
    NotFinite,
    /// A unit symbol this crate does not know.
    #[error(
        "unknown unit `{0}` (known: m, g, s, min, h, Hz, N, Pa, J, A, V, rad, deg, %, with prefixes p n u/µ m c k M G)"
    )]
    UnknownUnit(String),
    /// An exponent that is not a small integer.
    #[error("bad exponent in `{0}` (write e.g. m^2 or s^-1)")]
    BadExponent(String),
    /// Misplaced operators, or implicit multiplication after `/`.
    #[error("cannot read unit `{0}`: {1}")]
    Syntax(String, &'static str),
}

/// A value converted to SI together with its dimension.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quantity {
    /// Magnitude in SI units of `dim`.
    pub value: f64,
    /// Physical dimension.
    pub dim: Dimension,
}

impl Quantity {
    /// Parses `"<number> <unit>"` (unit optional) into SI.
    ///
    /// ```
    /// use nlvid_study::{Dimension, Quantity};
    /// let q = Quantity::parse("2.94 kPa").unwrap();
    /// assert_eq!(q.dim, Dimension::PRESSURE);
    /// assert!((q.value - 2940.0).abs() < 1e-9);
    /// ```
    ///
    /// # Errors
    /// [`UnitError`] when the number or the unit cannot be read, or the value
    /// is not finite (including overflow after scaling to SI).
    pub fn parse(text: &str) -> Result<Self, UnitError> {
        let t = text.trim();
        if t.is_empty() {
            return Err(UnitError::Empty);
        }
        let lower = t.trim_start_matches(['+', '-']).to_ascii_lowercase();
        if lower.starts_with("nan") || lower.starts_with("inf") {
            return Err(UnitError::NotFinite);
        }
        let n = number_prefix_len(t);
        if n == 0 {
            return Err(UnitError::BadNumber(t.to_string()));
        }
        let (mantissa, exp10) = match t[..n].find(['e', 'E']) {
            Some(k) => {
                // Exponents beyond i32 overflow or underflow any f64 anyway.
                let e: i64 = t[k + 1..n].parse().map_err(|_| UnitError::NotFinite)?;
                (&t[..k], e)
            }
            None => (&t[..n], 0),
        };
        let (pow10, factor, dim) = parse_unit_scaled(t[n..].trim())?;
        // Decimal scaling is done by the decimal parser, so "40 um" gives the
        // double nearest 4e-5 (not 40 * 1e-6 = 3.9999999999999996e-5).
        let decimal: f64 = format!("{mantissa}e{}", exp10 + i64::from(pow10))
            .parse()
            .map_err(|_| UnitError::BadNumber(t.to_string()))?;
        let value = decimal * factor;
        if !value.is_finite() {
            return Err(UnitError::NotFinite);
        }
        Ok(Self { value, dim })
    }
}

impl fmt::Display for Quantity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let u = self.dim.si_unit();
        if u.is_empty() {
            write!(f, "{}", fmt_number(self.value))
        } else {
            write!(f, "{} {u}", fmt_number(self.value))
        }
    }
}

/// Formats a number compactly and exactly (shortest round-trip digits),
/// switching to exponent notation outside [1e-3, 1e6).
pub fn fmt_number(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 || (1e-3..1e6).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// Length of the leading decimal number: `[+-]?(d+(.d*)?|.d+)([eE][+-]?d+)?`.
fn number_prefix_len(t: &str) -> usize {
    let b = t.as_bytes();
    let mut i = 0;
    if i < b.len() && (b[i] == b'+' || b[i] == b'-') {
        i += 1;
    }
    let digits_start = i;
    while i < b.len() && b[i].is_ascii_digit() {
        i += 1;
    }
    let mut ndig = i - digits_start;
    if i < b.len() && b[i] == b'.' {
        let j = i + 1;
        let mut k = j;
        while k < b.len() && b[k].is_ascii_digit() {
            k += 1;
        }
        ndig += k - j;
        if ndig > 0 {
            i = k;
        }
    }
    if ndig == 0 {
        return 0;
    }
    if i < b.len() && (b[i] == b'e' || b[i] == b'E') {
        let mut k = i + 1;
        if k < b.len() && (b[k] == b'+' || b[k] == b'-') {
            k += 1;
        }
        let ds = k;
        while k < b.len() && b[k].is_ascii_digit() {
            k += 1;
        }
        if k > ds {
            i = k;
        }
    }
    i
}

/// Parses a unit expression into (factor to SI, dimension). Empty means 1.
///
/// # Errors
/// Unknown symbols, bad exponents, misplaced operators (see module docs).
pub fn parse_unit(expr: &str) -> Result<(f64, Dimension), UnitError> {
    let (p, f, d) = parse_unit_scaled(expr)?;
    Ok((10f64.powi(p) * f, d))
}

/// As [`parse_unit`], the factor split into an exact power of ten and the rest.
fn parse_unit_scaled(expr: &str) -> Result<(i32, f64, Dimension), UnitError> {
    #[derive(PartialEq, Clone, Copy)]
    enum Op {
        Mul,
        Div,
        Implicit,
    }
    let syntax = |why| UnitError::Syntax(expr.to_string(), why);
    let mut pow10 = 0i32;
    let mut factor = 1.0;
    let mut dim = Dimension::NONE;
    let mut pending: Option<Op> = None; // operator seen since the last atom
    let mut seen_atom = false;
    let mut seen_div = false;
    let mut chars = expr.char_indices().peekable();
    while let Some(&(i, c)) = chars.peek() {
        match c {
            c if c.is_whitespace() => {
                chars.next();
                if seen_atom && pending.is_none() {
                    pending = Some(Op::Implicit);
                }
            }
            '*' | '·' | '/' => {
                chars.next();
                if !seen_atom {
                    return Err(syntax("operator before any unit"));
                }
                let op = if c == '/' { Op::Div } else { Op::Mul };
                match pending {
                    Some(Op::Mul) | Some(Op::Div) => return Err(syntax("two operators in a row")),
                    _ => pending = Some(op),
                }
            }
            _ => {
                let mut end = expr.len();
                while let Some(&(j, d)) = chars.peek() {
                    if d.is_whitespace() || matches!(d, '*' | '·' | '/') {
                        end = j;
                        break;
                    }
                    chars.next();
                }
                let atom = &expr[i..end];
                let (p, f, d) = parse_atom(atom)?;
                let op = if seen_atom {
                    pending.unwrap_or(Op::Implicit)
                } else {
                    Op::Mul
                };
                if seen_div && op != Op::Div {
                    return Err(syntax(
                        "ambiguous after `/`: write `N s/m` or `N/m/s`, or use negative exponents",
                    ));
                }
                match op {
                    Op::Div => {
                        seen_div = true;
                        pow10 -= p;
                        factor /= f;
                        dim = dim.div(d);
                    }
                    Op::Mul | Op::Implicit => {
                        pow10 += p;
                        factor *= f;
                        dim = dim.mul(d);
                    }
                }
                seen_atom = true;
                pending = None;
            }
        }
    }
    if matches!(pending, Some(Op::Mul) | Some(Op::Div)) {
        return Err(syntax("operator at the end"));
    }
    Ok((pow10, factor, dim))
}

/// One unit symbol with optional prefix and `^exponent`.
fn parse_atom(atom: &str) -> Result<(i32, f64, Dimension), UnitError> {
    let (sym, exp) = match atom.split_once('^') {
        Some((s, e)) => {
            let e: i8 = e
                .parse()
                .ok()
                .filter(|e: &i8| (-9..=9).contains(e) && *e != 0)
                .ok_or_else(|| UnitError::BadExponent(atom.to_string()))?;
            (s, e)
        }
        None => (atom, 1),
    };
    let (p, f, d) = lookup_symbol(sym).ok_or_else(|| UnitError::UnknownUnit(sym.to_string()))?;
    let e = i32::from(exp);
    Ok((p * e, f.powi(e), d.powi(exp)))
}

fn lookup_symbol(sym: &str) -> Option<(i32, f64, Dimension)> {
    if let Some(u) = UNITS.iter().find(|u| u.symbol == sym) {
        return Some((u.pow10, u.factor, u.dim));
    }
    for (p, pf) in PREFIXES {
        if let Some(rest) = sym.strip_prefix(p)
            && let Some(u) = UNITS.iter().find(|u| u.prefixable && u.symbol == rest)
        {
            return Some((pf + u.pow10, u.factor, u.dim));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn si(t: &str) -> (f64, Dimension) {
        let q = Quantity::parse(t).unwrap();
        (q.value, q.dim)
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * b.abs().max(1e-300)
    }

    #[test]
    fn issue_examples_convert_to_si() {
        let cases = [
            ("12.22 um", 12.22e-6, Dimension::LENGTH),
            ("0.12 N/m", 0.12, Dimension::TENSION),
            ("5 mm/s", 5e-3, Dimension::VELOCITY),
            ("2.94 kPa", 2940.0, Dimension::PRESSURE),
            ("50 s", 50.0, Dimension::TIME),
            ("1.5 mm", 1.5e-3, Dimension::LENGTH),
            ("0.3", 0.3, Dimension::NONE),
            ("10 um/s", 10e-6, Dimension::VELOCITY),
            ("2 nN", 2e-9, Dimension::FORCE),
            ("20 ms", 0.02, Dimension::TIME),
            ("2 kHz", 2000.0, Dimension::FREQUENCY),
            ("90 deg", std::f64::consts::FRAC_PI_2, Dimension::ANGLE),
            ("40 nm/V", 40e-9, Dimension::LENGTH_PER_VOLTAGE),
            ("1.2 V", 1.2, Dimension::VOLTAGE),
            ("3 µm", 3e-6, Dimension::LENGTH),
            ("3 μm", 3e-6, Dimension::LENGTH),
            ("1 GPa", 1e9, Dimension::PRESSURE),
            ("4 MPa", 4e6, Dimension::PRESSURE),
            ("7 pN", 7e-12, Dimension::FORCE),
            ("2 kg", 2.0, Dimension::MASS),
            ("2 min", 120.0, Dimension::TIME),
            ("25 %", 0.25, Dimension::NONE),
            ("3 cm", 0.03, Dimension::LENGTH),
            ("1e-3 Pa s", 1e-3, Dimension::VISCOSITY),
            ("1 N*s/m", 1.0, Dimension::new(0, 1, -1, 0, 0)),
            ("2 um^2", 2e-12, Dimension::AREA),
            ("0.5 1/s", 0.5, Dimension::FREQUENCY),
            ("0.5 s^-1", 0.5, Dimension::FREQUENCY),
            ("9.81 m/s/s", 9.81, Dimension::new(1, 0, -2, 0, 0)),
            ("-1.5e2mm", -0.15, Dimension::LENGTH),
            (".5 m", 0.5, Dimension::LENGTH),
        ];
        for (t, v, d) in cases {
            let (got, gd) = si(t);
            assert!(close(got, v), "{t}: {got} != {v}");
            assert_eq!(gd, d, "{t}");
        }
    }

    #[test]
    fn decimal_prefixes_give_the_double_nearest_the_written_value() {
        // Compared with Rust's own decimal parser on the SI spelling.
        let cases = [
            ("40 um", "4e-5"),
            ("1.8 mm", "1.8e-3"),
            ("2.94 kPa", "2940"),
            ("0.12 mN/um", "120"),
            ("12.22 um", "12.22e-6"),
            ("5 mm/s", "0.005"),
            ("3 um^2", "3e-12"),
            ("7 %", "0.07"),
            ("1.5e-3 mm", "1.5e-6"),
        ];
        for (t, want) in cases {
            let want: f64 = want.parse().unwrap();
            assert_eq!(Quantity::parse(t).unwrap().value, want, "{t}");
        }
        assert_eq!(parse_unit("nm/V").unwrap().0, 1e-9);
    }

    #[test]
    fn voltage_and_sensitivity_are_consistent_with_base_units() {
        // V = W/A = kg m^2 s^-3 A^-1; N m / (A s) must be a volt.
        assert_eq!(si("1 N m/A/s").1, Dimension::VOLTAGE);
        assert_eq!(
            Dimension::LENGTH.div(Dimension::VOLTAGE),
            Dimension::LENGTH_PER_VOLTAGE
        );
        assert_eq!(Dimension::FORCE.div(Dimension::AREA), Dimension::PRESSURE);
    }

    #[test]
    fn bad_units_are_rejected_with_a_reason() {
        assert_eq!(
            Quantity::parse("3 furlong"),
            Err(UnitError::UnknownUnit("furlong".into()))
        );
        assert_eq!(
            Quantity::parse("3 Mpa"),
            Err(UnitError::UnknownUnit("Mpa".into()))
        );
        assert_eq!(
            Quantity::parse("3 kmin"),
            Err(UnitError::UnknownUnit("kmin".into()))
        );
        assert!(matches!(
            Quantity::parse("um"),
            Err(UnitError::BadNumber(_))
        ));
        assert!(matches!(
            Quantity::parse("1 m^x"),
            Err(UnitError::BadExponent(_))
        ));
        assert!(matches!(
            Quantity::parse("1 N/m s"),
            Err(UnitError::Syntax(..))
        ));
        assert!(matches!(
            Quantity::parse("1 N/"),
            Err(UnitError::Syntax(..))
        ));
        assert!(matches!(
            Quantity::parse("1 /s"),
            Err(UnitError::Syntax(..))
        ));
        assert!(matches!(
            Quantity::parse("1 N//m"),
            Err(UnitError::Syntax(..))
        ));
        assert_eq!(Quantity::parse("   "), Err(UnitError::Empty));
        assert_eq!(Quantity::parse("NaN m"), Err(UnitError::NotFinite));
        assert_eq!(Quantity::parse("-inf Pa"), Err(UnitError::NotFinite));
        assert_eq!(Quantity::parse("1e308 GPa"), Err(UnitError::NotFinite));
    }

    #[test]
    fn dimension_names_and_units_print() {
        assert_eq!(Dimension::TENSION.si_unit(), "N/m");
        assert_eq!(Dimension::new(-1, 1, -3, 0, 0).si_unit(), "kg m^-1 s^-3");
        assert_eq!(Dimension::LENGTH.to_string(), "length (m)");
        assert_eq!(
            Quantity::parse("12.22 um").unwrap().to_string(),
            "1.222e-5 m"
        );
    }
}

#[cfg(test)]
mod robustness {
    use super::*;

    #[test]
    fn odd_numbers_parse_like_rusts_decimal_parser() {
        for (t, v) in [
            ("1. m", 1.0),
            ("1.e3 m", 1000.0),
            ("+2 m", 2.0),
            ("1E-3 m", 1e-3),
        ] {
            assert_eq!(Quantity::parse(t).map(|q| q.value), Ok(v), "{t}");
        }
        assert!(Quantity::parse("1e m").is_err());
        assert!(Quantity::parse(".").is_err());
        assert!(Quantity::parse("-").is_err());
        assert_eq!(
            Quantity::parse("1e99999999999 m"),
            Err(UnitError::NotFinite)
        );
    }

    #[test]
    fn arbitrary_text_never_panics() {
        // Deterministic pseudo-random strings over an alphabet of the characters
        // the parser treats specially (seeded LCG, no dependency).
        let alphabet: Vec<char> = "0123456789.eE+-^/*· umkMGnpcµμsNPaVHz%°_x"
            .chars()
            .collect();
        let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
        for _ in 0..20_000 {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            let len = (state >> 60) as usize;
            let s: String = (0..len)
                .map(|_| {
                    state = state
                        .wrapping_mul(6_364_136_223_846_793_005)
                        .wrapping_add(1_442_695_040_888_963_407);
                    alphabet[(state >> 33) as usize % alphabet.len()]
                })
                .collect();
            if let Ok(q) = Quantity::parse(&s) {
                assert!(q.value.is_finite(), "{s:?}");
            }
        }
    }
}
