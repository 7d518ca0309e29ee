//! The commit a build records is mfx's own, fixed at build time: not the current directory's, not
//! another repository's. Tests the build script's git half (`build_git.rs`) on throw-away
//! repositories, and the built constants from a process started inside a different repository.

use std::path::{Path, PathBuf};
use std::process::Command;

use bench_core::build_info;

#[path = "../build_git.rs"]
mod build_git;

/// A fresh folder under the system temp dir, unique to this test process and `name`.
/// A temp folder removed when the test ends, pass or fail (derefs to its path).
struct Tmp(tempfile::TempDir);
impl std::ops::Deref for Tmp {
    type Target = std::path::Path;
    fn deref(&self) -> &std::path::Path {
        self.0.path()
    }
}
impl AsRef<std::path::Path> for Tmp {
    fn as_ref(&self) -> &std::path::Path {
        self.0.path()
    }
}
fn tmp_dir(prefix: &str) -> Tmp {
    Tmp(tempfile::Builder::new()
        .prefix(&format!("{prefix}-"))
        .tempdir()
        .expect("a temp folder"))
}
fn temp(name: &str) -> Tmp {
    tmp_dir(&format!("mfx-provenance-{name}"))
}

fn git(dir: &Path, args: &[&str]) -> String {
    let out = Command::new("git")
        .args(["-c", "user.name=t", "-c", "user.email=t@example.com", "-C"])
        .arg(dir)
        .args(args)
        .env_remove("GIT_DIR")
        .env_remove("GIT_INDEX_FILE")
        .env_remove("GIT_WORK_TREE")
        .output()
        .expect("git runs");
    assert!(
        out.status.success(),
        "git {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap().trim().to_string()
}

/// A repository with one commit of `a.txt`; returns its HEAD.
fn repo_with_commit(dir: &Path) -> String {
    git(dir, &["init", "-q"]);
    std::fs::write(dir.join("a.txt"), "one\n").unwrap();
    git(dir, &["add", "a.txt"]);
    git(dir, &["commit", "-q", "-m", "first"]);
    git(dir, &["rev-parse", "HEAD"])
}

/// The mfx workspace root (bench-core's parent).
fn mfx_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .to_path_buf()
}

/// What `git_rev()` must say for this build, asked of git in the mfx checkout itself.
fn expected_rev() -> String {
    if let Some(rev) = option_env!("MFX_GIT_REV").filter(|r| !r.trim().is_empty()) {
        return rev.trim().to_string();
    }
    let root = mfx_root();
    let short = git(&root, &["rev-parse", "--short=12", "HEAD"]);
    let dirty = !git(&root, &["status", "--porcelain", "--untracked-files=no"]).is_empty();
    if dirty {
        format!("{short}+dirty")
    } else {
        short
    }
}

#[test]
fn build_records_the_mfx_checkouts_commit() {
    assert_eq!(build_info::git_rev(), expected_rev());
    if option_env!("MFX_GIT_REV").is_some_and(|r| !r.trim().is_empty()) {
        assert_eq!(build_info::GIT_SOURCE, "MFX_GIT_REV");
    } else {
        assert_eq!(build_info::GIT_SOURCE, "git", "built from the mfx checkout");
        assert_eq!(build_info::GIT_COMMIT.len(), 40, "full hex");
        assert!(build_info::GIT_COMMIT.starts_with(&build_info::git_rev()[..12]));
    }
    assert_eq!(build_info::VERSION, env!("CARGO_PKG_VERSION"));
}

/// Run by `a_process_in_another_repository_records_mfxs_commit` in a child process; a no-op when
/// the test harness runs it directly.
#[test]
fn child_prints_git_rev() {
    if std::env::var_os("MFX_PROVENANCE_CHILD").is_some() {
        println!("git_rev={}", build_info::git_rev());
    }
}

#[test]
fn a_process_in_another_repository_records_mfxs_commit() {
    let other = temp("other-repo");
    let other_head = repo_with_commit(&other);
    // This very test binary, started inside the other repository and pointed at it by GIT_DIR.
    let out = Command::new(std::env::current_exe().unwrap())
        .args([
            "--exact",
            "child_prints_git_rev",
            "--nocapture",
            "--test-threads=1",
        ])
        .current_dir(&other)
        .env("MFX_PROVENANCE_CHILD", "1")
        .env("GIT_DIR", other.join(".git"))
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let rev = stdout
        .lines()
        .find_map(|l| l.split_once("git_rev=").map(|(_, rev)| rev.trim()))
        .unwrap_or_else(|| panic!("child printed no git_rev: {stdout}"));
    assert_eq!(rev, expected_rev());
    assert!(
        !rev.starts_with(&other_head[..12]),
        "took the other repository's commit"
    );
    std::fs::remove_dir_all(&other).unwrap();
}

