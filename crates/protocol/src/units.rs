//! Unit-suffixed CSV headers: `time_s`, `piezo_um`, `force [nN]`, `Z (µm)`.
//!
//! A header is split into a name and a unit; the unit gives the SI factor
//! and the dimension. Units are parsed by the study crate
//! ([`nlvid_study::parse_unit`]); a column counts as time, length or force
//! when its unit has that dimension. A header without a recognised unit is
//! dimensionless.

/// Physical dimension of a column.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dim {
    /// Seconds.
    Time,
    /// Metres.
    Length,
    /// Newtons.
    Force,
    /// No unit.
    None,
}

/// A parsed header: lower-case name, dimension and factor to SI.
#[derive(Debug, Clone, PartialEq)]
pub struct Header {
    /// Name without the unit, trimmed and lower-cased.
    pub name: String,
    /// The unit symbol as written ("" if none).
    pub unit: String,
    /// Dimension of the unit.
    pub dim: Dim,
    /// Multiply a cell by this to get SI.
    pub to_si: f64,
}

/// Dimension and SI factor of a unit symbol, if it is a time, length or
/// force unit the study crate's unit parser knows (so CSV headers and study
/// files accept the same spellings: `um`, `µm`, `nN`, `ms`, ...).
pub fn unit(symbol: &str) -> Option<(Dim, f64)> {
    use nlvid_study::Dimension;
    if symbol.trim().is_empty() {
        return None;
    }
    let (f, d) = nlvid_study::parse_unit(symbol).ok()?;
    let dim = if d == Dimension::TIME {
        Dim::Time
    } else if d == Dimension::LENGTH {
        Dim::Length
    } else if d == Dimension::FORCE {
        Dim::Force
    } else {
        return None;
    };
    Some((dim, f))
}

/// Split a header into name and unit (see the module doc for the forms).
pub fn parse_header(raw: &str) -> Header {
    let raw = raw.trim();
    let bracketed = [('[', ']'), ('(', ')')].iter().find_map(|&(o, c)| {
        let inner = raw.strip_suffix(c)?;
        let open = inner.rfind(o)?;
        Some((inner[..open].trim(), inner[open + 1..].trim()))
    });
    let (name, sym) = match bracketed {
        Some(split) => split,
        None => match raw.rsplit_once('_') {
            Some((n, u)) if unit(u).is_some() => (n, u),
            _ => (raw, ""),
        },
    };
    let (dim, to_si) = unit(sym).unwrap_or((Dim::None, 1.0));
    Header {
        name: name.trim().to_lowercase(),
        unit: sym.to_string(),
        dim,
        to_si,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn suffix_and_bracket_forms_parse_to_the_same_si_factor() {
        let a = parse_header("piezo_um");
        let b = parse_header("Piezo [µm]");
        let c = parse_header("piezo (um)");
        for h in [&a, &b, &c] {
            assert_eq!(h.name, "piezo");
            assert_eq!(h.dim, Dim::Length);
            assert_eq!(h.to_si, 1e-6);
        }
        let t = parse_header("time_ms");
        assert_eq!((t.name.as_str(), t.dim, t.to_si), ("time", Dim::Time, 1e-3));
    }

    #[test]
    fn unknown_suffix_is_part_of_the_name() {
        let h = parse_header("cell_id");
        assert_eq!(h.name, "cell_id");
        assert_eq!(h.dim, Dim::None);
    }
}
