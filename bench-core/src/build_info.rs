//! What this build of mfx is, fixed at compile time by `bench-core/build.rs`: nothing here asks
//! git or the current directory at run time, so a sweep started anywhere (or from a copy of the
//! tree on another machine) records the commit the binary was built from.
//!
//! Source of the values, in order: the `MFX_GIT_REV` environment variable at build time, taken
//! as given (`<rev>` or `<rev>+dirty`; the device workflow sets it); else git, asked at build
//! time in the workspace root, which must be the top of its own checkout (mfx unpacked inside
//! another project's repository does not take that project's commit); else unknown. Cargo
//! rebuilds when HEAD, the current branch, the index or any tracked file changes.

/// Full hex of the commit built (as given when from `MFX_GIT_REV`), or `unknown`.
pub const GIT_COMMIT: &str = env!("MFX_BUILD_GIT_COMMIT");

/// Tracked files differed from the commit (staged or not; untracked files do not count).
pub const GIT_DIRTY: bool = const_str_is_true(env!("MFX_BUILD_GIT_DIRTY"));

/// Where the values came from: `git`, `MFX_GIT_REV`, or `none: <reason>`.
pub const GIT_SOURCE: &str = env!("MFX_BUILD_GIT_SOURCE");

/// mfx's version (the workspace's).
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// `rustc --version` of the compiler that built mfx.
pub const RUSTC: &str = env!("MFX_BUILD_RUSTC");

/// wgpu's version, from the workspace's Cargo.lock.
pub const WGPU: &str = env!("MFX_BUILD_WGPU");

/// Cargo profile and opt-level of bench-core (e.g. `release (opt-level 3)`).
pub const PROFILE: &str = env!("MFX_BUILD_PROFILE");

/// The `git_rev` column: 12 hex digits, `+dirty` when the tree had changes; `MFX_GIT_REV`
/// verbatim when that was set; `unknown (built outside a git checkout)` otherwise.
pub fn git_rev() -> String {
    if GIT_SOURCE == "MFX_GIT_REV" {
        return if GIT_DIRTY {
            format!("{GIT_COMMIT}+dirty")
        } else {
            GIT_COMMIT.to_string()
        };
    }
    if GIT_COMMIT == "unknown" {
        return "unknown (built outside a git checkout)".to_string();
    }
    let short = &GIT_COMMIT[..GIT_COMMIT.len().min(12)];
    if GIT_DIRTY {
        format!("{short}+dirty")
    } else {
        short.to_string()
    }
}

const fn const_str_is_true(s: &str) -> bool {
    matches!(s.as_bytes(), b"true")
}
