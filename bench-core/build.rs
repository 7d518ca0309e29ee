//! Embeds the mfx commit at build time (read by `src/build_info.rs`), so a run never asks the
//! current directory which commit it is: the device machine's copy of `.git` may be stale, and a
//! sweep started from another repository would otherwise record that repository's commit.

use std::path::Path;

#[path = "build_git.rs"]
mod build_git;
use build_git::{parse_override, read_git};

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=build_git.rs");
    // An explicit revision wins (the device workflow builds from a copy whose `.git` may be a
    // stale snapshot); the value is used as given, `+dirty` suffix included.
    println!("cargo:rerun-if-env-changed=MFX_GIT_REV");
    let manifest = std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
    let root = Path::new(&manifest)
        .parent()
        .expect("bench-core sits in the workspace root");
    let (commit, dirty, source) = match std::env::var("MFX_GIT_REV") {
        Ok(rev) if !rev.trim().is_empty() => {
            let (c, d) = parse_override(&rev);
            (c, d, "MFX_GIT_REV".to_string())
        }
        _ => match read_git(root) {
            Ok(g) => {
                for p in &g.watch {
                    println!("cargo:rerun-if-changed={}", p.display());
                }
                (g.commit, g.dirty, "git".to_string())
            }
            Err(why) => {
                println!("cargo:warning=mfx commit unknown: {why}");
                // Rerun if the sources become a checkout later.
                println!("cargo:rerun-if-changed={}", root.join(".git").display());
                ("unknown".to_string(), false, format!("none: {why}"))
            }
        },
    };
    // The toolchain and wgpu this binary was built with, for run.json (a run on another
    // machine or months later says what compiled it).
    println!("cargo:rerun-if-env-changed=RUSTC");
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let rustc_version = std::process::Command::new(&rustc)
        .arg("--version")
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_else(|| "unknown".into());
    println!("cargo:rustc-env=MFX_BUILD_RUSTC={rustc_version}");
    let lock = root.join("Cargo.lock");
    println!("cargo:rerun-if-changed={}", lock.display());
    let wgpu = std::fs::read_to_string(&lock)
        .ok()
        .and_then(|t| locked_version(&t, "wgpu"))
        .unwrap_or_else(|| "unknown".into());
    println!("cargo:rustc-env=MFX_BUILD_WGPU={wgpu}");
    let profile = std::env::var("PROFILE").unwrap_or_else(|_| "unknown".into());
    let opt = std::env::var("OPT_LEVEL").unwrap_or_else(|_| "?".into());
    println!("cargo:rustc-env=MFX_BUILD_PROFILE={profile} (opt-level {opt})");
    println!("cargo:rustc-env=MFX_BUILD_GIT_COMMIT={commit}");
    println!("cargo:rustc-env=MFX_BUILD_GIT_DIRTY={dirty}");
    println!(
        "cargo:rustc-env=MFX_BUILD_GIT_SOURCE={}",
        source.replace('\n', " ")
    );
}

/// The version of package `name` in a Cargo.lock (the first entry of that name).
fn locked_version(lock: &str, name: &str) -> Option<String> {
    let want = format!("name = \"{name}\"");
    let mut lines = lock.lines();
    while let Some(l) = lines.next() {
        if l.trim() == want {
            let v = lines.next()?.trim().strip_prefix("version = \"")?;
            return Some(v.trim_end_matches('"').to_string());
        }
    }
    None
}
