//! Names on charts. A configuration is named by its method and the axes that vary among that
//! method's configurations in the chart (the rest go in the caption once); a scene by its
//! generator, its mesh file's stem and the parameters that tell it apart from the chart's other
//! scenes. Names are never cut: two different things never share a name.

use schema::{cols, PointKey};
use std::collections::BTreeMap;

use mfx_analysis::data::Rec;

/// A row's configuration axes: the `k=v` pairs of its point key's last field (the axes the
/// method read, as the sweep set them; an axis left at its default is absent).
pub fn config_axes(r: &Rec) -> Vec<(String, String)> {
    match r.get(cols::POINT_KEY).parse::<PointKey>() {
        Ok(k) => k
            .axes()
            .into_iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect(),
        Err(_) => Vec::new(),
    }
}

/// Identity of a configuration: method and its axes (study, scene and resolution left out).
pub fn config_key(r: &Rec) -> String {
    let axes: Vec<String> = config_axes(r)
        .into_iter()
        .map(|(k, v)| format!("{k}={v}"))
        .collect();
    format!("{}|{}", r.get(cols::METHOD), axes.join(","))
}

/// Labels of the configurations in a set of rows.
#[derive(Clone, Debug, Default)]
pub struct ConfigLabels {
    by_key: BTreeMap<String, String>,
    /// `method: axis=value, …` for axes that are the same in every configuration of a method.
    fixed: BTreeMap<String, Vec<String>>,
}

impl ConfigLabels {
    pub fn new<'a>(rows: impl IntoIterator<Item = &'a Rec>) -> ConfigLabels {
        // method → configurations (axis maps), first-seen order.
        type Configs = Vec<(String, BTreeMap<String, String>)>;
        let mut methods: Vec<(String, Configs)> = Vec::new();
        for r in rows {
            let m = r.get(cols::METHOD).to_string();
            let key = config_key(r);
            let axes: BTreeMap<String, String> = config_axes(r).into_iter().collect();
            let i = match methods.iter().position(|(n, _)| *n == m) {
                Some(i) => i,
                None => {
                    methods.push((m, Vec::new()));
                    methods.len() - 1
                }
            };
            if !methods[i].1.iter().any(|(k, _)| *k == key) {
                methods[i].1.push((key, axes));
            }
        }
        let mut out = ConfigLabels::default();
        for (m, cfgs) in &methods {
            let mut names: Vec<&String> = cfgs.iter().flat_map(|(_, a)| a.keys()).collect();
            names.sort();
            names.dedup();
            // An axis varies when two configurations differ in it (absent counts as a value).
            let varies = |n: &str| {
                let first = cfgs[0].1.get(n);
                cfgs.iter().any(|(_, a)| a.get(n) != first)
            };
            let fixed: Vec<String> = names
                .iter()
                .filter(|n| !varies(n))
                .map(|n| format!("{n}={}", cfgs[0].1[n.as_str()]))
                .collect();
            if !fixed.is_empty() {
                out.fixed.insert(m.clone(), fixed);
            }
            for (key, axes) in cfgs {
                let parts: Vec<String> = axes
                    .iter()
                    .filter(|(n, _)| varies(n))
                    .map(|(n, v)| format!("{n}={v}"))
                    .collect();
                let label = if parts.is_empty() {
                    m.clone()
                } else {
                    format!("{m} {}", parts.join(", "))
                };
                out.by_key.insert(key.clone(), label);
            }
        }
        // Distinct configurations keep distinct names whatever happened above.
        let mut seen: BTreeMap<String, usize> = BTreeMap::new();
        for l in out.by_key.values() {
            *seen.entry(l.clone()).or_default() += 1;
        }
        for (k, l) in out.by_key.iter_mut() {
            if seen[l.as_str()] > 1 {
                *l = format!("{l} [{}]", k.split_once('|').map(|x| x.1).unwrap_or(k));
            }
        }
        out
    }

    /// The row's configuration label (its method alone when it is not in the set).
    pub fn get(&self, r: &Rec) -> String {
        self.by_key
            .get(&config_key(r))
            .cloned()
            .unwrap_or_else(|| r.get(cols::METHOD).to_string())
    }

    /// "Fixed: depth_peel max_layers=256; …" for a caption, or "" when nothing is fixed.
    pub fn fixed_note(&self) -> String {
        if self.fixed.is_empty() {
            return String::new();
        }
        let parts: Vec<String> = self
            .fixed
            .iter()
            .map(|(m, f)| format!("{m} {}", f.join(", ")))
            .collect();
        format!("Same in every configuration: {}.", parts.join("; "))
    }
}

