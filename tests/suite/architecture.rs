//! The shape of the code, as docs/architecture.md draws it: the import graph
//! of the top-level modules (read from the sources: every `crate::<module>`
//! outside comments and test modules) has no cycle, every import goes down
//! the layers (the user side and the kernel side never import each other),
//! nothing inside the crate imports through `lib.rs`, geometry imports none
//! of the kernel side's rooms that read it (materials, probes, ...), and the
//! picture in docs/architecture.md is the graph the code has.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The layers, bottom up. A module may import modules of lower layers, and
/// of its own layer where the layer allows it (the graph stays acyclic).
const LAYERS: &[(&str, &[&str])] = &[
    (
        "foundation",
        &["error", "choice", "real", "math", "limits", "output", "vec3", "sampling", "settings", "mesh", "input"],
    ),
    ("user side", &["scene"]),
    (
        "kernel side",
        &["handle", "probe", "film", "material", "texture", "geometry", "camera", "estimator", "plan", "kernel"],
    ),
    ("bridge", &["job"]),
    ("driver", &["render", "rounds", "shard", "files", "provenance"]),
    ("instruments", &["instruments"]),
];

/// The two sides of the bridge: neither imports the other (they sit in
/// different layers, and the user side is below the kernel side only to
/// order the picture).
const USER_SIDE: &[&str] = &["scene"];

fn layer_of(m: &str) -> Option<usize> {
    LAYERS.iter().position(|(_, mods)| mods.contains(&m))
}

fn kernel_side(m: &str) -> bool {
    layer_of(m) == Some(2)
}

