//! The N rows of a run with the highest FLIP mean, kept with their images for the report.

use std::io;
use std::path::Path;

use crate::{magma_rgb8, save_rgb8_png, FlipResult};

/// Header of `flip/worst.csv`; paths are relative to the run folder.
pub const WORST_CSV_HEADER: [&str; 9] = {
    let c = schema::flip_worst::ALL;
    [
        c[0].name, c[1].name, c[2].name, c[3].name, c[4].name, c[5].name, c[6].name, c[7].name,
        c[8].name,
    ]
};

struct Entry {
    point_key: String,
    method: String,
    scene_label: String,
    mean: f64,
    p99: f64,
    width: u32,
    height: u32,
    method_rgb8: Vec<u8>,
    truth_rgb8: Vec<u8>,
    flip_rgb8: Vec<u8>,
    /// Offer order: ties in the mean keep the earlier row ahead, so ranks are deterministic.
    seq: u64,
}

/// Keeps the `n` offered rows with the highest `flip_mean` (ties: the first offered wins).
pub struct WorstKeeper {
    n: usize,
    entries: Vec<Entry>,
    seq: u64,
}

impl WorstKeeper {
    pub fn new(n: usize) -> Self {
        Self {
            n,
            entries: Vec::new(),
            seq: 0,
        }
    }

    /// The smallest mean a new row must beat to be kept, or `None` while there is room.
    fn threshold(&self) -> Option<f64> {
        (self.entries.len() >= self.n).then(|| {
            self.entries
                .iter()
                .map(|e| e.mean)
                .fold(f64::INFINITY, f64::min)
        })
    }

    /// Offers one image row. Returns whether it was kept. Cheap when it is not among the worst:
    /// the mean is compared before anything is copied or coloured. A NaN mean is never kept
    /// (it cannot be ranked; FLIP of 8-bit images is always finite).
    #[allow(
        clippy::too_many_arguments,
        reason = "one candidate: its point, method, scene, FLIP result and both 8-bit images with their size"
    )]
    pub fn offer(
        &mut self,
        point_key: &str,
        method: &str,
        scene_label: &str,
        flip: &FlipResult,
        method_rgb8: &[u8],
        truth_rgb8: &[u8],
        width: u32,
        height: u32,
    ) -> bool {
        if self.n == 0 || flip.mean.is_nan() {
            return false;
        }
        if let Some(t) = self.threshold() {
            if flip.mean <= t {
                return false;
            }
            // Evict the lowest mean; among equal lowest, the latest offered.
            let evict = (0..self.entries.len())
                .min_by(|&a, &b| {
                    let (ea, eb) = (&self.entries[a], &self.entries[b]);
                    ea.mean.total_cmp(&eb.mean).then(eb.seq.cmp(&ea.seq))
                })
                .expect("full keeper has entries");
            self.entries.swap_remove(evict);
        }
        let pixels = width as usize * height as usize;
        assert_eq!(
            method_rgb8.len(),
            pixels * 3,
            "WorstKeeper: method image size"
        );
        assert_eq!(
            truth_rgb8.len(),
            pixels * 3,
            "WorstKeeper: truth image size"
        );
        assert_eq!(flip.map.len(), pixels, "WorstKeeper: FLIP map size");
        self.entries.push(Entry {
            point_key: point_key.to_string(),
            method: method.to_string(),
            scene_label: scene_label.to_string(),
            mean: flip.mean,
            p99: flip.p99,
            width,
            height,
            method_rgb8: method_rgb8.to_vec(),
            truth_rgb8: truth_rgb8.to_vec(),
            flip_rgb8: magma_rgb8(&flip.map),
            seq: self.seq,
        });
        self.seq += 1;
        true
    }

    /// Number of rows kept so far.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Kept point keys, worst first.
    pub fn ranked_keys(&self) -> Vec<&str> {
        self.ranked().iter().map(|e| e.point_key.as_str()).collect()
    }

    fn ranked(&self) -> Vec<&Entry> {
        let mut v: Vec<&Entry> = self.entries.iter().collect();
        v.sort_by(|a, b| b.mean.total_cmp(&a.mean).then(a.seq.cmp(&b.seq)));
        v
    }

    /// Writes `dir/flip/<rank>-method.png`, `-truth.png`, `-flip.png` (rank 1 = highest mean)
    /// and `dir/flip/worst.csv`. Rank PNGs left in `flip/` by an earlier write are removed first,
    /// so every image there is listed in the CSV.
    pub fn write(&self, dir: &Path) -> io::Result<()> {
        let folder = dir.join("flip");
        std::fs::create_dir_all(&folder)?;
        for f in std::fs::read_dir(&folder)? {
            let f = f?;
            let name = f.file_name();
            let name = name.to_string_lossy();
            if is_rank_png(&name) {
                std::fs::remove_file(f.path())?;
            }
        }
        let mut csv = csv::Writer::from_path(folder.join("worst.csv")).map_err(io::Error::other)?;
        csv.write_record(WORST_CSV_HEADER)
            .map_err(io::Error::other)?;
        for (i, e) in self.ranked().into_iter().enumerate() {
            let rank = i + 1;
            let rel = |kind: &str| format!("flip/{rank}-{kind}.png");
            let (w, h) = (e.width, e.height);
            save_rgb8_png(&dir.join(rel("method")), &e.method_rgb8, w, h)?;
            save_rgb8_png(&dir.join(rel("truth")), &e.truth_rgb8, w, h)?;
            save_rgb8_png(&dir.join(rel("flip")), &e.flip_rgb8, w, h)?;
            csv.write_record([
                rank.to_string(),
                e.point_key.clone(),
                e.method.clone(),
                e.scene_label.clone(),
                e.mean.to_string(),
                e.p99.to_string(),
                rel("method"),
                rel("truth"),
                rel("flip"),
            ])
            .map_err(io::Error::other)?;
        }
        csv.flush()
    }
}

