//! Every integration test of this crate, one module per topic, built as
//! one binary: one link instead of one per file, and the test harness
//! keeps both cores busy across topics (run one topic with
//! `cargo test -p nlvid-surrogate --test it <module>::`).

mod build_resume;
mod cell_domain_accuracy;
mod common;
mod dace_example;
mod design_section;
mod forward_build;
mod infill;
mod model_file;
mod output_coordinates;
mod output_scale;
mod theta_search;
