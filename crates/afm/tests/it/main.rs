//! Every integration test of this crate, one module per topic, built as
//! one binary: one link instead of one per file, and the test harness
//! keeps both cores busy across topics (run one topic with
//! `cargo test -p nlvid-afm --test it <module>::`).

mod bad_input;
mod common;
mod creep;
mod geometry;
mod hertz_and_contact;
mod ibw_reader;
mod indenters;
mod inspect_batch;
mod jpk_layouts;
mod jpk_reader;
mod lee_radok;
mod lee_radok_global;
mod nanite_agreement;
mod robustness;
