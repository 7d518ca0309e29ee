//! A bundle holds its files byte for byte, is recognised by its first entry, and the same
//! inputs give the same bytes.

use mfx_table::bundle;

#[test]
fn a_bundle_round_trips_its_files_and_is_reproducible() {
    let t = tempfile::tempdir().unwrap();
    let src = t.path().join("src");
    std::fs::create_dir_all(src.join("report")).unwrap();
    std::fs::write(src.join("run.json"), b"{\"a\": 1}").unwrap();
    std::fs::write(src.join("report/index.html"), b"<html></html>").unwrap();
    let files = vec![
        (
            "report/index.html".to_string(),
            src.join("report/index.html"),
        ),
        ("run.json".to_string(), src.join("run.json")),
    ];
    let manifest = serde_json::json!({"format": bundle::FORMAT, "run": "r"});
    let a = t.path().join("a.tar.gz");
    let b = t.path().join("b.tar.gz");
    bundle::write(&a, &manifest, &files).unwrap();
    bundle::write(&b, &manifest, &files).unwrap();
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    assert!(bundle::is_bundle(&a));
    assert!(!bundle::is_bundle(&src.join("run.json")));
    let opened = bundle::open(&a).unwrap();
    assert_eq!(opened.manifest["run"], "r");
    assert_eq!(
        std::fs::read(opened.dir().join("report/index.html")).unwrap(),
        b"<html></html>"
    );
    let dir = opened.dir().to_path_buf();
    drop(opened);
    assert!(!dir.exists(), "the temporary folder goes with the handle");
    // Any other file is refused, naming it.
    let e = bundle::extract(&src.join("run.json"), &t.path().join("x"))
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("run.json") && e.contains("not an mfx bundle"),
        "{e}"
    );
    // A bundle of a later format is refused, not misread.
    bundle::write(&b, &serde_json::json!({"format": 99}), &files).unwrap();
    let e = bundle::open(&b).err().unwrap().to_string();
    assert!(e.contains("format Some(99)"), "{e}");
}
