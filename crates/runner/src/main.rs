//! The `radlab` binary: see [`radlab_runner::cli`].

fn main() -> std::process::ExitCode {
    match radlab_runner::cli::main() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
