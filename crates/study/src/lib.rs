//! Study files: TOML whose quantities carry units, converted to SI on load,
//! with errors that name file, line, column and key.
//!
//! Every pipeline stage defines its own settings struct in its own crate and
//! reads its section through [`Section`] (usually by implementing
//! [`FromSection`]). Each reader converts `"12.22 um"`-style strings to SI,
//! checks the dimension and the allowed range, and marks the key as read;
//! `finish()` then reports any key nobody read, so typos never pass silently.
//! [`Study`] loads a whole file, hands out sections and gives a provenance
//! hash ([`StudyHash`]).
//!
//! Cost: parsing is linear in the file size; each key lookup is linear in
//! the size of its table (tables are small). Nothing here is on a hot path.
//!
//! ```
//! use nlvid_study::{Bounds, Dimension, Study};
//!
//! let text = r#"
//! [geometry]
//! radius = "12.22 um"
//! [protocol]
//! speed = "5 mm/s"
//! hold = "50 s"
//! "#;
//! let mut study = Study::parse("capsule.toml", text)?;
//! let mut geo = study.section("geometry")?;
//! let r = geo.req_quantity("radius", Dimension::LENGTH, Bounds::positive())?;
//! geo.finish()?;
//! let mut p = study.section("protocol")?;
//! let v = p.req_quantity("speed", Dimension::VELOCITY, Bounds::positive())?;
//! // `hold` is not read: finish() names it.
//! let err = p.finish().unwrap_err();
//! assert_eq!(err.to_string(), "capsule.toml:6:1: key `protocol.hold`: unknown key (expected one of: speed)");
//! assert!((r - 12.22e-6).abs() < 1e-18 && (v - 5e-3).abs() < 1e-15);
//! # Ok::<(), nlvid_study::StudyError>(())
//! ```
//!
//! The file format is documented in `docs/study-format.md`.
#![warn(missing_docs)]

mod atomic;
mod bounds;
mod delimiter;
mod error;
mod section;
mod source;
mod study;
mod tree;
mod units;

pub use atomic::{
    check_output_dir, check_output_file, clean_stale_temps, next_to, process_alive, write_atomic,
    write_atomic_with,
};
pub use bounds::Bounds;
pub use delimiter::delimiter_hint;
pub use error::{ErrorKind, Location, Result, StudyError, closest, error_message};
pub use section::{FromSection, Section};
pub use study::{Leaf, LeafValue, Lint, Study, StudyHash};
pub use units::{Dimension, Quantity, UnitError, fmt_number, parse_unit};
