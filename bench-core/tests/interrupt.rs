//! SIGINT/SIGTERM: the first signal is recorded for the runner, a second one kills unless it is
//! the first delivered twice (within `interrupt::REPEAT_GRACE`, as coreutils `timeout` does). Each case runs
//! in a child process (this test binary again, one test selected), so no signal reaches the
//! harness running the other tests.

use std::os::unix::process::ExitStatusExt;
use std::process::Command;

use bench_core::interrupt;
use signal_hook::consts::{SIGINT, SIGTERM};
use signal_hook::low_level::raise;

/// Runs `test` of this binary in a child with `MFX_INTERRUPT_CHILD` set.
fn child(test: &str) -> std::process::Output {
    Command::new(std::env::current_exe().unwrap())
        .args(["--exact", test, "--nocapture", "--test-threads=1"])
        .env("MFX_INTERRUPT_CHILD", "1")
        .output()
        .unwrap()
}

fn in_child() -> bool {
    std::env::var_os("MFX_INTERRUPT_CHILD").is_some()
}

#[test]
fn child_one_sigint() {
    if !in_child() {
        return;
    }
    assert_eq!(interrupt::requested(), None, "before install");
    interrupt::install().unwrap();
    interrupt::install().unwrap(); // idempotent: still one handler set
    assert_eq!(interrupt::requested(), None, "nothing raised yet");
    raise(SIGINT).unwrap();
    // The process is still here: the first signal only set the flag.
    assert_eq!(interrupt::requested(), Some("SIGINT"));
    println!("survived first SIGINT");
}

#[test]
fn child_two_sigints() {
    if !in_child() {
        return;
    }
    interrupt::install().unwrap();
    raise(SIGINT).unwrap();
    println!("first: {:?}", interrupt::requested());
    std::thread::sleep(interrupt::REPEAT_GRACE * 2);
    raise(SIGINT).unwrap();
    println!("survived second SIGINT");
}

#[test]
fn child_sigterm_delivered_twice() {
    if !in_child() {
        return;
    }
    interrupt::install().unwrap();
    // `timeout` signals the command, then its process group: two copies within microseconds.
    raise(SIGTERM).unwrap();
    raise(SIGTERM).unwrap();
    println!("survived a doubled SIGTERM: {:?}", interrupt::requested());
}

#[test]
fn child_sigterm() {
    if !in_child() {
        return;
    }
    interrupt::install().unwrap();
    raise(SIGTERM).unwrap();
    println!("first: {:?}", interrupt::requested());
}

#[test]
fn first_sigint_is_recorded_and_survived() {
    let out = child("child_one_sigint");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("survived first SIGINT"), "{stdout}");
}

#[test]
fn second_sigint_kills() {
    let out = child("child_two_sigints");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("first: Some(\"SIGINT\")"), "{stdout}");
    assert!(!stdout.contains("survived second"), "{stdout}");
    assert_eq!(
        out.status.signal(),
        Some(SIGINT),
        "killed by the default action: {:?}",
        out.status
    );
}

#[test]
fn the_same_sigterm_delivered_twice_is_one_request() {
    let out = child("child_sigterm_delivered_twice");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout} {:?}", out.status);
    assert!(
        stdout.contains("survived a doubled SIGTERM: Some(\"SIGTERM\")"),
        "{stdout}"
    );
}

#[test]
fn sigterm_is_named() {
    let out = child("child_sigterm");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}");
    assert!(stdout.contains("first: Some(\"SIGTERM\")"), "{stdout}");
}