/// The source files under `dir`, recursively.
fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The code of a file that takes part in the graph: without its test module
/// (everything from `#[cfg(test)]` on, by the crate's convention) and without
/// comments (doc links are not imports).
fn code(text: &str) -> String {
    let text = text.split("#[cfg(test)]").next().unwrap_or("");
    text.lines()
        .map(|l| match l.find("//") {
            Some(i) if !l[..i].contains('"') => &l[..i],
            _ => l,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The identifiers that follow `crate::` in `code`.
fn crate_paths(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(i) = rest.find("crate::") {
        let after = &rest[i + "crate::".len()..];
        let ident: String = after.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
        if !ident.is_empty() {
            out.push(ident);
        }
        rest = after;
    }
    out
}

struct Graph {
    /// Module -> the modules it imports.
    edges: BTreeMap<String, BTreeSet<String>>,
    /// Imports through the crate root or `super::` at the top level: (file, path).
    through_root: Vec<(String, String)>,
}

fn graph() -> Graph {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut all = Vec::new();
    files(&src, &mut all);
    let top = |p: &Path| -> String {
        let rel = p.strip_prefix(&src).unwrap();
        let first = rel.components().next().unwrap().as_os_str().to_string_lossy().into_owned();
        first.trim_end_matches(".rs").to_string()
    };
    let modules: BTreeSet<String> = all.iter().map(|p| top(p)).collect();
    let mut g = Graph { edges: BTreeMap::new(), through_root: Vec::new() };
    for p in &all {
        let m = top(p);
        // The front (lib.rs re-exports) and the binary (main.rs, cli/) are above every layer.
        if ["lib", "main", "cli"].contains(&m.as_str()) {
            continue;
        }
        let text = code(&std::fs::read_to_string(p).unwrap());
        let name = p.strip_prefix(&src).unwrap().display().to_string();
        if p.parent() == Some(src.as_path()) && text.contains("super::") {
            g.through_root.push((name.clone(), "super::".into()));
        }
        let entry = g.edges.entry(m.clone()).or_default();
        for ident in crate_paths(&text) {
            if !modules.contains(&ident) || ident == "lib" || ident == "main" {
                g.through_root.push((name.clone(), format!("crate::{ident}")));
            } else if ident != m {
                entry.insert(ident);
            }
        }
    }
    g
}

#[test]
fn every_module_has_a_layer() {
    let g = graph();
    let missing: Vec<&String> = g.edges.keys().filter(|m| layer_of(m).is_none()).collect();
    assert!(
        missing.is_empty(),
        "modules without a layer in tests/suite/architecture.rs (and docs/architecture.md): {missing:?}"
    );
}

#[test]
fn nothing_imports_through_the_crate_root() {
    let g = graph();
    assert!(g.through_root.is_empty(), "imports through lib.rs (use the defining module): {:?}", g.through_root);
}

#[test]
fn imports_go_down_the_layers_and_the_two_sides_never_meet() {
    let g = graph();
    let mut bad = Vec::new();
    for (from, tos) in &g.edges {
        let Some(lf) = layer_of(from) else { continue };
        for to in tos {
            let lt = layer_of(to).unwrap_or(usize::MAX);
            let sides = (USER_SIDE.contains(&from.as_str()) && kernel_side(to))
                || (kernel_side(from) && USER_SIDE.contains(&to.as_str()));
            if lt > lf || sides {
                bad.push(format!("{from} ({}) -> {to} ({})", LAYERS[lf].0, LAYERS.get(lt).map_or("?", |l| l.0)));
            }
        }
    }
    assert!(bad.is_empty(), "imports that go up a layer or cross between the sides: {bad:#?}");
}

/// A cycle in `edges`, if there is one (depth-first search with colours; a
/// grey node reached again closes a cycle).
fn find_cycle(edges: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit<'a>(
        m: &'a str,
        g: &'a BTreeMap<String, BTreeSet<String>>,
        colour: &mut BTreeMap<&'a str, u8>,
        path: &mut Vec<&'a str>,
    ) -> Option<Vec<String>> {
        match colour.get(m) {
            Some(1) => {
                let start = path.iter().position(|&x| x == m).unwrap();
                let mut cycle: Vec<String> = path[start..].iter().map(|s| s.to_string()).collect();
                cycle.push(m.to_string());
                return Some(cycle);
            }
            Some(2) => return None,
            _ => {}
        }
        colour.insert(m, 1);
        path.push(m);
        for to in g.get(m).into_iter().flatten() {
            if let Some(c) = visit(to, g, colour, path) {
                return Some(c);
            }
        }
        path.pop();
        colour.insert(m, 2);
        None
    }
    let mut colour = BTreeMap::new();
    edges.keys().find_map(|m| visit(m, edges, &mut colour, &mut Vec::new()))
}

#[test]
fn the_import_graph_has_no_cycle() {
    if let Some(cycle) = find_cycle(&graph().edges) {
        panic!("import cycle: {}", cycle.join(" -> "));
    }
}

/// The identifiers that follow `prefix` in `code`.
fn paths_after(code: &str, prefix: &str) -> Vec<String> {
    code.match_indices(prefix)
        .map(|(i, _)| code[i + prefix.len()..].chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect())
        .filter(|s: &String| !s.is_empty())
        .collect()
}

/// Inside every folder, the files (and sub-folders) import each other
/// without a cycle: read from `super::x` in a folder's own files and its
/// sub-folders' `mod.rs`, and from `crate::<folder>::x` anywhere below it.
/// (`geometry` once had `bvh -> cuboids -> bvh`, which the top-level graph
/// cannot see.)
#[test]
fn no_folder_has_an_import_cycle_among_its_files() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut dirs = vec![];
    let mut stack = vec![src.clone()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                dirs.push(p.clone());
                stack.push(p);
            }
        }
    }
    let mut bad = Vec::new();
    for dir in dirs {
        let rel = dir.strip_prefix(&src).unwrap();
        let prefix = format!(
            "crate::{}::",
            rel.components().map(|c| c.as_os_str().to_string_lossy()).collect::<Vec<_>>().join("::")
        );
        let mut members: BTreeMap<String, (Vec<String>, Vec<String>)> = BTreeMap::new(); // name -> (super-texts, all texts)
        for e in std::fs::read_dir(&dir).unwrap() {
            let p = e.unwrap().path();
            let name = p.file_stem().unwrap().to_string_lossy().into_owned();
            if p.is_dir() {
                let mut all = Vec::new();
                files(&p, &mut all);
                let texts: Vec<String> = all.iter().map(|f| code(&std::fs::read_to_string(f).unwrap())).collect();
                let own = std::fs::read_to_string(p.join("mod.rs")).map(|t| vec![code(&t)]).unwrap_or_default();
                members.insert(name, (own, texts));
            } else if p.extension().is_some_and(|x| x == "rs") && name != "mod" {
                let text = code(&std::fs::read_to_string(&p).unwrap());
                members.insert(name, (vec![text.clone()], vec![text]));
            }
        }
        let mut edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        for (name, (own, all)) in &members {
            let refs = own
                .iter()
                .flat_map(|t| paths_after(t, "super::"))
                .chain(all.iter().flat_map(|t| paths_after(t, &prefix)));
            let to: BTreeSet<String> = refs.filter(|r| r != name && members.contains_key(r)).collect();
            edges.insert(name.clone(), to);
        }
        if let Some(cycle) = find_cycle(&edges) {
            bad.push(format!("{}: {}", rel.display(), cycle.join(" -> ")));
        }
    }
    assert!(bad.is_empty(), "import cycles inside folders: {bad:#?}");
}

