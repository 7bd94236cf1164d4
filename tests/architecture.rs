//! The layering of `src/` (docs/architecture.md), checked from the source text: which module
//! refers to which, no cycles, every import going down the layers, `film` and `scene` apart,
//! no engine in the layers below the engines, no engine importing another, `unsafe` only in
//! the Embree layer with a SAFETY line, and `main.rs` short.
//!
//! A module is a file. An edge A → B means that A names an item path (`crate::…`, `super::…`,
//! `self::…`, in a `use` or inline) that resolves to file B: the longest prefix of the path
//! that is a module. A folder's `mod.rs` declares and re-exports its children, so its edges
//! to its own descendants are not counted; every other edge is.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Every `.rs` file under `src/`, by module path (`engines::photon::trace`; `""` for lib.rs).
fn modules() -> BTreeMap<String, PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for e in std::fs::read_dir(dir).expect("src/ readable") {
            let p = e.expect("entry").path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|e| e == "rs") {
                out.push(p);
            }
        }
    }
    let src = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    walk(&src, &mut files);
    files
        .into_iter()
        .filter(|p| !p.ends_with("main.rs"))
        .map(|p| {
            let rel = p.strip_prefix(&src).unwrap().with_extension("");
            let mut parts: Vec<String> = rel.iter().map(|s| s.to_string_lossy().into()).collect();
            if parts.last().is_some_and(|l| l == "mod" || l == "lib") {
                parts.pop();
            }
            (parts.join("::"), p)
        })
        .collect()
}

/// The code of a file without comments, string literals and its `#[cfg(test)]` module.
fn code(path: &Path) -> String {
    let text = std::fs::read_to_string(path).expect("readable");
    let text = match text.find("#[cfg(test)]\nmod tests") {
        Some(i) => &text[..i],
        None => &text[..],
    };
    let mut out = String::new();
    let mut in_string = false;
    for line in text.lines() {
        let mut chars = line.chars().peekable();
        while let Some(c) = chars.next() {
            if in_string {
                if c == '\\' {
                    chars.next();
                } else if c == '"' {
                    in_string = false;
                }
                continue;
            }
            if c == '/' && chars.peek() == Some(&'/') {
                break;
            }
            if c == '"' {
                in_string = true;
                continue;
            }
            out.push(c);
        }
        out.push('\n');
    }
    out
}

/// Item paths named in a file, absolute (`engines::photon::Photon`): `use` trees expanded
/// one level of braces at a time, `super`/`self` resolved against the file's module.
fn paths(module: &str, code: &str) -> Vec<String> {
    let here: Vec<&str> = if module.is_empty() {
        vec![]
    } else {
        module.split("::").collect()
    };
    // `super` and `self` are relative to the file's module: a file `a/b.rs` is module a::b.
    let resolve = |p: &str| -> Option<String> {
        let mut segs: Vec<&str> = p
            .split("::")
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .collect();
        let mut base: Vec<&str> = match segs.first().copied() {
            Some("crate") => {
                segs.remove(0);
                vec![]
            }
            Some("self") => {
                segs.remove(0);
                here.clone()
            }
            Some("super") => {
                let mut b = here.clone();
                while segs.first() == Some(&"super") {
                    segs.remove(0);
                    b.pop();
                }
                b
            }
            _ => return None,
        };
        base.extend(segs.iter().filter(|s| **s != "self"));
        Some(base.join("::"))
    };
    let mut found = Vec::new();
    // `use` declarations, braces expanded.
    let mut rest = code;
    while let Some(i) = rest.find("use ") {
        let after = &rest[i + 4..];
        let Some(end) = after.find(';') else { break };
        let tree = &after[..end];
        let preceded_ok = i == 0 || !rest.as_bytes()[i - 1].is_ascii_alphanumeric();
        if preceded_ok {
            expand(tree.trim(), &mut |p| {
                if let Some(abs) = resolve(&p) {
                    found.push(abs);
                }
            });
        }
        rest = &after[end..];
    }
    // Inline paths (`crate::render::CHUNK_SAMPLES`, `super::raytrace::render_with(…)`).
    let bytes: Vec<char> = code.chars().collect();
    let mut i = 0;
    while i < bytes.len() {
        let starts = ["crate::", "super::", "self::"];
        let at = |s: &str| bytes[i..].iter().take(s.len()).copied().eq(s.chars());
        let boundary = i == 0
            || !(bytes[i - 1].is_alphanumeric() || bytes[i - 1] == '_' || bytes[i - 1] == ':');
        if boundary && starts.iter().any(|s| at(s)) {
            let mut j = i;
            while j < bytes.len()
                && (bytes[j].is_alphanumeric() || bytes[j] == '_' || bytes[j] == ':')
            {
                j += 1;
            }
            let p: String = bytes[i..j].iter().collect();
            if let Some(abs) = resolve(p.trim_end_matches(':')) {
                found.push(abs);
            }
            i = j;
        } else {
            i += 1;
        }
    }
    found
}