/// `gen(k=v,…)` → (generator, parameters in label order).
pub fn parse_scene(label: &str) -> (String, Vec<(String, String)>) {
    match label.split_once('(') {
        Some((g, rest)) => {
            let inner = rest.strip_suffix(')').unwrap_or(rest);
            let params = inner
                .split(',')
                .filter_map(|kv| kv.split_once('='))
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect();
            (g.to_string(), params)
        }
        None => (label.to_string(), Vec::new()),
    }
}

/// A file path's stem: `models/stanford-bunny.obj` → `stanford-bunny`.
pub fn file_stem(path: &str) -> &str {
    let name = path.rsplit(['/', '\\']).next().unwrap_or(path);
    match name.rsplit_once('.') {
        Some((s, _)) if !s.is_empty() => s,
        _ => name,
    }
}

fn is_path(k: &str) -> bool {
    matches!(k, "path" | "mesh" | "file" | "obj")
}

/// A scene's full name with mesh paths shortened to their stem:
/// `obj(path=models/holes.obj,instances=4)` → `obj holes (instances=4)`.
pub fn scene_name(label: &str) -> String {
    scene_name_with(label, &|_| true)
}

fn scene_name_with(label: &str, keep: &dyn Fn(&str) -> bool) -> String {
    let (g, params) = parse_scene(label);
    let mut s = g;
    for (_, v) in params.iter().filter(|(k, _)| is_path(k)) {
        s.push(' ');
        s.push_str(file_stem(v));
    }
    let rest: Vec<String> = params
        .iter()
        .filter(|(k, _)| !is_path(k) && keep(k))
        .map(|(k, v)| format!("{k}={v}"))
        .collect();
    if !rest.is_empty() {
        s.push_str(&format!(" ({})", rest.join(", ")));
    }
    s
}

/// Names for a set of scene labels: generator, mesh stem, and only the parameters that differ
/// between scenes of the same generator. Distinct labels always get distinct names (two meshes
/// with one stem in different folders keep their paths).
pub fn scene_names(labels: &[String]) -> Vec<String> {
    let parsed: Vec<(String, Vec<(String, String)>)> =
        labels.iter().map(|l| parse_scene(l)).collect();
    let mut names: Vec<String> = labels
        .iter()
        .zip(&parsed)
        .map(|(l, (g, params))| {
            let peers: Vec<&Vec<(String, String)>> = parsed
                .iter()
                .filter(|(g2, _)| g2 == g)
                .map(|(_, p)| p)
                .collect();
            let varies = |k: &str| {
                let v0 = params.iter().find(|(n, _)| n == k).map(|x| &x.1);
                peers
                    .iter()
                    .any(|p| p.iter().find(|(n, _)| n == k).map(|x| &x.1) != v0)
            };
            scene_name_with(l, &varies)
        })
        .collect();
    for i in 0..names.len() {
        let clash =
            (0..names.len()).any(|j| j != i && names[j] == names[i] && labels[j] != labels[i]);
        if clash {
            names[i] = labels[i].clone();
        }
    }
    names
}

