//! What the `ppm` command tests share.

use std::io::{BufRead, BufReader, Read};
use std::process::{Command, Stdio};

/// Runs `command` (a `ppm` invocation), waits for a line of its standard error that starts
/// with `started`, lets it work half a second more, sends SIGINT (as Ctrl-C does), and
/// returns its exit code and standard error.
pub fn interrupted(mut command: Command, started: &str) -> (Option<i32>, String) {
    let mut child = command
        .stderr(Stdio::piped())
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    let mut stderr = BufReader::new(child.stderr.take().unwrap());
    let mut seen = String::new();
    let mut line = String::new();
    while !line.starts_with(started) {
        line.clear();
        let read = stderr.read_line(&mut line).unwrap();
        seen.push_str(&line);
        assert!(read > 0, "ppm ended before {started:?}: {seen}");
    }
    std::thread::sleep(std::time::Duration::from_millis(500));
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let status = child.wait().unwrap();
    stderr.read_to_string(&mut seen).unwrap();
    (status.code(), seen)
}
