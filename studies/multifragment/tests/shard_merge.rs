//! Sharding and merging lose and invent nothing: the shards of the smoke suite, merged, hold
//! exactly the point keys of the unsharded run; every point lands in exactly one shard; saved
//! images travel with the merge and hold the image of their row.

use mfx_multifragment::STUDIES;
use std::path::Path;

use bench_core::record::{CsvSink, Status};
use bench_core::runner::{self, RunOptions};
use bench_core::{merge, testing};
use scenarios::Suite;

fn sweep(gpu: &bench_core::Gpu, suite: &Suite, shard: (usize, usize), out: &Path, images: bool) {
    std::fs::create_dir_all(out).unwrap();
    let groups = runner::shard_groups(
        runner::expand(STUDIES, suite, gpu.facts.is_software).unwrap(),
        shard,
    );
    let mut sink = CsvSink::create(&out.join("runs.csv")).unwrap();
    let opts = RunOptions {
        run_id: format!("test-shard{}of{}", shard.0, shard.1),
        git_rev: "test".into(),
        shard,
        save_images: images.then(|| out.to_path_buf()),
        ..Default::default()
    };
    let n = runner::run(gpu, STUDIES, suite, &groups, &opts, &mut sink)
        .unwrap()
        .written;
    assert_eq!(n, runner::rows_in(&groups));
}

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
fn tmp() -> Tmp {
    tmp_dir("mfx-shard-merge")
}

fn rows(p: &Path) -> Vec<csv::StringRecord> {
    csv::Reader::from_path(p)
        .unwrap()
        .records()
        .map(|r| r.unwrap())
        .collect()
}

#[test]
fn merged_shards_of_smoke_equal_the_unsharded_point_set() {
    let gpu = testing::gpu();
    let suite = Suite::load("smoke").unwrap();
    let t = tmp();
    sweep(gpu, &suite, (0, 1), &t.join("full"), false);
    // Three shards of four groups: uneven on purpose (one shard gets two groups).
    for i in 0..3 {
        sweep(gpu, &suite, (i, 3), &t.join(format!("job/shard-{i}")), true);
    }
    let m = merge::merge(&[t.join("job")], &t.join("merged")).unwrap();
    assert_eq!(m.files.len(), 3);
    assert!(m.duplicates.is_empty(), "{}", m.summary());
    let full = merge::point_keys(&t.join("full/runs.csv")).unwrap();
    let merged = merge::point_keys(&t.join("merged/runs.csv")).unwrap();
    assert!(!full.is_empty());
    assert_eq!(
        merged, full,
        "merged shards = unsharded run, as sorted multisets of point keys"
    );
    let mut each: Vec<String> = (0..3)
        .flat_map(|i| merge::point_keys(&t.join(format!("job/shard-{i}/runs.csv"))).unwrap())
        .collect();
    each.sort();
    assert_eq!(each, full, "every point in exactly one shard");

    // Images: every ok method row names its image and the merged folder has it.
    let recs = rows(&t.join("merged/runs.csv"));
    let h = csv::Reader::from_path(t.join("merged/runs.csv"))
        .unwrap()
        .headers()
        .unwrap()
        .clone();
    let col = |n: &str| h.iter().position(|c| c == n).unwrap();
    let mut checked = 0;
    for r in &recs {
        if !r[col("method")].starts_with("floor_") && r[col("status")].parse() == Ok(Status::Ok) {
            let f = &r[col("image_file")];
            assert!(f.starts_with("images/") && f.ends_with(".npy"), "{f}");
            let (w, hgt, px) =
                bench_core::image_io::read_npy_rgba(&t.join("merged").join(f)).unwrap();
            assert_eq!(
                (w.to_string(), hgt.to_string()),
                (r[col("width")].to_string(), r[col("height")].to_string())
            );
            assert_eq!(px.len(), (w * hgt) as usize);
            assert!(
                px.iter().any(|p| p[3] > 0.0),
                "the saved image is not empty"
            );
            checked += 1;
        }
    }
    assert!(
        checked >= 9,
        "one image per smoke scene and method, found {checked}"
    );
    assert_eq!(m.images_copied, checked);

    // Merging the same shard twice reports, and keeps out of runs.csv, every row of it.
    let again = merge::merge(
        &[
            t.join("job"),
            t.join("job/shard-0/runs.csv"),
            t.join("job/shard-0"),
        ],
        &t.join("twice"),
    )
    .unwrap();
    assert!(
        again.duplicates.is_empty(),
        "the same file named twice is read once"
    );
    std::fs::create_dir_all(t.join("copy")).unwrap();
    std::fs::copy(t.join("job/shard-0/runs.csv"), t.join("copy/runs.csv")).unwrap();
    let dup = merge::merge(&[t.join("job"), t.join("copy")], &t.join("dup")).unwrap();
    assert_eq!(dup.duplicates.len(), rows(&t.join("copy/runs.csv")).len());
    assert_eq!(merge::point_keys(&t.join("dup/runs.csv")).unwrap(), full);
    assert_eq!(
        rows(&t.join("dup/duplicates.csv")).len(),
        dup.duplicates.len()
    );
}