#[test]
fn reads_commit_and_dirtiness_of_a_checkout() {
    let dir = temp("dirty");
    let head = repo_with_commit(&dir);
    let s = build_git::read_git(&dir).unwrap();
    assert_eq!((s.commit.as_str(), s.dirty), (head.as_str(), false));
    let head_file = dir.join(".git/HEAD").canonicalize().unwrap();
    let canon: Vec<PathBuf> = s.watch.iter().map(|p| p.canonicalize().unwrap()).collect();
    assert!(canon.contains(&head_file), "HEAD watched: {:?}", s.watch);
    assert!(canon.contains(&dir.join("a.txt").canonicalize().unwrap()));
    assert!(canon.contains(
        &dir.join(".git/refs/heads")
            .canonicalize()
            .unwrap()
            .join(git(&dir, &["symbolic-ref", "--short", "HEAD"]))
    ));

    // Untracked files do not count.
    std::fs::write(dir.join("new.txt"), "x").unwrap();
    assert!(!build_git::read_git(&dir).unwrap().dirty);
    // A staged new file does.
    git(&dir, &["add", "new.txt"]);
    assert!(build_git::read_git(&dir).unwrap().dirty);
    git(&dir, &["rm", "-q", "--cached", "new.txt"]);
    assert!(!build_git::read_git(&dir).unwrap().dirty);
    // So does an unstaged change to a tracked file.
    std::fs::write(dir.join("a.txt"), "two\n").unwrap();
    assert!(build_git::read_git(&dir).unwrap().dirty);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_worktree_names_its_own_head_and_the_shared_ref() {
    let main = temp("wt-main");
    let head = repo_with_commit(&main);
    let wt = temp("wt-linked");
    std::fs::remove_dir_all(&wt).unwrap();
    git(
        &main,
        &["worktree", "add", "-q", "-b", "side", wt.to_str().unwrap()],
    );
    assert!(
        wt.join(".git").is_file(),
        "a linked worktree has a .git file"
    );
    let s = build_git::read_git(&wt).unwrap();
    assert_eq!((s.commit.as_str(), s.dirty), (head.as_str(), false));
    let canon: Vec<PathBuf> = s.watch.iter().map(|p| p.canonicalize().unwrap()).collect();
    let wt_gitdir = PathBuf::from(git(&wt, &["rev-parse", "--absolute-git-dir"]));
    assert!(canon.contains(&wt_gitdir.join("HEAD").canonicalize().unwrap()));
    assert!(canon.contains(&wt_gitdir.join("index").canonicalize().unwrap()));
    let side_ref = main.join(".git/refs/heads/side").canonicalize().unwrap();
    assert!(
        canon.contains(&side_ref),
        "branch ref in the common dir: {:?}",
        s.watch
    );
    std::fs::remove_dir_all(&wt).unwrap();
    std::fs::remove_dir_all(&main).unwrap();
}

#[test]
fn a_folder_inside_another_checkout_is_not_that_checkout() {
    let dir = temp("nested");
    repo_with_commit(&dir);
    let sub = dir.join("vendored-mfx");
    std::fs::create_dir_all(&sub).unwrap();
    let err = build_git::read_git(&sub).unwrap_err();
    assert!(err.contains("not the top"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn no_checkout_no_commit() {
    let dir = temp("bare-folder");
    // Not a repository, or (if the temp dir sits in one) not the top of it: an error either way.
    assert!(build_git::read_git(&dir).is_err());
    let empty = temp("no-commit");
    git(&empty, &["init", "-q"]);
    assert!(build_git::read_git(&empty).is_err(), "no commit yet");
    std::fs::remove_dir_all(&dir).unwrap();
    std::fs::remove_dir_all(&empty).unwrap();
}

#[test]
fn override_is_taken_as_given() {
    assert_eq!(
        build_git::parse_override("dc489b7ca3ca"),
        ("dc489b7ca3ca".to_string(), false)
    );
    assert_eq!(
        build_git::parse_override(" dc489b7ca3ca+dirty\n"),
        ("dc489b7ca3ca".to_string(), true)
    );
}