/// `<digits>-method.png`, `<digits>-truth.png` or `<digits>-flip.png`.
fn is_rank_png(name: &str) -> bool {
    let Some((rank, kind)) = name.split_once('-') else {
        return false;
    };
    !rank.is_empty()
        && rank.bytes().all(|b| b.is_ascii_digit())
        && matches!(kind, "method.png" | "truth.png" | "flip.png")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn result(mean: f64, pixels: usize) -> FlipResult {
        FlipResult {
            map: vec![mean as f32; pixels],
            mean,
            p50: mean,
            p95: mean,
            p99: mean,
            max: mean,
        }
    }

    #[test]
    fn keeps_the_highest_means_ties_to_the_first() {
        let mut k = WorstKeeper::new(3);
        let img = vec![0u8; 2 * 2 * 3];
        for (key, mean) in [
            ("a", 0.1),
            ("b", 0.5),
            ("c", 0.3),
            ("d", 0.05),
            ("e", 0.3),
            ("f", 0.4),
        ] {
            k.offer(key, "m", "s", &result(mean, 4), &img, &img, 2, 2);
        }
        // 0.5 (b), 0.4 (f), 0.3: c was offered before e, so c stays and e is refused.
        assert_eq!(k.ranked_keys(), vec!["b", "f", "c"]);
        assert!(!k.offer("g", "m", "s", &result(0.3, 4), &img, &img, 2, 2));
        assert!(!k.offer("nan", "m", "s", &result(f64::NAN, 4), &img, &img, 2, 2));
        assert!(!WorstKeeper::new(0).offer("x", "m", "s", &result(1.0, 4), &img, &img, 2, 2));
    }

    #[test]
    fn a_refused_row_is_not_checked_or_copied() {
        // The images of a row that cannot be kept are never read: wrong sizes do not panic.
        let mut k = WorstKeeper::new(1);
        let img = vec![0u8; 12];
        assert!(k.offer("a", "m", "s", &result(0.5, 4), &img, &img, 2, 2));
        assert!(!k.offer("b", "m", "s", &result(0.1, 4), &[], &[], 2, 2));
    }

    #[test]
    fn writes_images_and_csv() {
        let dir_tmp = tempfile::Builder::new()
            .prefix("mfx-flip-worst-")
            .tempdir()
            .unwrap();
        let dir = dir_tmp.path().to_path_buf();
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("flip")).unwrap();
        // A stale rank image from an earlier write goes; other files stay.
        std::fs::write(dir.join("flip/9-flip.png"), b"stale").unwrap();
        std::fs::write(dir.join("flip/notes.txt"), b"keep").unwrap();
        let (w, h) = (3u32, 2u32);
        let method: Vec<u8> = (0..18).map(|i| i as u8 * 10).collect();
        let truth = vec![255u8; 18];
        let mut k = WorstKeeper::new(2);
        k.offer(
            "s|x,y|3x2|m1|",
            "m1",
            "x,y",
            &result(0.2, 6),
            &method,
            &truth,
            w,
            h,
        );
        k.offer(
            "s|x,y|3x2|m2|",
            "m2",
            "x,y",
            &result(0.7, 6),
            &truth,
            &method,
            w,
            h,
        );
        k.write(&dir).unwrap();

        assert!(!dir.join("flip/9-flip.png").exists());
        assert!(dir.join("flip/notes.txt").exists());
        let mut rd = csv::Reader::from_path(dir.join("flip/worst.csv")).unwrap();
        assert_eq!(
            rd.headers().unwrap().iter().collect::<Vec<_>>(),
            WORST_CSV_HEADER
        );
        let rows: Vec<csv::StringRecord> = rd.records().map(|r| r.unwrap()).collect();
        assert_eq!(rows.len(), 2);
        assert_eq!(
            rows[0].iter().collect::<Vec<_>>(),
            [
                "1",
                "s|x,y|3x2|m2|",
                "m2",
                "x,y",
                "0.7",
                "0.7",
                "flip/1-method.png",
                "flip/1-truth.png",
                "flip/1-flip.png"
            ]
        );
        assert_eq!(&rows[1][2], "m1");
        for row in &rows {
            for col in 6..9 {
                let img = image::open(dir.join(&row[col])).unwrap().into_rgb8();
                assert_eq!(img.dimensions(), (w, h));
            }
        }
        // Rank 2 is m1: its method image is the gradient, its truth white, its FLIP map the
        // magma colour of 0.2 everywhere.
        let m = image::open(dir.join("flip/2-method.png"))
            .unwrap()
            .into_rgb8();
        assert_eq!(m.into_raw(), method);
        let t = image::open(dir.join("flip/2-truth.png"))
            .unwrap()
            .into_rgb8();
        assert_eq!(t.into_raw(), truth);
        let f = image::open(dir.join("flip/2-flip.png"))
            .unwrap()
            .into_rgb8();
        assert_eq!(f.into_raw(), magma_rgb8(&[0.2; 6]));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn rank_png_names() {
        assert!(is_rank_png("12-flip.png"));
        assert!(is_rank_png("1-method.png"));
        assert!(!is_rank_png("x-flip.png"));
        assert!(!is_rank_png("-flip.png"));
        assert!(!is_rank_png("1-flip.jpg"));
        assert!(!is_rank_png("worst.csv"));
    }
}
