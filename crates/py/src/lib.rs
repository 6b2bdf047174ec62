//! Python bindings of nlvid (`import nlvid`), built by maturin from
//! `crates/py/pyproject.toml`. The API mirrors the library crates, not the
//! command line: each function here is a thin wrapper of the library call
//! the matching `nlvid` subcommand makes (named in its doc), so results are
//! the CLI's. Arrays come in as float64 numpy arrays, read in place where
//! they are contiguous ([`arrays`]); errors become Python exceptions with
//! the library's messages ([`errors`]); long calls release the GIL.
//!
//! Python side: `crates/py/python/nlvid/` (re-exports, `.pyi` stubs),
//! tests in `crates/py/tests/`, run by `scripts/test-python.sh`.

use pyo3::prelude::*;

mod afm;
mod arrays;
mod bench;
mod cohort;
mod columns;
mod errors;
mod fit;
mod metamodel;
mod pyjson;
mod simulate;
mod study;

/// The extension module `nlvid._nlvid`.
#[pymodule]
fn _nlvid(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    errors::register(m)?;
    study::register(m)?;
    simulate::register(m)?;
    metamodel::register(m)?;
    fit::register(m)?;
    afm::register(m)?;
    cohort::register(m)?;
    bench::register(m)?;
    Ok(())
}
