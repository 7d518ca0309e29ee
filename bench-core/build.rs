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
    println!("cargo:rustc-env=MFX_BUILD_GIT_COMMIT={commit}");
    println!("cargo:rustc-env=MFX_BUILD_GIT_DIRTY={dirty}");
    println!(
        "cargo:rustc-env=MFX_BUILD_GIT_SOURCE={}",
        source.replace('\n', " ")
    );
}
