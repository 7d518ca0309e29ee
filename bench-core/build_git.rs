// The git half of bench-core's build script, in its own file so that `tests/provenance.rs` can
// test it on throw-away repositories (`#[path]`). Only std: build scripts get no dependencies
// beyond `[build-dependencies]`, and this needs none. Its errors stay `String`: each is one
// reason that the build script prints as a cargo warning (and records as "unknown" provenance)
// and no caller tells one from another, so an error enum would add `thiserror` to the build
// dependencies for nothing.

use std::path::{Path, PathBuf};
use std::process::Command;

/// What the build records about the checkout it was built from.
#[derive(Debug, PartialEq)]
pub struct GitState {
    /// Full hex of HEAD.
    pub commit: String,
    /// Tracked files differ from HEAD (staged or not); untracked files do not count.
    pub dirty: bool,
    /// Files whose change can change `commit` or `dirty`: HEAD, its reflog, the current ref,
    /// packed-refs, the index, and every tracked file (those that exist).
    pub watch: Vec<PathBuf>,
}

/// git run in `root` with none of the variables a git hook or a parent process may set to send it
/// elsewhere (`GIT_DIR` of another repository, a hook's temporary `GIT_INDEX_FILE`, …), and
/// without optional locks, so that asking never rewrites the index (which would itself trigger the
/// next rebuild).
fn git(root: &Path, args: &[&str]) -> Result<String, String> {
    let out = Command::new("git")
        .arg("--no-optional-locks")
        .arg("-C")
        .arg(root)
        .args(args)
        .env_remove("GIT_DIR")
        .env_remove("GIT_WORK_TREE")
        .env_remove("GIT_INDEX_FILE")
        .env_remove("GIT_COMMON_DIR")
        .env_remove("GIT_OBJECT_DIRECTORY")
        .env_remove("GIT_NAMESPACE")
        .output()
        .map_err(|e| format!("git not runnable: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "git {}: {}",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    String::from_utf8(out.stdout).map_err(|e| format!("git {}: {e}", args.join(" ")))
}

/// The state of the git checkout whose top level is exactly `root`. An error (the reason) when
/// `root` is not the top of a git checkout: no git, no repository, no commit yet, or a repository
/// that merely contains `root` (sources unpacked inside some other project's checkout), whose
/// commit is not ours.
pub fn read_git(root: &Path) -> Result<GitState, String> {
    let top = git(root, &["rev-parse", "--show-toplevel"])?;
    let same = |a: &Path, b: &Path| match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    };
    if !same(Path::new(top.trim()), root) {
        return Err(format!(
            "{} is inside the git checkout {}, not the top of its own",
            root.display(),
            top.trim()
        ));
    }
    let commit = git(root, &["rev-parse", "--verify", "HEAD^{commit}"])?
        .trim()
        .to_string();
    let dirty = !git(root, &["status", "--porcelain", "--untracked-files=no"])?
        .trim()
        .is_empty();

    // A worktree keeps HEAD, index and HEAD's reflog in its own git dir and refs in the common
    // one: `--git-path` resolves each (relative to `root` when relative). Not the whole refs
    // folder: it is shared by every worktree, so other branches' commits would rebuild this one.
    // A missing file is left out (cargo would rerun on every build): a branch that lives only in
    // packed-refs gets a loose ref on its next commit, which also appends to logs/HEAD.
    let mut names = vec![
        "HEAD".to_string(),
        "index".into(),
        "logs/HEAD".into(),
        "packed-refs".into(),
    ];
    if let Ok(r) = git(root, &["symbolic-ref", "-q", "HEAD"]) {
        names.push(r.trim().to_string());
    }
    let mut watch = Vec::new();
    for name in &names {
        let p = root.join(git(root, &["rev-parse", "--git-path", name])?.trim());
        if p.exists() {
            watch.push(p);
        }
    }
    let files = git(root, &["ls-files", "-z"])?;
    for f in files.split('\0').filter(|f| !f.is_empty()) {
        let p = root.join(f);
        // Likewise a deleted tracked file: deleting or restoring it through git rewrites the
        // index, which is watched.
        if p.exists() {
            watch.push(p);
        }
    }
    Ok(GitState {
        commit,
        dirty,
        watch,
    })
}

/// `MFX_GIT_REV` as given at build time: `<rev>` or `<rev>+dirty`.
pub fn parse_override(rev: &str) -> (String, bool) {
    let rev = rev.trim();
    match rev.strip_suffix("+dirty") {
        Some(c) => (c.to_string(), true),
        None => (rev.to_string(), false),
    }
}
