//! What broke: `ashlar serve` printed "listening on …" before it installed its SIGTERM handler
//! (the handler was registered lazily, when the shutdown future was first polled). A supervisor
//! that stopped the server right after that line, as `tests/service/service_web.rs` does, killed it
//! with the default action: exit by signal 15, no graceful shutdown, running jobs not requeued.
//! Seen under load in `server_log_to_a_file_has_no_colour_codes`. The handlers are now
//! registered before the line is printed (`service::ShutdownSignals`).
use std::io::BufRead;
use std::process::{Command, Stdio};

/// SIGTERM at the earliest moment a client can know the server is up: it must exit cleanly,
/// every time (five rounds: the old race lost most rounds on a loaded machine, and some on an
/// idle one).
#[test]
fn sigterm_right_after_the_listening_line_is_a_graceful_shutdown() {
    for round in 0..5 {
        let dir =
            std::env::temp_dir().join(format!("ashlar-sigterm-{}-{round}", std::process::id()));
        let mut child = Command::new(env!("CARGO_BIN_EXE_ashlar"))
            .args(["serve", "--addr", "127.0.0.1:0", "--workers", "1", "--data"])
            .arg(dir.join("data"))
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("spawn ashlar serve");
        let mut stdout = std::io::BufReader::new(child.stdout.take().expect("stdout"));
        let mut line = String::new();
        stdout.read_line(&mut line).expect("the listening line");
        assert!(line.contains("listening on"), "first line {line:?}");
        let kill = Command::new("kill")
            .args(["-TERM", &child.id().to_string()])
            .status()
            .expect("kill -TERM");
        assert!(kill.success());
        let mut rest = String::new();
        std::io::Read::read_to_string(&mut stdout, &mut rest).expect("read stdout");
        let exit = child.wait().expect("wait");
        assert!(
            exit.success(),
            "round {round}: ashlar serve ended by {exit}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
