//! Study files: TOML with quantities that carry units, converted to SI on load, with errors that name file, line and key.
