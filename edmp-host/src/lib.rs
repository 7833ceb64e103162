//! `edmp-host` as a library: the std shell of edmp-rs. Every command is a module here (its
//! `Args` and `run`), and so are the one reader and writer of the scene and plan formats
//! (`json`), which the `edmp-host` binary and the Python package both use. Planning math lives
//! in `edmp-core`.

pub mod bench;
pub mod bench_report;
pub mod bench_rrt;
pub mod embed;
pub mod fk;
pub mod gen_data;
pub mod json;
mod metrics;
pub mod moveit;
pub mod plan_cmd;
mod plots;
pub mod render;
mod rrt;
pub mod rrt_cmd;
pub mod sample;
mod scenes;
pub mod suite;
pub mod threads;
pub mod timed;
pub mod view;

/// What went wrong, and the exit status it maps to (`spec/formats.md`).
#[derive(Debug)]
pub enum Failure {
    /// Bad input or I/O: exit 2, nothing written.
    Input(String),
    /// Ran, but found no path: exit 1.
    NoPath(String),
}
