//! The documents a new user and a citing author read first: they exist and say what the code
//! does (the schema version, the licence the manifest declares, README.md a door, not a notebook).

use std::path::Path;

fn read(rel: &str) -> String {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join(rel);
    std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

#[test]
fn results_readme_names_the_schema_version_the_csv_writes() {
    let readme = read("results/README.md");
    let want = format!("Schema version {}.", schema::SCHEMA_VERSION);
    assert!(
        readme.contains(&want),
        "results/README.md must say '{want}' (the version runs.csv's `schema` column writes)"
    );
    for v in 1..schema::SCHEMA_VERSION {
        assert!(
            !readme.contains(&format!("Schema version {v}.")),
            "results/README.md still says schema version {v}"
        );
    }
}

#[test]
fn the_declared_licences_have_their_files_and_a_citation_exists() {
    let manifest = read("Cargo.toml");
    assert!(manifest.contains(r#"license = "MIT OR Apache-2.0""#));
    assert!(read("LICENSE-MIT").contains("Permission is hereby granted"));
    assert!(read("LICENSE-APACHE").contains("Apache License"));
    let cff = read("CITATION.cff");
    for key in ["cff-version:", "title:", "authors:", "license:"] {
        assert!(cff.contains(key), "CITATION.cff lacks {key}");
    }
}

/// Every model a suite names is in the tree or has a command of this repository that brings it
/// (what `mfx check` prints when it is missing), models/README.md names it, and no suite
/// description points into one machine's folders.
#[test]
fn every_model_a_suite_names_is_carried_or_fetched_and_credited() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let credits = read("models/README.md");
    let mut seen = 0;
    for dir in ["scenarios/suites", "scenarios/suites/internal"] {
        for e in std::fs::read_dir(root.join(dir)).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_none_or(|x| x != "toml") {
                continue;
            }
            let suite = scenarios::Suite::load(p.to_str().unwrap()).unwrap();
            assert!(
                !suite.description.contains("/work/")
                    && !suite.description.contains("shared/models"),
                "{}: a machine path in the description",
                p.display()
            );
            for m in bench_core::check::models_needed(&suite) {
                seen += 1;
                // In the tree: tracked by git (a fetched copy beside it does not count).
                let here = std::process::Command::new("git")
                    .args(["ls-files", "--error-unmatch", &m])
                    .current_dir(root)
                    .output()
                    .is_ok_and(|o| o.status.success());
                assert!(
                    here || scenarios::obj::fetch_command(&m).is_some(),
                    "{}: {m} is neither in the tree nor fetched by a script",
                    p.display()
                );
                let file = Path::new(&m).file_name().unwrap().to_str().unwrap();
                let stem = file.split('.').next().unwrap();
                assert!(
                    credits.contains(stem),
                    "models/README.md does not name {file}"
                );
            }
        }
    }
    assert!(seen > 0, "the suites name models");
}

/// README.md is a user's door (what mfx answers, the two commands, a handful of CLI lines, one
/// sample, links); findings live in results/reference/README.md beside their runs.
#[test]
fn the_readme_is_a_door_of_at_most_200_lines() {
    let readme = read("README.md");
    let n = readme.lines().count();
    assert!(n <= 200, "README.md has {n} lines (at most 200)");
    for link in [
        "results/README.md",
        "results/reference/README.md",
        "bash scripts/test.sh",
        "bash scripts/main.sh",
    ] {
        assert!(readme.contains(link), "README.md lacks {link}");
    }
    let reference = read("results/reference/README.md");
    for run in [
        "2026-12-03-h200-sources-b",
        "2026-12-03-h200-resolve",
        "2026-12-02-h200-floors",
    ] {
        assert!(
            reference.contains(run),
            "results/reference/README.md lacks {run}"
        );
    }
}