/// Calls `f` with every path of a `use` tree: `a::{b, c::{d, e}}` gives a::b, a::c::d, a::c::e.
fn expand(tree: &str, f: &mut dyn FnMut(String)) {
    let tree = tree.trim();
    match tree.find('{') {
        None => {
            let p = tree.split(" as ").next().unwrap_or(tree).trim();
            if !p.is_empty() {
                f(p.trim_end_matches("::*").to_string());
            }
        }
        Some(open) => {
            let prefix = &tree[..open];
            let inner = &tree[open + 1..tree.rfind('}').unwrap_or(tree.len())];
            let mut depth = 0;
            let mut start = 0;
            let mut parts = Vec::new();
            for (k, c) in inner.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        parts.push(&inner[start..k]);
                        start = k + 1;
                    }
                    _ => {}
                }
            }
            parts.push(&inner[start..]);
            for part in parts {
                let part = part.trim();
                if !part.is_empty() {
                    expand(&format!("{prefix}{part}"), f);
                }
            }
        }
    }
}

/// The module graph: for each module, the modules it refers to.
fn graph() -> BTreeMap<String, BTreeSet<String>> {
    let modules = modules();
    let mut edges = BTreeMap::new();
    for (module, file) in &modules {
        let is_mod_rs = file.ends_with("mod.rs") || file.ends_with("lib.rs");
        let mut targets = BTreeSet::new();
        for p in paths(module, &code(file)) {
            let segs: Vec<&str> = p.split("::").collect();
            let target = (0..=segs.len())
                .rev()
                .map(|n| segs[..n].join("::"))
                .find(|m| modules.contains_key(m));
            let Some(target) = target else { continue };
            let own_descendant =
                is_mod_rs && (module.is_empty() || target.starts_with(&format!("{module}::")));
            if target != *module && !own_descendant {
                targets.insert(target);
            }
        }
        edges.insert(module.clone(), targets);
    }
    edges
}

fn top(module: &str) -> &str {
    module.split("::").next().unwrap_or("")
}

