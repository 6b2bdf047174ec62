//! Argument parsers shared by subcommands (clap `value_parser`s).

/// Parses a command-line quantity such as `--dt 1ms` or `--speed "5 um/s"`
/// into SI, checking its dimension; for clap's `value_parser`:
/// `#[arg(long, value_parser = |s: &str| quantity(s, Dimension::TIME))]`.
///
/// # Errors
/// A message naming the text, the unit problem or the wrong dimension.
pub fn quantity(text: &str, dim: nlvid_study::Dimension) -> Result<f64, String> {
    let q = nlvid_study::Quantity::parse(text).map_err(|e| format!("`{text}`: {e}"))?;
    if q.dim == dim {
        Ok(q.value)
    } else if q.dim == nlvid_study::Dimension::NONE {
        Err(format!(
            "`{text}` has no unit; expected a {dim}, e.g. \"{text} {}\"",
            dim.example_unit()
        ))
    } else {
        Err(format!("`{text}` is a {}, expected a {dim}", q.dim))
    }
}