/// A file-name stem from any text: letters, digits, `-` and `_`, at most 64 characters; a longer
/// text keeps its first 47 and an FNV-1a hash of the whole, so two labels never share a file.
pub fn file_safe(s: &str) -> String {
    let mut out = String::new();
    for c in s.chars() {
        let c = if c.is_ascii_alphanumeric() || c == '-' {
            c
        } else {
            '_'
        };
        if !(c == '_' && out.ends_with('_')) {
            out.push(c);
        }
    }
    let out = out.trim_matches('_').to_string();
    if out.len() <= 64 {
        return out;
    }
    let mut h: u64 = 0xcbf29ce484222325;
    for b in s.bytes() {
        h ^= b as u64;
        h = h.wrapping_mul(0x100000001b3);
    }
    format!("{}_{:016x}", &out[..47], h)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(key: &str) -> Rec {
        let method = key.parse::<PointKey>().unwrap().method;
        Rec([
            (cols::POINT_KEY.to_string(), key.to_string()),
            (cols::METHOD.to_string(), method),
        ]
        .into_iter()
        .collect())
    }

    #[test]
    fn labels_name_only_the_axes_that_vary() {
        let rows: Vec<Rec> = [
            "methods|s|64x64|depth_peel|max_layers=256,occlusion_stop=true",
            "methods|s|64x64|kbuffer_rmw|layers=4,variant=plain",
            "methods|s|64x64|kbuffer_rmw|layers=8,variant=plain",
            "methods|s|64x64|kbuffer_rmw|layers=8,variant=heuristics",
            "methods|s|64x64|wboit|",
        ]
        .iter()
        .map(|k| rec(k))
        .collect();
        let l = ConfigLabels::new(&rows);
        let got: Vec<String> = rows.iter().map(|r| l.get(r)).collect();
        assert_eq!(
            got,
            [
                "depth_peel",
                "kbuffer_rmw layers=4, variant=plain",
                "kbuffer_rmw layers=8, variant=plain",
                "kbuffer_rmw layers=8, variant=heuristics",
                "wboit"
            ]
        );
        assert_eq!(
            l.fixed_note(),
            "Same in every configuration: depth_peel max_layers=256, occlusion_stop=true."
        );
    }

    #[test]
    fn an_axis_present_in_some_configurations_only_is_named() {
        // The shadows sweeps: the bias sweep sets bias_mode, the layer sweep leaves it default;
        // shadow_map_res varies too. No two of these may share a label.
        let rows: Vec<Rec> = [
            "shadows|s|512x512|layered_ssm|layers=3,max_nspp=169,shadow_map_res=512",
            "shadows|s|512x512|layered_ssm|layers=3,max_nspp=169,shadow_map_res=1024",
            "shadows|s|512x512|layered_ssm|bias_mode=slope,layers=3,shadow_map_res=1024",
            "shadows|s|512x512|layered_ssm|bias_mode=midpoint,layers=3,shadow_map_res=1024",
            "shadows|s|512x512|layered_ssm|hsm=false,layers=3,max_nspp=169,shadow_map_res=1024",
        ]
        .iter()
        .map(|k| rec(k))
        .collect();
        let l = ConfigLabels::new(&rows);
        let got: Vec<String> = rows.iter().map(|r| l.get(r)).collect();
        for (i, a) in got.iter().enumerate() {
            assert!(!got[..i].contains(a), "{got:?}");
        }
        assert!(got[2].contains("bias_mode=slope") && got[2].contains("shadow_map_res=1024"));
        assert!(!got[0].contains("layers=3"), "layers never varies: {got:?}");
    }

    #[test]
    fn scene_names_use_the_mesh_stem_and_never_collide() {
        let labels: Vec<String> = [
            "obj(instances=4,path=/home/u/models/holes-a.obj)",
            "obj(instances=4,path=/home/u/models/holes-b.obj)",
            "obj(instances=16,path=/home/u/models/holes-b.obj)",
            "shells(count=4,segments=64)",
            "shells(count=16,segments=64)",
            "grass(blades=2000)",
            "obj(instances=4,path=/other/holes-a.obj)",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        let n = scene_names(&labels);
        assert_eq!(n[1], "obj holes-b (instances=4)");
        assert_eq!(n[3], "shells (count=4)");
        assert_eq!(n[5], "grass");
        for (i, a) in n.iter().enumerate() {
            assert!(!n[..i].contains(a), "{n:?}");
        }
        assert_eq!(
            scene_name("soft_shadow(case=obj,path=models/stanford-bunny.obj)"),
            "soft_shadow stanford-bunny (case=obj)"
        );
    }

    #[test]
    fn file_names_of_long_labels_stay_distinct() {
        let a = file_safe(&format!("methods_error_vs_time_obj_{}_a", "x".repeat(80)));
        let b = file_safe(&format!("methods_error_vs_time_obj_{}_b", "x".repeat(80)));
        assert_ne!(a, b);
        assert!(a.len() <= 64);
        assert_eq!(
            file_safe("quads(depth_complexity=8)"),
            "quads_depth_complexity_8"
        );
    }
}