#[test]
fn the_module_graph_has_no_cycle() {
    let g = graph();
    // Depth-first search for a back edge, reporting the cycle.
    fn visit(
        m: &str,
        g: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        stack: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(m.to_string(), 1);
        stack.push(m.to_string());
        for t in g.get(m).into_iter().flatten() {
            match state.get(t.as_str()).copied().unwrap_or(0) {
                1 => {
                    let from = stack.iter().position(|s| s == t).unwrap();
                    let mut cycle = stack[from..].to_vec();
                    cycle.push(t.clone());
                    return Some(cycle);
                }
                0 => {
                    if let Some(c) = visit(t, g, state, stack) {
                        return Some(c);
                    }
                }
                _ => {}
            }
        }
        stack.pop();
        state.insert(m.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for m in g.keys() {
        if state.get(m.as_str()).copied().unwrap_or(0) == 0 {
            if let Some(cycle) = visit(m, &g, &mut state, &mut Vec::new()) {
                panic!("import cycle: {}", cycle.join(" → "));
            }
        }
    }
    // The check sees what it should: known edges are there.
    assert!(
        g["engines::compose"].contains("engines::raytrace"),
        "{:?}",
        g["engines::compose"]
    );
    assert!(
        g["cli::render"].contains("engines"),
        "{:?}",
        g["cli::render"]
    );
    assert!(
        g["film::ray_tree"].contains("camera"),
        "{:?}",
        g["film::ray_tree"]
    );
    assert!(
        g["scene::sky"].contains("image_io"),
        "{:?}",
        g["scene::sky"]
    );
    assert!(
        g["scene::volume_grid"].contains("image_io"),
        "{:?}",
        g["scene::volume_grid"]
    );
}

/// The layers of docs/architecture.md, bottom up, by top-level module (`""` is lib.rs).
const LAYERS: [(&str, &[&str]); 10] = [
    (
        "base",
        &[
            "geometry",
            "sampling",
            "color",
            "output",
            "interrupt",
            "progress",
            "camera",
            "image_io",
            "bytes",
            "simd",
        ],
    ),
    ("scene", &["scene"]),
    ("visibility", &["accel"]),
    ("film", &["film"]),
    ("floor", &["render", "parallel"]),
    ("engines", &["engines"]),
    (
        "planning and reports",
        &["plan", "report", "bench", "farm", "generate"],
    ),
    ("command line", &["cli"]),
    ("viewer", &["viewer"]),
    ("the crate's root", &[""]),
];

fn layer(module: &str) -> usize {
    LAYERS
        .iter()
        .position(|(_, modules)| modules.contains(&top(module)))
        .unwrap_or_else(|| {
            panic!("module {module} is in no layer: add it to LAYERS and to docs/architecture.md")
        })
}

#[test]
fn every_import_goes_down_the_layers() {
    for (module, targets) in graph() {
        for t in &targets {
            assert!(
                layer(t) <= layer(&module),
                "{module} (layer {}) imports {t} (layer {}, above it)",
                LAYERS[layer(&module)].0,
                LAYERS[layer(t)].0
            );
        }
    }
}

#[test]
fn film_and_scene_are_side_by_side_and_the_engines_plan_nothing() {
    // The film and the scene share the camera and the image readers, which lie below both;
    // neither imports the other. The engines answer the planner; they do not ask it.
    let forbidden = [("film", "scene"), ("scene", "film"), ("engines", "plan")];
    for (module, targets) in graph() {
        for t in &targets {
            for (from, to) in forbidden {
                assert!(
                    !(top(&module) == from && top(t) == to),
                    "{module} imports {t}: {from} must not import {to}"
                );
            }
        }
    }
}

#[test]
fn the_layers_below_the_engines_import_no_engine() {
    let below = [
        "geometry", "scene", "accel", "film", "color", "output", "sampling", "render",
    ];
    let above = ["engines", "cli", "plan", "report", "bench", "farm"];
    for (module, targets) in graph() {
        if below.contains(&top(&module)) {
            for t in &targets {
                assert!(
                    !above.contains(&top(t)),
                    "{module} (a layer below the engines) imports {t}"
                );
            }
        }
    }
}

#[test]
fn no_engine_imports_another() {
    // The pure engines; `compose` wires them, `engine` is their interface, `scattering` the
    // materials they share.
    let engines = ["raycast", "raytrace", "radiosity", "photon", "path"];
    let engine_of = |m: &str| -> Option<String> {
        let mut segs = m.split("::");
        (segs.next() == Some("engines"))
            .then(|| segs.next().map(str::to_string))
            .flatten()
            .filter(|e| engines.contains(&e.as_str()))
    };
    for (module, targets) in graph() {
        let Some(own) = engine_of(&module) else {
            continue;
        };
        for t in &targets {
            assert!(
                engine_of(t).is_none_or(|e| e == own),
                "{module} (engine {own}) imports {t}"
            );
            assert!(
                t != "engines",
                "{module} imports the engines' registry (take the interface from engines::engine)"
            );
        }
    }
}

#[test]
fn unsafe_code_is_only_in_the_embree_layer_and_each_block_says_why() {
    for (module, file) in modules() {
        let code = code(&file);
        let uses_unsafe = code.contains("unsafe ")
            || code.contains("unsafe{")
            || code.lines().any(|l| l.trim_start().starts_with("unsafe"));
        if !module.starts_with("accel::embree") {
            assert!(!uses_unsafe, "{module} uses unsafe");
            continue;
        }
        let text = std::fs::read_to_string(&file).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        for (k, line) in lines.iter().enumerate() {
            let l = line.trim_start();
            let block = l.contains("unsafe {") || l.starts_with("unsafe impl");
            if block && !l.starts_with("//") {
                let said = lines[k.saturating_sub(4)..k]
                    .iter()
                    .any(|p| p.contains("SAFETY:"));
                assert!(
                    said,
                    "{}:{}: unsafe without a SAFETY line above",
                    file.display(),
                    k + 1
                );
            }
        }
    }
}

#[test]
fn main_only_parses_and_dispatches() {
    let main = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src/main.rs");
    let lines = std::fs::read_to_string(main).unwrap().lines().count();
    assert!(lines <= 250, "src/main.rs has {lines} lines");
}
