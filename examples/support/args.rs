//! The examples' command-line reading: `--name VALUE` pairs, shared by the diagnostic examples
//! (they take a few knobs each and keep clap out of their builds).

/// The value after `name` on the command line, if `name` is given.
pub fn arg(name: &str) -> Option<String> {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1).cloned())
}
