//! The `ashlar` binary: everything lives in the library; see `ashlar::cli`.
fn main() -> std::process::ExitCode {
    ashlar::cli::main()
}
