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

/// Writes a command's report to standard output. A reader that stops early (`edmp-host fk |
/// head -1`) closes the pipe: that ends the output quietly, as for other Unix tools, instead of
/// the panic `println!` would raise.
pub(crate) fn print_stdout(text: &str) -> Result<(), String> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(format!("cannot write to standard output: {e}")),
        _ => Ok(()),
    }
}

/// Writes a command's document to `output` when given (`-o FILE`), else to standard output
/// ([`print_stdout`]); an error names the file.
pub(crate) fn write_document(output: Option<&std::path::Path>, text: &str) -> Result<(), String> {
    match output {
        Some(path) => std::fs::write(path, text).map_err(|e| format!("{}: {e}", path.display())),
        None => print_stdout(text),
    }
}
