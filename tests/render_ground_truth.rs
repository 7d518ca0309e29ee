//! `mfx render --camera-out / --camera-in / --reference-out` through the built binary on
//! lavapipe: the files exist with the documented dtypes and shapes, the depth complexity is the
//! reference's, and the camera JSON maps the OBJ file's own coordinates to the right pixels.

use std::path::Path;
use std::process::Command;

fn mfx(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_mfx"))
        .args(args)
        .env(
            "XDG_RUNTIME_DIR",
            std::env::var("XDG_RUNTIME_DIR").unwrap_or("/tmp".into()),
        )
        .output()
        .expect("mfx runs");
    let text =
        String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "mfx {args:?} failed:\n{text}");
    text
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
fn tmp(name: &str) -> Tmp {
    tmp_dir(&format!("mfx-render-{name}"))
}

/// Two axis-aligned 4×4 squares at z = 5 and z = 7 in the file's own (off-centre) coordinates.
const OBJ: &str = "v 10 10 5\nv 14 10 5\nv 14 14 5\nv 10 14 5\nv 10 10 7\nv 14 10 7\nv 14 14 7\nv 10 14 7\nf 1 2 3\nf 1 3 4\nf 5 6 7\nf 5 7 8\n";

fn npy<T: npyz::Deserialize>(p: &Path) -> (Vec<u64>, String, Vec<T>) {
    let bytes = std::fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    let f = npyz::NpyFile::new(&bytes[..]).unwrap();
    let shape = f.shape().to_vec();
    let dtype = f.dtype().descr().trim_matches('\'').to_string();
    (shape, dtype, f.into_vec().unwrap())
}

fn png_bit_depth(p: &Path) -> u8 {
    let b = std::fs::read(p).unwrap();
    assert_eq!(&b[1..4], b"PNG", "{}", p.display());
    b[24] // IHDR bit depth
}

type M = [[f64; 4]; 4];

fn project(m: &M, v: [f64; 3], w: f64, h: f64) -> (f64, f64) {
    let c: Vec<f64> = (0..4)
        .map(|r| m[r][0] * v[0] + m[r][1] * v[1] + m[r][2] * v[2] + m[r][3])
        .collect();
    let (x, y) = (c[0] / c[3], c[1] / c[3]);
    ((x + 1.0) / 2.0 * w - 0.5, (1.0 - y) / 2.0 * h - 0.5)
}

#[test]
fn reference_out_and_camera_json_of_an_obj() {
    let t = tmp("obj");
    let obj = t.join("two.obj");
    std::fs::write(&obj, OBJ).unwrap();
    let (w, h) = (48usize, 32usize);
    let out = mfx(&[
        "render",
        "--obj",
        obj.to_str().unwrap(),
        "--width",
        "48",
        "--height",
        "32",
        "--camera-out",
        t.join("cam.json").to_str().unwrap(),
        "--reference-out",
        t.join("ref").to_str().unwrap(),
    ]);
    let r = t.join("ref");
    let (shape, dtype, dc) = npy::<u16>(&r.join("depth_complexity.npy"));
    assert_eq!((shape, dtype.as_str()), (vec![h as u64, w as u64], "<u2"));
    assert_eq!(png_bit_depth(&r.join("depth_complexity.png")), 16);
    let (shape, dtype, refimg) = npy::<f32>(&r.join("reference.npy"));
    assert_eq!(
        (shape, dtype.as_str()),
        (vec![h as u64, w as u64, 4], "<f4")
    );
    let (shape, dtype, peel) = npy::<f32>(&r.join("depth_peel.npy"));
    assert_eq!(
        (shape, dtype.as_str()),
        (vec![h as u64, w as u64, 4], "<f4")
    );
    assert!(r.join("depth_peel.png").is_file() && r.join("reference.png").is_file());
    // The CLI prints the reference's maximum: the file must hold the same.
    let max = *dc.iter().max().unwrap();
    assert!(
        out.contains(&format!("depth complexity max {max},")),
        "{out}"
    );
    assert_eq!(max, 2, "two overlapping squares");
    // depth_peel is exact here: its image matches the reference to f32 compositing rounding.
    let diff = refimg
        .iter()
        .zip(&peel)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    assert!(diff < 1e-5, "depth_peel vs reference max diff {diff}");

    // The JSON's clip_from_object maps file coordinates to pixels: pixel centres well inside
    // the projection of both squares see 2 fragments, those well outside both see 0.
    let cam: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(t.join("cam.json")).unwrap()).unwrap();
    assert_eq!(cam["width"], 48);
    assert_eq!(cam["height"], 32);
    let m: M = serde_json::from_value(cam["clip_from_object"][0].clone()).unwrap();
    let rect = |z: f64| {
        let (x0, y0) = project(&m, [10.0, 10.0, z], w as f64, h as f64);
        let (x1, y1) = project(&m, [14.0, 14.0, z], w as f64, h as f64);
        (x0.min(x1), x0.max(x1), y0.min(y1), y0.max(y1))
    };
    let (a, b) = (rect(5.0), rect(7.0));
    let inner = (a.0.max(b.0), a.1.min(b.1), a.2.max(b.2), a.3.min(b.3));
    let outer = (a.0.min(b.0), a.1.max(b.1), a.2.min(b.2), a.3.max(b.3));
    let (mut n_in, mut n_out) = (0, 0);
    for y in 0..h {
        for x in 0..w {
            let (px, py) = (x as f64, y as f64);
            let d = dc[y * w + x];
            // 0.01 px margin: sub-pixel snapping (1/256 px) moves edges by less than that.
            if px > inner.0 + 0.01
                && px < inner.1 - 0.01
                && py > inner.2 + 0.01
                && py < inner.3 - 0.01
            {
                assert_eq!(d, 2, "pixel ({x},{y}) inside both squares");
                n_in += 1;
            } else if px < outer.0 - 0.01
                || px > outer.1 + 0.01
                || py < outer.2 - 0.01
                || py > outer.3 + 0.01
            {
                assert_eq!(d, 0, "pixel ({x},{y}) outside both squares");
                n_out += 1;
            }
        }
    }
    assert!(
        n_in > 20 && n_out > 20,
        "the test covers both regions ({n_in}, {n_out})"
    );
}

