//! `edmp-host` as a library: the std shell of edmp-rs. Every subcommand is a module of
//! [`commands`] (its `Args` and `run`); [`formats`] holds the one reader and writer of each file
//! format, which the `edmp-host` binary and the Python package both use; `scenes` generates the
//! benchmark's scenes and `rrt` is the classical baseline. Planning math lives in `edmp-core`.

pub mod arm;
pub mod commands;
pub mod depth;
pub mod formats;
mod metrics;
pub mod planning;
mod plots;
mod rrt;
mod scenes;
pub mod threads;

/// What went wrong, and the exit status it maps to (docs/formats.md).
#[derive(Debug)]
pub enum Failure {
    /// Bad input or I/O: exit 2, nothing written.
    Input(String),
    /// Ran, but found no path: exit 1.
    NoPath(String),
}
