//! One module per `edmp-host` subcommand: its `Args` (clap) and its `run`. The binary
//! (`main.rs`) only parses the arguments and maps the outcome to an exit status.

pub mod bench;
pub mod bench_report;
pub mod bench_rrt;
pub mod embed;
pub mod fk;
pub mod gen_data;
pub mod gen_suite;
pub mod import_moveit;
pub mod plan;
pub mod render;
pub mod rrt;
pub mod sample;
pub mod view;