#[test]
fn camera_in_renders_from_the_given_matrix() {
    let t = tmp("camin");
    let obj = t.join("two.obj");
    std::fs::write(&obj, OBJ).unwrap();
    mfx(&[
        "render",
        "--obj",
        obj.to_str().unwrap(),
        "--width",
        "40",
        "--height",
        "40",
        "--camera-out",
        t.join("cam.json").to_str().unwrap(),
    ]);
    // An orthographic camera looking down −z: world x, y are NDC x, y; depth 0.5 − 0.25 z.
    let mut cam: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(t.join("cam.json")).unwrap()).unwrap();
    cam["clip_from_world"] = serde_json::json!([
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, -0.25, 0.5],
        [0.0, 0.0, 0.0, 1.0]
    ]);
    std::fs::write(t.join("ortho.json"), cam.to_string()).unwrap();
    mfx(&[
        "render",
        "--obj",
        obj.to_str().unwrap(),
        "--camera-in",
        t.join("ortho.json").to_str().unwrap(),
        "--reference-out",
        t.join("ref").to_str().unwrap(),
        "--camera-out",
        t.join("again.json").to_str().unwrap(),
    ]);
    let (shape, _, dc) = npy::<u16>(&t.join("ref/depth_complexity.npy"));
    assert_eq!(shape, vec![40, 40], "size comes from the camera file");
    // Both squares map to world x, y ∈ [−2/3, 2/3] (centre (12,12,6), radius 3): pixels
    // (x + 0.5)/20 − 1 within ±2/3 → 6.2 < x < 32.8, same for y.
    for y in 0..40 {
        for x in 0..40 {
            let inside = (7..=32).contains(&x) && (7..=32).contains(&y);
            assert_eq!(
                dc[y * 40 + x],
                if inside { 2 } else { 0 },
                "pixel ({x},{y})"
            );
        }
    }
    // What was read is what is written back (the f32 matrix the GPU used).
    let again: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(t.join("again.json")).unwrap()).unwrap();
    assert_eq!(again["clip_from_world"], cam["clip_from_world"]);
    // A bad camera is an error naming the file and the value.
    cam["near"] = serde_json::json!(-1.0);
    std::fs::write(t.join("bad.json"), cam.to_string()).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_mfx"))
        .args([
            "render",
            "--obj",
            obj.to_str().unwrap(),
            "--camera-in",
            t.join("bad.json").to_str().unwrap(),
            "--camera-out",
            t.join("x.json").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("bad.json") && err.contains("near -1"),
        "{err}"
    );
}