/// The graph as docs/architecture.md draws it (mermaid), edges of the
/// transitive reduction only (an edge implied by a longer path is left out,
/// as in the picture), layers as subgraphs.
fn mermaid(g: &Graph) -> String {
    let reach = |from: &str, to: &str, skip: (&str, &str)| -> bool {
        let mut stack = vec![from.to_string()];
        let mut seen = BTreeSet::new();
        while let Some(m) = stack.pop() {
            for n in g.edges.get(&m).into_iter().flatten() {
                if (m.as_str(), n.as_str()) == skip {
                    continue;
                }
                if n == to {
                    return true;
                }
                if seen.insert(n.clone()) {
                    stack.push(n.clone());
                }
            }
        }
        false
    };
    let mut out = String::from("```mermaid\nflowchart BT\n");
    for (name, mods) in LAYERS.iter().rev() {
        out += &format!("  subgraph L_{}[\"{name}\"]\n", name.replace(' ', "_"));
        for m in *mods {
            out += &format!("    {m}\n");
        }
        out += "  end\n";
    }
    for (from, tos) in &g.edges {
        for to in tos {
            if !reach(from, to, (from, to)) {
                out += &format!("  {from} --> {to}\n");
            }
        }
    }
    out + "```\n"
}

#[test]
fn the_picture_in_the_docs_is_the_code() {
    let g = graph();
    let want = mermaid(&g);
    let doc_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/architecture.md");
    let doc = std::fs::read_to_string(&doc_path).unwrap();
    let (begin, end) = ("<!-- import graph: begin -->\n", "<!-- import graph: end -->");
    let have = doc
        .split_once(begin)
        .and_then(|(_, rest)| rest.split_once(end))
        .map(|(g, _)| g.to_string())
        .expect("docs/architecture.md has the import graph between its markers");
    assert!(
        have == want,
        "docs/architecture.md's import graph is not the code's; replace the block between the markers with:\n{want}"
    );
}

/// The house's two size rules, held: no function in `src` is longer than 80
/// lines (from its `fn` line to its closing brace), and none silences
/// clippy's `too_many_arguments` (arguments that travel together are a
/// struct: a pass's context, a packet's lanes).
#[test]
fn functions_are_short_and_take_few_arguments() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut all = Vec::new();
    files(&src, &mut all);
    let (mut long, mut allows) = (Vec::new(), Vec::new());
    for p in &all {
        let text = std::fs::read_to_string(p).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        let name = p.strip_prefix(&src).unwrap().display().to_string();
        for (i, line) in lines.iter().enumerate() {
            if line.contains("allow(clippy::too_many_arguments)") {
                allows.push(format!("{name}:{}", i + 1));
            }
            let code = line.trim_start();
            let indent = line.len() - code.len();
            let is_fn = ["fn ", "pub fn ", "pub(crate) fn ", "pub(super) fn ", "const fn ", "pub const fn "]
                .iter()
                .any(|p| code.starts_with(p));
            if !is_fn || code.ends_with(';') {
                continue;
            }
            let close = format!("{}}}", " ".repeat(indent));
            if let Some(len) = lines[i..].iter().position(|l| l.trim_end() == close) {
                if len + 1 > 80 {
                    long.push(format!("{name}:{} ({} lines)", i + 1, len + 1));
                }
            }
        }
    }
    assert!(long.is_empty(), "functions over 80 lines (split them): {long:#?}");
    assert!(allows.is_empty(), "too_many_arguments allowed (group the arguments): {allows:#?}");
}

/// The modules geometry must not import (issue 38): geometry is shapes, their
/// tests and their searches, and the rooms that read it (materials and
/// textures that shade its hits, the probes that count its work, the plan,
/// the estimator, the kernels, the film, the camera, the bridge) stay above
/// it. What a primitive carries of its material is a handle
/// (`handle::Kind` and a row; `handle` imports nothing).
const GEOMETRY_NEVER_IMPORTS: &[&str] =
    &["material", "probe", "texture", "kernel", "job", "plan", "estimator", "film", "camera"];

/// No file under `src/geometry` imports a module of
/// [`GEOMETRY_NEVER_IMPORTS`], as `crate::<module>` or through the crate
/// root by `super::super::<module>` (read as the graph is: outside comments
/// and test modules).
#[test]
fn geometry_needs_nothing_from_materials_or_probes() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut all = Vec::new();
    files(&src.join("geometry"), &mut all);
    assert!(!all.is_empty(), "src/geometry has source files");
    let mut bad = Vec::new();
    for p in &all {
        let text = code(&std::fs::read_to_string(p).unwrap());
        let name = p.strip_prefix(&src).unwrap().display().to_string();
        for ident in crate_paths(&text).into_iter().chain(paths_after(&text, "super::super::")) {
            if GEOMETRY_NEVER_IMPORTS.contains(&ident.as_str()) {
                bad.push(format!("{name}: crate::{ident}"));
            }
        }
    }
    bad.sort();
    bad.dedup();
    assert!(bad.is_empty(), "geometry imports what it must not (issue 38): {bad:#?}");
}
